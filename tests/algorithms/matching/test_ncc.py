"""NCC: integer and sub-pixel shifts, epipolar and 2-D search, ambiguity and validity."""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from photodem.algorithms.matching.ncc import ncc_epipolar, ncc_search_2d, ncc_surface


def _texture(shape, sigma, seed=0):
    t = ndimage.gaussian_filter(np.random.default_rng(seed).standard_normal(shape), sigma)
    return 100 + 30 * t / t.std()


def _shifted(img, dx, dy):
    # right(x) = left(x + dx, y + dy): a left point (c, r) is at (c − dx, r − dy) on the right
    yy, xx = np.mgrid[0 : img.shape[0], 0 : img.shape[1]].astype(float)
    return ndimage.map_coordinates(img, [yy + dy, xx + dx], order=3, mode="reflect")


def test_surface_is_one_for_identical_windows():
    rng = np.random.default_rng(1)
    t = rng.random((3, 5, 5))
    s = np.zeros((3, 5, 9))
    s[:, :, 2:7] = 2 * t + 7  # linear radiometric change
    rho = ncc_surface(t, s)
    assert rho.shape == (3, 1, 5)
    assert np.allclose(rho[:, 0, 2], 1.0, atol=1e-5)


def test_epipolar_integer_shifts_99_percent():
    rng = np.random.default_rng(2)
    left = _texture((300, 400), 1.2)
    d = 13
    right = np.roll(left, -d, axis=1) + rng.normal(0, 3, left.shape)  # right col = left col − d
    cols = rng.integers(60, 380, 2000)
    rows = rng.integers(10, 290, 2000)
    res = ncc_epipolar(left, right, cols, rows, -5, 40, window=11)
    ok = np.abs(res.disparity - d) < 0.5
    assert ok.mean() >= 0.99
    assert res.valid.mean() >= 0.99 and (res.ncc[res.valid] > 0.8).all()


def test_epipolar_subpixel_on_smooth_texture():
    rng = np.random.default_rng(3)
    left = _texture((200, 300), 2.5)
    d = 7.3
    right = _shifted(left, d, 0.0)
    cols = rng.integers(40, 280, 500)
    rows = rng.integers(10, 190, 500)
    res = ncc_epipolar(left, right, cols, rows, np.full(500, 0), np.full(500, 15), window=11)
    err = res.disparity[res.valid] - d
    assert res.valid.mean() > 0.98
    assert np.sqrt(np.mean(err**2)) < 0.1


def test_search_2d_subpixel_and_fraction_carried():
    rng = np.random.default_rng(4)
    left = _texture((200, 200), 2.5)
    dx, dy = -2.4, 3.2
    right = _shifted(left, dx, dy)
    c = rng.uniform(40, 160, 300)
    r = rng.uniform(40, 160, 300)
    res = ncc_search_2d(left, right, c, r, c - dx + 1.7, r - dy - 1.2, radius=5, window=13)
    e = np.hypot(res.cols - (c - dx), res.rows - (r - dy))
    assert res.valid.mean() > 0.98
    assert np.sqrt(np.mean(e[res.valid] ** 2)) < 0.2  # 2-D parabola per axis: a little coarser


def test_invalid_and_ambiguous_cases():
    left = np.full((60, 200), 50.0)
    right = left.copy()
    res = ncc_epipolar(left, right, [100], [30], 0, 10)  # no texture
    assert not res.valid[0]
    # a periodic pattern along the row: ambiguous, the ratio is near 1
    x = np.arange(200)
    stripes = np.tile(100 + 50 * np.sin(2 * np.pi * x / 6.0), (60, 1))
    res = ncc_epipolar(stripes, stripes, [100], [30], -10, 10, window=7)
    assert res.ratio[0] > 0.9 and not res.valid[0]
    # shift outside the search range: the peak lies on the range border → invalid
    tex = _texture((60, 200), 1.2)
    res = ncc_epipolar(tex, np.roll(tex, -20, axis=1), [120], [30], 0, 10)
    assert not res.valid[0]
    # template leaving the image → invalid, not an exception
    res = ncc_epipolar(tex, tex, [2], [30], -3, 3)
    assert not res.valid[0]
