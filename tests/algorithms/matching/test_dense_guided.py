"""The DSM-guided pass of dense matching: its guide, its uniqueness test, the verification of
the holes it fills, and the refinement frame that uses them (issue 22, part AD)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from photodem.algorithms.errors import InputError
from photodem.algorithms.matching import dense
from photodem.algorithms.matching.dense import DenseOptions
from photodem.algorithms.matching.dense_guided import (
    dsm_guide,
    unique_along_rows,
    verified_holes,
)

# a slope across the base: d = A + B·x + C·y (C px per row is a shear no window matcher takes)
A, B, C = -40.0, 0.1, 1.2


def _texture(h: int, w: int, periodic: bool, seed: int = 5):
    """A grey-value function g(x, y) of continuous x on rows 0..h−1: smooth random texture,
    or stripes of 12 px period along the row with a weak random texture."""
    rng = np.random.default_rng(seed)
    base = ndimage.gaussian_filter(rng.normal(size=(h, 4 * w)), 1.5)
    base = 60.0 * base / base.std()

    def g(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        rnd = ndimage.map_coordinates(base, [y, x + w], order=3, mode="nearest")
        if periodic:
            return 128.0 + 60.0 * np.sin(2 * np.pi * x / 12.0) + 0.1 * rnd
        return 128.0 + rnd

    return g


def sheared_pair(periodic: bool = False, h: int = 64, w: int = 200):
    """Left and right frame (common columns) and the true disparity of every left pixel:
    left pixel x of row y matches right pixel x − d(x, y), d = A + B·x + C·y; right pixels
    that show no left content are NaN."""
    g = _texture(h, w, periodic)
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    left = g(x, y)
    x_l = (x + A + C * y) / (1.0 - B)  # the left column a right pixel shows
    right = np.where((x_l >= 0) & (x_l <= w - 1), g(x_l, y), np.nan)
    truth = A + B * x + C * y
    return left.astype(np.float32), right.astype(np.float32), truth


def test_guided_options_are_checked() -> None:
    """An unknown choice of refined holes is refused with the choices."""
    with pytest.raises(InputError, match="objects, verified"):
        dense._checked_settings(DenseOptions(refine_holes="all"), -8, 8, (10, 10), (10, 10),
                                4, "x", 0)


def test_unique_along_rows_tells_random_texture_from_stripes() -> None:
    """A right match on random texture is unique; on stripes repeating every 12 px along the
    row a match one period off correlates as well as the right one — ambiguous."""
    for periodic, expected in ((False, True), (True, False)):
        left, right, truth = sheared_pair(periodic)
        warped = dense._warp_rows(right, truth.astype(np.float32))
        rows, cols = np.mgrid[20:44:4, 110:190:8]
        rows, cols = rows.ravel(), cols.ravel()
        ok = unique_along_rows(left, warped, rows, cols, np.zeros(rows.size))
        assert ok.mean() == (1.0 if expected else 0.0), (periodic, ok.mean())


def test_verified_holes_refine_a_sheared_slope_and_refuse_a_period_off() -> None:
    """Starting 0.4 px off the truth, least-squares matching with the guide's slope (1.2 px of
    shear per row) puts the holes within 0.05 px of it; on stripes, a start one period
    (12 px) off the truth is refused by the uniqueness test."""
    left, right, truth = sheared_pair()
    guide = (truth + 0.4).astype(np.float32)
    holes = np.zeros(left.shape, bool)
    holes[12:52, 100:175] = True  # windows beyond the right content are refused
    warped = dense._warp_rows(right, guide)
    residual = np.zeros(left.shape, np.float32)
    d, take = verified_holes(left, right, guide, residual, guide.copy(), holes, warped)
    assert take[holes].mean() > 0.9
    assert not take[~holes].any()
    err = np.abs(d - truth)[take]
    print(f"verified {take[holes].mean():.1%}, error median {np.median(err):.3f} px")
    assert np.median(err) < 0.05 and err.max() < 0.3

    left, right, truth = sheared_pair(periodic=True)
    wrong = (truth + 12.0).astype(np.float32)
    d, take = verified_holes(left, right, wrong, np.zeros(left.shape, np.float32), wrong,
                             holes, dense._warp_rows(right, wrong))
    assert take.sum() == 0


def test_refine_frame_fills_the_holes_of_a_sheared_slope_from_the_guide() -> None:
    """SGM cannot take a slope with 1.2 px of disparity per row; the guided refinement
    (``refine_holes="verified"``, the guide from ``extra``) matches it within ± 8 px of a
    guide 2 px off and gives the first pass's holes verified disparities; the default choice
    ("objects") gives terrain holes nothing."""
    cv2 = pytest.importorskip("cv2")
    left, right, truth = sheared_pair()
    first = np.full(left.shape, np.nan, np.float32)  # the first pass found nothing
    extra = (truth + 2.0).astype(np.float32)
    right_disp = np.full(left.shape, np.nan, np.float32)
    opts = DenseOptions(refine=8, normalise_window=21, block_size=7, refine_holes="verified")
    _, _, opts = dense._checked_settings(opts, -8, 8, left.shape, right.shape, 4, "x", 0)
    out = dense._refine_frame(cv2, left, right, first, opts, right_disp, extra)
    core = np.zeros(left.shape, bool)
    core[8:56, 100:185] = True
    got = np.isfinite(out) & core
    err = np.abs(out - truth)[got]
    print(f"filled {got.sum() / core.sum():.1%} of the core, error median "
          f"{np.median(err):.3f} px, max {err.max():.2f} px")
    assert got.sum() > 0.6 * core.sum()
    assert np.median(err) < 0.1 and np.percentile(err, 99) < 1.0
    plain = dense._refine_frame(cv2, left, right, first, DenseOptions(
        **{**opts.__dict__, "refine_holes": "objects"}), right_disp, extra)
    assert not np.isfinite(plain).any()


class _Pair:
    """A normal-case pair over flat ground: x_l = X·f/D, x_r = (X − B)·f/D (no rotation)."""

    height, sizes = 40, ((60, 40), (60, 40))
    focal, base, z_cam = 100.0, 10.0, 100.0

    def world_to_epipolar(self, pts: np.ndarray, side: str):
        depth = self.z_cam - pts[:, 2]
        x = pts[:, 0] - (self.base if side == "right" else 0.0)
        return x * self.focal / depth + 5.0, -pts[:, 1] * self.focal / depth + 20.0


def test_dsm_guide_projects_the_measured_cells_and_fills_the_rest() -> None:
    """A plane at 50 m, measured in a ring around an empty square, gives every left pixel
    the disparity of 50 m (f·B/D = 20 px): the hole is membrane-filled, pixels no cell
    reaches take their neighbour's value; nothing measured gives NaN."""
    from affine import Affine

    from photodem.algorithms.surface.gridding import Grid

    grid = Grid(Affine(0.1, 0.0, -2.0, 0.0, -0.1, 2.0), 60, 60, 0.1)
    z = np.full(grid.shape, 50.0, np.float32)
    measured = np.ones(grid.shape, bool)
    measured[20:40, 20:40] = False
    z[~measured] = 7.0  # interpolated heights are not trusted
    guide = dsm_guide(_Pair(), z, measured, grid)
    assert guide.shape == (40, 60)
    np.testing.assert_allclose(guide, 20.0, atol=1e-4)
    assert np.isnan(dsm_guide(_Pair(), z, np.zeros_like(measured), grid)).all()


