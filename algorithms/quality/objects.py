r"""Object metrics: does a DSM keep its buildings and trees? (issue 19)

A DSM is the surface *with* its objects; the usual accuracy statistics on open terrain do not
tell whether its roofs are there. This module measures it on the grid of a true DSM
:math:`Z_s` with its true DTM :math:`Z_t` (nDSM :math:`n = Z_s - Z_t`), all arrays on that grid:

**Masks** (:func:`object_masks`), with the cell size :math:`c` and the Euclidean distance
transform :math:`e` (distance in cells from a cell centre to the nearest centre of the other
kind), a cell's distance to the boundary being :math:`(e - \tfrac12)\,c`:

* *object*: :math:`n \ge h_o` (``object_height``, default 2.5 m);
* *object interior*: object and :math:`(e_{obj} - \tfrac12)\,c \ge` ``inset`` (1 m): wall cells
  and the blurred fringe of a roof do not count;
* *open*: :math:`n <` ``open_height`` (0.3 m) and :math:`(e_{\neg obj} - \tfrac12)\,c \ge`
  ``open_margin`` (1 m) from any object cell.

A square object of :math:`k \times k` cells has an interior of :math:`(k - 2m)^2` cells with
:math:`m = \lceil \text{inset}/c \rceil`.

**Completeness** (:class:`CompletenessAccumulator`) of a mask: of its cells with a valid truth,
the share where the DSM is within ±0.5 m and ±1 m of the truth; a cell the DSM leaves empty
(NaN) counts as a miss. ``measured`` is the share the DSM gives a height at all.

**Building outlines** (:func:`outline_metrics`): per building (label of its true footprint) of
true height :math:`h_b` (median nDSM inside its footprint), the footprint from the DSM is the set
of cells near the building with :math:`Z_{DSM} - Z_t \ge h_b / 2` that are connected
(8-neighbourhood) to the true footprint and not inside another building's footprint. Against
the true footprint: :math:`\mathrm{IoU} = |A \cap B| / |A \cup B|`, and the wall position error
— for every boundary cell of either footprint, the distance to the nearest boundary cell of the
other (symmetric), its median in m and in GSD. A building the DSM misses entirely has
IoU 0 and no wall error.

The arrays are windows of the truth grid: :func:`object_masks` needs a margin of
:func:`mask_margin` cells around the window for exact distances (the windowed driver is
:mod:`.objects_run`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Dict, List, Mapping, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage

Array = NDArray[Any]

#: Defaults of the masks (m): object height above the DTM, inset of the interior, open height,
#: distance of open cells from objects.
OBJECT_HEIGHT = 2.5
INSET = 1.0
OPEN_HEIGHT = 0.3
OPEN_MARGIN = 1.0
#: |Δh| limits (m) of the completeness shares.
COMPLETENESS_LIMITS = {"within_0_5": 0.5, "within_1": 1.0}
#: Object classes of :func:`object_classes`: (code, name).
OBJECT_CLASSES = ((1, "object interior"), (2, "object edge"), (3, "open"), (4, "other"))


@dataclass
class ObjectMasks:
    """Boolean masks on a truth grid window (see the module text)."""

    objects: Array
    interior: Array
    open: Array


def mask_margin(cell: float, inset: float = INSET, open_margin: float = OPEN_MARGIN) -> int:
    """Cells of margin a window needs so that its masks equal those of the whole grid."""
    return math.ceil(max(inset, open_margin) / float(cell) + 0.5) + 1


def _far_from(mask: Array, limit_m: float, cell: float) -> Array:
    """Cells whose centre is ≥ ``limit_m`` from the boundary of ``~mask`` (distance − ½ cell)."""
    if not mask.any():
        return np.zeros(mask.shape, bool)
    if mask.all():
        return np.ones(mask.shape, bool)
    e = ndimage.distance_transform_edt(mask)
    return (e - 0.5) * cell >= limit_m - 1e-9


def object_masks(dsm_true: ArrayLike, dtm_true: ArrayLike, cell: float, *,
                 object_height: float = OBJECT_HEIGHT, inset: float = INSET,
                 open_height: float = OPEN_HEIGHT,
                 open_margin: float = OPEN_MARGIN) -> ObjectMasks:
    """Object, object-interior and open masks from the true DSM and DTM.

    Parameters
    ----------
    dsm_true, dtm_true : array_like, same shape
        True surface and terrain heights (m) on the truth grid; NaN = unknown (counts as
        neither object nor open).
    cell : float
        Cell size (m).
    object_height, inset, open_height, open_margin : float
        See the module text (m).

    Returns
    -------
    ObjectMasks
    """
    n = np.asarray(dsm_true, np.float64) - np.asarray(dtm_true, np.float64)
    known = np.isfinite(n)
    obj = known & (n >= object_height)
    interior = obj & _far_from(obj, inset, cell)
    low = known & (n < open_height)
    open_ = low & _far_from(~obj, open_margin, cell)
    return ObjectMasks(obj, interior, open_)


def object_classes(masks: ObjectMasks, valid: Optional[ArrayLike] = None) -> Array:
    """Class code per cell (:data:`OBJECT_CLASSES`; NaN where ``valid`` is False)."""
    out = np.full(masks.objects.shape, 4.0)
    out[masks.objects] = 2.0
    out[masks.interior] = 1.0
    out[masks.open] = 3.0
    if valid is not None:
        out[~np.asarray(valid, bool)] = np.nan
    return out


class CompletenessAccumulator:
    """Completeness per named mask or per class label, fed window by window.

    Examples
    --------
    >>> acc = CompletenessAccumulator()
    >>> acc.add(dsm - truth, {"interior": interior, "open": open_}, truth_valid)
    ...                                                      # doctest: +SKIP
    >>> acc.result()["interior"]["within_0_5"]               # doctest: +SKIP
    """

    def __init__(self) -> None:
        self.counts: Dict[str, Dict[str, int]] = {}

    def _add_one(self, key: str, a: Array, sel: Array) -> None:
        c = self.counts.setdefault(key, {"cells": 0, "measured": 0,
                                         **dict.fromkeys(COMPLETENESS_LIMITS, 0)})
        v = a[sel]
        c["cells"] += int(v.size)
        c["measured"] += int(np.count_nonzero(np.isfinite(v)))
        for k, lim in COMPLETENESS_LIMITS.items():
            c[k] += int(np.count_nonzero(v <= lim))  # NaN compares False: a miss

    def add(self, dz: ArrayLike, masks: Mapping[str, ArrayLike],
            truth_valid: Optional[ArrayLike] = None) -> None:
        """Add Δh = DSM − truth (NaN where the DSM is empty) for each named boolean mask."""
        a = np.abs(np.asarray(dz, np.float64))
        valid = np.ones(a.shape, bool) if truth_valid is None else np.asarray(truth_valid, bool)
        for name, m in masks.items():
            self._add_one(str(name), a, np.asarray(m, bool) & valid)

    def add_labels(self, dz: ArrayLike, labels: ArrayLike, names: Optional[Mapping[int, str]]
                   = None, truth_valid: Optional[ArrayLike] = None) -> None:
        """Add Δh per class label (NaN labels ignored); ``names`` maps codes to names."""
        a = np.abs(np.asarray(dz, np.float64))
        lab = np.asarray(labels, np.float64)
        ok = np.isfinite(lab)
        if truth_valid is not None:
            ok &= np.asarray(truth_valid, bool)
        for u in np.unique(lab[ok]):
            key = (names or {}).get(int(u), None) if float(u).is_integer() else None
            if key is None:
                key = str(int(u)) if float(u).is_integer() else str(u)
            self._add_one(key, a, ok & (lab == u))

    def result(self) -> Dict[str, Dict[str, Any]]:
        """Per key: ``cells`` and the shares ``measured``, ``within_0_5``, ``within_1``."""
        out = {}
        for key, c in self.counts.items():
            n = c["cells"]
            out[key] = {"cells": n, **{k: (c[k] / n if n else None)
                                       for k in ("measured", *COMPLETENESS_LIMITS)}}
        return out


def completeness(dsm: ArrayLike, truth: ArrayLike, masks: Mapping[str, ArrayLike]
                 ) -> Dict[str, Dict[str, Any]]:
    """Completeness of ``dsm`` against ``truth`` (same grid) for each mask, in one call."""
    t = np.asarray(truth, np.float64)
    acc = CompletenessAccumulator()
    acc.add(np.asarray(dsm, np.float64) - t, masks, np.isfinite(t))
    return acc.result()


# -- building outlines --------------------------------------------------------------------------


def _boundary(mask: Array) -> Array:
    """Cells of ``mask`` with a 4-neighbour outside it (the raster edge counts as outside)."""
    inner = ndimage.binary_erosion(mask, structure=ndimage.generate_binary_structure(2, 1),
                                   border_value=0)
    return mask & ~inner


def wall_distances(found: ArrayLike, true: ArrayLike) -> Array:
    """Distances (cells) from each boundary cell of either mask to the other's boundary."""
    bf, bt = _boundary(np.asarray(found, bool)), _boundary(np.asarray(true, bool))
    if not bf.any() or not bt.any():
        return np.zeros(0)
    to_true = ndimage.distance_transform_edt(~bt)[bf]
    to_found = ndimage.distance_transform_edt(~bf)[bt]
    return np.concatenate([to_true, to_found])


