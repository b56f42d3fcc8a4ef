"""Ray casting of the synthetic renderer against closed forms and the monoplotting code."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from photodem.algorithms.geometry.dem_intersection import intersect_rays_dem
from photodem.algorithms.raster.sample import DemSampler
from photodem.algorithms.synthetic.render import Renderer
from photodem.algorithms.synthetic.terrain import Grid, band_noise


def _scene(with_box: bool):
    grid = Grid(1000.0, 2000.0, 0.25, 400, 480)
    X, Y = np.broadcast_arrays(grid.xs - grid.x0, grid.ys - (grid.y1 - 100.0))
    dsm = 10.0 + 0.1 * X - 0.05 * Y
    if with_box:
        box = (np.abs(X - 60.0) < 8.0) & (np.abs(Y - 50.0) < 6.0)
        dsm = np.where(box, dsm + 15.0, dsm)
    albedo = np.ones((1,) + grid.shape, dtype=np.float32)
    return grid, dsm, Renderer(grid, dsm, albedo, np.zeros((0, 3)), 0.5)


def test_trace_plane_closed_form() -> None:
    grid, _dsm, r = _scene(False)
    rng = np.random.default_rng(0)
    origin = np.array([1060.0, 1950.0, 300.0])
    a, b = 0.1, -0.05
    c0 = 10.0 - a * grid.x0 - b * (grid.y1 - 100.0)
    target = np.column_stack([rng.uniform(1005, 1115, 2000), rng.uniform(1905, 1995, 2000)])
    z = c0 + a * target[:, 0] + b * target[:, 1]
    d = np.column_stack([target - origin[:2], z - origin[2]])
    hits = r.trace(origin, d)
    # closed form: z = 10 + 0.1 (x − x0) − 0.05 (y − y1 + 100) along the ray
    lam = (c0 + a * origin[0] + b * origin[1] - origin[2]) / (d[:, 2] - a * d[:, 0] - b * d[:, 1])
    exact = origin + lam[:, None] * d
    assert np.abs(hits - exact).max() < 1e-4


def test_trace_occlusion_matches_monoplotting() -> None:
    grid, dsm, r = _scene(True)
    rng = np.random.default_rng(1)
    origin = np.array([1010.0, 1990.0, 120.0])  # oblique view: the box hides ground behind it
    target = np.column_stack([rng.uniform(1040, 1090, 3000), rng.uniform(1935, 1965, 3000)])
    d = np.column_stack([target - origin[:2], np.full(3000, -100.0)])
    hits = r.trace(origin, d)
    ref = intersect_rays_dem(origin, d, DemSampler(dsm, grid.transform), tol=1e-5)
    assert np.isfinite(hits).all()
    on_box = hits[:, 2] - (10.0 + 0.1 * (hits[:, 0] - grid.x0)
                           - 0.05 * (hits[:, 1] - grid.y1 + 100.0)) > 1.0
    assert on_box.mean() > 0.2  # many rays stop on the roof or the wall
    # both find the first crossing of the same bilinear surface; a ray that grazes a roof
    # corner by less than half a cell may be caught by one marcher and not by the other
    differ = np.abs(hits - ref).max(axis=1) > 1e-3
    assert differ.mean() < 0.005
    surface = DemSampler(dsm, grid.transform).height(hits[differ, 0], hits[differ, 1])
    assert np.allclose(hits[differ, 2], surface, atol=1e-3)  # ours is a true crossing...
    assert np.all(hits[differ, 2] > ref[differ, 2])  # ...and the earlier one


def test_band_noise_is_smooth_and_normalised() -> None:
    grid = Grid(0.0, 100.0, 0.1, 500, 600)
    n = band_noise(np.random.default_rng(5), grid, 5.0)
    assert n.dtype == np.float32 and n.shape == grid.shape
    assert 0.7 < n.std() < 1.3
    assert np.abs(np.diff(n, axis=1)).max() < 0.3  # features of ~5 m on 0.1 m cells


def test_sparse_crowns_show_the_ground_dense_ones_do_not() -> None:
    """A sparse crown has gaps where the truth DSM is the ground and the land cover stays
    the ground's; a dense one has none; both carry leaf-clump relief."""
    from photodem.algorithms.synthetic.objects import OPEN, TREE, _burn_trees  # private helper

    grid = Grid(0.0, 20.0, 0.1, 200, 400)
    dtm = np.full(grid.shape, 50.0)
    dsm = dtm.copy()
    lc = np.full(grid.shape, OPEN, dtype=np.uint8)
    obj = SimpleNamespace(trees=np.array([[10.0, 10.0, 4.0, 10.0], [30.0, 10.0, 4.0, 10.0]]),
                          tree_sparse=np.array([0.3, 0.0]))
    _burn_trees(grid, dtm, dsm, lc, obj, np.random.default_rng(3))
    d = np.hypot(grid.xs - 10.0, grid.ys - 10.0) < 3.0
    gaps = d & (dsm == dtm)
    assert 0.1 < gaps.mean() / d.mean() < 0.5
    assert (lc[gaps] == OPEN).all() and (lc[d & ~gaps] == TREE).all()
    d2 = np.hypot(grid.xs - 30.0, grid.ys - 10.0)
    assert (dsm[d2 < 3.0] > dtm[d2 < 3.0]).all()
    profile = 10.0 * np.clip(1.0 - (d2 / 4.0) ** 2, 0.0, None) ** 0.6
    relief = (dsm - dtm - profile)[d2 < 3.0]
    assert 0.1 < relief.std() < 0.5