def test_terrain_holes_keep_a_slope_and_refuse_a_hole_beside_a_roof() -> None:
    """A hole on a 40° slope (its border rises 0.1 m per cell round it) is terrain; a hole
    whose border holds a roof edge 6 m above the ground next to it is not, nor one whose
    border is a single measured speck on a roof; cells outside the area are never holes."""
    from photodem.algorithms.matching.dense_guided import terrain_holes

    x = np.mgrid[0:40, 0:80][1].astype(np.float64)
    z = (0.12 * x).astype(np.float32)  # 0.12 m per 0.14 m cell ≈ 40°
    measured = np.ones(z.shape, bool)
    measured[10:30, 5:25] = False  # a hole in the slope
    measured[10:30, 45:65] = False  # a hole beside a roof
    z[8:10, 45:65] = 10.0  # the roof's edge along the top of the second hole
    area = np.ones(z.shape, bool)
    area[:, 75:] = False
    measured[:, 75:] = False
    got = terrain_holes(z, measured, area, 1.5)
    assert got[10:30, 5:25].all()
    assert not got[10:30, 45:65].any()
    assert not got[:, 75:].any()
    # an unmeasured roof with one measured speck at roof height inside
    z2, m2 = np.zeros((30, 30), np.float32), np.ones((30, 30), bool)
    m2[5:25, 5:25] = False
    m2[15, 15], z2[15, 15] = True, 6.0
    assert not terrain_holes(z2, m2, np.ones_like(m2), 1.5).any()
