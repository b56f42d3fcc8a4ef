r"""Orthorectification of one image onto a DEM: indirect differential rectification in tiles.

For every output cell with centre :math:`(X, Y)` the height :math:`Z = h(X, Y)` comes from the
DEM (bilinear, :mod:`..raster.sample` conventions), the collinearity equations give the image
position (:mod:`..geometry.projection`, with distortion)

.. math::

   p = R^T (X - C), \qquad x = -c\,\frac{p_x}{p_z}, \quad y = -c\,\frac{p_y}{p_z}
   \;\rightarrow\; \text{distortion} \;\rightarrow\; (col, row),

and the image is resampled there (nearest, bilinear or cubic — OpenCV ``remap`` on the image
window the tile needs; OpenCV quantises the sub-pixel position to 1/32 px). A DTM gives a
classical ortho: objects above it lean away from the nadir point by the relief displacement

.. math:: \Delta R = h\,\frac{R}{H}

(h the height above the DTM, R the radial distance from the nadir, H the flying height above
ground). A *true* ortho rectifies onto the DSM and masks the cells the camera cannot see
(:mod:`.visibility`), so that roofs sit on their footprints and nothing ghosts onto the ground
behind them; a mosaic fills the masked cells from other images.

Products (the shared format of the ortho package):

* ``<output>.tif`` — tiled, deflate-compressed GeoTIFF with internal overviews: the image's
  colour bands (same dtype) plus an alpha band (255 valid, 0 outside the image, without DEM
  height or occluded); tags ``PHOTODEM_IMAGE``, ``PHOTODEM_CAMERA_X/Y/Z`` (projection centre),
  ``PHOTODEM_DEM``, ``PHOTODEM_DSM``, ``PHOTODEM_TRUE_ORTHO`` (0/1), ``PHOTODEM_GSD``;
* ``<stem>_visibility.tif`` — uint8: 0 outside the image (or no height), 1 visible,
  2 occluded.

The output grid is north-up with cell size ``gsd`` and its origin on a multiple of ``gsd``, so
orthos of one block at one GSD share a grid. Both files are written under temporary names and
renamed when complete; an error or a cancellation leaves nothing behind. Memory is bounded by
the tile size (plus the image window and DEM window a tile needs), not by the output size.
"""

from __future__ import annotations

import contextlib
import math
import os
import threading
import time
from collections import deque
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, Iterator, List, Optional, Sequence, Tuple, Union

import numpy as np
import rasterio
from affine import Affine
from numpy.typing import ArrayLike, NDArray
from rasterio.crs import CRS
from rasterio.enums import ColorInterp, Resampling
from rasterio.vrt import WarpedVRT
from rasterio.windows import Window, from_bounds
from scipy.ndimage import binary_opening

from ..crs_check import same_horizontal_crs
from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from ..geometry.camera import Camera
from ..geometry.orientation import ExteriorOrientation
from ..geometry.projection import border_rays
from ..input_errors import check_raster
from ..project.model import Project
from ..raster.io import atomic_output, cog_output, gtiff_profile, open_image, overview_factors
from ..raster.sample import bilinear, bilinear_grid
from .visibility import fill_from_below, march_margin, occluded

try:
    import cv2
except ImportError as exc:  # pragma: no cover - dependency is declared
    raise InputError("Orthorectification needs OpenCV: install 'opencv-python-headless' "
                     "(PyPI) or 'python3-opencv' (Debian).") from exc

PathLike = Union[str, Path]
Array = NDArray[np.float64]
Extent = Tuple[float, float, float, float]

RESAMPLING = ("nearest", "bilinear", "cubic")
#: visibility codes
OUTSIDE, VISIBLE, OCCLUDED = 0, 1, 2
#: cells of one output raster at most (a typo in the GSD must not fill the disk)
MAX_CELLS = 2_000_000_000
#: A true ortho fills the DSM's holes from below, each hole cell from valid cells up to this
#: far (m) along its row and column: the ground behind walls that the matcher could not see
#: gets a height, and the occlusion test finds it hidden.
TRUE_ORTHO_FILL_M = 20.0


# -- rasters in the project CRS ---------------------------------------------------------------
@contextlib.contextmanager
def open_surface(path: PathLike, crs: str, feedback: Optional[Feedback] = None,
                 what: str = "DEM") -> Iterator[Any]:
    """Open a DEM/DSM so that it reads in the project CRS.

    A raster in another CRS is reprojected on the fly (GDAL warped VRT, bilinear) with a
    warning; a compound CRS whose horizontal part is the project CRS (e.g. "UTM + EGM2008
    height") is read directly (:func:`same_horizontal_crs`); one without a CRS is taken to be
    in the project CRS (also with a warning).

    Raises
    ------
    InputError
        When the file cannot be read as a raster.
    """
    feedback = ensure_feedback(feedback)
    path = Path(path)
    if not path.is_file():
        raise InputError(f"The {what} '{path}' does not exist.")
    try:
        src = rasterio.open(path)
    except Exception as exc:  # rasterio.errors.RasterioIOError and friends
        raise InputError(f"Cannot read the {what} '{path}' as a raster: {exc}") from exc
    with src:
        target = CRS.from_user_input(crs) if crs else None
        if src.crs is None or target is None:
            if src.crs is None and target is not None:
                feedback.warning(f"The {what} '{path.name}' has no CRS; it is taken to be in "
                                 "the project CRS.")
            yield src
        elif src.crs == target or same_horizontal_crs(src.crs, target):
            # a compound CRS (e.g. "UTM + EGM2008 height") over the project's horizontal CRS
            # is the same grid: read it directly (no warp, no resampling of the heights)
            yield src
        else:
            feedback.warning(
                f"The {what} '{path.name}' is in {src.crs.to_string() or 'another CRS'}, not in "
                f"the project CRS {target.to_string()}; it is reprojected on the fly "
                "(bilinear). Reproject it once beforehand to save time.")
            with WarpedVRT(src, crs=target, resampling=Resampling.bilinear, dtype="float32",
                           src_nodata=src.nodata, nodata=float("nan")) as vrt:
                yield vrt


