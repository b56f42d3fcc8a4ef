r"""Orthophoto mosaic: several orthos → one Cloud-Optimised GeoTIFF, seams, balancing.

Inputs
    Orthos in the PhotoDEM format (:mod:`.rectify`): colour bands + alpha band (255 valid,
    0 outside or occluded), tags ``PHOTODEM_IMAGE`` and ``PHOTODEM_CAMERA_X/Y`` (projection
    centre). Other orthos are accepted too: validity from an alpha band, else the nodata value,
    else the raster extent; the nadir point is then the raster centre (with a warning). All
    inputs must have the same CRS, colour band count and data type.

Grid
    North-up, cell size ``gsd`` (default the finest input), origin on a multiple of the cell
    size (the rule of :func:`.rectify.orthorectify_image`, so orthos of the same GSD are copied
    cell for cell; others are resampled bilinearly, alpha by nearest neighbour).

Steps
    1. *Seam grid*: the mosaic grid reduced by the integer factor
       :math:`f = \lceil \max(W, H) / \mathrm{seam\_cells} \rceil`; every ortho is
       block-averaged onto it (colour and alpha, GDAL ``average``), with DSM (block maximum)
       and DTM (block mean) when given.
    2. *Balancing* (:mod:`.balance`) from the cells valid in both images of every overlap.
    3. *Partition* (:mod:`.seamlines`): nadir Voronoi partition, then least-cost seams
       (``auto``), or the operator's seamlines.
    4. *Mosaic*, tile by tile (``tile`` × ``tile`` cells plus a halo of half the feather width):
       the label of each cell is the seam-grid label (or the operator's region, rasterised at
       full resolution); where that image is not valid (outside, or occluded in a true ortho)
       the cell is filled from the valid image with the nearest projection centre ("next best
       image"). Feathering: with :math:`d_k` the signed distance (cells) of a cell to the
       border of image :math:`k`'s region (positive inside) and :math:`F` the feather width in
       cells, the weights are :math:`w_k = \mathrm{clip}(\tfrac12 + d_k/F, 0, 1)` times the
       validity of image :math:`k`, and the value is :math:`\sum_k w_k v_k' / \sum_k w_k` — a
       linear ramp of width :math:`F` across every seam.

Memory
    Seam grid: at most ``seam_cells²`` cells, a window per ortho (≈ overlap factor × bands ×
    4 bytes per cell); mosaic: one tile plus halo per ortho that touches it. Neither grows with
    the mosaic size beyond the seam grid, whose size is a parameter.

Outputs
    ``output`` (colour bands + alpha, the inputs' data type, overviews), beside it
    ``<stem>_seamlines.gpkg`` (layer ``footprints``: one polygon per source image with
    ``image``, ``ortho``, ``area_m2``; layer ``seamlines``: shared borders) and
    ``<stem>_balance.json`` (gains/offsets per image and band, mean and mean absolute
    difference per overlap before/after balancing).
"""

from __future__ import annotations

import functools
import json
import math
import time
from contextlib import ExitStack
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import rasterio
from affine import Affine
from numpy.typing import NDArray
from rasterio.enums import ColorInterp, Resampling
from rasterio.warp import reproject
from rasterio.windows import Window
from scipy import ndimage
from shapely.geometry import box
from shapely.ops import unary_union

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from ..project.model import Project
from ..raster.io import (
    atomic_output,
    cog_output,
    gtiff_profile,
    open_image,
    overview_factors,
    scratch_folder,
)
from ..raster.tiled_dask import check_scheduler, map_tiles
from . import balance as bal
from . import seamlines as sl
from .rectify import orthorectify_image

PathLike = Union[str, Path]
Array = NDArray[Any]

#: Seamline sources besides a vector file.
SEAMLINE_MODES = ("auto", "nadir", "edits")


@dataclass
class OrthoInfo:
    """What the mosaic needs to know about one input ortho."""

    path: Path
    name: str
    crs: Any
    transform: Affine
    width: int
    height: int
    colour: List[int]
    alpha: Optional[int]
    nodata: Optional[float]
    dtype: str
    centre: Tuple[float, float]
    centre_from_tags: bool
    colorinterp: List[Any]

    @property
    def gsd(self) -> float:
        return min(abs(self.transform.a), abs(self.transform.e))

    @property
    def bounds(self) -> Tuple[float, float, float, float]:
        t = self.transform
        xs = (t.c, t.c + t.a * self.width)
        ys = (t.f, t.f + t.e * self.height)
        return min(xs), min(ys), max(xs), max(ys)


def read_ortho_info(path: PathLike) -> OrthoInfo:
    """Open an ortho and describe it (see the module notes on accepted inputs).

    Raises
    ------
    InputError
        Missing or unreadable file, rotated raster.
    """

    path = Path(path)
    if not path.is_file():
        raise InputError(f"Ortho '{path}' does not exist.")
    try:
        with rasterio.open(path) as src:
            tags = src.tags()
            interp = list(src.colorinterp)
            alpha = [i + 1 for i, c in enumerate(interp) if c == ColorInterp.alpha]
            if not alpha and "PHOTODEM_IMAGE" in tags and src.count >= 2:
                alpha = [src.count]  # the shared format: the last band is alpha
            colour = [b for b in range(1, src.count + 1) if b not in alpha]
            t = src.transform
            if abs(t.b) > 0 or abs(t.d) > 0:
                raise InputError(f"'{path.name}' is a rotated raster; warp it north-up first.")
            b = src.bounds
            try:
                centre = (float(tags["PHOTODEM_CAMERA_X"]), float(tags["PHOTODEM_CAMERA_Y"]))
                from_tags = True
            except (KeyError, ValueError):
                centre = (0.5 * (b.left + b.right), 0.5 * (b.bottom + b.top))
                from_tags = False
            return OrthoInfo(path, tags.get("PHOTODEM_IMAGE") or path.stem, src.crs, t,
                             src.width, src.height, colour, alpha[0] if alpha else None,
                             src.nodata, src.dtypes[colour[0] - 1] if colour else src.dtypes[0],
                             centre, from_tags, [interp[i - 1] for i in colour])
    except rasterio.errors.RasterioIOError as exc:
        raise InputError(f"Cannot read the ortho '{path.name}': {exc}") from exc


