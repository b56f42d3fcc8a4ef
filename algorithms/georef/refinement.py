"""Refinement of verified pairs and control points (seed-001 §2.13–2.15).

Per verified pair the image outline is generalised (Douglas–Peucker, removes the pixel
staircase), mapped into the map by the global transform and registered onto the reference
outline by a **trimmed ICP**: points sampled along the image outline, their closest points on the
reference outline, pairs farther than f·σ (σ = RMS distance) dropped, a least-squares affine or
projective update, repeated. Trimming (not a robust estimator) because partial objects can have
more than half outliers.

Control points: reference vertices whose outline turns by ≥ α_min there (points on straight or
gently curved lines are poor control points) paired with the closest point on the registered
image outline; all pairs pooled, sorted by residual, accepted while the RMS of the accepted
residuals stays below σ_NP (or up to a maximum count). The image coordinates are the closest
point taken back through the pair's inverse transform. Extension (reported): an outline without
enough sharp vertices (smooth forest edges) contributes points at equal spacing along it.

Objects cut by the image border (extension): once the verified pairs give the transform, image
objects that touch the border are paired with the part of a reference object inside the image
(:func:`border_pairs`); their outline points on the image border are not object outlines and
are left out of the ICP and the control points (the ``keep`` masks, :func:`frame_mask`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, List, Optional, Sequence, Tuple

import numpy as np
from matplotlib.path import Path as MplPath
from numpy.typing import NDArray
from scipy.spatial import cKDTree
from shapely.geometry import Polygon

from .correspondence import Hypothesis, apply, overlap
from .fit import fit_matrix
from .objects import orient_ring

#: A mask function: (n, 2) points → (n,) bool, True for the points to use.
Keep = Callable[[NDArray[np.float64]], NDArray[np.bool_]]


def frame_mask(shape: Sequence[int], margin: float) -> Keep:
    """The image points (level-0 px, pixel centres at integers) at least ``margin`` px inside
    the image frame: outlines of objects cut by the border run along it there."""
    rows, cols = int(shape[0]), int(shape[1])

    def keep(xy: NDArray[np.float64]) -> NDArray[np.bool_]:
        xy = np.asarray(xy, float).reshape(-1, 2)
        return ((xy[:, 0] >= margin - 0.5) & (xy[:, 0] <= cols - 0.5 - margin)
                & (xy[:, 1] >= margin - 0.5) & (xy[:, 1] <= rows - 0.5 - margin))
    return keep


def _kept(pts: NDArray[np.float64], keep: Optional[Keep]) -> NDArray[np.float64]:
    return pts if keep is None else pts[keep(pts)]


def simplify_ring(ring: NDArray[np.float64], tolerance: float) -> NDArray[np.float64]:
    """Douglas–Peucker generalisation of a closed ring (shapely), unclosed output."""
    p = Polygon(ring).simplify(tolerance, preserve_topology=True)
    if p.is_empty or p.geom_type != "Polygon":
        return np.asarray(ring, float)
    return np.asarray(p.exterior.coords, float)[:-1]


def sample_ring(ring: NDArray[np.float64], spacing: float, keep_vertices: bool = False
                ) -> NDArray[np.float64]:
    """Points at (about) equal ``spacing`` along a closed ring; with ``keep_vertices`` the
    ring's own vertices plus points inserted so that no segment is longer than ``spacing``."""
    p = np.vstack([ring, ring[:1]])
    seg = np.hypot(*np.diff(p, axis=0).T)
    if keep_vertices:
        n_sub = np.maximum(np.ceil(seg / max(spacing, 1e-12)).astype(int), 1)
        k = np.repeat(np.arange(len(seg)), n_sub)
        f = np.concatenate([np.arange(m) / m for m in n_sub])
        return p[k] + f[:, None] * (p[k + 1] - p[k])
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    n = max(int(cum[-1] / spacing), 8)
    t = np.linspace(0.0, cum[-1], n, endpoint=False)
    k = np.clip(np.searchsorted(cum, t, side="right") - 1, 0, len(seg) - 1)
    f = (t - cum[k]) / np.where(seg[k] > 0, seg[k], 1.0)
    return p[k] + f[:, None] * (p[k + 1] - p[k])


