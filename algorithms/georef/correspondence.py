"""Object correspondences: hypotheses, consistent interpretation, verification (seed-001
§2.9, §2.11, §2.12).

1. **Hypotheses**: every (image object, reference object) pair whose six CWM invariants agree
   within a relative difference ``rd`` (U = 1 − min/max < rd for each). Exact and fast: U < rd
   ⇔ |log a − log b| < −log(1 − rd), so a k-d tree on the log-invariants with the Chebyshev
   metric finds exactly the pairs of the box test. Each hypothesis carries its pair transform
   image → map from the standard positions, its quality Q and weight W = 1/Q.
2. **Consistent interpretation**: depth-first search over the hypotheses, largest objects first,
   with a null branch (a hypothesis may be skipped), each object used at most once (image
   objects of different runs that cover the same ground are one object), binary constraints
   with every accepted pair (the centroid of one pair's image object mapped by the other pair's
   transform lies in the partner's minimum bounding rectangle — both ways) and the overlap
   ≥ δ of the candidate's objects under the current global transform (the weighted mean of
   the accepted pair transforms). Stops at ``max_depth`` pairs or at a node budget, keeping
   the largest interpretation found.
3. **Verification**: all hypotheses against the global transform — rotation, shear, scales,
   translation within tolerances and the same handedness, then overlap ≥ δ_v under the global
   transform; at most one image object per reference object and vice versa. Extension
   (marked in the result): the global affine is re-estimated by least squares from the
   verified pairs' centroids and the verification repeated once.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree
from shapely.geometry import Polygon

from .invariants import ObjectFeatures, d4_alternatives, pair_transform


@dataclass
class Hypothesis:
    """One candidate pair (image object ``i`` ↔ reference object ``j``)."""

    i: int  # index into the image features
    j: int  # index into the reference features
    transform: NDArray[np.float64]  # 3 × 3 image → map
    q: float
    w: float
    d: float  # quasi-Euclidean distance of the invariants (√Σ U²)
    alternative: bool = False  # from a D4 alternative of an ambiguous standard position


@dataclass
class Interpretation:
    """The consistent pairs found by the search and the global transform."""

    pairs: List[Hypothesis]
    transform: Optional[NDArray[np.float64]]
    nodes: int
    depth_reached: bool
    stats: Dict[str, Any] = field(default_factory=dict)


def relative_difference(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """U(a, b) = 1 − min/max for positive values (0 when equal)."""
    a = np.asarray(a, float)
    b = np.asarray(b, float)
    return 1.0 - np.minimum(a, b) / np.maximum(a, b)


def find_hypotheses(img: Sequence[ObjectFeatures], ref: Sequence[ObjectFeatures],
                    rd: float = 0.03, use_border_objects: bool = False,
                    min_area_img: float = 0.0, min_area_ref: float = 0.0,
                    max_per_object: int = 0) -> List[Hypothesis]:
    """All pairs passing the invariant box test, with pair transforms, Q and W.

    Parameters
    ----------
    rd : float
        Relative difference allowed for each invariant (0.03 = 3 %).
    use_border_objects : bool
        Also objects cut by the image/reference border (their invariants are not valid).
    min_area_img, min_area_ref : float
        Unary size constraints (own units).
    max_per_object : int
        Keep at most this many hypotheses per image object (the smallest Q; 0 = all).

    Returns
    -------
    list of Hypothesis
        Sorted largest reference object first, then largest image object, then ids.
    """
    def usable(fs: Sequence[ObjectFeatures], amin: float) -> NDArray[np.int64]:
        return np.array([k for k, f in enumerate(fs)
                         if np.all(np.isfinite(f.invariants)) and np.all(f.invariants > 0)
                         and np.all(np.isfinite(f.normaliser))
                         and f.area >= amin and (use_border_objects or not f.obj.touches_border)],
                        dtype=np.int64)

    ii, jj = usable(img, min_area_img), usable(ref, min_area_ref)
    if ii.size == 0 or jj.size == 0:
        return []
    fi = np.array([img[k].invariants for k in ii])
    fj = np.array([ref[k].invariants for k in jj])
    radius = -math.log(1.0 - rd)
    ti, tj = cKDTree(np.log(fi)), cKDTree(np.log(fj))
    lists = tj.query_ball_tree(ti, r=radius * (1 + 1e-12), p=np.inf)
    allv = np.vstack([fi, fj])
    span = allv.max(axis=0) - allv.min(axis=0)
    span[span <= 0] = 1.0
    hyps: List[Hypothesis] = []
    for b, near in enumerate(lists):
        for a in sorted(near):
            u = relative_difference(fi[a], fj[b])
            if not np.all(u < rd):
                continue
            q = float(np.sqrt(np.sum(((fi[a] - fj[b]) / span) ** 2)))
            w = 1.0 / q if q > 0 else 1e6
            fa, fb = img[ii[a]], ref[jj[b]]
            d = float(np.sqrt(np.sum(u * u)))
            hyps.append(Hypothesis(int(ii[a]), int(jj[b]), pair_transform(fa, fb), q, w, d))
            if fa.ambiguous or fb.ambiguous:
                for Na in d4_alternatives(fa):
                    hyps.append(Hypothesis(int(ii[a]), int(jj[b]), pair_transform(fa, fb, Na),
                                           q, w, d, alternative=True))
    if max_per_object:
        by_i: Dict[int, List[Hypothesis]] = {}
        for h in hyps:
            by_i.setdefault(h.i, []).append(h)
        hyps = [h for lst in by_i.values()
                for h in sorted(lst, key=lambda h: (h.q, h.j))[:max_per_object]]
    hyps.sort(key=lambda h: (-ref[h.j].area, -img[h.i].area, h.j, h.i, h.alternative))
    return hyps


# -- geometry helpers ------------------------------------------------------------------------
def apply(T: NDArray[np.float64], pts: NDArray[np.float64]) -> NDArray[np.float64]:
    """Apply a 3 × 3 transform (affine or projective) to (n, 2) points."""
    p = np.asarray(pts, float)
    x = T[0, 0] * p[..., 0] + T[0, 1] * p[..., 1] + T[0, 2]
    y = T[1, 0] * p[..., 0] + T[1, 1] * p[..., 1] + T[1, 2]
    w = T[2, 0] * p[..., 0] + T[2, 1] * p[..., 1] + T[2, 2]
    return np.stack([x / w, y / w], axis=-1)


def in_mbr(mbr: Tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]],
           pts: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Points inside a rotated rectangle (centre, unit axes, half sizes)."""
    centre, axes, half = mbr
    d = np.asarray(pts, float) - centre
    u = d[..., 0] * axes[0, 0] + d[..., 1] * axes[0, 1]
    v = d[..., 0] * axes[1, 0] + d[..., 1] * axes[1, 1]
    return (np.abs(u) <= half[0]) & (np.abs(v) <= half[1])


