"""Review dialog of a polygon georeferencing: control points, object pairs, residual map.

The operator switches control points off (they become check points), rejects object pairs,
adds control points by hand, chooses the transform and the outlier removal, and sees the
residuals and RMSE update at once; *Save* writes the folder's products again
(:func:`~photodem.algorithms.georef.review.save_review`). Independent check points imported
from a file follow the control points in the point table (role "check (independent)", tinted
rows without a Use box), with their own colour on the residual map and their own RMSE in the
summary. The same dialog serves the standalone toolbox and QGIS.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable, Dict, List, Optional

import numpy as np
import rasterio
from matplotlib.backends.backend_qt5agg import FigureCanvasQTAgg
from matplotlib.figure import Figure

from ...algorithms.errors import Cancelled, PhotodemError
from ...algorithms.feedback import Feedback
from ...algorithms.georef.fit import KINDS
from ...algorithms.georef.products import (
    INDEPENDENT_COLOUR,
    ROLE_COLOURS,
    draw_residuals,
    residual_scale,
    skipped_ids_text,
)
from ...algorithms.georef.review import Review, load_review, save_review
from ...algorithms.raster.io import open_image
from ..i18n import error_text, tr
from ..qt import QtCore, QtGui, QtWidgets, pyqtSignal

#: Tint of the independent check points' table rows.
INDEPENDENT_TINT = "#efe6f7"
#: Colour of the control points without an object pair that a stage found (keypoints, the
#: area search's grid) on the residual map: not the operator's manual points.
STAGE_POINT_COLOUR = "tab:cyan"


def point_columns() -> List[str]:
    """Headers of the control point table (the first column holds the Use check box)."""
    return [tr("Use"), "#", tr("Role"), tr("Pair"), tr("Column"), tr("Row"), "X", "Y",
            tr("dX [px]"), tr("dY [px]"), tr("Residual [px]"), tr("Residual [m]"),
            tr("Leave-one-out [m]")]


def pair_columns() -> List[str]:
    """Headers of the object pair table (the first column holds the Reject check box)."""
    return [tr("Reject"), "#", tr("Image object"), tr("Reference object"),
            tr("Segmentation run"), tr("Threshold [DN]"), "Q", tr("Overlap"), tr("ICP RMS [px]"),
            tr("Iterations"), tr("Converged")]


def role_text(role: str) -> str:
    """The operator's word for a point role."""
    return {"control": tr("control point"), "outlier": tr("outlier (dropped)"),
            "check": tr("check point (off)"), "rejected": tr("pair rejected"),
            "independent": tr("check (independent)")}.get(role, role)


def origin_text(origin: str) -> str:
    """The operator's word for the origin of a control point without an object pair."""
    return {"manual": tr("manual"), "keypoints": tr("keypoints"),
            "grid": tr("search grid")}.get(origin, origin)


def reason_texts() -> Dict[str, str]:
    """The evidence gate's reasons (keys of
    :data:`~photodem.algorithms.georef.evidence.REASON_TEXTS`) as translated format strings
    with the same named figures."""
    return {
        "spread": tr("the control points cover {hull_pct:.0f} % of the image (needs "
                     "≥ {min_hull_pct:.0f} %) and {quadrants} of 4 quadrants (needs "
                     "≥ {min_quadrants})"),
        "no_holdout": tr("too few control points for a held-out check"),
        "halves": tr("the corners disagree by {corner_px:.1f} px between transforms of halves "
                     "of the control points (at most {max_px:g} px)"),
        "holdout": tr("control points held out quadrant by quadrant are predicted with an "
                      "RMSE of {rmse_px:.1f} px (at most {max_px:g} px)"),
        "no_agreement": tr("no image–reference agreement could be measured (the reference "
                           "does not reach into the image)"),
        "edge_peak": tr("image and reference do not agree: edge peak ratio {peak:.2f} (needs "
                        "≥ {need:g})"),
        "correlation_peak": tr("image and reference do not agree: correlation peak margin "
                               "{peak:.2f} (needs ≥ {need:g})"),
        "offset": tr("image and reference agree best {offset_px:.1f} px away from the result "
                     "(at most {max_px:g} px)"),
        "corner_misfit": tr("image and reference agree best {misfit_px:.1f} px away from the "
                            "result at an image corner (extrapolated from the quadrants; at "
                            "most {max_px:g} px)"),
        "local_offsets": tr("image and reference agree best away from the result in the "
                            "{quadrants} (at most {max_px:g} px)"),
        "buildings_area": tr("building footprints cannot confirm a result of the area-based "
                             "search (roof edges displaced by relief, walls and cast shadows "
                             "agree with the footprints a few pixels apart)"),
    }


