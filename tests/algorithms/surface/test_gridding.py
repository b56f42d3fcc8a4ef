"""Gridding: closed forms (plane, median, gap sizes, masks, breakline barriers)."""

from __future__ import annotations

import numpy as np
import pytest
from shapely.geometry import LineString, box

from photodem.algorithms.surface.gridding import (
    Grid,
    GridAccumulator,
    fill_gaps,
    grid_points,
    reject_outliers,
    write_grid,
)


def _plane_points(n: int = 40000, seed: int = 0):
    rng = np.random.default_rng(seed)
    x = rng.uniform(0, 50, n)
    y = rng.uniform(0, 50, n)
    return x, y, 100.0 + 0.1 * x - 0.05 * y


def test_plane_points_give_the_plane_at_cell_centres() -> None:
    # 4 points per cell, symmetric about the centre → median = plane at the centre exactly
    s = 1.0
    cx, cy = np.meshgrid(np.arange(0.5, 20), np.arange(0.5, 20))
    off = np.array([[-0.25, -0.25], [0.25, 0.25], [-0.25, 0.25], [0.25, -0.25]])
    x = (cx[..., None] + off[:, 0]).ravel()
    y = (cy[..., None] + off[:, 1]).ravel()
    z = 10.0 + 0.3 * x + 0.2 * y
    res = grid_points(x, y, z, s, bounds=(0, 0, 20, 20))
    gx = res.transform.c + (np.arange(res.grid.width) + 0.5) * s
    gy = res.transform.f - (np.arange(res.grid.height) + 0.5) * s
    truth = 10.0 + 0.3 * gx[None, :] + 0.2 * gy[:, None]
    assert res.z.shape == (20, 20)
    np.testing.assert_allclose(res.z, truth, atol=1e-4)
    assert (res.count == 4).all()


def test_median_rejects_outliers_and_weights_work() -> None:
    x = np.full(7, 0.5)
    y = np.full(7, 0.5)
    z = np.array([1.0, 1.1, 0.9, 1.05, 0.95, 50.0, -40.0])
    res = grid_points(x, y, z, 1.0, bounds=(0, 0, 1, 1))
    assert res.z[0, 0] == pytest.approx(1.0, abs=1e-6) and res.count[0, 0] == 7
    # a weighted median follows the precise points
    zs = np.array([1.0, 2.0, 3.0])
    sig = np.array([1.0, 1.0, 0.1])
    res = grid_points(np.full(3, 0.5), np.full(3, 0.5), zs, 1.0, bounds=(0, 0, 1, 1),
                      sigma=sig)
    assert res.z[0, 0] == pytest.approx(3.0)


def test_streaming_with_spill_equals_in_memory(tmp_path) -> None:
    x, y, z = _plane_points()
    z = z + np.random.default_rng(1).normal(0, 0.1, z.size)
    grid = Grid.from_bounds(0, 0, 50, 50, 1.0)
    ref = GridAccumulator(grid)
    ref.add(x, y, z)
    z_ref, c_ref = ref.reduce()
    acc = GridAccumulator(grid, tile=16, memory_mb=0.05, scratch_dir=tmp_path)
    for part in np.array_split(np.arange(x.size), 13):
        acc.add(x[part], y[part], z[part])
    z_s, c_s = acc.reduce()
    np.testing.assert_array_equal(c_s, c_ref)
    np.testing.assert_array_equal(z_s, z_ref)
    assert not list(tmp_path.iterdir())  # scratch removed


def test_covered_cells_are_those_with_points_in_memory_and_spilled(tmp_path) -> None:
    """``covered`` reads the buffered and the spilled points without consuming them."""
    rng = np.random.default_rng(2)
    x, y = rng.uniform(0, 50, 400), rng.uniform(0, 50, 400)
    grid = Grid.from_bounds(0, 0, 50, 50, 1.0)
    acc = GridAccumulator(grid, tile=16, memory_mb=0.002, scratch_dir=tmp_path)
    for part in np.array_split(np.arange(x.size), 7):
        acc.add(x[part], y[part], np.ones(part.size))
    assert any(tmp_path.iterdir())  # some points went to scratch files
    covered = acc.covered()
    _, count = acc.reduce()
    np.testing.assert_array_equal(covered, count > 0)
    assert 0 < covered.sum() < covered.size


