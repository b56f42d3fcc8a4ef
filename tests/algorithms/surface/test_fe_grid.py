"""Finite-element gridding: closed forms (planes, smooth surfaces, kinks), masks, tiles, IRLS."""

from __future__ import annotations

import numpy as np
import pytest
import rasterio
from shapely.geometry import LineString, Polygon

from photodem.algorithms.errors import InputError
from photodem.algorithms.processing import registry
from photodem.algorithms.surface.fe_grid import _crossings, fe_interpolate
from photodem.algorithms.surface.gridding import Grid, GridAccumulator, finish_grid, grid_points
from tests.conftest import shared_data

CRS = "EPSG:25832"


def _nodes(grid: Grid):
    """x, y of the node (cell centre) grid, row 0 at the north edge."""
    t = grid.transform
    c = t.c + (np.arange(grid.width) + 0.5) * grid.spacing
    r = t.f - (np.arange(grid.height) + 0.5) * grid.spacing
    return np.meshgrid(c, r)


def _scatter(n: int, m: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    return rng.uniform(0, n, m), rng.uniform(0, n, m)


def plane(x, y):
    return 50.0 + 0.1 * x - 0.2 * y


def wave(x, y):
    return 50.0 + 3.0 * np.sin(x / 9.0) * np.cos(y / 7.0) + 0.02 * x


@pytest.mark.parametrize("solver", ["cg", "direct"])
def test_plane_is_exact_from_scattered_points(solver) -> None:
    g = Grid.from_bounds(0, 0, 80, 60, 1.0)
    x, y = _scatter(80, 200)
    y = y * 0.75
    z, info = fe_interpolate(x, y, plane(x, y), g, solver=solver, tile=40, overlap=8)
    X, Y = _nodes(g)
    assert np.isfinite(z).all() and z.dtype == np.float32
    assert np.abs(z - plane(X, Y)).max() < 1e-4  # curvature of a plane is zero
    assert info["used"] == 200 and info["rms"] < 1e-4 and info["count"].sum() == 200


def test_smooth_surface_beats_membrane() -> None:
    n = 100
    g = Grid.from_bounds(0, 0, n, n, 1.0)
    x, y = _scatter(n, n * n // 25, seed=1)  # one point per 5 × 5 cells
    X, Y = _nodes(g)
    truth = wave(X, Y)
    z, _ = fe_interpolate(x, y, wave(x, y), g, smoothing=0.01)
    mem = grid_points(x, y, wave(x, y), 1.0, bounds=(0, 0, n, n), max_gap=1e9).z
    rms_fe = float(np.sqrt(np.mean((z - truth) ** 2)))
    rms_mem = float(np.sqrt(np.mean((mem - truth) ** 2)))
    print(f"RMS vs truth: FE {rms_fe:.3f} m, membrane {rms_mem:.3f} m (relief 6 m)")
    assert rms_fe < 0.35 * rms_mem and rms_fe < 0.2  # measured: 0.135 vs 0.524


def test_breakline_keeps_the_kink_of_a_valley() -> None:
    n = 60
    g = Grid.from_bounds(0, 0, n, n, 1.0)
    x, y = _scatter(n, n * n // 4, seed=2)

    def valley(x, y):
        return 10.0 + 0.5 * np.abs(x - 30.5) + 0.05 * y

    thalweg = LineString([(30.5, -1.0, valley(30.5, -1.0)), (30.5, 61.0, valley(30.5, 61.0))])
    X, Y = _nodes(g)
    truth = valley(X, Y)
    with_bl, info = fe_interpolate(x, y, valley(x, y), g, smoothing=1.0, breaklines=[thalweg])
    without, _ = fe_interpolate(x, y, valley(x, y), g, smoothing=1.0)
    err_bl = np.abs(with_bl[:, 30] - truth[:, 30]).max()  # node column 30 is x = 30.5
    err_no = np.abs(without[:, 30] - truth[:, 30]).max()
    assert info["breakline_vertices"] > 100
    assert err_bl < 1e-3 and err_no > 0.1 and err_bl < 0.01 * err_no
    assert np.abs(with_bl - truth).max() < 1e-3  # two planes, both exact
    # a 2-D breakline only allows the kink: still far better than none
    flat, _ = fe_interpolate(x, y, valley(x, y), g, smoothing=1.0,
                             breaklines=[LineString([(30.5, -1.0), (30.5, 61.0)])])
    assert np.abs(flat[:, 30] - truth[:, 30]).max() < 0.2 * err_no


def test_exclusions_boundaries_and_gaps_are_nan() -> None:
    n = 40
    g = Grid.from_bounds(0, 0, n, n, 1.0)
    x, y = _scatter(n, 1600, seed=3)
    far = ~((np.abs(x - 30) < 6) & (np.abs(y - 30) < 6))  # a 12 m data hole
    x, y = x[far], y[far]
    excl = Polygon([(5, 5), (15, 5), (15, 15), (5, 15)])
    bnd = Polygon([(0, 0), (40, 0), (40, 40), (0, 40)]).difference(
        Polygon([(0, 35), (5, 35), (5, 40), (0, 40)]))
    z, info = fe_interpolate(x, y, plane(x, y), g, exclusions=[excl], boundaries=[bnd],
                             max_gap=6.0)
    assert np.isnan(z[40 - 15:40 - 5, 5:15]).all()  # exclusion (rows count from the north)
    assert np.isnan(z[0:5, 0:5]).all()  # outside the boundary
    # nodes farther than max_gap/2 from data: the middle of the 12 m hole
    assert np.isnan(z[40 - 32:40 - 28, 28:32]).all()
    X, Y = _nodes(g)
    ok = np.isfinite(z)
    assert ok.sum() > 1000 and np.abs(z[ok] - plane(X, Y)[ok]).max() < 1e-3
    assert info["count"][40 - 15:40 - 5, 5:15].sum() == 0
    filled, _ = fe_interpolate(x, y, plane(x, y), g, exclusions=[excl], boundaries=[bnd])
    assert np.isfinite(filled[40 - 34:40 - 26, 26:34]).all()  # default: every gap


def test_tiles_are_seamless() -> None:
    n = 120
    g = Grid.from_bounds(0, 0, n, n, 1.0)
    x, y = _scatter(n, n * n // 4, seed=4)
    one, _ = fe_interpolate(x, y, wave(x, y), g, smoothing=0.1, tile=1000)
    tiled, info = fe_interpolate(x, y, wave(x, y), g, smoothing=0.1, tile=32, overlap=16)
    assert info["tiles"] == 16
    relief = float(np.ptp(one))
    assert np.abs(tiled - one).max() < 1e-3 * relief  # measured: 1e-4 m = 1.3e-5 relief


def test_robust_mode_ignores_blunders() -> None:
    n = 60
    g = Grid.from_bounds(0, 0, n, n, 1.0)
    rng = np.random.default_rng(5)
    x, y = _scatter(n, n * n, seed=5)
    zt = wave(x, y)
    z = zt + rng.normal(0.0, 0.02, x.size)
    bad = rng.random(x.size) < 0.10
    z[bad] += rng.choice([-1.0, 1.0], bad.sum()) * rng.uniform(2.0, 8.0, bad.sum())
    X, Y = _nodes(g)
    truth = wave(X, Y)
    plain, _ = fe_interpolate(x, y, z, g, smoothing=1.0)
    rob, info = fe_interpolate(x, y, z, g, smoothing=1.0, robust=True)
    rms_plain = float(np.sqrt(np.mean((plain - truth) ** 2)))
    rms_rob = float(np.sqrt(np.mean((rob - truth) ** 2)))
    assert rms_plain > 0.3 and rms_rob < 0.03  # measured: 0.5 vs 0.01 m
    caught = info["robust_weight"] < 0.5
    assert caught[bad].mean() > 0.95 and caught[~bad].mean() < 0.01
    assert info["downweighted"] == caught.sum() and info["sigma_mad"] < 0.05


def test_scale_invariance_and_weights() -> None:
    g = Grid.from_bounds(0, 0, 50, 50, 1.0)
    x, y = _scatter(50, 400, seed=6)
    z1, _ = fe_interpolate(x, y, wave(x, y), g, smoothing=0.3)
    zk, _ = fe_interpolate(x, y, 1000.0 * wave(x, y), g, smoothing=0.3,
                           weights=np.full(x.size, 1e-6))
    assert np.allclose(zk / 1000.0, z1, atol=1e-4)


def _relief_fit(x, y, z, truth, spacing: float, size: float, **kw):
    """Gain (regression of the surface on the truth) and RMS at the inner nodes."""
    g = Grid.from_bounds(0, 0, size, size, spacing)
    zg, _ = fe_interpolate(x, y, z, g, smoothing=1.0, **kw)
    X, Y = _nodes(g)
    t = truth(X, Y)[4:-4, 4:-4]
    z = zg[4:-4, 4:-4]
    return float(np.sum(z * t) / np.sum(t * t)), float(np.sqrt(np.mean((z - t) ** 2)))


def test_reference_spacing_keeps_the_relief_on_coarser_grids() -> None:
    # the same noisy points of a 12-cell relief gridded at 1, 2 and 3 × the spacing the
    # smoothing refers to: per cell, the coarse grids flatten the relief (the bug behind
    # fbm_lsm DSMs asked for at 4 GSD); with reference_spacing they keep it
    size, rng = 96.0, np.random.default_rng(3)

    def relief(x, y):
        return 5.0 * np.sin(2 * np.pi * x / 12.0) * np.cos(2 * np.pi * y / 12.0)

    x, y = rng.uniform(0, size, 4608), rng.uniform(0, size, 4608)
    z = relief(x, y) + rng.normal(0.0, 0.2, x.size)
    gain0, rms0 = _relief_fit(x, y, z, relief, 1.0, size, reference_spacing=1.0)
    plain, _ = _relief_fit(x, y, z, relief, 2.0, size)
    assert plain < 0.5 * gain0  # per cell: half the relief is gone at twice the spacing
    for spacing in (2.0, 3.0):
        gain, rms = _relief_fit(x, y, z, relief, spacing, size, reference_spacing=1.0)
        assert gain0 - 0.05 < gain < gain0 + 0.2 and rms < 1.05 * rms0
    with pytest.raises(InputError, match="reference spacing"):
        _relief_fit(x, y, z, relief, 2.0, size, reference_spacing=0.0)


def test_crossings_of_edges() -> None:
    # a segment from (u, v) = (0.5, 0.5) to (2.5, 0.5) crosses columns 1 and 2 on row band 0
    hx, vx, cx = _crossings(np.array([[0.5, 0.5, 2.5, 0.5]]), (3, 4))
    assert vx[0, 1] and vx[0, 2] and vx.sum() == 2 and not hx.any()
    assert cx[0, 0] and cx[0, 2]
    # through the node (1, 1): both horizontal edges at that node are touched
    hx, vx, _ = _crossings(np.array([[1.0, -0.5, 1.0, 1.5]]), (3, 3))
    assert hx[0, 0] and hx[0, 1] and hx[1, 0] and hx[1, 1] and hx.sum() == 4


def test_errors() -> None:
    g = Grid.from_bounds(0, 0, 10, 10, 1.0)
    x, y = _scatter(10, 20)
    with pytest.raises(InputError, match="smoothing"):
        fe_interpolate(x, y, x, g, smoothing=0.0)
    with pytest.raises(InputError, match="solver"):
        fe_interpolate(x, y, x, g, solver="magic")
    with pytest.raises(InputError, match="No point lies"):
        fe_interpolate(x + 100, y, x, g)


def test_interpolate_dem_fe(tmp_path) -> None:
    c = np.arange(40) + 0.5
    X, Y = np.meshgrid(c, c)
    keep = ~((np.abs(X - 20) < 8) & (np.abs(Y - 20) < 8))
    pts = tmp_path / "p.xyz"
    np.savetxt(pts, np.c_[X[keep], Y[keep], plane(X[keep], Y[keep])], fmt="%.6f")
    res = registry.run("interpolate_dem", {"points": str(pts), "output": str(tmp_path / "d.tif"),
                                           "spacing": 1.0, "crs": CRS, "method": "fe",
                                           "smoothing": 0.5})
    assert res["coverage"] == 1.0 and res["filled"] == 16 * 16
    with rasterio.open(res["dem"]) as src:
        z = src.read(1)
    assert np.allclose(z, plane(c[None, :], c[::-1, None]), atol=1e-3)
    with pytest.raises(InputError, match="method"):
        from photodem.algorithms.surface.interpolate import interpolate_dem

        interpolate_dem(pts, tmp_path / "e.tif", 1.0, crs=CRS, method="kriging")


def test_real_dem_resampled_sparsely() -> None:
    dem = shared_data("ngi_aerial_block") / "ngi" / "dem.tif"
    with rasterio.open(dem) as src:
        truth = src.read(1).astype(float)[:240, :240]
        t = src.transform
    s = t.a
    g = Grid(t, 240, 240, s)
    X, Y = _nodes(g)
    rng = np.random.default_rng(7)
    pick = rng.random(truth.shape) < 1.0 / 16.0  # one height per 4 × 4 cells
    pick &= np.isfinite(truth)
    x, y, z = X[pick], Y[pick], truth[pick]
    fe, _ = fe_interpolate(x, y, z, g, smoothing=0.01)
    acc = GridAccumulator(g)
    acc.add(x, y, z)
    mem = finish_grid(*acc.reduce(), g, max_gap=1e9).z
    test = ~pick & np.isfinite(truth)
    rms_fe = float(np.sqrt(np.nanmean((fe - truth)[test] ** 2)))
    rms_mem = float(np.sqrt(np.nanmean((mem - truth)[test] ** 2)))
    print(f"NGI dem.tif, 1/16 of the nodes: RMS FE {rms_fe:.2f} m, membrane {rms_mem:.2f} m")
    assert rms_fe < rms_mem
