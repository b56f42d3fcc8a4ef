r"""Does a true ortho's occlusion mask match the truth? (issue 19)

A true ortho (:func:`.rectify.orthorectify_image` with a DSM) writes ``<stem>_visibility.tif``:
0 outside the image (or no height), 1 visible, 2 occluded — occluded as seen through the DSM
it was made with. With a **true DSM** the same test gives the *truth visibility* of every ortho
cell: the cell's true surface point :math:`(x, y, h_{true}(x, y))` is hidden when the ray to
the projection centre passes below the true DSM (:func:`.rectify.occlusion_flags`, the very
routine of the ortho, with its tolerance of one DSM cell and its 2 × 2 opening, so that an ortho
made on the true DSM agrees with it cell for cell).

Behind a wall of height :math:`h` at horizontal distance :math:`D` from the nadir, seen from
:math:`H` above the ground, the ground is hidden over a strip of width

.. math:: w = \frac{h\,D}{H - h} = \frac{h\,d}{H},

:math:`d = D + w` the distance of the strip's far end from the nadir (relief displacement).

Agreement over the cells inside the image (code 1 or 2) that have a true height: with
*tp* = occluded in both, *fp* = occluded in the ortho only, *fn* = in the truth only,

.. math:: P = \frac{tp}{tp + fp}, \quad R = \frac{tp}{tp + fn}, \quad
          F_1 = \frac{2\,tp}{2\,tp + fp + fn} .

Which cells are judged: with the image's camera and orientation, every cell whose true
surface point projects into the image — a cell the ortho left at 0 because its DSM had no
height there then counts as *not occluded* in the ortho (``no_height`` counts them), so a DSM
with holes where the occlusions are cannot look good. Without them, the cells the ortho marked
1 or 2 (holes of the DSM cannot be told from cells outside the image). ``f1_with_height`` is
F1 without the truly occluded cells the ortho had no height for (``no_height_occluded``): it
tells the DSM's coverage (holes the ortho could not fill) from its shape (walls, crowns); the
headline figure stays ``f1``. The raster is processed
in windows of ``window_size`` cells (plus a ring of one cell for the opening); the truth DSM is
read per window with the march margin, never whole.
"""

from __future__ import annotations

import contextlib
from pathlib import Path
from typing import Any, Dict, Iterable, Optional, Tuple, Union

import numpy as np
import rasterio
from affine import Affine
from numpy.typing import ArrayLike, NDArray
from rasterio.features import geometry_mask
from rasterio.windows import Window

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from ..geometry.camera import Camera
from ..geometry.orientation import ExteriorOrientation
from .rectify import (
    occlusion_flags,
    open_surface,
    project_grid,
    read_surface,
    surface_heights,
)

PathLike = Union[str, Path]
COUNT_KEYS = ("cells", "tp", "fp", "fn", "tn", "no_height", "no_height_occluded")


def ortho_centre(ortho: PathLike) -> NDArray[np.float64]:
    """Projection centre from the tags ``PHOTODEM_CAMERA_X/Y/Z`` of an ortho.

    Raises
    ------
    InputError
        When the file has no such tags (not a PhotoDEM ortho).
    """
    with rasterio.open(ortho) as src:
        tags = src.tags()
    try:
        return np.array([float(tags[f"PHOTODEM_CAMERA_{k}"]) for k in "XYZ"])
    except KeyError as exc:
        raise InputError(f"'{Path(ortho).name}' has no projection centre tags; give the "
                         "centre explicitly.") from exc


def _ortho_of(visibility: Path) -> Path:
    """The ortho beside ``<stem>_visibility.tif``."""
    stem = visibility.stem
    if not stem.endswith("_visibility"):
        raise InputError(f"'{visibility.name}' is not named <ortho>_visibility.tif; give the "
                         "projection centre explicitly.")
    return visibility.with_name(stem[: -len("_visibility")] + visibility.suffix)