def read_surface(ds: Any, bounds: Extent, margin_cells: int = 2,
                 max_cells: Optional[int] = None) -> Optional[Tuple[Array, Affine]]:
    """Read the window of a DEM dataset covering ``bounds`` (plus a margin) as float64/NaN.

    ``max_cells`` reads a decimated version (nearest) when the window is larger, for
    statistics. Returns ``None`` when the window misses the raster.
    """
    win = from_bounds(*bounds, transform=ds.transform)
    col0 = math.floor(win.col_off) - margin_cells
    row0 = math.floor(win.row_off) - margin_cells
    col1 = math.ceil(win.col_off + win.width) + margin_cells
    row1 = math.ceil(win.row_off + win.height) + margin_cells
    col0, row0 = max(col0, 0), max(row0, 0)
    col1, row1 = min(col1, ds.width), min(row1, ds.height)
    if col1 - col0 < 2 or row1 - row0 < 2:
        return None
    window = Window(col0, row0, col1 - col0, row1 - row0)
    transform = ds.window_transform(window)
    shape = None
    if max_cells is not None and window.width * window.height > max_cells:
        f = math.sqrt(window.width * window.height / max_cells)
        shape = (max(int(window.height / f), 2), max(int(window.width / f), 2))
        transform = transform * Affine.scale(window.width / shape[1], window.height / shape[0])
    data = ds.read(1, window=window, out_shape=shape, masked=True)
    arr = data.astype(np.float64).filled(np.nan)
    return arr, transform


def surface_heights(array: Array, transform: Affine, xs: Array, ys: Array) -> Array:
    """Bilinear heights on the grid ``xs`` (columns) × ``ys`` (rows), shape (len(ys), len(xs)).

    :func:`..raster.sample.bilinear_grid` with NaN outside the hull of cell centres or next to
    nodata with non-zero weight. For a north-up DEM the interpolation runs between the rows
    first (two gathered rows per output row), then between the columns, a fraction of the
    cost of interpolating every cell on its own.
    """
    if transform.b != 0.0 or transform.d != 0.0:  # rotated DEM: the general sampler
        return bilinear(array, transform, xs[None, :], ys[:, None])
    inv = ~transform
    col = inv.a * xs + inv.c - 0.5
    row = inv.e * ys + inv.f - 0.5
    return bilinear_grid(array, col[None, :], row[:, None], edge="nan", nodata="weighted",
                         order="rows")


# -- geometry --------------------------------------------------------------------------------
def _image_mm(camera: Camera, eo: ExteriorOrientation, x: ArrayLike, y: ArrayLike,
              z: ArrayLike) -> Tuple[Array, Array]:
    r"""Undistorted image coordinates (mm) of world points: :math:`p = R^T (X - C)`,
    :math:`x = -c\,p_x/p_z`, :math:`y = -c\,p_y/p_z`; NaN behind the camera (:math:`p_z \ge 0`).

    Term by term on separate contiguous arrays (no BLAS: bit-identical in every environment).
    """
    R, C = eo.rotation, eo.position
    dx = np.asarray(x, dtype=float) - C[0]
    dy = np.asarray(y, dtype=float) - C[1]
    dz = np.asarray(z, dtype=float) - C[2]
    # in place where possible: these passes over the tile are memory-bound
    shape = np.broadcast_shapes(dx.shape, dy.shape, dz.shape)
    tmp = np.empty(shape)
    p = []
    for k in range(3):  # p_k = (R0k·dx + R1k·dy) + R2k·dz
        pk = np.empty(shape)
        np.add(R[0, k] * dx, R[1, k] * dy, out=pk)
        np.multiply(dz, R[2, k], out=tmp)
        pk += tmp
        p.append(pk)
    px, py, pz = p
    with np.errstate(divide="ignore", invalid="ignore"):
        np.divide(-camera.focal_length, pz, out=pz)  # pz → the scale −c/p_z
    pz[~(pz > 0)] = np.nan  # behind the camera (p_z ≥ 0 gives a scale ≤ 0) or NaN
    px *= pz
    py *= pz
    return px, py


