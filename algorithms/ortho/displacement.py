r"""Where a DEM error moves an orthophoto: predicted displacement and measured shifts.

Predicted displacement (seed-002-003 A8)
----------------------------------------
An orthophoto cell :math:`(X', Y')` takes its grey value from the image point of
:math:`(X', Y', Z_{DEM})`. A ground feature at its true position :math:`P = (X, Y, Z_{ref})` is
seen along the ray from the projection centre :math:`C = (X_0, Y_0, Z_0)` through :math:`P`; the
ortho shows it where that ray meets the height :math:`Z_{DEM} = Z_{ref} + e` (:math:`e` = DEM −
reference, the DEM error). Intersecting the ray at that height gives, exactly,

.. math::

   \mathbf d = (X' - X,\; Y' - Y) = -\frac{e}{Z_0 - Z_{ref}}\,(X - X_0,\; Y - Y_0),
   \qquad \Delta R = |\mathbf d| = |\Delta h|\,\frac{R}{H}

with :math:`\Delta h = Z_{ref} - Z_{DEM} = -e`, :math:`R` the horizontal distance of the cell
from the nadir point :math:`(X_0, Y_0)` and :math:`H = Z_0 - Z_{ref}` the flying height above the
cell. The displacement is radial: a DEM that is too low (:math:`e < 0`) pushes the feature away
from the nadir, one that is too high pulls it towards the nadir. Tilt does not enter (the
derivation only uses the ray), only whether the cell is seen by the image at all.

Measured shift
--------------
Two orthos of the same area (e.g. one on the DEM under test and one on a reference DEM, or two
neighbouring orthos in their overlap) are matched in windows on a regular grid: the reference
ortho's window (template) is searched in the other ortho by normalised cross-correlation in a
square neighbourhood (:func:`..matching.ncc.ncc_search_2d`, parabola sub-pixel peak) and then
refined by least-squares matching with a shift + radiometric model
(:func:`..matching.lsm.lsm_match`, free of the parabola's pixel-locking bias). The shift of a
window is the position in the other ortho minus the position in the reference ortho, in map
units (x east, y north) and in pixels of the reference ortho. Both orthos are read in strips of
window rows, so memory does not grow with the ortho size; an ortho on another grid or CRS is
resampled (bilinear) onto the reference grid strip by strip.
"""

from __future__ import annotations

import csv
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple, Union

import numpy as np
import rasterio
from numpy.typing import ArrayLike, NDArray
from rasterio.enums import ColorInterp
from rasterio.warp import Resampling, reproject, transform_bounds
from rasterio.windows import Window, from_bounds
from scipy import ndimage

from ..errors import GeometryError, InputError
from ..feedback import Feedback, ensure_feedback
from ..matching.lsm import lsm_match
from ..matching.ncc import ncc_search_2d
from ..project.model import Project
from ..raster.io import atomic_output, gtiff_profile, open_image
from ..raster.sample import bilinear
from ..surface.point_output import write_points

PathLike = Union[str, Path]
Array = NDArray[np.float64]

#: Band order of the displacement raster written by :func:`predict_displacement`.
DISPLACEMENT_BANDS = ("displacement", "dx", "dy", "radial")

#: Rows of the predicted raster processed at once (bounds the memory: ≈ 120 bytes per cell).
BLOCK_ROWS = 512

#: Status codes of a measured window (field ``status`` of the points).
STATUS = {
    0: "ok",
    1: "outside",  # the template or the search window leaves the valid part of an ortho
    2: "no_texture",  # no contrast in the template
    3: "low_ncc",  # NCC peak below min_ncc, on the border of the search range, or ambiguous
    4: "lsm_failed",  # the least-squares refinement did not converge or is imprecise
}


