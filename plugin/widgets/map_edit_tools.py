"""The editing tools of the standalone map: start/ground/check points, exclusion areas,
boundaries, breaklines and seamlines drawn on the :class:`~.map_view.MapView` and written into
the :class:`~.edit_session.EditSession` (undoable, saved by *Save edits*).

What a drawing becomes is the same as in QGIS: both faces run the shared steps of
:mod:`.edit_flow` over the core's :mod:`~photodem.algorithms.project.edit_rules`.

* :class:`EditContext` — the project, the session, the chosen surface, the breakline Z mode,
  the questions (:class:`.edit_forms.DialogAsker`) and the message callback;
* :class:`CaptureTool` — left clicks add vertices (a rubber band follows the cursor), a right
  click or Enter finishes, Backspace drops the last vertex, Esc cancels;
* :class:`PointCaptureTool`, :class:`PolygonCaptureTool`, :class:`LineCaptureTool`;
* :func:`editing_toolbar` — the toolbar of the main window.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence, Set, Tuple

from ...algorithms.errors import PhotodemError
from ...algorithms.project import edit_rules, edit_tools
from ...algorithms.project.edits import EDIT_LAYERS
from ...algorithms.project.model import Project
from ...algorithms.project.products import ELEVATION_KINDS, find_products
from ...algorithms.project.stereo_models import block_footprints
from ..i18n import tr
from ..qt import QtCore, QtGui, QtWidgets, pyqtSignal
from . import edit_flow
from .edit_forms import DialogAsker
from .map_layer import MapTool, ViewState
from .map_vertex_tools import DeleteFeatureTool, VertexTool, redrape

XY = Tuple[float, float]
#: ``message(text, level)`` with level ``info``, ``warning`` or ``critical``.
Message = Callable[[str, str], None]
#: Colours of the rubber band (vertices, lines) and of the marks (crossings, self-intersections).
BAND = QtGui.QColor(255, 0, 160)
MARK = QtGui.QColor(220, 0, 0)


def layer_shape(layer: str) -> str:
    """``point``, ``line`` or ``polygon``: how an edit layer is drawn."""
    geometry = EDIT_LAYERS[layer][0]
    return "polygon" if "Polygon" in geometry else "line" if "Line" in geometry else "point"


def layer_titles() -> Dict[str, str]:
    """The tools' names, in the operator's language."""
    return {"start_points": tr("Start point"), "exclusion_areas": tr("Exclusion area"),
            "breaklines": tr("Breakline"), "ground_points": tr("Ground point"),
            "check_points": tr("Check point"), "boundaries": tr("Boundary"),
            "seamlines": tr("Seamline")}


class EditContext(QtCore.QObject):
    """What the capture tools share, and the host of :mod:`.edit_flow`'s steps.

    Parameters
    ----------
    project : Project or path
        The open project (its CRS is the CRS of ``edits.gpkg``).
    session : EditSession
        Where the edits go (in memory, undoable; *Save edits* writes ``edits.gpkg``).
    message : callable, optional
        ``message(text, level)`` — the main window's status bar / message box.
    ask : object, optional
        The questions (:class:`.edit_forms.DialogAsker`; tests pass a stand-in).
    """

    marks_changed = pyqtSignal()

    def __init__(self, project: Any, session: Any, message: Optional[Message] = None,
                 ask: Any = None, parent: Optional[QtCore.QObject] = None) -> None:
        super().__init__(parent)
        self.project = project if isinstance(project, Project) else Project.load(project)
        self.session = session
        self.message = message or (lambda text, level: None)
        self.ask = ask if ask is not None else DialogAsker(None)
        self.surface: Optional[str] = None
        self.z_mode = "drape"
        self.marks: List[XY] = []
        self.seamline_files: Callable[[], List[str]] = lambda: []
        self._footprints: Any = None

    # -- host of edit_flow -------------------------------------------------------------------------
    def say(self, text: str, level: str = "warning") -> None:
        self.message(text, level)

    def project_crs(self) -> str:
        return str(self.project.crs)

    def footprints(self) -> Any:
        """The block's footprints, computed once (a projection of every image's border)."""
        if self._footprints is None:
            self._footprints = block_footprints(self.project)
        return self._footprints

    def surface_path(self, needed: bool = True) -> Optional[str]:
        """The chosen surface file, or None (with a message when ``needed``)."""
        if not self.surface:
            if needed:
                self.say(tr("Choose a surface (DSM or DTM) in the editing toolbar."))
            return None
        if not Path(self.surface).is_file():
            self.say(tr("The surface '{0}' is not a file.").format(self.surface), "critical")
            return None
        return str(self.surface)

    def mark(self, points: Sequence[XY]) -> None:
        self.marks = [tuple(p) for p in points]
        self.marks_changed.emit()

    def clear_marks(self) -> None:
        if self.marks:
            self.marks = []
            self.marks_changed.emit()

    # -- edits -------------------------------------------------------------------------------------
    def can_edit(self, layer: str) -> bool:
        """Whether ``layer`` takes edits now; else the operator is told why."""
        if self.session is None:
            self.say(tr("Open a PhotoDEM project first (File → Open project…)."))
            return False
        if getattr(self.session, "read_only", False):
            self.say(tr("The edits are read-only: {0}").format(
                getattr(self.session, "problem", "") or ""), "critical")
            return False
        return True

    def write(self, edit: Optional[edit_flow.Edit]) -> List[int]:
        """Add the features of ``edit`` to the session as one undoable step; their fids."""
        if edit is None or not self.can_edit(edit.layer):
            return []
        stack = getattr(self.session, "undo_stack", None)
        many = len(edit.features) > 1 and stack is not None
        if many:
            stack.beginMacro(edit.title)
        try:
            return [self.session.add(edit.layer, g, a, text=edit.title) for g, a in edit.features]
        except PhotodemError as exc:  # the session refused (read-only, unknown field)
            self.say(str(exc), "critical")
            return []
        finally:
            if many:
                stack.endMacro()

    def existing_lines(self, layer: str) -> List[Any]:
        """The session's lines of ``layer`` (unsaved ones included)."""
        return [g for _, g, _ in self.session.features(layer) if g is not None]

    def seamline_sources(self) -> List[Any]:
        """The lines of the mosaics' seamline files (``seamline_files``), project CRS."""
        lines: List[Any] = []
        for path in self.seamline_files():
            try:
                lines += edit_tools.mosaic_seamlines(path, self.project_crs())
            except PhotodemError as exc:
                self.say(str(exc))
        return lines

    def add_point(self, layer: str, x: float, y: float) -> List[int]:
        return self.write(edit_flow.point_edit(self, layer, x, y))

    def add_polygon(self, layer: str, coords: Sequence[XY]) -> List[int]:
        from shapely.geometry import Polygon  # lazy: shapely is loaded by the core already

        return self.write(edit_flow.polygon_edit(self, layer, Polygon(coords)))

    def add_line(self, layer: str, coords: Sequence[XY], map_units_per_pixel: float
                 ) -> List[int]:
        if layer == "seamlines":
            tolerance = edit_rules.SNAP_PIXELS * map_units_per_pixel
            edit = edit_flow.line_edit(self, layer, coords, seam_lines=self.seamline_sources(),
                                       tolerance=tolerance)
        else:
            edit = edit_flow.line_edit(self, layer, coords, self.existing_lines(layer))
        return self.write(edit)


