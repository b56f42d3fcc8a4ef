"""Rasters for the screen: tiles read from the overview that fits the zoom, coloured to RGBA.

The standalone map view (``plugin/widgets/raster_tiles.py``) draws a raster as 256 × 256
tiles on a fixed grid per zoom level (:class:`TileGrid`), so panning reuses tiles and a tile is
read once. Level ``k`` has pixels ``2**k`` times coarser than the raster; a tile is read with a
decimated read (``out_shape``), which GDAL serves from the GeoTIFF overview of that factor —
never the whole raster. A raster in another CRS than the map is reprojected tile by tile
(:func:`rasterio.warp.reproject` of the tile's source window only).

Colouring follows the QGIS styles of the project (``resources/styles/*.qml``, read here with
:mod:`xml.etree` so both faces use one definition):

- DEM: a hillshade (315°/45°, Horn's gradient of :mod:`.terrain`) under the elevation ramp of
  ``dem_elevation.qml`` at its opacity (50 %), the ramp spread over the 2–98 % range of the
  raster (computed once from the smallest overview);
- difference: the discrete classes of ``dem_difference.qml``;
- RGB(A) orthos and mosaics: 8-bit as is, 16-bit stretched 2–98 % per band, transparent where
  the alpha band, the mask or nodata says so;
- any other single band: grey, stretched 2–98 %.

Nodata is transparent everywhere. Tiles of a DEM are read with a 1-pixel margin so that the
hillshade of neighbouring tiles joins without a seam.

Qt-free: the map view turns the RGBA arrays into images.
"""

from __future__ import annotations

import math
import os
import warnings
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any, List, Optional, Sequence, Tuple, Union

import numpy as np
import rasterio
from affine import Affine
from numpy.typing import NDArray
from rasterio.crs import CRS
from rasterio.enums import ColorInterp, MaskFlags, Resampling
from rasterio.errors import NotGeoreferencedWarning
from rasterio.warp import reproject, transform_bounds
from rasterio.warp import transform as warp_points
from rasterio.windows import Window

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from .io import overview_factors
from .terrain import horn_gradient, shade

PathLike = Union[str, Path]
Bounds = Tuple[float, float, float, float]

#: Side of a tile in pixels of its level.
TILE = 256
#: Kinds drawn as hillshade + elevation ramp.
DEM_KINDS = ("dsm", "dtm")
#: Kinds drawn as colour images.
RGB_KINDS = ("ortho", "mosaic", "rgb")
#: A raster larger than this (pixels, either side) without overviews is slow to draw.
OVERVIEW_THRESHOLD = 2048
#: Zoom tolerance of the level choice: a level up to 25 % coarser than the screen is used.
LEVEL_TOLERANCE = 1.25
#: Pixels per side of the decimated read the 2–98 % statistics are taken from.
STATS_PIXELS = 512

STYLES = Path(__file__).resolve().parents[2] / "resources" / "styles"
_M_PER_DEG_LAT = 110_574.0
_M_PER_DEG_LON = 111_320.0


