"""Generalisation, trimmed ICP, control points and the final transform."""

from __future__ import annotations

import numpy as np
import pytest
from _shapes import blob
from shapely.geometry import LineString, Polygon

from photodem.algorithms.georef.correspondence import Hypothesis, apply
from photodem.algorithms.georef.fit import corner_error, fit_transform
from photodem.algorithms.georef.refinement import (
    border_pairs,
    control_points,
    frame_mask,
    grow_ring,
    outline_offset,
    simplify_ring,
    trimmed_icp,
)


def _affine(a: float, s: float, t=(0.0, 0.0)) -> np.ndarray:
    T = np.eye(3)
    T[:2, :2] = s * np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    T[:2, 2] = t
    return T


def test_douglas_peucker_bounds_the_deviation() -> None:
    ring = blob(2, 400) * 100
    simple = simplify_ring(ring, 1.0)
    assert len(simple) < len(ring) / 3
    # as lines (GEOS 3.11 of Debian 12 mis-measures the Hausdorff distance of LinearRings)
    a = LineString(np.vstack([ring, ring[:1]]))
    b = LineString(np.vstack([simple, simple[:1]]))
    assert a.hausdorff_distance(b) <= 1.0 + 1e-9


def test_icp_converges_from_the_published_range() -> None:
    # affine per pair (a projective fit to one smooth closed outline is ill-conditioned and
    # drifts: the pipeline fits projective jointly over all verified outlines)
    model = "affine"
    target = blob(4, 200) * 100
    for a, s, t in ((np.radians(12), 1.0, (0, 0)), (0.0, 1.3, (0, 0)), (0.0, 1.0, (15, -10))):
        P = _affine(a, s, t)
        source = apply(np.linalg.inv(P), target)
        res = trimmed_icp(source, target, spacing=1.0, model=model, max_iter=100)
        assert res.rms < 0.05
        assert np.allclose(res.transform @ np.linalg.inv(P), np.eye(3), atol=2e-3)


def test_trimmed_icp_registers_a_fragment() -> None:
    target = blob(5, 300) * 100
    P = _affine(np.radians(5), 1.05, (4, 3))
    fragment = apply(np.linalg.inv(P), target[:250])  # 5/6 of the outline, closed by a chord
    res = trimmed_icp(fragment, target, spacing=1.0, f=1.0, max_iter=100)
    assert res.kept < 0.95  # the chord was trimmed
    corners = np.array([[-100, -100], [100, -100], [100, 100], [-100, 100]], float)
    err = np.hypot(*(apply(res.transform, corners) - apply(P, corners)).T)
    plain = trimmed_icp(fragment, target, spacing=1.0, f=1e9, max_iter=100)
    err_plain = np.hypot(*(apply(plain.transform, corners) - apply(P, corners)).T)
    assert err.max() < 3.0 and err.max() < 0.5 * err_plain.max()


def test_control_points_on_exact_pairs() -> None:
    T = _affine(0.3, 2.0, (1000.0, 2000.0))
    pairs = []
    for k in range(3):
        ring_map = blob(10 + k, 120) * 80 + np.array([300.0 * k, 0.0]) + T[:2, 2]
        pairs.append((apply(np.linalg.inv(T), ring_map), ring_map, T))
    for mode in ("outline", "vertices"):
        gcps = control_points(pairs, mode=mode, spacing=2.0)
        assert len(gcps) >= 12
        img = np.array([g.image for g in gcps])
        mp = np.array([g.map for g in gcps])
        err_px = np.hypot(*(apply(np.linalg.inv(T), mp) - img).T)
        assert err_px.max() < 0.01
    # σ_NP limits the count: more tolerance, more points
    noisy = [(a + np.random.default_rng(1).normal(0, 0.3, a.shape), b, t) for a, b, t in pairs]
    counts = [len(control_points(noisy, sigma_np=s, spacing=2.0)) for s in (0.05, 0.2, 1.0)]
    assert counts == sorted(counts) and counts[0] < counts[-1]


