r"""Sampling rasters (DEMs above all) at world coordinates.

Everyone samples DEMs through this module: :func:`bilinear` for an array plus its affine
geotransform, :class:`DemSampler` for a DEM held in memory (read by window from a file).

Pixel centres: with a rasterio/GDAL ``transform`` the fractional pixel position of a world
point is :math:`(c', r') = T^{-1}(x, y)`, and the centre of cell ``[i, j]`` lies at
:math:`(c', r') = (j + 0.5, i + 0.5)`. Bilinear interpolation between the four surrounding cell
centres :math:`z_{00}, z_{01}, z_{10}, z_{11}` with fractions :math:`f_c, f_r \in [0, 1]`:

.. math::

   z = (1-f_r)\,[(1-f_c)\,z_{00} + f_c\,z_{01}] + f_r\,[(1-f_c)\,z_{10} + f_c\,z_{11}]

A point outside the hull of cell centres, or with a NaN neighbour of non-zero weight, gives NaN.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional, Tuple, Union

import numpy as np
from affine import Affine
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError

Array = NDArray[np.float64]


def world_to_grid(transform: Affine, x: ArrayLike, y: ArrayLike) -> Tuple[Array, Array]:
    """World (x, y) → fractional (col, row) with cell centres at integer values."""
    inv = ~transform
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    col = inv.a * x + inv.b * y + inv.c - 0.5
    row = inv.d * x + inv.e * y + inv.f - 0.5
    return col, row


def grid_to_world(transform: Affine, col: ArrayLike, row: ArrayLike) -> Tuple[Array, Array]:
    """Cell (col, row) with centres at integer values → world (x, y)."""
    c = np.asarray(col, dtype=float) + 0.5
    r = np.asarray(row, dtype=float) + 0.5
    t = transform
    return t.a * c + t.b * r + t.c, t.d * c + t.e * r + t.f


def bilinear_grid(array: NDArray, col: ArrayLike, row: ArrayLike) -> Array:
    """Bilinear interpolation of a 2-D array at fractional (col, row), centres at integers.

    NaN outside ``0 ≤ col ≤ width−1, 0 ≤ row ≤ height−1`` and wherever one of the four
    neighbours with non-zero weight is NaN.
    """
    a = np.asarray(array)
    if a.ndim != 2:
        raise ValueError("bilinear sampling needs a 2-D array")
    h, w = a.shape
    col = np.asarray(col, dtype=float)
    row = np.asarray(row, dtype=float)
    inside = (col >= 0) & (col <= w - 1) & (row >= 0) & (row <= h - 1)  # NaN compares False
    c = np.where(inside, col, 0.0)
    r = np.where(inside, row, 0.0)
    # the lower-left neighbour index is clipped so that the last row/column still has a partner
    c0 = np.clip(np.floor(c).astype(np.intp), 0, max(w - 2, 0))
    r0 = np.clip(np.floor(r).astype(np.intp), 0, max(h - 2, 0))
    c1 = np.minimum(c0 + 1, w - 1)
    r1 = np.minimum(r0 + 1, h - 1)
    fc = c - c0
    fr = r - r0
    z00 = a[r0, c0].astype(float)
    z01 = a[r0, c1].astype(float)
    z10 = a[r1, c0].astype(float)
    z11 = a[r1, c1].astype(float)
    z = (_term((1.0 - fr) * (1.0 - fc), z00) + _term((1.0 - fr) * fc, z01)
         + _term(fr * (1.0 - fc), z10) + _term(fr * fc, z11))
    return np.where(inside, z, np.nan)


def _term(weight: Array, value: Array) -> Array:
    """weight·value, but 0 where the weight is 0 (a NaN neighbour that does not contribute,
    e.g. exactly at a valid cell centre, must not turn the result into NaN)."""
    return np.where(weight == 0.0, 0.0, weight * value)


def bilinear(array: NDArray, transform: Affine, x: ArrayLike, y: ArrayLike) -> Array:
    """Sample a 2-D raster bilinearly at world coordinates.

    Parameters
    ----------
    array : ndarray, shape (rows, cols)
        Raster values; NaN is nodata.
    transform : affine.Affine
        Geotransform (GDAL convention: maps the corner of cell [0, 0] at (0, 0)).
    x, y : array_like
        World coordinates (broadcast against each other).

    Returns
    -------
    ndarray
        Interpolated values, NaN outside the hull of cell centres or next to nodata.
    """
    col, row = world_to_grid(transform, x, y)
    return bilinear_grid(array, col, row)


class DemSampler:
    """A DEM in memory: heights at world coordinates, height range, cell size.

    Parameters
    ----------
    array : ndarray, shape (rows, cols)
        Heights; NaN (or ``nodata``) marks missing cells. Stored as float64.
    transform : affine.Affine
        Geotransform of the array.
    crs : object, optional
        The CRS (kept for the caller; not used for sampling).
    nodata : float, optional
        A value to turn into NaN.
    """

    def __init__(self, array: ArrayLike, transform: Affine, crs: object = None,
                 nodata: Optional[float] = None) -> None:
        a = np.array(array, dtype=float)
        if a.ndim != 2 or min(a.shape) < 2:
            raise InputError("A DEM needs at least 2 × 2 cells.")
        if nodata is not None and not np.isnan(nodata):
            a[a == nodata] = np.nan
        if not np.isfinite(a).any():
            raise InputError("The DEM holds no valid height (all cells are nodata).")
        self.array = a
        self.transform = transform
        self.crs = crs
        self._min = float(np.nanmin(a))
        self._max = float(np.nanmax(a))

    @classmethod
    def from_file(cls, path: Union[str, Path],
                  bounds: Optional[Tuple[float, float, float, float]] = None,
                  band: int = 1, margin_cells: int = 2) -> DemSampler:
        """Read a DEM (or only the window covering ``bounds``) with rasterio.

        Parameters
        ----------
        path : path
            Any raster rasterio reads.
        bounds : (xmin, ymin, xmax, ymax), optional
            World extent needed; the window read covers it plus ``margin_cells`` cells.
        band : int
            Band number (1-based).
        """
        import rasterio
        from rasterio.windows import Window, from_bounds

        path = Path(path)
        if not path.is_file():
            raise InputError(f"DEM '{path}' does not exist.")
        with rasterio.open(path) as src:
            if bounds is None:
                window = Window(0, 0, src.width, src.height)
            else:
                win = from_bounds(*bounds, transform=src.transform)
                col0 = int(np.floor(win.col_off)) - margin_cells
                row0 = int(np.floor(win.row_off)) - margin_cells
                col1 = int(np.ceil(win.col_off + win.width)) + margin_cells
                row1 = int(np.ceil(win.row_off + win.height)) + margin_cells
                col0, row0 = max(col0, 0), max(row0, 0)
                col1, row1 = min(col1, src.width), min(row1, src.height)
                if col1 - col0 < 2 or row1 - row0 < 2:
                    raise InputError(
                        f"The DEM '{path.name}' does not cover the area {bounds}; use a DEM "
                        "that covers the images' footprints."
                    )
                window = Window(col0, row0, col1 - col0, row1 - row0)
            data = src.read(band, window=window, masked=True).astype(float).filled(np.nan)
            return cls(data, src.window_transform(window), crs=src.crs)

    # -- properties ----------------------------------------------------------------------------
    @property
    def min(self) -> float:
        """Lowest valid height."""
        return self._min

    @property
    def max(self) -> float:
        """Highest valid height."""
        return self._max

    @property
    def shape(self) -> Tuple[int, int]:
        return self.array.shape  # type: ignore[return-value]

    @property
    def cell_size(self) -> float:
        """The smaller ground size of a cell (m), also for rotated transforms."""
        t = self.transform
        return float(min(np.hypot(t.a, t.d), np.hypot(t.b, t.e)))

    @property
    def bounds(self) -> Tuple[float, float, float, float]:
        """Extent (xmin, ymin, xmax, ymax) of the cell centres, where sampling is defined."""
        h, w = self.shape
        x, y = grid_to_world(self.transform, [0, w - 1, w - 1, 0], [0, 0, h - 1, h - 1])
        return float(x.min()), float(y.min()), float(x.max()), float(y.max())

    # -- sampling ------------------------------------------------------------------------------
    def height(self, x: ArrayLike, y: ArrayLike) -> Array:
        """Bilinear height at world (x, y); NaN outside or next to nodata."""
        return bilinear(self.array, self.transform, x, y)

    def __repr__(self) -> str:
        h, w = self.shape
        return (f"DemSampler({w}×{h} cells of {self.cell_size:g} m, "
                f"heights {self.min:.2f}…{self.max:.2f})")