def _pen(color: QtGui.QColor, width: float, style: Any = QtCore.Qt.SolidLine) -> QtGui.QPen:
    pen = QtGui.QPen(color, width, style)
    pen.setCosmetic(True)
    return pen


def paint_marks(painter: QtGui.QPainter, view: ViewState, marks: Sequence[XY]) -> None:
    """Red crosses at map points (crossings, self-intersections)."""
    painter.setPen(_pen(MARK, 3))
    for x, y in marks:
        p = view.to_pixel(x, y)
        painter.drawLine(QtCore.QPointF(p.x() - 8, p.y() - 8), QtCore.QPointF(p.x() + 8, p.y() + 8))
        painter.drawLine(QtCore.QPointF(p.x() - 8, p.y() + 8), QtCore.QPointF(p.x() + 8, p.y() - 8))


class CaptureTool(MapTool):
    """Vertices by left clicks, a rubber band to the cursor; right click / Enter finishes,
    Backspace removes the last vertex, Esc cancels. Subclasses implement :meth:`finished`.

    Parameters
    ----------
    view : MapView
        The map the tool draws on.
    shape : str
        ``line`` or ``polygon``.
    """

    def __init__(self, view: Any, shape: str, parent: Optional[QtCore.QObject] = None) -> None:
        super().__init__(parent if parent is not None else view)
        self.map_view = view
        self.shape = shape
        self.vertices: List[XY] = []
        self.hover: Optional[XY] = None
        self.marks: Callable[[], Sequence[XY]] = lambda: []

    @property
    def minimum(self) -> int:
        return 3 if self.shape == "polygon" else 2

    def deactivate(self) -> None:
        self.cancel()

    def cancel(self) -> None:
        self.vertices, self.hover = [], None
        self.changed.emit()

    def press(self, event: QtGui.QMouseEvent, x: float, y: float) -> bool:
        return event.button() in (QtCore.Qt.LeftButton, QtCore.Qt.RightButton)

    def release(self, event: QtGui.QMouseEvent, x: float, y: float) -> bool:
        if event.button() == QtCore.Qt.LeftButton:
            self.vertices.append((x, y))
            self.changed.emit()
            return True
        if event.button() == QtCore.Qt.RightButton:
            self.finish()
            return True
        return False

    def move(self, event: QtGui.QMouseEvent, x: float, y: float) -> bool:
        self.hover = (x, y)
        if self.vertices:
            self.changed.emit()
        return False

    def key_press(self, event: QtGui.QKeyEvent) -> bool:
        key = event.key()
        if key in (QtCore.Qt.Key_Return, QtCore.Qt.Key_Enter):
            self.finish()
        elif key == QtCore.Qt.Key_Backspace and self.vertices:
            self.vertices.pop()
            self.changed.emit()
        elif key == QtCore.Qt.Key_Escape and self.vertices:
            self.cancel()
        else:
            return False
        return True

    def finish(self) -> None:
        """The drawing is complete: hand it on (too few vertices: dropped)."""
        coords, self.vertices = self.vertices, []
        self.changed.emit()
        if len(coords) >= self.minimum:
            self.finished(coords)

    def finished(self, coords: List[XY]) -> None:
        raise NotImplementedError

    def paint(self, painter: QtGui.QPainter, view: ViewState) -> None:
        paint_marks(painter, view, self.marks())
        if not self.vertices:
            return
        points = [view.to_pixel(x, y) for x, y in self.vertices]
        if self.hover is not None:
            points.append(view.to_pixel(*self.hover))
        painter.setRenderHint(QtGui.QPainter.Antialiasing)
        painter.setPen(_pen(BAND, 2))
        if self.shape == "polygon" and len(points) > 2:
            fill = QtGui.QColor(BAND)
            fill.setAlpha(50)
            painter.setBrush(fill)
            painter.drawPolygon(QtGui.QPolygonF(points))
        else:
            painter.drawPolyline(QtGui.QPolygonF(points))
        painter.setBrush(QtGui.QColor(255, 255, 255))
        for p in points[: len(self.vertices)]:
            painter.drawRect(QtCore.QRectF(p.x() - 3, p.y() - 3, 6, 6))