def reason_text(key: str, values: Dict[str, Any]) -> Optional[str]:
    """One reason of the evidence gate in the operator's language; ``None`` for a key this
    version does not know (the caller shows the core's English sentence)."""
    template = reason_texts().get(key)
    if template is None:
        return None
    if key == "local_offsets":
        names = (tr("top left quadrant ({0} px)"), tr("top right quadrant ({0} px)"),
                 tr("bottom left quadrant ({0} px)"), tr("bottom right quadrant ({0} px)"))
        values = {**values, "quadrants": ", ".join(names[int(k)].format(f"{o:.1f}")
                                                   for k, o in values["quadrants"])}
    try:
        return template.format(**values)
    except (KeyError, ValueError, IndexError, TypeError):  # a translation that lost a figure
        return None


def _reasons(ev: Dict[str, Any]) -> str:
    """The gate's reasons of an evidence dict, translated where the report has their keys
    (reports written before the keys: the core's English sentences)."""
    items = ev.get("reason_items")
    english = list(ev.get("reasons") or [])
    if not items or len(items) != len(english):
        return "; ".join(english)
    return "; ".join(reason_text(k, v) or text for (k, v), text in zip(items, english))


def evidence_html(report: Dict[str, Any]) -> str:
    """The automatic result's independent evidence (report.json ``evidence``) for the
    dialog: the verdict (UNVERIFIED in red) and its figures; '' for results without it."""
    ev = report.get("evidence")
    if not ev:
        return ""
    if report.get("verified"):
        verdict = f"<b>{tr('Verified: yes')}</b>"
    else:
        verdict = f"<b style='color:#c0392b'>{tr('UNVERIFIED')}</b> — {_reasons(ev)}"
    parts = []
    if ev.get("independent_points", True) and ev.get("hull_share") is not None:
        parts.append(tr("control points cover {0} % of the image, {1} of 4 quadrants").format(
            f"{100 * ev['hull_share']:.0f}", ev.get("quadrants")))
        if ev.get("corner_disagreement_px") is not None:
            parts.append(tr("corners disagree by {0} px between halves").format(
                f"{ev['corner_disagreement_px']:.2f}"))
    elif not ev.get("independent_points", True):
        parts.append(tr("control points from a grid through the search transform"))
    if ev.get("peak") is not None:
        what = (tr("edge peak ratio {0}") if ev.get("agreement") == "edges"
                else tr("correlation peak margin {0}"))
        parts.append(what.format(f"{ev['peak']:.2f}") + " "
                     + tr("at {0} px").format(f"{ev['offset_px']:.1f}"))
    local = [f"{v:.1f}" for v in ev.get("local_offsets_px") or [] if v is not None]
    if local:
        parts.append(tr("quadrant offsets {0} px").format(", ".join(local)))
    if ev.get("corner_misfit_px") is not None:
        parts.append(tr("corner misfit {0} px").format(f"{ev['corner_misfit_px']:.1f}"))
    if report.get("verified"):
        return f"{tr('Evidence of the automatic result:')} {verdict}: {'; '.join(parts)}"
    # the reasons first, the figures on their own line: both are lists joined by "; "
    return (f"{tr('Evidence of the automatic result:')} {verdict}.<br>{tr('Figures:')} "
            f"{'; '.join(parts)}")


