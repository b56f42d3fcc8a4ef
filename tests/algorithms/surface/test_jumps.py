"""Jump breaklines that float noise in the points does not change (issue: the same fbm_lsm DSM
from QGIS and from the CLI)."""

from __future__ import annotations

from typing import Set, Tuple

import numpy as np
from shapely.ops import unary_union

from photodem.algorithms.surface.jumps import jump_breaklines, plan_triangulation

#: A projected origin like the synthetic blocks' (UTM, m).
ORIGIN = (402000.0, 5674000.0)


def _grid_points(noise: float, seed: int = 0) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points every 0.4 m (the grid densification's nodes, shifted by up to 2 cm as by relief
    and matching) at a projected origin, a 6 m roof in the middle; plan coordinates with
    ``noise`` m of noise (``seed``)."""
    xx, yy = np.meshgrid(np.arange(0.2, 16, 0.4), np.arange(0.2, 12, 0.4))
    shift = np.random.default_rng(99).uniform(-0.02, 0.02, (2, xx.size))
    x, y = xx.ravel() + shift[0], yy.ravel() + shift[1]
    z = np.where((np.abs(x - 8) < 3) & (np.abs(y - 6) < 2.5), 6.0, 0.0)
    rng = np.random.default_rng(seed)
    x = x + ORIGIN[0] + rng.normal(0, noise, x.size)
    y = y + ORIGIN[1] + rng.normal(0, noise, y.size)
    return x, y, z


def _triangles(x: np.ndarray, y: np.ndarray) -> Set[Tuple[int, ...]]:
    return set(map(tuple, np.sort(plan_triangulation(x, y).simplices, axis=1)))


def test_plan_triangulation_ignores_float_noise() -> None:
    """Points that differ by 2 µm (another BLAS) give the same triangles, and every point is a
    vertex. Measured on Delaunay of the projected coordinates themselves: TRI_CHANGED of the
    triangles (512 of 659) changed, and Qhull used only 337 of the 1200 points as vertices
    (the others: "coplanar")."""
    x, y, _ = _grid_points(0.0)
    for seed in (1, 2):
        xn, yn, _ = _grid_points(2e-6, seed)
        assert _triangles(x, y) == _triangles(xn, yn)
    assert len(np.unique(plan_triangulation(x, y).simplices)) == x.size
    # the same points elsewhere: the same triangles (only the local corner counts)
    assert _triangles(x - ORIGIN[0], y - ORIGIN[1]) == _triangles(x, y)


def test_jump_breaklines_ignore_float_noise() -> None:
    """The wall breaklines of the `general` preset (upper offset, hysteresis) round a roof are
    the same for points that differ by float noise: the same pieces, moved by the noise only
    (measured before: 67, 56 and 56 pieces, up to 0.80 m apart)."""
    lines = []
    for noise, seed in ((0.0, 0), (2e-6, 1), (2e-6, 2)):
        x, y, z = _grid_points(noise, seed)
        found = jump_breaklines(x, y, z, 1.5, 1.0, upper_offset=0.6, weak_slope=0.7)
        assert len(found) == 1
        lines.append(found[0])
    assert unary_union(lines[0]).length > 20.0  # round the 6 × 5 m roof
    for other in lines[1:]:
        assert len(other.geoms) == len(lines[0].geoms)
        assert lines[0].hausdorff_distance(other) < 1e-4
