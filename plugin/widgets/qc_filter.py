"""The QC panel's *Filter review* tab: re-filter the drawn area with another preset, see the
eliminated cells and the height change before/after, and write into the DTM only on *Accept*.

The computation is :func:`photodem.algorithms.filtering.review.refilter_area` (off the GUI
thread through the panel's worker); *Accept* is
:func:`~photodem.algorithms.filtering.review.accept_refilter`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Dict, Optional

import numpy as np
from matplotlib.colors import ListedColormap

from ...algorithms.errors import PhotodemError
from ...algorithms.filtering.presets import PRESET_NAMES
from ...algorithms.filtering.review import accept_refilter, refilter_area
from ..i18n import error_text, tr
from ..qt import QtWidgets, pyqtSignal
from .qc_plots import PlotCanvas
from .qc_worker import FunctionWorker

#: Colours of the eliminated-cells views: ground (transparent grey), object (red).
MASK_COLOURS = ListedColormap(["#d9d9d9", "#d7301f"])


class FilterReviewTab(QtWidgets.QWidget):
    """The review tab; ``panel`` is the :class:`~.qc_panel.QcPanel` it lives in (area,
    inputs, worker, messages).

    Signals
    -------
    dtm_changed(str)
        The DTM file an *Accept* wrote (the host refreshes its layer).
    """

    dtm_changed = pyqtSignal(str)

    def __init__(self, panel: Any) -> None:
        super().__init__(panel)
        self.panel = panel
        self.review: Optional[Dict[str, Any]] = None
        lay = QtWidgets.QVBoxLayout(self)
        form = QtWidgets.QHBoxLayout()
        self.dtm_edit = QtWidgets.QLineEdit(self)
        self.dtm_edit.setPlaceholderText(tr("dtm.tif of a PhotoDEM filter run (its mask.tif "
                                            "beside it)"))
        form.addWidget(QtWidgets.QLabel(tr("DTM"), self))
        form.addWidget(self.dtm_edit, 1)
        self.preset_combo = QtWidgets.QComboBox(self)
        for name in PRESET_NAMES:
            self.preset_combo.addItem(name, name)
        form.addWidget(QtWidgets.QLabel(tr("Preset"), self))
        form.addWidget(self.preset_combo)
        self.threshold_spin = QtWidgets.QDoubleSpinBox(self)
        self.threshold_spin.setRange(0.0, 20.0)
        self.threshold_spin.setSingleStep(0.1)
        self.threshold_spin.setSpecialValueText(tr("preset"))
        self.threshold_spin.setSuffix(" m")
        form.addWidget(QtWidgets.QLabel(tr("Final threshold"), self))
        form.addWidget(self.threshold_spin)
        self.run_button = QtWidgets.QPushButton(tr("Re-filter area"), self)
        self.run_button.clicked.connect(self.run)
        form.addWidget(self.run_button)
        lay.addLayout(form)
        self.plot = PlotCanvas(self)
        self.plot.clear(tr("Draw an area, choose a preset and press 'Re-filter area'"))
        lay.addWidget(self.plot, 1)
        row = QtWidgets.QHBoxLayout()
        self.summary = QtWidgets.QLabel(self)
        self.summary.setWordWrap(True)
        row.addWidget(self.summary, 1)
        self.accept_button = QtWidgets.QPushButton(tr("Accept into the DTM"), self)
        self.accept_button.setEnabled(False)
        self.accept_button.clicked.connect(lambda: self.accept())
        row.addWidget(self.accept_button)
        lay.addLayout(row)

    def run(self) -> bool:
        """Start the re-filtering of the panel's area (nothing is written)."""
        dsm = self.panel.inputs().get("dem")
        dtm = self.dtm_edit.text().strip()
        if self.panel.area is None:
            self.panel._report("warning", tr("Draw the area to re-filter first."))
            return False
        if not dsm or not Path(dsm).is_file() or not dtm or not Path(dtm).is_file():
            self.panel._report("warning", tr("Choose the DSM (as DEM) and the DTM it was "
                                             "filtered into."))
            return False
        over = {"threshold": self.threshold_spin.value() or None}
        kwargs = {"dsm": dsm, "dtm": dtm, "area": self.panel.area,
                  "preset": self.preset_combo.currentData(), "overrides": over,
                  "project": str(self.panel.project_root) if self.panel.project_root else None}
        return self.panel._start(FunctionWorker(refilter_area, kwargs), self._done,
                                 tr("Re-filtering the area…"))

    def _done(self, review: Dict[str, Any]) -> None:
        self.review = review
        self.draw(review)
        s, e = review["stats"], review["eliminated"]

        def pct(v: Optional[float]) -> str:
            return "–" if v is None else f"{100 * v:.1f} %"

        self.summary.setText(tr("Eliminated in the area: {0} before, {1} with '{2}'; new − old "
                                "DTM: median {3:+.3f} m, max |Δh| {4:.2f} m. Nothing is written "
                                "until you accept.")
                             .format(pct(e["before"]), pct(e["after"]), review["preset"],
                                     s["median"] or 0.0,
                                     max(abs(s["min"] or 0.0), abs(s["max"] or 0.0))))
        self.accept_button.setEnabled(True)
        self.panel.tabs.setCurrentWidget(self)

    def draw(self, review: Dict[str, Any]) -> None:
        """Eliminated cells before | after | new − old DTM, inside the area."""
        fig = self.plot.figure
        fig.clf()
        inside = review["inside"]
        h, w = review["window"][2:]
        t = review["transform"]
        extent = (t[2], t[2] + w * t[0], t[5] + h * t[4], t[5])
        views = ((review["old_mask"], tr("eliminated before")),
                 (review["new_mask"], tr("eliminated after")))
        for k, (mask, title) in enumerate(views, start=1):
            ax = fig.add_subplot(1, 3, k)
            ax.imshow(np.where(inside, mask, np.nan), cmap=MASK_COLOURS, vmin=0, vmax=1,
                      extent=extent, interpolation="nearest")
            ax.set_title(title, fontsize=9)
            ax.set_xticks([])
            ax.set_yticks([])
        ax = fig.add_subplot(1, 3, 3)
        d = np.where(inside, review["new"] - review["old"], np.nan)
        lim = max(float(np.nanmax(np.abs(d))) if np.isfinite(d).any() else 0.0, 0.1)
        im = ax.imshow(d, cmap="RdBu_r", vmin=-lim, vmax=lim, extent=extent,
                       interpolation="nearest")
        ax.set_title(tr("new − old DTM [m]"), fontsize=9)
        ax.set_xticks([])
        ax.set_yticks([])
        fig.colorbar(im, ax=ax, fraction=0.046, pad=0.04)
        self.plot.axes = fig.axes[0]
        self.plot.draw_idle()

    def accept(self, confirm: bool = True) -> bool:
        """Write the reviewed area into the DTM (asks first unless ``confirm`` is False)."""
        dtm = self.dtm_edit.text().strip()
        if self.review is None or not dtm:
            return False
        if confirm and QtWidgets.QMessageBox.question(
                self, tr("Accept into the DTM"),
                tr("Write the re-filtered area into '{0}' (and its mask)? The cells outside the "
                   "area stay as they are.").format(dtm)) != QtWidgets.QMessageBox.Yes:
            return False
        try:
            written = accept_refilter(dtm, self.review)
        except PhotodemError as exc:
            self.panel._report("error", error_text(exc))
            return False
        self.accept_button.setEnabled(False)
        self.panel._report("info", tr("The area was written into {0}.").format(written["dtm"]))
        self.dtm_changed.emit(written["dtm"])
        return True