class PointCaptureTool(MapTool):
    """A left click writes a start, ground or check point (the height from the surface)."""

    def __init__(self, view: Any, session: Any, layer: str, context: EditContext) -> None:
        super().__init__(view)
        self.map_view, self.session, self.layer, self.context = view, session, layer, context
        context.marks_changed.connect(self.changed)

    def press(self, event: QtGui.QMouseEvent, x: float, y: float) -> bool:
        return event.button() == QtCore.Qt.LeftButton

    def release(self, event: QtGui.QMouseEvent, x: float, y: float) -> bool:
        if event.button() != QtCore.Qt.LeftButton:
            return False
        self.context.add_point(self.layer, x, y)
        return True

    def paint(self, painter: QtGui.QPainter, view: ViewState) -> None:
        paint_marks(painter, view, self.context.marks)


class _EditCapture(CaptureTool):
    """A capture tool that writes into an edit layer through the context."""

    def __init__(self, view: Any, session: Any, layer: str, context: EditContext,
                 shape: str) -> None:
        super().__init__(view, shape)
        self.session, self.layer, self.context = session, layer, context
        self.marks = lambda: self.context.marks
        context.marks_changed.connect(self.changed)


class PolygonCaptureTool(_EditCapture):
    """An exclusion area (keep/remove/exclude asked) or a boundary (its name asked)."""

    def __init__(self, view: Any, session: Any, layer: str, context: EditContext) -> None:
        super().__init__(view, session, layer, context, "polygon")

    def finished(self, coords: List[XY]) -> None:
        self.context.add_polygon(self.layer, coords)