def project_points(camera: Camera, eo: ExteriorOrientation, x: ArrayLike, y: ArrayLike,
                   z: ArrayLike) -> Tuple[Array, Array]:
    """Pixel (col, row) of world points (broadcastable arrays), exactly; NaN behind the camera.

    :func:`_image_mm`, then the camera's distortion and pixel transformation (the formula of
    :meth:`Camera.camera_to_pixel`).
    """
    u, v = _image_mm(camera, eo, x, y, z)
    if camera.has_distortion:
        u, v = camera.distort(u, v)
    return camera.image_to_pixel(u, v)


def project_grid(camera: Camera, eo: ExteriorOrientation, xs: Array, ys: Array, z: Array
                 ) -> Tuple[Array, Array]:
    """Pixel (col, row) of the grid points (xs[j], ys[i], z[i, j]) for every cell, exactly.

    X − C varies only along columns and Y − C only along rows (see :func:`project_points`).
    """
    return project_points(camera, eo, np.asarray(xs, float)[None, :],
                          np.asarray(ys, float)[:, None], z)


def footprint_bounds(camera: Camera, eo: ExteriorOrientation, z_low: float, z_high: float,
                     max_range: float = 20.0) -> Optional[Extent]:
    """Bounding box of the image border rays between the heights ``z_low`` and ``z_high``.

    Rays that do not reach a height (pointing above the horizon) are cut at ``max_range``
    times the flying height above ``z_low``. ``None`` if no border ray points downwards.
    """
    _, _, d = border_rays(camera, eo, 24, unit=False)  # 24 rays per edge, unscaled
    C = eo.position
    pts: List[Array] = []
    for z in (z_low, z_high):
        with np.errstate(divide="ignore", invalid="ignore"):
            lam = (z - C[2]) / d[:, 2]
        far = max_range * max(C[2] - z_low, 1.0) / np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-12)
        lam = np.where((lam > 0) & np.isfinite(lam), np.minimum(lam, far), far)
        if not (d[:, 2] < 0).any():
            return None
        pts.append(C[None, :2] + lam[:, None] * d[:, :2])
    xy = np.concatenate(pts)
    return (float(xy[:, 0].min()), float(xy[:, 1].min()),
            float(xy[:, 0].max()), float(xy[:, 1].max()))


def _intersect(a: Extent, b: Extent) -> Optional[Extent]:
    out = (max(a[0], b[0]), max(a[1], b[1]), min(a[2], b[2]), min(a[3], b[3]))
    return out if out[0] < out[2] and out[1] < out[3] else None


def _bounds_of(ds: Any) -> Extent:
    b = ds.bounds
    return (float(b.left), float(b.bottom), float(b.right), float(b.top))


def _height_stats(ds: Any, bounds: Extent) -> Optional[Tuple[float, float, float]]:
    """(min, mean, max) of the valid heights in ``bounds`` (decimated read), or None."""
    got = read_surface(ds, bounds, margin_cells=1, max_cells=1_000_000)
    if got is None:
        return None
    a = got[0]
    a = a[np.isfinite(a)]
    if a.size == 0:
        return None
    return float(a.min()), float(a.mean()), float(a.max())


def dem_footprint_box(camera: Camera, eo: ExteriorOrientation, dem: Any, name: str = "",
                      dem_name: str = "DEM") -> Tuple[Extent, float, float]:
    """The ortho's extent on an open DEM: the bounding box (clipped to the DEM) of the image
    footprint over the DEM's whole height range under it, the mean and the highest DEM
    height in it.

    The border rays are cut with the lowest and the highest DEM height under the footprint,
    found by two refinements starting from the whole DEM's mean height, so that the box holds
    every cell the image can see. This differs from the footprint *polygon* of
    :func:`..geometry.stereo.image_footprint` (the outline on one plane at the mean terrain
    height, for overlaps and B/H), which would cut off the image's view of low ground.

    Raises
    ------
    InputError
        When the footprint misses the DEM (or the DEM holds no height under it).
    """
    dem_bounds = _bounds_of(dem)
    miss = InputError(
        f"The footprint of image '{name}' misses the {dem_name} ({dem_bounds[0]:.1f}, "
        f"{dem_bounds[1]:.1f}, {dem_bounds[2]:.1f}, {dem_bounds[3]:.1f}) or lies on nodata "
        "only; use a DEM that covers the image (same CRS as the project).")
    stats = _height_stats(dem, dem_bounds)
    if stats is None:
        raise miss
    z_low = z_high = stats[1]
    box: Optional[Extent] = None
    for _ in range(3):
        fp = footprint_bounds(camera, eo, z_low, z_high)
        if fp is None:
            raise miss
        box = _intersect(fp, dem_bounds)
        if box is None:
            raise miss
        got = _height_stats(dem, box)
        if got is None:
            raise miss
        if got[0] >= z_low and got[2] <= z_high:
            stats = got
            break
        z_low, z_high = min(z_low, got[0]), max(z_high, got[2])
        stats = got
    assert box is not None and stats is not None
    return box, stats[1], stats[2]


