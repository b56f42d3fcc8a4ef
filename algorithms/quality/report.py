r"""The DEM comparison report: one self-contained HTML file, plus the numbers as JSON and CSV.

Figures are drawn with matplotlib's Agg canvas (no pyplot, no GUI backend: this also runs
inside QGIS) and embedded as base64 PNG, so the HTML opens anywhere without side files:

1. |Δh| in the 0.5 m classes to 5 m plus "> 5 m" with the cumulative share — the table format
   of DEM acceptance (Raguse 2000, Anhang 3) — and the signed distribution of Δh, counted
   window by window over the whole difference raster (exact, bounded memory);
2. the difference map over a hillshade of the DEM, read decimated (``out_shape``), never the
   whole raster;
3. box summaries per class drawn from the statistics only (``Axes.bxp``): the box is
   median ± MAD with :math:`\mathrm{MAD} = \mathrm{NMAD}/1.4826` (for a symmetric distribution
   exactly the interquartile range), the whiskers reach :math:`\mp q_{95}(|\Delta h|)` clipped to
   [min, max], the dots are min and max, the triangle is the mean;
4. error against slope class (mean, NMAD, RMS, 95 % |Δh|);
5. the tables: statistics in m and in ‰ of the flying height H
   (:math:`v_{‰} = 1000\,v/H`), the |Δh| classes, per class and per slope class.

Δh is always DEM − reference (positive: the DEM is too high).
"""

from __future__ import annotations

import base64
import html
import io
import json
import math
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import rasterio
from affine import Affine
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import BoundaryNorm, ListedColormap
from matplotlib.figure import Figure
from numpy.typing import NDArray
from rasterio.warp import Resampling, reproject, transform_bounds
from rasterio.windows import Window, from_bounds

from ..feedback import Feedback, ensure_feedback
from ..jsonable import json_ready
from ..raster.io import atomic_output
from .class_legend import class_label
from .rasters import DIFFERENCE_CLASSES, difference_bounds, difference_colors

PathLike = Union[str, Path]

#: Statistics shown in the summary table: key, label, kind ("m", "count", "share").
STAT_ROWS: Tuple[Tuple[str, str, str], ...] = (
    ("count", "cells compared", "count"),
    ("mean", "mean Δh (bias)", "m"),
    ("median", "median Δh", "m"),
    ("std", "standard deviation", "m"),
    ("rms", "RMS", "m"),
    ("nmad", "NMAD (1.4826 · median |Δh − median|)", "m"),
    ("min", "minimum Δh", "m"),
    ("max", "maximum Δh", "m"),
    ("q68", "68 % quantile of |Δh|", "m"),
    ("q90", "90 % quantile of |Δh|", "m"),
    ("q95", "95 % quantile of |Δh|", "m"),
    ("q99", "99 % quantile of |Δh|", "m"),
    ("share_0_25", "share |Δh| ≤ 0.25 m", "share"),
    ("share_0_5", "share |Δh| ≤ 0.5 m", "share"),
    ("share_1", "share |Δh| ≤ 1 m", "share"),
)

#: Columns of the CSV (after ``scope`` and ``name``).
CSV_KEYS = ("count", "mean", "median", "std", "rms", "nmad", "min", "max", "q68", "q90",
            "q95", "q99", "share_0_25", "share_0_5", "share_1")

#: Statistics that scale with H in the ‰ columns (lengths; not counts or shares).
LENGTH_KEYS = ("mean", "median", "std", "rms", "nmad", "min", "max", "q68", "q90", "q95", "q99")

#: Largest side (px) of the decimated rasters drawn in the map.
MAP_PIXELS = 900


# -- matplotlib without pyplot --------------------------------------------------------------------
def new_figure(width: float, height: float) -> Any:
    """A matplotlib Figure on an Agg canvas (inches); no global backend is touched."""
    fig = Figure(figsize=(width, height), dpi=100)
    FigureCanvasAgg(fig)
    return fig