# ================================================================================================
# (a) predicted displacement
# ================================================================================================
def displacement_field(x: ArrayLike, y: ArrayLike, error: ArrayLike, z_ref: ArrayLike,
                       centre: ArrayLike) -> Tuple[Array, Array, Array]:
    r"""Ortho displacement of features at (x, y) caused by a DEM error, exactly.

    Parameters
    ----------
    x, y : array_like
        True horizontal positions of the features (map units, broadcast together).
    error : array_like
        DEM error :math:`e = Z_{DEM} - Z_{ref}` (m) at the features.
    z_ref : array_like
        True (reference) height :math:`Z_{ref}` of the features (m).
    centre : (3,) array_like
        Projection centre :math:`(X_0, Y_0, Z_0)` of the image.

    Returns
    -------
    dx, dy : ndarray
        :math:`\mathbf d = -e\,(X - X_0, Y - Y_0)/(Z_0 - Z_{ref})` (m): where the ortho shows
        the feature minus where it is.
    radial : ndarray
        Signed radial displacement :math:`-e\,R/H` (m), positive away from the nadir point.
        NaN where :math:`H \le 0` (the cell is not below the camera).
    """
    c = np.asarray(centre, dtype=float).reshape(3)
    rx = np.asarray(x, dtype=float) - c[0]
    ry = np.asarray(y, dtype=float) - c[1]
    h = c[2] - np.asarray(z_ref, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        k = np.where(h > 0, -np.asarray(error, dtype=float) / np.where(h > 0, h, 1.0), np.nan)
    return k * rx, k * ry, k * np.hypot(rx, ry)


def _grid_of(path: PathLike) -> Tuple[Any, Any, int, int]:
    p = Path(path)
    if not p.is_file():
        raise InputError(f"Raster '{p}' does not exist; check the path.")
    with rasterio.open(p) as src:
        return src.transform, src.crs, src.width, src.height


def _read_on_grid(path: PathLike, transform: Any, crs: Any, width: int, height: int,
                  row0: int, nrows: int, feedback: Feedback, warned: Dict[str, bool],
                  band: int = 1) -> Array:
    """Band ``band`` of a raster on rows ``row0 … row0+nrows`` of a target grid (NaN nodata).

    A raster on the same grid (same CRS, cell size and whole-cell offset) is read directly;
    anything else is resampled bilinearly (reprojected, with a warning once per file).
    """
    with rasterio.open(path) as src:
        same_crs = src.crs == crs or (src.crs is None or crs is None)
        t = src.transform
        off_c = (transform.c - t.c) / t.a if t.a else math.nan
        off_r = (transform.f - t.f) / t.e if t.e else math.nan
        aligned = (same_crs and t.b == 0 and t.d == 0 and transform.b == 0 and transform.d == 0
                   and abs(t.a - transform.a) <= 1e-9 * abs(t.a)
                   and abs(t.e - transform.e) <= 1e-9 * abs(t.e)
                   and abs(off_c - round(off_c)) < 1e-6 and abs(off_r - round(off_r)) < 1e-6)
        if aligned:
            win = Window(round(off_c), round(off_r) + row0, width, nrows)
            data = src.read(band, window=win, boundless=True, masked=True)
            return np.ma.filled(data.astype(np.float64), np.nan)
        key = str(path)
        if not warned.get(key):
            warned[key] = True
            what = "CRS" if not same_crs else "grid"
            feedback.warning(f"'{Path(path).name}' has another {what}; it is resampled "
                             "(bilinear) onto the grid of the first raster.")
        out = np.full((nrows, width), np.nan, np.float64)
        win_t = transform * transform.translation(0, row0)
        src_nodata = src.nodata if src.nodata is not None else None
        reproject(rasterio.band(src, band), out, src_transform=t, src_crs=src.crs or crs,
                  src_nodata=src_nodata, dst_transform=win_t, dst_crs=crs or src.crs,
                  dst_nodata=np.nan, resampling=Resampling.bilinear)
        return out


def _seen_by(camera: Any, eo: Any, x: Array, y: Array, z: Array) -> NDArray[np.bool_]:
    """Cells whose point (x, y, z) projects inside the image (and in front of the camera)."""
    pts = np.stack([x - eo.position[0], y - eo.position[1], z - eo.position[2]], axis=-1)
    # einsum, not a BLAS product: the result feeds a threshold (same bits in every process)
    p = np.einsum("...i,ij->...j", pts, eo.rotation)
    col, row = camera.camera_to_pixel(p)
    return ((col >= -0.5) & (col <= camera.width - 0.5) & (row >= -0.5)
            & (row <= camera.height - 0.5))


@dataclass
class _PredictionGrid:
    """Output grid of a predicted displacement and where its heights come from.

    ``z_const`` is the constant true height used when only the error raster is given.
    """

    transform: Any
    crs: Any
    width: int
    height: int
    error: Optional[PathLike]
    dem: Optional[PathLike]
    reference: Optional[PathLike]
    z_const: Optional[float]

    @property
    def base(self) -> PathLike:
        """The raster whose grid is the output grid."""
        return self.error if self.error is not None else self.dem  # type: ignore[return-value]

    def heights(self, row0: int, nrows: int, feedback: Feedback, warned: Dict[str, bool]
                ) -> Tuple[Array, Array]:
        """DEM error e and true height Z_ref on rows ``row0 … row0+nrows`` of the grid."""
        block = (self.transform, self.crs, self.width, self.height, row0, nrows, feedback,
                 warned)
        if self.error is not None:
            e = _read_on_grid(self.error, *block)
            if self.reference is not None:
                z_ref = _read_on_grid(self.reference, *block)
            elif self.dem is not None:
                z_ref = _read_on_grid(self.dem, *block) - e
            else:
                z_ref = np.full_like(e, float(self.z_const))  # type: ignore[arg-type]
        else:
            z_dem = _read_on_grid(self.dem, *block)  # type: ignore[arg-type]
            z_ref = _read_on_grid(self.reference, *block)  # type: ignore[arg-type]
            e = z_dem - z_ref
        return e, z_ref


def _prediction_grid(proj: Project, error: Optional[PathLike], dem: Optional[PathLike],
                     reference: Optional[PathLike], terrain_height: Optional[float]
                     ) -> _PredictionGrid:
    """Check the height inputs and take the output grid from the error raster or the DEM."""
    if error is None and (dem is None or reference is None):
        raise InputError("Give the DEM-error raster (DEM − reference), or both the DEM and the "
                         "reference DEM, to predict the ortho displacement.")
    base = error if error is not None else dem
    transform, crs, width, height = _grid_of(base)  # type: ignore[arg-type]
    if crs is None and proj.crs:
        crs = rasterio.crs.CRS.from_user_input(proj.crs)
    z_const = None
    if error is not None and dem is None and reference is None:
        z_const = terrain_height if terrain_height is not None else proj.terrain_height
        if z_const is None:
            raise InputError("The flying height above the ground needs the true heights: give "
                             "the reference DEM, the DEM, or a terrain height.")
    return _PredictionGrid(transform, crs, width, height, error, dem, reference, z_const)


@dataclass
class _DisplacementStats:
    """Running sums of the predicted |d| (float64, exact enough) and a histogram for p95."""

    n: int = 0
    s1: float = 0.0
    s2: float = 0.0
    s_h: float = 0.0
    mx: float = 0.0
    max_e: float = 0.0
    edges: Optional[Array] = None
    hist: Optional[NDArray[np.int64]] = None

    def add(self, vals: Array, heights: Array, errors: Array) -> None:
        """Add the |d| of seen cells, their flying heights Z0 − Z_ref and their errors."""
        if not vals.size:
            return
        self.n += vals.size
        self.s1 += float(vals.sum())
        self.s2 += float(np.square(vals).sum())
        self.s_h += float(heights.sum())
        self.mx = max(self.mx, float(vals.max()))
        self.max_e = max(self.max_e, float(np.abs(errors).max()))
        if self.edges is None:  # 1 mm bins up to 1 km: exact enough for p95
            self.edges = np.linspace(0.0, 1000.0, 1_000_001)
            self.hist = np.zeros(self.edges.size - 1, np.int64)
        self.hist += np.histogram(np.minimum(vals, 999.9995), bins=self.edges)[0]

    def summary(self, camera: Any) -> Dict[str, Any]:
        """The statistics of :func:`predict_displacement`'s result (rounded as reported)."""
        n, mx = self.n, self.mx
        h_mean = self.s_h / n
        gsd = float(camera.gsd(h_mean))
        cum = np.cumsum(self.hist)
        p95 = float(self.edges[int(np.searchsorted(cum, 0.95 * n)) + 1])  # type: ignore[index]
        above = 100.0 * float(n - cum[min(int(gsd * 1000.0), cum.size - 1)]) / n
        return {
            "flying_height_m": round(h_mean, 3),
            "gsd_m": round(gsd, 5),
            "cells": int(n),
            "max_m": round(mx, 4),
            "mean_m": round(self.s1 / n, 4),
            "rms_m": round(math.sqrt(self.s2 / n), 4),
            "p95_m": round(p95, 3),
            "max_px": round(mx / gsd, 3),
            "share_above_1gsd_pct": round(above, 3),
            "max_error_m": round(self.max_e, 4),
        }


def _predict_block(grid: _PredictionGrid, camera: Any, eo: Any, row0: int, nrows: int,
                   feedback: Feedback, warned: Dict[str, bool], stats: _DisplacementStats
                   ) -> NDArray[np.float32]:
    """The four bands of rows ``row0 … row0+nrows``; adds the seen cells to ``stats``."""
    t, width = grid.transform, grid.width
    rows, cols = np.mgrid[row0:row0 + nrows, 0:width].astype(np.float64)
    x = t.a * (cols + 0.5) + t.b * (rows + 0.5) + t.c
    y = t.d * (cols + 0.5) + t.e * (rows + 0.5) + t.f
    e, z_ref = grid.heights(row0, nrows, feedback, warned)
    dx, dy, radial = displacement_field(x, y, e, z_ref, eo.position)
    ok = np.isfinite(radial) & _seen_by(camera, eo, x, y,
                                        np.where(np.isfinite(z_ref), z_ref, 0.0))
    mag = np.where(ok, np.abs(radial), np.nan)
    out = np.stack([mag, np.where(ok, dx, np.nan), np.where(ok, dy, np.nan),
                    np.where(ok, radial, np.nan)]).astype(np.float32)
    vals = mag[ok]
    if vals.size:
        stats.add(vals, eo.position[2] - z_ref[ok], e[ok])
    return out


def predict_displacement(project: Any, image: str, output: PathLike, *,
                         error: Optional[PathLike] = None, dem: Optional[PathLike] = None,
                         reference: Optional[PathLike] = None,
                         terrain_height: Optional[float] = None,
                         feedback: Optional[Feedback] = None) -> Dict[str, Any]:
    r"""Predicted ortho displacement :math:`\Delta R = \Delta h\,R/H` of one image, as a raster.

    Parameters
    ----------
    project : Project or path
        The project (or its folder / project.toml).
    image : str
        Name of the image in the project.
    output : path
        GeoTIFF with four float32 bands (:data:`DISPLACEMENT_BANDS`): |d| (m), dx, dy (m, map
        axes) and the signed radial displacement (m, + away from the nadir point); NaN where the
        cell is not seen by the image or a height is missing. Written atomically.
    error : path, optional
        DEM-error raster :math:`e = Z_{DEM} - Z_{ref}` (m), e.g. ``difference.tif`` of
        ``dem_compare``. Its grid is the output grid.
    dem, reference : path, optional
        The DEM used (or to be used) for the ortho and the reference (true) DEM. Without
        ``error`` both are needed: :math:`e = DEM - reference` on the DEM's grid. With ``error``
        they give the true height :math:`Z_{ref}` (reference, or DEM − e) for :math:`H`.
    terrain_height : float, optional
        :math:`Z_{ref}` when only ``error`` is given (default: the project's terrain height).

    Returns
    -------
    dict
        ``displacement`` (path), ``image``, ``nadir`` [X0, Y0], ``flying_height_m`` (mean H),
        ``gsd_m`` (the image's GSD at that height), ``cells`` (seen cells with a value),
        ``max_m``, ``mean_m``, ``rms_m``, ``p95_m``, ``max_px`` (in image GSD),
        ``share_above_1gsd_pct``, ``max_error_m`` (largest |e| used), ``seconds``.

    Raises
    ------
    InputError
        Missing inputs, or no height for :math:`H`.
    GeometryError
        The image does not see any cell of the raster.
    """
    feedback = ensure_feedback(feedback)
    start = time.perf_counter()
    proj = project if isinstance(project, Project) else Project.load(project)
    rec = proj.image(image)
    camera = proj.camera_of(rec)
    eo = rec.eo
    grid = _prediction_grid(proj, error, dem, reference, terrain_height)
    width, height = grid.width, grid.height
    profile = gtiff_profile(width, height, len(DISPLACEMENT_BANDS), "float32", nodata=float("nan"),
                            transform=grid.transform, crs=grid.crs, predictor=3)
    warned: Dict[str, bool] = {}
    stats = _DisplacementStats()
    with atomic_output(output) as tmp, open_image(tmp, "w", **profile) as dst:
        for b, name in enumerate(DISPLACEMENT_BANDS, start=1):
            dst.set_band_description(b, name)
        dst.update_tags(PHOTODEM_IMAGE=rec.name, PHOTODEM_CAMERA_X=repr(eo.position[0]),
                        PHOTODEM_CAMERA_Y=repr(eo.position[1]),
                        PHOTODEM_CAMERA_Z=repr(eo.position[2]),
                        PHOTODEM_FORMULA="d = -e (X - X0, Y - Y0) / (Z0 - Zref)")
        for row0 in range(0, height, BLOCK_ROWS):
            feedback.progress(100.0 * row0 / height)
            nrows = min(BLOCK_ROWS, height - row0)
            out = _predict_block(grid, camera, eo, row0, nrows, feedback, warned, stats)
            dst.write(out, window=Window(0, row0, width, nrows))
        if stats.n == 0:  # raised inside atomic_output: nothing is left behind
            raise GeometryError(
                f"Image '{rec.name}' sees no cell of '{Path(str(grid.base)).name}' with a "
                "height error; check that the rasters cover the image's footprint.")
    summary = stats.summary(camera)
    feedback.progress(100.0)
    result = {
        "displacement": str(output),
        "image": rec.name,
        "nadir": [float(eo.position[0]), float(eo.position[1])],
        **summary,
        "seconds": round(time.perf_counter() - start, 3),
    }
    mx, gsd = stats.mx, float(camera.gsd(stats.s_h / stats.n))
    feedback.info(f"Predicted displacement of {rec.name}: max {mx:.3f} m ({mx / gsd:.2f} px), "
                  f"RMS {result['rms_m']:.3f} m over {stats.n} cells "
                  f"(H = {stats.s_h / stats.n:.1f} m).")
    return result


# ================================================================================================
# (b) measured shift between two orthos
# ================================================================================================
@dataclass
class ShiftResult:
    """Shifts measured between two orthos, one entry per window of the grid.

    Attributes
    ----------
    x, y : (n,) float64
        Window centres in the reference ortho (map units).
    dx, dy : (n,) float64
        Shift (map units, x east / y north): position in the other ortho − position in the
        reference ortho; NaN when not measured.
    dcol, drow : (n,) float64
        The same in pixels of the reference ortho (column / row axes).
    ncc : (n,) float32
        NCC peak of the integer search (NaN when not searched).
    corr : (n,) float32
        Correlation coefficient after least-squares matching.
    sigma : (n,) float32
        Precision of the shift from LSM (pixels, the larger of σ_col and σ_row).
    status : (n,) uint8
        :data:`STATUS` code; 0 = a good match.
    pixel_size : float
        Cell size of the reference ortho (map units).
    crs : object
        CRS of the reference ortho.
    """

    x: Array
    y: Array
    dx: Array
    dy: Array
    dcol: Array
    drow: Array
    ncc: NDArray[np.float32]
    corr: NDArray[np.float32]
    sigma: NDArray[np.float32]
    status: NDArray[np.uint8]
    pixel_size: float
    crs: Any

    @property
    def valid(self) -> NDArray[np.bool_]:
        return self.status == 0

    def summary(self) -> Dict[str, Any]:
        """Statistics of the good matches (m and px), and the counts per status."""
        ok = self.valid
        n = int(ok.sum())
        counts = {name: int((self.status == code).sum()) for code, name in STATUS.items()}
        out: Dict[str, Any] = {"windows": int(self.x.size), "matched": n,
                               "matched_pct": round(100.0 * n / max(self.x.size, 1), 2),
                               "status": counts, "pixel_size_m": self.pixel_size}
        if n == 0:
            return out
        dx, dy = self.dx[ok], self.dy[ok]
        mag = np.hypot(dx, dy)
        px = self.pixel_size
        mdx, mdy = float(dx.mean()), float(dy.mean())
        out.update({
            "mean_dx_m": round(mdx, 4),
            "mean_dy_m": round(mdy, 4),
            "mean_shift_m": round(math.hypot(mdx, mdy), 4),  # length of the mean vector
            "mean_abs_shift_m": round(float(mag.mean()), 4),
            "median_shift_m": round(float(np.median(mag)), 4),
            "rms_shift_m": round(float(np.sqrt(np.mean(mag * mag))), 4),
            "max_shift_m": round(float(mag.max()), 4),
            "std_dx_m": round(float(dx.std()), 4),
            "std_dy_m": round(float(dy.std()), 4),
            "mean_shift_px": round(math.hypot(mdx, mdy) / px, 4),
            "mean_abs_shift_px": round(float(mag.mean()) / px, 4),
            "rms_shift_px": round(float(np.sqrt(np.mean(mag * mag))) / px, 4),
            "max_shift_px": round(float(mag.max()) / px, 4),
            "mean_ncc": round(float(self.ncc[ok].mean()), 4),
            "mean_sigma_px": round(float(self.sigma[ok].mean()), 4),
        })
        return out


def _bands(src: Any) -> Tuple[List[int], Optional[int]]:
    """Colour bands (at most three) and the alpha band of an ortho (None without one).

    The alpha band is the band flagged as alpha, else the last band of a 2- or 4-band raster
    (grey/RGB + alpha written without the flag).
    """
    interp = list(src.colorinterp)
    alpha = next((i + 1 for i, c in enumerate(interp) if c == ColorInterp.alpha), None)
    if alpha is None and src.count in (2, 4) and interp[-1] == ColorInterp.undefined:
        alpha = src.count
    bands = [i + 1 for i in range(src.count) if i + 1 != alpha]
    return (bands or [1])[:3], alpha


def _read_grey(src: Any, transform: Any, crs: Any, col0: int, row0: int, width: int,
               height: int, aligned: bool) -> Tuple[NDArray[np.float32], NDArray[np.bool_]]:
    """Mean of the colour bands and the validity mask on a window of the target grid."""
    bands, alpha = _bands(src)
    if aligned:
        t = src.transform
        c = round((transform.c - t.c) / t.a) + col0
        r = round((transform.f - t.f) / t.e) + row0
        win = Window(c, r, width, height)
        data = src.read(bands, window=win, boundless=True, fill_value=0).astype(np.float32)
        mask = src.read_masks(bands[0], window=win, boundless=True) > 0
        if alpha is not None:
            mask &= src.read(alpha, window=win, boundless=True, fill_value=0) > 0
        # boundless mask reads of some GDAL versions report the outside as valid
        inside = np.zeros((height, width), bool)
        rr0, cc0 = max(0, -r), max(0, -c)
        rr1, cc1 = min(height, src.height - r), min(width, src.width - c)
        if rr1 > rr0 and cc1 > cc0:
            inside[rr0:rr1, cc0:cc1] = True
        mask &= inside
    else:
        win_t = transform * transform.translation(col0, row0)
        dst_crs = crs or src.crs
        # read only the source window that covers this strip (plus a margin of 2 cells)
        x0, y0 = win_t * (0, height)
        x1, y1 = win_t * (width, 0)
        b = (min(x0, x1), min(y0, y1), max(x0, x1), max(y0, y1))
        if src.crs is not None and crs is not None and src.crs != crs:
            b = transform_bounds(crs, src.crs, *b, densify_pts=21)
        w = from_bounds(*b, transform=src.transform)
        c0 = max(math.floor(w.col_off) - 2, 0)
        r0 = max(math.floor(w.row_off) - 2, 0)
        c1 = min(math.ceil(w.col_off + w.width) + 2, src.width)
        r1 = min(math.ceil(w.row_off + w.height) + 2, src.height)
        data = np.zeros((len(bands), height, width), np.float32)
        m = np.zeros((height, width), np.uint8)
        if c1 > c0 and r1 > r0:
            sw = Window(c0, r0, c1 - c0, r1 - r0)
            st = src.window_transform(sw)
            srcs = src.read(bands, window=sw).astype(np.float32)
            valid = src.read_masks(bands[0], window=sw)
            if alpha is not None:
                valid = np.where(src.read(alpha, window=sw) > 0, valid, 0).astype(np.uint8)
            for k in range(len(bands)):
                reproject(srcs[k], data[k], src_transform=st, src_crs=src.crs or crs,
                          dst_transform=win_t, dst_crs=dst_crs, src_nodata=None,
                          resampling=Resampling.bilinear, dst_nodata=0)
            reproject(valid, m, src_transform=st, src_crs=src.crs or crs,
                      dst_transform=win_t, dst_crs=dst_crs, resampling=Resampling.nearest,
                      src_nodata=None, dst_nodata=0)
        # a bilinear value next to invalid cells mixes in nodata: shrink the mask by one cell
        mask = ndimage.binary_erosion(m > 0, iterations=1, border_value=0)
    grey = data.mean(axis=0, dtype=np.float32) if data.shape[0] > 1 else data[0]
    return grey, mask


def _box_any(bad: NDArray[np.bool_], rows: NDArray, cols: NDArray, half: int) -> NDArray:
    """Does the (2·half+1)² box around each (row, col) hold a True cell (integral image)?"""
    ii = np.zeros((bad.shape[0] + 1, bad.shape[1] + 1), np.int64)
    ii[1:, 1:] = bad.astype(np.int64).cumsum(0).cumsum(1)
    r0, r1 = rows - half, rows + half + 1
    c0, c1 = cols - half, cols + half + 1
    return (ii[r1, c1] - ii[r0, c1] - ii[r1, c0] + ii[r0, c0]) > 0


def _check_shift_options(ortho: PathLike, reference: PathLike, spacing: Optional[int],
                         window: int, radius: int) -> int:
    """Refuse bad matching options and missing orthos; return the window spacing."""
    if window < 5 or window % 2 == 0:
        raise InputError(f"The matching window must be an odd number ≥ 5 px, not {window}.")
    if radius < 1:
        raise InputError("The search radius must be at least 1 px.")
    spacing = int(spacing) if spacing else int(window)
    if spacing < 1:
        raise InputError("The window spacing must be at least 1 px.")
    for p in (ortho, reference):
        if not Path(p).is_file():
            raise InputError(f"Ortho '{p}' does not exist; check the path.")
    return spacing


@dataclass
class _ShiftArea:
    """The reference grid and the area common to both orthos (reference pixels)."""

    transform: Any
    crs: Any
    pixel_size: float
    aligned: bool
    col0: int
    col1: int
    row0: int
    row1: int


def _shift_area(ref: Any, oth: Any, ortho: PathLike, reference: PathLike,
                feedback: Feedback) -> _ShiftArea:
    """How the other ortho lies on the reference grid, and the area both cover."""
    T, crs = ref.transform, ref.crs
    if T.b != 0 or T.d != 0:
        raise InputError(f"The reference ortho '{Path(reference).name}' is rotated; use a "
                         "north-up ortho as the reference.")
    px = float(abs(T.a))
    t = oth.transform
    same_crs = crs == oth.crs or crs is None or oth.crs is None
    off_c = (T.c - t.c) / t.a
    off_r = (T.f - t.f) / t.e if t.e else math.nan
    aligned = (same_crs and t.b == 0 and t.d == 0 and abs(t.a - T.a) <= 1e-9 * px
               and abs(t.e - T.e) <= 1e-9 * px and abs(off_c - round(off_c)) < 1e-6
               and abs(off_r - round(off_r)) < 1e-6)
    if not same_crs:
        feedback.warning(f"'{Path(ortho).name}' is in another CRS than the reference "
                         "ortho; it is reprojected (bilinear) onto the reference grid.")
    elif not aligned:
        feedback.info(f"'{Path(ortho).name}' is on another grid; it is resampled "
                      "(bilinear) onto the reference grid.")
    # the common area in reference pixels
    ob = oth.bounds if same_crs else transform_bounds(oth.crs, crs, *oth.bounds)
    rb = ref.bounds
    left, right = max(rb.left, ob[0]), min(rb.right, ob[2])
    bottom, top = max(rb.bottom, ob[1]), min(rb.top, ob[3])
    inv = ~T
    c_a, r_a = inv * (left, top)
    c_b, r_b = inv * (right, bottom)
    return _ShiftArea(T, crs, px, aligned,
                      max(math.ceil(min(c_a, c_b) - 1e-9), 0),
                      min(math.floor(max(c_a, c_b) + 1e-9), ref.width),
                      max(math.ceil(min(r_a, r_b) - 1e-9), 0),
                      min(math.floor(max(r_a, r_b) + 1e-9), ref.height))


@dataclass
class _MatchOptions:
    """Window size, search radius and the acceptance limits of one shift measurement."""

    window: int
    radius: int
    min_ncc: float
    max_sigma: float


def _match_strip(grey: Tuple[Array, Array, Array, Array], rr: NDArray, cc: NDArray,
                 opt: _MatchOptions) -> Dict[str, NDArray]:
    """NCC search and LSM refinement of the windows (rr, cc) of one strip.

    ``grey`` is (reference grey, its mask, other grey, its mask). Returns the arrays
    ``dc, dr, ncc, corr, sig, st`` (one entry per window, :data:`STATUS` codes in ``st``).
    """
    ga, ma, gb, mb = grey
    half, radius, window = opt.window // 2, opt.radius, opt.window
    status = np.zeros(rr.size, np.uint8)
    out = _box_any(~ma, rr, cc, half + 1) | _box_any(~mb, rr, cc, half + radius + 1)
    status[out] = 1
    ncc = np.full(rr.size, np.nan, np.float32)
    corr = np.full(rr.size, np.nan, np.float32)
    sig = np.full(rr.size, np.nan, np.float32)
    dc = np.full(rr.size, np.nan)
    dr = np.full(rr.size, np.nan)
    todo = np.flatnonzero(status == 0)
    if todo.size:
        a = np.where(ma, ga, 0.0).astype(np.float32)
        b = np.where(mb, gb, 0.0).astype(np.float32)
        c_t, r_t = cc[todo].astype(float), rr[todo].astype(float)
        found = ncc_search_2d(a, b, c_t, r_t, c_t, r_t, radius=radius, window=window,
                              min_ncc=opt.min_ncc, max_ratio=0.9)
        ncc[todo] = found.ncc
        flat = ~np.isfinite(found.ncc)
        status[todo[flat]] = 2
        status[todo[~flat & ~found.valid]] = 3
        good = todo[found.valid]
        if good.size:
            sel = found.valid
            lsm = lsm_match(a, b, c_t[sel], r_t[sel], found.cols[sel], found.rows[sel],
                            window=window, model="shift", max_shift=1.5,
                            min_corr=opt.min_ncc, max_sigma=opt.max_sigma)
            corr[good] = lsm.corr
            sig[good] = np.maximum(lsm.sigma_col, lsm.sigma_row)
            ok = lsm.valid
            status[good[~ok]] = 4
            dc[good[ok]] = lsm.cols[ok] - c_t[sel][ok]
            dr[good[ok]] = lsm.rows[ok] - r_t[sel][ok]
    return {"dc": dc, "dr": dr, "ncc": ncc, "corr": corr, "sig": sig, "st": status}


def _shift_result(res: Dict[str, List[NDArray]], area: _ShiftArea) -> ShiftResult:
    """The windows of all strips as one :class:`ShiftResult` in map units."""
    T = area.transform
    cat = {k: (np.concatenate(v) if v else np.zeros(0)) for k, v in res.items()}
    cols = cat["c"].astype(float)
    rows = cat["r"].astype(float)
    x = T.a * (cols + 0.5) + T.b * (rows + 0.5) + T.c
    y = T.d * (cols + 0.5) + T.e * (rows + 0.5) + T.f
    dcol, drow = cat["dc"], cat["dr"]
    return ShiftResult(x=x, y=y, dx=T.a * dcol + T.b * drow, dy=T.d * dcol + T.e * drow,
                       dcol=dcol, drow=drow, ncc=cat["ncc"].astype(np.float32),
                       corr=cat["corr"].astype(np.float32), sigma=cat["sig"].astype(np.float32),
                       status=cat["st"].astype(np.uint8), pixel_size=area.pixel_size,
                       crs=area.crs)


def measure_shift(ortho: PathLike, reference: PathLike, *, spacing: Optional[int] = None,
                  window: int = 31, radius: int = 8, min_ncc: float = 0.6,
                  max_sigma: float = 0.3, strip_rows: int = 1024,
                  feedback: Optional[Feedback] = None) -> ShiftResult:
    """Shift of ``ortho`` relative to ``reference`` by local matching on a grid of windows.

    Parameters
    ----------
    ortho : path
        The ortho to check (any grid/CRS; resampled bilinearly onto the reference grid when it
        is not on it). Colour bands are averaged; alpha / nodata / the GDAL mask marks invalid
        cells.
    reference : path
        The reference ortho; its grid defines the windows and the pixel unit.
    spacing : int, optional
        Distance of the window centres (reference pixels); default the window size.
    window : int
        Template size (odd, pixels).
    radius : int
        Search radius (pixels) of the NCC search around the unshifted position; larger shifts
        are not found.
    min_ncc : float
        Lowest NCC peak (and LSM correlation) of a good match.
    max_sigma : float
        Largest LSM precision (px) of a good match.
    strip_rows : int
        Rows read at once (bounds the memory: ≈ 40 bytes × strip_rows × common width).

    Returns
    -------
    ShiftResult

    Raises
    ------
    InputError
        Bad parameters, or the orthos do not overlap by more than one window.
    """
    feedback = ensure_feedback(feedback)
    spacing = _check_shift_options(ortho, reference, spacing, window, radius)
    opt = _MatchOptions(window, radius, min_ncc, max_sigma)
    margin = window // 2 + radius + 2  # the search window plus the LSM's bilinear border
    with rasterio.open(reference) as ref, rasterio.open(ortho) as oth:
        area = _shift_area(ref, oth, ortho, reference, feedback)
        T, crs, col0, row0 = area.transform, area.crs, area.col0, area.row0
        if area.col1 - col0 < 2 * margin + 1 or area.row1 - row0 < 2 * margin + 1:
            raise InputError(f"The orthos '{Path(ortho).name}' and '{Path(reference).name}' "
                             f"overlap by less than one window ({window} px + {radius} px "
                             "search radius each side); choose orthos of the same area.")
        gcols = np.arange(col0 + margin, area.col1 - margin, spacing)
        grows = np.arange(row0 + margin, area.row1 - margin, spacing)
        per_strip = max(1, (max(int(strip_rows), spacing + 2 * margin) - 2 * margin) // spacing)
        res: Dict[str, List[NDArray]] = {k: [] for k in
                                         ("c", "r", "dc", "dr", "ncc", "corr", "sig", "st")}
        width = area.col1 - col0
        for s in range(0, grows.size, per_strip):
            feedback.progress(95.0 * s / max(grows.size, 1))
            srows = grows[s:s + per_strip]
            top_row = int(srows[0]) - margin
            nrows = int(srows[-1]) - top_row + margin + 1
            ga, ma = _read_grey(ref, T, crs, col0, top_row, width, nrows, True)
            gb, mb = _read_grey(oth, T, crs, col0, top_row, width, nrows, area.aligned)
            rr, cc = np.meshgrid(srows - top_row, gcols - col0, indexing="ij")
            rr, cc = rr.ravel(), cc.ravel()
            found = _match_strip((ga, ma, gb, mb), rr, cc, opt)
            res["c"].append(cc + col0)
            res["r"].append(rr + top_row)
            for key, val in found.items():
                res[key].append(val)
    feedback.progress(100.0)
    return _shift_result(res, area)


def _fields(result: ShiftResult, predicted: Optional[Dict[str, Array]]) -> Dict[str, NDArray]:
    fields: Dict[str, NDArray] = {
        "dx": result.dx, "dy": result.dy, "shift": np.hypot(result.dx, result.dy),
        "dx_px": result.dx / result.pixel_size, "dy_px": result.dy / result.pixel_size,
        "ncc": result.ncc.astype(np.float64), "corr": result.corr.astype(np.float64),
        "sigma_px": result.sigma.astype(np.float64),
        "status": np.array([STATUS[int(s)] for s in result.status], dtype=object).astype(str),
    }
    if predicted:
        fields.update({f"pred_{k}": v for k, v in predicted.items()})
    return fields


def write_shift_points(path: PathLike, result: ShiftResult,
                       predicted: Optional[Dict[str, Array]] = None,
                       feedback: Optional[Feedback] = None) -> Path:
    """Write the measured windows as a GeoPackage (``.gpkg``, 3-D points at z = 0) or CSV.

    Fields: dx, dy, shift (map units), dx_px, dy_px (map axes, in reference pixels), ncc, corr,
    sigma_px, status (:data:`STATUS` names), and ``pred_*`` fields when a prediction is given.
    """
    path = Path(path)
    fields = _fields(result, predicted)
    if path.suffix.lower() == ".gpkg":
        return write_points(path, result.x, result.y, np.zeros_like(result.x), fields,
                            crs=result.crs, feedback=feedback)
    if path.suffix.lower() != ".csv":
        raise InputError(f"Cannot write shift points to '{path.name}': use .gpkg or .csv.")
    names = list(fields)
    with atomic_output(path) as tmp, open(tmp, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(["x", "y", *names])
        for i in range(result.x.size):
            row = [f"{result.x[i]:.3f}", f"{result.y[i]:.3f}"]
            for k in names:
                v = fields[k][i]
                if isinstance(v, str):
                    row.append(v)
                else:
                    row.append("" if not np.isfinite(v) else f"{float(v):.4f}")
            w.writerow(row)
    return path


def sample_prediction(displacement: PathLike, x: ArrayLike, y: ArrayLike) -> Dict[str, Array]:
    """Predicted dx, dy and |d| (bilinear, NaN outside) of a displacement raster at points."""
    with rasterio.open(displacement) as src:
        dx = src.read(2).astype(np.float64)
        dy = src.read(3).astype(np.float64)
        t = src.transform
    px, py = bilinear(dx, t, x, y), bilinear(dy, t, x, y)
    return {"dx": px, "dy": py, "shift": np.hypot(px, py)}


def compare_shifts(result: ShiftResult, predicted: Dict[str, Array],
                   min_px: float = 1.0) -> Dict[str, Any]:
    r"""Measured against predicted shifts at the good windows.

    Over windows whose predicted shift :math:`\mathbf p` is at least ``min_px`` reference
    pixels: the ratio of the measured shift :math:`\mathbf m` along the predicted direction,
    :math:`\rho = \mathbf m\cdot\mathbf p / |\mathbf p|^2` (median, and the share of windows
    with :math:`|\rho - 1| \le 0.15`); over all good windows with a prediction: the RMS of
    :math:`|\mathbf m - \mathbf p|` (m and px).
    """
    ok = result.valid & np.isfinite(predicted["dx"]) & np.isfinite(predicted["dy"])
    px = result.pixel_size
    out: Dict[str, Any] = {"windows": int(ok.sum())}
    if not ok.any():
        return out
    mx, my = result.dx[ok], result.dy[ok]
    qx, qy = predicted["dx"][ok], predicted["dy"][ok]
    diff = np.hypot(mx - qx, my - qy)
    out["rms_difference_m"] = round(float(np.sqrt(np.mean(diff * diff))), 4)
    out["rms_difference_px"] = round(float(np.sqrt(np.mean(diff * diff))) / px, 4)
    big = np.hypot(qx, qy) >= min_px * px
    out["windows_predicted_above_min"] = int(big.sum())
    if big.any():
        rho = (mx[big] * qx[big] + my[big] * qy[big]) / (qx[big] ** 2 + qy[big] ** 2)
        out["ratio_median"] = round(float(np.median(rho)), 4)
        out["within_15pct_pct"] = round(100.0 * float(np.mean(np.abs(rho - 1.0) <= 0.15)), 2)
    return out
