r"""Filter review: re-run the low-pass filter on an area with other parameters, see before/after,
and patch the DTM only when the operator accepts.

:func:`refilter_area` reads the DSM in the area's bounding window plus a margin of the preset's
largest window (so that the filter sees the terrain around the area as in a full run), filters
it with :func:`.lowpass.lowpass_filter` and the project's edits, and compares the new DTM with the
existing one (read on the same cells) inside the area: :math:`\Delta h = h_{new} - h_{old}`
statistics and the eliminated shares before (the DTM folder's ``mask.tif``) and after. Nothing
is written. :func:`accept_refilter` then writes the new heights (and mask values) of the cells
whose centres lie in the area into ``dtm.tif`` (and ``mask.tif``), atomically (a patched copy
renamed into place); the cells outside the area keep their values bit for bit.
"""

from __future__ import annotations

import math
import shutil
from pathlib import Path
from typing import Any, Dict, Optional, Union

import numpy as np
import rasterio
import shapely.wkt
from rasterio.features import geometry_mask
from rasterio.windows import Window, from_bounds

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from ..quality.stats import difference_stats
from ..raster.io import atomic_output
from ..surface.gridding import Grid
from .lowpass import lowpass_filter, lowpass_parameters
from .surface_input import read_filter_constraints

PathLike = Union[str, Path]

#: Most cells of the window (area + margin) filtered at once.
MAX_REVIEW_CELLS = 16_000_000


def _area_geometry(area: Any) -> Any:
    if isinstance(area, str):
        area = shapely.wkt.loads(area)
    if area is None or area.is_empty or area.geom_type not in ("Polygon", "MultiPolygon"):
        raise InputError("Draw the area to re-filter as a polygon.")
    return area


def _window(src: Any, bounds: Any, margin: float) -> Window:
    """Whole-cell window of ``src`` covering ``bounds`` grown by ``margin`` (clipped)."""
    xmin, ymin, xmax, ymax = bounds
    win = from_bounds(xmin - margin, ymin - margin, xmax + margin, ymax + margin,
                      transform=src.transform)
    c0, r0 = max(math.floor(win.col_off), 0), max(math.floor(win.row_off), 0)
    c1 = min(math.ceil(win.col_off + win.width), src.width)
    r1 = min(math.ceil(win.row_off + win.height), src.height)
    if c1 <= c0 or r1 <= r0:
        raise InputError("The area lies outside the DSM; draw it where the DSM has heights.")
    if (c1 - c0) * (r1 - r0) > MAX_REVIEW_CELLS:
        raise InputError(f"The area with its margin holds more than {MAX_REVIEW_CELLS} cells; "
                         "draw a smaller area.")
    return Window(c0, r0, c1 - c0, r1 - r0)


def _read(path: Path, window: Window, transform: Any) -> np.ndarray:
    """Band 1 of ``path`` on the DSM window (same grid required), float64, NaN = nodata."""
    with rasterio.open(path) as src:
        if not np.allclose(tuple(src.transform)[:6], tuple(transform)[:6], atol=1e-6):
            raise InputError(f"'{path.name}' is not on the DSM's grid; the review compares "
                             "cells of a DTM filtered from this DSM.")
        a = src.read(1, window=window, masked=True, boundless=True)
    return np.ma.filled(a.astype(np.float64), np.nan)


