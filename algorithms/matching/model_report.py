r"""The internal quality report of one matched stereo model: ``report.json`` + ``report.html``.

The HTML is self-contained (figures as embedded PNG, drawn on matplotlib's Agg canvas by the
helpers of :mod:`..quality.report`, with the look of the DEM-comparison report):

1. headline metrics: method, model, images, points raw / reduced / failed, the shares of the
   model area measured / interpolated / empty (they add up to 100 %), the internal accuracies
   σ1 (raw points) and σ2 = F·σ1/√n̄ (reduced points, seed-000 §5.1) in metres and in per
   mille of the flying height (:math:`v_{‰} = 1000\,v/H`), spacing, timings;
2. one row per pyramid level / measuring module with whatever counters the matcher recorded
   (features, candidates, windows, failures, LSM tried / failed …); a key ending in ``_pct``
   is a percentage, other numbers are shown as counts or values;
3. maps, read decimated (:func:`..quality.report.read_decimated`, at most ``MAP_PIXELS`` per
   side) so that big rasters cost little: the DSM hillshade (Horn gradient, sun from the
   north-west at 45°) with the failure locations, the coverage (measured: count > 0;
   interpolated: count = 0 with a height; gap: no height; excluded: inside an exclusion
   area), the σ map with a colour bar.

The report dict (every key optional; the renderer shows "–" for what is missing)::

    {"model", "method", "images": [..], "crs", "flying_height_m",
     "metrics": {...}, "levels": [{...}, ...],
     "reduction": {"sigma1_m", "sigma2_m", "points_raw", "points_reduced", "outliers",
                   "cell_m", "mode"},
     "seconds": {...}, "options": {...}}
"""

from __future__ import annotations

import html
import math
from pathlib import Path
from typing import Any, Dict, Iterable, List, Optional, Sequence, Tuple, Union

import numpy as np
from matplotlib.colors import BoundaryNorm, ListedColormap
from matplotlib.patches import Patch
from numpy.typing import NDArray
from rasterio.features import rasterize

from ..feedback import Feedback, ensure_feedback
from ..jsonable import json_ready
from ..quality.rasters import horn_gradient, shade
from ..quality.report import (
    _CSS,
    MAP_PIXELS,
    _embed,
    _table,
    new_figure,
    read_decimated,
    write_json,
)
from ..raster.io import atomic_output

PathLike = Union[str, Path]
Array = NDArray[Any]

#: Coverage classes of the map: value, label, colour.
COVERAGE_CLASSES: Tuple[Tuple[int, str, str], ...] = (
    (1, "measured (points in the cell)", "#1a9850"),
    (2, "interpolated (no point, height filled)", "#fee08b"),
    (3, "gap (no height)", "#d73027"),
    (4, "exclusion area", "#878787"),
)

#: Headline metrics: label, where to look (section, key…), kind.
HEADLINE: Tuple[Tuple[str, Tuple[Tuple[str, str], ...], str], ...] = (
    ("points raw", (("reduction", "points_raw"), ("metrics", "points_raw"),
                    ("metrics", "points")), "count"),
    ("points reduced", (("reduction", "points_reduced"), ("metrics", "points_reduced")),
     "count"),
    ("points failed", (("metrics", "points_failed"), ("metrics", "failed")), "count"),
    ("outliers (reduction)", (("reduction", "outliers"), ("metrics", "outliers")), "count"),
    ("coverage (measured + interpolated)", (("metrics", "coverage_pct"),), "pct"),
    ("measured", (("metrics", "measured_pct"),), "pct"),
    ("interpolated", (("metrics", "interpolated_pct"), ("metrics", "filled_pct")), "pct"),
    ("empty", (("metrics", "empty_pct"),), "pct"),
    ("valid disparities", (("metrics", "valid_disparity_pct"),), "pct"),
    ("failed matching windows", (("metrics", "failed_windows"),), "count"),
    ("failed windows at the finest level", (("metrics", "failed_windows_finest_pct"),),
     "pct"),
    ("grid spacing", (("metrics", "spacing_m"), ("options", "spacing")), "m"),
    ("groundel size", (("reduction", "cell_m"),), "m"),
    ("mean points per groundel", (("reduction", "n_mean"),), "value"),
)


