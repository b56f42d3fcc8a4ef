"""Förstner operator: corners at sub-pixel accuracy, edges rejected, grid selection."""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from photodem.algorithms.matching.interest import forstner, forstner_measures


def _checkerboard(shift=(0.0, 0.0), size=160, square=20, blur=1.0, upsample=8):
    # rendered at 8× resolution, blurred and box-averaged: true corners at known sub-pixel spots
    n = size * upsample
    x = (np.arange(n) + 0.5) / upsample - 0.5 - shift[0]
    y = (np.arange(n) + 0.5) / upsample - 0.5 - shift[1]
    board = ((np.floor(x[None, :] / square) + np.floor(y[:, None] / square)) % 2).astype(float)
    img = board.reshape(size, upsample, size, upsample).mean(axis=(1, 3))
    return 50 + 100 * ndimage.gaussian_filter(img, blur)


def test_checkerboard_corners_subpixel():
    sx, sy = 0.37, -0.21
    img = _checkerboard((sx, sy))
    cols, rows, w, q = forstner(img, q_min=0.6)
    # the board edges lie at pixel coordinate 20k + shift (pixel centres at integers)
    k = np.arange(1, 8)
    tc = 20 * k + sx
    tr = 20 * k + sy
    tx, ty = np.meshgrid(tc, tr)
    truth = np.column_stack([tx.ravel(), ty.ravel()])
    d = np.hypot(cols[:, None] - truth[None, :, 0], rows[:, None] - truth[None, :, 1])
    nearest = d.min(axis=0)
    assert (nearest < 0.1).all(), nearest.max()
    # nothing but corners inside the board: every point is within 1 px of a corner
    inner = (cols > 10) & (cols < 150) & (rows > 10) & (rows < 150)
    assert (d.min(axis=1)[inner] < 1.0).all()
    assert (q > 0.6).all() and np.all(np.diff(w) <= 0)


def test_edges_have_low_roundness_and_are_rejected():
    img = np.zeros((80, 80))
    img[:, 40:] = 100.0
    img = ndimage.gaussian_filter(img, 1.0) + np.random.default_rng(0).normal(0, 0.5, img.shape)
    _, q, _ = forstner_measures(img)
    assert np.median(q[10:-10, 37:43]) < 0.2
    pts = forstner(img, q_min=0.6, w_factor=5.0)
    near_edge = np.abs(pts.cols - 39.5) < 3
    assert near_edge.sum() == 0


def test_rectangle_corners():
    img = np.zeros((100, 100))
    img[30:70, 25:75] = 100.0
    img = ndimage.gaussian_filter(img, 1.0)
    cols, rows, _, _ = forstner(img, q_min=0.5)
    truth = np.array([[24.5, 29.5], [74.5, 29.5], [24.5, 69.5], [74.5, 69.5]])
    d = np.hypot(cols[:, None] - truth[None, :, 0], rows[:, None] - truth[None, :, 1])
    assert cols.size == 4
    assert d.min(axis=0).max() < 0.6  # L-corners are biased inwards by the blur, a bit


def test_grid_selection_spreads_points():
    rng = np.random.default_rng(3)
    img = ndimage.gaussian_filter(rng.standard_normal((200, 200)), 1.5)
    all_pts = forstner(img)
    grid = forstner(img, grid_cell=25, per_cell=2, subpixel=False)
    cell = (grid.rows.astype(int) // 25) * 10 + grid.cols.astype(int) // 25
    assert np.bincount(cell).max() <= 2
    assert 0 < grid.cols.size < all_pts.cols.size
    assert np.unique(cell).size >= 0.9 * 64  # inner cells (border excluded) all have points
    assert forstner(img, max_points=10).cols.size == 10
