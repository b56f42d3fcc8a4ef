import numpy as np
import pytest

from photodem.algorithms.quality.targets import target_centroids


def _disc_image(centres, radius, shape=(120, 160), contrast=60.0, noise=0.0, seed=0):
    rng = np.random.default_rng(seed)
    rows, cols = np.mgrid[0 : shape[0], 0 : shape[1]]
    img = np.full(shape, 80.0)
    ss = 8  # supersampled, anti-aliased discs
    sub = (np.arange(ss) + 0.5) / ss - 0.5
    for cx, cy in centres:
        cover = np.zeros(shape)
        for oy in sub:
            for ox in sub:
                cover += np.hypot(cols + ox - cx, rows + oy - cy) <= radius
        img += contrast * cover / ss**2
    return img + rng.normal(0.0, noise, shape) if noise else img


def test_centroids_of_subpixel_discs_are_exact_without_noise():
    true = np.array([[30.3, 40.7], [80.55, 61.2], [121.9, 90.45]])
    img = _disc_image(true, radius=3.0)
    c, r, ok = target_centroids(img, true[:, 0] + 1.2, true[:, 1] - 0.9, radius=5.0)
    assert ok.all()
    assert np.abs(c - true[:, 0]).max() < 0.01
    assert np.abs(r - true[:, 1]).max() < 0.01


def test_centroid_precision_with_noise_and_rejections():
    rng = np.random.default_rng(1)
    true = np.column_stack([rng.uniform(15, 145, 30), rng.uniform(15, 105, 30)])
    # keep targets apart so windows hold one disc each
    keep = [0]
    for i in range(1, len(true)):
        if np.min(np.hypot(*(true[keep] - true[i]).T)) > 18:
            keep.append(i)
    true = true[keep]
    img = _disc_image(true, radius=3.0, noise=2.0)
    c, r, ok = target_centroids(img, true[:, 0], true[:, 1], radius=5.0)
    assert ok.all()
    err = np.hypot(c - true[:, 0], r - true[:, 1])
    assert np.sqrt(np.mean(err**2)) < 0.05
    # outside the image, on NaN, or without contrast: rejected
    img[10:30, 10:30] = np.nan
    c, r, ok = target_centroids(img, [2.0, 20.0, 150.0], [2.0, 20.0, 60.0], radius=5.0)
    assert not ok.any() and np.isnan(c).all()


@pytest.mark.parametrize("dtype", [np.uint8, np.float32])
def test_accepts_integer_and_float_images(dtype):
    img = _disc_image([(50.0, 50.0)], radius=3.0).clip(0, 255).astype(dtype)
    c, r, ok = target_centroids(img, [51.0], [49.0], radius=5.0)
    assert ok[0] and abs(c[0] - 50.0) < 0.05 and abs(r[0] - 50.0) < 0.05