# -- opening ------------------------------------------------------------------------------------
def open_raster(path: PathLike) -> Any:
    """Open ``path`` with rasterio, or raise :class:`InputError` naming the file."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"Raster '{path}' does not exist.")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", NotGeoreferencedWarning)  # shown in pixel coordinates
            return rasterio.open(path)
    except (rasterio.errors.RasterioError, rasterio.errors.RasterioIOError) as exc:
        # rasterio 1.3 (Debian's) derives RasterioIOError from OSError, 1.4 from RasterioError
        raise InputError(f"GDAL cannot open the raster '{path.name}' ({path}): {exc}") from exc


@dataclass(frozen=True)
class RasterInfo:
    """What the map needs to know of a raster file (read once at opening).

    Attributes
    ----------
    width, height, count : int
        Size and number of bands.
    dtype : str
        Data type of band 1.
    transform : Affine
        Pixel → raster coordinates; for a raster without CRS ``x = col, y = -row``.
    crs : str
        The CRS as WKT, empty when the raster has none.
    nodata : float or None
    overviews : tuple of int
        Overview factors of band 1 (empty: none).
    rgb_bands : tuple of int
        Bands shown as R, G, B (1-based; empty for a single-band raster).
    alpha_band : int
        The alpha band (1-based), 0 when there is none.
    per_dataset_mask : bool
        The raster has a mask band (read with ``read_masks``).
    """

    width: int
    height: int
    count: int
    dtype: str
    transform: Affine
    crs: str
    nodata: Optional[float]
    overviews: Tuple[int, ...]
    rgb_bands: Tuple[int, ...] = ()
    alpha_band: int = 0
    per_dataset_mask: bool = False

    @property
    def has_crs(self) -> bool:
        return bool(self.crs)

    @property
    def needs_overviews(self) -> bool:
        """Larger than :data:`OVERVIEW_THRESHOLD` pixels and without overviews."""
        return max(self.width, self.height) > OVERVIEW_THRESHOLD and not self.overviews

    @property
    def bounds(self) -> Bounds:
        """(xmin, ymin, xmax, ymax) in the raster's coordinates."""
        t = self.transform
        xs = [(t * (c, r))[0] for c in (0, self.width) for r in (0, self.height)]
        ys = [(t * (c, r))[1] for c in (0, self.width) for r in (0, self.height)]
        return min(xs), min(ys), max(xs), max(ys)


#: Pixel coordinates of a raster without CRS: x = col, y = −row (north up on screen).
PIXEL_TRANSFORM = Affine(1.0, 0.0, 0.0, 0.0, -1.0, 0.0)


def raster_info(src: Any) -> RasterInfo:
    """:class:`RasterInfo` of an open dataset."""
    crs = src.crs.to_wkt() if src.crs else ""
    transform = src.transform if crs else PIXEL_TRANSFORM
    interp = list(src.colorinterp)
    alpha = interp.index(ColorInterp.alpha) + 1 if ColorInterp.alpha in interp else 0
    colour = [i + 1 for i in range(src.count) if i + 1 != alpha]
    rgb = tuple(colour[:3]) if len(colour) >= 3 else ()
    flags = src.mask_flag_enums[0] if src.count else []
    return RasterInfo(src.width, src.height, src.count, src.dtypes[0], transform, crs,
                      src.nodata, tuple(src.overviews(1)), rgb, alpha,
                      MaskFlags.per_dataset in flags and alpha == 0)


def guess_kind(info: RasterInfo, path: PathLike) -> str:
    """The kind of a raster that is not a known product, from its bands and name.

    Three or more colour bands → ``ortho`` (``image`` without a CRS); a name with
    ``diff`` → ``difference``; one floating-point band → ``dsm``; else ``image``.
    """
    if info.rgb_bands:
        return "ortho" if info.has_crs else "image"
    if "diff" in Path(path).stem.lower():
        return "difference"
    if info.dtype.startswith("float") and info.has_crs:
        return "dsm"
    return "image"


