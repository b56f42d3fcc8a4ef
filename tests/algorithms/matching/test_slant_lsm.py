"""LSM refinement of the slant passes' disparities (issue 22, part X) on synthetic slopes."""

from __future__ import annotations

import numpy as np
import pytest
from _slopes import slope_pair

from photodem.algorithms.matching.dense import array_source
from photodem.algorithms.matching.slant_lsm import refine_slant


def _slope_pair(k: float, periodic: bool = False) -> tuple:
    return slope_pair(k, periodic, h=80, seed=5)


def _points(truth: np.ndarray, h: int = 80) -> tuple:
    rows, cols = np.mgrid[10:h - 10:3, 10:118:3]
    return cols.ravel(), rows.ravel(), truth[cols.ravel()]


@pytest.mark.parametrize("k, scale", [(2.0, 0.7), (1.6, 0.7), (0.6, 1.4)])
def test_refinement_brings_a_slant_disparity_to_the_truth(k: float, scale: float) -> None:
    """Started 0.6 px off on a slope of scale ``k`` (the pass's stretch ``1/scale`` as the
    start of the x-scale), LSM ends within 0.2 px of the truth (measured ≤ 0.09 px) at all
    points whose windows lie inside the right image."""
    left, right, truth = _slope_pair(k)
    cols, rows, d_true = _points(truth)
    d, keep = refine_slant(array_source(left)[0], array_source(right)[0], d_true + 0.6, cols,
                           rows, scale)
    err = np.abs(d - d_true)[keep]
    print(f"k {k}: kept {keep.mean():.3f}, max error {err.max():.3f} px")
    assert keep.mean() > 0.95
    assert err.max() < 0.2


def test_refinement_rejects_a_wrong_start() -> None:
    """A start 3 or 4 px off (random texture) or half a period off (stripes) is not kept: LSM
    moves more than 1 px from it or ends at a low correlation."""
    for periodic, offsets in ((False, (3.0, -4.0)), (True, (4.0 * 1.5, -2.0 * 1.5))):
        left, right, truth = _slope_pair(1.5, periodic)
        cols, rows, d_true = _points(truth)
        src_l, src_r = array_source(left)[0], array_source(right)[0]
        _, keep = refine_slant(src_l, src_r, d_true + 0.3, cols, rows, 0.7)
        assert keep.mean() > 0.9  # the right start is kept on this texture
        for off in offsets:
            _, keep = refine_slant(src_l, src_r, d_true + off, cols, rows, 0.7)
            print(f"periodic {periodic}, start {off:+.1f} px off: kept {keep.mean():.3f}")
            assert keep.mean() < 0.02


def test_refinement_rejects_windows_on_masked_pixels() -> None:
    """Points whose right window reaches masked pixels are not kept (their grey values are
    made up), the others are."""
    left, right, truth = _slope_pair(1.5)
    right[:, :60] = np.nan
    cols, rows, d_true = _points(truth)
    _, keep = refine_slant(array_source(left)[0], array_source(right)[0], d_true, cols, rows,
                           0.7)
    x_r = cols - d_true
    assert not keep[x_r < 60 + 5].any()
    assert keep[x_r > 60 + 12].mean() > 0.95


def test_refinement_in_chunks_gives_the_same_result(monkeypatch) -> None:
    """Chunks of points (each on the windows of its own bounding box) change nothing."""
    from photodem.algorithms.matching import slant_lsm

    left, right, truth = _slope_pair(1.6)
    cols, rows, d_true = _points(truth)
    src_l, src_r = array_source(left)[0], array_source(right)[0]
    d_all, keep_all = refine_slant(src_l, src_r, d_true + 0.4, cols, rows, 0.7)
    monkeypatch.setattr(slant_lsm, "CHUNK_POINTS", 37)
    d, keep = refine_slant(src_l, src_r, d_true + 0.4, cols, rows, 0.7)
    np.testing.assert_array_equal(keep, keep_all)
    np.testing.assert_allclose(d[keep], d_all[keep], atol=1e-6)
