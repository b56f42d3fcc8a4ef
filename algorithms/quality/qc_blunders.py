r"""Blunder spots of a DEM against a reference, and the one-click way from a spot to an edit.

A cell is a blunder when :math:`|\Delta h - \mathrm{median}| > k \cdot \mathrm{NMAD}` (the
robust statistics of the same area, default :math:`k = 3`; an absolute ``threshold`` in metres
may replace :math:`k\cdot\mathrm{NMAD}`). Blunder cells that touch (8-neighbourhood) form one
spot; a spot has its size (cells, m²), its largest :math:`|\Delta h|`, the signed mean, its
centroid (mean of the cell centres), bounds and outline (the union of its cells). Spots are
sorted by size, then by magnitude, largest first.

The differences come from :func:`~.compare.compare_dems` (the same grid and resampling as
``dem_compare``), window by window; the flags of the area's window are kept as one byte per
cell, so an area is limited to :data:`MAX_CELLS` cells.

:func:`spot_to_exclusion` and :func:`spot_to_ground_point` write a spot into the project's
``edits.gpkg`` through :func:`~photodem.algorithms.project.edits.add_features`.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Dict, List, Optional, Union

import numpy as np
from affine import Affine
from rasterio.features import shapes
from scipy import ndimage
from shapely.geometry import Point, shape
from shapely.ops import unary_union

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from ..project.edit_checks import check_new_polygon
from ..project.edits import EXCLUSION_ACTIONS, add_features
from .compare import compare_dems

PathLike = Union[str, Path]

#: Most cells of the area searched for blunders at once (one byte and one float each).
MAX_CELLS = 40_000_000


class _Collector:
    """Keeps Δh of the windows (float32) to flag them once the NMAD is known."""

    def __init__(self) -> None:
        self.windows: List[Any] = []
        self.cells = 0

    def hook(self, row: int, col: int, dz: Any) -> None:
        self.cells += dz.size
        if self.cells > MAX_CELLS:
            raise InputError(f"The area holds more than {MAX_CELLS} cells; search for blunders "
                             "in a smaller area (draw a polygon or zoom in).")
        self.windows.append((row, col, dz.astype(np.float32)))


def _spot(label: int, cells: Any, dz: Any, transform: Affine, cell_area: float) -> Dict[str, Any]:
    """One spot: cells (rows, cols) of the area window, their Δh, the window's transform."""
    rows, cols = cells
    r0, c0 = int(rows.min()), int(cols.min())
    sub = np.zeros((int(rows.max()) - r0 + 1, int(cols.max()) - c0 + 1), np.uint8)
    sub[rows - r0, cols - c0] = 1
    t = transform * Affine.translation(c0, r0)
    parts = [shape(g) for g, v in shapes(sub, mask=sub.astype(bool), transform=t) if v == 1]
    outline = unary_union(parts)
    xs, ys = transform * (cols + 0.5, rows + 0.5)
    values = dz[rows, cols].astype(np.float64)
    imax = int(np.argmax(np.abs(values)))
    return {
        "id": label,
        "cells": int(rows.size),
        "area_m2": float(rows.size * cell_area),
        "max_abs_dh": float(abs(values[imax])),
        "max_dh": float(values[imax]),
        "mean_dh": float(values.mean()),
        "centroid": (float(np.mean(xs)), float(np.mean(ys))),
        "peak": (float(xs[imax]), float(ys[imax])),
        "bounds": tuple(float(v) for v in outline.bounds),
        "outline": outline.wkt,
    }


