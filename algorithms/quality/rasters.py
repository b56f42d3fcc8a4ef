r"""Rasters that help judge a DEM: hillshade, slope, and the colour style of a difference model.

Both derivatives use Horn's 3 × 3 gradient. With the neighbourhood

.. code-block:: text

    a b c
    d e f        (rows run southwards, columns eastwards)
    g h i

.. math::

   p = \frac{\partial z}{\partial x} = \frac{(c + 2f + i) - (a + 2d + g)}{8\,\Delta x},\qquad
   q = \frac{\partial z}{\partial y} = \frac{(a + 2b + c) - (g + 2h + i)}{8\,\Delta y}

(:math:`y` northwards). The slope is :math:`S = \arctan\sqrt{p^2 + q^2}`; the hillshade is the
cosine between the surface normal :math:`n = (-p, -q, 1)/\sqrt{1 + p^2 + q^2}` and the unit
vector towards the sun
:math:`L = (\sin A\cos h,\ \cos A\cos h,\ \sin h)` (azimuth :math:`A` clockwise from north,
altitude :math:`h`), clipped at 0 and scaled to 1…255 (0 is nodata).

Rasters are processed window by window with a 1-cell margin, so memory is bounded by
``window_size`` and not by the DEM. A cell with a nodata neighbour is nodata; at the raster edge
the edge row/column is repeated (as GDAL's ``-compute_edges``). In a geographic CRS the cell
size is converted to metres per row (:math:`\Delta x = \Delta\lambda\cdot 111\,320\cos\varphi`).

The difference style (:data:`DIFFERENCE_CLASSES`) follows the convention operators know from
DEM acceptance (Raguse 2000): a neutral (pale yellow) class for :math:`|\Delta h| \le 0.25` m,
blue below (DEM lower than the reference), red above, classes to ±5 m.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Tuple, Union

import numpy as np
import rasterio
from numpy.typing import NDArray
from rasterio.windows import Window

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from ..raster.io import atomic_output, gtiff_profile, open_image
from ..raster.terrain import horn_gradient, shade, slope_degrees  # re-exported below

PathLike = Union[str, Path]

#: Metres per degree of latitude (mean) and of longitude at the equator (WGS 84).
_M_PER_DEG_LAT = 110_574.0
_M_PER_DEG_LON = 111_320.0

#: Classes of the difference style: (upper bound in m, colour, label); the last bound is +inf.
#: Blue below (DEM lower than the reference), pale yellow ±0.25 m, red above.
DIFFERENCE_CLASSES: Tuple[Tuple[float, str, str], ...] = (
    (-5.0, "#08306b", "< −5 m"),
    (-3.0, "#2166ac", "−5 … −3 m"),
    (-2.0, "#4393c3", "−3 … −2 m"),
    (-1.0, "#92c5de", "−2 … −1 m"),
    (-0.5, "#c6dbef", "−1 … −0.5 m"),
    (-0.25, "#e3eef8", "−0.5 … −0.25 m"),
    (0.25, "#ffffbf", "−0.25 … +0.25 m"),
    (0.5, "#fee0b6", "+0.25 … +0.5 m"),
    (1.0, "#fdb863", "+0.5 … +1 m"),
    (2.0, "#f4a582", "+1 … +2 m"),
    (3.0, "#d6604d", "+2 … +3 m"),
    (5.0, "#b2182b", "+3 … +5 m"),
    (math.inf, "#67001f", "> +5 m"),
)


def difference_bounds() -> List[float]:
    """Class boundaries of :data:`DIFFERENCE_CLASSES` (finite ones, ascending, m)."""
    return [b for b, _, _ in DIFFERENCE_CLASSES if math.isfinite(b)]


def difference_colors() -> List[str]:
    """Colours of :data:`DIFFERENCE_CLASSES`, lowest class first."""
    return [c for _, c, _ in DIFFERENCE_CLASSES]


def difference_style_qml() -> str:
    """The QGIS (≥ 3.22) raster style of a difference model as QML text.

    A single-band pseudocolour renderer with a *discrete* colour ramp: a cell takes the colour
    of the first class whose upper bound is ≥ its value.
    """
    def esc(text: str) -> str:
        return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")

    items = []
    for bound, colour, label in DIFFERENCE_CLASSES:
        value = "inf" if math.isinf(bound) else f"{bound:g}"
        items.append(f'          <item alpha="255" value="{value}" label="{esc(label)}" '
                     f'color="{colour}"/>')
    lo, hi = difference_bounds()[0], difference_bounds()[-1]
    return "\n".join([
        "<!DOCTYPE qgis PUBLIC 'http://mrcc.com/qgis.dtd' 'SYSTEM'>",
        '<qgis version="3.22.0" styleCategories="AllStyleCategories" '
        'hasScaleBasedVisibilityFlag="0" minScale="1e+08" maxScale="0">',
        "  <pipe>",
        f'    <rasterrenderer type="singlebandpseudocolor" band="1" opacity="1" '
        f'alphaBand="-1" classificationMin="{lo:g}" classificationMax="{hi:g}" '
        'nodataColor="">',
        "      <rasterTransparency/>",
        "      <minMaxOrigin>",
        "        <limits>None</limits>",
        "        <extent>WholeRaster</extent>",
        "        <statAccuracy>Estimated</statAccuracy>",
        "        <cumulativeCutLower>0.02</cumulativeCutLower>",
        "        <cumulativeCutUpper>0.98</cumulativeCutUpper>",
        "        <stdDevFactor>2</stdDevFactor>",
        "      </minMaxOrigin>",
        "      <rastershader>",
        f'        <colorrampshader colorRampType="DISCRETE" classificationMode="1" '
        f'clip="0" minimumValue="{lo:g}" maximumValue="{hi:g}" labelPrecision="2">',
        *items,
        "        </colorrampshader>",
        "      </rastershader>",
        "    </rasterrenderer>",
        '    <brightnesscontrast brightness="0" contrast="0" gamma="1"/>',
        '    <huesaturation saturation="0" grayscaleMode="0" colorizeOn="0" '
        'colorizeRed="255" colorizeGreen="128" colorizeBlue="128" colorizeStrength="100"/>',
        '    <rasterresampler maxOversampling="2"/>',
        "  </pipe>",
        "  <blendMode>0</blendMode>",
        "</qgis>",
        "",
    ])


def style_path() -> Path:
    """The packaged style ``resources/styles/dem_difference.qml``."""
    return Path(__file__).resolve().parents[2] / "resources" / "styles" / "dem_difference.qml"


def write_difference_style(raster: PathLike) -> Path:
    """Write the difference style beside ``raster`` as ``<stem>.qml``.

    QGIS applies a ``.qml`` of the same base name automatically when the raster is added.
    """
    target = Path(raster).with_suffix(".qml")
    with atomic_output(target) as tmp:
        tmp.write_text(difference_style_qml(), encoding="utf-8")
    return target


# -- window by window ---------------------------------------------------------------------------
def _profile(src: Any, dtype: str, nodata: float) -> Dict[str, Any]:
    return gtiff_profile(src.width, src.height, 1, dtype, src.crs, nodata=nodata,
                         transform=src.transform,
                         predictor=3 if dtype.startswith("float") else 2)


def _cell_metres(src: Any, row0: int, rows: int) -> Tuple[Union[float, NDArray[Any]], float]:
    """Cell width (per row if geographic) and height in metres for rows row0…row0+rows−1."""
    t = src.transform
    if abs(t.b) > 1e-12 or abs(t.d) > 1e-12:
        raise InputError("The DEM has a rotated geotransform; warp it to a north-up grid first "
                         "(e.g. gdalwarp).")
    dx, dy = abs(t.a), abs(t.e)
    if src.crs is not None and src.crs.is_geographic:
        lat = t.f + t.e * (np.arange(row0, row0 + rows) + 0.5)
        dx_m = dx * _M_PER_DEG_LON * np.cos(np.radians(lat))[:, None]
        return np.maximum(dx_m, 1e-6), dy * _M_PER_DEG_LAT
    return dx, dy


def _read_with_margin(src: Any, row0: int, col0: int, rows: int, cols: int) -> NDArray[Any]:
    """Heights of a window plus a 1-cell margin; outside the raster the edge is repeated."""
    r0, c0 = max(row0 - 1, 0), max(col0 - 1, 0)
    r1, c1 = min(row0 + rows + 1, src.height), min(col0 + cols + 1, src.width)
    data = src.read(1, window=Window(c0, r0, c1 - c0, r1 - r0), masked=True)
    z = np.ma.filled(data.astype(np.float64), np.nan)
    pad = ((r0 - (row0 - 1), (row0 + rows + 1) - r1), (c0 - (col0 - 1), (col0 + cols + 1) - c1))
    if any(v for side in pad for v in side):
        z = np.pad(z, pad, mode="edge")
    return z


def _map_windows(dem: PathLike, output: PathLike, dtype: str, nodata: float,
                 func: Callable[[NDArray[Any], Any, float], NDArray[Any]],
                 window_size: int, feedback: Optional[Feedback]) -> Path:
    """Apply ``func(z_with_margin, dx, dy)`` window by window and write ``output`` atomically."""
    feedback = ensure_feedback(feedback)
    dem = Path(dem)
    if not dem.is_file():
        raise InputError(f"DEM '{dem}' does not exist.")
    # whole 256-cell tiles per window: the tiled output is written without re-reading blocks
    size = max(256, -(-int(window_size) // 256) * 256)
    with rasterio.open(dem) as src:
        profile = _profile(src, dtype, nodata)
        windows = [(r, c, min(size, src.height - r), min(size, src.width - c))
                   for r in range(0, src.height, size) for c in range(0, src.width, size)]
        with atomic_output(output) as tmp, open_image(tmp, "w", **profile) as dst:
            for k, (r, c, h, w) in enumerate(windows):
                z = _read_with_margin(src, r, c, h, w)
                dx, dy = _cell_metres(src, r, h)
                dst.write(func(z, dx, dy).astype(dtype)[None], window=Window(c, r, w, h))
                feedback.progress(100.0 * (k + 1) / len(windows))
    return Path(output)


def write_slope(dem: PathLike, output: PathLike, *, window_size: int = 1024,
                feedback: Optional[Feedback] = None) -> Path:
    """Slope of a DEM in degrees (float32, NaN nodata), window by window.

    Parameters
    ----------
    dem : path
        Input DEM (any raster rasterio reads; band 1; nodata honoured).
    output : path
        GeoTIFF to write (atomically: nothing is left behind on failure or cancel).
    window_size : int
        Cells per window side (rounded up to whole 256-cell tiles); bounds the memory.
    """
    def func(z: NDArray[Any], dx: Any, dy: float) -> NDArray[Any]:
        return slope_degrees(*horn_gradient(z, dx, dy))

    return _map_windows(dem, output, "float32", float("nan"), func, window_size, feedback)


def write_hillshade(dem: PathLike, output: PathLike, *, azimuth: float = 315.0,
                    altitude: float = 45.0, z_factor: float = 1.0, window_size: int = 1024,
                    feedback: Optional[Feedback] = None) -> Path:
    """Hillshade of a DEM (uint8: 1 = full shadow … 255 = facing the sun, 0 = nodata).

    Parameters
    ----------
    azimuth : float
        Direction the light comes from, degrees clockwise from north (315 = north-west).
    altitude : float
        Sun elevation above the horizon (degrees).
    z_factor : float
        Vertical exaggeration.
    """
    def func(z: NDArray[Any], dx: Any, dy: float) -> NDArray[Any]:
        p, q = horn_gradient(z, dx, dy)
        s = shade(z_factor * p, z_factor * q, azimuth, altitude)
        return np.where(np.isnan(s), 0, 1.0 + np.round(254.0 * np.nan_to_num(s)))

    return _map_windows(dem, output, "uint8", 0, func, window_size, feedback)


__all__ = [
    "DIFFERENCE_CLASSES",
    "difference_bounds",
    "difference_colors",
    "difference_style_qml",
    "horn_gradient",
    "shade",
    "slope_degrees",
    "style_path",
    "write_difference_style",
    "write_hillshade",
    "write_slope",
]
