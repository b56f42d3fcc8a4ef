"""Groundel reduction: closed forms, robustness, σ1/σ2 against synthetic truth, vectorisation."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from photodem.algorithms.errors import InputError
from photodem.algorithms.surface.groundel import reduce_groundels


def _cells(rng, n_side: int, per_cell: int, size: float):
    """Points uniformly in n_side × n_side cells of side ``size``, origin (0, 0) top-left."""
    m = n_side * n_side
    cx = np.repeat(np.arange(m) % n_side, per_cell)
    cy = np.repeat(np.arange(m) // n_side, per_cell)
    x = (cx + rng.uniform(0.0, 1.0, cx.size)) * size
    y = -(cy + rng.uniform(0.0, 1.0, cy.size)) * size
    return x, y


def test_exact_plane_recovered_with_30_percent_gross_outliers() -> None:
    rng = np.random.default_rng(1)
    x, y = _cells(rng, 5, 120, 10.0)
    z = 10.0 + 0.3 * x - 0.2 * y
    bad = rng.random(x.size) < 0.3
    z_obs = z + np.where(bad, rng.uniform(5.0, 30.0, x.size) * rng.choice([-1, 1], x.size), 0)
    r = reduce_groundels(x, y, z_obs, 10.0, origin=(0.0, 0.0))
    assert r.cells == 25 and r.plane.all()
    np.testing.assert_allclose(r.z, 10.0 + 0.3 * r.x - 0.2 * r.y, atol=1e-4)
    np.testing.assert_allclose(r.slope, np.tile([0.3, -0.2], (25, 1)), atol=1e-5)
    # every gross error flagged, no good point flagged
    np.testing.assert_array_equal(r.outlier, bad)
    assert r.n_outliers == int(bad.sum())
    np.testing.assert_array_equal(r.outliers, np.bincount(r.cell_index, weights=bad))
    # the representative point is a measured point on the plane
    assert np.abs(r.residual[r.rep_index]).max() < 1e-4
    np.testing.assert_array_equal(r.rep_z, z_obs[r.rep_index])
    # the median of a tilted cell is biased (it is the height of the median point, not of the
    # centre) — the plane is not
    med = reduce_groundels(x, y, z, 10.0, origin=(0.0, 0.0), mode="median")
    assert np.abs(med.z - (10.0 + 0.3 * med.x - 0.2 * med.y)).max() < 0.6


def test_median_and_lower_modes_closed_form() -> None:
    # one cell, heights 1…10 (+ a blunder at 100): median 6, 10th percentile 2.0
    x = np.linspace(0.5, 9.5, 11)
    y = np.full(11, -5.0)
    z = np.array([1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 100.0])
    med = reduce_groundels(x, y, z, 10.0, origin=(0.0, 0.0), mode="median")
    assert med.cells == 1 and med.z[0] == pytest.approx(np.median(z))
    assert med.rep_z[0] == 6.0 and not med.plane[0]
    low = reduce_groundels(x, y, z, 10.0, origin=(0.0, 0.0), mode="lower",
                           lower_percentile=10.0)
    assert low.z[0] == pytest.approx(np.percentile(z, 10.0))
    # σ1 of a cell: 1.4826 · MAD · √(n/(n−2)), the blunder flagged
    mad = np.median(np.abs(z - np.median(z)))
    assert med.sigma1[0] == pytest.approx(1.4826 * mad * math.sqrt(11 / 9))
    assert med.outlier[-1] and med.outlier.sum() == 1
    # weighted median: the heavy point wins
    w = np.ones(11)
    w[2] = 100.0
    assert reduce_groundels(x, y, z, 10.0, origin=(0.0, 0.0), mode="median",
                            weights=w).z[0] == 3.0


def test_lower_envelope_finds_the_ground_under_vegetation() -> None:
    rng = np.random.default_rng(2)
    x, y = _cells(rng, 6, 60, 8.0)
    ground = 50.0 + rng.normal(0.0, 0.05, x.size)
    tree = rng.random(x.size) < 0.5
    z = ground + np.where(tree, rng.uniform(3.0, 8.0, x.size), 0.0)
    low = reduce_groundels(x, y, z, 8.0, origin=(0.0, 0.0), mode="lower",
                           lower_percentile=10.0)
    med = reduce_groundels(x, y, z, 8.0, origin=(0.0, 0.0), mode="median")
    assert abs(np.mean(low.z) - 50.0) < 0.1
    assert np.mean(med.z) - 50.0 > 1.0


@pytest.mark.parametrize("slope", [0.0, 0.4])
def test_sigma1_matches_the_noise_and_sigma2_formula(slope: float) -> None:
    rng = np.random.default_rng(3)
    x, y = _cells(rng, 40, 30, 6.0)
    sigma = 0.25
    z = 100.0 + slope * x - 0.5 * slope * y + rng.normal(0.0, sigma, x.size)
    r = reduce_groundels(x, y, z, 6.0, origin=(0.0, 0.0), F=2.0)
    assert r.sigma1_mean == pytest.approx(sigma, rel=0.10)
    assert r.n_mean == pytest.approx(30.0)
    assert r.sigma2 == pytest.approx(2.0 * r.sigma1_mean / math.sqrt(30.0))
    # the tilted plane is used where the slope is real, the median where it is not
    assert (r.plane.mean() > 0.95) if slope else (r.plane.mean() < 0.15)
    # the plane value at the centre is unbiased and about σ/√n·√(π/2) precise
    err = r.z - (100.0 + slope * r.x - 0.5 * slope * r.y)
    assert abs(err.mean()) < 0.02
    assert err.std() < 2.0 * sigma / math.sqrt(30.0)
    # outlier flags at 3σ: about 0.3 % of Gaussian points
    assert r.n_outliers / r.points_valid < 0.02
    s = r.summary()
    assert s["sigma1_m"] == pytest.approx(r.sigma1_mean)
    assert s["points_reduced"] == 1600 and s["points_raw"] == x.size
    assert s["cell_m"] == 6.0 and s["mode"] == "l1"


def test_small_cells_invalid_points_and_grid() -> None:
    x = np.array([1.0, 2.0, 11.0, 12.0, 13.0, np.nan, 25.0])
    y = np.array([-1.0, -2.0, -1.0, -2.0, -3.0, -1.0, -15.0])
    z = np.array([5.0, 7.0, 1.0, 2.0, 3.0, 0.0, 9.0])
    r = reduce_groundels(x, y, z, 10.0, origin=(0.0, 0.0), mode="median", min_points=3)
    assert r.points_raw == 7 and r.points_valid == 6 and r.cells == 3
    np.testing.assert_array_equal(r.n, [2, 3, 1])
    assert np.isnan(r.sigma1[0]) and np.isfinite(r.sigma1[1]) and np.isnan(r.sigma1[2])
    assert r.cell_index[5] == -1 and np.isnan(r.residual[5])
    assert r.sigma1_mean == pytest.approx(r.sigma1[1]) and r.n_mean == 3.0
    grid, layers = r.grid()
    assert (grid.height, grid.width) == (2, 3) and grid.transform.c == 0.0
    assert layers["z"][0, 0] == 6.0 and layers["z"][0, 1] == 2.0 and layers["z"][1, 2] == 9.0
    assert np.isnan(layers["z"][1, 0]) and layers["n"][1, 2] == 1
    # the default origin snaps to the cell size
    d = reduce_groundels(x, y, z, 10.0, mode="median")
    assert d.origin == (0.0, 0.0)


def test_bad_input() -> None:
    with pytest.raises(InputError, match="mode"):
        reduce_groundels([0.0], [0.0], [0.0], 1.0, mode="mean")
    with pytest.raises(InputError, match="positive"):
        reduce_groundels([0.0], [0.0], [0.0], 0.0)
    with pytest.raises(InputError, match="lengths"):
        reduce_groundels([0.0, 1.0], [0.0], [0.0], 1.0)
    with pytest.raises(InputError, match="No finite"):
        reduce_groundels([np.nan], [0.0], [0.0], 1.0)


def test_chunks_give_the_same_result() -> None:
    rng = np.random.default_rng(4)
    x, y = _cells(rng, 20, 25, 5.0)
    z = 3.0 + 0.1 * x + rng.normal(0.0, 0.2, x.size)
    order = rng.permutation(x.size)  # input order does not matter either
    a = reduce_groundels(x, y, z, 5.0, origin=(0.0, 0.0))
    b = reduce_groundels(x[order], y[order], z[order], 5.0, origin=(0.0, 0.0),
                         chunk_points=1234)
    np.testing.assert_allclose(a.z, b.z, atol=1e-6)
    np.testing.assert_allclose(a.sigma1, b.sigma1, rtol=1e-6)
    np.testing.assert_array_equal(a.outlier[order], b.outlier)


def test_a_million_points_vectorised() -> None:
    rng = np.random.default_rng(5)
    n = 1_000_000
    x = rng.uniform(0.0, 1000.0, n)
    y = rng.uniform(0.0, 1000.0, n)
    z = 100.0 + 0.2 * x - 0.1 * y + rng.normal(0.0, 0.3, n)
    t0 = time.perf_counter()
    r = reduce_groundels(x, y, z, 6.0)
    seconds = time.perf_counter() - t0
    assert r.points_valid == n and r.cells > 27_000
    assert r.sigma1_mean == pytest.approx(0.3, rel=0.05)
    assert seconds < 30.0  # ~2.5 s on the reference machine; a per-cell loop takes minutes