def footprint_from_dsm(dsm: ArrayLike, dtm_true: ArrayLike, true_fp: Array, height: float,
                       others: Optional[Array] = None) -> Array:
    """The building's footprint in a DSM: nDSM ≥ ``height``/2, connected to the true one."""
    cand = (np.asarray(dsm, np.float64) - np.asarray(dtm_true, np.float64)) >= 0.5 * height
    if others is not None:
        cand &= ~others
    lab, n = ndimage.label(cand, structure=np.ones((3, 3), bool))
    if n == 0:
        return cand
    hit = np.unique(lab[true_fp & cand])
    return np.isin(lab, hit[hit > 0])


def building_outline(dsm: Array, dtm: Array, dsm_true: Array, labels: Array, b: int,
                     cell: float) -> Optional[Dict[str, Any]]:
    """IoU and wall distances of building ``b`` inside a window around it.

    Returns the row of :func:`outline_metrics` with the boundary distances (m) under ``"_d"``,
    or None when the building has no cells or no positive height in the window.
    """
    true_fp = labels == b
    if not true_fp.any():
        return None
    h = float(np.nanmedian((dsm_true - dtm)[true_fp]))
    if not math.isfinite(h) or h <= 0:
        return None
    found = footprint_from_dsm(dsm, dtm, true_fp, h, others=(labels > 0) & ~true_fp)
    inter = int(np.count_nonzero(found & true_fp))
    union = int(np.count_nonzero(found | true_fp))
    d = wall_distances(found, true_fp) * cell
    return {"id": int(b), "height_m": h, "cells": int(true_fp.sum()), "found_cells":
            int(found.sum()), "intersection": inter, "union": union,
            "iou": inter / union if union else 0.0,
            "wall_median_m": float(np.median(d)) if d.size else None, "_d": d}