class AddPointDialog(QtWidgets.QDialog):
    """Asks for a manual control point: image column/row and map X/Y."""

    def __init__(self, crs_hint: str, parent: Optional[QtWidgets.QWidget] = None) -> None:
        super().__init__(parent)
        self.setWindowTitle(tr("Add control point"))
        form = QtWidgets.QFormLayout(self)
        self.fields: List[QtWidgets.QDoubleSpinBox] = []
        for label, lo, hi, decimals in ((tr("Image column [px]"), -1e6, 1e6, 2),
                                        (tr("Image row [px]"), -1e6, 1e6, 2),
                                        (tr("Map X"), -1e9, 1e9, 3),
                                        (tr("Map Y"), -1e9, 1e9, 3)):
            box = QtWidgets.QDoubleSpinBox(self)
            box.setRange(lo, hi)
            box.setDecimals(decimals)
            form.addRow(label, box)
            self.fields.append(box)
        hint = QtWidgets.QLabel(tr("Map coordinates in {0}; pixel centres at whole numbers, "
                                   "the top-left pixel is (0, 0).").format(crs_hint))
        hint.setWordWrap(True)
        form.addRow(hint)
        buttons = QtWidgets.QDialogButtonBox(
            QtWidgets.QDialogButtonBox.Ok | QtWidgets.QDialogButtonBox.Cancel, parent=self)
        buttons.accepted.connect(self.accept)
        buttons.rejected.connect(self.reject)
        form.addRow(buttons)

    def values(self) -> List[float]:
        return [f.value() for f in self.fields]


