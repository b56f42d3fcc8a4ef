"""The QC panel's plots and tables: Δh histogram, profile, statistics tables (Qt + matplotlib).

Pure views: they draw what the core (:mod:`photodem.algorithms.quality.qc_stats`,
:mod:`~photodem.algorithms.quality.qc_profile`) computed and hold no state beyond it.
"""

from __future__ import annotations

import math
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np
from matplotlib.backends.backend_qt5agg import FigureCanvasQTAgg
from matplotlib.figure import Figure

from ...algorithms.quality.class_legend import class_label
from ...algorithms.quality.qc_stats import rebin_histogram
from ..i18n import tr
from ..qt import QtWidgets

#: Curve colours of the profile (up to 5 surfaces), colour-blind safe (Okabe–Ito).
PROFILE_COLOURS = ("#0072b2", "#d55e00", "#009e73", "#cc79a7", "#e69f00")


def stat_rows() -> List[Tuple[str, str, str]]:
    """(key, label, unit) of the statistics table, in display order."""
    return [("count", tr("Count"), ""), ("mean", tr("Mean"), "m"),
            ("median", tr("Median"), "m"), ("std", tr("Std. deviation"), "m"),
            ("rms", "RMS", "m"), ("nmad", "NMAD", "m"), ("min", tr("Minimum"), "m"),
            ("max", tr("Maximum"), "m"), ("q68", tr("68 % quantile of |Δh|"), "m"),
            ("q90", tr("90 % quantile of |Δh|"), "m"), ("q95", tr("95 % quantile of |Δh|"), "m"),
            ("q99", tr("99 % quantile of |Δh|"), "m"),
            ("share_0_25", tr("Within ±0.25 m"), "%"), ("share_0_5", tr("Within ±0.5 m"), "%"),
            ("share_1", tr("Within ±1 m"), "%")]


