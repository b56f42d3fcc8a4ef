"""Occlusion test (ray marching with empty-space skipping) against closed forms."""

from __future__ import annotations

import numpy as np
import pytest
from affine import Affine

from photodem.algorithms.ortho.visibility import (
    fill_from_below,
    march_margin,
    nearest_valid_along,
    occluded,
)

CELL = 0.1
X0, Y1 = 1000.0, 2000.0
N = 600  # 60 m × 60 m
BOX = (1020.0, 1030.0, 1950.0, 1962.0)  # xmin, xmax, ymin, ymax of a 12 m block
GROUND, HEIGHT = 100.0, 12.0
CENTRE = np.array([1045.0, 1935.0, 180.0])  # south-east of the block, 80 m above ground


def _scene():
    T = Affine(CELL, 0.0, X0, 0.0, -CELL, Y1)
    xs = X0 + (np.arange(N) + 0.5) * CELL
    ys = Y1 - (np.arange(N) + 0.5) * CELL
    gx, gy = np.meshgrid(xs, ys)
    inside = (gx > BOX[0]) & (gx < BOX[1]) & (gy > BOX[2]) & (gy < BOX[3])
    dsm = np.where(inside, GROUND + HEIGHT, GROUND)
    return T, gx, gy, inside, dsm


def _box_shadow(gx, gy):
    """Closed form: ground points whose segment to the centre passes through the block.

    Along P + t (C − P), t ∈ [0, 1], the height is Z + t (C_z − Z); the segment is below the
    roof for t ≤ h / (C_z − Z). Slab method for the interval of t inside the rectangle.
    """
    t_lo = np.zeros(gx.shape)
    t_hi = np.full(gx.shape, HEIGHT / (CENTRE[2] - GROUND))
    for p, c, lo, hi in ((gx, CENTRE[0], BOX[0], BOX[1]), (gy, CENTRE[1], BOX[2], BOX[3])):
        d = c - p
        with np.errstate(divide="ignore", invalid="ignore"):
            a, b = (lo - p) / d, (hi - p) / d
        t0, t1 = np.minimum(a, b), np.maximum(a, b)
        t_lo, t_hi = np.maximum(t_lo, t0), np.minimum(t_hi, t1)
    return t_lo < t_hi


def test_box_shadow_matches_closed_form() -> None:
    T, gx, gy, inside, dsm = _scene()
    z = dsm.copy()  # the cells' surface points are on the DSM (true ortho)
    occ = occluded(gx, gy, z, CENTRE, dsm, T)
    truth = _box_shadow(gx, gy) & ~inside
    # the ramp of the bilinear DSM makes the walls 1 cell wide: compare away from the edges
    from scipy.ndimage import binary_dilation, binary_erosion

    def rim(mask):
        return binary_dilation(mask, iterations=2) & ~binary_erosion(mask, iterations=2)

    edge = rim(inside) | rim(truth)
    assert truth.sum() > 2000  # a real shadow: lean h·R/H = 12 · ~25 / 80 ≈ 4 m
    mismatch = (occ != truth) & ~edge
    assert mismatch.sum() == 0, mismatch.sum()
    iou = (occ & truth).sum() / (occ | truth).sum()
    assert iou > 0.95, iou
    # the roof itself and the ground on the camera side are visible
    assert not occ[binary_erosion(inside, iterations=2)].any()
    assert not occ[gy < BOX[2] - 1.0].any()


def test_skipping_does_not_change_the_result() -> None:
    T, gx, gy, _, dsm = _scene()
    sub = (slice(None, None, 3), slice(None, None, 3))
    fast = occluded(gx[sub], gy[sub], dsm[sub], CENTRE, dsm, T)
    plain = occluded(gx[sub], gy[sub], dsm[sub], CENTRE, dsm, T, levels=())
    assert np.array_equal(fast, plain)


def test_flat_terrain_nodata_and_nadir_are_visible() -> None:
    T = Affine(1.0, 0.0, 0.0, 0.0, -1.0, 100.0)
    ramp = np.add.outer(np.zeros(100), np.linspace(0.0, 10.0, 100))  # 10 % slope
    gx, gy = np.meshgrid(np.arange(100) + 0.5, 100 - (np.arange(100) + 0.5))
    z = ramp.copy()
    assert not occluded(gx, gy, z, [50.0, 50.0, 500.0], ramp, T).any()
    holes = ramp.copy()
    holes[40:60, 20:30] = np.nan  # nodata never occludes
    assert not occluded(gx, gy, z, [50.0, 50.0, 500.0], holes, T).any()
    # NaN heights give False; a point exactly below the centre is visible
    assert not occluded([np.nan, 50.0], [50.0, 50.0], [1.0, 5.0], [50.0, 50.0, 500.0],
                        ramp, T).any()