def outline_metrics(dsm: ArrayLike, dtm_true: ArrayLike, dsm_true: ArrayLike, labels: ArrayLike,
                    cell: float, *, gsd: Optional[float] = None, margin: float = 5.0
                    ) -> Dict[str, Any]:
    """Footprints of the buildings in a DSM against their true footprints.

    Parameters
    ----------
    dsm, dtm_true, dsm_true : array_like, same shape
        DSM under test (resampled onto the truth grid; NaN = empty), true DTM and true DSM.
    labels : array_like of int
        True footprints rasterised on the same grid: building number, 0 = none.
    cell : float
        Cell size (m).
    gsd : float, optional
        Ground sampling distance (m): the wall error also in GSD.
    margin : float
        Metres around a footprint's bounding box in which the DSM footprint is sought.

    Returns
    -------
    dict
        ``buildings`` (per building: id, height_m, cells, found_cells, iou, wall_median_m),
        ``count``, ``iou_pooled`` (Σ intersections / Σ unions), ``iou_median``,
        ``wall_median_m`` (median over all boundary distances of all buildings), and
        ``wall_median_gsd`` with ``gsd``.
    """
    z, t, s = (np.asarray(a, np.float64) for a in (dsm, dtm_true, dsm_true))
    lab = np.asarray(labels)
    pad = math.ceil(margin / cell)
    objs = ndimage.find_objects(lab.astype(np.int64))
    rows: List[Dict[str, Any]] = []
    dist: List[Array] = []
    for i, sl in enumerate(objs):
        if sl is None:
            continue
        r0, r1 = max(sl[0].start - pad, 0), min(sl[0].stop + pad, lab.shape[0])
        c0, c1 = max(sl[1].start - pad, 0), min(sl[1].stop + pad, lab.shape[1])
        w = (slice(r0, r1), slice(c0, c1))
        one = building_outline(z[w], t[w], s[w], lab[w], i + 1, cell)
        if one is not None:
            dist.append(one.pop("_d"))
            rows.append(one)
    return summarise_outlines(rows, dist, gsd)


def summarise_outlines(rows: List[Dict[str, Any]], dist: List[Array],
                       gsd: Optional[float] = None) -> Dict[str, Any]:
    """Pooled figures of per-building rows (as :func:`outline_metrics` returns them)."""
    d = np.concatenate(dist) if dist else np.zeros(0)
    inter = sum(r["intersection"] for r in rows)
    union = sum(r["union"] for r in rows)
    wall = float(np.median(d)) if d.size else None
    return {
        "count": len(rows),
        "iou_pooled": inter / union if union else None,
        "iou_median": float(np.median([r["iou"] for r in rows])) if rows else None,
        "wall_median_m": wall,
        "wall_median_gsd": (wall / gsd if wall is not None and gsd else None),
        "buildings": rows,
    }


__all__ = [
    "COMPLETENESS_LIMITS",
    "INSET",
    "OBJECT_CLASSES",
    "OBJECT_HEIGHT",
    "OPEN_HEIGHT",
    "OPEN_MARGIN",
    "CompletenessAccumulator",
    "ObjectMasks",
    "building_outline",
    "completeness",
    "footprint_from_dsm",
    "mask_margin",
    "object_classes",
    "object_masks",
    "outline_metrics",
    "summarise_outlines",
    "wall_distances",
]
