"""Region growing, multiple segmentation and region outlines."""

from __future__ import annotations

import numpy as np
import pytest

from photodem.algorithms.errors import InputError
from photodem.algorithms.georef.invariants import central_moments
from photodem.algorithms.georef.regions import (
    grow_regions,
    image_objects,
    label_rings,
    merge_regions,
    stretch_to_byte,
)


def _scene(noise: float = 1.5, seed: int = 0) -> tuple:
    rng = np.random.default_rng(seed)
    img = np.full((160, 200), 110.0)
    truth = np.zeros(img.shape, int)
    truth[30:90, 20:80] = 1
    img[30:90, 20:80] = 60.0
    yy, xx = np.mgrid[:160, :200]
    disc = (yy - 110) ** 2 + (xx - 140) ** 2 < 30**2
    truth[disc] = 2
    img[disc] = 170.0
    return img + rng.normal(0, noise, img.shape), truth


def test_objects_recovered_and_count_falls_with_threshold() -> None:
    img, truth = _scene()
    counts = []
    for h in (4, 6, 8, 12):
        lab = grow_regions(img, h)
        counts.append(int(lab.max()))
    assert counts == sorted(counts, reverse=True)
    lab = merge_regions(grow_regions(img, 8), img, 8)
    for k in (1, 2):
        t = truth == k
        best = max(np.sum(t & (lab == v)) / np.sum(t | (lab == v))
                   for v in np.unique(lab[t]))
        assert best >= 0.95


def test_scan_corner_follows_the_image_flip() -> None:
    img, _ = _scene()
    a = grow_regions(img, 6, "lower_left")
    b = grow_regions(img[::-1, ::-1], 6, "upper_right")[::-1, ::-1]
    # same partition (labels may be numbered differently)
    pairs = set(zip(a.ravel().tolist(), b.ravel().tolist()))
    assert len(pairs) == a.max() == b.max()
    with pytest.raises(InputError):
        grow_regions(img, 6, "middle")


def test_multiband_needs_every_band() -> None:
    img, _ = _scene(noise=0.0)
    two = np.stack([img, np.where(img > 100, 50.0, 50.0)])
    two[1, :, 100:] = 200.0  # the second band splits the image in two halves
    lab = grow_regions(two, 6)
    assert lab[0, 0] != lab[0, 199]
    assert grow_regions(img, 6)[0, 0] == grow_regions(img, 6)[0, 199]


def test_rings_follow_pixel_edges_with_exact_area() -> None:
    lab = np.zeros((10, 12), np.int32)
    lab[2:5, 3:6] = 1
    lab[6:9, 1:11] = 2
    lab[7, 4] = 3  # a hole in region 2: dropped
    rings = dict(label_rings(lab))
    area = {k: 0.5 * abs(np.sum(r[:, 0] * np.roll(r[:, 1], -1) - np.roll(r[:, 0], -1) * r[:, 1]))
            for k, r in rings.items()}
    assert area[1] == 9.0 and area[2] == 30.0  # outer ring only: the hole is filled
    assert rings[1][:, 0].min() == 3.0 and rings[1][:, 0].max() == 6.0
    # m20 of a pixel block = centre sum + N/12 (the note's rule): 3 × 2 block → 4.5
    block = np.array([[0, 0], [3, 0], [3, 2], [0, 2]], float)
    m, _, a = central_moments(block, 2)
    assert m[2, 0] * a**2 == pytest.approx(4.5)


def test_level_coordinates_are_level_zero() -> None:
    img, _truth = _scene(noise=0.5)
    for level in (0, 1, 2):
        objs, info = image_objects(img, (8.0,), min_area=500, max_area=5000,
                                   pyramid_level=level, merge=True)
        assert info["level"] == level
        c = [o.ring.mean(axis=0) for o in objs]
        # the square's centre in level-0 pixel coordinates (centres at integers)
        centre = np.array([49.5, 59.5])
        assert min(np.hypot(*(ci - centre)) for ci in c) <= 0.5 * 2**level + 0.5


def test_size_window_drops_background_and_flags_border() -> None:
    img, _ = _scene(noise=0.5)
    objs, _ = image_objects(img, (8.0,), max_area=0.2, pyramid_level=0, merge=True)
    areas = [o.area for o in objs]
    assert len(objs) >= 2 and max(areas) < 0.2 * img.size  # the background is not there
    assert not any(o.touches_border for o in objs if o.area > 1000)


def test_stretch() -> None:
    a = np.linspace(1000, 5000, 101)
    s = stretch_to_byte(a)
    assert s.min() == 0 and s.max() == 255
