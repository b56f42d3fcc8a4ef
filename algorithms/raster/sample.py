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
import rasterio
from affine import Affine
from numpy.typing import ArrayLike, NDArray
from rasterio.windows import Window, from_bounds

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


#: edge policies of :func:`bilinear_grid`
EDGES = ("nan", "clamp")
#: NaN policies: a NaN neighbour spoils the value when its weight is non-zero / always
NODATA = ("weighted", "any")
#: evaluation orders of the four-neighbour formula (they differ in the last bits only)
ORDERS = ("weights", "rows", "columns")


def bilinear_grid(array: NDArray, col: ArrayLike, row: ArrayLike, *, edge: str = "nan",
                  nodata: str = "weighted", order: str = "weights") -> Array:
    r"""Bilinear interpolation of a 2-D array at fractional (col, row), centres at integers.

    The one bilinear sampler of the package; callers state their choices explicitly.

    Parameters
    ----------
    array : ndarray, shape (rows, cols)
        Values; NaN is nodata. Gathered values are converted to float64.
    col, row : array_like
        Fractional positions (broadcast against each other). A ``row`` of shape (m, 1) and a
        ``col`` of shape (1, n) with ``order="rows"`` take a separable path (one gathered row
        pair per output row) with the same values.
    edge : {"nan", "clamp"}
        Outside ``0 ≤ col ≤ width−1, 0 ≤ row ≤ height−1``: ``"nan"`` gives NaN; ``"clamp"``
        moves the position onto the nearest edge of the hull of cell centres first (the outer
        half cells take the edge values). NaN positions give NaN either way.
    nodata : {"weighted", "any"}
        ``"weighted"``: NaN only where a neighbour with non-zero weight is NaN (exactly at a
        valid cell centre, NaN neighbours do not matter); ``"any"``: NaN where any of the four
        neighbours is NaN.
    order : {"weights", "rows", "columns"}
        How the four neighbours :math:`z_{00}, z_{01}, z_{10}, z_{11}` are combined — the same
        formula, rounded differently:
        ``"weights"`` :math:`\sum w_k z_k` with :math:`w_{00} = (1-f_r)(1-f_c)` …;
        ``"rows"`` first between the rows, then between the columns;
        ``"columns"`` first between the columns, then between the rows
        (each step :math:`(1-f)\,a + f\,b`).

    Returns
    -------
    ndarray
        Interpolated values (float64), shape of the broadcast positions.
    """
    _check_choice("edge", edge, EDGES)
    _check_choice("nodata", nodata, NODATA)
    _check_choice("order", order, ORDERS)
    a = np.asarray(array)
    if a.ndim != 2:
        raise ValueError("bilinear sampling needs a 2-D array")
    h, w = a.shape
    col = np.asarray(col, dtype=float)
    row = np.asarray(row, dtype=float)
    if edge == "clamp":
        col = np.clip(col, 0.0, w - 1.0)
        row = np.clip(row, 0.0, h - 1.0)
    col_in = (col >= 0) & (col <= w - 1)  # NaN compares False
    row_in = (row >= 0) & (row <= h - 1)
    if order == "rows" and col.ndim == 2 and row.ndim == 2 and col.shape[0] == 1 \
            and row.shape[1] == 1:
        return _separable_rows(a, _Axis(col[0], col_in[0], w), _Axis(row[:, 0], row_in[:, 0], h),
                               nodata == "weighted")
    inside = col_in & row_in
    cx = _Axis(np.where(inside, col, 0.0), inside, w)
    rx = _Axis(np.where(inside, row, 0.0), inside, h)
    z00 = a[rx.i0, cx.i0].astype(float)
    z01 = a[rx.i0, cx.i1].astype(float)
    z10 = a[rx.i1, cx.i0].astype(float)
    z11 = a[rx.i1, cx.i1].astype(float)
    skip = nodata == "weighted"
    fc, fr = cx.f, rx.f
    if order == "weights":
        term = _term if skip else np.multiply
        z = (term((1.0 - fr) * (1.0 - fc), z00) + term((1.0 - fr) * fc, z01)
             + term(fr * (1.0 - fc), z10) + term(fr * fc, z11))
    elif order == "rows":
        z = _lerp(_lerp(z00, z10, fr, skip), _lerp(z01, z11, fr, skip), fc, skip)
    else:
        z = _lerp(_lerp(z00, z01, fc, skip), _lerp(z10, z11, fc, skip), fr, skip)
    return np.where(inside, z, np.nan)


class _Axis:
    """Neighbour indices and fraction along one axis of :func:`bilinear_grid`.

    ``i0`` is clipped so that the last row/column still has a partner ``i1 = i0 + 1``;
    ``f = pos − i0`` (in [0, 1] inside). ``inside`` is kept for the caller.
    """

    def __init__(self, pos: Array, inside: NDArray[np.bool_], n: int) -> None:
        self.pos = np.where(inside, pos, 0.0)
        self.inside = inside
        self.i0 = np.clip(np.floor(self.pos).astype(np.intp), 0, max(n - 2, 0))
        self.i1 = np.minimum(self.i0 + 1, n - 1)
        self.f = self.pos - self.i0


def _separable_rows(a: NDArray, cx: _Axis, rx: _Axis, skip: bool) -> Array:
    """``order="rows"`` on the grid ``rx.pos`` (rows) × ``cx.pos`` (columns): every output row
    interpolates its two gathered array rows once (full width), then between the columns."""
    rows = _lerp(a[rx.i0].astype(float), a[rx.i1].astype(float), rx.f[:, None], skip)
    z = _lerp(rows[:, cx.i0], rows[:, cx.i1], cx.f[None, :], skip)
    z[~rx.inside, :] = np.nan
    z[:, ~cx.inside] = np.nan
    return z


def _check_choice(name: str, value: str, allowed: Tuple[str, ...]) -> None:
    if value not in allowed:
        raise ValueError(f"bilinear_grid: {name} must be one of {', '.join(allowed)}, "
                         f"not {value!r}")


def _term(weight: Array, value: Array) -> Array:
    """weight·value, but 0 where the weight is 0 (a NaN neighbour that does not contribute,
    e.g. exactly at a valid cell centre, must not turn the result into NaN)."""
    return np.where(weight == 0.0, 0.0, weight * value)


def _lerp(a: Array, b: Array, f: Array, skip: bool) -> Array:
    """(1 − f)·a + f·b; with ``skip`` a term of weight 0 contributes 0 even if its value is
    NaN (computed only when the plain formula gives a NaN: the same values otherwise)."""
    out = (1.0 - f) * a + f * b
    if skip and np.isnan(out).any():
        out = (np.where(f == 1.0, 0.0, (1.0 - f) * a) + np.where(f == 0.0, 0.0, f * b))
    return out


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