class LineCaptureTool(_EditCapture):
    """A breakline (draped, typed or interpolated heights; crossings refused) or a seamline
    (snapped onto the mosaics' seamlines)."""

    def __init__(self, view: Any, session: Any, layer: str, context: EditContext) -> None:
        super().__init__(view, session, layer, context, "line")

    def finished(self, coords: List[XY]) -> None:
        self.context.add_line(self.layer, coords, self.map_view.map_units_per_pixel())


def capture_tool(view: Any, session: Any, layer: str, context: EditContext) -> MapTool:
    """The tool that draws features of the edit layer ``layer``."""
    kind = layer_shape(layer)
    cls = {"point": PointCaptureTool, "polygon": PolygonCaptureTool,
           "line": LineCaptureTool}[kind]
    return cls(view, session, layer, context)


# -- the toolbar -------------------------------------------------------------------------------
def window_message(window: Any) -> Message:
    """``message(text, level)`` into the window's status bar; refusals also in a message box
    when the window shows boxes (``window.message_boxes``, off in tests)."""
    def message(text: str, level: str = "warning") -> None:
        window.statusBar().showMessage(text, 15000)
        if level == "critical" and getattr(window, "message_boxes", False):
            QtWidgets.QMessageBox.warning(window, tr("PhotoDEM"), text)
    return message


def z_mode_labels() -> List[Tuple[str, str]]:
    """The breakline height modes with their labels."""
    labels = {"drape": tr("Z draped"), "typed": tr("Z typed"),
              "interpolate": tr("Z interpolated")}
    return [(mode, labels[mode]) for mode in edit_rules.Z_MODES]


