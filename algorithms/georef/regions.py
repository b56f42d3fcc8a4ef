"""Image objects: multiple region-growing segmentation and the regions' outlines.

Region growing with an adaptive threshold (Levine & Shaheen; Hild 2003 §2.1, methods note
seed-001 §2.1): one pass in scan order from a chosen corner; a pixel joins the 4-neighbour region
(left or previous row) whose mean it is close to — within the region's own threshold
``h' = (1 − min(0.8, σ'/F')) · h`` after the pixel is added, so inhomogeneous regions grow more
strictly — or starts a new region. No merging afterwards. No single threshold segments every
object well, so the segmentation runs for several thresholds and **all** regions of all runs are
candidate objects ("multiple segmentation").

The scan is inherently sequential (each decision changes the region the next pixel compares
with); it runs as a tight pure-Python loop over a pyramid level of the image (``"auto"``: at most
:data:`AUTO_MAX_PIXELS` pixels), ~1 µs per pixel. Outlines follow the pixel edges of the segmented
level (``rasterio.features.shapes``) and are given in level-0 image coordinates (pixel centres at
integers).
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
from numpy.typing import NDArray
from rasterio import features
from rasterio.transform import Affine
from scipy import ndimage

from ..errors import InputError
from ..feedback import Feedback
from ..raster.io import open_image
from .objects import IMAGE, PolygonObject, orient_ring

#: Default thresholds (DN of 8-bit data), over- to under-segmentation (seed-001 §2.19).
DEFAULT_THRESHOLDS = (5.0, 6.0, 7.0, 8.0)
#: ``pyramid_level="auto"`` segments the first level with at most this many pixels.
AUTO_MAX_PIXELS = 4_000_000
#: Clamp of σ/F in the adaptive threshold (fixed in the method).
CLAMP = 0.8

CORNERS = ("lower_left", "upper_left", "lower_right", "upper_right")


def _flip(a: NDArray[Any], corner: str) -> NDArray[Any]:
    """View of ``a`` (…, rows, cols) whose row-major scan starts at ``corner``."""
    if corner not in CORNERS:
        raise InputError.of("Unknown scan start corner '{value}'; use one of {options}.",
                            value=corner, options=", ".join(CORNERS))
    if corner.startswith("lower"):
        a = a[..., ::-1, :]
    if corner.endswith("right"):
        a = a[..., ::-1]
    return a


def grow_regions(image: NDArray[Any], threshold: float, start_corner: str = "lower_left"
                 ) -> NDArray[np.int32]:
    """Label image of the adaptive-threshold region growing.

    Parameters
    ----------
    image : ndarray, shape (rows, cols) or (bands, rows, cols)
        Grey values in 0..255 (see :func:`stretch_to_byte`); NaN = no data (label 0).
    threshold : float
        The global threshold h (DN). Small → over-, large → under-segmentation.
    start_corner : {"lower_left", "upper_left", "lower_right", "upper_right"}
        Where the scan starts (the method's default: lower left); the result depends on it.

    Returns
    -------
    ndarray of int32, shape (rows, cols)
        Regions 1..n numbered in scan order, 0 on no-data pixels. Every region is
        4-connected. With several bands a pixel must pass the test in every band and the
        region with the smallest sum of squared differences wins.
    """
    a = np.asarray(image, dtype=np.float64)
    if a.ndim == 2:
        a = a[None]
    if a.ndim != 3:
        raise InputError("Region growing needs a (rows, cols) or (bands, rows, cols) image.")
    a = _flip(a, start_corner)
    if a.shape[0] == 1:
        lab = _grow_single(a[0], float(threshold))
    else:
        lab = _grow_multi(a, float(threshold))
    return np.ascontiguousarray(_flip(lab, start_corner))


def _grow_single(img: NDArray[np.float64], h: float) -> NDArray[np.int32]:
    """One band: the scan as a tight loop on Python floats (inherently sequential)."""
    rows, cols = img.shape
    out = np.zeros((rows, cols), np.int32)
    valid = np.isfinite(img)
    cnt: List[float] = [0.0]  # region 0 = no data, never joined
    mean: List[float] = [0.0]
    m2: List[float] = [0.0]
    prev = [0] * cols
    sqrt = math.sqrt
    for r in range(rows):
        line = img[r].tolist()
        ok = valid[r].tolist()
        cur = [0] * cols
        left = 0
        for c in range(cols):
            if not ok[c]:
                cur[c] = 0
                left = 0
                continue
            p = line[c]
            best = 0
            best_d = 0.0
            up = prev[c]
            for lab in (left, up) if up != left else (left,):
                if lab == 0:
                    continue
                n = cnt[lab]
                f = mean[lab]
                f_new = f + (p - f) / (n + 1.0)
                s = sqrt((m2[lab] + (p - f) * (p - f_new)) / n)
                ratio = s / f_new if f_new > 0.0 else CLAMP
                d = abs(p - f_new)
                if d <= (1.0 - (ratio if ratio < CLAMP else CLAMP)) * h and (
                        best == 0 or d < best_d):
                    best, best_d = lab, d
            if best == 0:
                best = len(cnt)
                cnt.append(1.0)
                mean.append(p)
                m2.append(0.0)
            else:
                n = cnt[best]
                f = mean[best]
                f_new = f + (p - f) / (n + 1.0)
                m2[best] += (p - f) * (p - f_new)
                mean[best] = f_new
                cnt[best] = n + 1.0
            cur[c] = best
            left = best
        out[r] = cur
        prev = cur
    return out


def _grow_multi(img: NDArray[np.float64], h: float) -> NDArray[np.int32]:
    """Several bands: every band must pass; the smallest Σ ΔF² wins (slower, general)."""
    nb, rows, cols = img.shape
    out = np.zeros((rows, cols), np.int32)
    valid = np.all(np.isfinite(img), axis=0)
    cnt: List[float] = [0.0]
    mean: List[List[float]] = [[0.0] * nb]
    m2: List[List[float]] = [[0.0] * nb]
    prev = [0] * cols
    sqrt = math.sqrt
    bands = range(nb)
    for r in range(rows):
        lines = [img[b, r].tolist() for b in bands]
        ok = valid[r].tolist()
        cur = [0] * cols
        left = 0
        for c in range(cols):
            if not ok[c]:
                left = 0
                continue
            px = [lines[b][c] for b in bands]
            best, best_d = 0, 0.0
            up = prev[c]
            for lab in (left, up) if up != left else (left,):
                if lab == 0:
                    continue
                n = cnt[lab]
                total = 0.0
                for b in bands:
                    p, f = px[b], mean[lab][b]
                    f_new = f + (p - f) / (n + 1.0)
                    s = sqrt((m2[lab][b] + (p - f) * (p - f_new)) / n)
                    ratio = s / f_new if f_new > 0.0 else CLAMP
                    d = abs(p - f_new)
                    if d > (1.0 - min(ratio, CLAMP)) * h:
                        total = -1.0
                        break
                    total += d * d
                if total >= 0.0 and (best == 0 or total < best_d):
                    best, best_d = lab, total
            if best == 0:
                best = len(cnt)
                cnt.append(1.0)
                mean.append(list(px))
                m2.append([0.0] * nb)
            else:
                n = cnt[best]
                for b in bands:
                    p, f = px[b], mean[best][b]
                    f_new = f + (p - f) / (n + 1.0)
                    m2[best][b] += (p - f) * (p - f_new)
                    mean[best][b] = f_new
                cnt[best] = n + 1.0
            cur[c] = best
            left = best
        out[r] = cur
        prev = cur
    return out


def merge_regions(labels: NDArray[np.int32], image: NDArray[Any], threshold: float
                  ) -> NDArray[np.int32]:
    """Extension: merge adjacent regions whose means agree within the adaptive threshold.

    The scan never merges, so one homogeneous object that the scan enters at two places (two
    lobes of a forest) stays split along an arbitrary line. Here adjacent regions are merged,
    the closest means first (union–find with pooled statistics), when
    |F_a − F_b| ≤ (1 − min(0.8, σ/F)) · h with σ and F of the merged region. Multi-band images
    use their band mean.
    """
    a = np.asarray(image, dtype=np.float64)
    if a.ndim == 3:
        a = a.mean(axis=0)
    lab = np.asarray(labels)
    n = int(lab.max()) + 1
    ok = lab > 0
    v = np.where(ok, a, 0.0)
    cnt = np.bincount(lab.ravel(), minlength=n).astype(np.float64)
    s1 = np.bincount(lab.ravel(), weights=v.ravel(), minlength=n)
    s2 = np.bincount(lab.ravel(), weights=(v * v).ravel(), minlength=n)
    pairs = []
    for x, y in ((lab[:, :-1], lab[:, 1:]), (lab[:-1, :], lab[1:, :])):
        m = (x != y) & (x > 0) & (y > 0)
        p = np.stack([np.minimum(x[m], y[m]), np.maximum(x[m], y[m])], axis=1)
        pairs.append(p)
    edges = np.unique(np.concatenate(pairs), axis=0) if pairs else np.zeros((0, 2), int)
    if edges.size == 0:
        return lab.astype(np.int32)
    mean = s1 / np.maximum(cnt, 1.0)
    order = np.argsort(np.abs(mean[edges[:, 0]] - mean[edges[:, 1]]), kind="stable")
    parent = list(range(n))
    cnt_l, s1_l, s2_l = cnt.tolist(), s1.tolist(), s2.tolist()

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for e in order.tolist():
        ra, rb = find(int(edges[e, 0])), find(int(edges[e, 1]))
        if ra == rb:
            continue
        na, nb = cnt_l[ra], cnt_l[rb]
        fa, fb = s1_l[ra] / na, s1_l[rb] / nb
        n_ab = na + nb
        f = (s1_l[ra] + s1_l[rb]) / n_ab
        var = max((s2_l[ra] + s2_l[rb]) / n_ab - f * f, 0.0) * n_ab / max(n_ab - 1.0, 1.0)
        ratio = math.sqrt(var) / f if f > 0 else CLAMP
        if abs(fa - fb) <= (1.0 - min(ratio, CLAMP)) * threshold:
            parent[rb] = ra
            cnt_l[ra] = n_ab
            s1_l[ra] += s1_l[rb]
            s2_l[ra] += s2_l[rb]
    root = np.array([find(i) for i in range(n)])
    # consecutive labels (label 0, no data, is never merged and keeps 0)
    _, inv = np.unique(root, return_inverse=True)
    out = inv.astype(np.int32)[lab]
    out[~ok] = 0
    return out.astype(np.int32)


def stretch_to_byte(array: NDArray[Any], low: float = 2.0, high: float = 98.0
                    ) -> NDArray[np.float64]:
    """Linear stretch of the ``low``–``high`` percentiles to 0..255 (NaN kept).

    The thresholds are DN of 8-bit data and σ/F depends on the offset, so 16-bit or
    reflectance data are brought to that range first.
    """
    a = np.asarray(array, dtype=np.float64)
    finite = a[np.isfinite(a)]
    if finite.size == 0:
        raise InputError.of("The image has no valid pixels.")
    lo, hi = np.percentile(finite, [low, high])
    if hi <= lo:
        return np.where(np.isfinite(a), 128.0, np.nan)
    return np.clip((a - lo) * (255.0 / (hi - lo)), 0.0, 255.0)


def reduce_level(image: NDArray[Any], level: int) -> NDArray[np.float64]:
    """Pyramid level ``level`` (factor 2 per level, mean of 2 × 2 blocks; the last odd row and
    column are dropped, as level-L pixel j covers level-0 pixels j·2^L … j·2^L + 2^L − 1)."""
    a = np.asarray(image, dtype=np.float64)
    for _ in range(int(level)):
        r, c = (a.shape[-2] // 2) * 2, (a.shape[-1] // 2) * 2
        a = a[..., :r, :c]
        a = 0.25 * (a[..., 0::2, 0::2] + a[..., 1::2, 0::2] + a[..., 0::2, 1::2]
                    + a[..., 1::2, 1::2])
    return a


def auto_level(width: int, height: int, max_pixels: int = AUTO_MAX_PIXELS) -> int:
    """Smallest pyramid level whose image has at most ``max_pixels`` pixels."""
    level = 0
    while (width >> level) * (height >> level) > max_pixels and min(width, height) >> level > 64:
        level += 1
    return level


def label_rings(labels: NDArray[Any], keep: Optional[NDArray[np.bool_]] = None
                ) -> List[Tuple[int, NDArray[np.float64]]]:
    """Outer rings of labelled regions along pixel edges (holes dropped).

    Coordinates are pixel corners of the label grid (pixel (r, c) covers [c, c+1] × [r, r+1]),
    positively oriented in that frame. ``keep`` (bool per label value, index = label) limits
    the regions traced.
    """
    lab = np.asarray(labels, dtype=np.int32)
    mask = lab > 0
    if keep is not None:
        mask &= np.asarray(keep, bool)[lab]
    out: List[Tuple[int, NDArray[np.float64]]] = []
    if not mask.any():
        return out
    for geom, value in features.shapes(lab, mask=mask, connectivity=4,
                                       transform=Affine.identity()):
        ring = np.asarray(geom["coordinates"][0], dtype=np.float64)
        out.append((int(value), orient_ring(ring)))
    out.sort(key=lambda t: t[0])
    return out


def image_objects(image: NDArray[Any], thresholds: Sequence[float] = DEFAULT_THRESHOLDS,
                  min_area: float = 0.0003, max_area: float = 0.05,
                  pyramid_level: Union[int, str] = "auto", start_corner: str = "lower_left",
                  smooth: float = 0.0, merge: bool = False,
                  feedback: Optional[Feedback] = None, first_id: int = 0
                  ) -> Tuple[List[PolygonObject], Dict[str, Any]]:
    """All regions of all threshold runs as candidate objects (multiple segmentation).

    Parameters
    ----------
    image : ndarray, (rows, cols) or (bands, rows, cols)
        Level-0 image in 0..255 (see :func:`stretch_to_byte`), NaN = no data.
    thresholds : sequence of float
        One segmentation run per threshold (DN).
    min_area, max_area : float
        Size window: below 1 as a share of the image area, else level-0 px². The huge
        background region is removed by ``max_area``.
    pyramid_level : int or "auto"
        Segment this pyramid level (``"auto"``: :func:`auto_level`).
    start_corner : str
        Scan start (see :func:`grow_regions`).
    smooth : float
        Extension: Gaussian smoothing (σ in pixels of the segmented level) before the
        region growing, against sensor noise; 0 = the method as published.
    merge : bool
        Extension: merge adjacent regions of similar mean after the scan
        (:func:`merge_regions`); False = the method as published.

    Returns
    -------
    objects : list of PolygonObject
        Rings in level-0 image coordinates (pixel centres at integers); ``touches_border``
        for regions touching the image border or no-data.
    info : dict
        Level used, regions per run before and after the size window.
    """
    fb = feedback or Feedback()
    a = np.asarray(image, dtype=np.float64)
    rows0, cols0 = a.shape[-2:]
    level = auto_level(cols0, rows0) if pyramid_level in ("auto", None, -1) else \
        int(pyramid_level)
    small = reduce_level(a, level)
    if smooth > 0:
        sig = (0, smooth, smooth) if small.ndim == 3 else smooth
        nan = ~np.isfinite(small)
        small = ndimage.gaussian_filter(np.where(nan, np.nanmean(small), small), sig)
        small[nan] = np.nan
    scale = float(2 ** level)
    area0 = float(rows0 * cols0)
    lo = min_area * area0 if min_area < 1 else float(min_area)
    hi = max_area * area0 if max_area <= 1 else float(max_area)
    valid = np.all(np.isfinite(small), axis=0) if small.ndim == 3 else np.isfinite(small)
    # pixels next to the border or to no-data: a region containing one is cut off there
    edge = ~valid
    edge = np.pad(edge, 1, constant_values=True)
    edge = (edge[:-2, 1:-1] | edge[2:, 1:-1] | edge[1:-1, :-2] | edge[1:-1, 2:]) & valid
    objects: List[PolygonObject] = []
    runs = []
    for k, h in enumerate(thresholds):
        fb.check()
        t0 = time.perf_counter()
        lab = grow_regions(small, float(h), start_corner)
        if merge:
            lab = merge_regions(lab, small, float(h))
        n = int(lab.max())
        counts = np.bincount(lab.ravel(), minlength=n + 1).astype(np.float64) * scale * scale
        keep = (counts >= lo) & (counts <= hi)
        keep[0] = False
        border = np.zeros(n + 1, bool)
        border[np.unique(lab[edge])] = True
        rings = label_rings(lab, keep)
        for value, ring in rings:
            # level-L corner coordinate u ↔ level-0 corner u·2^L ↔ centre convention − 0.5
            ring0 = ring * scale - 0.5
            objects.append(PolygonObject(
                id=first_id + len(objects), ring=ring0, source=IMAGE, run=k,
                threshold=float(h), touches_border=bool(border[value]),
                attributes={"label": value, "pixels": round(float(counts[value]) / scale**2)}))
        # (no timings in the result: reports must be identical between runs)
        runs.append({"threshold": float(h), "regions": n, "in_size_window": int(keep.sum())})
        fb.progress(100.0 * (k + 1) / len(thresholds))
        fb.info(f"Segmentation h = {h:g}: {n} regions, {int(keep.sum())} within the size "
                f"window ({lo:.0f}…{hi:.0f} px²), {time.perf_counter() - t0:.1f} s.")
    info = {"level": level, "smooth": smooth, "merge": merge, "min_area_px": lo,
            "max_area_px": hi, "runs": runs, "size": [int(cols0), int(rows0)]}
    return objects, info


def load_image(path: Union[str, Path], band: Optional[int] = None
               ) -> Tuple[NDArray[np.float64], Dict[str, Any]]:
    """Read an image to georeference as one 0..255 grey band.

    Default: the mean of all bands (seed-001: the XS experiment used the band mean); ``band``
    (1-based) selects one. Non-byte data are stretched (2–98 %); masked pixels become NaN.
    Whole-image read: the images this method is for (satellite scenes, scanned photos at a
    pyramid level) are a few Mpx.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError.of("Image '{path}' not found.", path=path)
    try:
        with open_image(path) as src:
            if band is not None and not 1 <= int(band) <= src.count:
                raise InputError.of("Band {band} does not exist: '{name}' has {count} "
                                    "band(s).", band=band, name=path.name, count=src.count)
            idx = [int(band)] if band is not None else list(range(1, src.count + 1))
            data = src.read(idx, masked=True).astype(np.float64)
            dtype = src.dtypes[0]
            info = {"width": src.width, "height": src.height, "bands": src.count,
                    "dtype": dtype, "crs": src.crs.to_wkt() if src.crs else None,
                    "transform": list(src.transform)[:6]}
    except InputError:
        raise
    except Exception as exc:  # rasterio's own message says what is wrong with the file
        raise InputError.of("Cannot read image '{path}': {error}", path=path,
                            error=exc) from exc
    mask = np.ma.getmaskarray(data).any(axis=0)
    grey = np.ma.getdata(data).mean(axis=0)
    grey[mask] = np.nan
    if dtype != "uint8":
        grey = stretch_to_byte(grey)
        info["stretch"] = "2–98 % percentiles to 0..255"
    info["band"] = "mean of all bands" if band is None else int(band)
    return grey, info