# -- the tile grid ------------------------------------------------------------------------------
@dataclass(frozen=True)
class TileGrid:
    """Fixed tile grids of one raster in map coordinates, one per zoom level.

    Level ``k`` has pixels of ``res * 2**k`` map units; its tile ``(col, row)`` covers
    ``TILE`` level pixels from ``origin`` eastwards and southwards.

    Attributes
    ----------
    origin : (float, float)
        Top-left corner (map coordinates).
    res : (float, float)
        Level-0 pixel size in map units (x, y; both positive).
    size : (int, int)
        Level-0 size in pixels (width, height).
    levels : int
        Number of levels: the last one fits in one tile.
    """

    origin: Tuple[float, float]
    res: Tuple[float, float]
    size: Tuple[int, int]
    levels: int = field(default=0)

    @staticmethod
    def make(origin: Tuple[float, float], res: Tuple[float, float],
             size: Tuple[int, int]) -> TileGrid:
        """A grid whose top level holds the whole raster in one tile."""
        levels = 1
        while max(size) / 2 ** (levels - 1) > TILE:
            levels += 1
        return TileGrid(origin, res, size, levels)

    def level_size(self, level: int) -> Tuple[int, int]:
        """(width, height) of ``level`` in its pixels (rounded up, as GDAL's overviews)."""
        f = 2 ** level
        return -(-self.size[0] // f), -(-self.size[1] // f)

    def level_transform(self, level: int) -> Affine:
        f = 2 ** level
        return Affine(self.res[0] * f, 0.0, self.origin[0], 0.0, -self.res[1] * f, self.origin[1])

    def level_for(self, units_per_pixel: float) -> int:
        """The coarsest level not coarser than the screen (within :data:`LEVEL_TOLERANCE`)."""
        ratio = units_per_pixel / min(self.res) * LEVEL_TOLERANCE
        level = math.floor(math.log2(ratio)) if ratio >= 1 else 0
        return min(max(level, 0), self.levels - 1)

    def tile_bounds(self, level: int, col: int, row: int) -> Bounds:
        t = self.level_transform(level)
        x0, y1 = t * (col * TILE, row * TILE)
        x1, y0 = t * ((col + 1) * TILE, (row + 1) * TILE)
        return x0, y0, x1, y1

    def tiles_in(self, extent: Bounds, level: int) -> List[Tuple[int, int]]:
        """(col, row) of the tiles of ``level`` that meet ``extent`` (inside the raster)."""
        t = ~self.level_transform(level)
        c0, r0 = t * (extent[0], extent[3])
        c1, r1 = t * (extent[2], extent[1])
        w, h = self.level_size(level)
        cols = range(max(int(c0 // TILE), 0), min(math.ceil(c1 / TILE), -(-w // TILE)))
        rows = range(max(int(r0 // TILE), 0), min(math.ceil(r1 / TILE), -(-h // TILE)))
        return [(c, r) for r in rows for c in cols]

    def parent(self, level: int, col: int, row: int) -> Tuple[int, int, int]:
        """The tile of the next coarser level that contains this one."""
        return level + 1, col // 2, row // 2


def same_crs(crs_a: str, crs_b: str) -> bool:
    """Whether two CRS (WKT or ``EPSG:n``) are the same; an empty one matches anything."""
    if not crs_a or not crs_b:
        return True
    return bool(_crs(crs_a) == _crs(crs_b))


@lru_cache(maxsize=64)
def _crs(text: str) -> CRS:
    return CRS.from_user_input(text)


def tile_grid(info: RasterInfo, map_crs: str = "") -> TileGrid:
    """The tile grid of a raster shown on a map in ``map_crs``.

    In the raster's own CRS (or without one) the grid is the raster's pixel grid, so a tile is
    a window of the raster; otherwise a grid over the raster's bounds in the map CRS with about
    the same number of pixels.
    """
    t = info.transform
    if not needs_warp(info, map_crs):
        return TileGrid.make((t.c, t.f), (abs(t.a), abs(t.e)), (info.width, info.height))
    x0, y0, x1, y1 = transform_bounds(_crs(info.crs), _crs(map_crs), *info.bounds,
                                      densify_pts=21)
    res = math.sqrt((x1 - x0) * (y1 - y0) / (info.width * info.height))
    size = (max(math.ceil((x1 - x0) / res), 1), max(math.ceil((y1 - y0) / res), 1))
    return TileGrid.make((x0, y1), (res, res), size)


def needs_warp(info: RasterInfo, map_crs: str) -> bool:
    """A tile must be reprojected: another CRS than the map, or a rotated geotransform."""
    t = info.transform
    rotated = abs(t.b) > 1e-12 or abs(t.d) > 1e-12 or t.a <= 0 or t.e >= 0
    return bool(info.crs) and bool(map_crs) and (rotated or not same_crs(info.crs, map_crs))


# -- reading ------------------------------------------------------------------------------------
def _valid_mask(src: Any, info: RasterInfo, data: NDArray[Any], window: Window,
                shape: Tuple[int, int]) -> NDArray[np.bool_]:
    """Which pixels hold data: alpha band, mask band or nodata (all bands equal to it)."""
    if info.alpha_band:
        return data[-1] > 0
    if info.per_dataset_mask:
        return src.read_masks(1, window=window, out_shape=shape,
                              resampling=Resampling.nearest) > 0
    if info.nodata is not None and not (isinstance(info.nodata, float)
                                        and math.isnan(info.nodata)):
        return np.any(data != info.nodata, axis=0)
    if np.issubdtype(data.dtype, np.floating):
        return np.all(np.isfinite(data), axis=0)
    return np.ones(shape, dtype=bool)


def _bands(info: RasterInfo, kind: str) -> List[int]:
    """The bands a kind is drawn from (+ the alpha band last, when there is one)."""
    colour = info.rgb_bands and kind not in DEM_KINDS + ("difference",)
    bands = list(info.rgb_bands) if colour else [1]
    return bands + ([info.alpha_band] if info.alpha_band else [])


def read_window(src: Any, info: RasterInfo, kind: str, window: Window,
                shape: Tuple[int, int]) -> NDArray[np.float32]:
    """Bands of ``kind`` in ``window`` (raster pixels) read at ``shape``, NaN where invalid.

    A decimated read: GDAL takes the overview that fits ``shape``. Returns float32
    ``(bands, rows, cols)`` without the alpha band.
    """
    bands = _bands(info, kind)
    data = src.read(bands, window=window, out_shape=(len(bands),) + shape,
                    resampling=Resampling.nearest)
    valid = _valid_mask(src, info, data, window, shape)
    out = data[: len(bands) - (1 if info.alpha_band else 0)].astype(np.float32)
    out[:, ~valid] = np.nan
    return out


def read_tile(src: Any, info: RasterInfo, grid: TileGrid, kind: str, key: Tuple[int, int, int],
              margin: int = 0, map_crs: str = "") -> NDArray[np.float32]:
    """The tile ``key = (level, col, row)`` of ``grid`` with ``margin`` pixels on each side.

    Returns float32 ``(bands, TILE + 2 margin, TILE + 2 margin)``, NaN outside the raster and
    where it has no data.
    """
    if needs_warp(info, map_crs):
        return _warped_tile(src, info, grid, kind, key, margin, map_crs)
    level, col, row = key
    f = 2 ** level
    n = TILE + 2 * margin
    lw, lh = grid.level_size(level)
    a0, b0 = col * TILE - margin, row * TILE - margin  # level pixels of the tile's corner
    c0, r0 = max(a0, 0), max(b0, 0)
    c1, r1 = min(a0 + n, lw), min(b0 + n, lh)
    out = np.full((len(_bands(info, kind)) - (1 if info.alpha_band else 0), n, n), np.nan,
                  dtype=np.float32)
    if c1 <= c0 or r1 <= r0:
        return out
    window = Window(c0 * f, r0 * f, min(c1 * f, info.width) - c0 * f,
                    min(r1 * f, info.height) - r0 * f)
    out[:, r0 - b0:r1 - b0, c0 - a0:c1 - a0] = read_window(src, info, kind, window,
                                                            (r1 - r0, c1 - c0))
    return out


def _warped_tile(src: Any, info: RasterInfo, grid: TileGrid, kind: str,
                 key: Tuple[int, int, int], margin: int, map_crs: str) -> NDArray[np.float32]:
    """A tile in the map CRS: the source window under it, read decimated, then reprojected."""
    level, col, row = key
    n = TILE + 2 * margin
    lt = grid.level_transform(level)
    dst_transform = lt * Affine.translation(col * TILE - margin, row * TILE - margin)
    x0, y1 = dst_transform * (0, 0)
    x1, y0 = dst_transform * (n, n)
    nb = len(_bands(info, kind)) - (1 if info.alpha_band else 0)
    out = np.full((nb, n, n), np.nan, dtype=np.float32)
    try:
        sb = transform_bounds(_crs(map_crs), _crs(info.crs), x0, y0, x1, y1, densify_pts=21)
    except Exception:  # a tile outside the CRS's area of use stays empty
        return out
    inv = ~info.transform
    corners = [inv * (x, y) for x in (sb[0], sb[2]) for y in (sb[1], sb[3])]
    cs = [c for c, _ in corners]
    rs = [r for _, r in corners]
    c0, c1 = max(math.floor(min(cs)) - 2, 0), min(math.ceil(max(cs)) + 2, info.width)
    r0, r1 = max(math.floor(min(rs)) - 2, 0), min(math.ceil(max(rs)) + 2, info.height)
    if c1 <= c0 or r1 <= r0:
        return out
    step = max(1, 2 ** math.floor(math.log2(max(max(c1 - c0, r1 - r0) / n, 1.0))))
    shape = (max(-(-(r1 - r0) // step), 1), max(-(-(c1 - c0) // step), 1))
    data = read_window(src, info, kind, Window(c0, r0, c1 - c0, r1 - r0), shape)
    src_transform = info.transform * Affine.translation(c0, r0) * Affine.scale(
        (c1 - c0) / shape[1], (r1 - r0) / shape[0])
    # bilinear for heights: nearest would terrace slopes, and the hillshade shows terraces
    resampling = Resampling.bilinear if kind in DEM_KINDS else Resampling.nearest
    for b in range(nb):
        reproject(data[b], out[b], src_transform=src_transform, src_crs=_crs(info.crs),
                  dst_transform=dst_transform, dst_crs=_crs(map_crs), src_nodata=np.nan,
                  dst_nodata=np.nan, resampling=resampling)
    return out


def read_value(src: Any, info: RasterInfo, x: float, y: float,
               map_crs: str = "") -> Optional[List[float]]:
    """Band values at the map point (full resolution, one pixel), NaN for nodata; None outside.

    All colour bands of an RGB raster, else band 1.
    """
    if needs_warp(info, map_crs) or (info.crs and map_crs and not same_crs(info.crs, map_crs)):
        xs, ys = warp_points(_crs(map_crs), _crs(info.crs), [x], [y])
        x, y = xs[0], ys[0]
    col, row = ~info.transform * (x, y)
    if not (0 <= col < info.width and 0 <= row < info.height):
        return None
    kind = "rgb" if info.rgb_bands else "dsm"
    data = read_window(src, info, kind, Window(int(col), int(row), 1, 1), (1, 1))
    return [float(v) for v in data[:, 0, 0]]


# -- statistics ---------------------------------------------------------------------------------
def band_stats(src: Any, info: RasterInfo, kind: str,
               cut: Tuple[float, float] = (2.0, 98.0)) -> List[Tuple[float, float]]:
    """The 2–98 % range of each drawn band, from a small read (never the whole raster).

    With overviews: a decimated read of the whole raster (GDAL serves the smallest
    overview). Without, and larger than :data:`OVERVIEW_THRESHOLD`: 64 windows on a grid.
    """
    if info.overviews or max(info.width, info.height) <= OVERVIEW_THRESHOLD:
        scale = max(info.width / STATS_PIXELS, info.height / STATS_PIXELS, 1.0)
        shape = (max(int(info.height / scale), 1), max(int(info.width / scale), 1))
        data = read_window(src, info, kind, Window(0, 0, info.width, info.height), shape)
    else:
        parts = []
        for i in range(8):
            for j in range(8):
                c = int((j + 0.5) * info.width / 8) - 32
                r = int((i + 0.5) * info.height / 8) - 32
                parts.append(read_window(src, info, kind, Window(c, r, 64, 64), (64, 64)))
        data = np.concatenate(parts, axis=2)
    stats = []
    for band in data:
        values = band[np.isfinite(band)]
        if values.size == 0:
            stats.append((0.0, 1.0))
            continue
        lo, hi = np.percentile(values, cut)
        stats.append((float(lo), float(hi) if hi > lo else float(lo) + 1.0))
    return stats


# -- colour ramps of the QML styles -------------------------------------------------------------
@dataclass(frozen=True)
class Ramp:
    """A colour ramp of a QGIS raster style (``colorrampshader``).

    Attributes
    ----------
    discrete : bool
        DISCRETE (a value takes the colour of the first item whose value is ≥ it) or
        INTERPOLATED.
    values : tuple of float
        Item values, ascending (``inf`` allowed for the last discrete class).
    colors : ndarray (n, 4) uint8
        RGBA of each item.
    opacity : float
        The renderer's opacity (0…1).
    lut : ndarray (LUT_SIZE, 4) uint8 or None
        An interpolated ramp sampled evenly from the first to the last value (fast lookup).
    """

    discrete: bool
    values: Tuple[float, ...]
    colors: NDArray[np.uint8]
    opacity: float = 1.0
    lut: Optional[NDArray[np.uint8]] = field(default=None, compare=False)


#: Entries of the lookup table of an interpolated ramp (colour error < 1 level of 255).
LUT_SIZE = 1024


def _lut(values: Sequence[float], colors: NDArray[np.uint8]) -> NDArray[np.uint8]:
    x = np.linspace(values[0], values[-1], LUT_SIZE)
    return np.stack([np.round(np.interp(x, values, colors[:, ch])) for ch in range(4)],
                    axis=1).astype(np.uint8)


@lru_cache(maxsize=8)
def qml_ramp(path: PathLike) -> Ramp:
    """The colour ramp of a QML raster style (parsed once)."""
    root = ET.parse(str(path)).getroot()
    renderer = root.find(".//rasterrenderer")
    shader = root.find(".//colorrampshader")
    if renderer is None or shader is None:
        raise InputError(f"'{path}' has no colour ramp.")
    values, colors = [], []
    for item in shader.findall("item"):
        values.append(float(item.get("value", "nan")))
        hexa = item.get("color", "#000000").lstrip("#")
        colors.append([int(hexa[i:i + 2], 16) for i in (0, 2, 4)] + [int(item.get("alpha",
                                                                                   "255"))])
    discrete = shader.get("colorRampType", "INTERPOLATED") == "DISCRETE"
    rgba = np.array(colors, dtype=np.uint8)
    lut = None if discrete or not np.all(np.isfinite(values)) else _lut(values, rgba)
    return Ramp(discrete, tuple(values), rgba, float(renderer.get("opacity", "1")), lut)


def elevation_ramp() -> Ramp:
    """``dem_elevation.qml``: placeholders on 0…1, spread over the 2–98 % range when drawn."""
    return qml_ramp(STYLES / "dem_elevation.qml")


def difference_ramp() -> Ramp:
    """``dem_difference.qml``: classes in metres."""
    return qml_ramp(STYLES / "dem_difference.qml")


def apply_ramp(ramp: Ramp, values: NDArray[Any]) -> NDArray[np.uint8]:
    """RGBA (…, 4) uint8 of ``values`` (NaN → transparent)."""
    v = np.asarray(values, dtype=np.float64)
    out = np.zeros(v.shape + (4,), dtype=np.uint8)
    ok = np.isfinite(v)
    if ramp.discrete:
        idx = np.searchsorted(np.asarray(ramp.values), v[ok], side="left")
        out[ok] = ramp.colors[np.minimum(idx, len(ramp.values) - 1)]
        return out
    if ramp.lut is not None:
        v0, v1 = ramp.values[0], ramp.values[-1]
        scaled = np.nan_to_num((v - v0) * ((LUT_SIZE - 1) / (v1 - v0)), nan=0.0)
        idx = np.clip(np.rint(scaled), 0, LUT_SIZE - 1).astype(np.intp)
        out = ramp.lut[idx]
        out[~ok] = 0
        return out
    for ch in range(4):
        out[..., ch][ok] = np.round(np.interp(v[ok], ramp.values, ramp.colors[:, ch]))
    return out


# -- colouring ----------------------------------------------------------------------------------
def _cell_size(grid_transform: Affine, map_crs: str, rows: int) -> Tuple[Any, float]:
    """Cell width and height in metres (a geographic map: per row, at its latitude)."""
    dx, dy = abs(grid_transform.a), abs(grid_transform.e)
    if map_crs and _crs(map_crs).is_geographic:
        lat = grid_transform.f + grid_transform.e * (np.arange(rows) + 0.5)
        return np.maximum(dx * _M_PER_DEG_LON * np.cos(np.radians(lat))[:, None], 1e-6), \
            dy * _M_PER_DEG_LAT
    return dx, dy


def hillshade_tile(z: NDArray[Any], dx: Any, dy: float) -> NDArray[np.float32]:
    """Illumination 0…1 (315°/45°) of the inner cells of ``z`` (a 1-cell margin around).

    Cells whose neighbours are partly nodata are shaded as flat ground.
    """
    p, q = horn_gradient(z, dx, dy, dtype=np.float32)
    s = shade(p, q)
    s[np.isnan(s)] = math.sin(math.radians(45.0))
    return s


def dem_rgba(z: NDArray[Any], dx: Any, dy: float, lo: float, hi: float,
             ramp: Optional[Ramp] = None) -> NDArray[np.uint8]:
    """Hillshade under the elevation ramp: ``(rows, cols, 4)`` of the inner cells of ``z``.

    ``z`` has a 1-cell margin; the ramp (default ``dem_elevation.qml``) is spread over
    ``lo…hi`` and blended at its opacity over the grey hillshade.
    """
    ramp = ramp or elevation_ramp()
    inner = np.asarray(z[1:-1, 1:-1], dtype=np.float32)
    grey = hillshade_tile(z, dx, dy) * np.float32(255.0 * (1.0 - ramp.opacity))
    colour = apply_ramp(ramp, (inner - np.float32(lo)) / np.float32(hi - lo))
    blended = colour[..., :3] * np.float32(ramp.opacity) + grey[..., None]
    out = np.empty(inner.shape + (4,), dtype=np.uint8)
    out[..., :3] = np.clip(blended, 0, 255)
    out[..., 3] = np.where(np.isfinite(inner), 255, 0)
    return out


def stretch(band: NDArray[Any], lo: float, hi: float) -> NDArray[np.uint8]:
    """Linear stretch of ``lo…hi`` to 0…255 (NaN → 0)."""
    with np.errstate(invalid="ignore"):
        v = (band - lo) * (255.0 / (hi - lo))
    return np.clip(np.nan_to_num(v, nan=0.0), 0, 255).astype(np.uint8)


def image_rgba(data: NDArray[Any], stats: Sequence[Tuple[float, float]],
               eight_bit: bool) -> NDArray[np.uint8]:
    """RGBA of 1 (grey) or 3 (colour) bands; 8-bit colour as is, else stretched."""
    rows, cols = data.shape[1:]
    out = np.empty((rows, cols, 4), dtype=np.uint8)
    for ch in range(3):
        b = data[min(ch, data.shape[0] - 1)]
        if eight_bit and data.shape[0] >= 3:
            out[..., ch] = np.nan_to_num(b, nan=0.0).astype(np.uint8)
        else:
            out[..., ch] = stretch(b, *stats[min(ch, len(stats) - 1)])
    out[..., 3] = np.where(np.all(np.isfinite(data), axis=0), 255, 0)
    return out


@dataclass(frozen=True)
class Style:
    """How one raster is coloured: its kind and the statistics of its bands."""

    kind: str
    stats: Tuple[Tuple[float, float], ...]
    eight_bit: bool = True

    @property
    def margin(self) -> int:
        """Pixels read around a tile: 1 for the hillshade of a DEM."""
        return 1 if self.kind in DEM_KINDS else 0


def colorize(style: Style, data: NDArray[Any], grid_transform: Affine,
             map_crs: str = "") -> NDArray[np.uint8]:
    """RGBA ``(rows, cols, 4)`` of a tile read with :func:`read_tile` (margin per ``style``)."""
    if style.kind in DEM_KINDS:
        dx, dy = _cell_size(grid_transform, map_crs, data.shape[1] - 2)
        lo, hi = style.stats[0]
        return dem_rgba(data[0], dx, dy, lo, hi)
    if style.kind == "difference":
        return apply_ramp(difference_ramp(), data[0])
    return image_rgba(data, style.stats, style.eight_bit)


def make_style(src: Any, info: RasterInfo, kind: str) -> Style:
    """The :class:`Style` of a raster (statistics read once, see :func:`band_stats`)."""
    eight_bit = info.dtype in ("uint8", "int8")
    colour_8bit = eight_bit and info.rgb_bands and kind not in DEM_KINDS
    needs_stats = kind != "difference" and not colour_8bit
    stats = tuple(band_stats(src, info, kind)) if needs_stats else ((0.0, 255.0),)
    return Style(kind, stats, eight_bit)


def render_tile(src: Any, info: RasterInfo, grid: TileGrid, style: Style,
                key: Tuple[int, int, int], map_crs: str = "") -> NDArray[np.uint8]:
    """Read and colour the tile ``key``: RGBA ``(TILE, TILE, 4)`` uint8."""
    data = read_tile(src, info, grid, style.kind, key, style.margin, map_crs)
    level, col, row = key
    transform = grid.level_transform(level) * Affine.translation(col * TILE - style.margin,
                                                                 row * TILE - style.margin)
    return colorize(style, data, transform, map_crs)


# -- overviews ----------------------------------------------------------------------------------
def overview_sidecar(path: PathLike) -> Path:
    """The external overview file GDAL reads for ``path``: ``<name>.ovr``."""
    path = Path(path)
    return path.with_name(path.name + ".ovr")


def build_external_overviews(path: PathLike, feedback: Optional[Feedback] = None) -> Path:
    """Build overviews of ``path`` into its ``.ovr`` sidecar; the raster is not touched.

    GDAL writes them to the sidecar, not into the file (``TIFF_USE_OVR``). They are built
    under a hidden temporary name (through a symbolic link to the raster) and renamed when complete,
    so a failed build leaves no half-written ``.ovr``.

    Raises
    ------
    InputError
        The raster or its folder is read-only, or an ``.ovr`` exists already.
    """
    feedback = ensure_feedback(feedback)
    path = Path(path).resolve()
    target = overview_sidecar(path)
    if target.exists():
        raise InputError(f"'{target.name}' exists already; remove it to rebuild the overviews.")
    if not os.access(path, os.W_OK):
        raise InputError(f"'{path.name}' is read-only: GDAL opens it for writing to build "
                         "overviews (into the sidecar only). Build them with "
                         f"'gdaladdo -ro {path.name}' instead.")
    if not os.access(path.parent, os.W_OK):
        raise InputError(f"The folder of '{path.name}' is read-only: overviews cannot be "
                         f"written beside it ({path.parent}).")
    link = path.with_name(f".{path.name}.{os.getpid()}.partial{path.suffix}")
    feedback.progress(0.0)
    try:
        os.symlink(path, link)
        env = rasterio.Env(TIFF_USE_OVR=True, GDAL_TIF_OVR_BLOCKSIZE=256,
                           COMPRESS_OVERVIEW="DEFLATE", INTERLEAVE_OVERVIEW="PIXEL",
                           BIGTIFF_OVERVIEW="IF_SAFER")
        # update mode only lets GDAL build overviews; TIFF_USE_OVR sends them to the sidecar
        with env, rasterio.open(link, "r+") as src:
            src.build_overviews(overview_factors(src.width, src.height), Resampling.average)
        os.replace(overview_sidecar(link), target)
    finally:
        link.unlink(missing_ok=True)
        overview_sidecar(link).unlink(missing_ok=True)
    feedback.progress(100.0)
    return target
