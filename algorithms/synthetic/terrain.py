r"""Truth terrain (bare-earth heights) of a synthetic block, and the grid it lives on.

Three terrain types:

* ``gentle`` — trend of ≈ 0.5 %, long-wave undulation (±1.5 m, λ ≈ 150 m) and a smooth open
  hill (+6.5 m, Gaussian);
* ``dunes`` — two trains of asymmetric dunes on a gentle trend: crest lines are sinuous
  (their phase is perturbed by long-wave noise), the stoss side rises over 80 % of a
  wavelength, the lee side falls over 20 % (lee slopes ≈ 30°); relief 2–10 m;
* ``steep`` — rough mountain terrain: a fractal sum of octaves (amplitude ∝ λ^0.9) scaled to a
  relief of ≈ 120 m, plus cliff bands (steps of 8–15 m over 2–3 m horizontally, > 70°) and
  small-scale roughness; slopes of 45° and more are common.

Band-limited noise (:func:`band_noise`) is white noise on a coarse lattice of spacing λ/4,
smoothed and interpolated by separable cubic convolution to the fine grid — cheap for any
grid size.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Tuple

import numpy as np
from affine import Affine
from scipy import ndimage

TERRAIN_TYPES = ("gentle", "dunes", "steep")


@dataclass(frozen=True)
class Grid:
    """A north-up raster grid in the project CRS.

    Attributes
    ----------
    x0, y1 : float
        West and north edges (m).
    cell : float
        Cell size (m).
    nrows, ncols : int
    """

    x0: float
    y1: float
    cell: float
    nrows: int
    ncols: int

    @property
    def transform(self) -> Affine:
        return Affine(self.cell, 0.0, self.x0, 0.0, -self.cell, self.y1)

    @property
    def shape(self) -> Tuple[int, int]:
        return self.nrows, self.ncols

    @property
    def xs(self) -> np.ndarray:
        """Cell-centre X of the columns, shape (1, ncols)."""
        return (self.x0 + (np.arange(self.ncols) + 0.5) * self.cell)[None, :]

    @property
    def ys(self) -> np.ndarray:
        """Cell-centre Y of the rows, shape (nrows, 1)."""
        return (self.y1 - (np.arange(self.nrows) + 0.5) * self.cell)[:, None]

    @property
    def bounds(self) -> Tuple[float, float, float, float]:
        return (self.x0, self.y1 - self.nrows * self.cell, self.x0 + self.ncols * self.cell,
                self.y1)

    def index(self, x: np.ndarray, y: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
        """Fractional (col, row) of world points, cell centres at integers."""
        col = (np.asarray(x) - self.x0) / self.cell - 0.5
        return col, (self.y1 - np.asarray(y)) / self.cell - 0.5

    def window(self, xmin: float, ymin: float, xmax: float, ymax: float
               ) -> Tuple[slice, slice]:
        """Row and column slices of the cells whose centres may lie in a box (clipped)."""
        c0 = max(int(np.floor((xmin - self.x0) / self.cell)) - 1, 0)
        c1 = min(int(np.ceil((xmax - self.x0) / self.cell)) + 1, self.ncols)
        r0 = max(int(np.floor((self.y1 - ymax) / self.cell)) - 1, 0)
        r1 = min(int(np.ceil((self.y1 - ymin) / self.cell)) + 1, self.nrows)
        return slice(r0, max(r1, r0)), slice(c0, max(c1, c0))


def band_noise(rng: np.random.Generator, grid: Grid, wavelength: float) -> np.ndarray:
    """Smooth random field with unit standard deviation and features of size ≈ ``wavelength``.

    Returns
    -------
    ndarray, float32, shape ``grid.shape``
    """
    lattice = max(wavelength / 4.0, grid.cell)
    factor = lattice / grid.cell
    shape = (int(np.ceil(grid.nrows / factor)) + 6, int(np.ceil(grid.ncols / factor)) + 6)
    coarse = rng.standard_normal(shape)
    coarse = ndimage.gaussian_filter(coarse, sigma=1.2, mode="wrap")
    coarse /= coarse.std() + 1e-12
    if factor <= 1.0 + 1e-9:
        return coarse[3:3 + grid.nrows, 3:3 + grid.ncols].astype(np.float32)
    # separable cubic convolution of the lattice at the fine cell centres
    rows = 3.0 + (np.arange(grid.nrows) + 0.5) / factor - 0.5
    cols = 3.0 + (np.arange(grid.ncols) + 0.5) / factor - 0.5
    tmp = _cubic_axis(coarse.astype(np.float32), rows, axis=0)
    return _cubic_axis(tmp, cols, axis=1)


def _cubic_axis(a: np.ndarray, coords: np.ndarray, axis: int) -> np.ndarray:
    r"""Keys cubic convolution (a = −½) of ``a`` along ``axis`` at fractional ``coords``.

    With :math:`i = \lfloor x \rfloor`, :math:`f = x - i` the weights of samples
    :math:`i-1 \ldots i+2` are :math:`(-f^3 + 2f^2 - f)/2,\ (3f^3 - 5f^2 + 2)/2,\
    (-3f^3 + 4f^2 + f)/2,\ (f^3 - f^2)/2`.
    """
    i = np.floor(coords).astype(np.intp)
    f = (coords - i).astype(np.float32)
    f2, f3 = f * f, f * f * f
    weights = ((-f3 + 2 * f2 - f) / 2, (3 * f3 - 5 * f2 + 2) / 2, (-3 * f3 + 4 * f2 + f) / 2,
               (f3 - f2) / 2)
    shape = [1, 1]
    shape[axis] = -1
    out = None
    for k, w in zip(range(-1, 3), weights):
        term = np.take(a, np.clip(i + k, 0, a.shape[axis] - 1), axis=axis) * w.reshape(shape)
        out = term if out is None else out + term
    return out


def _dune_profile(u: np.ndarray) -> np.ndarray:
    """Asymmetric dune of unit height over one wavelength (u in [0, 1)): C¹ stoss/lee."""
    u = u - np.floor(u)
    stoss = 0.5 - 0.5 * np.cos(np.pi * u / 0.8)
    lee = 0.5 + 0.5 * np.cos(np.pi * (u - 0.8) / 0.2)
    return np.where(u < 0.8, stoss, lee)


def make_terrain(kind: str, grid: Grid, rng: np.random.Generator, base_height: float
                 ) -> np.ndarray:
    """Bare-earth heights (float64) of the given terrain type on ``grid``.

    Parameters
    ----------
    kind : {"gentle", "dunes", "steep"}
    grid : Grid
    rng : numpy.random.Generator
    base_height : float
        Mean height (m).
    """
    X = grid.xs - (grid.x0 + grid.ncols * grid.cell / 2.0)
    Y = grid.ys - (grid.y1 - grid.nrows * grid.cell / 2.0)
    extent = max(grid.ncols, grid.nrows) * grid.cell
    azimuth = rng.uniform(0.0, 2.0 * np.pi)
    trend = 0.005 * (np.cos(azimuth) * X + np.sin(azimuth) * Y)
    if kind == "gentle":
        z = trend + 1.5 * band_noise(rng, grid, 150.0)
        cx, cy = rng.uniform(-0.25, 0.25, 2) * extent
        radius = rng.uniform(0.12, 0.18) * extent
        z = z + 6.5 * np.exp(-((X - cx) ** 2 + (Y - cy) ** 2) / (2.0 * radius ** 2))
    elif kind == "dunes":
        z = trend.astype(np.float64)
        for wavelength, amplitude in ((min(60.0, extent / 3.0), 5.0),
                                      (min(25.0, extent / 6.0), 1.2)):
            a = azimuth + rng.uniform(-0.4, 0.4)
            s = np.cos(a) * X + np.sin(a) * Y + 0.15 * wavelength * band_noise(
                rng, grid, 3.0 * wavelength)
            z = z + amplitude * _dune_profile(s / wavelength + rng.uniform())
    elif kind == "steep":
        z = np.zeros(grid.shape)
        for wavelength in (400.0, 200.0, 100.0, 50.0, 25.0, 12.0):
            z += (wavelength / 400.0) ** 0.9 * band_noise(rng, grid, wavelength)
        z = (z - z.min()) / (np.ptp(z) + 1e-12) * 110.0
        z += 0.012 * (np.cos(azimuth) * X + np.sin(azimuth) * Y) * 10.0
        for _ in range(2):  # cliff bands: steep steps along wavy lines
            a = rng.uniform(0.0, 2.0 * np.pi)
            s = np.cos(a) * X + np.sin(a) * Y + 4.0 * band_noise(rng, grid, 40.0)
            s0 = rng.uniform(-0.25, 0.25) * extent
            width = rng.uniform(2.0, 3.0)
            z += rng.uniform(8.0, 15.0) * np.clip((s - s0) / width + 0.5, 0.0, 1.0)
        z += 0.4 * band_noise(rng, grid, 4.0)
    else:
        raise ValueError(f"unknown terrain type {kind!r}")
    z = np.asarray(z, dtype=np.float64)
    return z - z.mean() + base_height