def check_inputs(infos: Sequence[OrthoInfo]) -> None:
    """One-line errors for inputs that cannot be mosaicked together."""
    if not infos:
        raise InputError("No orthos given; give at least one ortho (or a project and a DEM).")
    names = [i.name for i in infos]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise InputError(f"The image {', '.join(dup)} occurs in more than one input ortho; "
                         "give each image once.")
    counts = {len(i.colour) for i in infos}
    if len(counts) > 1:
        detail = ", ".join(f"{i.path.name}: {len(i.colour)}" for i in infos)
        raise InputError(f"The orthos have different band counts ({detail}); mosaic only "
                         "orthos with the same bands (e.g. all RGB or all grey).")
    dtypes = {i.dtype for i in infos}
    if len(dtypes) > 1:
        detail = ", ".join(f"{i.path.name}: {i.dtype}" for i in infos)
        raise InputError(f"The orthos have different data types ({detail}); convert them to "
                         "one type first.")
    crss = {str(i.crs) if i.crs else "" for i in infos}
    if len(crss) > 1:
        raise InputError("The orthos are in different CRSs; rectify (or warp) them all into "
                         "the project CRS first.")


def mosaic_grid(infos: Sequence[OrthoInfo], gsd: Optional[float] = None
                ) -> Tuple[Affine, int, int, float]:
    """Transform, width, height and cell size of the mosaic grid (see the module notes)."""
    s = float(gsd) if gsd else min(i.gsd for i in infos)
    if not s > 0:
        raise InputError(f"The mosaic cell size must be positive, got {gsd}.")
    xmin = min(i.bounds[0] for i in infos)
    ymin = min(i.bounds[1] for i in infos)
    xmax = max(i.bounds[2] for i in infos)
    ymax = max(i.bounds[3] for i in infos)
    x0 = round(math.floor(xmin / s + 1e-9) * s, 6)
    y0 = round(math.ceil(ymax / s - 1e-9) * s, 6)
    width = max(math.ceil((xmax - x0) / s - 1e-9), 1)
    height = max(math.ceil((y0 - ymin) / s - 1e-9), 1)
    if width * height > 2 ** 36:
        raise InputError(f"The mosaic would have {width} × {height} cells; give a larger GSD.")
    return Affine(s, 0.0, x0, 0.0, -s, y0), width, height, s


def _aligned(info: OrthoInfo, transform: Affine) -> Optional[Tuple[int, int]]:
    """(row, col) of the ortho's first cell on a grid, if it lies on it without resampling."""
    t, s = info.transform, transform.a
    if t.e > 0 or abs(t.a - s) > 1e-9 * s or abs(-t.e - s) > 1e-9 * s:
        return None
    col, row = (t.c - transform.c) / s, (transform.f - t.f) / s
    if abs(col - round(col)) > 1e-6 or abs(row - round(row)) > 1e-6:
        return None
    return round(row), round(col)


def _window_of(info: OrthoInfo, transform: Affine, width: int, height: int
               ) -> Optional[Tuple[int, int, int, int]]:
    """Rows/cols ``(r0, r1, c0, c1)`` of a grid that the ortho's extent touches."""
    s = transform.a
    b = info.bounds
    c0 = max(math.floor((b[0] - transform.c) / s + 1e-9), 0)
    c1 = min(math.ceil((b[2] - transform.c) / s - 1e-9), width)
    r0 = max(math.floor((transform.f - b[3]) / s + 1e-9), 0)
    r1 = min(math.ceil((transform.f - b[1]) / s - 1e-9), height)
    if r1 <= r0 or c1 <= c0:
        return None
    return r0, r1, c0, c1


def _read_on_grid(src: Any, info: OrthoInfo, transform: Affine, r0: int, r1: int, c0: int,
                  c1: int, resampling: str) -> Tuple[Array, Array]:
    """Colour (b, h, w) float32 and validity (h, w) float32 in [0, 1] of one grid window.

    ``resampling`` is ``"full"`` (the mosaic grid: copied when aligned, else bilinear colour
    and nearest alpha) or ``"average"`` (block averages on a coarser grid).
    """

    h, w = r1 - r0, c1 - c0
    colour = np.full((len(info.colour), h, w), np.nan, np.float32)
    valid = np.zeros((h, w), np.float32)
    off = _aligned(info, transform) if resampling == "full" else None
    if off is not None:
        ar, ac = off
        a0, a1 = max(r0, ar), min(r1, ar + info.height)
        b0, b1 = max(c0, ac), min(c1, ac + info.width)
        if a1 <= a0 or b1 <= b0:
            return colour, valid
        win = Window(b0 - ac, a0 - ar, b1 - b0, a1 - a0)
        sl_ = (slice(a0 - r0, a1 - r0), slice(b0 - c0, b1 - c0))
        data = src.read(info.colour, window=win)
        colour[:, sl_[0], sl_[1]] = data
        if info.alpha is not None:
            valid[sl_] = src.read(info.alpha, window=win) > 0
        elif info.nodata is not None:
            valid[sl_] = np.all(data != info.nodata, axis=0)
        else:
            valid[sl_] = 1.0
        return colour, valid
    win_tr = transform * Affine.translation(c0, r0)
    avg = resampling == "average"
    for k, band in enumerate(info.colour):
        reproject(source=rasterio.band(src, band), destination=colour[k],
                  src_transform=info.transform, src_crs=info.crs, dst_transform=win_tr,
                  dst_crs=info.crs, src_nodata=info.nodata, dst_nodata=np.nan,
                  init_dest_nodata=True,
                  resampling=Resampling.average if avg else Resampling.bilinear)
    if info.alpha is not None:
        a = np.full((h, w), np.nan, np.float32)
        reproject(source=rasterio.band(src, info.alpha), destination=a,
                  src_transform=info.transform, src_crs=info.crs, dst_transform=win_tr,
                  dst_crs=info.crs, src_nodata=None, dst_nodata=np.nan, init_dest_nodata=True,
                  resampling=Resampling.average if avg else Resampling.nearest)
        a = np.nan_to_num(a, nan=0.0)
        valid = (a / 255.0 if avg else (a > 0)).astype(np.float32)
    else:
        valid = np.all(np.isfinite(colour), axis=0).astype(np.float32)
    valid[~np.all(np.isfinite(colour), axis=0)] = 0.0
    return colour, valid