def closest_on_ring(points: NDArray[np.float64], ring: NDArray[np.float64],
                    chunk: int = 256) -> Tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Closest point on the closed polyline ``ring`` for every point, and the distance.

    Small problems are solved exactly against every segment; large ones against the segments
    next to the 12 nearest vertices of the ring densified to the points' spacing (a k-d tree;
    the same geometry, so the result is the exact closest point unless the outline folds back
    within that distance many times).
    """
    points = np.asarray(points, float)
    if len(points) * len(ring) <= 100_000:
        return _closest_brute(points, ring, chunk)

    step = _spacing(points)
    dense = sample_ring(ring, step, keep_vertices=True)
    n = len(dense)
    k = min(12, n)
    _, idx = cKDTree(dense).query(points, k=k)
    idx = np.asarray(idx).reshape(len(points), k)
    seg = np.concatenate([idx, (idx - 1) % n], axis=1)  # segments starting at/ending in them
    a = dense[seg]
    b = dense[(seg + 1) % n]
    ab = b - a
    L2 = np.maximum(np.einsum("pki,pki->pk", ab, ab), 1e-300)
    ap = points[:, None, :] - a
    u = np.clip(np.einsum("pki,pki->pk", ap, ab) / L2, 0.0, 1.0)
    q = a + u[..., None] * ab
    diff = points[:, None, :] - q
    d2 = np.einsum("pki,pki->pk", diff, diff)
    j = np.argmin(d2, axis=1)
    r = np.arange(len(points))
    return q[r, j], np.sqrt(d2[r, j])


def _spacing(points: NDArray[np.float64]) -> float:
    d = np.hypot(*np.diff(points, axis=0).T)
    d = d[d > 0]
    return float(np.median(d)) if d.size else 1.0


def _closest_brute(points: NDArray[np.float64], ring: NDArray[np.float64], chunk: int
                   ) -> Tuple[NDArray[np.float64], NDArray[np.float64]]:
    a = ring
    b = np.roll(ring, -1, axis=0)
    ab = b - a
    L2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    out = np.empty_like(points)
    dist = np.empty(len(points))
    for s in range(0, len(points), chunk):
        p = points[s:s + chunk]
        ap = p[:, None, :] - a[None, :, :]
        u = np.clip(np.einsum("pki,ki->pk", ap, ab) / L2[None, :], 0.0, 1.0)
        q = a[None, :, :] + u[..., None] * ab[None, :, :]
        d2 = np.einsum("pki,pki->pk", p[:, None, :] - q, p[:, None, :] - q)
        k = np.argmin(d2, axis=1)
        out[s:s + chunk] = q[np.arange(len(p)), k]
        dist[s:s + chunk] = np.sqrt(d2[np.arange(len(p)), k])
    return out, dist


def estimate(src: NDArray[np.float64], dst: NDArray[np.float64], model: str = "affine"
             ) -> Optional[NDArray[np.float64]]:
    """Least-squares 3 × 3 transform src → dst (affine, or projective by normalised DLT)."""
    try:
        return fit_matrix(src, dst, model)
    except (ValueError, np.linalg.LinAlgError):
        return None


@dataclass
class IcpResult:
    transform: NDArray[np.float64]  # map → map correction (applied after the global one)
    rms: float
    iterations: int
    converged: bool
    kept: float  # share of the sampled points kept by the trimming


def trimmed_icp(source: NDArray[np.float64], target: NDArray[np.float64], spacing: float,
                f: float = 2.0, model: str = "affine", max_iter: int = 50, tol: float = 1e-4,
                keep: Optional[Keep] = None) -> IcpResult:
    """Register the ``source`` outline onto the ``target`` outline (both in map units).
    ``keep``: the sampled source points that are outline (default: all)."""
    pts = sample_ring(source, spacing)
    pts = _kept(pts, keep)
    T = np.eye(3)
    rms, kept, iters = float("nan"), 0.0, 0
    converged = False
    for it in range(1, max_iter + 1):
        iters = it
        cur = apply(T, pts)
        q, d = closest_on_ring(cur, target)
        sigma = float(np.sqrt(np.mean(d * d)))
        near = d <= f * max(sigma, 1e-12)
        if near.sum() < (8 if model == "projective" else 6):
            break
        U = estimate(cur[near], q[near], model)
        if U is None:
            break
        T = U @ T
        rms, kept = float(np.sqrt(np.mean(d[near] ** 2))), float(near.mean())
        # parameter change as the largest movement of the sampled points
        move = float(np.max(np.hypot(*(apply(U, cur) - cur).T)))
        if move < tol * spacing:
            converged = True
            break
    return IcpResult(T, rms, iters, converged, kept)


def turning_vertices(ring: NDArray[np.float64], alpha_min: float) -> NDArray[np.int64]:
    """Indices of the ring's vertices whose direction changes by ≥ ``alpha_min`` degrees."""
    a = np.roll(ring, 1, axis=0)
    b = np.roll(ring, -1, axis=0)
    d1 = ring - a
    d2 = b - ring
    ang = np.abs(np.degrees(np.arctan2(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0],
                                       np.einsum("ij,ij->i", d1, d2))))
    return np.nonzero(ang >= alpha_min)[0]