def overlap(ring_a: NDArray[np.float64], ring_b: NDArray[np.float64]) -> float:
    """min(A(a∩b)/A(a), A(a∩b)/A(b)) (eq. 4.3), exact with shapely; 0 for invalid shapes."""
    try:
        a = Polygon(ring_a)
        b = Polygon(ring_b)
        if not a.is_valid:
            a = a.buffer(0)
        if not b.is_valid:
            b = b.buffer(0)
        if a.area <= 0 or b.area <= 0:
            return 0.0
        inter = a.intersection(b).area
    except Exception:  # a degenerate mapped polygon
        return 0.0
    return float(min(inter / a.area, inter / b.area))


def weighted_mean_transform(pairs: Sequence[Hypothesis]) -> NDArray[np.float64]:
    """Normalised weighted mean (weights W = 1/Q) of the pairs' affine parameters."""
    w = np.array([h.w for h in pairs], float)
    w = w / w.sum()
    T = np.zeros((3, 3))
    for wk, h in zip(w, pairs):
        T += wk * h.transform
    T[2] = (0.0, 0.0, 1.0)
    return T


# -- the search ------------------------------------------------------------------------------
def consistent_interpretation(hyps: Sequence[Hypothesis], img: Sequence[ObjectFeatures],
                              ref: Sequence[ObjectFeatures], max_depth: int = 6,
                              min_overlap: float = 0.7, budget: int = 20000,
                              same_object_overlap: float = 0.5,
                              deadline: float = math.inf) -> Interpretation:
    """Depth-first interpretation-tree search (module notes, step 2).

    Parameters
    ----------
    max_depth : int
        Stop as soon as this many consistent pairs are found.
    min_overlap : float
        δ: overlap of a candidate's objects under the current global transform.
    budget : int
        Nodes (candidate tests) at most; the largest interpretation found is returned.
    same_object_overlap : float
        Image objects (of different runs) overlapping each other by more than this share of
        the smaller are the same ground object: at most one of them per interpretation.
    deadline : float
        ``time.perf_counter()`` time at which the search stops as at the node budget.
    """
    n = len(hyps)
    if n == 0:
        return Interpretation([], None, 0, False)
    H = np.array([h.transform for h in hyps])  # (n, 3, 3)
    ci = np.array([img[h.i].centroid for h in hyps])
    hi = np.array([h.i for h in hyps])
    hj = np.array([h.j for h in hyps])
    # centroid of each candidate's image object mapped by its own transform = its ref centroid
    # (exact by construction); binary test: candidate k vs accepted a:
    #   T_a(c_i[k]) ∈ MBR(ref j_k)  and  T_k(c_i[a]) ∈ MBR(ref j_a)
    mbr_c = np.array([ref[h.j].mbr[0] for h in hyps])
    mbr_ax = np.array([ref[h.j].mbr[1] for h in hyps])
    mbr_h = np.array([ref[h.j].mbr[2] for h in hyps])
    conflict_cache: Dict[Tuple[int, int], bool] = {}

    def same_object(a: int, b: int) -> bool:
        if a == b:
            return True
        key = (min(a, b), max(a, b))
        if key not in conflict_cache:
            ra, rb = img[a].obj.ring, img[b].obj.ring
            if img[a].obj.run == img[b].obj.run:
                conflict_cache[key] = False  # one run's regions never overlap
            else:
                try:
                    pa, pb = Polygon(ra).buffer(0), Polygon(rb).buffer(0)
                    inter = pa.intersection(pb).area
                    conflict_cache[key] = inter > same_object_overlap * min(pa.area, pb.area)
                except Exception:
                    conflict_cache[key] = True
        return conflict_cache[key]

    def mbr_ok(k_idx: NDArray[np.int64], a: int) -> NDArray[np.bool_]:
        Ta = H[a]
        p = apply(Ta, ci[k_idx])  # accepted pair's transform on the candidates' image centroids
        d = p - mbr_c[k_idx]
        u = np.einsum("ki,ki->k", d, mbr_ax[k_idx, 0])
        v = np.einsum("ki,ki->k", d, mbr_ax[k_idx, 1])
        ok = (np.abs(u) <= mbr_h[k_idx, 0]) & (np.abs(v) <= mbr_h[k_idx, 1])
        # candidates' transforms on the accepted pair's image centroid
        q = np.einsum("kij,j->ki", H[k_idx, :2, :], np.array([ci[a, 0], ci[a, 1], 1.0]))
        ok &= in_mbr(ref[hyps[a].j].mbr, q)
        return ok

    state = {"nodes": 0, "best": [], "best_w": 0.0}

    def record(chosen: List[int]) -> None:
        wsum = sum(hyps[k].w for k in chosen)
        if len(chosen) > len(state["best"]) or (
                len(chosen) == len(state["best"]) and wsum > state["best_w"]):
            state["best"] = list(chosen)
            state["best_w"] = wsum

    def dfs(cands: NDArray[np.int64], chosen: List[int], T: NDArray[np.float64]) -> bool:
        record(chosen)
        if len(chosen) >= max_depth:
            return True
        for pos, k in enumerate(cands.tolist()):
            if state["nodes"] >= budget or time.perf_counter() >= deadline:
                return False
            state["nodes"] += 1
            h = hyps[k]
            if any(hj[a] == h.j or same_object(int(hi[a]), h.i) for a in chosen):
                continue
            # the candidate's objects must overlap under the current global transform
            if overlap(apply(T, img[h.i].obj.ring), ref[h.j].obj.ring) < min_overlap:
                continue
            new = [*chosen, k]
            rest = cands[pos + 1:]
            if rest.size:
                rest = rest[(hj[rest] != h.j) & (hi[rest] != h.i)]
                if rest.size:
                    rest = rest[mbr_ok(rest, k)]
            Tn = weighted_mean_transform([hyps[a] for a in new])
            if dfs(rest, new, Tn):
                return True
        return False

    order = np.arange(n)
    found = False
    for k in order.tolist():
        if state["nodes"] >= budget or time.perf_counter() >= deadline:
            break
        state["nodes"] += 1
        rest = order[k + 1:]
        rest = rest[(hj[rest] != hj[k]) & (hi[rest] != hi[k])]
        if rest.size:
            rest = rest[mbr_ok(rest, k)]
        if len(state["best"]) >= 2 and rest.size + 1 <= len(state["best"]):
            continue  # cannot beat the best interpretation
        if dfs(rest, [k], hyps[k].transform):
            found = True
            break
    best = [hyps[k] for k in state["best"]]
    T = weighted_mean_transform(best) if best else None
    return Interpretation(best, T, state["nodes"], found)


