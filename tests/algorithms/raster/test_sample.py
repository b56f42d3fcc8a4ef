"""raster.sample.bilinear_grid: the one bilinear sampler, its edge, nodata and order choices."""

from __future__ import annotations

import numpy as np
import pytest

from photodem.algorithms.raster.sample import EDGES, NODATA, ORDERS, bilinear_grid

H, W = 6, 9


def _ramp() -> np.ndarray:
    # z = 3 + 2·col − 4·row: bilinear interpolation reproduces a linear ramp
    rows, cols = np.mgrid[0:H, 0:W]
    return 3.0 + 2.0 * cols - 4.0 * rows


def _ramp_at(col: np.ndarray, row: np.ndarray) -> np.ndarray:
    return 3.0 + 2.0 * col - 4.0 * row


@pytest.mark.parametrize("order", ORDERS)
@pytest.mark.parametrize("edge", EDGES)
def test_ramp_reproduced_exactly_inside(edge: str, order: str) -> None:
    # dyadic positions (multiples of 1/8) keep every product exact: the ramp comes back bit
    # for bit, with every edge policy and evaluation order
    k = np.arange(0, 8 * (W - 1) + 1) / 8.0
    r = np.arange(0, 8 * (H - 1) + 1) / 8.0
    col, row = np.meshgrid(k, r)
    got = bilinear_grid(_ramp(), col, row, edge=edge, order=order)
    assert np.array_equal(got, _ramp_at(col, row))


@pytest.mark.parametrize("order", ORDERS)
def test_ramp_at_random_positions(order: str) -> None:
    rng = np.random.default_rng(3)
    col = rng.uniform(0, W - 1, 1000)
    row = rng.uniform(0, H - 1, 1000)
    np.testing.assert_allclose(bilinear_grid(_ramp(), col, row, order=order),
                               _ramp_at(col, row), rtol=0, atol=1e-12)


def test_edge_nan_outside_the_hull_of_cell_centres() -> None:
    col = np.array([-0.5, -1e-9, 0.0, W - 1.0, W - 1 + 1e-9, W - 0.5, 2.0, np.nan])
    row = np.array([2.0, 2.0, 2.0, 2.0, 2.0, 2.0, -0.25, 2.0])
    got = bilinear_grid(_ramp(), col, row, edge="nan")
    assert np.isnan(got[[0, 1, 4, 5, 6, 7]]).all()
    assert np.array_equal(got[[2, 3]], _ramp_at(col[[2, 3]], row[[2, 3]]))


def test_edge_clamp_takes_the_nearest_edge_value() -> None:
    col = np.array([-0.5, -3.0, W - 0.5, W + 4.0, 3.5, 3.5, -2.0, np.nan])
    row = np.array([2.5, 2.5, 2.5, 2.5, -0.5, H + 1.0, H + 2.0, 2.0])
    got = bilinear_grid(_ramp(), col, row, edge="clamp")
    want = _ramp_at(np.clip(col, 0, W - 1), np.clip(row, 0, H - 1))
    assert np.array_equal(got[:-1], want[:-1])
    assert np.isnan(got[-1])  # a NaN position stays NaN


@pytest.mark.parametrize("order", ORDERS)
def test_nodata_weighted_and_any(order: str) -> None:
    z = _ramp()
    z[2, 3] = np.nan
    # at the valid centre (row 1, col 3) and on the column line col = 2 the NaN cell
    # (row 2, col 3) is a neighbour of weight 0; at (2, 3.5) and (2.5, 2.5) it has weight > 0
    col = np.array([3.0, 2.0, 3.5, 2.5])
    row = np.array([1.0, 2.5, 2.0, 2.5])
    weighted = bilinear_grid(z, col, row, nodata="weighted", order=order)
    assert np.array_equal(weighted[:2], _ramp_at(col[:2], row[:2]))
    assert np.isnan(weighted[2:]).all()
    assert np.isnan(bilinear_grid(z, col, row, nodata="any", order=order)).all()
    # far from the NaN both policies agree
    assert bilinear_grid(z, 7.25, 4.5, nodata="any", order=order) == _ramp_at(7.25, 4.5)


def test_separable_rows_path_equals_pointwise() -> None:
    rng = np.random.default_rng(5)
    z = rng.normal(size=(H, W))
    z[rng.random((H, W)) < 0.15] = np.nan
    col = np.concatenate([rng.uniform(-1, W, 40), np.arange(W, dtype=float)])
    row = np.concatenate([rng.uniform(-1, H, 30), np.arange(H, dtype=float)])
    grid = bilinear_grid(z, col[None, :], row[:, None], order="rows")
    cc, rr = np.meshgrid(col, row)
    point = bilinear_grid(z, cc, rr, order="rows")
    assert np.array_equal(grid, point, equal_nan=True)
    np.testing.assert_allclose(grid, bilinear_grid(z, cc, rr), rtol=0, atol=1e-12)


def test_float32_and_integer_arrays_give_float64() -> None:
    z = _ramp()
    for a in (z.astype(np.float32), z.astype(np.int32)):
        got = bilinear_grid(a, np.array([1.5]), np.array([2.25]))
        assert got.dtype == np.float64 and got[0] == _ramp_at(1.5, 2.25)


def test_unknown_choice_is_refused() -> None:
    for kw in ({"edge": "wrap"}, {"nodata": "ignore"}, {"order": "cubic"}):
        with pytest.raises(ValueError):
            bilinear_grid(_ramp(), 1.0, 1.0, **kw)
    assert NODATA == ("weighted", "any")
