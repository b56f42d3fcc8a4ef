"""Contour moments, CWM invariants, standard position, pair transforms, MBR."""

from __future__ import annotations

import numpy as np
import pytest
from _shapes import blob, random_affine

from photodem.algorithms.georef.invariants import (
    algebraic_invariants,
    central_moments,
    cwm_invariants,
    d4_alternatives,
    min_bounding_rectangle,
    object_features,
    pair_transform,
    raw_moments,
)
from photodem.algorithms.georef.objects import IMAGE, REFERENCE, PolygonObject, orient_ring


def test_moments_of_a_rectangle_and_triangle() -> None:
    rect = np.array([[0, 0], [3, 0], [3, 2], [0, 2]], float)
    M = raw_moments(rect, 8)
    for p in range(9):
        for q in range(9 - p):
            exact = 3 ** (p + 1) / (p + 1) * 2 ** (q + 1) / (q + 1)
            assert M[p, q] == pytest.approx(exact, rel=1e-12)
    tri = np.array([[0, 0], [1, 0], [0, 1]], float)
    Mt = raw_moments(tri, 4)
    assert Mt[0, 0] == pytest.approx(0.5) and Mt[1, 1] == pytest.approx(1 / 24)
    assert Mt[2, 0] == pytest.approx(1 / 12)


def test_utm_sized_coordinates_lose_nothing() -> None:
    b = blob(3)
    m1, _c1, a1 = central_moments(b)
    m2, _c2, a2 = central_moments(b * 50 + np.array([512345.0, 5612345.0]))
    assert np.allclose(m1, m2, rtol=1e-8, atol=1e-12)
    assert a2 == pytest.approx(a1 * 2500, rel=1e-10)


def test_cwm_invariant_under_affine_with_reflection() -> None:
    rng = np.random.default_rng(0)
    for seed in range(10):
        b = blob(seed)
        L = random_affine(rng)
        b2 = orient_ring(b @ L.T + rng.uniform(-1e5, 1e5, 2))
        i1 = cwm_invariants(central_moments(b)[0])
        i2 = cwm_invariants(central_moments(b2)[0])
        assert np.allclose(i1, i2, rtol=1e-9)
        assert np.allclose(algebraic_invariants(central_moments(b)[0]),
                           algebraic_invariants(central_moments(b2)[0]), rtol=1e-7, atol=1e-12)


def test_yang_cohen_exponent_is_not_scale_invariant() -> None:
    b = blob(1)
    def true_moments(ring):
        m, _, area = central_moments(ring)
        s = np.sqrt(area)
        p, q = np.indices(m.shape)
        return m * s ** (p + q + 2)
    m1, m2 = true_moments(b), true_moments(3 * b)
    assert np.allclose(cwm_invariants(m1), cwm_invariants(m2), rtol=1e-9)
    assert not np.allclose(cwm_invariants(m1, exponent_offset=0),
                           cwm_invariants(m2, exponent_offset=0), rtol=1e-3)


def test_pair_transform_recovers_the_affine() -> None:
    rng = np.random.default_rng(5)
    ok = 0
    for seed in range(20):
        b = blob(seed)
        L = random_affine(rng)
        t = rng.uniform(-1e4, 1e4, 2)
        fa, fb = object_features([PolygonObject(0, orient_ring(b), IMAGE),
                                  PolygonObject(1, orient_ring(b @ L.T + t), REFERENCE)])
        T = pair_transform(fa, fb)
        back = pair_transform(fb, fa)
        assert np.allclose(back @ T, np.eye(3), atol=1e-9)
        cands = [T]
        if fa.ambiguous or fb.ambiguous:  # near-symmetric: one D4 alternative is right
            cands += [pair_transform(fa, fb, N) for N in d4_alternatives(fa)]
        good = [np.allclose(C[:2, :2], L, atol=1e-4 * np.abs(L).max())
                and np.allclose(C[:2, 2], t, atol=1e-4 * np.abs(t).max()) for C in cands]
        assert any(good)
        ok += good[0]
    assert ok >= 12  # most shapes are not ambiguous at all


def test_standard_position_of_an_elongated_outline() -> None:
    # full shear steps cycle for this hexagon (and for 6 of 86 RGI glacier outlines)
    ring = np.array([[-1.932, 0.194], [-4.705, -0.148], [-1.355, -0.921], [-0.562, -0.973],
                     [0.409, -0.302], [4.863, -0.375]])
    rng = np.random.default_rng(11)
    for _ in range(5):
        L = random_affine(rng)
        t = rng.uniform(-1e4, 1e4, 2)
        fa, fb = object_features([PolygonObject(0, orient_ring(ring), IMAGE),
                                  PolygonObject(1, orient_ring(ring @ L.T + t), REFERENCE)])
        assert np.all(np.isfinite(fa.normaliser)) and np.all(np.isfinite(fb.normaliser))
        cands = [pair_transform(fa, fb)]
        if fa.ambiguous or fb.ambiguous:
            cands += [pair_transform(fa, fb, N) for N in d4_alternatives(fa)]
        assert any(np.allclose(C[:2, :2], L, atol=1e-4 * np.abs(L).max()) for C in cands)


def test_mbr_matches_brute_force() -> None:
    b = blob(7) @ np.array([[3.0, 0.4], [0.0, 1.0]]).T
    centre, axes, half = min_bounding_rectangle(b)
    area = 4 * half[0] * half[1]
    best = min((np.ptp(b @ [np.cos(a), np.sin(a)]) * np.ptp(b @ [-np.sin(a), np.cos(a)]))
               for a in np.radians(np.arange(0, 180, 0.1)))
    assert area <= best * 1.0001 and area >= best * 0.999
    d = b - centre
    assert np.all(np.abs(d @ axes[0]) <= half[0] + 1e-9)
    assert np.all(np.abs(d @ axes[1]) <= half[1] + 1e-9)