def default_gsd(camera: Camera, eo: ExteriorOrientation, mean_height: float) -> float:
    """The image's GSD at the mean DEM height, H·pixel/c, rounded to two significant digits."""
    flying = float(eo.position[2]) - mean_height
    if not flying > 0:
        raise InputError("The projection centre lies below the DEM's mean height; check the "
                         "image orientation and the DEM (heights in metres, same datum).")
    gsd = float(camera.gsd(flying))
    digits = 1 - math.floor(math.log10(gsd))
    return round(gsd, digits)


def _grid(extent: Extent, gsd: float) -> Tuple[Affine, int, int]:
    """North-up grid with its origin on a multiple of ``gsd`` covering ``extent``."""
    # rounded to µm so that equal GSDs give identical origins (no 0.99999… artefacts)
    xmin = round(math.floor(extent[0] / gsd + 1e-9) * gsd, 6)
    ymax = round(math.ceil(extent[3] / gsd - 1e-9) * gsd, 6)
    width = max(math.ceil((extent[2] - xmin) / gsd - 1e-9), 1)
    height = max(math.ceil((ymax - extent[1]) / gsd - 1e-9), 1)
    return Affine(gsd, 0.0, xmin, 0.0, -gsd, ymax), width, height


# -- image access ----------------------------------------------------------------------------
_REMAP_DTYPES = ("uint8", "uint16", "int16", "float32", "float64")


class _ImageSource:
    """Reads windows of the colour bands (and the validity mask) of an image file."""

    def __init__(self, ds: Any) -> None:
        self.ds = ds
        alpha = [i + 1 for i, c in enumerate(ds.colorinterp) if c == ColorInterp.alpha]
        self.bands = [i for i in range(1, ds.count + 1) if i not in alpha] or [1]
        self.dtype = np.dtype(ds.dtypes[self.bands[0] - 1])
        self.masked = bool(alpha) or ds.nodata is not None
        self.colorinterp = [ds.colorinterp[i - 1] for i in self.bands]

    def read(self, col0: int, row0: int, col1: int, row1: int
             ) -> Tuple[NDArray[Any], Optional[NDArray[np.uint8]]]:
        """Bands (rows, cols, bands) and the mask (255 valid) of a window, or no mask."""
        win = Window(col0, row0, col1 - col0, row1 - row0)
        data = self.ds.read(self.bands, window=win)
        mask = self.ds.read_masks(self.bands[0], window=win) if self.masked else None
        return np.ascontiguousarray(np.moveaxis(data, 0, -1)), mask


def _remap(src: NDArray[Any], mapx: NDArray[np.float32], mapy: NDArray[np.float32],
           interpolation: int) -> NDArray[Any]:
    """cv2.remap for any band count and dtype; returns (rows, cols, bands)."""
    dtype = src.dtype
    work = src if dtype.name in _REMAP_DTYPES else src.astype(np.float64)
    outs = []
    for b0 in range(0, work.shape[2], 4):  # OpenCV remaps at most 4 channels at once
        part = np.ascontiguousarray(work[:, :, b0:b0 + 4])
        res = cv2.remap(part, mapx, mapy, interpolation, borderMode=cv2.BORDER_REPLICATE)
        outs.append(res.reshape(mapx.shape + (part.shape[2],)))
    out = np.concatenate(outs, axis=2) if len(outs) > 1 else outs[0]
    if out.dtype != dtype:
        if np.issubdtype(dtype, np.integer):
            info = np.iinfo(dtype)
            out = np.clip(np.rint(out), info.min, info.max)
        out = out.astype(dtype)
    return out


# -- the product -----------------------------------------------------------------------------
def visibility_path(ortho: PathLike) -> Path:
    """``<stem>_visibility.tif`` beside an ortho."""
    p = Path(ortho)
    return p.with_name(f"{p.stem}_visibility.tif")


def _profile(width: int, height: int, count: int, dtype: str, transform: Affine, crs: str
             ) -> Dict[str, Any]:
    # horizontal differencing + fast deflate: smaller and faster to write than plain deflate;
    # blocks are compressed on all cores while the next tile is computed
    return gtiff_profile(width, height, count, dtype, crs, transform=transform,
                         nodata=None, zlevel=1, num_threads="all_cpus",
                         predictor=3 if np.issubdtype(np.dtype(dtype), np.floating) else 2)


class _SerialReads:
    """A rasterio dataset whose reads are serialised: tiles are computed in threads, and one
    GDAL handle must not be read from two threads at once."""

    def __init__(self, ds: Any) -> None:
        self._ds = ds
        self._lock = threading.Lock()

    def __getattr__(self, name: str) -> Any:
        return getattr(self._ds, name)

    def read(self, *args: Any, **kwargs: Any) -> Any:
        with self._lock:
            return self._ds.read(*args, **kwargs)

    def read_masks(self, *args: Any, **kwargs: Any) -> Any:
        with self._lock:
            return self._ds.read_masks(*args, **kwargs)


def _tiles(width: int, height: int, tile: int, workers: int
           ) -> List[Tuple[int, int, int, int]]:
    """(first row, first col, rows, cols) of the processing tiles: squares of at most ``tile``
    cells, small enough that every worker gets about two tiles, in multiples of the 256-cell
    GeoTIFF block (whole blocks are compressed as soon as they are complete)."""
    share = math.sqrt(width * height / (2.0 * workers))
    tile = min(tile, max(256, 256 * math.ceil(share / 256)))
    return [(r0, c0, min(tile, height - r0), min(tile, width - c0))
            for r0 in range(0, height, tile) for c0 in range(0, width, tile)]