def _coverage(info: OrthoInfo, transform: Affine, r0: int, r1: int, c0: int, c1: int,
              frac: Array) -> Array:
    """1 where a seam-grid cell is inside the image footprint (visible or occluded).

    From ``<stem>_visibility.tif`` (0 outside, 1 visible, 2 occluded; block minimum > 0);
    without it the valid fraction ``frac``.
    """

    vis = info.path.with_name(f"{info.path.stem}_visibility.tif")
    if not vis.is_file():
        return frac
    out = np.full((r1 - r0, c1 - c0), np.nan, np.float32)
    with rasterio.open(vis) as src:
        reproject(source=rasterio.band(src, 1), destination=out, src_transform=src.transform,
                  src_crs=src.crs or info.crs, dst_transform=transform * Affine.translation(c0, r0),
                  dst_crs=info.crs or src.crs, src_nodata=None, dst_nodata=np.nan,
                  init_dest_nodata=True, resampling=Resampling.min)
    return np.maximum(np.where(np.nan_to_num(out, nan=0.0) > 0, 1.0, 0.0), frac
                      ).astype(np.float32)


def _read_height(path: PathLike, transform: Affine, shape: Tuple[int, int], crs: Any,
                 how: str) -> Array:
    """A DSM/DTM block-aggregated (``max`` or ``average``) onto the seam grid, NaN = none."""

    out = np.full(shape, np.nan, np.float32)
    try:
        with rasterio.open(path) as src:
            reproject(source=rasterio.band(src, 1), destination=out,
                      src_transform=src.transform, src_crs=src.crs or crs,
                      dst_transform=transform, dst_crs=crs or src.crs,
                      src_nodata=src.nodata if src.nodata is not None else np.nan,
                      dst_nodata=np.nan, init_dest_nodata=True,
                      resampling=Resampling.max if how == "max" else Resampling.average)
    except rasterio.errors.RasterioIOError as exc:
        raise InputError(f"Cannot read the surface '{Path(path).name}': {exc}") from exc
    out[~np.isfinite(out)] = np.nan
    return out


def _dtype_range(dtype: str) -> Tuple[float, float]:
    dt = np.dtype(dtype)
    if np.issubdtype(dt, np.integer):
        info = np.iinfo(dt)
        return float(info.min), float(info.max)
    return -np.inf, np.inf


def _signed_distance(mask: Array) -> Array:
    """Distance (cells) to the region border: +½, +1½ … inside, −½, −1½ … outside."""
    inside = ndimage.distance_transform_edt(mask)
    outside = ndimage.distance_transform_edt(~mask)
    return np.where(mask, inside - 0.5, 0.5 - outside)


def _blend(values: List[Array], valid: List[Array], labels: Array, ids: List[int],
           feather: float) -> Tuple[Array, Array]:
    """Feathered mosaic of one tile (see the module notes); returns (bands, alpha mask)."""
    nb = values[0].shape[0]
    h, w = labels.shape
    present = [k for k, i in enumerate(ids) if (labels == i).any()]
    if feather < 1.0 or len(present) <= 1:
        out = np.zeros((nb, h, w), np.float32)
        for k in present:
            m = labels == ids[k]
            out[:, m] = values[k][:, m]
        return out, labels >= 0
    num = np.zeros((nb, h, w), np.float32)
    den = np.zeros((h, w), np.float32)
    for k, i in enumerate(ids):
        mask = labels == i
        d = _signed_distance(mask)
        wk = np.clip(0.5 + d / feather, 0.0, 1.0).astype(np.float32) * (valid[k] > 0)
        if not wk.any():
            continue
        num += wk * np.nan_to_num(values[k], nan=0.0)
        den += wk
    out = num / np.maximum(den, 1e-12)
    return out, labels >= 0


def _seam_sources(seamlines: str, project: Any) -> Optional[Path]:
    """The vector file of the operator's seamlines, or None for automatic seams."""
    text = (seamlines or "auto").strip()
    if text.lower() in ("auto", "nadir"):
        return None
    if text.lower() == "edits":
        if project is None:
            raise InputError("seamlines=edits needs the project (its edits.gpkg has the "
                             "'seamlines' layer); give 'project' or a seamline file.")
        return Path(project.edits_path)
    return Path(text)