def png_bytes(fig: Any, dpi: int = 110) -> bytes:
    """The figure as PNG bytes; no software/date metadata, so equal inputs give equal files."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, metadata={"Software": None})
    return buf.getvalue()


def _embed(fig: Any, alt: str) -> str:
    data = base64.b64encode(png_bytes(fig)).decode("ascii")
    return f'<img alt="{html.escape(alt)}" src="data:image/png;base64,{data}">'


# -- reading the statistics -----------------------------------------------------------------------
def _is_stats(value: Any) -> bool:
    return isinstance(value, dict) and "count" in value


def stats_entries(group: Any) -> List[Tuple[str, Dict[str, Any]]]:
    """(label, statistics) pairs of a per-class / per-slope result.

    Accepts ``{label: stats}``, ``{label: {"stats": stats, …}}`` and lists of dicts with a
    ``label``/``name``/``class`` key, so the report does not depend on how the grouping is
    keyed.
    """
    out: List[Tuple[str, Dict[str, Any]]] = []
    if isinstance(group, dict):
        items: List[Tuple[Any, Any]] = list(group.items())
    elif isinstance(group, (list, tuple)):
        items = []
        for entry in group:
            if isinstance(entry, dict):
                label = entry.get("label", entry.get("name", entry.get("class", len(items))))
                items.append((label, entry))
    else:
        return out
    for label, value in items:
        stats = value if _is_stats(value) else (value.get("stats") if isinstance(value, dict)
                                                else None)
        if _is_stats(stats):
            out.append((str(label), stats))
    return out


def _num(stats: Dict[str, Any], key: str) -> float:
    value = stats.get(key)
    try:
        return float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return float("nan")


def _share(value: float) -> float:
    """A share as percent (statistics give fractions 0…1)."""
    return 100.0 * value


def _permille(stats: Dict[str, Any], key: str, flying_height: Optional[float]) -> float:
    per = stats.get("permille")
    if isinstance(per, dict) and key in per:
        return _num(per, key)
    if flying_height:
        return 1000.0 * _num(stats, key) / float(flying_height)
    return float("nan")


def _fmt(value: float, kind: str = "m") -> str:
    if value is None or not math.isfinite(value):
        return "–"
    if kind == "count":
        return f"{round(value):,}".replace(",", "\u202f")
    if kind == "share":
        return f"{_share(value):.1f} %"
    if kind == "permille":
        return f"{value:.3f} ‰"
    return f"{value:.3f}"


# -- numbers from the difference raster -----------------------------------------------------------
def signed_histogram(difference: PathLike, limit: float, bins: int,
                     window_rows: int = 1024) -> Dict[str, Any]:
    """Histogram of the signed Δh over the whole raster, read in strips of rows.

    Returns
    -------
    dict
        ``edges`` (bins + 1 values from −limit to +limit), ``counts``, ``under`` and ``over``
        (cells beyond ±limit).
    """
    edges = np.linspace(-limit, limit, bins + 1)
    counts = np.zeros(bins, dtype=np.int64)
    under = over = 0
    with rasterio.open(difference) as src:
        for r0 in range(0, src.height, window_rows):
            h = min(window_rows, src.height - r0)
            data = src.read(1, window=Window(0, r0, src.width, h), masked=True)
            v = np.ma.filled(data.astype(np.float64), np.nan)
            v = v[np.isfinite(v)]
            counts += np.histogram(v, bins=edges)[0]
            under += int(np.count_nonzero(v < -limit))
            over += int(np.count_nonzero(v > limit))
    return {"edges": edges.tolist(), "counts": counts.tolist(), "under": under, "over": over}


def read_decimated(path: PathLike, bounds: Optional[Tuple[float, float, float, float]] = None,
                   max_pixels: int = MAP_PIXELS) -> Tuple[NDArray[Any], Any, Any]:
    """Read band 1 at reduced resolution (``out_shape``): at most ``max_pixels`` per side.

    Returns
    -------
    array (NaN = nodata), transform of the reduced grid, CRS
    """
    with rasterio.open(path) as src:
        if bounds is None:
            window = Window(0, 0, src.width, src.height)
        else:
            window = from_bounds(*bounds, transform=src.transform).round_offsets().round_lengths()
        w, h = max(int(window.width), 1), max(int(window.height), 1)
        scale = max(w / max_pixels, h / max_pixels, 1.0)
        shape = (max(round(h / scale), 1), max(round(w / scale), 1))
        data = src.read(1, window=window, out_shape=shape, masked=True,
                        boundless=bounds is not None)
        arr = np.ma.filled(data.astype(np.float64), np.nan)
        transform = src.window_transform(window) * Affine.scale(w / shape[1], h / shape[0])
        return arr, transform, src.crs


def _hillshade_on(hillshade: PathLike, transform: Any, crs: Any,
                  shape: Tuple[int, int]) -> Optional[NDArray[Any]]:
    """The hillshade resampled onto a small grid (decimated read, then reprojected)."""
    h, w = shape
    left, top = transform * (0, 0)
    right, bottom = transform * (w, h)
    bounds = (min(left, right), min(top, bottom), max(left, right), max(top, bottom))
    with rasterio.open(hillshade) as src:
        hs_crs = src.crs
    if crs is not None and hs_crs is not None and hs_crs != crs:
        bounds = transform_bounds(crs, hs_crs, *bounds)
    try:
        arr, hs_transform, _ = read_decimated(hillshade, bounds, max_pixels=2 * max(shape))
    except Exception:  # no overlap or unreadable: the map is drawn without relief
        return None
    arr = np.where(arr > 0, arr, np.nan)  # 0 is the hillshade's nodata
    out = np.full(shape, np.nan)
    reproject(arr, out, src_transform=hs_transform, src_crs=hs_crs or crs,
              dst_transform=transform, dst_crs=crs or hs_crs, src_nodata=np.nan,
              dst_nodata=np.nan, resampling=Resampling.bilinear)
    return out


# -- figures --------------------------------------------------------------------------------------
def _histogram_limit(stats: Dict[str, Any]) -> float:
    q99 = _num(stats, "q99")
    if not math.isfinite(q99) or q99 <= 0:
        q99 = max(abs(_num(stats, "min")), abs(_num(stats, "max")), 0.5)
    return float(min(max(math.ceil(1.1 * q99 / 0.5) * 0.5, 0.5), 50.0))


def figure_histograms(stats: Dict[str, Any], signed: Optional[Dict[str, Any]]) -> Any:
    """|Δh| classes with cumulative share (left) and the signed distribution (right)."""
    fig = new_figure(11.0, 4.2)
    ax = fig.add_subplot(1, 2, 1)
    hist = stats.get("histogram") or {}
    edges = list(hist.get("edges") or [])
    counts = list(hist.get("counts") or [])
    over = int(hist.get("over") or 0)
    total = max(sum(counts) + over, 1)
    if counts and len(edges) == len(counts) + 1:
        labels = [f"{a:g}–{b:g}" for a, b in zip(edges[:-1], edges[1:])] + [f"> {edges[-1]:g}"]
        values = [100.0 * c / total for c in [*counts, over]]
        pos = np.arange(len(values))
        ax.bar(pos, values, color="#4393c3", edgecolor="#2166ac", width=0.8)
        ax.set_xticks(pos)
        ax.set_xticklabels(labels, rotation=45, ha="right", fontsize=8)
        ax.set_xlabel("|Δh| class [m]")
        ax.set_ylabel("cells [%]")
        ax2 = ax.twinx()
        ax2.plot(pos, np.cumsum(values), color="#b2182b", marker="o", markersize=3)
        ax2.set_ylim(0, 102)
        ax2.set_ylabel("cumulative [%]", color="#b2182b")
        ax2.tick_params(axis="y", colors="#b2182b")
    ax.set_title("|Δh| in 0.5 m classes")
    ax.grid(True, axis="y", alpha=0.3)

    ax = fig.add_subplot(1, 2, 2)
    if signed is not None:
        e = np.asarray(signed["edges"])
        c = np.asarray(signed["counts"], dtype=float)
        width = float(e[1] - e[0])
        ax.bar(e[:-1], 100.0 * c / max(c.sum() + signed["under"] + signed["over"], 1),
               width=width, align="edge", color="#92c5de", edgecolor="#4393c3", linewidth=0.3)
        ax.set_ylabel(f"cells per {width:g} m bin [%]")
        note = []
        if signed["under"]:
            note.append(f"{signed['under']} cells < −{e[-1]:g} m")
        if signed["over"]:
            note.append(f"{signed['over']} cells > +{e[-1]:g} m")
        if note:
            ax.text(0.02, 0.97, "\n".join(note), transform=ax.transAxes, va="top", fontsize=8)
    for key, colour, style in (("mean", "#b2182b", "-"), ("median", "#2166ac", "--")):
        v = _num(stats, key)
        if math.isfinite(v):
            ax.axvline(v, color=colour, linestyle=style, linewidth=1.2,
                       label=f"{key} {v:+.3f} m")
    ax.axvspan(-0.25, 0.25, color="#ffffbf", alpha=0.6, zorder=0, label="±0.25 m")
    ax.set_xlabel("Δh = DEM − reference [m]")
    ax.set_title("Signed distribution of Δh")
    ax.legend(loc="upper right", fontsize=8)
    ax.grid(True, axis="y", alpha=0.3)
    fig.tight_layout()
    return fig


def _colormap() -> Tuple[Any, Any]:
    colours = difference_colors()
    cmap = ListedColormap(colours[1:-1]).with_extremes(under=colours[0], over=colours[-1],
                                                       bad=(0, 0, 0, 0))
    bounds = difference_bounds()
    return cmap, BoundaryNorm(bounds, cmap.N)


def figure_map(difference: PathLike, hillshade: Optional[PathLike]) -> Any:
    """The difference model (classes of :data:`.rasters.DIFFERENCE_CLASSES`) over a hillshade."""
    diff, transform, crs = read_decimated(difference)
    h, w = diff.shape
    relief = _hillshade_on(hillshade, transform, crs, diff.shape) if hillshade else None
    left, top = transform * (0, 0)
    right, bottom = transform * (w, h)
    extent = (left, right, bottom, top)
    aspect = (top - bottom) / max(right - left, 1e-9)
    fig = new_figure(10.0, float(np.clip(8.2 * aspect, 3.5, 11.0)) + 0.8)
    ax = fig.add_subplot(1, 1, 1)
    if relief is not None and np.isfinite(relief).any():
        ax.imshow(np.ma.masked_invalid(relief), cmap="gray", extent=extent, vmin=1, vmax=255,
                  interpolation="nearest")
        alpha = 0.65
    else:
        alpha = 1.0
    cmap, norm = _colormap()
    image = ax.imshow(np.ma.masked_invalid(diff), cmap=cmap, norm=norm, extent=extent,
                      alpha=alpha, interpolation="nearest")
    cbar = fig.colorbar(image, ax=ax, extend="both", shrink=0.85, pad=0.02)
    cbar.set_label("Δh = DEM − reference [m]")
    cbar.set_ticks(difference_bounds())
    cbar.set_ticklabels([f"{b:g}" for b in difference_bounds()])
    units = "m"
    if crs is not None and getattr(crs, "is_geographic", False):
        units = "°"
    ax.set_xlabel(f"Easting [{units}]")
    ax.set_ylabel(f"Northing [{units}]")
    ax.ticklabel_format(useOffset=False, style="plain")
    for label in ax.get_xticklabels():
        label.set_rotation(30)
        label.set_ha("right")
    ax.set_title("Difference model over the hillshade of the DEM"
                 if relief is not None else "Difference model")
    fig.tight_layout()
    return fig


def box_summary(label: str, stats: Dict[str, Any]) -> Dict[str, Any]:
    """A ``bxp`` box from statistics: median ± MAD, whiskers ∓q95(|Δh|) within [min, max]."""
    med, nmad = _num(stats, "median"), _num(stats, "nmad")
    lo, hi, q95 = _num(stats, "min"), _num(stats, "max"), _num(stats, "q95")
    mad = nmad / 1.4826 if math.isfinite(nmad) else 0.0
    q1, q3 = med - mad, med + mad
    whislo = max(-q95, lo) if math.isfinite(q95) else lo
    whishi = min(q95, hi) if math.isfinite(q95) else hi
    whislo, whishi = min(whislo, q1), max(whishi, q3)  # a whisker never inside the box
    return {"label": label, "med": med, "q1": q1, "q3": q3, "whislo": whislo,
            "whishi": whishi, "mean": _num(stats, "mean"), "fliers": [lo, hi]}


def figure_boxplots(entries: Sequence[Tuple[str, Dict[str, Any]]], title: str) -> Any:
    """Box summaries of Δh per class, from the statistics alone (no raw values needed)."""
    boxes = [box_summary(f"{label}\nn={int(_num(s, 'count'))}", s)
             for label, s in entries if _num(s, "count") > 0]
    fig = new_figure(max(6.0, 0.9 * len(boxes) + 2.5), 4.6)
    ax = fig.add_subplot(1, 1, 1)
    if boxes:
        ax.bxp(boxes, showmeans=True, showfliers=True, patch_artist=True,
               boxprops={"facecolor": "#c6dbef"},
               flierprops={"marker": "o", "markersize": 4, "markerfacecolor": "#444444"},
               meanprops={"marker": "^", "markerfacecolor": "#b2182b",
                          "markeredgecolor": "#b2182b"},
               medianprops={"color": "#08306b"})
        for tick in ax.get_xticklabels():
            tick.set_fontsize(8)
    ax.axhspan(-0.25, 0.25, color="#ffffbf", alpha=0.7, zorder=0)
    ax.axhline(0.0, color="#555555", linewidth=0.8)
    ax.set_ylabel("Δh = DEM − reference [m]")
    ax.set_title(title)
    ax.grid(True, axis="y", alpha=0.3)
    fig.tight_layout()
    return fig


def figure_slope(entries: Sequence[Tuple[str, Dict[str, Any]]]) -> Any:
    """Error measures per slope class."""
    fig = new_figure(8.0, 4.4)
    ax = fig.add_subplot(1, 1, 1)
    used = [(label, s) for label, s in entries if _num(s, "count") > 0]
    pos = np.arange(len(used))
    for key, name, colour, marker in (("rms", "RMS", "#b2182b", "o"),
                                      ("q95", "95 % |Δh|", "#f4a582", "s"),
                                      ("nmad", "NMAD", "#2166ac", "D"),
                                      ("mean", "mean (bias)", "#555555", "^")):
        ax.plot(pos, [_num(s, key) for _, s in used], marker=marker, color=colour, label=name)
    ax.set_xticks(pos)
    ax.set_xticklabels([f"{label}\nn={int(_num(s, 'count'))}" for label, s in used],
                       fontsize=8)
    ax.axhline(0.0, color="#999999", linewidth=0.8)
    ax.set_xlabel("slope class [°]")
    ax.set_ylabel("Δh [m]")
    ax.set_title("Error against terrain slope")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    return fig


# -- tables ---------------------------------------------------------------------------------------
def _table(header: Sequence[str], rows: Sequence[Sequence[str]], cls: str = "") -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in row) + "</tr>"
                   for row in rows)
    return f'<table class="{cls}"><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>'


def summary_table(stats: Dict[str, Any], flying_height: Optional[float]) -> str:
    header = ["statistic", "value [m]"] + (["‰ H"] if flying_height else [])
    rows = []
    for key, label, kind in STAT_ROWS:
        value = _num(stats, key)
        row = [label, _fmt(value, kind)]
        if flying_height:
            row.append(_fmt(_permille(stats, key, flying_height), "permille")
                       if key in LENGTH_KEYS else "")
        rows.append(row)
    return _table(header, rows)


def classes_table(stats: Dict[str, Any]) -> str:
    """|Δh| classes with cells, share and cumulative share (Raguse 2000, Anhang 3)."""
    hist = stats.get("histogram") or {}
    edges, counts = list(hist.get("edges") or []), list(hist.get("counts") or [])
    over = int(hist.get("over") or 0)
    total = max(sum(counts) + over, 1)
    rows, cum = [], 0
    labels = [f"{a:.1f} – {b:.1f}" for a, b in zip(edges[:-1], edges[1:])]
    if edges:
        labels.append(f"> {edges[-1]:.1f}")
    for label, count in zip(labels, [*counts, over]):
        cum += count
        rows.append([label, _fmt(count, "count"), f"{100.0 * count / total:.1f} %",
                     f"{100.0 * cum / total:.1f} %"])
    return _table(["|Δh| [m]", "cells", "share", "cumulative"], rows)


def group_table(entries: Sequence[Tuple[str, Dict[str, Any]]], first: str,
                flying_height: Optional[float]) -> str:
    header = [first, "cells", "mean", "median", "std", "RMS", "NMAD", "min", "max",
              "95 % |Δh|", "≤ 0.5 m"]
    if flying_height:
        header.append("RMS ‰ H")
    rows = []
    for label, s in entries:
        row = [label, _fmt(_num(s, "count"), "count")]
        row += [_fmt(_num(s, k)) for k in ("mean", "median", "std", "rms", "nmad", "min", "max",
                                           "q95")]
        row.append(_fmt(_num(s, "share_0_5"), "share"))
        if flying_height:
            row.append(_fmt(_permille(s, "rms", flying_height), "permille"))
        rows.append(row)
    return _table(header, rows, "wide") + '<p class="note">heights in m</p>'


def shift_table(shift: Dict[str, Any]) -> str:
    rows = [["dx (east)", _fmt(_num(shift, "dx")) + " m"],
            ["dy (north)", _fmt(_num(shift, "dy")) + " m"],
            ["dz (vertical)", _fmt(_num(shift, "dz")) + " m"]]
    if "iterations" in shift:
        rows.append(["iterations", str(shift.get("iterations"))])
    if "converged" in shift:
        rows.append(["converged", "yes" if shift.get("converged") else "no"])
    return _table(["co-registration shift (applied to the DEM)", "value"], rows)


# -- the files ------------------------------------------------------------------------------------
def csv_rows(result: Dict[str, Any], flying_height: Optional[float] = None) -> List[List[str]]:
    """One row per scope (all, class, slope) with the statistics and the |Δh| class counts."""
    stats = result.get("stats") or {}
    edges = list((stats.get("histogram") or {}).get("edges") or [])
    hist_cols = [f"n_{a:g}_{b:g}" for a, b in zip(edges[:-1], edges[1:])]
    if edges:
        hist_cols.append(f"n_over_{edges[-1]:g}")
    per_cols = [f"{k}_permille" for k in LENGTH_KEYS] if flying_height else []
    rows = [["scope", "name", *CSV_KEYS, *hist_cols, *per_cols]]
    groups = [("all", [("all", stats)]),
              ("class", stats_entries(result.get("per_class"))),
              ("slope", stats_entries(result.get("per_slope"))),
              ("object", stats_entries(result.get("per_object")))]
    for scope, entries in groups:
        for name, s in entries:
            row = [scope, name.replace(",", ";")]
            for key in CSV_KEYS:
                v = _num(s, key)
                row.append("" if not math.isfinite(v) else
                           (str(int(v)) if key == "count" else f"{v:.6f}"))
            hist = s.get("histogram") or {}
            counts = [*list(hist.get("counts") or []), hist.get("over", "")]
            row += [str(c) for c in counts][:len(hist_cols)] + [""] * max(
                0, len(hist_cols) - len(counts))
            for key in LENGTH_KEYS if flying_height else ():
                v = _permille(s, key, flying_height)
                row.append("" if not math.isfinite(v) else f"{v:.6f}")
            rows.append(row)
    return rows


def completeness_rows(completeness: Dict[str, Any]) -> List[List[str]]:
    """Rows (scope, name, cells, measured, within_0_5, within_1) of a completeness result."""
    rows = [["scope", "name", "cells", "measured", "within_0_5", "within_1"]]
    for scope in ("class", "object"):
        for name, c in (completeness.get(f"per_{scope}") or {}).items():
            rows.append([scope, str(name).replace(",", ";"), str(int(c.get("cells") or 0))]
                        + ["" if c.get(k) is None else f"{c[k]:.6f}"
                           for k in ("measured", "within_0_5", "within_1")])
    return rows


def completeness_table(completeness: Dict[str, Any],
                       names: Optional[Dict[str, str]] = None) -> str:
    """HTML table of the completeness per class (named by ``names``: code → name) and per
    object class."""
    rows = [[("class " + class_label(r[1], names or {}) if r[0] == "class" else r[1]),
             _fmt(float(r[2]), "count")]
            + [_fmt(float(v), "share") if v else "–" for v in r[3:]]
            for r in completeness_rows(completeness)[1:]]
    return _table(["class", "reference cells", "measured", "within ±0.5 m", "within ±1 m"],
                  rows)


def write_completeness_csv(path: PathLike, completeness: Dict[str, Any]) -> Path:
    """The completeness as CSV (:func:`completeness_rows`), written atomically."""
    text = "\n".join(",".join(row) for row in completeness_rows(completeness)) + "\n"
    with atomic_output(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


def write_csv(path: PathLike, result: Dict[str, Any],
              flying_height: Optional[float] = None) -> Path:
    """The statistics as CSV (:func:`csv_rows`), written atomically."""
    text = "\n".join(",".join(row) for row in csv_rows(result, flying_height)) + "\n"
    with atomic_output(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


def write_json(path: PathLike, data: Dict[str, Any]) -> Path:
    """JSON (numpy values converted, NaN → null), written atomically.

    File names that are not UTF-8 (kept by Python as lone surrogates) are written as JSON
    escapes (``\\udce9``), which read back as the same name.
    """
    with atomic_output(path) as tmp:
        tmp.write_text(json.dumps(json_ready(data), indent=1, ensure_ascii=False) + "\n",
                       encoding="utf-8", errors="backslashreplace")
    return Path(path)


_CSS = """
body { font-family: "DejaVu Sans", Arial, sans-serif; margin: 24px auto; max-width: 1150px;
       color: #222; line-height: 1.4; }
h1 { font-size: 1.6em; margin-bottom: 0.2em; } h2 { font-size: 1.25em; margin-top: 1.6em;
  border-bottom: 1px solid #ccc; }
table { border-collapse: collapse; margin: 8px 0; font-size: 0.92em; }
th, td { border: 1px solid #ccc; padding: 3px 8px; text-align: right; }
th { background: #eef3f8; } td:first-child, th:first-child { text-align: left; }
table.wide { width: 100%; } img { max-width: 100%; height: auto; }
.note { color: #555; font-size: 0.88em; margin-top: 2px; }
.cols { display: flex; gap: 32px; flex-wrap: wrap; align-items: flex-start; }
"""


def write_report(path: PathLike, result: Dict[str, Any], *, dem: str, reference: str,
                 difference: Optional[PathLike] = None, hillshade: Optional[PathLike] = None,
                 flying_height: Optional[float] = None, title: str = "DEM comparison",
                 feedback: Optional[Feedback] = None) -> Path:
    """Write the self-contained HTML report of a DEM comparison.

    Parameters
    ----------
    path : path
        The HTML file (written atomically).
    result : dict
        What :func:`.compare.compare_dems` returns: ``stats``, ``shift`` (or None),
        ``per_class``, ``per_slope``, ``grid``.
    dem, reference : str
        Names of the compared DEMs as shown in the report (:func:`.names.report_path`: the
        project-relative or the absolute path, so that two ``dtm.tif`` can be told apart).
    difference, hillshade : path, optional
        The difference raster (map and signed histogram) and the DEM's hillshade (map
        background).
    flying_height : float, optional
        H in metres for the ‰ columns.
    """
    feedback = ensure_feedback(feedback)
    stats = result.get("stats") or {}
    names = result.get("class_names") or {}
    per_class = [(class_label(k, names), s) for k, s in stats_entries(result.get("per_class"))]
    per_slope = stats_entries(result.get("per_slope"))
    parts = [f"<h1>{html.escape(title)}</h1>",
             f"<p>DEM <b>{html.escape(dem)}</b> against reference <b>{html.escape(reference)}"
             "</b>. Δh = DEM − reference: positive where the DEM is too high. "
             + (f"Flying height H = {flying_height:g} m (‰ H = 1000 · value / H)."
                if flying_height else "") + "</p>"]
    grid = result.get("grid")
    if isinstance(grid, dict) and grid:
        items = [f"{html.escape(str(k))}: {html.escape(_plain(v))}" for k, v in grid.items()
                 if k in ("crs", "width", "height", "resolution")]
        parts.append('<p class="note">Comparison grid — ' + "; ".join(items) + "</p>")
    shift = result.get("shift")
    summary = summary_table(stats, flying_height)
    if isinstance(shift, dict):
        summary = f'<div class="cols"><div>{summary}</div><div>{shift_table(shift)}</div></div>'
    parts += ["<h2>Statistics</h2>", summary,
              '<p class="note">Statistics of all compared cells, on the unclassed values.</p>']
    signed = None
    if difference is not None and Path(difference).is_file():
        signed = signed_histogram(difference, _histogram_limit(stats), 100)
    feedback.progress(20.0)
    parts += ["<h2>Distribution of the differences</h2>",
              _embed(figure_histograms(stats, signed), "histograms of the differences"),
              '<div class="cols"><div>', classes_table(stats), "</div></div>"]
    if difference is not None and Path(difference).is_file():
        parts += ["<h2>Difference map</h2>",
                  _embed(figure_map(difference, hillshade), "difference map"),
                  '<p class="note">Pale yellow: |Δh| ≤ 0.25 m; blue: DEM below the reference; '
                  "red: DEM above it. Drawn at reduced resolution; open the difference raster "
                  "in QGIS (its style is beside it) for every cell.</p>"]
    feedback.progress(60.0)
    if per_class:
        parts += ["<h2>By class</h2>",
                  _embed(figure_boxplots(per_class, "Δh by class"), "box plots by class"),
                  '<p class="note">Box: median ± MAD (MAD = NMAD / 1.4826, the interquartile '
                  "range of a symmetric distribution); whiskers: ∓ 95 % quantile of |Δh| "
                  "within min…max; dots: min and max; triangle: mean.</p>",
                  group_table(per_class, "class", flying_height)]
    parts += _object_parts(result, flying_height)
    if per_slope:
        parts += ["<h2>By slope</h2>", _embed(figure_slope(per_slope), "error against slope"),
                  group_table(per_slope, "slope class [°]", flying_height)]
    feedback.progress(90.0)
    legend = ", ".join(f"{label}" for _, _, label in DIFFERENCE_CLASSES)
    parts.append(f'<p class="note">Difference classes: {html.escape(legend)}.</p>')
    page = ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{html.escape(title)}</title><style>{_CSS}</style></head><body>\n"
            + "\n".join(parts) + "\n</body></html>\n")
    with atomic_output(path) as tmp:
        tmp.write_text(page, encoding="utf-8")
    feedback.progress(100.0)
    return Path(path)


def _object_parts(result: Dict[str, Any], flying_height: Optional[float]) -> List[str]:
    """HTML of the statistics per object class and of the completeness (when computed)."""
    parts: List[str] = []
    per_object = stats_entries(result.get("per_object"))
    if per_object:
        parts += ["<h2>By object class</h2>", group_table(per_object, "object class",
                                                          flying_height),
                  '<p class="note">Object: reference ≥ the object height above the terrain '
                  "model; interior: at least 1 m inside an object; open: less than 0.3 m "
                  "above the terrain and at least 1 m from any object.</p>"]
    comp = result.get("completeness")
    if comp:
        parts += ["<h2>Completeness</h2>",
                  completeness_table(comp, result.get("class_names")),
                  '<p class="note">Of the cells with a reference height: the share the DEM '
                  "measures at all, and the shares within ±0.5 m and ±1 m of the reference "
                  "(cells the DEM leaves empty count as misses).</p>"]
    return parts


def _plain(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, (list, tuple)):
        return ", ".join(_plain(v) for v in value)
    return str(value)


__all__ = [
    "box_summary",
    "completeness_rows",
    "completeness_table",
    "csv_rows",
    "figure_boxplots",
    "figure_histograms",
    "figure_map",
    "figure_slope",
    "new_figure",
    "png_bytes",
    "read_decimated",
    "signed_histogram",
    "stats_entries",
    "write_completeness_csv",
    "write_csv",
    "write_json",
    "write_report",
]
