"""Radiometric balancing: known gains/offsets recovered, datum, histogram matching."""

from __future__ import annotations

import numpy as np
import pytest

from photodem.algorithms.ortho.balance import (
    BalanceImage,
    apply_balance,
    balance_images,
    overlap_stats,
    solve_gain_offset,
)

GAINS = (1.0, 1.25, 0.8)
OFFSETS = (0.0, -20.0, 15.0)


def _block(noise: float = 1.0, gamma: bool = False):
    """Three images (2 bands) in a row over one texture, each with its own gain/offset."""
    rng = np.random.default_rng(4)
    base = 60 + 100 * rng.random((2, 60, 200))
    images = []
    for k, (g, o) in enumerate(zip(GAINS, OFFSETS)):
        c0 = 60 * k
        v = g * base[:, :, c0:c0 + 80] + o + noise * rng.normal(size=(2, 60, 80))
        if gamma and k == 2:
            v = 255 * (np.clip(v, 0, 255) / 255) ** 2.0
        images.append(BalanceImage(0, c0, v.astype(np.float32), np.ones((60, 80), bool)))
    return images


def test_moments_of_the_overlaps() -> None:
    pairs = overlap_stats(_block(noise=0.0))
    assert [(p.i, p.j, p.n) for p in pairs] == [(0, 1, 60 * 20), (1, 2, 60 * 20)]
    p = pairs[0]
    assert p.mean_j == pytest.approx(1.25 * p.mean_i - 20, rel=1e-5)
    assert p.std_j == pytest.approx(1.25 * p.std_i, rel=1e-5)


def test_known_gains_and_offsets_recovered_with_a_reference() -> None:
    images = _block(noise=0.0)
    gains, offsets = solve_gain_offset(overlap_stats(images), 3, 2, reference=0)
    for k in range(3):  # g_k·(G_k·t + O_k) + o_k = t
        assert gains[k] == pytest.approx(1 / GAINS[k], rel=1e-4)
        assert offsets[k] == pytest.approx(-OFFSETS[k] / GAINS[k], abs=0.01)


def test_mean_gain_one_datum_and_overlaps_within_2_dn() -> None:
    images = _block(noise=2.0)
    gains, offsets, luts, report = balance_images(images, "gain_offset")
    assert gains.mean(axis=0) == pytest.approx([1.0, 1.0], abs=1e-6)
    assert offsets.sum(axis=0) == pytest.approx([0.0, 0.0], abs=1e-3)
    # all three balanced to one radiometry: g_k·G_k equal
    prod = gains[:, 0] * np.array(GAINS)
    assert prod.std() / prod.mean() < 0.01
    assert report["before"]["mean_difference"] > 10
    assert report["after"]["mean_difference"] <= 2.0
    assert all(luts[k] is None for k in range(3))
    corrected = apply_balance(images[1].bands, gains[1], offsets[1])
    assert corrected.dtype == np.float32 and corrected.shape == images[1].bands.shape


def test_histogram_matching_removes_a_non_linear_difference() -> None:
    images = _block(noise=0.0, gamma=True)
    _, _, _, lin = balance_images(images, "gain_offset")
    _, _, luts, hist = balance_images(images, "histogram")
    assert all(lut is not None for lut in luts)
    assert hist["after"]["mean_abs_difference"] < 0.7 * lin["after"]["mean_abs_difference"]
    assert hist["after"]["mean_difference"] <= 2.0


def test_isolated_image_is_left_unchanged() -> None:
    images = _block(noise=0.0)
    images.append(BalanceImage(500, 500, np.full((2, 10, 10), 99.0, np.float32),
                               np.ones((10, 10), bool)))
    gains, offsets, _, report = balance_images(images, "gain_offset", names=list("ABCD"))
    assert gains[3] == pytest.approx([1.0, 1.0], abs=1e-4)
    assert offsets[3] == pytest.approx([0.0, 0.0], abs=1e-2)
    assert [p["image_a"] + p["image_b"] for p in report["pairs"]] == ["AB", "BC"]