def orthorectify_image(
    project: Union[Project, PathLike],
    image: str,
    dem: PathLike,
    output: PathLike,
    *,
    gsd: Optional[float] = None,
    resampling: str = "bilinear",
    dsm: Optional[PathLike] = None,
    extent: Optional[Sequence[float]] = None,
    tile: int = 1024,
    feedback: Optional[Feedback] = None,
) -> Dict[str, Any]:
    """Orthorectify one image of a project onto a DEM (true ortho with a DSM).

    Parameters
    ----------
    project : Project or path
        The project (or its folder / project.toml).
    image : str
        Image name in the project.
    dem : path
        Heights to rectify onto: a DTM (classical ortho) or the DSM (true ortho). Any CRS;
        another one than the project's is reprojected on the fly with a warning.
    output : path
        The ortho GeoTIFF; ``<stem>_visibility.tif`` is written beside it.
    gsd : float, optional
        Cell size (m). Default: the image's GSD at the DEM's mean height under the footprint,
        rounded to two significant digits.
    resampling : {"nearest", "bilinear", "cubic"}
    dsm : path, optional
        True ortho: cells whose ray to the projection centre is blocked by this DSM are
        occluded (alpha 0, visibility 2). The DEM should then be the DSM too.
    extent : (xmin, ymin, xmax, ymax), optional
        Output extent in the project CRS; default the image footprint on the DEM.
    tile : int
        Tile size (cells) of the processing; bounds the memory.
    feedback : Feedback, optional
        Progress per tile, cancellation.

    Returns
    -------
    dict
        ``ortho``, ``visibility`` (paths), ``gsd`` (m), ``occluded_pct`` (% of the cells
        inside the image), ``valid_pct`` (% of all cells with alpha 255), ``cells``
        ([width, height]), ``extent``, ``seconds``.

    Raises
    ------
    InputError
        Unknown image, unknown resampling, footprint missing the DEM, unreadable inputs.
    Cancelled
        When cancelled; nothing is written.
    """
    start = time.perf_counter()
    feedback = ensure_feedback(feedback)
    tile = _checked_tile(resampling, tile)
    if not isinstance(project, Project):
        project = Project.load(project)
    rec = project.image(image)
    camera = project.camera_of(rec)
    image_path = _checked_image(project, rec)
    output = Path(output)
    vis_path = visibility_path(output)
    with contextlib.ExitStack() as stack:
        dem_ds, dsm_ds = _open_surfaces(stack, project.crs, dem, dsm, feedback)
        source = _open_source(stack, image_path, rec.name, camera)
        box, gsd = _extent_and_gsd(camera, rec.eo, dem_ds, rec.name, extent, gsd)
        transform, width, height = _grid(box, gsd)
        if width * height > MAX_CELLS:
            raise InputError(f"The ortho would have {width}×{height} cells at {gsd:g} m; choose "
                             "a larger GSD or a smaller extent.")
        zmax_dsm = None
        if dsm_ds is not None:
            got = _height_stats(dsm_ds, box)  # decimated: refined per tile
            zmax_dsm = got[2] if got is not None else None
        feedback.info(f"Orthorectifying '{rec.name}' onto '{Path(dem).name}': {width}×{height} "
                      f"cells of {gsd:g} m, {resampling}"
                      + (f", occlusion test against '{Path(dsm).name}'." if dsm else "."))
        job = _OrthoJob(_INTERPOLATION[resampling], source, camera, rec.eo, dem_ds, dsm_ds,
                        zmax_dsm, transform, width, height)
        dst, vdst = _open_outputs(stack, output, vis_path, job, project.crs)
        counts = _write_tiles(job, dst, vdst, tile, feedback)
        feedback.progress(96.0)
        _finish(dst, vdst, source, rec.name, rec.eo, dem, dsm, width, height, gsd)
        if counts[VISIBLE] == 0:
            raise InputError(f"No cell of the ortho of image '{rec.name}' is visible (the "
                             "footprint misses the DEM or the extent); nothing was written.")
    return _summary(job, counts, gsd, output, vis_path, rec.name, bool(dsm),
                    time.perf_counter() - start, feedback)


def _checked_tile(resampling: str, tile: int) -> int:
    """The tile size as int, after checking it and the resampling name."""
    if resampling not in RESAMPLING:
        raise InputError(f"Unknown resampling '{resampling}'; use one of "
                         f"{', '.join(RESAMPLING)}.")
    if int(tile) < 16:
        raise InputError("The tile size must be at least 16 cells.")
    return int(tile)


def _checked_image(project: Project, rec: Any) -> Path:
    """The image file of a project image, checked to exist and to read as a raster."""
    image_path = project.image_path(rec)
    if not image_path.is_file():
        raise InputError(f"Image file '{image_path}' of image '{rec.name}' does not exist; fix "
                         "its path in project.toml.")
    check_raster(image_path, "image")  # a truncated image fails here, before any work
    return image_path


