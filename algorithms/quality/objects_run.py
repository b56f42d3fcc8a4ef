"""Object metrics of a DSM file against truth files, window by window (issue 19).

:func:`object_metrics` reads the DSM onto the grid of the true DSM (bilinear, reprojected when
the CRS or grid differ) and gives the completeness of the object interior, all object cells and
open cells (:mod:`.objects`), and the building outlines against true footprints. Nothing is read
whole: completeness in windows of ``window_size`` cells with the margin the masks need, outlines
in one window per building (its bounding box plus ``margin`` metres).
"""

from __future__ import annotations

import contextlib
import math
from pathlib import Path
from typing import Any, Dict, List, Mapping, Optional, Sequence, Union

import numpy as np
from affine import Affine
from rasterio.enums import Resampling
from rasterio.features import geometry_mask, rasterize
from shapely.geometry import box

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from .compare import (
    _ComparisonGrid,
    _GridReader,
    _ObjectSource,
    _open_raster,
    _read_polygons,
    _read_window,
)
from .objects import (
    OBJECT_HEIGHT,
    CompletenessAccumulator,
    building_outline,
    summarise_outlines,
)

PathLike = Union[str, Path]
Array = np.ndarray


class _Sources:
    """The open DSM (on the truth grid), truth DSM and DTM, and the area mask per window."""

    def __init__(self, stack: contextlib.ExitStack, dsm: PathLike, truth_dsm: PathLike,
                 truth_dtm: PathLike, area: Any, object_height: float,
                 cover: Optional[PathLike] = None,
                 cover_classes: Optional[Mapping[str, Sequence[int]]] = None) -> None:
        self.ref = _open_raster(stack, truth_dsm, "true DSM")
        src = _open_raster(stack, dsm, "DSM")
        self.grid = _ComparisonGrid(src, self.ref)
        g = self.grid
        self.dsm = _GridReader(stack, src, self.ref.crs, g.transform, g.width, g.height,
                               Resampling.bilinear)
        self.objects = _ObjectSource(stack, truth_dtm, self.ref, g.transform, g.width,
                                     g.height, object_height)
        # the DTM without margin, for the outlines
        self.dtm = _GridReader(stack, _open_raster(stack, truth_dtm, "true DTM"), self.ref.crs,
                               g.transform, g.width, g.height, Resampling.bilinear)
        self.area = area
        # land cover on the comparison grid (nearest: codes are not to be averaged)
        self.cover = None if cover is None else _GridReader(
            stack, _open_raster(stack, cover, "land cover"), self.ref.crs, g.transform,
            g.width, g.height, Resampling.nearest)
        self.cover_classes = dict(cover_classes or {}) if cover is not None else {}

    def interior_by_cover(self, interior: Array, r: int, c: int, h: int, w: int
                          ) -> Dict[str, Array]:
        """The interior mask of the window split by the land-cover classes, keyed
        ``interior_<name>`` (empty without a land cover)."""
        if self.cover is None:
            return {}
        codes = self.cover.read(r, c, h, w)
        return {f"interior_{name}": interior & np.isin(codes, list(values))
                for name, values in self.cover_classes.items()}

    def area_mask(self, r: int, c: int, h: int, w: int) -> Array:
        """True inside the area (everywhere without one)."""
        if self.area is None:
            return np.ones((h, w), bool)
        t = self.grid.transform * Affine.translation(c, r)
        return geometry_mask([self.area], out_shape=(h, w), transform=t, invert=True)

    def truth(self, r: int, c: int, h: int, w: int) -> Array:
        return _read_window(self.ref, self.grid.r_off + r, self.grid.c_off + c, h, w)


def _completeness(s: _Sources, window_size: int, fb: Feedback) -> Dict[str, Any]:
    acc = CompletenessAccumulator()
    wins = s.grid.windows(window_size)
    for i, (r, c, h, w) in enumerate(wins):
        codes = s.objects.labels(s.ref, s.grid, r, c, h, w)
        zt = s.truth(r, c, h, w)
        dz = s.dsm.read(r, c, h, w) - zt
        valid = np.isfinite(zt) & s.area_mask(r, c, h, w)
        interior = codes == 1
        with np.errstate(invalid="ignore"):
            acc.add(dz, {"interior": interior, "objects": interior | (codes == 2),
                         "open": codes == 3, **s.interior_by_cover(interior, r, c, h, w)},
                    valid)
        fb.progress(70.0 * (i + 1) / len(wins))
    return acc.result()