@dataclass
class ControlPoint:
    image: Tuple[float, float]  # level-0 pixel (col, row), pixel centres at integers
    map: Tuple[float, float]
    residual: float  # nearest-point distance after ICP (map units)
    pair: int  # index of the verified pair
    sharp: bool  # from a turning vertex (else equal spacing, the extension)


def control_points(pairs: Sequence[Tuple[NDArray[np.float64], NDArray[np.float64],
                                         NDArray[np.float64]]],
                   alpha_min: float = 30.0, sigma_np: float = float("inf"),
                   max_count: int = 500, min_per_pair: int = 4, spacing: float = 1.0,
                   mode: str = "outline", per_pair: int = 24, keep: Optional[Keep] = None
                   ) -> List[ControlPoint]:
    """Control points of refined pairs.

    Parameters
    ----------
    pairs : sequence of (image ring, reference ring, image → map transform of the pair)
        The pair transform is the ICP correction composed with the global transform.
    alpha_min : float
        Turning angle (degrees) of usable reference vertices.
    sigma_np : float
        Accept points (smallest residual first) while the RMS of the accepted residuals is
        ≤ this (map units).
    max_count : int
        At most this many points.
    min_per_pair : int
        ``mode="vertices"``: outlines with fewer sharp vertices contribute points every
        ``perimeter/12`` instead.
    mode : {"outline", "vertices"}
        ``"vertices"``: reference vertices turning by ≥ ``alpha_min`` (the method as
        published). ``"outline"`` (default, extension): ``per_pair`` points at equal spacing
        along each reference outline — segmented outlines round off sharp corners, so corner
        vertices pair with points cut inside the corner (a bias of ~1 px on synthetic data).
    keep : callable, optional
        The image points (level-0 px) that are outline; others are no candidates (default:
        all).
    """
    cands: List[ControlPoint] = []
    for k, (img_ring, ref_ring, T) in enumerate(pairs):
        mapped = apply(T, img_ring)
        perim = float(np.sum(np.hypot(*np.diff(np.vstack([ref_ring, ref_ring[:1]]),
                                                 axis=0).T)))
        if mode == "outline":
            pts = sample_ring(ref_ring, max(perim / per_pair, spacing))
            sharp = False
        else:
            idx = turning_vertices(ref_ring, alpha_min)
            sharp = True
            pts = ref_ring[idx]
            if len(idx) < min_per_pair:
                pts = sample_ring(ref_ring, max(perim / 12.0, spacing))
                sharp = False
        q, d = closest_on_ring(pts, mapped)
        back = apply(np.linalg.inv(T), q)
        ok = np.ones(len(back), bool) if keep is None else keep(back)
        for p, b, r in zip(pts[ok], back[ok], d[ok]):
            cands.append(ControlPoint((float(b[0]), float(b[1])), (float(p[0]), float(p[1])),
                                      float(r), k, sharp))
    cands.sort(key=lambda c: (c.residual, c.pair, c.map))
    out: List[ControlPoint] = []
    s2 = 0.0
    for c in cands:
        if len(out) >= max_count:
            break
        if np.sqrt((s2 + c.residual**2) / (len(out) + 1)) > sigma_np:
            break
        out.append(c)
        s2 += c.residual**2
    return out


