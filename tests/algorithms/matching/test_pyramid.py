"""Gaussian pyramid and level coordinates."""

from __future__ import annotations

import numpy as np
import pytest

from photodem.algorithms.matching.pyramid import (
    build_pyramid,
    convert_level,
    from_level,
    level_shape,
    levels_for_disparity,
    scale_distance,
    to_level,
)


def test_shapes_and_dtype():
    img = np.random.default_rng(0).random((101, 64))
    pyr = build_pyramid(img, 4)
    assert [p.shape for p in pyr] == [level_shape(img.shape, k) for k in range(4)]
    assert pyr[1].shape == (51, 32) and pyr[3].shape == (13, 8)
    assert all(p.dtype == np.float32 for p in pyr)


def test_coordinate_round_trip():
    x = np.array([-0.5, 0.0, 3.25, 100.0])
    for k in range(5):
        assert np.allclose(from_level(to_level(x, k), k), x)
        assert np.allclose(convert_level(convert_level(x, 0, k), k, 0), x)
    assert np.allclose(from_level(0.0, 1), 0.5)
    assert np.allclose(from_level(0.0, 2), 1.5)
    assert np.allclose(convert_level(1.0, 2, 1), 2.5)
    assert np.allclose(scale_distance(3.0, 2, 0), 12.0)


def test_linear_ramp_stays_consistent_with_coordinates():
    # a linear ramp g = x keeps g = level-0 coordinate of the pixel centre on every level
    img = np.tile(np.arange(64, dtype=float), (32, 1))
    pyr = build_pyramid(img, 4, sigma=1.0)
    for k, lev in enumerate(pyr):
        cols = np.arange(lev.shape[1])
        inner = slice(2, -2) if lev.shape[1] > 6 else slice(1, -1)
        assert np.allclose(lev[lev.shape[0] // 2, inner], from_level(cols, k)[inner], atol=1e-3)


def test_feature_position_across_levels():
    # a Gaussian blob at a known level-0 position is found at to_level() on coarser levels
    yy, xx = np.mgrid[0:128, 0:128]
    c0, r0 = 50.3, 70.8
    img = np.exp(-((xx - c0) ** 2 + (yy - r0) ** 2) / (2 * 6.0**2))
    for k, lev in enumerate(build_pyramid(img, 4)):
        ys, xs = np.mgrid[0 : lev.shape[0], 0 : lev.shape[1]]
        wsum = lev.sum()
        assert (lev * xs).sum() / wsum == pytest.approx(to_level(c0, k), abs=0.02)
        assert (lev * ys).sum() / wsum == pytest.approx(to_level(r0, k), abs=0.02)


def test_levels_for_disparity():
    assert levels_for_disparity(2.0) == 1
    assert levels_for_disparity(4.0) == 2
    assert levels_for_disparity(64.0, pull_in=2.0) == 6
    assert levels_for_disparity(65.0, pull_in=2.0) == 7
    assert levels_for_disparity(1000.0, shape=(200, 300), min_size=32) == 3
    with pytest.raises(ValueError):
        build_pyramid(np.zeros((8, 8)), 0)