class GeorefReviewDialog(QtWidgets.QDialog):
    """Review and edit a georeferencing result folder.

    Parameters
    ----------
    folder : path
        Output folder of ``georeference_polygons``.
    message_boxes : bool
        Ask before discarding changes and show save errors in message boxes (tests switch
        it off).

    Raises
    ------
    PhotodemError
        The folder holds no georeferencing result.
    """

    saved = pyqtSignal(dict)  # the paths written by Save

    def __init__(self, folder: Any, parent: Optional[QtWidgets.QWidget] = None,
                 message_boxes: bool = True) -> None:
        super().__init__(parent)
        self.review: Review = load_review(folder)
        self.message_boxes = message_boxes
        self.dirty = False
        self.rows: List[Dict[str, Any]] = []
        self.check: Dict[str, Any] = {"count": 0, "points": []}  # independent check points
        self.fit: Any = None
        self.setWindowTitle(tr("Review georeferencing — {0}").format(self.review.name))
        self.resize(1250, 760)

        # top: transform, outlier removal, summary
        self.kind_combo = QtWidgets.QComboBox(self)
        for kind in KINDS:
            self.kind_combo.addItem(tr(kind), kind)
        self.kind_combo.setCurrentIndex(KINDS.index(self.review.kind))
        self.outlier_box = QtWidgets.QCheckBox(tr("Drop outliers (> 3 σ0)"), self)
        self.outlier_box.setChecked(self.review.drop_outliers)
        self.summary = QtWidgets.QLabel(self)
        self.summary.setTextFormat(QtCore.Qt.RichText)
        self.summary.setWordWrap(True)
        self.evidence_label = QtWidgets.QLabel(evidence_html(self.review.report), self)
        self.evidence_label.setTextFormat(QtCore.Qt.RichText)
        self.evidence_label.setWordWrap(True)
        top = QtWidgets.QHBoxLayout()
        top.addWidget(QtWidgets.QLabel(tr("Transform:"), self))
        top.addWidget(self.kind_combo)
        top.addWidget(self.outlier_box)
        top.addStretch(1)

        # middle: residual map | tables

        self.figure = Figure(figsize=(6, 6))
        self.canvas = FigureCanvasQTAgg(self.figure)
        self.canvas.setMinimumWidth(380)
        self.axes = self.figure.add_subplot(111)
        self._ring: Any = None  # the selection marker, moved without redrawing the map
        self._every = np.zeros((0, 2))  # image positions of the table's rows
        self.thumb, self.thumb_factor = _thumbnail(self.review.folder
                                                   / f"{self.review.name}_gcps.tif")
        self.point_table = self._table(point_columns())
        self.pair_table = self._table(pair_columns())
        self.tabs = QtWidgets.QTabWidget(self)
        self.tabs.addTab(self.point_table, tr("Control points"))
        self.tabs.addTab(self.pair_table, tr("Object pairs"))
        splitter = QtWidgets.QSplitter(QtCore.Qt.Horizontal, self)
        splitter.addWidget(self.canvas)
        splitter.addWidget(self.tabs)
        splitter.setSizes([480, 770])

        # bottom: actions
        self.add_button = QtWidgets.QPushButton(tr("Add control point…"), self)
        self.import_button = QtWidgets.QPushButton(tr("Import check points…"), self)
        self.import_button.setToolTip(tr(
            "Independent check points from a CSV/TXT file with a header: col,row,x,y (pixel "
            "centres at whole numbers) or pixel,line,mapX,mapY (a QGIS .points file); they are "
            "never used in the fit."))
        self.worst_button = QtWidgets.QPushButton(tr("Switch off largest residual"), self)
        self.save_button = QtWidgets.QPushButton(tr("Save"), self)
        self.save_button.setToolTip(tr("Write the control points, the georeferenced image and "
                                       "the report again (the automatic result is kept as "
                                       "report_auto.json)."))
        self.close_button = QtWidgets.QPushButton(tr("Close"), self)
        buttons = QtWidgets.QHBoxLayout()
        for b in (self.add_button, self.import_button, self.worst_button):
            buttons.addWidget(b)
        buttons.addStretch(1)
        buttons.addWidget(self.save_button)
        buttons.addWidget(self.close_button)

        layout = QtWidgets.QVBoxLayout(self)
        layout.addLayout(top)
        layout.addWidget(self.summary)
        layout.addWidget(self.evidence_label)
        layout.addWidget(splitter, 1)
        layout.addLayout(buttons)

        self._fill_pairs()
        self._fill_points()
        self.refresh()
        for table in (self.point_table, self.pair_table):
            table.resizeColumnsToContents()
        self.kind_combo.currentIndexChanged.connect(self._on_kind)
        self.outlier_box.toggled.connect(self._on_outliers)
        self.point_table.itemChanged.connect(self._on_point_item)
        self.pair_table.itemChanged.connect(self._on_pair_item)
        self.point_table.itemSelectionChanged.connect(self._show_selection)
        self.add_button.clicked.connect(self.add_point)
        self.import_button.clicked.connect(lambda: self.import_check_points())
        self.worst_button.clicked.connect(self.switch_off_worst)
        self.save_button.clicked.connect(self.save)
        self.close_button.clicked.connect(self.close)
        self.canvas.mpl_connect("button_press_event", self._on_click)

    # -- building --------------------------------------------------------------------------------
    def _table(self, columns: List[str]) -> QtWidgets.QTableWidget:
        table = QtWidgets.QTableWidget(0, len(columns), self)
        table.setHorizontalHeaderLabels(columns)
        table.setSelectionBehavior(QtWidgets.QAbstractItemView.SelectRows)
        table.setEditTriggers(QtWidgets.QAbstractItemView.NoEditTriggers)
        table.verticalHeader().setVisible(False)
        # widths are set once after filling: ResizeToContents would measure every column
        # again for each of the thousands of cells a refresh changes
        table.horizontalHeader().setSectionResizeMode(QtWidgets.QHeaderView.Interactive)
        return table

    @staticmethod
    def _check_item(checked: bool) -> QtWidgets.QTableWidgetItem:
        item = QtWidgets.QTableWidgetItem()
        item.setFlags(QtCore.Qt.ItemIsUserCheckable | QtCore.Qt.ItemIsEnabled
                      | QtCore.Qt.ItemIsSelectable)
        item.setCheckState(QtCore.Qt.Checked if checked else QtCore.Qt.Unchecked)
        return item

    def _fill_pairs(self) -> None:
        table = self.pair_table
        table.blockSignals(True)
        table.setRowCount(len(self.review.pairs))
        for r, pair in enumerate(self.review.pairs):
            table.setItem(r, 0, self._check_item(pair["pair"] in self.review.rejected_pairs))
            values = (pair["pair"], pair.get("image_object"), pair.get("reference_object"),
                      pair.get("run"), pair.get("threshold"), pair.get("q"),
                      pair.get("overlap"), pair.get("icp_rms_px"), pair.get("iterations"),
                      pair.get("converged"))
            for c, v in enumerate(values, start=1):
                table.setItem(r, c, QtWidgets.QTableWidgetItem(_fmt(v)))
        table.blockSignals(False)

    def _fill_points(self) -> None:
        """(Re)build the point rows: the Use check boxes and fixed columns; after the control
        points the independent check points (tinted, no Use box: never in the fit)."""
        table = self.point_table
        table.blockSignals(True)
        n = len(self.review.points)
        table.setRowCount(n + len(self.review.check_points))
        for r, p in enumerate(self.review.points):
            table.setItem(r, 0, self._check_item(p.enabled))
            for c in range(1, table.columnCount()):
                table.setItem(r, c, QtWidgets.QTableWidgetItem(""))
        tint = QtGui.QBrush(QtGui.QColor(INDEPENDENT_TINT))
        for r in range(n, table.rowCount()):
            for c in range(table.columnCount()):
                item = QtWidgets.QTableWidgetItem("")
                item.setFlags(QtCore.Qt.ItemIsEnabled | QtCore.Qt.ItemIsSelectable)
                item.setBackground(tint)
                table.setItem(r, c, item)
        table.blockSignals(False)

    # -- state changes ---------------------------------------------------------------------------
    def _changed(self) -> None:
        self.dirty = True
        self.refresh()

    def _on_kind(self, index: int) -> None:
        self.review.kind = self.kind_combo.itemData(index)
        self._changed()

    def _on_outliers(self, checked: bool) -> None:
        self.review.drop_outliers = bool(checked)
        self._changed()

    def _on_point_item(self, item: QtWidgets.QTableWidgetItem) -> None:
        if item.column() == 0 and item.row() < len(self.review.points):
            self.review.points[item.row()].enabled = item.checkState() == QtCore.Qt.Checked
            self._changed()

    def _on_pair_item(self, item: QtWidgets.QTableWidgetItem) -> None:
        if item.column() == 0:
            pair = self.review.pairs[item.row()]["pair"]
            self.review.set_pair_rejected(pair, item.checkState() == QtCore.Qt.Checked)
            self._changed()

    def set_point_enabled(self, index: int, enabled: bool) -> None:
        """Switch a control point on or off (as its check box does)."""
        self.point_table.item(index, 0).setCheckState(
            QtCore.Qt.Checked if enabled else QtCore.Qt.Unchecked)

    def set_pair_rejected(self, row: int, rejected: bool) -> None:
        """Reject an object pair or take it back (as its check box does)."""
        self.pair_table.item(row, 0).setCheckState(
            QtCore.Qt.Checked if rejected else QtCore.Qt.Unchecked)

    def add_point(self, values: Optional[List[float]] = None) -> None:
        """Add a manual control point (asks for it unless ``values`` are given)."""
        if not values:
            dialog = AddPointDialog(self.review.report.get("transform", {}).get("crs", ""),
                                    self)
            if dialog.exec_() != QtWidgets.QDialog.Accepted:
                return
            values = dialog.values()
        try:
            self.review.add_point(values[:2], values[2:])
        except PhotodemError as exc:
            self._error(error_text(exc))
            return
        self._fill_points()
        self._changed()
        self.point_table.selectRow(len(self.review.points) - 1)

    def import_check_points(self, path: Optional[str] = None) -> bool:
        """Import independent check points from a file (asks for it unless ``path`` is
        given); they replace those imported before. True on success."""
        if not path:
            start = self.review.check_file or str(self.review.folder)
            path = QtWidgets.QFileDialog.getOpenFileName(
                self, tr("Import check points"), start,
                tr("Check points (*.csv *.txt *.points);;All files (*)"))[0]
            if not path:
                return False
        try:
            skipped = self.review.import_check_points(path)
        except PhotodemError as exc:
            self._error(error_text(exc))
            return False
        warning = self._skipped_note(skipped)
        self._fill_points()
        self._changed()
        self.point_table.resizeColumnToContents(2)  # the role column: the longer role text
        if warning and self.message_boxes:
            QtWidgets.QMessageBox.information(self, tr("PhotoDEM"), warning)
        self.tabs.setCurrentWidget(self.point_table)
        # after the event loop: the table's scroll range follows its new rows only then
        QtCore.QTimer.singleShot(0, self._show_check_rows)
        return True

    @staticmethod
    def _skipped_note(ids: List[str]) -> str:
        """The note on check points skipped outside the image ('' without any)."""
        if not ids:
            return ""
        return tr("Skipped check points outside the image ({0}): {1}.").format(
            len(ids), skipped_ids_text(ids))

    def _show_check_rows(self) -> None:
        """Scroll the point table to the independent check points."""
        item = self.point_table.item(len(self.review.points), 0)
        if item is not None:
            self.point_table.scrollToItem(item, QtWidgets.QAbstractItemView.PositionAtTop)

    def switch_off_worst(self) -> None:
        """Switch off the control point with the largest residual."""
        candidates = [r for r in self.rows if r["role"] == "control"]
        if candidates:
            worst = max(candidates, key=lambda r: r["residual_px"])
            self.set_point_enabled(worst["id"], False)

    # -- display ---------------------------------------------------------------------------------
    def refresh(self) -> None:
        """Fit, fill the residual columns and the summary, redraw the map."""
        try:
            self.fit = self.review.fit()
        except PhotodemError as exc:
            self.fit, self.rows = None, []
            self.check = {"count": 0, "points": []}
            self.summary.setText(f"<span style='color:#c0392b'>{error_text(exc)}</span>")
            self.save_button.setEnabled(False)
            self._draw()
            return
        self._show_fit()

    def _show_fit(self) -> None:
        """Fill the residual columns and the summary from ``self.fit``, redraw the map."""
        self.rows = self.review.table(self.fit)
        table = self.point_table
        table.blockSignals(True)
        table.setUpdatesEnabled(False)
        for r, row in enumerate(self.rows):
            values = (row["id"], role_text(row["role"]),
                      row["pair"] if row["origin"] == "pair" else origin_text(row["origin"]),
                      row["col"], row["row"],
                      row["x"], row["y"], row["dx_px"], row["dy_px"], row["residual_px"],
                      row["residual_map"], row["loo_map"])
            for c, v in enumerate(values, start=1):
                table.item(r, c).setText(_fmt(v))
        self.check = self.review.independent_check(self.fit)
        for r, p in enumerate(self.check["points"], start=len(self.rows)):
            values = (p["id"], role_text("independent"), "", p["col"], p["row"], p["x"],
                      p["y"], p["dx_map"] / self.fit.pixel_size,
                      p["dy_map"] / self.fit.pixel_size, p["residual_px"], p["residual_map"],
                      None)
            for c, v in enumerate(values, start=1):
                table.item(r, c).setText(_fmt(v))
        table.setUpdatesEnabled(True)
        table.blockSignals(False)
        fit = self.fit
        check, n_check = self.review.check_rmse(fit)
        text = tr("RMSE <b>{0:.3f} px</b> = {1:.3f} m, σ0 {2:.3f} m; {3} of {4} points in "
                  "the fit").format(fit.rmse_px, fit.rmse_map, fit.sigma0, int(fit.used.sum()),
                                    len(self.rows))
        if n_check:
            text += tr("; {0} check points: RMSE {1:.3f} m").format(n_check, check)
        if self.check["count"]:
            text += tr("; {0} independent check points: RMSE <b>{1:.3f} px</b> = {2:.3f} m"
                       ).format(self.check["count"], self.check["rmse_px"],
                                self.check["rmse_m"])
        if self.dirty:
            text += " — <i>" + tr("not saved") + "</i>"
        note = self._skipped_note(self.review.check_skipped)
        if note:
            text += "<br><span style='color:#b9770e'>" + note + "</span>"
        self.summary.setText(text)
        self.save_button.setEnabled(True)
        self._draw()

    def _draw(self) -> None:
        ax = self.axes
        ax.clear()
        if self.thumb is not None:
            f = self.thumb_factor
            h, w = self.thumb.shape
            ax.imshow(self.thumb, cmap="gray", extent=(-0.5, w * f - 0.5, h * f - 0.5, -0.5))
        xy = self.review.image_xy()
        ind = self.check["points"] if self.rows else []
        ind_xy = np.array([[p["col"], p["row"]] for p in ind]).reshape(-1, 2)
        ind_res = np.array([[p["dcol"], p["drow"]] for p in ind]).reshape(-1, 2)
        if self.rows and len(xy):
            res = np.array([[r["dcol"], r["drow"]] for r in self.rows])
            # one scale for both kinds of points: their arrows compare
            span = float(np.ptp(np.vstack([xy, ind_xy]), axis=0).max())
            k = residual_scale(np.vstack([res, ind_res]), span, share=0.08)
            for role, colour in ROLE_COLOURS.items():
                sel = np.array([r["role"] == role and not _stage_point(r) for r in self.rows])
                if sel.any():
                    draw_residuals(ax, xy[sel], res[sel], k, colour, label=role_text(role))
            self._draw_stage_points(xy, res, k)
            if len(ind_xy):
                draw_residuals(ax, ind_xy, ind_res, k, INDEPENDENT_COLOUR, marker="^",
                               size=6, width=0.004, mec="black", mew=0.5,
                               label=role_text("independent"))
            ax.legend(loc="lower right", fontsize=7)
            ax.set_title(tr("Residuals (×{0:g})").format(k), fontsize=9)
        elif len(xy):
            ax.plot(xy[:, 0], xy[:, 1], ".", color="0.5", ms=3)
        self._every = np.vstack([xy, ind_xy])
        self._ring, = ax.plot([], [], "o", mfc="none", mec="yellow", ms=9)
        ax.set_aspect("equal")
        if self.thumb is not None:
            h, w = self.thumb.shape
            ax.set_xlim(-0.5, w * self.thumb_factor - 0.5)
            ax.set_ylim(h * self.thumb_factor - 0.5, -0.5)
        self._show_selection()

    def _draw_stage_points(self, xy: np.ndarray, res: np.ndarray, k: float) -> None:
        """The control points a stage found without object pairs (keypoints, the area
        search's grid): their own colour and legend entry, apart from manual points."""
        for origin in ("keypoints", "grid"):
            sel = np.array([_stage_point(r) and r["origin"] == origin for r in self.rows])
            if sel.any():
                draw_residuals(self.axes, xy[sel], res[sel], k, STAGE_POINT_COLOUR,
                               marker="s", size=4,
                               label=tr("control point ({0})").format(origin_text(origin)))

    def _show_selection(self) -> None:
        """Ring the selected table rows' points on the map."""
        if self._ring is None:
            return
        every = self._every
        selected = [r for r in sorted({i.row() for i in self.point_table.selectedIndexes()})
                    if r < len(every)]
        self._ring.set_data(every[selected, 0], every[selected, 1])
        self.canvas.draw_idle()

    def _on_click(self, event: Any) -> None:
        """Select the point (control or independent check point) nearest to a click."""
        if event.inaxes is not self.axes or event.xdata is None:
            return
        xy = np.vstack([self.review.image_xy(),
                        np.array([[p["col"], p["row"]] for p in self.check["points"]]
                                 ).reshape(-1, 2)])
        if not len(xy):
            return
        k = int(np.argmin(np.hypot(xy[:, 0] - event.xdata, xy[:, 1] - event.ydata)))
        self.tabs.setCurrentWidget(self.point_table)
        self.point_table.selectRow(k)

    # -- saving ----------------------------------------------------------------------------------
    def save(self) -> bool:
        """Write the products again; True on success."""
        progress = QtWidgets.QProgressDialog(tr("Writing the georeferenced image …"),
                                             tr("Cancel"), 0, 100, self)
        progress.setWindowModality(QtCore.Qt.WindowModal)
        progress.setMinimumDuration(500)
        feedback = Feedback(on_progress=lambda pct: (progress.setValue(int(pct)),
                                                     QtWidgets.QApplication.processEvents()))
        progress.canceled.connect(feedback.cancel)
        try:
            paths = save_review(self.review, feedback=feedback, fit=self.fit)
        except Cancelled:
            return False
        except PhotodemError as exc:
            self._error(error_text(exc))
            return False
        finally:
            progress.close()
        self.dirty = False
        self._show_fit()  # the state is unchanged: only the summary loses "not saved"
        self.saved.emit(paths)
        return True

    def _error(self, text: str) -> None:
        self.summary.setText(f"<span style='color:#c0392b'>{text}</span>")
        if self.message_boxes:
            QtWidgets.QMessageBox.warning(self, tr("PhotoDEM"), text)

    def closeEvent(self, event: Any) -> None:
        if self.dirty and self.message_boxes:
            answer = QtWidgets.QMessageBox.question(
                self, tr("PhotoDEM"), tr("Discard the changes that are not saved?"),
                QtWidgets.QMessageBox.Discard | QtWidgets.QMessageBox.Cancel)
            if answer != QtWidgets.QMessageBox.Discard:
                event.ignore()
                return
        super().closeEvent(event)