@dataclass
class _SeamGrid:
    """The mosaic grid reduced by an integer factor (module notes, step 1)."""

    factor: int
    cell: float
    transform: Affine
    width: int
    height: int

    @classmethod
    def of(cls, transform: Affine, W: int, H: int, s: float, seam_cells: int) -> _SeamGrid:
        """At most ``seam_cells`` cells a side (never fewer than 16) over the mosaic grid."""
        f = max(1, math.ceil(max(W, H) / max(int(seam_cells), 16)))
        cs = f * s
        return cls(f, cs, Affine(cs, 0.0, transform.c, 0.0, -cs, transform.f),
                   math.ceil(W / f), math.ceil(H / f))

    @property
    def shape(self) -> Tuple[int, int]:
        return self.height, self.width


@dataclass
class _MosaicPlan:
    """The checked inputs, the mosaic grid and the options of one mosaic."""

    infos: List[OrthoInfo]
    names: List[str]
    crs: Any
    transform: Affine
    width: int
    height: int
    gsd: float
    output: Path
    ref_index: Optional[int]
    seamlines: str
    seam_file: Optional[Path]
    feather_m: float
    balance: str
    dsm: Optional[PathLike]
    dtm: Optional[PathLike]
    corridor: Optional[float]
    min_height: float
    tile: int
    scheduler: str = ""

    @property
    def feather_px(self) -> float:
        return self.feather_m / self.gsd


@dataclass
class _Radiometry:
    """Balancing of every image: gains, offsets and histogram look-up tables."""

    gains: List[Array]
    offsets: List[Array]
    luts: List[Any]

    def apply(self, k: int, colour: Array) -> Array:
        """Colour bands of image ``k`` balanced."""
        return bal.apply_balance(colour, self.gains[k], self.offsets[k], self.luts[k])

    def grey(self, k: int, bands: Array) -> Array:
        """Mean of the balanced bands of image ``k``."""
        return apply_mean(bands, self.gains[k], self.offsets[k], self.luts[k])


@dataclass
class _Partition:
    """Labels of the seam grid, the seams alone, their statistics and operator regions."""

    labels: Array
    partition: Array
    stats: Dict[str, Any]
    regions: List[Tuple[Any, int]]


def _plan_mosaic(inputs: Sequence[PathLike], output: PathLike, gsd: Optional[float],
                 options: Dict[str, Any], project: Any, fb: Feedback) -> _MosaicPlan:
    """Read and check the inputs, fix the grid and resolve the options' defaults."""
    if options["balance"] not in bal.BALANCE_MODES:
        raise InputError(f"Balancing '{options['balance']}' is not one of "
                         f"{', '.join(bal.BALANCE_MODES)}.")
    infos = [read_ortho_info(p) for p in inputs]
    check_inputs(infos)
    for i in infos:
        if not i.centre_from_tags:
            fb.warning(f"{i.path.name} has no PHOTODEM_CAMERA_X/Y tags; its nadir point is "
                       "taken as the raster centre.")
    names = [i.name for i in infos]
    transform, W, H, s = mosaic_grid(infos, gsd)
    reference = options["reference"]
    ref_index = None
    if reference:
        if reference not in names:
            raise InputError(f"The reference image '{reference}' is not one of the inputs "
                             f"({', '.join(names)}).")
        ref_index = names.index(reference)
    seamlines = options["seamlines"]
    feather = options["feather"]
    return _MosaicPlan(
        infos, names, infos[0].crs, transform, W, H, s, Path(output), ref_index, seamlines,
        _seam_sources(seamlines, project), 10.0 * s if feather is None else float(feather),
        options["balance"], options["dsm"], options["dtm"], options["corridor"],
        options["min_height"], options["tile"], check_scheduler(options.get("scheduler")))


def _sample_seam_grid(srcs: List[Any], plan: _MosaicPlan, grid: _SeamGrid, fb: Feedback
                      ) -> Tuple[List[bal.BalanceImage], List[Array], List[Array]]:
    """Every ortho block-averaged onto the seam grid: samples, valid fractions, coverage."""
    infos = plan.infos
    samples: List[bal.BalanceImage] = []
    fracs: List[Array] = []
    covers: List[Array] = []
    for k, (info, src) in enumerate(zip(infos, srcs)):
        fb.step(0, 15).progress(100.0 * k / len(infos))
        win = _window_of(info, grid.transform, grid.width, grid.height)
        if win is None:
            samples.append(bal.BalanceImage(0, 0, np.zeros((len(info.colour), 0, 0),
                                                           np.float32),
                                            np.zeros((0, 0), bool)))
            fracs.append(np.zeros((0, 0), np.float32))
            covers.append(np.zeros((0, 0), np.float32))
            continue
        r0, r1, c0, c1 = win
        colour, frac = _read_on_grid(src, info, grid.transform, r0, r1, c0, c1, "average")
        full = frac >= 1.0 - 1e-6
        colour[:, ~full] = np.nan
        samples.append(bal.BalanceImage(r0, c0, colour, full))
        fracs.append(frac)
        covers.append(_coverage(info, grid.transform, r0, r1, c0, c1, frac))
    return samples, fracs, covers


def _operator_partition(plan: _MosaicPlan, grid: _SeamGrid, labels: Array,
                        stats: Dict[str, Any]) -> Tuple[Array, List[Tuple[Any, int]]]:
    """Labels with the operator's regions burnt in, and the regions (area, image index)."""
    layers = ("seamlines",) if plan.seamlines.strip().lower() == "edits" else None
    assigned, cuts = sl.read_operator_seamlines(plan.seam_file, plan.crs, plan.names, layers)
    regions: List[Tuple[Any, int]] = []
    if cuts:
        regions.extend(sl.cut_regions(cuts, _bounds(plan.transform, plan.width, plan.height),
                                      labels, grid.transform, len(plan.infos)))
    regions.extend(assigned)  # assigned polygons win over cut regions
    op = sl.rasterize_regions(regions, grid.shape, grid.transform)
    labels = np.where(op >= 0, op, labels).astype(np.int32)
    stats.update(regions=len(regions), assigned=len(assigned), cut_lines=len(cuts))
    return labels, regions