def joint_icp(pairs: Sequence[Tuple[NDArray[np.float64], NDArray[np.float64]]],
              start: NDArray[np.float64], spacing: float, f: float = 2.0,
              model: str = "affine", max_iter: int = 50, tol: float = 1e-4,
              keep: Optional[Keep] = None) -> IcpResult:
    """One image → map transform registering all verified outlines at once.

    ``pairs`` holds (image ring in image coordinates, reference ring in map units);
    ``spacing`` is the sampling step along the image rings (image pixels). Each image point is
    paired with the closest point of its own partner's outline; trimming at f·σ over all of
    them. A segmentation that shrinks or grows every object a little moves each outline
    towards or away from its own centroid — per-pair transforms absorb that as scale and pass
    it into the control points; one transform for all objects cannot, and averages it out.
    ``keep``: the sampled image points that are outline (default: all).
    """
    pts = [_kept(sample_ring(r, spacing), keep) for r, _ in pairs]
    owner = np.concatenate([np.full(len(p), k) for k, p in enumerate(pts)])
    src = np.vstack(pts)
    T = np.asarray(start, float).copy()
    rms, kept, iters, converged = float("nan"), 0.0, 0, False
    for it in range(1, max_iter + 1):
        iters = it
        cur = apply(T, src)
        q = np.empty_like(cur)
        d = np.empty(len(cur))
        for k, (_, ref) in enumerate(pairs):
            m = owner == k
            q[m], d[m] = closest_on_ring(cur[m], ref)
        sigma = float(np.sqrt(np.mean(d * d)))
        near = d <= f * max(sigma, 1e-12)
        U = estimate(src[near], q[near], model)
        if U is None:
            break
        move = float(np.max(np.hypot(*(apply(U, src) - cur).T)))
        T = U
        rms, kept = float(np.sqrt(np.mean(d[near] ** 2))), float(near.mean())
        if move < tol * spacing * float(np.sqrt(abs(np.linalg.det(T[:2, :2])))):
            converged = True
            break
    return IcpResult(T, rms, iters, converged, kept)


def outline_offset(pairs: Sequence[Tuple[NDArray[np.float64], NDArray[np.float64]]],
                   T: NDArray[np.float64], spacing: float, keep: Optional[Keep] = None
                   ) -> float:
    """Mean signed distance (map units) of the image outlines mapped by ``T`` from their
    partners' outlines: positive when the image objects are smaller (lie inside).
    ``keep``: the sampled image points that are outline (default: all)."""
    total, n = 0.0, 0
    for img_ring, ref_ring in pairs:
        pts = _kept(sample_ring(img_ring, spacing), keep)
        if len(pts) == 0:
            continue
        cur = apply(T, pts)
        _, d = closest_on_ring(cur, ref_ring)
        inside = MplPath(ref_ring).contains_points(cur)
        s = np.where(inside, d, -d)
        sigma = float(np.sqrt(np.mean(d * d)))
        near = d <= 2.0 * max(sigma, 1e-12)
        total += float(np.sum(s[near]))
        n += int(near.sum())
    return total / n if n else 0.0


def grow_ring(ring: NDArray[np.float64], distance: float) -> NDArray[np.float64]:
    """The ring moved outwards by ``distance`` (inwards when negative), mitred corners."""
    p = Polygon(ring).buffer(distance, join_style=2, mitre_limit=3.0)
    if p.is_empty:
        return np.asarray(ring, float)
    if p.geom_type != "Polygon":
        p = max(p.geoms, key=lambda g: g.area)

    return orient_ring(np.asarray(p.exterior.coords, float))