def _truth(truth_ds: Any, centre: ArrayLike, xs: NDArray[np.float64], ys: NDArray[np.float64]
           ) -> Tuple[NDArray[np.bool_], NDArray[np.float64]]:
    """Truth occlusion flags and true heights of the cells ``xs`` × ``ys``."""
    bounds = (float(xs.min()), float(ys.min()), float(xs.max()), float(ys.max()))
    got = read_surface(truth_ds, bounds)
    if got is None:
        return np.zeros((ys.size, xs.size), dtype=bool), np.full((ys.size, xs.size), np.nan)
    z = surface_heights(got[0], got[1], xs, ys)
    valid = np.isfinite(z)
    if not valid.any():
        return np.zeros(z.shape, dtype=bool), z
    return occlusion_flags(truth_ds, None, centre, xs, ys, z, valid) & valid, z


def truth_occlusion(truth_ds: Any, centre: ArrayLike, xs: NDArray[np.float64],
                    ys: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Truth visibility of the cells ``xs`` (columns) × ``ys`` (rows): True where the true
    surface point is hidden from ``centre`` by the true DSM (an open dataset in the CRS of the
    cells). Cells without a true height are False."""
    return _truth(truth_ds, centre, xs, ys)[0]


def _window_counts(vis: NDArray[np.uint8], truth_occ: NDArray[np.bool_],
                   judged: NDArray[np.bool_]) -> Dict[str, int]:
    o, t = (vis == 2) & judged, truth_occ & judged
    return {"cells": int(judged.sum()), "tp": int((o & t).sum()), "fp": int((o & ~t).sum()),
            "fn": int((~o & t).sum()), "tn": int((judged & ~o & ~t).sum()),
            "no_height": int((judged & (vis == 0)).sum()),
            "no_height_occluded": int((t & (vis == 0)).sum())}


def agreement_from_counts(counts: Dict[str, int]) -> Dict[str, Any]:
    """Precision, recall, F1 (also over the cells with a height, ``f1_with_height``) and the
    occluded shares (%) from summed counts (None where a ratio has no cells)."""
    counts = {k: int(counts.get(k, 0)) for k in COUNT_KEYS}
    tp, fp, fn, n = (counts[k] for k in ("tp", "fp", "fn", "cells"))
    fn_height = fn - counts["no_height_occluded"]

    def ratio(a: int, b: int) -> Optional[float]:
        return a / b if b else None

    return {**counts, "precision": ratio(tp, tp + fp),
            "recall": ratio(tp, tp + fn), "f1": ratio(2 * tp, 2 * tp + fp + fn),
            "f1_with_height": ratio(2 * tp, 2 * tp + fp + fn_height),
            "ortho_occluded_pct": 100.0 * ratio(tp + fp, n) if n else None,
            "truth_occluded_pct": 100.0 * ratio(tp + fn, n) if n else None,
            "no_height_pct": 100.0 * ratio(counts["no_height"], n) if n else None}


def pooled_agreement(results: Iterable[Dict[str, Any]]) -> Dict[str, Any]:
    """The agreement over several orthos (counts summed, then the ratios)."""
    total = dict.fromkeys(COUNT_KEYS, 0)
    for r in results:
        for k in COUNT_KEYS:
            total[k] += int(r.get(k, 0))
    return agreement_from_counts(total)


def occlusion_agreement(visibility: PathLike, truth_dsm: PathLike, *,
                        centre: Optional[ArrayLike] = None, camera: Optional[Camera] = None,
                        eo: Optional[ExteriorOrientation] = None, area: Any = None,
                        window_size: int = 512, feedback: Optional[Feedback] = None
                        ) -> Dict[str, Any]:
    """Compare a true ortho's occlusion mask with the truth visibility from the true DSM.

    Parameters
    ----------
    visibility : path
        ``<stem>_visibility.tif`` of a true ortho (0 outside, 1 visible, 2 occluded).
    truth_dsm : path
        True DSM (any grid; read in the visibility raster's CRS, bilinear at the cell centres).
    centre : array_like, shape (3,), optional
        Projection centre of the image; default ``eo.position``, else from the tags of the
        ortho beside ``visibility`` (:func:`ortho_centre`).
    camera, eo : optional
        The image's camera and exterior orientation: judge every cell whose true surface point
        lies in the image (see the module notes); without them the cells marked 1 or 2.
    area : shapely geometry, optional
        Judge only cells inside it (CRS of the raster), e.g. the measuring area of the
        models the DSM was matched in, so that the image's footprint beyond the DSM does not
        count as holes.
    window_size : int
        Window edge (cells); bounds the memory.
    feedback : Feedback, optional
        Progress per window, cancellation.

    Returns
    -------
    dict
        ``cells`` (judged), ``tp``, ``fp``, ``fn``, ``tn``, ``no_height``,
        ``no_height_occluded``, ``precision``, ``recall``, ``f1``, ``f1_with_height``,
        ``ortho_occluded_pct``, ``truth_occluded_pct``, ``no_height_pct`` (see the module
        notes), ``image``.
    """
    fb = ensure_feedback(feedback)
    visibility = Path(visibility)
    if window_size < 8:
        raise InputError("The window size must be at least 8 cells.")
    if (camera is None) != (eo is None):
        raise InputError("Give both the camera and the orientation of the image, or neither.")
    if centre is None:
        C = eo.position if eo is not None else ortho_centre(_ortho_of(visibility))
    else:
        C = np.asarray(centre, float)
    total = dict.fromkeys(COUNT_KEYS, 0)
    with contextlib.ExitStack() as stack:
        vsrc = stack.enter_context(rasterio.open(visibility))
        crs = vsrc.crs.to_string() if vsrc.crs else ""
        tds = stack.enter_context(open_surface(truth_dsm, crs, fb, "true DSM"))
        t, W, H = vsrc.transform, vsrc.width, vsrc.height
        if t.b != 0.0 or t.d != 0.0:
            raise InputError("The visibility raster must be north-up.")
        wins = [(r, c) for r in range(0, H, window_size) for c in range(0, W, window_size)]
        for i, (r0, c0) in enumerate(wins):
            fb.check()
            h, w = min(window_size, H - r0), min(window_size, W - c0)
            vis = vsrc.read(1, window=Window(c0, r0, w, h))
            if camera is not None or (vis > 0).any():
                # a ring of one cell, as the ortho's tiles have, for the 2 × 2 opening
                xs = t.c + (np.arange(c0 - 1, c0 + w + 1) + 0.5) * t.a
                ys = t.f + (np.arange(r0 - 1, r0 + h + 1) + 0.5) * t.e
                occ, z = _truth(tds, C, xs, ys)
                inner = (slice(1, -1), slice(1, -1))
                judged = _judged(vis, xs, ys, z, camera, eo)[inner]
                if area is not None:
                    judged &= geometry_mask([area], out_shape=(h, w), invert=True,
                                            transform=t * Affine.translation(c0, r0))
                for k, v in _window_counts(vis, occ[inner], judged).items():
                    total[k] += v
            fb.progress(100.0 * (i + 1) / len(wins))
        image = vsrc.tags().get("PHOTODEM_IMAGE", visibility.stem)
    return {**agreement_from_counts(total), "image": image}


def _judged(vis: NDArray[np.uint8], xs: NDArray[np.float64], ys: NDArray[np.float64],
            z: NDArray[np.float64], camera: Optional[Camera], eo: Optional[ExteriorOrientation]
            ) -> NDArray[np.bool_]:
    """Cells to judge on the ringed grid: true point in the image (with a camera), else the
    ortho's cells inside the image; always with a true height."""
    has = np.isfinite(z)
    if camera is None or eo is None:
        ring = np.zeros(z.shape, dtype=bool)
        ring[1:-1, 1:-1] = vis > 0
        return ring & has
    col, row = project_grid(camera, eo, xs, ys, np.where(has, z, 0.0))
    return (has & (col >= -0.5) & (col <= camera.width - 0.5) & (row >= -0.5)
            & (row <= camera.height - 0.5))


__all__ = [
    "agreement_from_counts",
    "occlusion_agreement",
    "ortho_centre",
    "pooled_agreement",
    "truth_occlusion",
]