# -- values ---------------------------------------------------------------------------------------
def _number(value: Any) -> Optional[float]:
    if isinstance(value, bool):
        return float(value)
    try:
        v = float(value)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


def _lookup(report: Dict[str, Any], paths: Iterable[Tuple[str, str]]) -> Any:
    for section, key in paths:
        part = report.get(section)
        if isinstance(part, dict) and part.get(key) is not None:
            return part[key]
    return None


def _text(value: Any, kind: str = "value") -> str:
    """A value for a table cell: numbers formatted by kind, lists joined, None → –."""
    if value is None:
        return "–"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, (list, tuple)):
        return ", ".join(_text(v, kind) for v in value) if value else "–"
    if isinstance(value, dict):
        return "; ".join(f"{k}: {_text(v)}" for k, v in value.items())
    v = _number(value)
    if v is None:
        return "–" if isinstance(value, float) else str(value)
    if kind == "count" or (kind == "value" and isinstance(value, (int, np.integer))):
        return f"{round(v):,}".replace(",", "\u202f")
    if kind == "pct":
        return f"{v:.1f} %"
    if kind == "m":
        return f"{v:.3f} m"
    if kind == "s":
        return f"{v:.1f} s"
    return f"{v:.4g}"


def _kind_of(key: str) -> str:
    k = key.lower()
    if k.endswith(("_pct", "percent")) or k.startswith("pct"):
        return "pct"
    if k.endswith("_m"):
        return "m"
    if k.endswith(("_s", "seconds")):
        return "s"
    return "value"


def _label(key: str) -> str:
    text = str(key)
    for suffix, unit in (("_pct", " [%]"), ("_m", " [m]"), ("_s", " [s]"), ("_px", " [px]")):
        if text.endswith(suffix):
            text = text[: -len(suffix)] + unit
            break
    return text.replace("_", " ")


def coverage_sentence(metrics: Dict[str, Any]) -> str:
    """The run log's coverage sentence: what was measured, interpolated and left empty (% of
    the model area), the valid disparities (dense) or the failed windows at the finest level
    (fbm_lsm)."""
    slant = _number(metrics.get("slant_measured_pct"))
    guided = _number(metrics.get("guided_measured_pct"))
    extras = ([f"slant passes alone {slant:.1f} %"] if slant is not None else []) + \
        ([f"guided pass {guided:.1f} %"] if guided is not None else [])
    alone = f" ({'; '.join(extras)})" if extras else ""
    parts = [f"measured {_number(metrics.get('measured_pct')) or 0.0:.1f} %{alone}, "
             f"interpolated {_number(metrics.get('interpolated_pct')) or 0.0:.1f} %, empty "
             f"{_number(metrics.get('empty_pct')) or 0.0:.1f} % of the model area"]
    if _number(metrics.get("valid_disparity_pct")) is not None:
        parts.append(f"valid disparities {metrics['valid_disparity_pct']:.1f} %")
    if _number(metrics.get("failed_windows_finest_pct")) is not None:
        parts.append(f"failed windows at the finest level "
                     f"{metrics['failed_windows_finest_pct']:.1f} %")
    return "; ".join(parts) + "."