# -- verification ----------------------------------------------------------------------------
def decompose(T: NDArray[np.float64]) -> Dict[str, float]:
    """Scales k_x, k_y, rotation κ and shear (rad) of the linear part; det sign."""
    a00, a01, a10, a11 = T[0, 0], T[0, 1], T[1, 0], T[1, 1]
    kx = math.hypot(a00, a10)
    ky = math.hypot(a01, a11)
    kappa = math.atan2(a10, a00)
    det = a00 * a11 - a01 * a10
    # angle between the images of the x and y axes, minus 90° (sign-free of the handedness)
    cosang = (a00 * a01 + a10 * a11) / (kx * ky) if kx > 0 and ky > 0 else 0.0
    shear = math.asin(max(-1.0, min(1.0, cosang)))
    return {"kx": kx, "ky": ky, "kappa": kappa, "shear": shear, "det": det}


def _angle_diff(a: float, b: float) -> float:
    return abs((a - b + math.pi) % (2 * math.pi) - math.pi)


@dataclass
class Verification:
    """Verified pairs and the transform they were verified with."""

    pairs: List[Hypothesis]
    overlaps: List[float]
    transform: NDArray[np.float64]
    stage1: int
    stage2: int
    reestimated: bool


def verify(hyps: Sequence[Hypothesis], img: Sequence[ObjectFeatures],
           ref: Sequence[ObjectFeatures], T: NDArray[np.float64], angle_tol: float = 45.0,
           scale_tol: float = 0.3, shift_tol: float = 0.3, min_overlap: float = 0.5,
           reestimate: bool = True) -> Verification:
    """Verify every hypothesis against the global transform ``T`` (module notes, step 3).

    Tolerances: ``angle_tol`` (degrees) for rotation and shear, ``scale_tol`` relative for k_x
    and k_y, ``shift_tol`` for the image centroid mapped by the pair vs the global transform,
    relative to the reference object's MBR size; then overlap ≥ ``min_overlap`` under ``T``.
    """
    def run(T: NDArray[np.float64]) -> Tuple[List[Hypothesis], List[float], int]:
        g = decompose(T)
        tol = math.radians(angle_tol)
        stage1 = []
        for h in hyps:
            p = decompose(h.transform)
            if np.sign(p["det"]) != np.sign(g["det"]):
                continue
            if _angle_diff(p["kappa"], g["kappa"]) > tol or abs(p["shear"] - g["shear"]) > tol:
                continue
            if abs(p["kx"] / g["kx"] - 1) > scale_tol or abs(p["ky"] / g["ky"] - 1) > scale_tol:
                continue
            c = np.array([*img[h.i].centroid, 1.0])
            d = (h.transform @ c)[:2] - (T @ c)[:2]
            size = 2.0 * float(np.max(ref[h.j].mbr[2]))
            if np.hypot(*d) > shift_tol * size:
                continue
            stage1.append(h)
        scored = []
        for h in stage1:
            ov = overlap(apply(T, img[h.i].obj.ring), ref[h.j].obj.ring)
            if ov >= min_overlap:
                scored.append((ov, h))
        # one partner per object: best overlap first
        scored.sort(key=lambda t: (-t[0], t[1].j, t[1].i))
        used_i, used_j, out, ovs = set(), set(), [], []
        for ov, h in scored:
            if h.i in used_i or h.j in used_j:
                continue
            used_i.add(h.i)
            used_j.add(h.j)
            out.append(h)
            ovs.append(ov)
        return out, ovs, len(stage1)

    pairs, ovs, n1 = run(T)
    reest = False
    if reestimate and len(pairs) >= 3:
        src = np.array([img[h.i].centroid for h in pairs])
        dst = np.array([ref[h.j].centroid for h in pairs])
        T2 = affine_from_points(src, dst)
        if T2 is not None:
            pairs2, ovs2, n12 = run(T2)
            if len(pairs2) >= len(pairs):
                pairs, ovs, n1, T, reest = pairs2, ovs2, n12, T2, True
    return Verification(pairs, ovs, T, n1, len(pairs), reest)


def affine_from_points(src: NDArray[np.float64], dst: NDArray[np.float64]
                       ) -> Optional[NDArray[np.float64]]:
    """Least-squares affine src → dst (≥ 3 non-collinear points), normalised coordinates."""
    src = np.asarray(src, float)
    dst = np.asarray(dst, float)
    if len(src) < 3:
        return None
    ms, md = src.mean(axis=0), dst.mean(axis=0)
    ss = float(np.sqrt(np.mean(np.sum((src - ms) ** 2, axis=1)))) or 1.0
    sd = float(np.sqrt(np.mean(np.sum((dst - md) ** 2, axis=1)))) or 1.0
    a = (src - ms) / ss
    b = (dst - md) / sd
    N = np.einsum("ki,kj->ij", a, a)
    if abs(np.linalg.det(N)) < 1e-9:
        return None
    L = np.linalg.solve(N, np.einsum("ki,kj->ij", a, b)).T * (sd / ss)
    T = np.eye(3)
    T[:2, :2] = L
    T[:2, 2] = md - L @ ms
    return T