def _open_surfaces(stack: contextlib.ExitStack, crs: str, dem: PathLike,
                   dsm: Optional[PathLike], feedback: Feedback) -> Tuple[Any, Any]:
    """The DEM and the DSM (or None) opened in the project CRS for reading from threads."""
    dem_ds = _SerialReads(stack.enter_context(open_surface(dem, crs, feedback, "DEM")))
    dsm_ds = None
    if dsm is not None:
        if Path(dsm).resolve() != Path(dem).resolve():
            feedback.warning("The true ortho rectifies onto the DEM and tests visibility "
                             "against a different DSM: cells below roofs and trees of the "
                             "DSM count as occluded. Use the DSM as DEM for a true ortho.")
        dsm_ds = _SerialReads(stack.enter_context(open_surface(dsm, crs, feedback, "DSM")))
    return dem_ds, dsm_ds


def _open_source(stack: contextlib.ExitStack, image_path: Path, name: str, camera: Camera
                 ) -> _ImageSource:
    """The image opened for windowed reads from threads; its size must match the camera."""
    src = stack.enter_context(open_image(image_path))
    if (src.width, src.height) != (camera.width, camera.height):
        raise InputError(f"Image '{name}' is {src.width}×{src.height} px but camera "
                         f"'{camera.name}' is {camera.width}×{camera.height} px.")
    return _ImageSource(_SerialReads(src))


def _extent_and_gsd(camera: Camera, eo: ExteriorOrientation, dem_ds: Any, name: str,
                    extent: Optional[Sequence[float]], gsd: Optional[float]
                    ) -> Tuple[Extent, float]:
    """The output extent (given, or the footprint box on the DEM) and the cell size (given,
    or :func:`default_gsd` at the DEM's mean height under the footprint)."""
    box, mean_z, _ = dem_footprint_box(camera, eo, dem_ds, name, "DEM")
    if extent is not None:
        ext = tuple(float(v) for v in extent)
        if not (ext[0] < ext[2] and ext[1] < ext[3]):
            raise InputError(f"The extent {ext} is empty; give xmin,ymin,xmax,ymax.")
        if _intersect(ext, _bounds_of(dem_ds)) is None:  # type: ignore[arg-type]
            raise InputError(f"The extent {ext} does not overlap the DEM; use an extent "
                             "inside the DEM.")
        box = ext  # type: ignore[assignment]
    if gsd is None:
        gsd = default_gsd(camera, eo, mean_z)
    gsd = float(gsd)
    if not gsd > 0:
        raise InputError(f"The GSD must be positive, got {gsd}.")
    return box, gsd


#: OpenCV interpolation of each resampling name
_INTERPOLATION = {"nearest": cv2.INTER_NEAREST, "bilinear": cv2.INTER_LINEAR,
                  "cubic": cv2.INTER_CUBIC}


@dataclass
class _OrthoJob:
    """What every tile of one ortho needs: the interpolation, the image and its orientation,
    the opened surfaces (DSM and its highest height for true orthos, else None) and the
    output grid."""

    interpolation: int
    source: _ImageSource
    camera: Camera
    eo: ExteriorOrientation
    dem_ds: Any
    dsm_ds: Any
    zmax_dsm: Optional[float]
    transform: Affine
    width: int
    height: int

    def rectify(self, cells: Tuple[int, int, int, int]
                ) -> Tuple[NDArray[Any], NDArray[np.uint8]]:
        """One tile (:func:`_rectify_tile`), alpha 255 on valid cells."""
        return _rectify_tile(self.interpolation, self.source, self.camera, self.eo,
                             self.dem_ds, self.dsm_ds, self.zmax_dsm, self.transform, cells, 255)


def _open_outputs(stack: contextlib.ExitStack, output: Path, vis_path: Path, job: _OrthoJob,
                  crs: str) -> Tuple[Any, Any]:
    """The ortho (a Cloud-Optimised GeoTIFF, through an uncompressed scratch file, see
    :func:`..raster.io.cog_output`) and the visibility raster, open for writing under
    temporary names."""
    n_bands = len(job.source.bands)
    dtype = job.source.dtype.name
    profile = _profile(job.width, job.height, n_bands + 1, dtype, job.transform, crs)
    vprofile = _profile(job.width, job.height, 1, "uint8", job.transform, crs)
    ortho_tmp, profile = stack.enter_context(cog_output(output, profile))
    vis_tmp = stack.enter_context(atomic_output(vis_path))
    dst = stack.enter_context(open_image(ortho_tmp, "w", **profile))
    vdst = stack.enter_context(open_image(vis_tmp, "w", **vprofile))
    return dst, vdst