def _outlines(s: _Sources, buildings: PathLike, margin: float, gsd: Optional[float],
              fb: Feedback) -> Dict[str, Any]:
    geoms, _ = _read_polygons(buildings, s.ref.crs, None, "building footprints", fb)
    g = s.grid
    t = g.transform
    cell = abs(t.a)
    x0, y1 = t * (0, 0)
    x1, y0 = t * (g.width, g.height)
    inside = box(min(x0, x1), min(y0, y1), max(x0, x1), max(y0, y1))
    region = inside if s.area is None else s.area
    keep = [gm for gm in geoms if region.contains(gm) and inside.contains(gm)]
    rows: List[Dict[str, Any]] = []
    dist: List[Array] = []
    for i, gm in enumerate(keep):
        bx0, by0, bx1, by1 = gm.bounds
        c0, r0 = ~t * (bx0 - margin, by1 + margin)
        c1, r1 = ~t * (bx1 + margin, by0 - margin)
        r0, c0 = max(math.floor(r0), 0), max(math.floor(c0), 0)
        r1, c1 = min(math.ceil(r1), g.height), min(math.ceil(c1), g.width)
        h, w = r1 - r0, c1 - c0
        wt = t * Affine.translation(c0, r0)
        near = [(j, o) for j, o in enumerate(keep) if o.intersects(box(*wt * (0, h),
                                                                          *wt * (w, 0)))]
        labels = rasterize([(o, j + 1) for j, o in near], out_shape=(h, w), transform=wt,
                           fill=0, dtype="int32")
        one = building_outline(s.dsm.read(r0, c0, h, w), s.dtm.read(r0, c0, h, w),
                               s.truth(r0, c0, h, w), labels, i + 1, cell)
        if one is not None:
            dist.append(one.pop("_d"))
            one["id"] = i
            rows.append(one)
        fb.progress(70.0 + 30.0 * (i + 1) / max(len(keep), 1))
    return summarise_outlines(rows, dist, gsd)


def object_metrics(dsm: PathLike, truth_dsm: PathLike, truth_dtm: PathLike, *,
                   buildings: Optional[PathLike] = None, area: Any = None,
                   object_height: float = OBJECT_HEIGHT, gsd: Optional[float] = None,
                   margin: float = 5.0, window_size: int = 1024,
                   cover: Optional[PathLike] = None,
                   cover_classes: Optional[Mapping[str, Sequence[int]]] = None,
                   feedback: Optional[Feedback] = None) -> Dict[str, Any]:
    """Completeness and building outlines of a DSM against truth rasters.

    Parameters
    ----------
    dsm : path
        DSM to judge (any grid and CRS; NaN/nodata = not measured).
    truth_dsm, truth_dtm : path
        True surface and terrain; the grid of ``truth_dsm`` is the comparison grid.
    buildings : path, optional
        True building footprints (polygons); only those wholly inside the area (and the common
        grid) count.
    area : shapely geometry, optional
        Where to judge, in the CRS of ``truth_dsm`` (e.g. a model's measuring area); default
        the common extent of the DSM and the truth. Cells of the area the DSM leaves empty are
        misses.
    object_height, gsd, margin
        As :func:`.objects.object_masks` and :func:`.objects.outline_metrics`.
    window_size : int
        Window edge (cells) of the completeness pass.
    cover : path, optional
        Land-cover raster (class codes); with ``cover_classes`` the object interior is also
        judged per class, e.g. ``{"buildings": [3], "crowns": [4]}``: on a block whose
        interior is part roofs, part tree crowns one figure hides which of them is lost.
    cover_classes : mapping of str to sequence of int, optional
        Name → land-cover codes of each class (``interior_<name>`` in the result).
    feedback : Feedback, optional

    Returns
    -------
    dict
        ``{"completeness": {"interior", "objects", "open"[, "interior_<name>" …]},
        "outlines": … or None, "cell": truth cell size}`` (see :mod:`.objects`).
    """
    fb = ensure_feedback(feedback)
    if not object_height > 0:
        raise InputError("The object height must be positive (metres above the DTM).")
    with contextlib.ExitStack() as stack:
        s = _Sources(stack, dsm, truth_dsm, truth_dtm, area, object_height, cover,
                     cover_classes)
        comp = _completeness(s, window_size, fb)
        outlines = _outlines(s, buildings, margin, gsd, fb) if buildings is not None else None
        cell = abs(s.grid.transform.a)
    fb.progress(100.0)
    return {"completeness": comp, "outlines": outlines, "cell": cell}


def object_figures(metrics: Dict[str, Any]) -> Dict[str, Any]:
    """The headline figures of :func:`object_metrics` as one flat row (shares in %).

    ``interior_0_5_pct``, ``interior_measured_pct``, ``objects_0_5_pct``, ``open_0_5_pct``,
    ``iou`` (pooled outline IoU), ``wall_gsd`` (median wall position error in GSD),
    ``buildings`` (judged footprints), and ``interior_<name>_0_5_pct`` for each land-cover
    class of the interior; None where a figure has no cells.
    """
    comp = metrics["completeness"]
    out = metrics.get("outlines") or {}

    def pct(key: str, share: str) -> Optional[float]:
        v = comp.get(key, {}).get(share)
        return None if v is None else 100.0 * float(v)

    return {"interior_0_5_pct": pct("interior", "within_0_5"),
            "interior_measured_pct": pct("interior", "measured"),
            "objects_0_5_pct": pct("objects", "within_0_5"),
            "open_0_5_pct": pct("open", "within_0_5"),
            "iou": out.get("iou_pooled"), "wall_gsd": out.get("wall_median_gsd"),
            "buildings": out.get("count", 0),
            **{f"{key}_0_5_pct": pct(key, "within_0_5") for key in comp
               if key.startswith("interior_")}}


__all__ = ["object_figures", "object_metrics"]