def _partition(plan: _MosaicPlan, grid: _SeamGrid, seam_imgs: List[sl.SeamImage],
               fb: Feedback) -> _Partition:
    """Step 3 of the module notes: nadir partition, then seams or the operator's regions."""
    # the partition is built on the image footprints; occluded cells are filled later
    labels = sl.nadir_labels(grid.shape, grid.transform, seam_imgs, geometric=True)
    next_best = sl.nadir_labels(grid.shape, grid.transform, seam_imgs)
    hag = None
    margin = math.ceil(0.5 * plan.feather_m / grid.cell) + 1
    if plan.dsm is not None and plan.dtm is not None:
        hag = sl.object_height(
            _read_height(plan.dsm, grid.transform, grid.shape, plan.crs, "max"),
            _read_height(plan.dtm, grid.transform, grid.shape, plan.crs, "average"))
    stats: Dict[str, Any] = {"mode": "auto" if plan.seam_file is None else "operator"}
    regions: List[Tuple[Any, int]] = []
    if plan.seam_file is not None:
        labels, regions = _operator_partition(plan, grid, labels, stats)
    elif plan.seamlines.strip().lower() == "auto" and len(plan.infos) > 1:
        cor_m = sl.default_corridor([i.centre for i in plan.infos]) if plan.corridor is None \
            else float(plan.corridor)
        cor = max(round(cor_m / grid.cell), 2)
        labels, st = sl.route_seams(labels, seam_imgs, hag, corridor=cor,
                                    min_height=plan.min_height, margin=margin,
                                    feedback=fb.step(15, 30))
        stats.update(st, corridor_m=round(cor * grid.cell, 3))
    else:
        stats["mode"] = "nadir"
    partition = labels  # footprint polygons: the seams, without occlusion fills
    labels = sl.fill_invalid(labels, seam_imgs, next_best)
    return _Partition(labels, partition, stats, regions)


@dataclass
class _TileCounts:
    """Cells of the mosaic filled from another image than their partition's, and covered."""

    filled: int = 0
    covered: int = 0


