"""The editing toolbar, the undo history, the quality panel and the batch dialog docked into the
standalone main window, bound to its map and its project.

The window provides ``map_view``, ``edit_session`` (None without a project), ``project_root`` and
the signal ``project_opened(str root)`` (see :mod:`.map_window`); :func:`install_editing` wires
everything to them once.
"""

from __future__ import annotations

from typing import Any, Dict, Optional

from ..i18n import tr
from ..qt import QtCore, QtWidgets
from ..widgets.map_edit_tools import EditingToolbar, editing_toolbar
from ..widgets.map_qc_tools import QcAreaTool, QcIdentifyTool, QcLineTool
from ..widgets.undo_history import UndoHistory, edit_actions

Qt = QtCore.Qt
#: Object names of the docks (the window's saved layout finds them by these).
QUALITY_DOCK = "photodemQuality"
HISTORY_DOCK = "photodemUndoHistory"
BATCH_DOCK = "photodemBatch"


def _dock(window: QtWidgets.QMainWindow, name: str, title: str, widget: QtWidgets.QWidget,
          area: Any = Qt.RightDockWidgetArea) -> QtWidgets.QDockWidget:
    dock = QtWidgets.QDockWidget(title, window)
    dock.setObjectName(name)
    dock.setWidget(widget)
    window.addDockWidget(area, dock)
    return dock


def session_writer(window: Any, fallback: Any) -> Any:
    """The quality panel's ``edit_writer``: with a project open, a blunder becomes an undoable
    edit of the window's edit session (saved with *Save edits*, never written behind the
    session's back); without one, ``fallback`` (the panel's own writer into the project typed
    in the panel)."""
    def write(layer: str, geometry: Any, attributes: Dict[str, Any]) -> None:
        session = getattr(window, "edit_session", None)
        if session is None:
            fallback(layer, geometry, attributes)
            return
        session.add(layer, geometry, attributes, text=tr("Blunder to {0}").format(layer))
    return write


def quality_dock(window: QtWidgets.QMainWindow) -> QtWidgets.QDockWidget:
    """The DEM quality panel in its dock (made once), bound to the map and the project:
    blunders go into the edit session, a blunder's *zoom* moves the map."""
    dock = window.findChild(QtWidgets.QDockWidget, QUALITY_DOCK)
    if dock is None:
        from ..widgets.qc_panel import QcPanel  # lazy: matplotlib loads on first use

        dock = _dock(window, QUALITY_DOCK, tr("DEM quality"), QcPanel())
    panel = dock.widget()
    if not panel.property("photodemBound"):
        panel.setProperty("photodemBound", True)
        panel.edit_writer = session_writer(window, panel.edit_writer)
        view = getattr(window, "map_view", None)
        if view is not None:
            panel.zoomTo.connect(lambda bounds: view.set_extent(tuple(bounds)))
            panel.edit_written.connect(lambda *_: view.refresh())
        panel.message.connect(lambda level, text: window.statusBar().showMessage(text, 15000))
        root = getattr(window, "project_root", None)
        if root is not None:
            panel.set_project(root)
    return dock


def batch_dock(window: Any, project: Optional[str] = None) -> QtWidgets.QDockWidget:
    """The batch dialog (``window.open_batch_dialog``: the running one or a new one) docked;
    its *Close* closes the dock."""
    dialog = window.open_batch_dialog(project)
    dock = window.findChild(QtWidgets.QDockWidget, BATCH_DOCK)
    if dock is None:
        dock = QtWidgets.QDockWidget(tr("Batch"), window)
        dock.setObjectName(BATCH_DOCK)
        window.addDockWidget(Qt.RightDockWidgetArea, dock)
        quality = window.findChild(QtWidgets.QDockWidget, QUALITY_DOCK)
        if quality is not None:  # one column of tabs beside the map: the map stays large
            window.tabifyDockWidget(quality, dock)
    if dock.widget() is not dialog:
        dialog.setWindowFlags(Qt.Widget)
        dock.setWidget(dialog)
        dialog.finished.connect(lambda _r: dock.close())
        dialog.backgrounded.connect(dock.close)  # the status bar's button shows it again
    dialog.show()
    dock.show()
    dock.raise_()
    return dock


def _qc_tools(window: Any, bar: EditingToolbar) -> None:
    """The quality panel's map tools on the editing toolbar (they open the panel)."""
    def panel() -> Any:
        opener = getattr(window, "open_quality_panel", None)  # the window places the dock
        if opener is not None:
            return opener()
        dock = quality_dock(window)
        dock.show()
        return dock.widget()

    more = bar.more
    more.addSeparator()
    bar.add_tool("qc_area", tr("QC area"), lambda: QcAreaTool(window.map_view, panel()), more)
    bar.add_tool("qc_profile", tr("QC profile"), lambda: QcLineTool(window.map_view, panel()),
                 more)
    bar.add_tool("qc_identify", tr("QC identify"),
                 lambda: QcIdentifyTool(window.map_view, panel()), more)


def _project_opened(window: Any, bar: EditingToolbar, history: UndoHistory, root: str) -> None:
    """A project was opened: the tools, the history, Undo/Redo and the panel follow it."""
    session = getattr(window, "edit_session", None)
    bar.set_project(root)
    history.set_session(session)
    for action in getattr(bar, "undo_actions", ()):
        bar.more.removeAction(action)
        action.deleteLater()
    bar.undo_actions = edit_actions(session, bar) if session is not None else ()
    for action in bar.undo_actions:
        bar.more.insertAction(bar.save_action, action)
    dock = window.findChild(QtWidgets.QDockWidget, QUALITY_DOCK)
    if dock is not None:
        dock.widget().set_project(root)


def install_editing(window: Any, ask: Any = None) -> EditingToolbar:
    """The editing toolbar (with the QC tools), the *Undo history* dock, and the quality panel
    bound to the map, in ``window``; they follow ``window.project_opened``."""
    bar = editing_toolbar(window, ask)
    window.addToolBarBreak()
    window.addToolBar(bar)
    window.addToolBarBreak()
    window.addToolBar(bar.more)
    _qc_tools(window, bar)
    history = UndoHistory(getattr(window, "edit_session", None))
    # under *Layers*: the toolbox on the right keeps its height for the forms
    history_dock = _dock(window, HISTORY_DOCK, tr("Undo history"), history,
                         Qt.LeftDockWidgetArea)
    layers = getattr(window, "layers_dock", None)
    if layers is not None:  # the layer list keeps two thirds of the height
        window.resizeDocks([layers, history_dock], [540, 200], Qt.Vertical)
    window.editing_toolbar, window.undo_history = bar, history
    window.project_opened.connect(
        lambda root: _project_opened(window, bar, history, root))
    if getattr(window, "project_root", None) is not None:
        _project_opened(window, bar, history, str(window.project_root))
    return bar
