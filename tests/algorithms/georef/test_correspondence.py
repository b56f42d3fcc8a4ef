"""Hypotheses (box test), the consistent interpretation and the verification."""

from __future__ import annotations

import numpy as np
from _shapes import blob, random_affine

from photodem.algorithms.georef.correspondence import (
    apply,
    consistent_interpretation,
    find_hypotheses,
    relative_difference,
    verify,
)
from photodem.algorithms.georef.invariants import ObjectFeatures, object_features
from photodem.algorithms.georef.objects import IMAGE, REFERENCE, PolygonObject, orient_ring


def _fake(inv: np.ndarray, k: int) -> ObjectFeatures:
    ring = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float) + k * 3
    f = object_features([PolygonObject(k, ring, IMAGE)])[0]
    f.invariants = inv
    f.ambiguous = False
    return f


def test_kd_tree_gives_the_brute_force_set() -> None:
    rng = np.random.default_rng(1)
    a = [_fake(rng.uniform(0.8, 1.0, 6), k) for k in range(60)]
    b = [_fake(rng.uniform(0.8, 1.0, 6), k) for k in range(50)]
    got = {(h.i, h.j) for h in find_hypotheses(a, b, rd=0.05)}
    brute = {(i, j) for i in range(60) for j in range(50)
             if np.all(relative_difference(a[i].invariants, b[j].invariants) < 0.05)}
    assert got == brute and len(brute) > 0


def _world(seed: int, n: int = 16):
    """Non-overlapping blobs (reference, map units) and their affine image plus decoys."""
    rng = np.random.default_rng(seed)
    ref, centres = [], []
    while len(ref) < n:
        c = rng.uniform(0, 1000, 2)
        if any(np.hypot(*(c - d)) < 140 for d in centres):
            continue
        centres.append(c)
        ref.append(orient_ring(blob(rng.integers(1 << 30)) * rng.uniform(20, 55) + c))
    L = random_affine(rng)
    L = L / np.sqrt(abs(np.linalg.det(L)))  # about 1 px per map unit
    T = np.eye(3)
    T[:2, :2] = L
    T[:2, 2] = rng.uniform(-500, 500, 2)
    Ti = np.linalg.inv(T)
    img = [orient_ring(apply(Ti, r) + rng.normal(0, 0.2, r.shape)) for r in ref[: n - 3]]
    img += [orient_ring(blob(rng.integers(1 << 30)) * 30 + rng.uniform(-2000, -1000, 2))
            for _ in range(4)]  # decoys far away
    fi = object_features([PolygonObject(k, r, IMAGE) for k, r in enumerate(img)])
    fr = object_features([PolygonObject(k, r, REFERENCE) for k, r in enumerate(ref)])
    return fi, fr, T


def test_search_and_verification_recover_the_affine() -> None:
    ok = 0
    for seed in range(10):
        fi, fr, T = _world(seed)
        hyps = find_hypotheses(fi, fr, rd=0.03)
        it = consistent_interpretation(hyps, fi, fr, max_depth=6)
        if it.transform is None:
            continue
        v = verify(hyps, fi, fr, it.transform)
        corners = np.array([[0, 0], [1000, 0], [0, 1000], [1000, 1000]], float)
        err = np.hypot(*(apply(np.linalg.inv(T) @ v.transform, corners) - corners).T).max()
        # every verified pair is a true correspondence (the image object k is reference k)
        assert all(h.i == h.j for h in v.pairs)
        ok += err < 2.0 and len(v.pairs) >= 6
    assert ok >= 9
