"""Tiles for large DSMs, the positive definite covariance kernel, bad input of linear prediction."""

from __future__ import annotations

import numpy as np
import pytest
from affine import Affine

from photodem.algorithms.errors import InputError
from photodem.algorithms.filtering.linear_prediction import (
    MAX_NEGATIVITY,
    Covariance,
    LPParameters,
    _kernel,
    filter_linear_prediction,
    lp_solve,
)
from photodem.algorithms.filtering.lowpass import lowpass_filter, lowpass_parameters
from photodem.algorithms.filtering.tiles import feather, tile_windows
from photodem.algorithms.processing import registry
from photodem.algorithms.raster.io import write_raster
from photodem.algorithms.surface.gridding import Grid


def test_tile_cores_partition_the_grid_and_pads_stay_inside() -> None:
    shape = (1000, 730)
    tiles = tile_windows(shape, 300 * 300, 40)
    assert len(tiles) > 1
    count = np.zeros(shape, int)
    for (r0, r1, c0, c1), (q0, q1, p0, p1) in tiles:
        assert 0 <= r0 <= q0 < q1 <= r1 <= shape[0] and 0 <= c0 <= p0 < p1 <= c1 <= shape[1]
        assert r0 % 128 == 0 and c0 % 128 == 0  # pyramid blocks line up with the whole grid
        count[q0:q1, p0:p1] += 1
    assert (count == 1).all()
    assert tile_windows((100, 100), 10 ** 4, 40) == [((0, 100, 0, 100), (0, 100, 0, 100))]


def test_feather_ramps_only_at_cut_edges() -> None:
    w = feather((0, 50, 128, 300), (50, 300), 10)
    assert w.shape == (50, 172)
    assert np.all(w[:, -1] == 1.0)  # the raster border: full weight
    assert w[25, 0] == pytest.approx(0.5 / 10.5) and w[25, 10] == 1.0
    assert np.all(np.diff(w[25, :11]) > 0)


def _hill_with_houses(n: int, spacing: float, seed: int = 3) -> np.ndarray:
    rng = np.random.default_rng(seed)
    r, c = np.mgrid[0:n, 0:n] * spacing
    z = 100 + 8 * np.sin(c / 150.0) * np.cos(r / 110.0) + 0.03 * c
    for _ in range(n // 6):  # houses 8–16 m, far below the tile overlap
        h, w = rng.integers(4, 8, 2)
        i, j = rng.integers(0, n - h), rng.integers(0, n - w)
        z[i:i + h, j:j + w] = z[i:i + h, j:j + w].max() + rng.uniform(4, 10)
    z += rng.normal(0, 0.1, z.shape)
    return z.astype(np.float32)


def test_lowpass_tiled_equals_untiled() -> None:
    n, s = 420, 2.0
    z = _hill_with_houses(n, s)
    grid = Grid(Affine(s, 0, 0, 0, -s, n * s), n, n, s)
    par = lowpass_parameters()
    a = lowpass_filter(z, s, par, None, grid)
    b = lowpass_filter(z, s, par, None, grid, max_cells=300 * 300)
    assert b["tiles"] > 1
    assert np.array_equal(a["ground"], b["ground"])
    d = np.abs(a["dtm"] - b["dtm"])
    assert np.nanmax(d) < 0.05 and np.sqrt(np.nanmean(d ** 2)) < 0.005


def test_linear_prediction_tiled_close_to_untiled() -> None:
    n, s = 400, 2.0
    z = _hill_with_houses(n, s)
    grid = Grid(Affine(s, 0, 0, 0, -s, n * s), n, n, s)
    a = filter_linear_prediction(z, grid)
    b = filter_linear_prediction(z, grid, max_cells=300 * 300)
    d = np.abs(a.dtm - b.dtm)
    # the coarse levels see only their tile: decimetres at most, centimetres typically
    assert np.sqrt(np.nanmean(d ** 2)) < 0.05 and np.nanquantile(d, 0.99) < 0.2
    assert np.mean(a.ground != b.ground) < 0.01


def test_kernel_is_positive_definite_enough() -> None:
    for corr in (1.0, 2.0, 3.0, 4.5, 6.0):
        k = _kernel(corr).astype(np.float64)
        d = np.arange(len(k)) - len(k) // 2
        f = np.linspace(0, 0.5, 513)
        spec = (np.cos(2 * np.pi * f[:, None] * d[None, :]) * k).sum(axis=1)
        assert -spec.min() * spec[0] <= MAX_NEGATIVITY * 1.01


def test_long_correlation_small_noise_converges() -> None:
    """corr = 6 cells with 1 % noise: with a 2.5·c truncation C + D was indefinite and the
    conjugate gradients overflowed (the coarsest level of a 4000² DSM)."""
    rng = np.random.default_rng(0)
    lz = np.cumsum(np.cumsum(rng.normal(0, 1, (80, 80)), 0), 1).astype(np.float32)
    lz -= lz.mean()
    act = np.ones(lz.shape, bool)
    cov = Covariance(float(lz.var()), 0.009 * float(lz.var()), 6.0, float(lz.var()))
    with np.errstate(over="raise", invalid="raise"):
        s, _, its = lp_solve(lz, act, cov, tol=5e-3, maxiter=2000)
    assert its < 2000 and np.isfinite(s).all()
    assert np.sqrt(np.mean((s - lz) ** 2)) < np.std(lz)


def test_linear_prediction_bad_input_one_line_error_nothing_written(tmp_path) -> None:
    t = Affine(1.0, 0, 0, 0, -1.0, 40.0)
    nan = tmp_path / "nan.tif"
    write_raster(nan, np.full((40, 40), np.nan, np.float32), t, "EPSG:25832")
    with pytest.raises(InputError) as err:
        registry.run("filter_linear_prediction", {"input": str(nan),
                                                  "output": str(tmp_path / "o1")})
    assert "\n" not in str(err.value)
    few = tmp_path / "few.xyz"
    few.write_text("1 1 1\n2 2 2\n3 3 3\n4 4 4\n")
    with pytest.raises(InputError) as err:
        registry.run("filter_linear_prediction", {"input": str(few),
                                                  "output": str(tmp_path / "o2")})
    assert "\n" not in str(err.value)
    ok = tmp_path / "ok.tif"
    write_raster(ok, np.full((40, 40), 5.0, np.float32), t, None)
    with pytest.raises(InputError, match="CRS") as err:
        registry.run("filter_linear_prediction", {"input": str(ok), "crs": "EPSG:999999",
                                                  "output": str(tmp_path / "o3")})
    assert "\n" not in str(err.value)
    assert not any(p.name.startswith(("o1", "o2", "o3", ".o")) for p in tmp_path.iterdir())
    with pytest.raises(InputError):
        filter_linear_prediction(np.full((40, 40), np.nan, np.float32),
                                 Grid(t, 40, 40, 1.0), LPParameters(), max_cells=100)