def _mosaic_tile(srcs: List[Any], plan: _MosaicPlan, grid: _SeamGrid, part: _Partition,
                 radio: _Radiometry, bounds: Tuple[int, int, int, int], halo: int,
                 counts: _TileCounts) -> Tuple[Array, Array]:
    """Bands and alpha mask of the tile ``bounds`` = (r0, r1, c0, c1), halo cut off."""
    infos, transform, f = plan.infos, plan.transform, grid.factor
    r0, r1, c0, c1 = bounds
    R0, R1 = max(r0 - halo, 0), min(r1 + halo, plan.height)
    C0, C1 = max(c0 - halo, 0), min(c1 + halo, plan.width)
    lab = part.labels[np.arange(R0, R1)[:, None] // f, np.arange(C0, C1)[None, :] // f]
    if part.regions:
        op = sl.rasterize_regions(part.regions, (R1 - R0, C1 - C0),
                                  transform * Affine.translation(C0, R0))
        lab = np.where(op >= 0, op, lab)
    ids, vals, valids = [], [], []
    for k, (info, src) in enumerate(zip(infos, srcs)):
        wk = _window_of(info, transform, plan.width, plan.height)
        if wk is None or wk[1] <= R0 or wk[0] >= R1 or wk[3] <= C0 or wk[2] >= C1:
            continue
        colour, valid = _read_on_grid(src, info, transform, R0, R1, C0, C1, "full")
        if not valid.any():
            continue
        ids.append(k)
        vals.append(radio.apply(k, colour))
        valids.append(valid > 0)
    final = _final_labels(lab, ids, valids, infos, transform, R0, R1, C0, C1)
    inner = (slice(r0 - R0, r1 - R0), slice(c0 - C0, c1 - C0))
    counts.filled += int(((final != lab) & (final >= 0))[inner].sum())
    counts.covered += int((final >= 0)[inner].sum())
    if ids:
        data, alpha = _blend(vals, valids, final, ids, plan.feather_px)
    else:
        data = np.zeros((len(infos[0].colour), R1 - R0, C1 - C0), np.float32)
        alpha = np.zeros((R1 - R0, C1 - C0), bool)
    return data[:, inner[0], inner[1]], alpha[inner]


def _mosaic_tile_task(plan: _MosaicPlan, grid: _SeamGrid, part: _Partition, radio: _Radiometry,
                      bounds: Tuple[int, int, int, int],
                      srcs: Optional[List[Any]] = None) -> Tuple[Array, Array, int, int]:
    """One tile of step 4 as a task: bands and alpha in the output type, filled and covered
    cells. Opens the orthos itself unless ``srcs`` are given (a Dask worker has its own)."""
    infos, dtype = plan.infos, plan.infos[0].dtype
    halo = math.ceil(plan.feather_px / 2.0) + 1 if plan.feather_px >= 1.0 else 0
    counts = _TileCounts()
    with ExitStack() as stack:
        if srcs is None:
            srcs = [stack.enter_context(rasterio.open(i.path)) for i in infos]
        data, alpha = _mosaic_tile(srcs, plan, grid, part, radio, bounds, halo, counts)
    if np.issubdtype(np.dtype(dtype), np.integer):
        lo, hi = _dtype_range(dtype)
        data = np.clip(np.rint(data), lo, hi)
    data = np.where(alpha[None], data, 0).astype(dtype)
    a = np.where(alpha, _alpha_value(dtype), 0).astype(dtype)
    return data, a, counts.filled, counts.covered


def _write_mosaic(srcs: List[Any], plan: _MosaicPlan, grid: _SeamGrid, part: _Partition,
                  radio: _Radiometry, fb: Feedback) -> _TileCounts:
    """Step 4 of the module notes: the mosaic COG, tile by tile, with overviews and tags.

    With ``plan.scheduler`` the tiles are Dask tasks (:mod:`..raster.tiled_dask`): seams and
    balancing travel once to every worker, each task reads its tile plus halo from the orthos
    (memory ≈ (tile + 2·halo)² × images touching it × (bands + 1) × 4 bytes), and this
    process writes the tiles into the staged COG in their order — the same bytes as here.
    """
    infos, W, H = plan.infos, plan.width, plan.height
    nb = len(infos[0].colour)
    prof = gtiff_profile(W, H, nb + 1, infos[0].dtype, plan.crs, transform=plan.transform,
                         nodata=None)
    tile = max(int(plan.tile), 64)
    jobs = [(r, min(r + tile, H), c, min(c + tile, W))
            for r in range(0, H, tile) for c in range(0, W, tile)]
    counts = _TileCounts()
    if plan.scheduler:
        task: Any = _mosaic_tile_task
    else:  # here: the orthos are open already
        task = functools.partial(_mosaic_tile_task, srcs=srcs)
    # a Cloud-Optimised GeoTIFF: the mosaic is the block's deliverable
    with cog_output(plan.output, prof) as (tmp, scratch_prof), \
            open_image(tmp, "w", **scratch_prof) as dst:
        for i, (data, a, filled, covered) in map_tiles(task, jobs, (plan, grid, part, radio),
                                                        plan.scheduler, fb.step(30, 95)):
            r0, r1, c0, c1 = jobs[i]
            win = Window(c0, r0, c1 - c0, r1 - r0)
            dst.write(data, indexes=list(range(1, nb + 1)), window=win)
            dst.write(a, nb + 1, window=win)
            counts.filled += filled
            counts.covered += covered
        dst.colorinterp = [*infos[0].colorinterp, ColorInterp.alpha]
        dst.update_tags(PHOTODEM_MOSAIC="1", PHOTODEM_IMAGES=",".join(plan.names),
                        PHOTODEM_GSD=f"{plan.gsd:g}", PHOTODEM_SEAMLINES=part.stats["mode"],
                        PHOTODEM_BALANCE=plan.balance)
        fb.progress(95.0)
        factors = overview_factors(W, H)
        if factors:
            dst.build_overviews(factors, Resampling.average)
            dst.update_tags(ns="rio_overview", resampling="average")
    return counts


def _footprints(plan: _MosaicPlan, grid: _SeamGrid, part: _Partition) -> List[Any]:
    """One polygon per image (None without one): the seams, operator regions exactly."""
    n = len(plan.infos)
    polys = sl.partition_polygons(part.partition, grid.transform, n)
    if not part.regions:
        return polys
    # operator regions exactly, the rest from the seam grid
    op_union = unary_union([g for g, _ in part.regions])
    area = _box(plan.transform, plan.width, plan.height)
    polys = [None if p is None else p.difference(op_union) for p in polys]
    for k in range(n):
        mine = [g for g, kk in part.regions if kk == k]
        if mine:
            piece = unary_union(mine).intersection(area)
            polys[k] = piece if polys[k] is None else polys[k].union(piece)
    return [None if p is None or p.is_empty else p for p in polys]


def mosaic_orthos(
    inputs: Sequence[PathLike],
    output: PathLike,
    *,
    gsd: Optional[float] = None,
    seamlines: str = "auto",
    balance: str = "gain_offset",
    feather: Optional[float] = None,
    reference: Optional[str] = None,
    dsm: Optional[PathLike] = None,
    dtm: Optional[PathLike] = None,
    corridor: Optional[float] = None,
    min_height: float = 2.0,
    project: Any = None,
    tile: int = 1024,
    seam_cells: int = 1024,
    scheduler: str = "",
    feedback: Optional[Feedback] = None,
) -> Dict[str, Any]:
    """Mosaic orthos into one raster with seamlines and radiometric balancing.

    Parameters
    ----------
    inputs : sequence of paths
        Orthos (see the module notes).
    output : path
        Mosaic GeoTIFF; ``<stem>_seamlines.gpkg`` and ``<stem>_balance.json`` go beside it.
    gsd : float, optional
        Cell size (m); default the finest input.
    seamlines : str
        ``"auto"`` (nadir partition + least-cost seams), ``"nadir"`` (nadir partition only),
        ``"edits"`` (the project's ``edits.gpkg`` layer ``seamlines``) or a vector file
        (:func:`.seamlines.read_operator_seamlines`).
    balance : {"none", "gain_offset", "histogram"}
    feather : float, optional
        Width of the blend across seams (m); default 10 cells, 0 = hard seams.
    reference : str, optional
        Image kept radiometrically unchanged; default mean gain 1 and mean offset 0.
    dsm, dtm : path, optional
        Surface and terrain: with both, seams avoid cells with DSM − DTM ≥ ``min_height``.
    corridor : float, optional
        Half-width of the seam search corridor (m); default a quarter of the median distance
        between neighbouring projection centres.
    min_height : float
        Height above terrain (m) from which an object is avoided.
    project : Project, optional
        Needed for ``seamlines="edits"``.
    tile : int
        Side of the mosaic tiles (cells); bounds the memory.
    seam_cells : int
        Longest side of the seam grid (cells); bounds the memory of seams and balancing.
    scheduler : str
        ``""`` (tiles in this process), ``"local"`` or ``"tcp://host:port"``: the tiles as Dask
        tasks (:mod:`..raster.tiled_dask`); the mosaic is the same bytes either way.
    feedback : Feedback, optional

    Returns
    -------
    dict
        ``mosaic, seamlines, report`` (paths), ``gsd``, ``cells`` [w, h], ``images``,
        ``seam_factor``, ``seams`` (routing statistics), ``balance`` (before/after summary),
        ``filled_pct`` (% of mosaic cells filled from another than their partition image),
        ``seconds``.
    """
    fb = ensure_feedback(feedback)
    start = time.perf_counter()
    plan = _plan_mosaic(inputs, output, gsd, {
        "seamlines": seamlines, "balance": balance, "feather": feather, "reference": reference,
        "dsm": dsm, "dtm": dtm, "corridor": corridor, "min_height": min_height, "tile": tile,
        "scheduler": scheduler,
    }, project, fb)
    W, H, s, names = plan.width, plan.height, plan.gsd, plan.names
    paths = sibling_paths(plan.output)
    grid = _SeamGrid.of(plan.transform, W, H, s, seam_cells)
    fb.info(f"Mosaic of {len(plan.infos)} orthos: {W} × {H} cells of {s:g} m, seam grid "
            f"{grid.width} × {grid.height} (factor {grid.factor}).")
    with ExitStack() as stack:
        srcs = [stack.enter_context(rasterio.open(i.path)) for i in plan.infos]
        samples, fracs, covers = _sample_seam_grid(srcs, plan, grid, fb)
        gains, offsets, luts, report = bal.balance_images(samples, balance, plan.ref_index,
                                                          names)
        radio = _Radiometry(gains, offsets, luts)
        fb.info(f"Balancing ({balance}): mean overlap difference "
                f"{report['before']['mean_difference']} → {report['after']['mean_difference']} "
                f"DN, mean |difference| {report['before']['mean_abs_difference']} → "
                f"{report['after']['mean_abs_difference']} DN.")
        seam_imgs = [
            sl.SeamImage(names[k], plan.infos[k].centre, smp.row, smp.col, fracs[k],
                         np.nan_to_num(radio.grey(k, smp.bands), nan=0.0), covers[k])
            for k, smp in enumerate(samples)]
        part = _partition(plan, grid, seam_imgs, fb)
        del seam_imgs, samples, fracs, covers
        counts = _write_mosaic(srcs, plan, grid, part, radio, fb)

    # 5. footprints / seamlines and the report -------------------------------------------------
    polys = _footprints(plan, grid, part)
    lines = sl.seam_lines(polys)
    sl.write_seamlines(paths["seamlines"], polys, names, [i.path.name for i in plan.infos],
                       lines, plan.crs)
    report["seams"] = part.stats
    report["seam_factor"] = grid.factor
    report["filled_pct"] = round(100.0 * counts.filled / max(counts.covered, 1), 3)
    with atomic_output(paths["report"]) as tmp:
        tmp.write_text(json.dumps(report, indent=2), encoding="utf-8")
    return {"mosaic": str(plan.output), "seamlines": str(paths["seamlines"]),
            "report": str(paths["report"]), "gsd": s, "cells": [W, H], "images": names,
            "seam_factor": grid.factor, "seams": part.stats,
            "balance": {"before": report["before"], "after": report["after"]},
            "filled_pct": report["filled_pct"],
            "seconds": round(time.perf_counter() - start, 2)}


def apply_mean(bands: Array, gain: Array, offset: Array,
               lut: Optional[Tuple[Array, Array]]) -> Array:
    """Grey value: the mean of the balanced bands (b, h, w) → (h, w)."""
    if bands.size == 0:
        return np.zeros(bands.shape[1:], np.float32)
    return bal.apply_balance(bands, gain, offset, lut).mean(axis=0)


def _alpha_value(dtype: str) -> float:
    dt = np.dtype(dtype)
    return 255.0 if dt == np.uint8 or not np.issubdtype(dt, np.integer) else \
        float(min(np.iinfo(dt).max, 65535))


def _final_labels(lab: Array, ids: List[int], valids: List[Array], infos: Sequence[OrthoInfo],
                  transform: Affine, R0: int, R1: int, C0: int, C1: int) -> Array:
    """Partition label where that image is valid, else the valid image nearest in nadir."""
    h, w = lab.shape
    best = np.full((h, w), np.inf)
    final = np.full((h, w), -1, np.int32)
    x, y = sl.cell_centres(transform, np.arange(R0, R1), np.arange(C0, C1))
    for k, valid in zip(ids, valids):
        cx, cy = infos[k].centre
        d2 = (x - cx) ** 2 + (y - cy) ** 2
        score = np.where(valid, np.where(lab == k, -1.0, d2), np.inf)
        better = score < best
        best[better] = score[better]
        final[better] = k
    return final


def _bounds(transform: Affine, W: int, H: int) -> Tuple[float, float, float, float]:
    return (transform.c, transform.f + transform.e * H, transform.c + transform.a * W,
            transform.f)


def _box(transform: Affine, W: int, H: int) -> Any:
    return box(*_bounds(transform, W, H))


def sibling_paths(output: PathLike) -> Dict[str, Path]:
    """Files a mosaic writes: the mosaic, ``<stem>_seamlines.gpkg``, ``<stem>_balance.json``."""
    out = Path(output)
    return {"mosaic": out, "seamlines": out.with_name(f"{out.stem}_seamlines.gpkg"),
            "report": out.with_name(f"{out.stem}_balance.json")}


def mosaic_project(
    project: Any,
    dem: PathLike,
    output: PathLike,
    *,
    images: Optional[Sequence[str]] = None,
    gsd: Optional[float] = None,
    resampling: str = "bilinear",
    dsm: Optional[PathLike] = None,
    true_ortho: bool = False,
    dtm: Optional[PathLike] = None,
    feedback: Optional[Feedback] = None,
    **mosaic_options: Any,
) -> Dict[str, Any]:
    """Rectify every (or the given) project image onto ``dem`` and mosaic the orthos.

    The orthos go to a scratch folder beside ``output`` that is removed afterwards. With
    ``true_ortho`` the images are rectified on ``dsm`` with the occlusion test, and occluded
    cells are filled from other images. Seams avoid objects when a DSM and a DTM are known:
    ``dsm`` and ``dtm`` (default: ``dem`` when it is not the DSM).

    Returns
    -------
    dict
        :func:`mosaic_orthos`'s result plus ``orthos`` (per image: gsd, occluded_pct).
    """
    fb = ensure_feedback(feedback)
    proj = project if isinstance(project, Project) else Project.load(project)
    if true_ortho and not dsm:
        raise InputError("A true-ortho mosaic needs a DSM: set 'dsm' or switch true_ortho off.")
    names = list(images) if images else [im.name for im in proj.images]
    if not names:
        raise InputError("The project has no images to rectify.")
    surface = dsm if true_ortho else dem
    if dtm is None and dsm is not None and Path(dem).resolve() != Path(dsm).resolve():
        dtm = dem
    out = Path(output)
    out.parent.mkdir(parents=True, exist_ok=True)
    with scratch_folder(out.parent, f"{out.stem}.orthos") as scratch:
        orthos, info = [], {}
        for k, name in enumerate(names):
            step = fb.step(40.0 * k / len(names), 40.0 * (k + 1) / len(names))
            path = scratch / f"{Path(name).stem}.tif"
            res = orthorectify_image(proj, name, surface, path, gsd=gsd, resampling=resampling,
                                     dsm=dsm if true_ortho else None, feedback=step)
            orthos.append(path)
            info[name] = {"gsd": res.get("gsd"), "occluded_pct": res.get("occluded_pct")}
        result = mosaic_orthos(orthos, out, gsd=gsd, dsm=dsm, dtm=dtm, project=proj,
                               feedback=fb.step(40, 100), **mosaic_options)
    result["orthos"] = info
    return result


@dataclass
class MosaicOptions:
    """Seams, balancing and tiling of a mosaic (the keywords of :func:`mosaic_orthos`)."""

    seamlines: str = "auto"
    balance: str = "gain_offset"
    feather: Optional[float] = None
    reference: Optional[str] = None
    corridor: Optional[float] = None
    min_height: float = 2.0
    tile: int = 1024
    seam_cells: int = 1024
    scheduler: str = ""


@dataclass
class MosaicSources:
    """What a mosaic is made of: orthos, or the project's images rectified on a DEM.

    Attributes
    ----------
    inputs : sequence of paths, optional
        Orthos; they win over ``dem`` (with a warning when both are given).
    project : Project, optional
        Needed with ``dem`` and for ``seamlines="edits"``.
    dem : path, optional
        Surface to rectify every project image on (:func:`mosaic_project`).
    dsm, dtm : path, optional
        Surfaces of the seam cost (and of true orthos).
    gsd : float, optional
        Cell size (m).
    resampling : str
        Resampling of the rectification.
    true_ortho : bool
        Rectify on the DSM with the occlusion test.
    """

    inputs: Optional[Sequence[PathLike]] = None
    project: Any = None
    dem: Optional[PathLike] = None
    dsm: Optional[PathLike] = None
    dtm: Optional[PathLike] = None
    gsd: Optional[float] = None
    resampling: str = "bilinear"
    true_ortho: bool = False


def run_mosaic(output: PathLike, sources: MosaicSources, options: MosaicOptions,
               feedback: Optional[Feedback] = None) -> Dict[str, Any]:
    """``mosaic``: mosaic the given orthos, or rectify the project's images first.

    Returns
    -------
    dict
        :func:`mosaic_orthos`'s (or :func:`mosaic_project`'s) result.

    Raises
    ------
    InputError
        Neither orthos nor a DEM, or a DEM without the project.
    """
    fb = ensure_feedback(feedback)
    keywords = asdict(options)
    if sources.inputs:
        if sources.dem:
            fb.warning("Both orthos and a DEM are given; the orthos are mosaicked "
                       "and the DEM is not used.")
        return mosaic_orthos(sources.inputs, output, gsd=sources.gsd, dsm=sources.dsm,
                             dtm=sources.dtm, project=sources.project, feedback=fb, **keywords)
    if sources.dem:
        if sources.project is None:
            raise InputError("Rectifying needs the project: give 'project' with 'dem' "
                             "(or give the orthos as 'inputs').")
        return mosaic_project(sources.project, sources.dem, output, gsd=sources.gsd,
                              resampling=sources.resampling, dsm=sources.dsm,
                              true_ortho=sources.true_ortho, dtm=sources.dtm, feedback=fb,
                              **keywords)
    raise InputError("Nothing to mosaic: give the orthos ('inputs'), or a project and "
                     "a DEM ('dem') to rectify every image first.")

__all__ = [
    "SEAMLINE_MODES",
    "MosaicOptions",
    "MosaicSources",
    "OrthoInfo",
    "check_inputs",
    "mosaic_grid",
    "mosaic_orthos",
    "mosaic_project",
    "read_ortho_info",
    "run_mosaic",
    "sibling_paths",
]