def _write_tiles(job: _OrthoJob, dst: Any, vdst: Any, tile: int, feedback: Feedback
                 ) -> NDArray[np.int64]:
    """Rectify all tiles and write them; the counts of the visibility codes.

    Tiles are computed on all cores (numpy and OpenCV release the GIL) and written here in
    order; at most one tile per worker waits, which bounds the memory.
    """
    workers = os.cpu_count() or 1
    tiles = _tiles(job.width, job.height, tile, workers)
    counts = np.zeros(3, dtype=np.int64)
    workers = max(1, min(workers, len(tiles)))
    pool = ThreadPoolExecutor(workers)
    try:
        todo = iter(tiles)
        running: deque[Tuple[Tuple[int, int, int, int], Future[Any]]] = deque()
        for cells in todo:
            running.append((cells, pool.submit(job.rectify, cells)))
            if len(running) > workers:
                break
        for k in range(len(tiles)):
            feedback.progress(95.0 * k / len(tiles))
            (r0, c0, th, tw), future = running.popleft()
            bands, vis = future.result()
            nxt = next(todo, None)
            if nxt is not None:
                running.append((nxt, pool.submit(job.rectify, nxt)))
            win = Window(c0, r0, tw, th)
            dst.write(bands, window=win)
            vdst.write(vis[None], window=win)
            counts += np.bincount(vis.ravel(), minlength=3)[:3]
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
    return counts


def _summary(job: _OrthoJob, counts: NDArray[np.int64], gsd: float, output: Path,
             vis_path: Path, name: str, true_ortho: bool, seconds: float, feedback: Feedback
             ) -> Dict[str, Any]:
    """The result of :func:`orthorectify_image`, reported to the feedback too."""
    width, height, transform = job.width, job.height, job.transform
    inside = int(counts[VISIBLE] + counts[OCCLUDED])
    occ_pct = 100.0 * float(counts[OCCLUDED]) / inside if inside else 0.0
    feedback.info(f"Ortho of '{name}': {width * height / 1e6:.2f} Mcells in {seconds:.1f} s "
                  f"({width * height / 1e6 / max(seconds, 1e-9):.2f} Mcells/s), "
                  f"{100.0 * counts[VISIBLE] / (width * height):.1f} % valid"
                  + (f", {occ_pct:.2f} % occluded." if true_ortho else "."))
    return {
        "ortho": str(output),
        "visibility": str(vis_path),
        "gsd": gsd,
        "occluded_pct": round(occ_pct, 4),
        "valid_pct": round(100.0 * float(counts[VISIBLE]) / (width * height), 4),
        "cells": [width, height],
        "extent": [transform.c, transform.f - height * gsd, transform.c + width * gsd,
                   transform.f],
        "seconds": round(seconds, 3),
    }


def _rectify_tile(interpolation: int, source: _ImageSource, camera: Camera,
                  eo: ExteriorOrientation, dem_ds: Any, dsm_ds: Any, zmax_dsm: Optional[float],
                  transform: Affine, cells: Tuple[int, int, int, int], alpha_value: int
                  ) -> Tuple[NDArray[Any], NDArray[np.uint8]]:
    """One tile (``cells`` = first row, first col, rows, cols of the output grid): heights,
    image positions, resampled bands + alpha, visibility codes.

    Heights and image positions are computed on the tile plus a ring of one cell, so that the
    occlusion clean-up (a 2 × 2 opening) sees the same neighbours as in one piece; cell
    centres come from their global indices, so every cell gets the same values whatever the
    tiling.
    """
    r0, c0, th, tw = cells
    gsd = transform.a
    xe = transform.c + (np.arange(c0 - 1, c0 + tw + 1) + 0.5) * gsd
    ye = transform.f - (np.arange(r0 - 1, r0 + th + 1) + 0.5) * gsd
    bounds = (float(xe[0] - gsd), float(ye[-1] - gsd), float(xe[-1] + gsd), float(ye[0] + gsd))
    z = _tile_heights(dem_ds, bounds, xe, ye, dsm_ds is not None)
    col, row = project_grid(camera, eo, xe, ye, z)
    valid = (np.isfinite(z) & (col >= -0.5) & (col <= camera.width - 0.5)
             & (row >= -0.5) & (row <= camera.height - 0.5))
    n_bands = len(source.bands)
    out = np.zeros((n_bands + 1, th, tw), dtype=source.dtype)
    vis = np.zeros((th, tw), dtype=np.uint8)
    inner = (slice(1, th + 1), slice(1, tw + 1))
    if not valid[inner].any():
        return out, vis
    if dsm_ds is not None:
        occ = occlusion_flags(dsm_ds, zmax_dsm, eo.position, xe, ye, z, valid)
        vis[valid[inner]] = np.where(occ[inner][valid[inner]], OCCLUDED, VISIBLE)
    else:
        vis[valid[inner]] = VISIBLE
    col, row, valid = col[inner], row[inner], valid[inner]
    # the image window this tile needs (a margin of 2 px for the cubic kernel)
    cv, rv = col[valid], row[valid]
    wc0 = max(math.floor(cv.min()) - 2, 0)
    wr0 = max(math.floor(rv.min()) - 2, 0)
    wc1 = min(math.ceil(cv.max()) + 3, camera.width)
    wr1 = min(math.ceil(rv.max()) + 3, camera.height)
    data, mask = source.read(wc0, wr0, wc1, wr1)
    # float32 maps (OpenCV's fast path); cells outside the image are cleared below
    mapx = (col - wc0).astype(np.float32)
    mapy = (row - wr0).astype(np.float32)
    mapx[~valid] = -1.0
    mapy[~valid] = -1.0
    res = _remap(data, mapx, mapy, interpolation)
    if mask is not None:  # cells on masked image pixels (nearest) are outside the image
        m = cv2.remap(mask, mapx, mapy, cv2.INTER_NEAREST, borderMode=cv2.BORDER_REPLICATE)
        vis[(m == 0) & valid] = OUTSIDE
    bad = vis != VISIBLE
    res[bad] = 0
    out[:n_bands] = np.moveaxis(res, -1, 0)
    out[n_bands][~bad] = alpha_value
    return out, vis


