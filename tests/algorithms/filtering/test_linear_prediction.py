"""Hierarchical robust linear prediction: closed forms, synthetic truth, edits, I/O."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from affine import Affine
from shapely.geometry import LineString

from photodem.algorithms.errors import InputError
from photodem.algorithms.filtering.linear_prediction import (
    Covariance,
    LPParameters,
    asymmetric_weights,
    covariance_apply,
    filter_linear_prediction,
    fit_covariance,
    lp_solve,
    predict_dense,
    residual_shift,
    run_filter_linear_prediction,
)
from photodem.algorithms.filtering.lp_pyramid import reduce_lowest, reduce_min, upsample2
from photodem.algorithms.filtering.presets import LINEAR_PREDICTION_PRESETS, PRESET_NAMES
from photodem.algorithms.filtering.surface_input import FilterConstraints
from photodem.algorithms.surface.gridding import Grid, line_barrier
from tests.conftest import shared_data


def _grid(n: int, m: int = 0, spacing: float = 1.0) -> Grid:
    m = m or n
    return Grid(Affine(spacing, 0.0, 1000.0, 0.0, -spacing, 2000.0 + n * spacing), m, n,
                spacing)


def _xy(shape):
    rr, cc = np.mgrid[0:shape[0], 0:shape[1]]
    return rr.astype(np.float64), cc.astype(np.float64)


# -- closed forms ----------------------------------------------------------------------------------
def test_grid_prediction_equals_dense_formula() -> None:
    """C (C + D)⁻¹ l by convolution + CG equals the textbook cᵀ C⁻¹ l at every cell."""
    rng = np.random.default_rng(0)
    h, w = 18, 21
    lz = rng.normal(size=(h, w)).astype(np.float32)
    act = rng.random((h, w)) < 0.6
    cov = Covariance(c0=1.0, noise=0.2, corr=2.0, vzz=1.2)
    s, _, _ = lp_solve(lz, act, cov, tol=1e-8, maxiter=3000)
    rr, cc = _xy((h, w))
    obs = np.column_stack([cc[act], rr[act]])
    dense = predict_dense(obs, lz[act], np.column_stack([cc.ravel(), rr.ravel()]), 1.0, 2.0,
                          0.2).reshape(h, w)
    # the only difference is the kernel truncation at 2.5 c (C < 0.2 % of C0)
    assert np.max(np.abs(s - dense)) < 0.01
    assert np.sqrt(np.mean((s - dense) ** 2)) < 0.003


def test_covariance_apply_is_separable_gaussian() -> None:
    x = np.zeros((21, 21), np.float32)
    x[10, 10] = 1.0
    y = covariance_apply(x, 2.0, 3.0)
    rr, cc = _xy(x.shape)
    d = np.hypot(rr - 10, cc - 10)
    ref = 2.0 * np.exp(-(d / 3.0) ** 2)
    inside = (np.abs(rr - 10) <= 7) & (np.abs(cc - 10) <= 7)
    np.testing.assert_allclose(y[inside], ref[inside], atol=1e-6)


def test_pure_interpolation_reproduces_support_points() -> None:
    rng = np.random.default_rng(1)
    lz = rng.normal(size=(15, 15)).astype(np.float32)
    act = rng.random((15, 15)) < 0.5
    s, _, _ = lp_solve(lz, act, Covariance(1.0, 0.0, 1.5, 1.0), tol=1e-8, maxiter=3000)
    assert np.array_equal(s[act], lz[act])
    # a hole is predicted from its neighbours (not left at 0 when they agree)
    lz2 = np.full((15, 15), 2.0, np.float32)
    act2 = np.ones((15, 15), bool)
    act2[7, 7] = False
    s2, _, _ = lp_solve(lz2, act2, Covariance(1.0, 0.0, 1.5, 1.0), tol=1e-8, maxiter=3000)
    assert abs(s2[7, 7] - 2.0) < 0.02


def test_asymmetric_weights_and_shift() -> None:
    r = np.array([-3.0, -0.1, 0.0, 0.3, 0.9, 1.1, -6.0])
    p = asymmetric_weights(r, g=0.0, half_weight=0.3, exponent=4.0, cutoff=1.0, low_cutoff=5.0)
    np.testing.assert_allclose(p[:3], 1.0)  # below the surface: full weight
    assert p[3] == pytest.approx(0.5)  # h above: half weight
    assert p[4] == pytest.approx(1.0 / (1.0 + 3.0 ** 4))
    assert p[5] == 0.0 and p[6] == 0.0  # above the cut-off / deep blunder
    assert residual_shift(np.array([-0.3, -0.4, 0.5, 2.0]), 1.0, 1.0) == pytest.approx(
        -math.sqrt((0.09 + 0.16) / 2))
    assert residual_shift(np.array([-3.0, 1.0]), 1.0, 0.5) == -0.5


def test_fit_covariance_recovers_gaussian_model() -> None:
    d = np.arange(8, dtype=float)
    emp = 0.8 * np.exp(-(d / 2.5) ** 2)
    emp[0] += 0.2  # white noise only at lag 0
    cov = fit_covariance(emp, 1.0, 4.0, min_noise_share=0.01)
    assert cov.corr == pytest.approx(2.5, rel=0.02)
    assert cov.c0 == pytest.approx(0.8, rel=0.02)
    assert cov.noise == pytest.approx(0.2, rel=0.1)
    fixed = fit_covariance(emp, 1.0, 4.0, noise_share=0.3)
    assert fixed.noise_share == pytest.approx(0.3)


def test_upsample2_is_bilinear_between_cell_centres() -> None:
    # a linear ramp in coarse cells stays the same linear ramp at the fine cell centres
    a = np.add.outer(np.arange(6.0), 2 * np.arange(5.0)).astype(np.float32)
    up = upsample2(a, (12, 10))
    fr, fc = _xy((12, 10))
    ref = (fr + 0.5) / 2 - 0.5 + 2 * ((fc + 0.5) / 2 - 0.5)
    inner = (fr > 0) & (fr < 11) & (fc > 0) & (fc < 9)
    np.testing.assert_allclose(up[inner], ref[inner], atol=1e-5)


# -- synthetic truth -------------------------------------------------------------------------
def test_plane_with_boxes_gives_the_plane() -> None:
    rng = np.random.default_rng(2)
    g = _grid(160)
    rr, cc = _xy(g.shape)
    plane = (100.0 + 0.05 * cc - 0.03 * rr).astype(np.float32)
    z = plane.copy()
    boxes = [(20, 20, 15, 20, 8.0), (90, 40, 30, 26, 12.0), (120, 120, 12, 12, 5.0),
             (40, 100, 45, 14, 9.0)]
    obj = np.zeros(g.shape, bool)
    for r0, c0, a, b, ht in boxes:
        z[r0:r0 + a, c0:c0 + b] += ht
        obj[r0:r0 + a, c0:c0 + b] = True
    z += rng.normal(0, 0.05, z.shape).astype(np.float32)
    res = filter_linear_prediction(z, g)
    e = res.dtm - plane
    assert np.sqrt(np.mean(e ** 2)) < 0.05
    assert np.max(np.abs(e)) < 0.3
    assert not res.ground[obj].any()
    assert res.ground[~obj].mean() > 0.98
    assert res.iterations and res.iterations[-1]["level"] == 0


def test_smooth_hill_with_trees_gives_the_hill() -> None:
    rng = np.random.default_rng(3)
    g = _grid(128)
    rr, cc = _xy(g.shape)
    hill = (50.0 + 8.0 * np.exp(-((rr - 64) ** 2 + (cc - 60) ** 2) / (2 * 28.0 ** 2))
            ).astype(np.float32)
    sigma = 0.1
    z = hill + rng.normal(0, sigma, hill.shape).astype(np.float32)
    trees = np.zeros(g.shape, bool)
    for _ in range(40):  # single trees: cones 4–12 m high, radius 2–5 m
        r0, c0 = rng.uniform(5, 123, 2)
        rad, ht = rng.uniform(2, 5), rng.uniform(4, 12)
        cone = ht * (1 - np.hypot(rr - r0, cc - c0) / rad)
        z = np.maximum(z, hill + cone.astype(np.float32))
        trees |= cone > 0.8  # clearly above the 0.5 m ground tolerance
    res = filter_linear_prediction(z, g)
    e = res.dtm - hill
    assert np.sqrt(np.mean(e ** 2)) < sigma * 1.5  # the hill within σ
    assert np.sqrt(np.mean(e[trees] ** 2)) < 0.3  # bridged under the crowns
    assert res.ground[trees].mean() < 0.05


def test_filtering_reduces_white_noise() -> None:
    rng = np.random.default_rng(4)
    g = _grid(150)
    rr, cc = _xy(g.shape)
    truth = (20 + 2 * np.sin(cc / 25.0) * np.cos(rr / 30.0)).astype(np.float32)
    sigma = 0.2
    z = truth + rng.normal(0, sigma, truth.shape).astype(np.float32)
    res = filter_linear_prediction(z, g, LPParameters(cutoff=3.0, half_weight=1.0))
    rms = float(np.sqrt(np.mean((res.dtm - truth) ** 2)))
    # variance reduced by more than half (seed-002-003 checklist 23)
    assert rms < sigma * math.sqrt(0.5)


def test_manual_ground_points_are_exact_and_checked() -> None:
    g = _grid(100)
    _, cc = _xy(g.shape)
    plane = (10.0 + 0.02 * cc).astype(np.float32)
    z = plane.copy()
    z[30:60, 30:60] += 6.0  # a building
    cons = FilterConstraints.empty(g)
    t = g.transform
    pts = [(t.c + 80.5, t.f - 20.5, 10.0 + 0.02 * 80 + 2.0),  # 2 m above the ground
           (t.c + 10.5, t.f - 70.5, 10.0 + 0.02 * 10),  # on the ground
           (t.c + 45.5, t.f - 45.5, 10.0 + 0.02 * 45 + 0.05)]  # under the building
    cons.ground_points = np.array(pts)
    res = filter_linear_prediction(z, g, constraints=cons)
    for x, y, h in pts:
        r, c = g.cell_of(x, y)
        assert res.dtm[int(r), int(c)] == np.float32(h)  # exact
    assert [d["index"] for d in res.disagreeing] == [0]
    assert res.disagreeing[0]["dh"] == pytest.approx(-2.0, abs=0.3)


def test_breakline_keeps_a_vertical_step() -> None:
    g = _grid(80, 100)
    rr, cc = _xy(g.shape)
    truth = np.where(cc >= 50, 15.0, 10.0).astype(np.float32) + 0.01 * rr.astype(np.float32)
    z = truth.copy()
    t = g.transform
    x_step = t.c + 50.0  # the step lies on the cell border col 49 | col 50
    line = LineString([(x_step, t.f + 5.0), (x_step, t.f - 85.0)])
    cons = FilterConstraints.empty(g)
    cons.breaklines = [line]
    cons.barrier, cons.barrier_z = line_barrier([line], g)
    without = filter_linear_prediction(z, g)
    res = filter_linear_prediction(z, g, constraints=cons)
    side = (np.abs(cc - 49.5) < 4) & ~cons.barrier  # 3 cells each side, not the line cells
    err_with = np.abs(res.dtm - truth)[side].max()
    err_without = np.abs(without.dtm - truth)[side].max()
    assert err_with < 0.2
    assert err_without > 1.0  # the step is smeared without the breakline


def test_keep_and_remove_areas() -> None:
    g = _grid(120)
    rr, cc = _xy(g.shape)
    plane = (30.0 + 0.01 * cc).astype(np.float32)
    z = plane.copy()
    dam = (cc >= 50) & (cc < 70)
    z[dam] += 6.0  # an embankment across the grid
    bush = (rr >= 10) & (rr < 40) & (cc >= 5) & (cc < 35)
    z[bush] += 0.4  # low vegetation that looks like ground
    cons = FilterConstraints.empty(g)
    cons.keep = dam.copy()
    cons.remove = bush.copy()
    res = filter_linear_prediction(z, g, constraints=cons)
    assert np.array_equal(res.dtm[dam], z[dam])  # bit for bit
    assert res.ground[dam].all()
    assert np.abs(res.dtm[bush] - plane[bush]).max() < 0.15  # bridged
    assert not res.ground[bush].any()
    plain = filter_linear_prediction(z, g)
    assert np.mean(plain.dtm[dam] - plane[dam]) < 1.0  # the known failure: dam removed


def test_too_few_cells_is_an_input_error() -> None:
    g = _grid(20)
    z = np.full(g.shape, np.nan, np.float32)
    z[0, :5] = 1.0
    with pytest.raises(InputError):
        filter_linear_prediction(z, g)


def test_presets_are_complete_and_valid() -> None:
    assert set(LINEAR_PREDICTION_PRESETS) == set(PRESET_NAMES)
    for name, values in LINEAR_PREDICTION_PRESETS.items():
        prm = LPParameters.from_dict(values)
        assert prm.cutoff > prm.half_weight > 0, name
        assert prm.coarse_spacing > 0 and prm.ground_tolerance > 0, name


# -- I/O ---------------------------------------------------------------------------------------
def test_run_on_points_and_raster(tmp_path: Path) -> None:
    from photodem.algorithms.raster.io import write_raster

    rng = np.random.default_rng(5)
    n = 3000
    x = rng.uniform(0, 60, n)
    y = rng.uniform(0, 60, n)
    zt = 5.0 + 0.05 * x
    obj = (x > 20) & (x < 35) & (y > 20) & (y < 35)
    zz = zt + np.where(obj, 7.0, 0.0)
    pts = tmp_path / "pts.xyz"
    np.savetxt(pts, np.column_stack([x, y, zz, np.arange(n)]), fmt="%.3f")
    out = run_filter_linear_prediction(pts, tmp_path / "p", spacing=1.0, crs="EPSG:25832")
    labels = np.loadtxt(out["labels"]).astype(int)
    assert len(labels) == n and out["mask"] is None
    assert (labels[obj] == 1).mean() > 0.95 and (labels[~obj] == 0).mean() > 0.95
    report = json.loads(Path(out["report"]).read_text())
    assert report["algorithm"] == "filter_linear_prediction" and report["iterations"]

    g = _grid(60)
    _, cc = _xy(g.shape)
    dsm = (5.0 + 0.05 * cc).astype(np.float32)
    dsm[20:35, 20:35] += 7.0
    tif = tmp_path / "dsm.tif"
    write_raster(tif, dsm, transform=g.transform, crs="EPSG:25832")
    out = run_filter_linear_prediction(tif, tmp_path / "r", preset="urban",
                                       overrides={"cutoff": 0.8}, write_levels=True)
    assert out["labels"] is None and Path(out["mask"]).is_file()
    assert Path(out["dtm"]).is_file() and (tmp_path / "r" / "level_0.tif").is_file()
    assert out["metrics"]["parameters"]["cutoff"] == 0.8

    empty = tmp_path / "empty.tif"
    write_raster(empty, np.full((30, 30), np.nan, np.float32), transform=g.transform,
                 crs="EPSG:25832")
    with pytest.raises(InputError):
        run_filter_linear_prediction(empty, tmp_path / "nothing")
    assert not (tmp_path / "nothing").exists()


def test_isprs_samp11_default_parameters() -> None:
    """Real ALS sample (steep urban slopes): ISPRS measures with the default preset."""
    path = shared_data("isprs_filtertest") / "samp11.txt"
    data = np.loadtxt(path)
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        xyz = Path(tmp) / "xyz.txt"
        np.savetxt(xyz, data[:, :3], fmt="%.2f")
        out = run_filter_linear_prediction(xyz, Path(tmp) / "out")
        labels = np.loadtxt(out["labels"]).astype(int)
    ref = data[:, 3].astype(int)
    a = np.sum((ref == 0) & (labels == 0))
    b = np.sum((ref == 0) & (labels == 1))
    c = np.sum((ref == 1) & (labels == 0))
    d = np.sum((ref == 1) & (labels == 1))
    n = a + b + c + d
    po = (a + d) / n
    pe = ((a + b) * (a + c) + (c + d) * (b + d)) / n ** 2
    kappa = (po - pe) / (1 - pe)
    total = (b + c) / n
    # far better than "everything is ground" (total error 43 %); the goal (kappa > 85 %) is
    # tracked by the bench. Measured 7.8 % and 83.9 % (with the single lowest cell per block,
    # no slope allowance at level 0 and no full weight on the opening: 14.6 % and 71.0 %;
    # before the low-outlier net cut, the local slope allowance and the slope-dependent label
    # tolerance: 28.2 % and 46.6 %)
    assert total < 0.09 and kappa > 0.82


def test_steep_lidar_scene_default_preset(tmp_path: Path) -> None:
    """Walls, houses on the slope, trees, low blunders (the low-pass tests' scene)."""
    from tests.algorithms.filtering.test_lowpass import kappa_pct, steep_scene

    data = steep_scene()
    path = tmp_path / "steep.xyz"
    np.savetxt(path, data[:, :3], fmt="%.3f")
    out = run_filter_linear_prediction(path, tmp_path / "out", crs="EPSG:25832")
    t1, t2, kappa = kappa_pct(data[:, 3], np.loadtxt(out["labels"]).astype(int))
    # before: kappa 50.6 % (Type I 18.7 %: low blunders pulled the pyramid down); 88.1 % with
    # the single lowest cell per block (Type I 2.7 %); now 96.8 % (0.4 % / 2.6 %)
    assert kappa > 90.0 and t1 < 2.5 and t2 < 6.0


def test_low_blunders_do_not_pull_the_dtm_down() -> None:
    rng = np.random.default_rng(8)
    g = _grid(120)
    rr, cc = _xy(g.shape)
    plane = (40.0 + 0.4 * cc - 0.2 * rr).astype(np.float32)  # 45 % slope
    z = plane + rng.normal(0, 0.05, plane.shape).astype(np.float32)
    pits = rng.random(g.shape) < 0.003
    z[pits] -= rng.uniform(3.0, 20.0, pits.sum()).astype(np.float32)
    res = filter_linear_prediction(z, g)
    e = (res.dtm - plane)[~pits]
    # without the net cut: 99 % |Δh| 17 m (the pyramid's lowest cells are the pits)
    assert np.abs(np.median(e)) < 0.05 and np.percentile(np.abs(e), 99) < 0.2
    assert not res.ground[pits].any()


def test_pyramid_reduction_keeps_slopes_and_drops_objects() -> None:
    """Two lowest cells per block, moved along the slope: unbiased on a steep noisy plane."""
    rng = np.random.default_rng(9)
    rr, cc = _xy((120, 120))
    plane = 0.6 * cc - 0.3 * rr  # 67 % slope
    z = (plane + rng.normal(0.0, 0.2, plane.shape)).astype(np.float32)
    centre = 0.6 * (cc[0::2, 0::2] + 0.5) - 0.3 * (rr[0::2, 0::2] + 0.5)
    e = (reduce_lowest(z) - centre)[2:-2, 2:-2]
    # measured −0.05 m (σ = 0.2 m); the plain minimum lies about (0.6 + 0.3)/2 m below the
    # block centre
    assert abs(float(np.mean(e))) < 0.1 and float(np.std(e)) < 0.2
    assert float(np.mean((reduce_min(z) - centre)[2:-2, 2:-2])) < -0.4
    # a box whose edges cut blocks in half: those blocks stay on the ground
    flat = np.zeros((40, 40), np.float32)
    flat[9:31, 9:31] = 8.0
    red = reduce_lowest(flat)
    assert np.all(red[4:16, 4:16][[0, -1], 1:-1] == 0.0)  # half-covered edge blocks
    assert np.all(red[5:15, 5:15] == 8.0)  # fully covered blocks keep the object


def test_terraced_slope_points_stay_ground() -> None:
    """Lowest-point grid of a terraced 50 % slope (1 m steps every 6 m) stays ground.

    The terrace edges lie above any smooth surface by up to slope × half a cell: the slope
    allowance of the weights reaches the finest level (before: 97.3 % ground).
    """
    from photodem.algorithms.filtering.surface_input import FilterInput, grid_lowest, point_labels

    rng = np.random.default_rng(10)
    n = 5000
    x, y = rng.uniform(0, 80, n), rng.uniform(0, 80, n)
    z = 100.0 + 0.5 * x + 1.0 * np.floor(x / 6.0) + rng.normal(0.0, 0.05, n)
    xyz = np.column_stack([x, y, z])
    zg, grid, cells = grid_lowest(xyz, 1.0)
    prm = LPParameters.from_dict(LINEAR_PREDICTION_PRESETS["default"])
    res = filter_linear_prediction(zg, grid, prm)
    inp = FilterInput(zg, grid, None, points=xyz, point_cells=cells, source="points")
    labels = point_labels(inp, res.dtm, prm.ground_tolerance, prm.ground_slope_factor)
    assert (labels == 0).mean() > 0.985


def test_terrace_banks_stay_ground() -> None:
    """Flat terraces 25 m deep between 5 m banks of 100 % slope: the smooth prediction
    passes metres below the upper edge of a bank, which lies on the opening and keeps its
    weight (before: 6.9 % of the cells rejected, the DTM 2.9 m low)."""
    g = _grid(160)
    rr, _ = _xy(g.shape)
    y = 160.0 - rr - 0.5
    z = 100.0 + 5.0 * np.floor(y / 25.0) + np.clip(np.mod(y, 25.0) - 20.0, 0.0, 5.0)
    res = filter_linear_prediction(z.astype(np.float32), g)
    assert res.ground.all() and np.abs(res.dtm - z).max() < 0.2