def open_review(parent: Optional[QtWidgets.QWidget], folder: Optional[str] = None,
                start: str = "", message_boxes: bool = True,
                on_error: Optional[Callable[[str], None]] = None
                ) -> Optional[GeorefReviewDialog]:
    """Open (and show) the review dialog of a georeferencing output folder — the toolbox's
    and the QGIS plugin's entry. Asks for the folder (starting at ``start``) unless given;
    a folder without a result goes to ``on_error`` and gives ``None``."""
    if not folder:
        folder = QtWidgets.QFileDialog.getExistingDirectory(
            parent, tr("Output folder of a georeferencing"), start)
        if not folder:
            return None
    try:
        dialog = GeorefReviewDialog(folder, parent, message_boxes=message_boxes)
    except PhotodemError as exc:
        if on_error is not None:
            on_error(error_text(exc))
        return None
    dialog.setAttribute(QtCore.Qt.WA_DeleteOnClose)
    dialog.show()
    return dialog


def _thumbnail(path: Path, max_side: int = 800) -> tuple:
    """The image's band mean at most ``max_side`` pixels wide/high, and its reduction
    factor (``None, 1`` when it cannot be read: the map then shows the points only)."""
    try:
        with open_image(path) as src:
            f = max(1, int(np.ceil(max(src.width, src.height) / max_side)))
            shape = (src.count, max(1, src.height // f), max(1, src.width // f))
            data = src.read(out_shape=shape, resampling=rasterio.enums.Resampling.average)
        return data.astype(np.float32).mean(axis=0), src.width / shape[2]
    except Exception:  # a missing or unreadable copy: the review works without the picture
        return None, 1


def _stage_point(row: Dict[str, Any]) -> bool:
    """A point row in the fit that a stage found without an object pair (keypoints, grid)."""
    return row["role"] == "control" and row["origin"] in ("keypoints", "grid")


def _fmt(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return tr("yes") if value else tr("no")
    if isinstance(value, float):
        if not np.isfinite(value):
            return "–"
        return f"{value:.3f}" if abs(value) < 1e5 else f"{value:.2f}"
    return str(value)