def test_only_small_gaps_are_filled_and_exactly_on_a_plane() -> None:
    yy, xx = np.mgrid[0:60, 0:60].astype(float)
    plane = (5.0 + 0.2 * xx - 0.1 * yy).astype(np.float32)
    z = plane.copy()
    z[10:13, 10:13] = np.nan     # 3 cells wide → filled
    z[30:50, 30:50] = np.nan     # 20 cells wide → stays empty
    out, filled = fill_gaps(z, 1.0, max_gap=6.0)
    np.testing.assert_allclose(out[10:13, 10:13], plane[10:13, 10:13], atol=1e-4)
    assert filled[10:13, 10:13].all()
    assert np.isnan(out[30:50, 30:50]).all() and not filled[30:50, 30:50].any()


def test_exclusion_and_boundary_are_nan() -> None:
    x, y, z = _plane_points()
    res = grid_points(x, y, z, 1.0, bounds=(0, 0, 50, 50), max_gap=5.0,
                      exclusions=[box(10, 10, 20, 20)], boundary=[box(5, 5, 45, 45)])
    t = res.transform
    cx = t.c + (np.arange(res.grid.width) + 0.5)
    cy = t.f - (np.arange(res.grid.height) + 0.5)
    X, Y = np.meshgrid(cx, cy)
    inside_excl = (X > 10) & (X < 20) & (Y > 10) & (Y < 20)
    outside = (X < 5) | (X > 45) | (Y < 5) | (Y > 45)
    assert np.isnan(res.z[inside_excl]).all() and np.isnan(res.z[outside]).all()
    assert (res.count[inside_excl | outside] == 0).all()
    rest = ~inside_excl & ~outside
    assert np.isfinite(res.z[rest]).all()  # small sampling gaps are filled


def test_breakline_is_not_crossed() -> None:
    # a 2 m step along x = 20; a gap straddles it
    s = 1.0
    cx, cy = np.meshgrid(np.arange(0.5, 40), np.arange(0.5, 40))
    z = np.where(cx < 20, 0.0, 2.0)
    keep = ~((cx > 14) & (cx < 26) & (cy > 14) & (cy < 26))
    line = LineString([(20, -5, 1.0), (20, 45, 1.0)])
    res = grid_points(cx[keep], cy[keep], z[keep], s, bounds=(0, 0, 40, 40), max_gap=20.0,
                      breaklines=[line])
    t = res.transform
    gx = t.c + (np.arange(res.grid.width) + 0.5) * s
    low = res.z[:, (gx > 14) & (gx < 19)]
    high = res.z[:, (gx > 21) & (gx < 26)]
    np.testing.assert_allclose(low, 0.0, atol=1e-6)
    np.testing.assert_allclose(high, 2.0, atol=1e-6)
    assert np.isfinite(res.z).all()
    # without the breakline the step is smeared into the gap
    res2 = grid_points(cx[keep], cy[keep], z[keep], s, bounds=(0, 0, 40, 40), max_gap=20.0)
    assert np.nanmax(res2.z[:, (gx > 14) & (gx < 19)]) > 0.2


def test_write_grid(tmp_path) -> None:
    import rasterio

    x, y, z = _plane_points(2000)
    res = grid_points(x, y, z, 2.0, max_gap=10.0)
    path = write_grid(tmp_path / "dsm.tif", res.z, res.grid, crs="EPSG:25832")
    with rasterio.open(path) as src:
        assert src.crs.to_epsg() == 25832 and src.transform == res.transform
        assert src.dtypes[0] == "float32" and np.isnan(src.nodata)


