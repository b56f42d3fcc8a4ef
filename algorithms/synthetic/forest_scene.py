r"""Synthetic steep forest: a laser-scanner-like point cloud of a closed canopy on a valley side.

The case DSM → DTM filters fail on first (issue 22, item 6): terrain sloping 30–45°, crowns
touching, only a few per cent of the returns on the ground.

* **Terrain** — one side of a valley in a rotated frame :math:`(u, v)` (u uphill, 25° from
  east): :math:`z = z_0 + s_0 u' + \tfrac{c}{2} u'^2 + A \cos(2\pi v / \lambda)` with
  :math:`u' = u - L/2`, :math:`s_0 = 0.8` (38.7°) and the curvature ``c`` chosen so that the
  uphill gradient runs from 0.6 (31°) at the foot to 1.0 (45°) at the top; the cosine
  (``A`` = 3 m, λ ≈ 0.7 L) adds spurs and gullies across the slope.
* **Canopy** — trees on a jittered 6 m lattice (a few left out: small gaps), heights
  15–35 m, crown radius 3.3–4.5 m (neighbouring crowns overlap), paraboloid crowns
  :math:`z_g(\text{trunk}) + H - D (r/R)^2` with crown depth ``D`` = 0.4 H; the canopy surface
  is the highest crown over a point (a 0.25 m raster).
* **Returns** — pulses uniformly at random; the first return on the canopy (or the ground in
  gaps); under the canopy a last return that reaches the ground with the probability that
  makes ``ground_share`` of all points ground returns, else lies in the understorey (shrubs 1.5–5 m,
  3 % of them) or inside the crowns. Noise σ = 3 cm on the ground, 10 cm in the canopy.

The true DTM is the analytic terrain at cell centres. Sizes: ``small`` (120 m square,
4 pulses/m², ≈ 0.1 M points; for tests) and ``bench`` (400 m square, ≈ 1.3 M points).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, Tuple, Union

import numpy as np
from affine import Affine
from numpy.typing import NDArray

from ..errors import InputError
from ..raster.io import write_raster
from ..surface.point_output import write_points

PathLike = Union[str, Path]
Array = NDArray[Any]

#: Scene sizes: side (m) and pulse density (1/m²).
FOREST_SIZES: Dict[str, Tuple[float, float]] = {"small": (120.0, 4.0), "bench": (400.0, 4.0)}
#: CRS and the south-west corner of the scenes.
FOREST_CRS = "EPSG:25832"
ORIGIN = (500000.0, 5400000.0)
#: Height of the valley floor side of the scene (m).
BASE_HEIGHT = 400.0
#: LAS classes of the points (ASPRS: 2 ground, 5 high vegetation).
GROUND_CLASS, VEGETATION_CLASS = 2, 5
#: Cell (m) of the canopy raster the returns are sampled from.
CANOPY_CELL = 0.25


@dataclass(frozen=True)
class ValleySide:
    """The analytic terrain (see the module notes); heights via :meth:`height`."""

    side: float
    s0: float = 0.8
    s_range: float = 0.2
    amplitude: float = 3.0
    azimuth_deg: float = 25.0

    def height(self, x: Array, y: Array) -> Array:
        """Terrain height (m) at scene coordinates (m from the south-west corner)."""
        a = math.radians(self.azimuth_deg)
        u = x * math.cos(a) + y * math.sin(a)
        v = -x * math.sin(a) + y * math.cos(a)
        half = 0.5 * self.side * (math.cos(a) + math.sin(a))  # centre of u over the square
        up = u - half
        c = self.s_range / half
        lam = 0.7 * self.side
        return (BASE_HEIGHT + self.s0 * (up + half) + 0.5 * c * up ** 2
                + self.amplitude * np.cos(2.0 * np.pi * v / lam))


@dataclass
class ForestScene:
    """A synthetic steep forest (see the module notes).

    Attributes
    ----------
    points : ndarray (n, 3)
        x, y, z in :data:`FOREST_CRS` (m).
    is_ground : ndarray (n,) bool
        True ground returns.
    terrain : ValleySide
        The true terrain (scene coordinates = x, y minus :data:`ORIGIN`).
    side : float
        Side of the square scene (m).
    canopy_cover : float
        Share of the area under a crown.
    """

    points: Array
    is_ground: Array
    terrain: ValleySide
    side: float
    canopy_cover: float

    @property
    def ground_share(self) -> float:
        """Share of the points that are ground returns."""
        return float(np.mean(self.is_ground))

    def ground_height(self, x: Array, y: Array) -> Array:
        """True terrain height at CRS coordinates."""
        return self.terrain.height(np.asarray(x, float) - ORIGIN[0],
                                   np.asarray(y, float) - ORIGIN[1])

    def truth_dtm(self, cell: float = 1.0) -> Tuple[Array, Affine]:
        """The true DTM on a ``cell`` grid over the scene: (heights float32, transform)."""
        n = round(self.side / cell)
        c = (np.arange(n) + 0.5) * cell
        xx, yy = np.meshgrid(c, self.side - c)
        t = Affine(cell, 0.0, ORIGIN[0], 0.0, -cell, ORIGIN[1] + self.side)
        return self.terrain.height(xx, yy).astype(np.float32), t

    def truth_at(self, transform: Affine, shape: Tuple[int, int]) -> Array:
        """The true DTM at the cell centres of any north-up grid (e.g. a filter's DTM)."""
        rows, cols = np.mgrid[0:shape[0], 0:shape[1]].astype(float)
        x, y = transform * (cols + 0.5, rows + 0.5)
        return self.ground_height(x, y)

    def slope_stats(self) -> Dict[str, float]:
        """Median, 5 % and 95 % terrain slope (°) and the relief (m) on a 1 m grid."""
        z, _ = self.truth_dtm(1.0)
        gy, gx = np.gradient(z.astype(float), 1.0)
        deg = np.degrees(np.arctan(np.hypot(gx, gy)))
        q5, q50, q95 = np.quantile(deg, [0.05, 0.5, 0.95])
        return {"slope_median_deg": float(q50), "slope_q05_deg": float(q5),
                "slope_q95_deg": float(q95), "relief_m": float(np.ptp(z))}


def _trees(rng: np.random.Generator, side: float) -> Array:
    """Trees (k, 4): x, y (scene m), height H, crown radius R; a jittered 6 m lattice."""
    d = 6.0
    c = np.arange(-d, side + d, d)
    xx, yy = np.meshgrid(c, c)
    n = xx.size
    x = xx.ravel() + rng.uniform(-1.5, 1.5, n)
    y = yy.ravel() + rng.uniform(-1.5, 1.5, n)
    keep = rng.random(n) > 0.03  # a few missing trees: small gaps
    h = rng.uniform(15.0, 35.0, n)
    r = rng.uniform(0.55, 0.75, n) * d
    return np.column_stack([x, y, h, r])[keep]


def _canopy(trees: Array, terrain: ValleySide, side: float) -> Array:
    """Canopy surface (m, NaN where no crown) on the :data:`CANOPY_CELL` raster (row 0 south)."""
    n = round(side / CANOPY_CELL)
    top = np.full((n, n), np.nan)
    zt = terrain.height(trees[:, 0], trees[:, 1])
    for (x, y, h, r), z0 in zip(trees, zt):
        c0, c1 = max(int((x - r) / CANOPY_CELL), 0), min(int((x + r) / CANOPY_CELL) + 1, n)
        r0, r1 = max(int((y - r) / CANOPY_CELL), 0), min(int((y + r) / CANOPY_CELL) + 1, n)
        if c0 >= c1 or r0 >= r1:
            continue
        cx = (np.arange(c0, c1) + 0.5) * CANOPY_CELL - x
        cy = (np.arange(r0, r1) + 0.5) * CANOPY_CELL - y
        q = (cx[None, :] ** 2 + cy[:, None] ** 2) / r ** 2
        crown = np.where(q <= 1.0, z0 + h - 0.4 * h * q, np.nan)
        block = top[r0:r1, c0:c1]
        top[r0:r1, c0:c1] = np.fmax(block, crown)
    return top


def _returns(rng: np.random.Generator, canopy: Array, terrain: ValleySide, side: float,
             density: float, ground_share: float) -> Tuple[Array, Array, float]:
    """Points (n, 3) in scene metres, their ground flags and the canopy cover."""
    n = round(side * side * density)
    x, y = rng.uniform(0.0, side, n), rng.uniform(0.0, side, n)
    k = canopy.shape[0]
    ci = np.minimum((x / CANOPY_CELL).astype(int), k - 1)
    ri = np.minimum((y / CANOPY_CELL).astype(int), k - 1)
    zg = terrain.height(x, y)
    top = canopy[ri, ci]
    under = np.isfinite(top) & (top > zg + 2.0)
    f = float(under.mean())
    # P(last return on the ground) so that ground returns are ground_share of all points
    p_g = float(np.clip((ground_share * (1.0 + f) - (1.0 - f)) / max(f, 1e-9), 0.005, 1.0))
    first = np.where(under, top + rng.normal(0.0, 0.1, n), zg + rng.normal(0.0, 0.03, n))
    xs, ys = x[under], y[under]
    m = xs.size
    to_ground = rng.random(m) < p_g
    low = rng.random(m) < 0.03  # understorey (shrubs)
    h_top = top[under] - zg[under]
    height = np.where(low, rng.uniform(1.5, 5.0, m), rng.uniform(0.35, 0.95, m) * h_top)
    above = np.where(to_ground, rng.normal(0.0, 0.03, m), height + rng.normal(0.0, 0.1, m))
    # the beam is inclined by the scan angle (±15° across the flight line, east–west): a
    # last return lies beside its first return, by its depth below it × tan(angle)
    depth = np.maximum(top[under] - zg[under] - above, 0.0)
    xs = xs + depth * np.tan(np.radians(rng.uniform(-15.0, 15.0, m)))
    xs = np.clip(xs + rng.normal(0.0, 0.05, m), 0.0, side)  # 10 cm footprint
    ys = np.clip(ys + rng.normal(0.0, 0.05, m), 0.0, side)
    last = terrain.height(xs, ys) + above
    pts = np.concatenate([np.column_stack([x, y, first]), np.column_stack([xs, ys, last])])
    ground = np.concatenate([~under, to_ground])
    return pts, ground, f


def make_forest_scene(size: str = "small", seed: int = 22,
                      ground_share: float = 0.035) -> ForestScene:
    """A seeded synthetic steep forest (see the module notes).

    Parameters
    ----------
    size : {"small", "bench"}
        120 m or 400 m square (:data:`FOREST_SIZES`).
    seed : int
        Random seed (same seed, same scene).
    ground_share : float
        Share of all points that are ground returns (0.02–0.05 for a closed canopy).

    Raises
    ------
    InputError
        Unknown size or a ground share outside (0, 1).
    """
    if size not in FOREST_SIZES:
        raise InputError(f"Unknown forest scene size '{size}'; use one of "
                         f"{', '.join(FOREST_SIZES)}.")
    if not 0.0 < ground_share < 1.0:
        raise InputError("The ground share must lie between 0 and 1.")
    side, density = FOREST_SIZES[size]
    rng = np.random.default_rng(seed)
    terrain = ValleySide(side)
    canopy = _canopy(_trees(rng, side), terrain, side)
    pts, ground, cover = _returns(rng, canopy, terrain, side, density, ground_share)
    pts[:, 0] += ORIGIN[0]
    pts[:, 1] += ORIGIN[1]
    return ForestScene(pts, ground, terrain, side, cover)


def write_forest_points(scene: ForestScene, path: PathLike) -> Path:
    """Write the points as LAS/LAZ (by the suffix; class 2 ground, 5 vegetation) or GeoPackage.

    Written atomically (nothing is left behind when writing fails).
    """
    cls = np.where(scene.is_ground, GROUND_CLASS, VEGETATION_CLASS).astype(np.uint8)
    p = scene.points
    return write_points(path, p[:, 0], p[:, 1], p[:, 2], {"classification": cls},
                        crs=FOREST_CRS)


def forest_dsm(scene: ForestScene, cell: float = 1.0, which: str = "highest"
               ) -> Tuple[Array, Affine]:
    """The points gridded to a DSM: the ``highest`` (canopy) or ``lowest`` return per cell.

    Returns
    -------
    (heights float32 with NaN for empty cells, transform)
    """
    if which not in ("highest", "lowest"):
        raise InputError("A forest DSM takes the 'highest' or the 'lowest' return per cell.")
    n = round(scene.side / cell)
    col = np.clip(((scene.points[:, 0] - ORIGIN[0]) / cell).astype(int), 0, n - 1)
    row = np.clip(((ORIGIN[1] + scene.side - scene.points[:, 1]) / cell).astype(int), 0, n - 1)
    flat = row * n + col
    if which == "highest":
        z = np.full(n * n, -np.inf)
        np.maximum.at(z, flat, scene.points[:, 2])
    else:
        z = np.full(n * n, np.inf)
        np.minimum.at(z, flat, scene.points[:, 2])
    z[~np.isfinite(z)] = np.nan
    t = Affine(cell, 0.0, ORIGIN[0], 0.0, -cell, ORIGIN[1] + scene.side)
    return z.reshape(n, n).astype(np.float32), t


def write_forest_rasters(scene: ForestScene, folder: PathLike, cell: float = 1.0
                         ) -> Dict[str, Path]:
    """Write ``dsm.tif`` (highest return per cell) and ``truth_dtm.tif`` into ``folder``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    dsm, t = forest_dsm(scene, cell, "highest")
    dtm, _ = scene.truth_dtm(cell)
    out = {"dsm": folder / "dsm.tif", "truth_dtm": folder / "truth_dtm.tif"}
    write_raster(out["dsm"], dsm, t, FOREST_CRS)
    write_raster(out["truth_dtm"], dtm, t, FOREST_CRS)
    return out


__all__ = ["FOREST_CRS", "FOREST_SIZES", "ForestScene", "ValleySide", "forest_dsm",
           "make_forest_scene", "write_forest_points", "write_forest_rasters"]
