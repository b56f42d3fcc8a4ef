"""The DEM quality panel: statistics where the operator looks, histogram, profile, identify,
blunder list, and the one click from a blunder to an edit (Qt only; QGIS and standalone).

The host (the QGIS dock :mod:`photodem.plugin.qgis.qc_dock`, or the standalone tool) feeds the
panel what the operator draws — :meth:`QcPanel.set_area` (a polygon as WKT or an extent),
:meth:`QcPanel.set_line` (vertices), :meth:`QcPanel.show_identify` (a point) — and listens to
:attr:`QcPanel.zoomTo` (a blunder row was clicked) and :attr:`QcPanel.difference_ready` (the
comparison wrote its difference model). Computations are the core's
(:mod:`photodem.algorithms.quality.qc_stats`, ``qc_blunders``, ``qc_profile``); area
statistics, blunders and *Compare* (the registry's ``dem_compare``) run off the GUI thread in
an :class:`~.worker.AlgorithmWorker`, cancellable. Profiles and identify read only the cells
along the line or at the point and run at once.

Edits go through :attr:`QcPanel.edit_writer` ``(layer, shapely geometry, attributes)``: by
default the core's :func:`~photodem.algorithms.project.edits.add_features` into the project's
``edits.gpkg``; the QGIS dock replaces it by the workspace layer's edit buffer (undo works).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence

import numpy as np
from shapely import wkt as shapely_wkt
from shapely.geometry import Point, box

from ...algorithms.errors import PhotodemError
from ...algorithms.project.edits import EXCLUSION_ACTIONS, add_features
from ...algorithms.quality import qc_blunders, qc_profile, qc_stats
from ...algorithms.quality.names import distinct_names
from ...algorithms.quality.profile import parse_coordinates
from ..i18n import error_text, tr
from ..qt import QtCore, QtWidgets, pyqtSignal
from .qc_filter import FilterReviewTab
from .qc_plots import (
    PlotCanvas,
    draw_histogram,
    draw_profile,
    fill_blunder_table,
    fill_group_table,
    fill_stats_table,
)
from .qc_worker import FunctionWorker
from .worker import AlgorithmWorker, start_in_thread

EditWriter = Callable[[str, Any, Dict[str, Any]], None]


def _path_row(parent: QtWidgets.QWidget, caption: str, filters: Optional[str]
              ) -> tuple:
    """A line edit with a browse button (returns the row widget and the line edit); without
    ``filters`` it browses for a folder."""
    row = QtWidgets.QWidget(parent)
    lay = QtWidgets.QHBoxLayout(row)
    lay.setContentsMargins(0, 0, 0, 0)
    edit = QtWidgets.QLineEdit(row)
    button = QtWidgets.QToolButton(row)
    button.setText("…")

    def browse() -> None:
        if filters is None:
            path = QtWidgets.QFileDialog.getExistingDirectory(parent, caption, edit.text())
        else:
            path, _ = QtWidgets.QFileDialog.getOpenFileName(parent, caption, edit.text(),
                                                            filters)
        if path:
            edit.setText(path)
            edit.editingFinished.emit()

    button.clicked.connect(browse)
    lay.addWidget(edit, 1)
    lay.addWidget(button)
    return row, edit


class QcPanel(QtWidgets.QWidget):
    """Interactive DEM quality checks (see the module text).

    Signals
    -------
    zoomTo(object)
        ``(xmin, ymin, xmax, ymax)`` of a blunder spot the operator clicked.
    difference_ready(str)
        The difference model written by *Compare* (with its ``.qml`` style beside it).
    statistics_ready(object)
        The result of an area statistic (:func:`~photodem.algorithms.quality.qc_stats.
        area_statistics`).
    edit_written(str, object)
        Layer name and shapely geometry of an edit written from a blunder.
    message(str, str)
        ``(level, text)`` for the host's message bar (``info``, ``warning``, ``error``).
    """

    zoomTo = pyqtSignal(object)  # noqa: N815 (Qt-style name the hosts connect to)
    difference_ready = pyqtSignal(str)
    statistics_ready = pyqtSignal(object)
    edit_written = pyqtSignal(str, object)
    message = pyqtSignal(str, str)

    def __init__(self, parent: Optional[QtWidgets.QWidget] = None) -> None:
        super().__init__(parent)
        self.project_root: Optional[Path] = None
        self.input_provider: Optional[Callable[[], Dict[str, Any]]] = None
        self.edit_writer: EditWriter = self._write_to_gpkg
        self.area: Any = None
        self.area_label = tr("whole model")
        self.line: Optional[np.ndarray] = None
        self.statistics: Optional[Dict[str, Any]] = None
        self.profile: Optional[Dict[str, Any]] = None
        self.blunders: Optional[Dict[str, Any]] = None
        self.last_error = ""
        self._worker: Optional[AlgorithmWorker] = None
        self._thread: Optional[QtCore.QThread] = None
        self._on_result: Optional[Callable[[Any], None]] = None
        self._build()

    # -- layout ----------------------------------------------------------------------------------
    def _build(self) -> None:
        lay = QtWidgets.QVBoxLayout(self)
        self.inputs_box = QtWidgets.QGroupBox(tr("Surfaces"), self)
        form = QtWidgets.QFormLayout(self.inputs_box)
        rasters = tr("Rasters (*.tif *.tiff *.vrt *.img);;All files (*)")
        row, self.project_edit = _path_row(self, tr("PhotoDEM project folder"), None)
        self.project_edit.setPlaceholderText(tr("edits and comparisons go into this project"))
        self.project_edit.editingFinished.connect(
            lambda: self.set_project(self.project_edit.text().strip() or None))
        form.addRow(tr("Project"), row)
        row, self.dem_edit = _path_row(self, tr("DEM to check"), rasters)
        form.addRow(tr("DEM"), row)
        row, self.reference_edit = _path_row(self, tr("Reference DEM"), rasters)
        form.addRow(tr("Reference"), row)
        row, self.classes_edit = _path_row(self, tr("Class raster"), rasters)
        form.addRow(tr("Classes (optional)"), row)
        self.surfaces_edit = QtWidgets.QLineEdit(self)
        self.surfaces_edit.setPlaceholderText(tr("further surfaces for profiles, separated by ;"))
        form.addRow(tr("Profile also"), self.surfaces_edit)
        lay.addWidget(self.inputs_box)
        lay.addLayout(self._build_actions())
        self.tabs = QtWidgets.QTabWidget(self)
        self.tabs.addTab(self._build_stats_tab(), tr("Statistics"))
        self.tabs.addTab(self._build_profile_tab(), tr("Profile"))
        self.tabs.addTab(self._build_blunder_tab(), tr("Blunders"))
        self.tabs.addTab(self._build_identify_tab(), tr("Identify"))
        self.filter_tab = FilterReviewTab(self)
        self.tabs.addTab(self.filter_tab, tr("Filter review"))
        lay.addWidget(self.tabs, 1)

    def _build_actions(self) -> QtWidgets.QLayout:
        grid = QtWidgets.QGridLayout()
        self.area_text = QtWidgets.QLabel(self)
        grid.addWidget(self.area_text, 0, 0, 1, 4)
        self.compare_button = QtWidgets.QPushButton(tr("Compare"), self)
        self.compare_button.setToolTip(tr("Run dem_compare on the whole model and add the "
                                          "difference model to the map"))
        self.compare_button.clicked.connect(self.compare)
        self.stats_button = QtWidgets.QPushButton(tr("Statistics of the area"), self)
        self.stats_button.clicked.connect(self.compute_statistics)
        self.cancel_button = QtWidgets.QPushButton(tr("Cancel"), self)
        self.cancel_button.setEnabled(False)
        self.cancel_button.clicked.connect(self.cancel)
        self.progress = QtWidgets.QProgressBar(self)
        self.progress.setRange(0, 100)
        grid.addWidget(self.compare_button, 1, 0)
        grid.addWidget(self.stats_button, 1, 1)
        grid.addWidget(self.cancel_button, 1, 2)
        grid.addWidget(self.progress, 1, 3)
        # Compare only: co-registration (Nuth & Kääb) on the stable terrain, as dem_compare
        self.coregister_check = QtWidgets.QCheckBox(tr("Co-register before comparing"), self)
        self.coregister_check.setToolTip(tr("Estimate and remove a horizontal shift and a "
                                            "vertical bias (Nuth & Kääb) on stable terrain "
                                            "first (Compare only)."))
        row, self.stable_edit = _path_row(
            self, tr("Stable terrain (mask raster or polygons)"),
            tr("Rasters or polygons (*.tif *.tiff *.gpkg *.shp *.geojson);;All files (*)"))
        self.stable_edit.setPlaceholderText(tr("stable terrain: mask raster or polygons "
                                               "(default: the whole common area)"))
        grid.addWidget(self.coregister_check, 2, 0, 1, 2)
        grid.addWidget(row, 2, 2, 1, 2)
        self.status = QtWidgets.QLabel(self)
        self.status.setWordWrap(True)
        grid.addWidget(self.status, 3, 0, 1, 4)
        self._show_area()
        return grid

    def _build_stats_tab(self) -> QtWidgets.QWidget:
        tab = QtWidgets.QWidget(self)
        lay = QtWidgets.QVBoxLayout(tab)
        row = QtWidgets.QHBoxLayout()
        self.extent_edit = QtWidgets.QLineEdit(tab)
        self.extent_edit.setPlaceholderText(tr("xmin, ymin, xmax, ymax (reference CRS)"))
        button = QtWidgets.QPushButton(tr("Use extent"), tab)
        button.clicked.connect(self._typed_extent)
        whole = QtWidgets.QPushButton(tr("Whole model"), tab)
        whole.clicked.connect(lambda: self.set_area(None))
        row.addWidget(QtWidgets.QLabel(tr("Area"), tab))
        row.addWidget(self.extent_edit, 1)
        row.addWidget(button)
        row.addWidget(whole)
        lay.addLayout(row)
        split = QtWidgets.QSplitter(QtCore.Qt.Horizontal, tab)
        self.stats_table = QtWidgets.QTableWidget(split)
        self.stats_table.verticalHeader().setVisible(False)
        fill_stats_table(self.stats_table, None)
        self.histogram = PlotCanvas(split)
        self.histogram.clear(tr("Draw an area or press 'Statistics of the area'"))
        split.setStretchFactor(1, 2)
        lay.addWidget(split, 2)
        self.group_table = QtWidgets.QTableWidget(tab)
        self.group_table.verticalHeader().setVisible(False)
        fill_group_table(self.group_table, None)
        lay.addWidget(self.group_table, 1)
        return tab

    def _build_profile_tab(self) -> QtWidgets.QWidget:
        tab = QtWidgets.QWidget(self)
        lay = QtWidgets.QVBoxLayout(tab)
        row = QtWidgets.QHBoxLayout()
        self.line_edit = QtWidgets.QLineEdit(tab)
        self.line_edit.setPlaceholderText(tr("x1,y1;x2,y2;… (DEM CRS), or draw a line on the "
                                             "map"))
        button = QtWidgets.QPushButton(tr("Profile"), tab)
        button.clicked.connect(self._typed_line)
        row.addWidget(self.line_edit, 1)
        row.addWidget(button)
        lay.addLayout(row)
        self.profile_plot = PlotCanvas(tab)
        self.profile_plot.clear(tr("Draw a line on the map"))
        lay.addWidget(self.profile_plot, 1)
        row = QtWidgets.QHBoxLayout()
        self.profile_info = QtWidgets.QLabel(tab)
        row.addWidget(self.profile_info, 1)
        self.csv_button = QtWidgets.QPushButton(tr("Export CSV…"), tab)
        self.csv_button.clicked.connect(lambda: self._export("csv"))
        self.png_button = QtWidgets.QPushButton(tr("Export PNG…"), tab)
        self.png_button.clicked.connect(lambda: self._export("png"))
        for b in (self.csv_button, self.png_button):
            b.setEnabled(False)
            row.addWidget(b)
        lay.addLayout(row)
        return tab

    def _build_blunder_tab(self) -> QtWidgets.QWidget:
        tab = QtWidgets.QWidget(self)
        lay = QtWidgets.QVBoxLayout(tab)
        row = QtWidgets.QHBoxLayout()
        row.addWidget(QtWidgets.QLabel(tr("|Δh − median| above k × NMAD, k ="), tab))
        self.k_spin = QtWidgets.QDoubleSpinBox(tab)
        self.k_spin.setRange(1.0, 20.0)
        self.k_spin.setSingleStep(0.5)
        self.k_spin.setValue(3.0)
        row.addWidget(self.k_spin)
        self.blunder_button = QtWidgets.QPushButton(tr("Find blunders"), tab)
        self.blunder_button.clicked.connect(self.find_blunders)
        row.addWidget(self.blunder_button)
        row.addStretch(1)
        lay.addLayout(row)
        self.blunder_table = QtWidgets.QTableWidget(tab)
        self.blunder_table.verticalHeader().setVisible(False)
        self.blunder_table.setSelectionBehavior(QtWidgets.QAbstractItemView.SelectRows)
        self.blunder_table.setSelectionMode(QtWidgets.QAbstractItemView.SingleSelection)
        self.blunder_table.cellClicked.connect(self._blunder_clicked)
        fill_blunder_table(self.blunder_table, [])
        lay.addWidget(self.blunder_table, 1)
        row = QtWidgets.QHBoxLayout()
        self.action_combo = QtWidgets.QComboBox(tab)
        for action in EXCLUSION_ACTIONS:
            self.action_combo.addItem(action, action)
        self.action_combo.setCurrentIndex(EXCLUSION_ACTIONS.index("remove"))
        self.exclusion_button = QtWidgets.QPushButton(tr("To exclusion area"), tab)
        self.exclusion_button.clicked.connect(lambda: self.blunder_to_exclusion())
        self.ground_button = QtWidgets.QPushButton(tr("To ground point"), tab)
        self.ground_button.setToolTip(tr("A ground point at the spot's centre with the "
                                         "reference height"))
        self.ground_button.clicked.connect(lambda: self.blunder_to_ground_point())
        row.addWidget(QtWidgets.QLabel(tr("Action"), tab))
        row.addWidget(self.action_combo)
        row.addWidget(self.exclusion_button)
        row.addWidget(self.ground_button)
        row.addStretch(1)
        lay.addLayout(row)
        return tab

    def _build_identify_tab(self) -> QtWidgets.QWidget:
        tab = QtWidgets.QWidget(self)
        lay = QtWidgets.QVBoxLayout(tab)
        self.identify_text = QtWidgets.QLabel(tr("Click on the map to see every surface's "
                                                 "height there."), tab)
        self.identify_table = QtWidgets.QTableWidget(tab)
        self.identify_table.verticalHeader().setVisible(False)
        lay.addWidget(self.identify_text)
        lay.addWidget(self.identify_table, 1)
        return tab

    # -- inputs ----------------------------------------------------------------------------------
    def set_project(self, root: Optional[Any]) -> None:
        """The project folder: edits go to its ``edits.gpkg``, *Compare* into its products."""
        self.project_root = Path(root) if root else None
        if self.project_root is not None and not (self.project_root / "project.toml").is_file():
            self._report("warning", tr("'{0}' is no PhotoDEM project (no project.toml); "
                                       "choose the project folder.").format(root))
            self.project_root = None
        if self.project_edit.text() != str(root or ""):
            self.project_edit.setText(str(root or ""))

    def set_inputs(self, dem: Optional[str] = None, reference: Optional[str] = None,
                   classes: Optional[str] = None,
                   surfaces: Optional[Sequence[str]] = None) -> None:
        """Fill the path fields (None leaves a field as it is)."""
        for edit, value in ((self.dem_edit, dem), (self.reference_edit, reference),
                            (self.classes_edit, classes)):
            if value is not None:
                edit.setText(str(value))
        if surfaces is not None:
            self.surfaces_edit.setText(";".join(str(s) for s in surfaces))

    def inputs(self) -> Dict[str, Any]:
        """``{"dem", "reference", "classes", "surfaces"}`` (+ ``"class_field"`` of class
        polygons) from the host or the path fields."""
        if self.input_provider is not None:
            return self.input_provider()
        extra = [s.strip() for s in self.surfaces_edit.text().split(";") if s.strip()]
        return {"dem": self.dem_edit.text().strip() or None,
                "reference": self.reference_edit.text().strip() or None,
                "classes": self.classes_edit.text().strip() or None, "surfaces": extra}

    def _pair(self) -> Optional[Dict[str, Any]]:
        given = self.inputs()
        for key, what in (("dem", tr("the DEM")), ("reference", tr("the reference"))):
            path = given.get(key)
            if not path or not Path(path).is_file():
                self._report("warning", tr("Choose {0}: '{1}' is not a raster file.")
                             .format(what, path or ""))
                return None
        return given

    def surfaces(self) -> List[str]:
        """The profile's and identify's surfaces: DEM, reference, then the others (≤ 5)."""
        given = self.inputs()
        out = [p for p in (given.get("dem"), given.get("reference"),
                           *(given.get("surfaces") or [])) if p and Path(p).is_file()]
        unique = list(dict.fromkeys(str(p) for p in out))
        return unique[:qc_profile.MAX_SURFACES]

    def _report(self, level: str, text: str) -> None:
        if level == "error":
            self.last_error = text
        self.status.setText(text)
        self.message.emit(level, text)

    # -- area statistics -------------------------------------------------------------------------
    def set_area(self, geometry: Any = None, label: str = "", run: bool = True) -> None:
        """The area of the statistics: WKT polygon, extent tuple, or None (whole model).

        With ``run`` the statistics are computed at once (off the GUI thread).
        """
        if isinstance(geometry, str):
            geometry = shapely_wkt.loads(geometry)
        self.area = geometry
        self.area_label = label or (tr("whole model") if geometry is None else tr("drawn area"))
        self._show_area()
        if run:
            self.compute_statistics()

    def _typed_extent(self) -> None:
        parts = [p for p in self.extent_edit.text().replace(";", ",").replace(" ", ",")
                 .split(",") if p]
        try:
            bounds = [float(p) for p in parts]
        except ValueError:
            bounds = []
        if len(bounds) != 4 or bounds[2] <= bounds[0] or bounds[3] <= bounds[1]:
            self._report("warning", tr("Give the extent as 'xmin, ymin, xmax, ymax'."))
            return
        self.set_area(box(*bounds), tr("extent {0}").format(", ".join(parts)))

    def _typed_line(self) -> None:
        try:
            coords = parse_coordinates(self.line_edit.text())
        except PhotodemError as exc:
            self._report("warning", str(exc))
            return
        self.set_line(coords)

    def _show_area(self) -> None:
        self.area_text.setText(tr("Area: {0}").format(self.area_label))

    def compute_statistics(self) -> bool:
        """Start the area statistic; False when inputs are missing or a run is going on."""
        given = self._pair()
        if given is None:
            return False
        kwargs = {"dem": given["dem"], "reference": given["reference"], "area": self.area,
                  "classes": given.get("classes"), "class_field": given.get("class_field")}
        return self._start(FunctionWorker(qc_stats.area_statistics, kwargs),
                           self._statistics_done, tr("Computing statistics…"))

    def _statistics_done(self, result: Dict[str, Any]) -> None:
        self.statistics = result
        fill_stats_table(self.stats_table, result["stats"])
        fill_group_table(self.group_table, result)
        draw_histogram(self.histogram, result)
        self.tabs.setCurrentIndex(0)
        self.statistics_ready.emit(result)

    # -- compare ---------------------------------------------------------------------------------
    def compare_folder(self, dem: str, reference: str) -> Optional[Path]:
        """``<project>/products/quality/<dem>_vs_<reference>``, or None without a project."""
        if self.project_root is None:
            return None
        a, b = (n.replace("/", "_") for n in distinct_names([dem, reference]))
        return self.project_root / "products" / "quality" / f"{a}_vs_{b}"

    def compare(self) -> bool:
        """Run ``dem_compare`` (whole model) into the project's products folder."""
        given = self._pair()
        if given is None:
            return False
        out = self.compare_folder(given["dem"], given["reference"])
        if out is None:
            self._report("warning", tr("Open a project first: the comparison is written into "
                                       "its products folder."))
            return False
        params = {"dem": given["dem"], "reference": given["reference"], "output": str(out)}
        for key in ("classes", "class_field"):
            if given.get(key):
                params[key] = given[key]
        if self.coregister_check.isChecked():
            params["coregister"] = True
            stable = self.stable_edit.text().strip()
            if stable:
                params["stable"] = stable
        return self._start(AlgorithmWorker("dem_compare", params), self._compare_done,
                           tr("Comparing…"))

    def _compare_done(self, result: Dict[str, Any]) -> None:
        result = dict(result)
        result.setdefault("histogram", None)
        self.area, self.area_label = None, tr("whole model")
        self._show_area()
        self._statistics_done(result)
        if result.get("difference"):
            self.difference_ready.emit(str(result["difference"]))

    # -- running ---------------------------------------------------------------------------------
    def is_running(self) -> bool:
        return self._worker is not None

    def _start(self, worker: AlgorithmWorker, on_result: Callable[[Any], None],
               text: str) -> bool:
        if self.is_running():
            self._report("warning", tr("A computation is running; wait or cancel it."))
            return False
        self._worker, self._on_result = worker, on_result
        worker.progress.connect(lambda p: self.progress.setValue(int(p)))
        worker.finished.connect(self._finished)
        worker.failed.connect(self._failed)
        worker.cancelled.connect(lambda m: self._report("info", tr("Cancelled.")))
        worker.done.connect(self._done)
        self._set_busy(True)
        self.status.setText(text)
        self._thread = start_in_thread(worker)
        return True

    def _set_busy(self, busy: bool) -> None:
        for b in (self.compare_button, self.stats_button, self.blunder_button):
            b.setEnabled(not busy)
        self.cancel_button.setEnabled(busy)
        self.progress.setValue(0)

    def _finished(self, result: Any) -> None:
        self.status.setText(tr("Done."))
        if self._on_result is not None:
            self._on_result(result)

    def _failed(self, text: str, operator_error: bool, parts: Any = None) -> None:
        self._report("error", error_text(text, parts) if operator_error
                     else tr("Internal error: {0}").format(text))

    def _done(self) -> None:
        self._worker, self._on_result = None, None
        self._set_busy(False)

    def cancel(self) -> None:
        """Ask the running computation to stop."""
        if self._worker is not None:
            self._worker.cancel()

    def wait(self, msecs: int = 60000) -> bool:
        """Process events until the running computation has ended (tests, closing)."""
        timer = QtCore.QElapsedTimer()
        timer.start()
        while self.is_running() and timer.elapsed() < msecs:
            QtWidgets.QApplication.processEvents(QtCore.QEventLoop.AllEvents, 50)
        return not self.is_running()

    # -- blunders --------------------------------------------------------------------------------
    def find_blunders(self) -> bool:
        """Start the blunder search in the current area."""
        given = self._pair()
        if given is None:
            return False
        kwargs = {"dem": given["dem"], "reference": given["reference"], "area": self.area,
                  "k": float(self.k_spin.value())}
        return self._start(FunctionWorker(qc_blunders.find_blunders, kwargs),
                           self._blunders_done, tr("Searching blunders…"))

    def _blunders_done(self, result: Dict[str, Any]) -> None:
        self.blunders = result
        fill_blunder_table(self.blunder_table, result["spots"])
        self.status.setText(tr("{0} blunder spots (|Δh − median| > {1:.2f} m).")
                            .format(result["total"], result["limit"]))
        self.tabs.setCurrentIndex(2)

    def _blunder_clicked(self, row: int, _col: int = 0) -> None:
        spot = self._spot(row)
        if spot is not None:
            self.zoomTo.emit(tuple(spot["bounds"]))

    def _spot(self, row: Optional[int]) -> Optional[Dict[str, Any]]:
        if row is None:
            row = self.blunder_table.currentRow()
        spots = (self.blunders or {}).get("spots", [])
        if not 0 <= row < len(spots):
            self._report("warning", tr("Select a blunder in the list first."))
            return None
        return spots[row]

    def _write_to_gpkg(self, layer: str, geometry: Any, attributes: Dict[str, Any]) -> None:
        edits = self.project_root / "edits.gpkg" if self.project_root is not None else None
        if edits is None or not edits.is_file():
            raise PhotodemError(tr("Open a project with an edits.gpkg first: the edit goes "
                                   "into it."))
        add_features(edits, layer, [(geometry, attributes)])

    def _write_edit(self, layer: str, geometry: Any, attributes: Dict[str, Any]) -> bool:
        try:
            self.edit_writer(layer, geometry, attributes)
        except PhotodemError as exc:
            self._report("error", str(exc))
            return False
        self.edit_written.emit(layer, geometry)
        self._report("info", tr("Written to {0}.").format(layer))
        return True

    def blunder_to_exclusion(self, row: Optional[int] = None,
                             action: Optional[str] = None) -> bool:
        """The spot's outline as an exclusion area (the chosen action) in the project's edits."""
        spot = self._spot(row)
        if spot is None:
            return False
        try:
            geom = qc_blunders.spot_polygon(spot)
        except PhotodemError as exc:
            self._report("error", str(exc))
            return False
        act = action or self.action_combo.currentData()
        return self._write_edit("exclusion_areas", geom,
                                {"action": act, "note": f"blunder {spot['id']}"})

    def blunder_to_ground_point(self, row: Optional[int] = None) -> bool:
        """A ground point at the spot's centroid with the reference height there."""
        spot = self._spot(row)
        given = self._pair() if spot is not None else None
        if spot is None or given is None:
            return False
        x, y = spot["centroid"]
        z = qc_profile.identify([given["reference"]], x, y, names=["ref"])["values"]["ref"]
        if z is None:
            self._report("error", tr("The reference has no height at the spot's centre."))
            return False
        return self._write_edit("ground_points", Point(x, y, z),
                                {"note": f"blunder {spot['id']}"})

    # -- profile and identify --------------------------------------------------------------------
    def set_line(self, coords: Any, edits: Optional[Any] = None) -> Optional[Dict[str, Any]]:
        """Profile of the surfaces along ``coords`` ((n, 2) or (n, 3)); drawn at once."""
        surfaces = self.surfaces()
        if not surfaces:
            self._report("warning", tr("Choose the surfaces first."))
            return None
        if edits is None and self.project_root is not None:
            edits = self.project_root / "edits.gpkg"
        if edits is not None and not Path(edits).is_file():
            edits = None
        try:
            prof = qc_profile.surface_profile(surfaces, coords, edits=edits)
        except PhotodemError as exc:
            self._report("error", str(exc))
            return None
        self.line = np.asarray(coords, dtype=float)
        self.profile = prof
        draw_profile(self.profile_plot, prof)
        self.profile_info.setText(tr("{0} stations, {1} breakline crossings, {2} check points")
                                  .format(len(prof["distance"]), len(prof["crossings"]),
                                          len(prof["check_points"])))
        for b in (self.csv_button, self.png_button):
            b.setEnabled(True)
        self.tabs.setCurrentIndex(1)
        return prof

    def export_profile_csv(self, path: Any) -> Path:
        """Write the profile table (see :func:`~photodem.algorithms.quality.qc_profile.
        write_profile_csv`)."""
        return qc_profile.write_profile_csv(path, self.profile)

    def export_profile_png(self, path: Any) -> Path:
        """Save the profile plot as PNG."""
        self.profile_plot.figure.savefig(str(path), dpi=150)
        return Path(path)

    def _export(self, kind: str) -> None:
        if self.profile is None:
            return
        filters = tr("CSV (*.csv)") if kind == "csv" else tr("PNG image (*.png)")
        path, _ = QtWidgets.QFileDialog.getSaveFileName(self, tr("Export profile"),
                                                        f"profile.{kind}", filters)
        if path:
            (self.export_profile_csv if kind == "csv" else self.export_profile_png)(path)
            self._report("info", tr("Profile written to {0}.").format(path))

    def show_identify(self, x: float, y: float) -> Optional[Dict[str, Any]]:
        """Every surface's height at (x, y) and their differences, shown in the Identify tab."""
        surfaces = self.surfaces()
        if not surfaces:
            self._report("warning", tr("Choose the surfaces first."))
            return None
        res = qc_profile.identify(surfaces, x, y)
        rows = [(name, v) for name, v in res["values"].items()]
        rows += [(f"{a} − {b}", d) for a, b, d in res["differences"]]
        self.identify_table.setColumnCount(2)
        self.identify_table.setHorizontalHeaderLabels([tr("Surface"), tr("Height [m]")])
        self.identify_table.setRowCount(len(rows))
        for r, (name, v) in enumerate(rows):
            self.identify_table.setItem(r, 0, QtWidgets.QTableWidgetItem(name))
            text = "–" if v is None else f"{v:.3f}"
            self.identify_table.setItem(r, 1, QtWidgets.QTableWidgetItem(text))
        self.identify_table.resizeColumnsToContents()
        self.identify_text.setText(tr("At x = {0:.2f}, y = {1:.2f}").format(x, y))
        self.tabs.setCurrentIndex(3)
        return res