def _tile_heights(dem_ds: Any, bounds: Extent, xe: Array, ye: Array, true_ortho: bool
                  ) -> Array:
    """Heights of the cell centres ``xe`` × ``ye`` (bilinear on the DEM). In a true ortho the
    DSM's holes are filled from below first (:func:`.visibility.fill_from_below`, looking up to
    :data:`TRUE_ORTHO_FILL_M` along rows and columns), from a window that reaches that far
    beyond the tile, so that every tiling gives the same heights."""
    size = 0
    if true_ortho:
        res = min(abs(dem_ds.transform.a), abs(dem_ds.transform.e))
        size = math.floor(TRUE_ORTHO_FILL_M / res)
    got = read_surface(dem_ds, bounds, margin_cells=2 + size)
    if got is None:
        return np.full((len(ye), len(xe)), np.nan)
    arr = got[0]
    if size and not np.isfinite(arr).all():
        arr = fill_from_below(arr, size)
    return surface_heights(arr, got[1], xe, ye)


def occlusion_flags(dsm_ds: Any, zmax: Optional[float], centre: ArrayLike, xs: Array,
                    ys: Array, z: Array, valid: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """Occlusion flags of a tile (cell centres ``xs`` × ``ys`` with heights ``z``) seen from the
    projection centre: the DSM window is read with the march margin, re-read larger when the
    window turns out to hold higher objects than estimated; thin lines removed (see below).
    :mod:`.occlusion_check` computes the truth visibility with it."""
    C = np.asarray(centre, dtype=float).reshape(3)
    gx, gy = np.meshgrid(xs, ys)
    r = np.hypot(gx - C[0], gy - C[1])
    zz = np.where(valid, z, np.nan)
    z_est = (float(np.nanmax(zz)) if zmax is None else max(zmax, float(np.nanmax(zz)))) + 1.0
    got = None
    for _ in range(4):
        margin = march_margin(zz, r, float(C[2]), z_est)
        bounds = (float(xs[0] - margin), float(ys[-1] - margin), float(xs[-1] + margin),
                  float(ys[0] + margin))
        got = read_surface(dsm_ds, bounds, margin_cells=3)
        if got is None:
            return np.zeros(z.shape, dtype=bool)
        window_max = float(np.nanmax(got[0])) if np.isfinite(got[0]).any() else z_est
        if window_max <= z_est:
            break
        z_est = window_max + 1.0
    assert got is not None
    occ = occluded(gx, gy, zz, C, got[0], got[1])
    # A wall seen edge-on (parallel to the rays) is a staircase of mixed cells in the DSM:
    # rays from cells on it graze the neighbouring steps and give occlusion lines one cell
    # wide. Real occlusions (behind buildings and trees) are wider; a 2 × 2 opening keeps them.
    return binary_opening(occ, structure=np.ones((2, 2), dtype=bool))


def _finish(dst: Any, vdst: Any, source: _ImageSource, name: str, eo: ExteriorOrientation,
            dem: PathLike, dsm: Optional[PathLike], width: int, height: int, gsd: float) -> None:
    """Colour interpretation, tags and overviews of the two rasters."""
    dst.colorinterp = [*source.colorinterp, ColorInterp.alpha]
    C = eo.position
    dst.update_tags(PHOTODEM_IMAGE=name, PHOTODEM_CAMERA_X=f"{C[0]:.4f}",
                    PHOTODEM_CAMERA_Y=f"{C[1]:.4f}", PHOTODEM_CAMERA_Z=f"{C[2]:.4f}",
                    PHOTODEM_DEM=str(Path(dem).resolve()),
                    PHOTODEM_DSM=str(Path(dsm).resolve()) if dsm else "",
                    PHOTODEM_TRUE_ORTHO="1" if dsm else "0", PHOTODEM_GSD=f"{gsd:g}")
    vdst.update_tags(PHOTODEM_IMAGE=name, PHOTODEM_VISIBILITY="0 outside, 1 visible, 2 occluded")
    factors = overview_factors(width, height)
    if factors:
        with rasterio.Env(GDAL_NUM_THREADS="ALL_CPUS"):  # flushing compresses on all cores
            dst.build_overviews(factors, Resampling.average)
            dst.update_tags(ns="rio_overview", resampling="average")
            if dsm:  # a classical ortho's visibility repeats its alpha band: no overviews
                vdst.build_overviews(factors, Resampling.nearest)


__all__ = [
    "RESAMPLING",
    "default_gsd",
    "dem_footprint_box",
    "footprint_bounds",
    "occlusion_flags",
    "open_surface",
    "orthorectify_image",
    "project_grid",
    "project_points",
    "read_surface",
    "same_horizontal_crs",
    "surface_heights",
    "visibility_path",
]