def test_march_margin_closed_form() -> None:
    # (h_max − Z) · r / (C_z − Z) = (130 − 100) · 40 / (300 − 100) = 6 m
    assert march_margin([100.0], [40.0], 300.0, 130.0) == pytest.approx(6.0)
    # never longer than the distance to the nadir, NaN ignored, nothing above: 0
    assert march_margin([100.0, np.nan], [4.0, 1.0], 101.0, 200.0) == pytest.approx(4.0)
    assert march_margin([150.0], [40.0], 300.0, 130.0) == 0.0


def test_rotated_window_is_rejected() -> None:
    with pytest.raises(ValueError):
        occluded([0.0], [0.0], [0.0], [0.0, 0.0, 10.0], np.zeros((3, 3)),
                 Affine(1.0, 0.1, 0.0, 0.1, -1.0, 0.0))


def _ringed(ring: int = 30, hole_in_roof: bool = True) -> np.ndarray:
    """The block of :func:`_scene` on a ground sloping 1 % to the east, with a ring of
    ``ring`` cells of holes round it (what a matcher leaves: the occlusions of both images)
    and a small hole inside the roof."""
    _, gx, _, inside, dsm = _scene()
    dsm = dsm + 0.01 * (gx - X0)
    grown = np.zeros_like(inside)
    r, c = np.nonzero(inside)
    grown[r.min() - ring:r.max() + ring + 1, c.min() - ring:c.max() + ring + 1] = True
    out = np.where(grown & ~inside, np.nan, dsm)
    if hole_in_roof:
        out[r.min() + 40:r.min() + 50, c.min() + 40:c.min() + 50] = np.nan
    return out


def test_fill_from_below_gives_a_ring_of_holes_the_ground_and_a_roof_hole_the_roof() -> None:
    _, gx, _, inside, dsm = _scene()
    ground = GROUND + 0.01 * (gx - X0)
    holed = _ringed()
    filled = fill_from_below(holed, 200)
    ring = ~np.isfinite(holed) & ~inside
    # the ring (a hole 3 m wide whose bounding box is 16 m × 18 m) takes the ground, never
    # the roof on its other side: the lowest ground along its row or column, so at most the
    # slope across the ring's 16 m below the ground under it
    assert np.isfinite(filled[ring]).all()
    dz = filled[ring] - ground[ring]
    assert dz.max() < 1e-9 and dz.min() > -0.01 * 16.0 - 1e-9
    # the hole inside the roof keeps the roof's height
    roof_hole = ~np.isfinite(holed) & inside
    roof = dsm + 0.01 * (gx - X0)
    assert roof_hole.any() and np.abs(filled[roof_hole] - roof[roof_hole]).max() < 0.011
    # valid cells are unchanged
    ok = np.isfinite(holed)
    assert np.array_equal(filled[ok], holed[ok])


def test_fill_from_below_is_local_and_never_extends_the_border() -> None:
    holed = _ringed()
    holed[:, :50] = np.nan  # the DSM ends 5 m into the window
    full = fill_from_below(holed, 40)
    assert np.isnan(full[:, :50]).all()  # beyond the outer border: no valid cell on one side
    # a window reaching max_size cells beyond the cells of interest fills them the same
    r0, r1, c0, c1 = 250, 350, 150, 250
    part = fill_from_below(holed[r0 - 40:r1 + 40, c0 - 40:c1 + 40], 40)
    assert np.array_equal(part[40:-40, 40:-40], full[r0:r1, c0:c1], equal_nan=True)
    # holes farther than max_size from valid cells on every side stay empty
    assert np.isnan(fill_from_below(_ringed(ring=30), 10)[~np.isfinite(_ringed())]).any()


def test_nearest_valid_along_gives_the_height_and_distance_in_each_direction() -> None:
    z = np.array([[1.0, np.nan, np.nan, 4.0, np.nan]])
    valid = np.isfinite(z)
    left, d_left = nearest_valid_along(z, valid, 1, False, 3)
    right, d_right = nearest_valid_along(z, valid, 1, True, 1)
    np.testing.assert_array_equal(left[0], [1.0, 1.0, 1.0, 4.0, 4.0])
    np.testing.assert_array_equal(d_left[0], [0, 1, 2, 0, 1])
    # looking right at most one cell: the cell two before 4 finds nothing
    np.testing.assert_array_equal(right[0], [1.0, np.nan, 4.0, 4.0, np.nan])
    np.testing.assert_array_equal(d_right[0], [0, np.inf, 1, 0, np.inf])