def border_pairs(img: Sequence[Any], ref: Sequence[Any], T: NDArray[np.float64],
                 shape: Sequence[int], taken: Sequence[Hypothesis], keep: Keep,
                 min_overlap: float = 0.8, max_px: float = 2.0, min_share: float = 0.8,
                 min_samples: int = 100) -> List[Tuple[Hypothesis, float]]:
    """Pairs of image objects cut by the image border with reference objects, under the
    verified transform ``T`` (image → map).

    Their invariants are not valid, so no hypothesis pairs them; but once ``T`` is known, the
    image object and the part of a reference object inside the mapped image frame must cover
    the same ground (:func:`.correspondence.overlap` ≥ ``min_overlap``) and the image outline
    off the border (``keep``, sampled every pixel, ≥ ``min_samples`` points) must lie on the
    reference outline: ≥ ``min_share`` of it within ``max_px`` px. Objects of ``taken`` pairs
    are not paired again; at most one partner per object, the largest overlap first. Slivers
    cut off at an image corner (< ``min_samples`` px of outline) are left out: on a bench map
    four of them (2–7 control points each) were 0.4–0.55 px off and pulled that corner.

    Parameters
    ----------
    img, ref : sequence of ObjectFeatures
        Image and reference object features (``.obj`` holds the ring).
    T : (3, 3) array
        Image → map transform of the verified pairs.
    shape : (rows, cols)
        Image size (level-0 px).
    taken : sequence of Hypothesis
        The verified pairs.
    keep : callable
        The image points that are outline (:func:`frame_mask`).

    Returns
    -------
    list of (Hypothesis, overlap)
        The pairs (transform ``T``, q = w = d = 0), largest overlap first.
    """
    rows, cols = int(shape[0]), int(shape[1])
    frame = Polygon(apply(T, np.array([[-0.5, -0.5], [cols - 0.5, -0.5],
                                       [cols - 0.5, rows - 0.5], [-0.5, rows - 0.5]])))
    px = float(np.sqrt(abs(np.linalg.det(T[:2, :2]))))
    used_i = {h.i for h in taken}
    used_j = {h.j for h in taken}
    clipped = {j: _clip(f.obj.ring, frame) for j, f in enumerate(ref) if j not in used_j}
    scored = []
    for i, f in enumerate(img):
        if not f.obj.touches_border or i in used_i:
            continue
        mapped = apply(T, f.obj.ring)
        box = Polygon(mapped).envelope
        for j, part in clipped.items():
            if part is None or not box.intersects(part.envelope):
                continue
            ov = overlap(mapped, np.asarray(part.exterior.coords, float)[:-1])
            if ov >= min_overlap and _on_outline(f.obj.ring, ref[j].obj.ring, T, keep,
                                                 px * max_px, min_share, min_samples):
                scored.append((ov, i, j))
    scored.sort(key=lambda t: (-t[0], t[2], t[1]))
    out = []
    for ov, i, j in scored:
        if i in used_i or j in used_j:
            continue
        used_i.add(i)
        used_j.add(j)
        out.append((Hypothesis(i, j, np.asarray(T, float).copy(), 0.0, 0.0, 0.0), ov))
    return out


def _clip(ring: NDArray[np.float64], frame: Polygon) -> Optional[Polygon]:
    """The part of a reference polygon inside the mapped image frame (``None``: none, or
    several parts)."""
    try:
        p = Polygon(ring)
        if not p.is_valid:
            p = p.buffer(0)
        part = p.intersection(frame)
    except Exception:  # a degenerate polygon
        return None
    return part if part.geom_type == "Polygon" and part.area > 0 else None


def _on_outline(img_ring: NDArray[np.float64], ref_ring: NDArray[np.float64],
                T: NDArray[np.float64], keep: Keep, max_dist: float, min_share: float,
                min_samples: int) -> bool:
    """Whether the image outline off the border lies on the reference outline under ``T``."""
    pts = _kept(sample_ring(img_ring, 1.0), keep)
    if len(pts) < min_samples:
        return False
    _, d = closest_on_ring(apply(T, pts), ref_ring)
    return bool(np.mean(d <= max_dist) >= min_share)
