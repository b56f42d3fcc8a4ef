"""Horn's 3 × 3 gradient, slope and illumination of a height grid (the maths is in
:mod:`..quality.rasters`, which writes hillshade and slope rasters with it; the map view of the
standalone tool shades DEM tiles with it, :mod:`.display`)."""

from __future__ import annotations

import math
from typing import Any, Tuple, Union

import numpy as np
from numpy.typing import NDArray


def horn_gradient(z: NDArray[Any], dx: Union[float, NDArray[Any]],
                  dy: float) -> Tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Horn's gradient (p = ∂z/∂x eastwards, q = ∂z/∂y northwards) of the inner cells.

    Parameters
    ----------
    z : ndarray, shape (rows + 2, cols + 2)
        Heights with a 1-cell margin on every side (NaN = nodata).
    dx : float or ndarray, shape (rows, 1)
        Cell width in metres (per row in a geographic CRS).
    dy : float
        Cell height in metres (positive).

    Returns
    -------
    p, q : ndarray, shape (rows, cols)
        NaN where any of the 9 cells is NaN.
    """
    z = np.asarray(z, dtype=np.float64)
    a, b, c = z[:-2, :-2], z[:-2, 1:-1], z[:-2, 2:]
    d, f = z[1:-1, :-2], z[1:-1, 2:]
    g, h, i = z[2:, :-2], z[2:, 1:-1], z[2:, 2:]
    e = z[1:-1, 1:-1]
    p = ((c + 2.0 * f + i) - (a + 2.0 * d + g)) / (8.0 * dx)
    q = ((a + 2.0 * b + c) - (g + 2.0 * h + i)) / (8.0 * dy)
    bad = np.isnan(e)  # p, q are NaN already where a neighbour is NaN
    p[bad] = np.nan
    q[bad] = np.nan
    return p, q


def slope_degrees(p: NDArray[Any], q: NDArray[Any]) -> NDArray[np.float64]:
    """Slope angle S = arctan √(p² + q²) in degrees."""
    return np.degrees(np.arctan(np.hypot(p, q)))


def shade(p: NDArray[Any], q: NDArray[Any], azimuth: float = 315.0,
          altitude: float = 45.0) -> NDArray[np.float64]:
    """Illumination n·L in 0…1 (0 in the shadow side), NaN where p or q is NaN."""
    az, alt = math.radians(azimuth), math.radians(altitude)
    lx, ly, lz = math.sin(az) * math.cos(alt), math.cos(az) * math.cos(alt), math.sin(alt)
    value = (lz - p * lx - q * ly) / np.sqrt(1.0 + p * p + q * q)
    return np.clip(value, 0.0, 1.0)