def format_value(value: Any, unit: str) -> str:
    """A statistic as the tables show it (``–`` when undefined)."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "–"
    if unit == "%":
        return f"{100.0 * value:.1f} %"
    if unit == "m":
        return f"{value:.3f}"
    return f"{int(value):,}".replace(",", "\u202f")


def _item(text: str) -> QtWidgets.QTableWidgetItem:
    item = QtWidgets.QTableWidgetItem(text)
    item.setFlags(item.flags() & ~0x2)  # not editable (Qt.ItemIsEditable)
    return item


def fill_stats_table(table: QtWidgets.QTableWidget, stats: Optional[Dict[str, Any]]) -> None:
    """One row per statistic (label, value)."""
    rows = stat_rows()
    table.setColumnCount(2)
    table.setHorizontalHeaderLabels([tr("Statistic"), tr("Value")])
    table.setRowCount(len(rows))
    for r, (key, label, unit) in enumerate(rows):
        table.setItem(r, 0, _item(label))
        table.setItem(r, 1, _item(format_value((stats or {}).get(key), unit)))
    table.resizeColumnsToContents()
    table.setColumnWidth(1, max(table.columnWidth(1), table.fontMetrics().width("-00000.000")))
    width = table.columnWidth(0) + table.columnWidth(1) + table.verticalScrollBar().sizeHint()\
        .width() + 2 * table.frameWidth() + 4
    table.setMinimumWidth(width)


GROUP_KEYS = (("count", ""), ("mean", "m"), ("median", "m"), ("nmad", "m"), ("rms", "m"),
              ("share_0_5", "%"))


def fill_group_table(table: QtWidgets.QTableWidget, result: Optional[Dict[str, Any]]) -> None:
    """Per class (with names) and per slope class: count, mean, median, NMAD, RMS, ±0.5 m."""
    res = result or {}
    names = res.get("class_names") or {}
    rows = [(tr("Class"), class_label(k, names), v) for k, v in res.get("per_class", {}).items()]
    rows += [(tr("Slope"), k, v) for k, v in res.get("per_slope", {}).items()]
    table.setColumnCount(2 + len(GROUP_KEYS))
    table.setHorizontalHeaderLabels([tr("Grouping"), tr("Group"), tr("Count"), tr("Mean"),
                                     tr("Median"), "NMAD", "RMS", tr("Within ±0.5 m")])
    table.setRowCount(len(rows))
    for r, (grouping, label, stats) in enumerate(rows):
        table.setItem(r, 0, _item(grouping))
        table.setItem(r, 1, _item(label))
        for c, (key, unit) in enumerate(GROUP_KEYS, start=2):
            table.setItem(r, c, _item(format_value(stats.get(key), unit)))
    table.resizeColumnsToContents()


class PlotCanvas(FigureCanvasQTAgg):
    """A matplotlib canvas with one axes, sized for a dock."""

    def __init__(self, parent: Optional[QtWidgets.QWidget] = None) -> None:
        self.figure = Figure(figsize=(5.0, 3.0), dpi=90, tight_layout=True)
        super().__init__(self.figure)
        self.setParent(parent)
        self.setMinimumHeight(220)
        self.axes = self.figure.add_subplot(1, 1, 1)

    def clear(self, message: str = "") -> None:
        self.axes.clear()
        if message:
            self.axes.text(0.5, 0.5, message, ha="center", va="center", color="grey",
                           transform=self.axes.transAxes)
            self.axes.set_axis_off()
        else:
            self.axes.set_axis_on()
        self.draw_idle()


def histogram_range(stats: Dict[str, Any]) -> Tuple[float, float]:
    """Median ± 5 NMAD (at least ± 0.5 m), rounded outwards to 0.1 m."""
    med = stats.get("median") or 0.0
    half = max(5.0 * (stats.get("nmad") or 0.0), 0.5)
    return math.floor((med - half) * 10) / 10, math.ceil((med + half) * 10) / 10


def draw_histogram(canvas: PlotCanvas, result: Dict[str, Any]) -> None:
    """The signed Δh histogram of an area statistic, with median and ±NMAD marked."""
    stats, hist = result.get("stats") or {}, result.get("histogram")
    if not hist or not stats.get("count"):
        canvas.clear(tr("No differences in this area"))
        return
    lo, hi = histogram_range(stats)
    edges, counts = rebin_histogram(hist, lo, hi, bins=60)
    ax = canvas.axes
    ax.clear()
    ax.set_axis_on()
    ax.bar(edges[:-1], counts, width=np.diff(edges), align="edge", color="#4393c3",
           edgecolor="white", linewidth=0.3)
    med, nmad = stats["median"], stats.get("nmad") or 0.0
    ax.axvline(med, color="#b2182b", linewidth=1.2, label=tr("median {0:.3f} m").format(med))
    for s in (-1, 1):
        ax.axvline(med + s * nmad, color="#b2182b", linewidth=0.8, linestyle="--")
    outside = int(stats["count"] - counts.sum())
    ax.set_title(tr("Δh histogram: {0} cells, NMAD {1:.3f} m").format(stats["count"], nmad)
                 + "\n" + tr("{0} cells outside the plot").format(outside), fontsize=9)
    ax.set_xlabel(tr("Δh = DEM − reference [m]"))
    ax.set_ylabel(tr("Cells"))
    ax.legend(loc="upper right", fontsize=8)
    canvas.draw_idle()


def draw_profile(canvas: PlotCanvas, profile: Dict[str, Any]) -> None:
    """Curves of the surfaces, breakline crossings (dashed), check points and vertex heights."""
    ax = canvas.axes
    ax.clear()
    ax.set_axis_on()
    d = profile["distance"]
    for colour, name in zip(PROFILE_COLOURS, profile["names"]):
        ax.plot(d, profile["heights"][name], color=colour, linewidth=1.2, label=name)
    for k, c in enumerate(profile.get("crossings", [])):
        ax.axvline(c["distance"], color="#555555", linewidth=0.9, linestyle="--",
                   label=tr("breakline") if k == 0 else None)
        if c.get("z") is not None:
            ax.plot([c["distance"]], [c["z"]], marker="D", color="#555555", markersize=5)
    cps = profile.get("check_points", [])
    if cps:
        z = [c["z"] if c["z"] is not None else np.nan for c in cps]
        ax.plot([c["distance"] for c in cps], z, linestyle="none", marker="^",
                color="#000000", markersize=7, label=tr("check point"))
    vert = profile.get("vertices")
    if vert is not None:
        ax.plot(vert["distance"], vert["z"], linestyle=":", marker="o", color="#7f7f7f",
                markersize=4, label=tr("line vertices (Z)"))
    ax.set_xlim(0.0, float(d[-1]))
    ax.set_xlabel(tr("Distance along the line [m]"))
    ax.set_ylabel(tr("Height [m]"))
    ax.set_title(tr("Profile: {0:.1f} m, spacing {1:g} m").format(profile["length"],
                                                                   profile["spacing"]),
                 fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    canvas.draw_idle()


def blunder_columns() -> List[str]:
    """Headers of the blunder table."""
    return ["#", tr("Cells"), tr("Area [m²]"), tr("Max. Δh [m]"), tr("Mean Δh [m]"), "X", "Y"]


def fill_blunder_table(table: QtWidgets.QTableWidget, spots: Sequence[Dict[str, Any]]) -> None:
    """One row per spot, largest first (the core's order)."""
    table.setColumnCount(len(blunder_columns()))
    table.setHorizontalHeaderLabels(blunder_columns())
    table.setRowCount(len(spots))
    for r, s in enumerate(spots):
        values = [str(s["id"]), str(s["cells"]), f"{s['area_m2']:.2f}", f"{s['max_dh']:+.2f}",
                  f"{s['mean_dh']:+.2f}", f"{s['centroid'][0]:.2f}", f"{s['centroid'][1]:.2f}"]
        for c, text in enumerate(values):
            table.setItem(r, c, _item(text))
    table.resizeColumnsToContents()