def find_blunders(dem: PathLike, reference: PathLike, area: Any = None, *, k: float = 3.0,
                  threshold: Optional[float] = None, min_cells: int = 1,
                  max_spots: int = 1000, window_size: int = 1024,
                  feedback: Optional[Feedback] = None) -> Dict[str, Any]:
    """Spots where the DEM departs from the reference by more than k·NMAD.

    Parameters
    ----------
    dem, reference : path
        As :func:`~.compare.compare_dems`.
    area : polygon, WKT or extent, optional
        Where to search (reference CRS); None = the whole common area.
    k : float
        Multiple of the NMAD (about the median) above which a cell is a blunder.
    threshold : float, optional
        Absolute limit of |Δh − median| in metres instead of k·NMAD.
    min_cells : int
        Smallest spot reported.
    max_spots : int
        Most spots returned (the largest); ``total`` counts them all.
    window_size : int
        Processing window edge (cells).
    feedback : Feedback, optional
        Progress; cancelling raises Cancelled.

    Returns
    -------
    dict
        ``spots`` (list of dicts: ``id, cells, area_m2, max_abs_dh, max_dh, mean_dh, centroid,
        peak, bounds, outline`` (WKT)), ``total``, ``limit`` (m), ``median``, ``nmad``, ``stats``
        (of the area, as ``dem_compare``) and ``crs``.
    """
    if not (math.isfinite(k) and k > 0):
        raise InputError(f"k must be a positive number, not {k}.")
    fb = ensure_feedback(feedback)
    col = _Collector()
    res = compare_dems(dem, reference, area=area, window_size=window_size, on_window=col.hook,
                       feedback=fb.step(0.0, 80.0))
    stats = res["stats"]
    med, nmad = float(stats["median"]), float(stats["nmad"])
    limit = float(threshold) if threshold is not None else k * nmad
    if not limit > 0:
        raise InputError("The limit k·NMAD is zero (the DEM equals the reference almost "
                         "everywhere); give an absolute threshold in metres.")
    box = res.get("area") or {"row": 0, "col": 0, "height": res["grid"]["height"],
                              "width": res["grid"]["width"]}
    dz = np.full((box["height"], box["width"]), np.nan, np.float32)
    for r, c, d in col.windows:
        dz[r - box["row"]:r - box["row"] + d.shape[0], c - box["col"]:c - box["col"] + d.shape[1]] \
            = d
    col.windows.clear()
    flags = np.abs(dz - med) > limit  # NaN compares False
    labels, n = ndimage.label(flags, structure=np.ones((3, 3), bool))
    transform = Affine(*res["grid"]["transform"]) * Affine.translation(box["col"], box["row"])
    cell_area = res["grid"]["resolution"][0] * res["grid"]["resolution"][1]
    spots = []
    for i, sl in enumerate(ndimage.find_objects(labels), start=1):
        if sl is None:
            continue
        rr, cc = np.nonzero(labels[sl] == i)
        if rr.size < min_cells:
            continue
        spots.append(_spot(i, (rr + sl[0].start, cc + sl[1].start), dz, transform, cell_area))
        fb.progress(80.0 + 20.0 * i / max(n, 1))
    spots.sort(key=lambda s: (-s["cells"], -s["max_abs_dh"]))
    for rank, s in enumerate(spots, start=1):
        s["id"] = rank
    return {"spots": spots[:max_spots], "total": len(spots), "limit": limit, "median": med,
            "nmad": nmad, "k": k, "stats": stats, "crs": res["grid"]["crs"]}


def spot_polygon(spot: Dict[str, Any], margin: float = 0.0) -> Any:
    """The spot's outline (shapely), grown by ``margin`` metres, checked as an edit polygon."""
    from shapely import wkt  # lazy: only the edit buttons need it

    geom = wkt.loads(spot["outline"])
    if margin > 0:
        geom = geom.buffer(margin, join_style=2)
    if geom.geom_type == "MultiPolygon":  # cells touching at a corner: join them (1 mm)
        geom = geom.buffer(1e-3, join_style=2)
    if geom.geom_type == "MultiPolygon":
        geom = geom.convex_hull
    check = check_new_polygon(geom)
    if check.ok:
        return geom
    if check.repaired is not None and check.repaired.geom_type == "Polygon":
        return check.repaired
    raise InputError("The spot's outline is not a valid polygon: "
                     + "; ".join(p.message for p in check.problems))


def spot_to_exclusion(edits: PathLike, spot: Dict[str, Any], action: str = "remove",
                      margin: float = 0.0, note: str = "") -> Any:
    """Append the spot's outline as an exclusion area (``action`` keep/remove/exclude).

    Returns the polygon written.
    """
    if action not in EXCLUSION_ACTIONS:
        raise InputError(f"Unknown action '{action}'; use one of {', '.join(EXCLUSION_ACTIONS)}.")
    geom = spot_polygon(spot, margin)
    add_features(edits, "exclusion_areas",
                 [(geom, {"action": action, "note": note or f"blunder {spot['id']}"})])
    return geom


def spot_to_ground_point(edits: PathLike, spot: Dict[str, Any], height: float,
                         note: str = "") -> Any:
    """Append a ground point at the spot's centroid with ``height`` (e.g. the reference's).

    Returns the point written.
    """
    if not math.isfinite(float(height)):
        raise InputError("The ground point needs a height; the reference has none there.")
    x, y = spot["centroid"]
    geom = Point(x, y, float(height))
    add_features(edits, "ground_points", [(geom, {"note": note or f"blunder {spot['id']}"})])
    return geom


__all__ = ["MAX_CELLS", "find_blunders", "spot_polygon", "spot_to_exclusion",
           "spot_to_ground_point"]