class EditingToolbar(QtWidgets.QToolBar):
    """One checkable action per edit tool (and per extra map tool, e.g. QC), the surface and the
    breakline Z mode; at most one tool is on.

    Parameters
    ----------
    window : QMainWindow
        With ``map_view`` and ``edit_session`` (None without a project).
    ask : object, optional
        The questions (tests pass a stand-in).
    """

    def __init__(self, window: Any, ask: Any = None) -> None:
        super().__init__(tr("PhotoDEM editing"), window)
        self.setObjectName("photodemEditing")
        self.window_ = window
        self.ask = ask
        self.message = window_message(window)
        self.context: Optional[EditContext] = None
        self.actions_: Dict[str, QtWidgets.QAction] = {}
        self.factories: Dict[str, Callable[[], Optional[MapTool]]] = {}
        self.extra_surfaces: List[Tuple[str, str]] = []  # chosen by hand (set_surface)
        self.hand_chosen: Optional[str] = None  # the surface the operator picked
        self.dsm_paths: Set[str] = set()  # the DSMs among the surfaces (the default is one)
        for layer, title in layer_titles().items():
            self.add_tool(layer, title, lambda name=layer: self.edit_tool(name))
        self.addSeparator()
        self.surface_box = QtWidgets.QComboBox(self)
        self.surface_box.setObjectName("photodemSurface")
        self.surface_box.setToolTip(tr("The surface that gives new points and breaklines "
                                       "their heights"))
        self.surface_box.setMinimumContentsLength(12)
        self.surface_box.currentIndexChanged.connect(self._surface_chosen)
        self.addWidget(self.surface_box)
        self.z_box = QtWidgets.QComboBox(self)
        self.z_box.setObjectName("photodemZMode")
        self.z_box.setToolTip(tr("Breakline heights: draped on the surface, typed at every "
                                 "vertex, or typed at the ends and interpolated between"))
        for mode, label in z_mode_labels():
            self.z_box.addItem(label, mode)
        self.z_box.currentIndexChanged.connect(lambda _i: self.set_z_mode(self.z_box.currentData()))
        self.addWidget(self.z_box)
        #: The second row: vertex and delete tools, re-drape, Undo/Redo, save, QC tools.
        self.more = QtWidgets.QToolBar(tr("PhotoDEM edit tools"), window)
        self.more.setObjectName("photodemEditTools")
        self.modify_actions = [self._tool_menu("vertex", tr("Vertices"), self.vertex_tool),
                               self._tool_menu("delete", tr("Delete feature"),
                                               self.delete_tool)]
        self.redrape_action = self.more.addAction(tr("Re-drape"), self.redrape)
        self.redrape_action.setToolTip(tr("New heights of every breakline and point from the "
                                          "chosen surface (one undo step)"))
        self.modify_actions.append(self.redrape_action)
        self.save_action = self.more.addAction(tr("Save edits"), self.save)
        self.save_action.setShortcut(QtGui.QKeySequence.Save)
        self.set_project(None)
        if self.view is not None:
            self.view.layers_changed.connect(self.fill_surfaces)

    @property
    def view(self) -> Any:
        return self.window_.map_view

    # -- tools -------------------------------------------------------------------------------------
    def add_tool(self, key: str, text: str, factory: Callable[[], Optional[MapTool]],
                 target: Any = None) -> QtWidgets.QAction:
        """A checkable action (on this toolbar, or on ``target``: another toolbar or a menu)
        that makes ``factory()`` the map's tool (None: refused)."""
        action = (target if target is not None else self).addAction(text)
        action.setCheckable(True)
        action.setObjectName(f"photodemTool_{key}")
        action.toggled.connect(lambda on, k=key: self._toggled(k, on))
        self.actions_[key] = action
        self.factories[key] = factory
        return action

    def _toggled(self, key: str, on: bool) -> None:
        if not on:
            if getattr(self.view.tool(), "tool_key", None) == key:
                self.view.set_tool(None)
            return
        for other, action in self.actions_.items():
            if other != key and action.isChecked():
                with QtCore.QSignalBlocker(action):
                    action.setChecked(False)
        tool = self.factories[key]()
        if tool is None:
            with QtCore.QSignalBlocker(self.actions_[key]):
                self.actions_[key].setChecked(False)
            self.view.set_tool(None)
            return
        tool.tool_key = key
        previous = self.view.tool()
        self.view.set_tool(tool)
        self.view.setFocus()
        if previous is not None and hasattr(previous, "tool_key"):
            previous.deleteLater()  # made by this toolbar: one tool object per activation

    def activate(self, key: str) -> Optional[MapTool]:
        """Switch the tool ``key`` on (as its action does); the map's tool or None."""
        self.actions_[key].setChecked(True)
        tool = self.view.tool()
        return tool if getattr(tool, "tool_key", None) == key else None

    def _tool_menu(self, kind: str, text: str,
                   factory: Callable[[str], Optional[MapTool]]) -> QtWidgets.QAction:
        """A toolbar button with one tool per edit layer in its menu (vertex, delete)."""
        menu = QtWidgets.QMenu(text, self)
        for layer, title in layer_titles().items():
            self.add_tool(f"{kind}:{layer}", title, lambda name=layer: factory(name), menu)
        button = QtWidgets.QToolButton(self)
        button.setText(text)
        button.setMenu(menu)
        button.setPopupMode(QtWidgets.QToolButton.InstantPopup)
        button.setObjectName(f"photodemTools_{kind}")
        return self.more.addWidget(button)

    def _modify_tool(self, tool: Any) -> Any:
        tool.message.connect(lambda text: self.message(text, "warning"))
        return tool

    def vertex_tool(self, layer: str) -> Optional[MapTool]:
        """Move (drag) or delete (right click) vertices of ``layer``; heights from the
        surface."""
        if self.context is None or not self.context.can_edit(layer):
            return None
        return self._modify_tool(VertexTool(self.view, self.context.session, layer,
                                            self.context.surface_path(False),
                                            self.context.project, parent=self))

    def delete_tool(self, layer: str) -> Optional[MapTool]:
        """A click removes the feature of ``layer`` under the cursor."""
        if self.context is None or not self.context.can_edit(layer):
            return None
        return self._modify_tool(DeleteFeatureTool(self.view, self.context.session, layer,
                                                   parent=self))

    def redrape(self) -> int:
        """*Re-drape*: every breakline and point gets its heights from the chosen surface
        again (one undo step); the number of features changed."""
        path = self.context.surface_path(True) if self.context is not None else None
        if path is None or not self.context.can_edit("breaklines"):
            return 0
        try:
            count = redrape(self.context.session, path)
        except PhotodemError as exc:
            self.message(str(exc), "critical")
            return 0
        self.message(tr("{0} features re-draped on the surface.").format(count), "info")
        return count

    def edit_tool(self, layer: str) -> Optional[MapTool]:
        if self.context is None:
            self.message(tr("Open a PhotoDEM project first (File → Open project…)."), "warning")
            return None
        if not self.context.can_edit(layer):
            return None
        return capture_tool(self.view, self.context.session, layer, self.context)

    # -- project, surface, mode --------------------------------------------------------------------
    def set_project(self, root: Optional[Any]) -> None:
        """The project whose edits the tools write (``window.edit_session``); None: off."""
        if self.view is not None:
            self.view.set_tool(None)
        session = getattr(self.window_, "edit_session", None)
        self.context = None
        if root is not None and session is not None:
            self.context = EditContext(root, session, self.message, self.ask, self)
            if self.ask is None:
                self.context.ask = DialogAsker(self.window_)
            self.context.seamline_files = self.seamline_files
            self.context.z_mode = self.z_box.currentData()
        for key, action in self.actions_.items():
            if not key.startswith("qc_"):
                action.setEnabled(self.context is not None)
        for action in self.modify_actions + [self.save_action]:
            action.setEnabled(self.context is not None)
        self.hand_chosen = None  # another project: its newest DSM again
        self.fill_surfaces(root)

    def surfaces(self, root: Optional[Any]) -> List[Tuple[str, str]]:
        """(label, path) of the DSMs and DTMs: the project's products, then those on the map
        (the truth rasters of a synthetic project, a raster added by hand)."""
        products = find_products(root) if root is not None else []
        found = [(f"{p.kind.upper()} {p.name}", str(p.path)) for p in products
                 if p.kind in ELEVATION_KINDS]
        self.dsm_paths = {str(p.path.resolve()) for p in products if p.kind == "dsm"}
        for layer in self.view.layers() if self.view is not None else []:
            path = getattr(layer, "path", None)
            if layer.kind in ELEVATION_KINDS and path is not None:
                found.append((layer.name, str(path)))
                if layer.kind == "dsm":
                    self.dsm_paths.add(str(Path(path).resolve()))
        unique: Dict[str, str] = {}
        for label, path in found + self.extra_surfaces:
            unique.setdefault(str(Path(path).resolve()), label)
        return [(label, path) for path, label in unique.items()]

    def default_surface(self, paths: List[str]) -> Optional[str]:
        """The newest DSM of ``paths`` (as QGIS's workspace chooses), else the newest one."""
        def age(path: str) -> Tuple[bool, float]:
            try:
                return path in self.dsm_paths, Path(path).stat().st_mtime
            except OSError:
                return False, 0.0
        return max(paths, key=age) if paths else None

    def fill_surfaces(self, root: Optional[Any] = None) -> None:
        """The surface list again (the chosen one stays when still there)."""
        if root is None and self.context is not None:
            root = self.context.project.root
        with QtCore.QSignalBlocker(self.surface_box):
            self.surface_box.clear()
            found = self.surfaces(root if self.context is not None else None)
            for label, path in found:
                self.surface_box.addItem(label, path)
            if not self.surface_box.count():
                self.surface_box.addItem(tr("(no DSM or DTM yet)"), None)
            # the operator's choice stays; until there is one, the newest DSM
            chosen = self.hand_chosen or self.default_surface([path for _l, path in found])
            index = self.surface_box.findData(chosen) if chosen else -1
            self.surface_box.setCurrentIndex(max(index, 0))
        self._surface_chosen()

    def set_surface(self, path: Any, name: str = "") -> None:
        """Choose the surface ``path`` (added to the list when missing)."""
        path = str(Path(path).resolve())
        self.hand_chosen = path
        if self.surface_box.findData(path) < 0:
            self.extra_surfaces.append((name or Path(path).stem, path))
            self.fill_surfaces()
        self.surface_box.setCurrentIndex(self.surface_box.findData(path))
        self._surface_chosen()

    def _surface_chosen(self, index: int = -1) -> None:
        if index >= 0:  # from the combo box: the operator's (or set_surface's) choice
            self.hand_chosen = self.surface_box.currentData()
        if self.context is not None:
            self.context.surface = self.surface_box.currentData()

    def set_z_mode(self, mode: str) -> None:
        """``drape``, ``typed`` or ``interpolate`` (breakline heights)."""
        index = self.z_box.findData(mode)
        if index >= 0 and index != self.z_box.currentIndex():
            self.z_box.setCurrentIndex(index)
        if self.context is not None:
            self.context.z_mode = mode

    def seamline_files(self) -> List[str]:
        """The mosaics' seamline files on the map (the operator's own seamlines excluded)."""
        out = []
        for layer in self.view.layers():
            path = getattr(layer, "path", None)
            if (layer.kind in ("seamlines", "mosaic_seamlines") and path is not None
                    and path.name.endswith("_seamlines.gpkg")):
                out.append(str(path))
        return out

    def save(self) -> Optional[Path]:
        """*Save edits*: the session writes ``edits.gpkg`` atomically."""
        session = self.context.session if self.context is not None else None
        if session is None:
            return None
        try:
            path = session.save()
        except PhotodemError as exc:
            self.message(str(exc), "critical")
            return None
        self.message(tr("Edits saved to {0}.").format(path), "info")
        return path


def editing_toolbar(window: Any, ask: Any = None) -> EditingToolbar:
    """The editing toolbar of the standalone window (added to it by :mod:`..app.docks`)."""
    return EditingToolbar(window, ask)