def test_reject_outliers_removes_spikes_but_keeps_steps_and_planes() -> None:
    # plane with a 5 m step (a building edge) and two isolated blunders
    yy, xx = np.mgrid[0:60, 0:80].astype(float)
    z = 100.0 + 0.05 * xx - 0.02 * yy + 5.0 * (xx >= 40)
    z = z.astype(np.float32)
    z[10, 10] += 3.0
    z[30, 60] -= 2.0
    z[5:8, 70:73] = np.nan  # empty cells are neither rejected nor a problem
    bad = reject_outliers(z, spacing=0.5, radius=2.5, threshold=1.0)
    assert bad[10, 10] and bad[30, 60]
    assert bad.sum() == 2  # the step and the tilted plane stay
    assert not reject_outliers(z, 0.5, 0.0, 1.0).any()  # radius 0 = off
    # a deviation below the threshold stays
    z2 = z.copy()
    z2[10, 10] -= 2.5
    assert not reject_outliers(z2, 0.5, 2.5, 1.0)[10, 10]


def test_grid_points_outlier_cells_are_refilled() -> None:
    x, y, z = _plane_points()
    z = z.copy()
    hit = (np.abs(x - 25.2) < 0.4) & (np.abs(y - 25.2) < 0.4)
    z[hit] += 10.0  # a blunder cluster covering one cell
    res = grid_points(x, y, z, spacing=1.0, bounds=(0, 0, 50, 50), max_gap=3.0)
    from photodem.algorithms.surface.gridding import finish_grid
    g = res.grid
    r, c = g.cell_of([25.2], [25.2])
    assert res.z[r[0], c[0]] > 105.0  # without the test the blunder survives the median
    clean = finish_grid(res.z, res.count, g, max_gap=3.0, outlier_radius=3.0,
                        outlier_threshold=1.0)
    assert abs(clean.z[r[0], c[0]] - (100.0 + 0.1 * 25.5 - 0.05 * 24.5)) < 0.05
    assert clean.filled[r[0], c[0]] and clean.count[r[0], c[0]] == 0


def test_deviates_from_checks_candidates_against_a_reference() -> None:
    """Candidate heights are tested against the neighbourhood of other heights (the dense
    slant passes against the plain pass, issue 22 part N): on the reference's plane they stay,
    1.5 m off they go, and the test of a grid against itself is :func:`reject_outliers`."""
    from photodem.algorithms.surface.gridding import deviates_from

    _, xx = np.mgrid[0:40, 0:40].astype(np.float32)
    plane = 100.0 + 0.1 * xx
    ref = plane.copy()
    ref[10:20, 10:20] = np.nan  # a hole the candidates fill
    cand = np.full_like(plane, np.nan)
    cand[10:20, 10:20] = plane[10:20, 10:20]
    cand[14, 14] += 1.5
    bad = deviates_from(cand, ref, spacing=0.5, radius=2.5, threshold=0.5)
    assert bad[14, 14] and bad.sum() == 1
    assert not deviates_from(cand, np.full_like(ref, np.nan), 0.5, 2.5, 0.5).any()
    z = plane.copy()
    z[5, 30] += 3.0
    np.testing.assert_array_equal(deviates_from(z, z, 0.5, 2.5, 1.0),
                                  reject_outliers(z, 0.5, 2.5, 1.0))


def test_deviates_from_at_a_few_cells_is_the_whole_grid_test_there() -> None:
    """``where`` tests a few scattered cells from their own windows (the rounds of the dense
    slant cells): the verdicts equal the whole-grid test's at those cells, at the borders and
    next to big holes of the reference too, and nothing else is tested."""
    from photodem.algorithms.surface.gridding import deviates_from

    rng = np.random.default_rng(5)
    _, xx = np.mgrid[0:60, 0:80].astype(np.float32)
    ref = (100.0 + 0.2 * xx + rng.normal(0.0, 0.3, xx.shape)).astype(np.float32)
    ref[20:45, 30:60] = np.nan  # a big hole: its cells take the nearest height
    ref[rng.random(ref.shape) < 0.2] = np.nan
    cand = (100.0 + 0.2 * xx + rng.normal(0.0, 1.0, xx.shape)).astype(np.float32)
    full = deviates_from(cand, ref, 0.5, 2.0, 0.5)
    for share in (0.003, 0.03, 0.5):
        where = rng.random(ref.shape) < share
        where[0, :3] = where[-1, -3:] = where[30, 40] = True  # corners, inside the hole
        np.testing.assert_array_equal(deviates_from(cand, ref, 0.5, 2.0, 0.5, where=where),
                                      full & where)