def test_fit_recovers_transforms_and_reports_residuals() -> None:
    rng = np.random.default_rng(0)
    img = rng.uniform(0, 1000, (40, 2))
    T = _affine(1.1, 30.0, (5e5, 5.6e6)) @ np.array([[1, 0.1, 0], [0, -1, 0], [0, 0, 1.0]])
    mp = apply(T, img)
    fit = fit_transform(img, mp, "affine")
    assert np.allclose(fit.matrix, T, rtol=1e-9, atol=1e-6)
    assert fit.rmse_px < 1e-6
    assert corner_error(fit, T, 1000, 1000).max() < 1e-6
    H = T.copy()
    H[2, :2] = (1e-5, -2e-5)
    fitp = fit_transform(img, apply(H, img), "projective")
    assert corner_error(fitp, H, 1000, 1000).max() < 1e-5
    # poly2 reproduces an affine too; one gross error is removed by the robust step
    bad = mp.copy()
    bad[7] += 500.0
    fit2 = fit_transform(img, bad + rng.normal(0, 0.5, bad.shape), "poly2")
    assert not fit2.used[7] and fit2.used.sum() == 39
    assert np.all(np.isfinite(fit2.loo_map[fit2.used]))
    assert fit2.rmse_map < 1.0


def test_outline_offset_is_measured_and_undone() -> None:
    ring = blob(3, 200) * 100
    shrunk = grow_ring(ring, -2.0)
    off = outline_offset([(shrunk, ring)], np.eye(3), 1.0)
    assert off == pytest.approx(2.0, abs=0.15)
    back = grow_ring(shrunk, off)
    assert Polygon(back).symmetric_difference(Polygon(ring)).area < 0.02 * Polygon(ring).area


def _cut_scene(T: np.ndarray, shape=(200, 300)):
    """Reference blobs (map units) and the image objects an image of ``shape`` px through
    ``T`` (image → map) shows: whole ones, and ones cut by the image frame (clipped)."""
    from types import SimpleNamespace

    rows, cols = shape
    frame = Polygon([(-0.5, -0.5), (cols - 0.5, -0.5), (cols - 0.5, rows - 0.5),
                     (-0.5, rows - 0.5)])
    centres = [(150, 100), (10, 60), (290, 150), (150, 195), (80, 150)]  # image px
    ref, img = [], []
    for k, c in enumerate(centres):
        ring_img = blob(30 + k, 160) * 30 + np.array(c, float)
        ref.append(SimpleNamespace(obj=SimpleNamespace(ring=apply(T, ring_img))))
        part = Polygon(ring_img).intersection(frame)
        img.append(SimpleNamespace(obj=SimpleNamespace(
            ring=np.asarray(part.exterior.coords, float)[:-1],
            touches_border=not frame.buffer(-1.0).contains(Polygon(ring_img)))))
    return img, ref


def test_objects_cut_by_the_border_pair_with_their_partners_only() -> None:
    T = _affine(0.4, 2.0, (5000.0, 3000.0))
    img, ref = _cut_scene(T)
    cut = [k for k, f in enumerate(img) if f.obj.touches_border]
    assert cut == [1, 2, 3]
    keep = frame_mask((200, 300), 3.0)
    taken = [Hypothesis(0, 0, T, 1.0, 1.0, 0.0)]
    pairs = border_pairs(img, ref, T, (200, 300), taken, keep)
    assert sorted((h.i, h.j) for h, _ in pairs) == [(1, 1), (2, 2), (3, 3)]
    assert all(ov > 0.95 for _, ov in pairs)
    # a transform 6 px off: the cut outlines no longer lie on the reference outlines
    off = T @ _affine(0.0, 1.0, (6.0, 0.0))
    assert border_pairs(img, ref, off, (200, 300), taken, keep) == []


def test_outline_points_on_the_image_border_are_left_out() -> None:
    T = _affine(0.4, 2.0, (5000.0, 3000.0))
    img, ref = _cut_scene(T)
    keep = frame_mask((200, 300), 3.0)
    assert keep(np.array([[2.6, 50.0], [2.4, 50.0], [296.4, 100.0], [296.6, 100.0]])).tolist() \
        == [True, False, True, False]
    pairs = [(img[k].obj.ring, ref[k].obj.ring, T) for k in (1, 2, 3)]
    gcps = control_points(pairs, spacing=2.0, keep=keep)
    xy = np.array([g.image for g in gcps])
    assert len(gcps) >= 20 and keep(xy).all()
    # every point lies on its true position: no point of the border runs is paired
    err = np.hypot(*(apply(T, xy) - np.array([g.map for g in gcps])).T) / 2.0
    assert err.max() < 0.01
    both = control_points(pairs, spacing=2.0)
    err_all = np.hypot(*(apply(T, np.array([g.image for g in both]))
                         - np.array([g.map for g in both])).T) / 2.0
    assert err_all.max() > 1.0  # without the mask, border runs pair with reference outlines