def headline_table(report: Dict[str, Any]) -> str:
    """The headline metrics (method, model, counts, coverage, σ1/σ2 in m and ‰ H, timing)."""
    H = _number(report.get("flying_height_m"))
    rows: List[List[str]] = [
        ["model", _text(report.get("model"))],
        ["method", _text(report.get("method"))],
        ["images", _text(report.get("images"))],
        ["CRS", _text(report.get("crs"))],
        ["flying height H", _text(H, "m") if H else "–"],
    ]
    for label, paths, kind in HEADLINE:
        rows.append([label, _text(_lookup(report, paths), kind)])
    red = report.get("reduction") if isinstance(report.get("reduction"), dict) else {}
    for key, label in (("sigma1_m", "σ1 (raw points, 1.4826·MAD per groundel)"),
                       ("sigma2_m", "σ2 = F·σ1/√n̄ (reduced points)")):
        v = _number(red.get(key))
        per = f" = {1000.0 * v / H:.3f} ‰ H" if (v is not None and H) else ""
        rows.append([label, (_text(v, "m") + per) if v is not None else "–"])
    if red.get("mode"):
        rows.append(["reduction mode", _text(red.get("mode"))])
    seconds = report.get("seconds")
    if isinstance(seconds, dict):
        total = _number(seconds.get("total"))
        if total is None:
            parts = [_number(v) for v in seconds.values()]
            total = sum(p for p in parts if p is not None) if any(
                p is not None for p in parts) else None
        rows.append(["run time", _text(total, "s")])
    return _table(["quantity", "value"], rows)


def levels_table(levels: Any) -> str:
    """One row per level/module; the columns are the union of the keys, in order of appearance.

    A failure share is added when a row has ``windows`` and ``failed_windows`` but no
    ``failure_pct``.
    """
    rows_in = [dict(r) for r in levels if isinstance(r, dict)] if isinstance(
        levels, (list, tuple)) else []
    if not rows_in:
        return '<p class="note">No per-level statistics were recorded.</p>'
    for r in rows_in:
        win, fail = _number(r.get("windows")), _number(r.get("failed_windows"))
        if "failure_pct" not in r and win and fail is not None:
            r["failure_pct"] = 100.0 * fail / win
    keys: List[str] = []
    for r in rows_in:
        keys += [k for k in r if k not in keys]
    first = [k for k in ("level", "module", "name") if k in keys]
    keys = first + [k for k in keys if k not in first]
    body = [[_text(r.get(k), _kind_of(k)) for k in keys] for r in rows_in]
    return _table([_label(k) for k in keys], body, "wide")


def dict_table(values: Any, first: str = "key") -> str:
    """A generic key/value table (other metrics, timings, options)."""
    if not isinstance(values, dict) or not values:
        return '<p class="note">–</p>'
    rows = [[_label(k), _text(v, _kind_of(str(k)))] for k, v in values.items()]
    return _table([first, "value"], rows)


# -- maps -----------------------------------------------------------------------------------------
def _extent(transform: Any, shape: Tuple[int, int]) -> Tuple[float, float, float, float]:
    h, w = shape
    left, top = transform * (0, 0)
    right, bottom = transform * (w, h)
    return (left, right, bottom, top)


def _map_axes(fig: Any, extent: Tuple[float, float, float, float], title: str) -> Any:
    ax = fig.add_subplot(1, 1, 1)
    ax.set_xlim(extent[0], extent[1])
    ax.set_ylim(extent[2], extent[3])
    ax.set_xlabel("Easting [m]")
    ax.set_ylabel("Northing [m]")
    ax.ticklabel_format(useOffset=False, style="plain")
    for label in ax.get_xticklabels():
        label.set_rotation(30)
        label.set_ha("right")
    ax.set_title(title)
    return ax


def _map_figure(shape: Tuple[int, int], extent: Tuple[float, float, float, float]) -> Any:
    aspect = (extent[3] - extent[2]) / max(extent[1] - extent[0], 1e-9)
    return new_figure(9.0, float(np.clip(7.2 * aspect, 3.5, 10.0)) + 0.8)


def hillshade_array(z: Array, transform: Any) -> Array:
    """Hillshade 0…1 of a (decimated) height grid; NaN where the height is NaN."""
    zp = np.pad(np.asarray(z, float), 1, mode="edge")
    p, q = horn_gradient(zp, abs(transform.a), abs(transform.e))
    return shade(p, q)


