"""The standalone main window: the map in the centre, layers on the left, the processing
toolbox (algorithm tree, generated parameter form, run panel) docked on the right.

Everything in the toolbox comes from the registry, so a new algorithm appears here (and in QGIS
and the CLI) without any GUI code. The map half lives in :mod:`.map_window`.
"""

from __future__ import annotations

import html
from pathlib import Path
from typing import Any, Dict, Optional

from ...algorithms.processing import registry
from ...algorithms.processing.spec import Algorithm
from ..i18n import tr
from ..qt import QtCore, QtGui, QtWidgets, pyqtSignal
from ..widgets.parameter_form import SETTINGS_PROJECT, ParameterForm
from ..widgets.run_panel import RunPanel
from .docks import batch_dock, install_editing, quality_dock
from .map_window import MapWindowMixin
from .model_menu import ModelMenu, prefer_map_project

ALG_ROLE = QtCore.Qt.UserRole + 1
#: Settings keys of the window's layout and the algorithm shown last.
SETTINGS_WINDOW = "PhotoDEM/toolbox/"


class ToolboxWindow(MapWindowMixin, QtWidgets.QMainWindow):
    """Main window of ``photodem gui``: map, layer list, processing toolbox.

    Parameters
    ----------
    message_boxes : bool
        Show operator errors in a message box as well as in the log (tests switch it off).
    settings : QSettings, optional
        Where the window remembers its layout, the last algorithm, project and input of each
        parameter; default ``QSettings()`` once the application has a name (``photodem gui``),
        else nothing is remembered.
    """

    algorithm_selected = pyqtSignal(str)
    #: A project was opened on the map (its root folder).
    project_opened = pyqtSignal(str)

    def __init__(self, parent: Optional[QtWidgets.QWidget] = None,
                 message_boxes: bool = True, settings: Any = None) -> None:
        super().__init__(parent)
        self.message_boxes = message_boxes
        if settings is None and QtCore.QCoreApplication.organizationName():
            settings = QtCore.QSettings()
        self.settings = settings
        self.batch_dialog: Optional[Any] = None  # the batch dialog (kept while it runs)
        self.setWindowTitle(tr("PhotoDEM toolbox"))
        self.resize(1400, 860)
        self.setDockOptions(QtWidgets.QMainWindow.AnimatedDocks
                            | QtWidgets.QMainWindow.AllowTabbedDocks)
        self.form: Optional[ParameterForm] = None
        self.last_georef = ""  # output folder of the last georeferencing run
        self.algorithm: Optional[Algorithm] = None

        # left: filter + algorithm tree
        self.filter_edit = QtWidgets.QLineEdit()
        self.filter_edit.setPlaceholderText(tr("Search algorithms …"))
        self.filter_edit.setClearButtonEnabled(True)
        self.tree = QtWidgets.QTreeWidget()
        self.tree.setHeaderHidden(True)
        self.tree.setUniformRowHeights(True)
        # names of one group often differ only at their end: "Filter DSM to DTM (…)"
        self.tree.setTextElideMode(QtCore.Qt.ElideMiddle)
        left = QtWidgets.QWidget()
        left_layout = QtWidgets.QVBoxLayout(left)
        left_layout.setContentsMargins(6, 6, 0, 6)
        left_layout.addWidget(self.filter_edit)
        left_layout.addWidget(self.tree, 1)

        # right: title, help, form (scrolling), run panel
        self.title = QtWidgets.QLabel()
        font = self.title.font()
        font.setPointSizeF(font.pointSizeF() * 1.35)
        font.setBold(True)
        self.title.setFont(font)
        self.help_label = QtWidgets.QLabel()
        self.help_label.setWordWrap(True)
        self.help_label.setTextFormat(QtCore.Qt.RichText)
        self.help_label.setAlignment(QtCore.Qt.AlignTop | QtCore.Qt.AlignLeft)
        self.help_label.setStyleSheet("color: #555;")
        self.form_area = QtWidgets.QScrollArea()
        self.form_area.setWidgetResizable(True)
        self.form_area.setFrameShape(QtWidgets.QFrame.StyledPanel)
        self.run_panel = RunPanel()
        self.run_panel.setEnabled(False)

        top = QtWidgets.QWidget()
        top_layout = QtWidgets.QVBoxLayout(top)
        top_layout.setContentsMargins(6, 6, 6, 0)
        top_layout.addWidget(self.title)
        # the help of a long algorithm scrolls: the form below keeps its room in the dock
        help_area = QtWidgets.QScrollArea()
        help_area.setWidgetResizable(True)
        help_area.setFrameShape(QtWidgets.QFrame.NoFrame)
        help_area.setWidget(self.help_label)
        help_area.setMaximumHeight(110)
        top_layout.addWidget(help_area)
        top_layout.addWidget(self.form_area, 1)
        right = QtWidgets.QSplitter(QtCore.Qt.Vertical)
        right.addWidget(top)
        bottom = QtWidgets.QWidget()
        bottom_layout = QtWidgets.QVBoxLayout(bottom)
        bottom_layout.setContentsMargins(6, 0, 6, 6)
        bottom_layout.addWidget(self.run_panel)
        right.addWidget(bottom)
        right.setStretchFactor(0, 3)
        right.setStretchFactor(1, 2)
        right.setSizes([470, 230])
        self.right_splitter = right

        # the toolbox is a dock beside the map: the tree above the form and the run panel
        splitter = QtWidgets.QSplitter(QtCore.Qt.Vertical)
        splitter.addWidget(left)
        splitter.addWidget(right)
        splitter.setStretchFactor(0, 1)
        splitter.setStretchFactor(1, 3)
        splitter.setSizes([220, 560])
        splitter.setMinimumWidth(380)
        self.splitter = splitter
        self._build_map()
        self.toolbox_dock = QtWidgets.QDockWidget(tr("Processing toolbox"), self)
        self.toolbox_dock.setObjectName("photodemToolbox")
        self.toolbox_dock.setWidget(splitter)
        self.addDockWidget(QtCore.Qt.RightDockWidgetArea, self.toolbox_dock)
        self.resizeDocks([self.layers_dock, self.toolbox_dock], [240, 470], QtCore.Qt.Horizontal)

        self._build_menu()
        self.statusBar().showMessage(tr("Open a project (File menu) or choose an algorithm "
                                        "in the toolbox."))
        self.populate()
        install_editing(self)  # editing toolbar, QC map tools, undo history (issue 21)
        self.model_menu = ModelMenu(self)  # run from the map; the open project in the forms

        self.tree.currentItemChanged.connect(self._on_current_item)
        self.filter_edit.textChanged.connect(self._apply_filter)
        self.run_panel.run_requested.connect(self.run_current)
        self.run_panel.run_finished.connect(self._on_run_finished)
        self.run_panel.show_on_map.connect(self.show_on_map)
        self._restore_layout()

    # -- building --------------------------------------------------------------------------------
    def _build_menu(self) -> None:
        file_menu = self.menuBar().addMenu(tr("&File"))
        view_menu = self.menuBar().addMenu(tr("&View"))
        self._build_map_menus(file_menu, view_menu)
        for dock in (self.layers_dock, self.toolbox_dock):
            view_menu.addAction(dock.toggleViewAction())
        quit_action = file_menu.addAction(tr("&Quit"))
        quit_action.setShortcut(QtGui.QKeySequence.Quit)
        quit_action.triggered.connect(self.close)
        tools_menu = self.menuBar().addMenu(tr("&Tools"))
        self.review_action = tools_menu.addAction(tr("Review georeferencing…"))
        self.review_action.setToolTip(tr("Check and edit the control points of a "
                                         "georeferencing result"))
        self.review_action.triggered.connect(lambda _checked=False: self.open_georef_review())
        # the batch dialog over stereo models (issue 20)
        self.batch_action = tools_menu.addAction(tr("Batch over stereo models…"))
        self.batch_action.setToolTip(tr("Run steps over many stereo models, resumable"))
        self.batch_action.triggered.connect(lambda _checked=False: batch_dock(self))
        # issue 20: the DEM quality panel, docked in this window
        self.quality_action = tools_menu.addAction(tr("DEM quality…"))
        self.quality_action.setToolTip(tr("Statistics, histogram, profiles, identify and "
                                          "blunders of a DEM against a reference"))
        self.quality_action.triggered.connect(lambda _checked=False: self.open_quality_panel())
        help_menu = self.menuBar().addMenu(tr("&Help"))
        about = help_menu.addAction(tr("&About PhotoDEM"))
        about.triggered.connect(self._about)

    def populate(self) -> None:
        """Fill the tree: one node per group, the algorithms below it."""
        self.tree.clear()
        groups: Dict[str, QtWidgets.QTreeWidgetItem] = {}
        folder_icon = self.style().standardIcon(QtWidgets.QStyle.SP_DirIcon)
        alg_icon = self.style().standardIcon(QtWidgets.QStyle.SP_FileIcon)
        for alg in registry.algorithms().values():
            group = alg.group or tr("Other")
            if group not in groups:
                node = QtWidgets.QTreeWidgetItem([tr(group)])
                node.setIcon(0, folder_icon)
                node.setFlags(node.flags() & ~QtCore.Qt.ItemIsSelectable)
                self.tree.addTopLevelItem(node)
                groups[group] = node
            item = QtWidgets.QTreeWidgetItem([tr(alg.name)])
            item.setIcon(0, alg_icon)
            item.setData(0, ALG_ROLE, alg.id)
            item.setToolTip(0, f"{alg.id}\n{tr(alg.help)}" if alg.help else alg.id)
            groups[group].addChild(item)
        self.tree.expandAll()

    def _apply_filter(self, text: str) -> None:
        needle = text.strip().lower()
        for i in range(self.tree.topLevelItemCount()):
            group = self.tree.topLevelItem(i)
            visible = 0
            for j in range(group.childCount()):
                item = group.child(j)
                hay = f"{item.text(0)} {item.data(0, ALG_ROLE)}".lower()
                hidden = bool(needle) and needle not in hay
                item.setHidden(hidden)
                visible += not hidden
            group.setHidden(visible == 0)

    # -- selection -------------------------------------------------------------------------------
    def _on_current_item(self, item: Optional[QtWidgets.QTreeWidgetItem], _prev: object) -> None:
        if item is None:
            return
        alg_id = item.data(0, ALG_ROLE)
        if alg_id:
            self.select_algorithm(str(alg_id))

    def select_algorithm(self, algorithm_id: str) -> ParameterForm:
        """Show the form of ``algorithm_id`` (also selects it in the tree)."""
        alg = registry.get(algorithm_id)
        previous = self.form
        if previous is not None:
            previous.remember(self.settings)
        self.algorithm = alg
        self.title.setText(tr(alg.name))
        help_text = html.escape(tr(alg.help)) if alg.help else ""
        self.help_label.setText(
            f"{help_text}<br><span style='color:gray'>photodem run {alg.id}</span>")
        self.form = ParameterForm(alg)
        self.form.restore(self.settings)  # the input of its last run
        if self.project_root is not None:  # the map's project wins over a remembered one
            prefer_map_project(self.form, str(self.project_root))
        if previous is not None:
            self.form.carry_over(previous)  # the project and input in view stay
        if self.form._project_params and not self.form.project() and self.settings is not None:
            last = self.settings.value(SETTINGS_PROJECT, "")
            if last:
                self.form.set_values({self.form._project_params[0]: last})
        container = QtWidgets.QWidget()
        layout = QtWidgets.QVBoxLayout(container)
        layout.addWidget(self.form)
        layout.addStretch(1)
        self.form_area.setWidget(container)
        self.run_panel.setEnabled(True)
        self.statusBar().showMessage(tr(alg.name))
        self._select_in_tree(alg.id)
        self.algorithm_selected.emit(alg.id)
        return self.form

    def _select_in_tree(self, algorithm_id: str) -> None:
        iterator = QtWidgets.QTreeWidgetItemIterator(self.tree)
        while iterator.value():
            item = iterator.value()
            if item.data(0, ALG_ROLE) == algorithm_id and self.tree.currentItem() is not item:
                self.tree.blockSignals(True)
                self.tree.setCurrentItem(item)
                self.tree.blockSignals(False)
                return
            iterator += 1

    # -- running ---------------------------------------------------------------------------------
    def run_current(self) -> None:
        """Run the selected algorithm with the values of the form."""
        if self.algorithm is None or self.form is None or self.run_panel.is_running():
            return
        self.form.setEnabled(False)
        self.tree.setEnabled(False)
        self.statusBar().showMessage(tr("Running {0} …").format(tr(self.algorithm.name)))
        self.form.remember(self.settings)
        self.run_panel.start(self.algorithm.id, self.form.values())

    def _on_run_finished(self, status: str, payload: object) -> None:
        if self.form is not None:
            self.form.setEnabled(True)
        self.tree.setEnabled(True)
        messages = {"done": tr("{0} finished."), "failed": tr("{0} failed."),
                    "cancelled": tr("{0} was cancelled.")}
        text = messages.get(status, "{0}").format(self._run_title())
        self.statusBar().showMessage(text)
        if status == "failed" and self.message_boxes:
            QtWidgets.QMessageBox.warning(self, tr("PhotoDEM"), str(payload))
        if status == "done":  # its rasters and vectors go on the map
            self.add_run_outputs(self.run_panel.map_outputs())
        if (status == "done" and self.run_panel.algorithm_id == "georeference_polygons"
                and isinstance(payload, dict) and payload.get("report")):
            self.last_georef = str(Path(payload["report"]).parent)
            self.statusBar().showMessage(text + " " + tr("Tools → Review georeferencing checks "
                                                         "and edits its control points."))

    def _run_title(self) -> str:
        """The operator's name of the algorithm that ran (its id if it is not the selected one)."""
        run_id = self.run_panel.algorithm_id
        if self.algorithm is not None and self.algorithm.id == run_id:
            return tr(self.algorithm.name)
        return str(run_id)

    def open_georef_review(self, folder: Optional[str] = None) -> Optional[QtWidgets.QDialog]:
        """Open the review dialog of a georeferencing output folder (asks for it unless
        given; the last result of this session is offered first)."""
        # lazy: the review dialog loads matplotlib and the georef package; opened on demand
        from ..widgets.georef_review import open_review

        def report(text: str) -> None:
            if self.message_boxes:
                QtWidgets.QMessageBox.warning(self, tr("PhotoDEM"), text)
            self.statusBar().showMessage(text)

        return open_review(self, folder, self.last_georef, self.message_boxes, report)

    def open_batch_dialog(self, project: Optional[str] = None) -> QtWidgets.QDialog:
        """Show the batch dialog (the one running in the background, or a new one on the
        form's project)."""
        # lazy: the batch dialog is opened on demand
        from ..widgets.batch_dialog import BatchDialog

        dialog = self.batch_dialog
        if dialog is None or not dialog.is_running():
            if dialog is not None:
                dialog.deleteLater()
            if project is None and self.form is not None:
                project = self.form.project() or None
            dialog = BatchDialog(project, self, settings=self.settings)
            dialog.backgrounded.connect(self._batch_in_background)
            dialog.batch_finished.connect(self._batch_finished)
            self.batch_dialog = dialog
        dialog.show()
        dialog.raise_()
        return dialog

    def _batch_in_background(self) -> None:
        """The batch dialog was closed while its batch runs: a button in the status bar
        shows it again."""
        if getattr(self, "batch_button", None) is None:
            self.batch_button = QtWidgets.QPushButton(tr("Batch running – show"), self)
            self.batch_button.setFlat(True)
            self.batch_button.clicked.connect(lambda _c=False: batch_dock(self))
            self.statusBar().addPermanentWidget(self.batch_button)
        self.batch_button.show()

    def _batch_finished(self, summary: object) -> None:
        button = getattr(self, "batch_button", None)
        if button is not None:
            button.hide()
        if isinstance(summary, dict):
            self.statusBar().showMessage(tr("Batch {0}: summary in {1}").format(
                summary.get("status"), summary.get("summary")))

    # -- remembering -----------------------------------------------------------------------------
    def _restore_layout(self) -> None:
        """The window's geometry, splitters and last algorithm from the settings."""
        s = self.settings
        if s is None:
            return
        for key, restore in ((SETTINGS_WINDOW + "geometry", self.restoreGeometry),
                             (SETTINGS_WINDOW + "state", self.restoreState),
                             (SETTINGS_WINDOW + "splitter", self.splitter.restoreState),
                             (SETTINGS_WINDOW + "right", self.right_splitter.restoreState)):
            value = s.value(key, None)
            if isinstance(value, QtCore.QByteArray):
                restore(value)
        last = s.value(SETTINGS_WINDOW + "algorithm", "")
        if last and last in registry.algorithms():
            self.select_algorithm(str(last))

    def save_layout(self) -> None:
        """Remember the layout, the algorithm shown and its input."""
        s = self.settings
        if s is None:
            return
        s.setValue(SETTINGS_WINDOW + "geometry", self.saveGeometry())
        s.setValue(SETTINGS_WINDOW + "state", self.saveState())
        s.setValue(SETTINGS_WINDOW + "splitter", self.splitter.saveState())
        s.setValue(SETTINGS_WINDOW + "right", self.right_splitter.saveState())
        if self.algorithm is not None:
            s.setValue(SETTINGS_WINDOW + "algorithm", self.algorithm.id)
        if self.form is not None:
            self.form.remember(s)
        s.sync()

    def open_quality_panel(self) -> QtWidgets.QWidget:
        """Show the DEM quality panel (issue 20) in a dock of this window; returns the panel."""
        dock = quality_dock(self)
        if dock.property("photodemTabbed") is None:  # first time: a tab beside the toolbox
            dock.setProperty("photodemTabbed", True)
            self.tabifyDockWidget(self.toolbox_dock, dock)
        dock.show()
        dock.raise_()
        return dock.widget()

    def closeEvent(self, event: QtGui.QCloseEvent) -> None:
        session = self.edit_session
        if session is not None and not session.maybe_save(self):
            event.ignore()  # the operator cancelled: unsaved edits stay
            return
        self.save_layout()
        if self.run_panel.is_running():
            self.run_panel.cancel()
            self.run_panel.wait(30000)
        if self.batch_dialog is not None and self.batch_dialog.is_running():
            self.batch_dialog.cancel()
            self.batch_dialog.wait(30000)
        quality = self.findChild(QtWidgets.QDockWidget, "photodemQuality")
        if quality is not None and quality.widget().is_running():  # issue 20
            quality.widget().cancel()
            quality.widget().wait(30000)
        self.map_view.set_tool(None)
        self.map_view.clear_layers()  # stops the tile threads of the rasters
        super().closeEvent(event)

    def _about(self) -> None:
        QtWidgets.QMessageBox.about(
            self, tr("About PhotoDEM"),
            tr("PhotoDEM: aerial photogrammetry — DSMs by image matching, DTMs by filtering, "
               "orthophoto mosaics and automatic georeferencing."))