def refilter_area(dsm: PathLike, dtm: PathLike, area: Any, *, preset: str = "default",
                  overrides: Optional[Dict[str, Any]] = None,
                  project: Optional[PathLike] = None, margin: Optional[float] = None,
                  feedback: Optional[Feedback] = None) -> Dict[str, Any]:
    """Re-filter the DSM in an area and compare with the existing DTM (nothing is written).

    Parameters
    ----------
    dsm : path
        The DSM the DTM was filtered from.
    dtm : path
        The existing DTM (``dtm.tif`` of a filter folder; its ``mask.tif`` beside it is read
        when present).
    area : shapely polygon or WKT
        In the DSM's CRS.
    preset, overrides
        As ``filter_lowpass`` (:func:`.lowpass.lowpass_parameters`).
    project : path, optional
        The project whose edits the filter honours.
    margin : float, optional
        Metres read around the area; default the preset's largest window.
    feedback : Feedback, optional

    Returns
    -------
    dict
        ``window`` (row, col, height, width of the DSM), ``transform``, ``crs``, ``dsm``,
        ``old``, ``new`` (DTM heights of the window), ``old_mask``/``new_mask`` (1 object,
        0 ground, NaN no data/unknown), ``inside`` (cells in the area), ``stats``
        (Δh = new − old inside), ``eliminated`` {``before``, ``after``} (shares inside),
        ``parameters``.
    """
    fb = ensure_feedback(feedback)
    geom = _area_geometry(area)
    params = lowpass_parameters(preset, overrides)
    dsm, dtm = Path(dsm), Path(dtm)
    for p, what in ((dsm, "DSM"), (dtm, "DTM")):
        if not p.is_file():
            raise InputError(f"The {what} '{p}' does not exist.")
    with rasterio.open(dsm) as src:
        reach = float(margin) if margin is not None else max(params.windows_m)
        win = _window(src, geom.bounds, reach)
        transform = src.window_transform(win)
        crs = src.crs
        z = np.ma.filled(src.read(1, window=win, masked=True).astype(np.float64), np.nan)
    old = _read(dtm, win, transform)
    grid = Grid(transform, int(win.width), int(win.height), abs(transform.a))
    cons = read_filter_constraints(project, grid, crs) if project else None
    res = lowpass_filter(z.astype(np.float32), grid.spacing, params, cons, grid,
                         feedback=fb.step(0.0, 95.0))
    new = res["dtm"].astype(np.float64)
    new_mask = np.where(np.isfinite(z), np.where(res["ground"], 0.0, 1.0), np.nan)
    mask_path = dtm.with_name("mask.tif")
    old_mask = np.full(z.shape, np.nan)
    if mask_path.is_file():
        m = _read(mask_path, win, transform)
        old_mask = np.where(m == 255, np.nan, m)
    inside = geometry_mask([geom], out_shape=z.shape, transform=transform, invert=True)

    def share(mask: np.ndarray) -> Optional[float]:
        m = mask[inside & np.isfinite(mask)]
        return float(m.mean()) if m.size else None

    return {"window": (int(win.row_off), int(win.col_off), int(win.height), int(win.width)),
            "transform": tuple(transform)[:6], "crs": crs.to_string() if crs else None,
            "dsm": z, "old": old, "new": new, "old_mask": old_mask, "new_mask": new_mask,
            "inside": inside, "stats": difference_stats((new - old)[inside]),
            "eliminated": {"before": share(old_mask), "after": share(new_mask)},
            "parameters": params.report(), "preset": params.preset, "area": geom.wkt}


def _patch(path: Path, review: Dict[str, Any], values: np.ndarray, nodata_fill: float) -> None:
    """Write ``values`` into the area's cells of ``path`` (a patched copy renamed in place)."""
    row, col, h, w = review["window"]
    win = Window(col, row, w, h)
    with atomic_output(path) as tmp:
        shutil.copyfile(path, tmp)
        with rasterio.open(tmp, "r+") as dst:
            current = dst.read(1, window=win)
            fill = dst.nodata if dst.nodata is not None else nodata_fill
            v = np.where(np.isfinite(values), values, fill).astype(current.dtype)
            dst.write(np.where(review["inside"], v, current), 1, window=win)


def accept_refilter(dtm: PathLike, review: Dict[str, Any]) -> Dict[str, Optional[str]]:
    """Write the reviewed area into the DTM (and its ``mask.tif``); cells outside stay as they
    are. Returns the paths written."""
    dtm = Path(dtm)
    if not dtm.is_file():
        raise InputError(f"The DTM '{dtm}' does not exist.")
    _patch(dtm, review, review["new"], np.nan)
    mask = dtm.with_name("mask.tif")
    written: Dict[str, Optional[str]] = {"dtm": str(dtm), "mask": None}
    if mask.is_file():
        _patch(mask, review, review["new_mask"], 255)
        written["mask"] = str(mask)
    return written


__all__ = ["MAX_REVIEW_CELLS", "accept_refilter", "refilter_area"]