def figure_dsm(dsm: PathLike, failures: Optional[Array] = None,
               max_pixels: int = MAP_PIXELS) -> Any:
    """DSM hillshade with the failure locations (red crosses)."""
    z, transform, _ = read_decimated(dsm, max_pixels=max_pixels)
    extent = _extent(transform, z.shape)
    fig = _map_figure(z.shape, extent)
    ax = _map_axes(fig, extent, "DSM (hillshade) and failure locations")
    ax.imshow(np.ma.masked_invalid(hillshade_array(z, transform)), cmap="gray", vmin=0,
              vmax=1, extent=extent, interpolation="nearest")
    if failures is not None:
        f = np.asarray(failures, float).reshape(-1, 2)
        f = f[np.isfinite(f).all(axis=1)]
        if f.size:
            ax.plot(f[:, 0], f[:, 1], "x", color="#d7191c", markersize=4, linestyle="none",
                    label=f"failures ({len(f)})")
            ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    return fig


def coverage_classes(z: Array, count: Optional[Array], excluded: Optional[Array]) -> Array:
    """Class per cell (:data:`COVERAGE_CLASSES`): 1 measured, 2 interpolated, 3 gap, 4 excluded.

    Without a count raster every cell with a height counts as measured.
    """
    has = np.isfinite(z)
    measured = has if count is None else (np.nan_to_num(count, nan=0.0) > 0) & has
    out = np.where(measured, 1, np.where(has, 2, 3)).astype(np.uint8)
    if excluded is not None:
        out[excluded] = 4
    return out


def _excluded_mask(geoms: Optional[Sequence[Any]], transform: Any,
                   shape: Tuple[int, int]) -> Optional[Array]:
    shapes = [(g, 1) for g in (geoms or []) if g is not None and not g.is_empty]
    if not shapes:
        return None
    return rasterize(shapes, out_shape=shape, transform=transform, fill=0,
                     dtype="uint8").astype(bool)


def figure_coverage(dsm: PathLike, count: Optional[PathLike] = None,
                    exclusions: Optional[Sequence[Any]] = None,
                    max_pixels: int = MAP_PIXELS) -> Tuple[Any, Dict[str, float]]:
    """Coverage map and the share (%) of each class."""
    z, transform, _ = read_decimated(dsm, max_pixels=max_pixels)
    cnt = None
    if count is not None and Path(count).is_file():
        cnt, _, _ = read_decimated(count, max_pixels=max_pixels)
        if cnt.shape != z.shape:  # a count raster on another grid: not used
            cnt = None
    classes = coverage_classes(z, cnt, _excluded_mask(exclusions, transform, z.shape))
    total = classes.size
    shares = {label: 100.0 * int(np.count_nonzero(classes == v)) / total
              for v, label, _ in COVERAGE_CLASSES}
    extent = _extent(transform, z.shape)
    fig = _map_figure(z.shape, extent)
    ax = _map_axes(fig, extent, "Coverage")
    cmap = ListedColormap([c for _, _, c in COVERAGE_CLASSES])
    norm = BoundaryNorm([0.5, 1.5, 2.5, 3.5, 4.5], cmap.N)
    ax.imshow(classes, cmap=cmap, norm=norm, extent=extent, interpolation="nearest")
    handles = [Patch(color=c, label=f"{label}: {shares[label]:.1f} %")
               for v, label, c in COVERAGE_CLASSES if shares[label] > 0]
    ax.legend(handles=handles, loc="upper right", fontsize=8, framealpha=0.85)
    fig.tight_layout()
    return fig, shares


def figure_sigma(sigma: PathLike, max_pixels: int = MAP_PIXELS) -> Any:
    """σ map (m) with a colour bar up to the 98 % quantile."""
    s, transform, _ = read_decimated(sigma, max_pixels=max_pixels)
    extent = _extent(transform, s.shape)
    fig = _map_figure(s.shape, extent)
    ax = _map_axes(fig, extent, "Height precision σ")
    finite = s[np.isfinite(s)]
    vmax = float(np.percentile(finite, 98)) if finite.size else 1.0
    image = ax.imshow(np.ma.masked_invalid(s), cmap="viridis", vmin=0.0,
                      vmax=vmax if vmax > 0 else 1.0, extent=extent, interpolation="nearest")
    cbar = fig.colorbar(image, ax=ax, extend="max", shrink=0.85, pad=0.02)
    cbar.set_label("σ [m]")
    fig.tight_layout()
    return fig


# -- the files ------------------------------------------------------------------------------------
def write_model_report(folder: PathLike, report: Dict[str, Any], *, dsm: PathLike,
                       sigma: Optional[PathLike] = None, count: Optional[PathLike] = None,
                       failures: Optional[Array] = None,
                       exclusions: Optional[Sequence[Any]] = None,
                       feedback: Optional[Feedback] = None) -> Dict[str, Path]:
    """Write ``report.json`` and ``report.html`` of one matched model into ``folder``.

    Parameters
    ----------
    folder : path
        Output folder (created if needed); both files are written atomically.
    report : dict
        The model's numbers (see the module notes); written to JSON as given (numpy values
        converted, NaN → null).
    dsm : path
        The model DSM (hillshade and coverage maps).
    sigma, count : path, optional
        σ raster (m) and points-per-cell raster on the DSM grid.
    failures : ndarray (k, 2), optional
        World x, y of failed matches, drawn on the hillshade.
    exclusions : sequence of shapely polygons, optional
        Exclusion areas, a class of their own in the coverage map.

    Returns
    -------
    dict
        ``{"json": path, "html": path}``.
    """
    feedback = ensure_feedback(feedback)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    report = json_ready(dict(report))
    name = report.get("model") or Path(dsm).parent.name
    title = f"Matching report — model {name}"
    parts = [f"<h1>{html.escape(str(title))}</h1>",
             f"<p>Method <b>{html.escape(_text(report.get('method')))}</b>; images "
             f"{html.escape(_text(report.get('images')))}. Internal quality of the matching: "
             "counts, failures per level, σ1/σ2 of the groundel reduction "
             "(‰ H = 1000 · value / flying height), coverage and precision maps.</p>",
             "<h2>Summary</h2>", headline_table(report)]
    metrics = report.get("metrics") if isinstance(report.get("metrics"), dict) else {}
    shown = {k for _, paths, _ in HEADLINE for s, k in paths if s == "metrics"}
    others = {k: v for k, v in metrics.items() if k not in shown}
    parts += ["<h2>Per level and module</h2>", levels_table(report.get("levels"))]
    feedback.progress(10.0)
    parts += ["<h2>DSM and failures</h2>",
              _embed(figure_dsm(dsm, failures), "DSM hillshade with failure locations")]
    feedback.progress(40.0)
    fig, shares = figure_coverage(dsm, count, exclusions)
    parts += ["<h2>Coverage</h2>", _embed(fig, "coverage map"),
              '<p class="note">' + "; ".join(f"{html.escape(k)}: {v:.1f} %"
                                              for k, v in shares.items()) +
              " (of the cells of the map, drawn at reduced resolution).</p>"]
    feedback.progress(70.0)
    if sigma is not None and Path(sigma).is_file():
        parts += ["<h2>Precision</h2>", _embed(figure_sigma(sigma), "sigma map")]
    feedback.progress(90.0)
    parts += ['<div class="cols"><div>', "<h2>Other metrics</h2>", dict_table(others, "metric"),
              "</div><div>", "<h2>Timings</h2>", dict_table(report.get("seconds"), "step"),
              "</div><div>", "<h2>Options</h2>", dict_table(report.get("options"), "option"),
              "</div></div>"]
    page = ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{html.escape(str(title))}</title><style>{_CSS}</style></head><body>\n"
            + "\n".join(parts) + "\n</body></html>\n")
    json_path = write_json(folder / "report.json", report)
    html_path = folder / "report.html"
    with atomic_output(html_path) as tmp:
        tmp.write_text(page, encoding="utf-8")
    feedback.progress(100.0)
    return {"json": json_path, "html": html_path}


__all__ = [
    "COVERAGE_CLASSES",
    "coverage_classes",
    "coverage_sentence",
    "dict_table",
    "figure_coverage",
    "figure_dsm",
    "figure_sigma",
    "headline_table",
    "hillshade_array",
    "levels_table",
    "write_model_report",
]
