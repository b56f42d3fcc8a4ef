r"""Coarse-to-fine control strategy of the feature-based + LSM matcher (seed-000 §3.3).

:func:`match_epipolar_fbm_lsm` matches an epipolar pair (rows correspond, d = col_l − col_r)
over Gaussian image pyramids. The approximation of every level is a **piecewise-planar
disparity grid aligned with the image pyramid**: one plane per matching window (window side
``fbm_window`` px of the level), split into components by breakline pixels
(:func:`.fbm.window_components`), so that nothing is interpolated or propagated across a
barrier.

Pyramid depth: enough levels that the disparity range shrinks to ≤ fbm_window/4 px at the
top, but the top level must still hold one whole matching window (plus the margins where no
point can lie) across the **stereo overlap** (left columns whose range [min_d, max_d] reaches
right-image data), and the image's shorter side ≥ 2 windows — else fewer levels.

Per level (coarsest first):

0. **Features** in the left image only where the search range can reach right-image data
   (no overlap = masked, not failed; below the top level per pixel the span of the coarser
   own and neighbouring planes ± the pull-in, :func:`_local_range`), Förstner weight
   thresholds **per sub-image** (2 × fbm_window; seed §2.3: strong and weak texture in one
   image both get points).
   **Candidates** (default ``candidates="correlation"``): the best local maximum of the 7 × 7
   NCC profile along the right row within the pull-in of each left point (interest operator in
   one image, as the best ISPRS approach, seed §3.4) — on real imagery only about half of the
   Förstner points are detected again in the other image, which starved the feature-to-feature
   candidates (``candidates="features"``, the seed's FBM, still available).
1. **Predictions** for each window component, in this order of preference:
   the previous level's plane of the component under the point (× 2; at the top level an
   ``approx`` grid from the caller), a seed (operator start point), the planes of already
   matched neighbouring components (region growing; evaluated at the point), or the full
   search range ``[min_d, max_d] / 2^k`` — at the top level, and at any level for components
   the coarser level could not predict (so that a failed coarse level never yields zero
   points silently).
2. **Waves** (best-first/breadth-first over the window graph): all components with a
   prediction are matched together with :func:`.fbm.fbm_level` (bidirectional FBM with robust
   per-window consistency). A component that fails runs the failure cascade once per level:
   *enlarge the window* (2 × window side, NCC window + 4), then *reduce the step* (denser
   Förstner points: w_factor/4, q ≥ 0.5, 3 × 3 non-maximum suppression); if it still fails it
   stays open and is retried from its matched neighbours' planes whenever more of them
   succeed (*come back from other sides*). Matching never stops at a failure.
   When no component is left, **neighbour consistency**: a matched component whose plane
   differs at its centre from the median of ≥ 3 matched neighbours' planes by more than
   max(neighbour_tol, pull-in/2) px loses its points and is redone once from its neighbours
   (a wrong coarse prediction must not propagate down the pyramid).
3. Components still unmatched at the end of the level are **marked** (``failures``) unless
   they are masked (≥ 90 % no-data/exclusion/no overlap) or tiny (< ½ window usable). Their
   planes are filled from the neighbours over the component graph (barrier-aware) for the
   next level (masked ones too, as predictions only).

At level 0 the accepted FBM points are refined by epipolar LSM (3 geometric + 2 radiometric
unknowns, :func:`.lsm.lsm_match`); points that do not converge or fail the σ_px / ρ
thresholds are **rejected** (seed §2.12; on the NGI pairs every FBM point off by > 2 px was
among them) unless ``lsm_reject=False`` (then they keep their FBM value with
:data:`FLAG_LSM_FAILED`). Then **grid densification** (``grid_step``, default 4 px): every
grid node of a component with a plane (matched, or filled from matched neighbours) is
searched by NCC around the plane (± the pull-in: a per-point refinement, the plane need not
fit rough terrain), refined by LSM and kept only if LSM accepts it and the right→left NCC
search returns to it (:data:`FLAG_GRID`); seed §3.1 "good points in regularly densified
sub-images". This gives the 24 m DSM of mountainous terrain ~5 % of the pixels as points
instead of ~0.3 %.

**Objects above the plane** (``object_search``, issue 19): grid nodes not kept near their
component's plane search the interval from ``d − pull`` to ``d + object_search`` px and are kept
when the best, unambiguous NCC peak lies above ``d + pull/2`` and passes LSM and the right→left
search, when their own pixel prefers it (shiftable windows, :func:`_own_pixel_upper`), and
after a one-node opening of the upper nodes (:func:`_inner_nodes`) — ground beside a wall that
matched the roof's edge goes; from the kept nodes the roof is grown node by node with a narrow
search (:func:`_grow_upper`), and opened again (:data:`FLAG_UPPER`).

Point flags (bits of ``EpipolarMatches.flags``):

=====  ==========================  ============================================================
bit    name                        meaning
=====  ==========================  ============================================================
1      :data:`FLAG_LSM`            disparity and σ from LSM
2      :data:`FLAG_LSM_FAILED`     LSM tried and rejected (σ, ρ, convergence): FBM value kept
4      :data:`FLAG_FEATURE_SUBPIXEL`  NCC parabola failed: Förstner feature difference kept
8      :data:`FLAG_ENLARGED`       window matched in the enlarged-window retry
16     :data:`FLAG_DENSIFIED`      window matched with denser points (reduced step)
32     :data:`FLAG_RETRY`          window matched in a later wave from its neighbours'
                                   predictions (came back from another side)
64     :data:`FLAG_GRID`           grid densification point (LSM)
128    :data:`FLAG_UPPER`          grid point found above the plane (``object_search``)
=====  ==========================  ============================================================

Only accepted points are returned (bidirectional failures and outliers are counted in
``stats``).
"""

from __future__ import annotations

import functools
import time
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Tuple

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from ..errors import InputError
from ..feedback import ensure_feedback
from .fbm import (
    FLAG_FEATURE_SUBPIXEL,
    FBMResult,
    Grouping,
    detect_features,
    fbm_level,
    fill_nodata,
    window_components,
)
from .interest import InterestPoints
from .lsm import lsm_match
from .ncc import ncc_epipolar
from .prediction import (
    COARSE,
    NEIGHBOURS,
    NONE,
    RANGE,
    SEED,
    ApproxGrid,
    CoarsePlanes,
    Predictor,
    eval_planes,
    fill_planes,
    points_planes,
    suspect_components,
)
from .pyramid import build_pyramid, from_level, levels_for_disparity, to_level

FLAG_LSM = 1
FLAG_LSM_FAILED = 2
FLAG_ENLARGED = 8
FLAG_DENSIFIED = 16
FLAG_RETRY = 32
FLAG_GRID = 64
FLAG_UPPER = 128
__all__ = ["FLAG_DENSIFIED", "FLAG_ENLARGED", "FLAG_FEATURE_SUBPIXEL", "FLAG_GRID", "FLAG_LSM",
           "FLAG_LSM_FAILED", "FLAG_RETRY", "FLAG_UPPER", "EpipolarMatches", "FbmLsmOptions",
           "match_epipolar_fbm_lsm"]



@dataclass
class FbmLsmOptions:
    """Parameters of :func:`match_epipolar_fbm_lsm` (px = pixels of the working level).

    Attributes
    ----------
    levels : int, optional
        Pyramid levels incl. level 0; None → :func:`.pyramid.levels_for_disparity` so that the
        range ``max_d − min_d`` shrinks to ≤ fbm_window/4 px at the top (top ≥ 2 windows).
    interest_window : int
        Förstner summation window (seed: 5 × 5; pilot 3 × 5).
    q_min, w_factor : float
        Förstner roundness threshold and weight factor × median(w).
    nms_window : int
        Non-maximum suppression of the interest points (5 → ≤ 4 % of the pixels).
    local_cell : int, optional
        Sub-images (px of each level) with their own Förstner weight threshold
        ``w_factor × median(w)`` (seed §2.3: homogeneous point distribution on images with
        strong texture differences); None → 2 × fbm_window; 0 → one global threshold.
    local_floor : float
        A sub-image's median counts at least this share of the image's median (keeps noise in
        uniform areas out).
    ncc_window : int
        Window of the candidate correlation ρ (seed ≈ 5 × 5).
    refine_window : int
        Window of the NCC parabola for the sub-pixel disparity.
    rho_min : float
        Candidates need ρ ≥ rho_min (seed 0.5–0.7).
    candidates : {"correlation", "features"}
        Candidate source (:func:`.fbm.fbm_level`): local maxima of the NCC profile along the
        right epipolar row for every left Förstner point (default: no need for the same point
        to be detected in both images, which on real images holds for only about half of
        them), or the right Förstner points (the seed's pure FBM).
    max_peaks : int
        Correlation candidates per point (the highest local NCC maxima). 1 (default): in
        weak texture the lower maxima of 7 × 7 windows are dense enough that a few of them
        agree on a false plane by chance; the best peak of each point rarely does.
    fbm_window : int
        Matching-window side, px (seed 30–40, ≈ 32).
    pull_in : float, optional
        Half width of the candidate search around the prediction, px. None → fbm_window/8
        (4 px) when predicted from the coarser level, fbm_window/4 (8 px, the FBM convergence
        range of the seed) when growing from seeds or neighbours; with correlation candidates
        at least 4 and 8 px (small windows on steep terrain).
    bidir_tol : float
        Left→right and right→left disparities must agree within this, px.
    row_tol : float
        Candidates within ± row_tol rows of the left point, px.
    min_points : int
        Accepted points a window needs to count as matched.
    huber_iterations, redescending_iterations, huber_k, redescending_c, reject_k, sigma_floor :
        Robust consistency (:func:`.fbm.robust_plane_fit`): 2 × Huber k = 1.5σ, 4 × exp(−(v/2.5σ)²),
        outliers beyond 3σ, σ ≥ 0.3 px.
    enlarge, densify : bool
        Failure cascade steps (enlarge the window; reduce the step = denser points).
    keep_coarse : bool
        Also return the points of the coarser levels (in level-0 pixels, ``level`` > 0).
    lsm : bool
        Refine the level-0 points by epipolar LSM.
    lsm_half : int
        LSM template half size (window = 2·half + 1 = 17 ≈ the seed's 16 × 16).
    lsm_max_sigma, lsm_min_rho : float
        LSM acceptance: σ_px ≤ 0.2 px, ρ ≥ 0.7 (seed Tab. 3.9).
    lsm_max_iter : int
        Gauss–Newton iteration limit.
    lsm_pull_in : float
        LSM may move the disparity at most this far from the FBM value, px.
    lsm_reject : bool
        Drop level-0 points whose LSM fails (seed §2.12: reject by σ_px / ρ / convergence);
        False keeps their FBM value with :data:`FLAG_LSM_FAILED`.
    object_pull_in : float, optional
        Pull-in at the finest level only, px (at least the normal one): reaches objects above
        the ground plane of a window (a roof 8 m high is ≈ 15 px at B/H 0.36, GSD 0.2 m)
        without widening the coarse levels' search, where it lets repetitive texture match
        wrongly (issue 19). None: as the other levels.
    neighbour_tol : float
        A matched window component whose plane differs from the median of its (≥ 3) matched
        neighbours' planes by more than max(neighbour_tol, pull-in/2) px at its centre is
        redone once from its neighbours (0 = off).
    grid_step : int
        With ``lsm``: densification on a regular grid of this step (level-0 px; 0 = off).
        Every grid node of a matched window component is predicted from the component's FBM
        plane, refined per point by an NCC search within ± the FBM pull-in (so the plane
        need not fit rough terrain) and then by LSM; only nodes passing the LSM thresholds
        are kept (:data:`FLAG_GRID`). Seed §3.1: "good points in regularly densified
        sub-images" (Hannah) and "match many points, then select the locally best".
    object_search : float, optional
        With ``grid_step``: grid nodes the search around the plane did not keep search again
        up to this many px *above* the plane (objects stand on the ground: a roof of a given
        height in px of the model's parallax, issue 19; see "Objects above the plane" in the
        module notes). None or 0: off.
    """

    levels: Optional[int] = None
    interest_window: int = 5
    q_min: float = 0.6
    w_factor: float = 1.0
    nms_window: int = 5
    local_cell: Optional[int] = None
    local_floor: float = 0.0625
    ncc_window: int = 7
    refine_window: int = 9
    rho_min: float = 0.6
    candidates: str = "correlation"
    max_peaks: int = 1
    fbm_window: int = 32
    pull_in: Optional[float] = None
    bidir_tol: float = 1.0
    row_tol: float = 1.0
    min_points: int = 3
    huber_iterations: int = 2
    redescending_iterations: int = 4
    huber_k: float = 1.5
    redescending_c: float = 2.5
    reject_k: float = 3.0
    sigma_floor: float = 0.3
    enlarge: bool = True
    densify: bool = True
    keep_coarse: bool = False
    lsm: bool = True
    lsm_half: int = 8
    lsm_max_sigma: float = 0.2
    lsm_min_rho: float = 0.7
    lsm_max_iter: int = 20
    lsm_pull_in: float = 2.0
    lsm_reject: bool = True
    object_pull_in: Optional[float] = None
    neighbour_tol: float = 2.0
    grid_step: int = 4
    object_search: Optional[float] = None


@dataclass
class EpipolarMatches:
    """All accepted points of an epipolar pair, in level-0 pixels of the left image.

    Attributes
    ----------
    col, row : float64
        Left epipolar pixel (sub-pixel Förstner position).
    disparity : float64
        d = col_left − col_right, px.
    sigma_px : float32
        σ of the disparity, px: the LSM shift σ, else σ0 of the point's FBM window.
    rho : float32
        Correlation coefficient (LSM after matching, else the NCC peak).
    flags : uint8
        ``FLAG_*`` bits (module docstring).
    level : int8
        Pyramid level the point was matched at (0 for final points).
    stats : dict
        JSON-ready: ``{"levels": {"k": {...}}, "total": {...}}`` with per level features
        left/right, candidates, windows, masked/failed windows, failure %, accepted points,
        outliers, bidirectional rejections, cascade recoveries, waves, seconds; LSM tried/failed.
    failures : (k, 3) float64
        col, row (left, level-0 px) and level of the window components marked as failed.
    """

    col: NDArray
    row: NDArray
    disparity: NDArray
    sigma_px: NDArray
    rho: NDArray
    flags: NDArray
    level: NDArray
    stats: Dict[str, Any] = field(default_factory=dict)
    failures: NDArray = field(default_factory=lambda: np.zeros((0, 3)))

    def __len__(self) -> int:
        return int(self.col.size)


def _reduce_any(mask: NDArray) -> NDArray:
    """Boolean 2 × 2 block 'any' (the pyramid's block layout, odd edges repeated)."""
    m = np.asarray(mask, bool)
    if m.shape[0] % 2 or m.shape[1] % 2:
        m = np.pad(m, ((0, m.shape[0] % 2), (0, m.shape[1] % 2)), mode="edge")
    return m.reshape(m.shape[0] // 2, 2, m.shape[1] // 2, 2).any(axis=(1, 3))


def _mask_pyramid(mask: Optional[NDArray], n: int) -> List[Optional[NDArray]]:
    """``n`` levels of a boolean mask (2 × 2 'any' per level; None stays None)."""
    if mask is None:
        return [None] * n
    out = [np.asarray(mask, bool)]
    for _ in range(n - 1):
        out.append(_reduce_any(out[-1]))
    return out


class _Collected:
    """Accepted points of one level, appended wave by wave."""

    def __init__(self) -> None:
        self.parts: List[Tuple[NDArray, ...]] = []

    def add(self, res: FBMResult, sel: NDArray, flag: int) -> None:
        if sel.any():
            self.parts.append((res.col[sel], res.row[sel], res.disparity[sel], res.rho[sel],
                               res.sigma_px[sel], (res.flags[sel] | flag).astype(np.uint8),
                               res.group[sel]))

    def drop_groups(self, drop: NDArray) -> None:
        """Remove the points of the components marked in ``drop``."""
        self.parts = [tuple(a[~drop[p[6]]] for a in p) for p in self.parts]

    def arrays(self) -> Tuple[NDArray, ...]:
        if not self.parts:
            return (np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0, np.float32),
                    np.zeros(0, np.float32), np.zeros(0, np.uint8), np.zeros(0, np.int64))
        return tuple(np.concatenate(p) for p in zip(*self.parts))


def _check_inputs(left: NDArray, right: NDArray, min_d: float, max_d: float,
                  mask: Optional[NDArray], barriers: Optional[NDArray],
                  seeds: Optional[NDArray], approx: Optional[Tuple[NDArray, float]]
                  ) -> Tuple[NDArray, NDArray]:
    """The two images as float32 after checking shapes, range, seeds and approximation.

    Raises
    ------
    InputError
        Naming what is wrong and how to fix it.
    """
    L = np.asarray(left, dtype=np.float32)
    R = np.asarray(right, dtype=np.float32)
    if L.ndim != 2 or R.ndim != 2:
        raise InputError("left and right must be 2-D grey images; convert colour images first")
    if L.shape[0] != R.shape[0]:
        raise InputError(f"epipolar images must have the same number of rows (left {L.shape}, "
                         f"right {R.shape}); resample both with the same epipolar pair")
    if not (np.isfinite(min_d) and np.isfinite(max_d)) or max_d < min_d:
        raise InputError(f"disparity range [{min_d}, {max_d}] is invalid: give min_d ≤ max_d")
    for name, m in (("mask", mask), ("barriers", barriers)):
        if m is not None and np.shape(m) != L.shape:
            raise InputError(f"{name} must have the left image's shape {L.shape}, "
                             f"not {np.shape(m)}")
    if seeds is not None:
        s = np.asarray(seeds, dtype=np.float64)
        if s.ndim != 2 or s.shape[1] != 3:
            raise InputError("seeds must be an (n, 3) array of col, row, disparity")
    if approx is not None:
        grid, step = approx
        if np.ndim(grid) != 2 or not step > 0:
            raise InputError("approx must be (2-D disparity grid, positive step in px)")
    return L, R


@dataclass
class _Run:
    """Constants of one matching run, shared by all levels."""

    opt: FbmLsmOptions
    min_d: float
    max_d: float
    shape0: Tuple[int, int]
    ws: int
    lsm_window: int
    margin_coarse: int
    margin0: int
    pull_ref: float
    pull_grow: float
    level_kw: Dict[str, Any]

    @property
    def use_right_features(self) -> bool:
        return self.opt.candidates == "features"


def _run_constants(opt: FbmLsmOptions, min_d: float, max_d: float,
                   shape0: Tuple[int, int]) -> _Run:
    """Window sizes, margins, pull-ins and the keywords of :func:`.fbm.fbm_level`."""
    ws = int(opt.fbm_window)
    lsm_window = 2 * int(opt.lsm_half) + 1
    margin_coarse = max(opt.ncc_window + 4, opt.refine_window) // 2 + 1
    margin0 = max(margin_coarse, lsm_window // 2 + 1 if opt.lsm else 0)
    # the coarser level's plane is off by its relief curvature, not by a share of the window:
    # small windows keep ≥ 4 px (8 px when growing) with correlation candidates, whose search
    # is not bound to the FBM convergence range of a window
    floor = 4.0 if opt.candidates == "correlation" else 0.0
    pull_ref = opt.pull_in if opt.pull_in is not None else max(ws / 8.0, floor)
    pull_grow = opt.pull_in if opt.pull_in is not None else max(ws / 4.0, 2.0 * floor)
    robust = {"huber_iterations": opt.huber_iterations,
              "redescending_iterations": opt.redescending_iterations,
              "huber_k": opt.huber_k, "redescending_c": opt.redescending_c,
              "reject_k": opt.reject_k, "sigma_floor": opt.sigma_floor}
    level_kw = {"rho_min": opt.rho_min, "row_tol": opt.row_tol, "bidir_tol": opt.bidir_tol,
                "min_points": opt.min_points, "robust": robust,
                "refine_window": opt.refine_window, "candidates": opt.candidates,
                "max_peaks": int(opt.max_peaks)}
    return _Run(opt, min_d, max_d, shape0, ws, lsm_window, margin_coarse, margin0, pull_ref,
                pull_grow, level_kw)


def _level_count(run: _Run, L0: NDArray, R0: NDArray, vL: NDArray, vR: NDArray) -> int:
    """Pyramid depth: ``opt.levels`` or enough for the range, limited by the overlap."""
    if run.opt.levels is not None:
        return max(1, int(run.opt.levels))
    ws = run.ws
    n_levels = levels_for_disparity(run.max_d - run.min_d, pull_in=ws / 4.0, min_size=2 * ws,
                                    shape=(min(L0.shape[0], R0.shape[0]),
                                           min(L0.shape[1], R0.shape[1])))
    # the top level must hold at least one whole matching window (plus the margins where
    # no point can lie) across the stereo overlap, else nothing can be matched there
    overlap0 = _overlap_width(vL, vR, run.min_d, run.max_d)
    while n_levels > 1 and overlap0 / 2.0 ** (n_levels - 1) < ws + 2 * run.margin_coarse:
        n_levels -= 1
    return n_levels


@dataclass
class _Pyramids:
    """Image, no-data, exclusion and barrier pyramids (index = level)."""

    left: List[NDArray]
    right: List[NDArray]
    nodata_left: List[Optional[NDArray]]
    nodata_right: List[Optional[NDArray]]
    mask: List[Optional[NDArray]]
    barriers: List[Optional[NDArray]]

    @property
    def n_levels(self) -> int:
        return len(self.nodata_left)


def _build_pyramids(Lf: NDArray, Rf: NDArray, vL: NDArray, vR: NDArray,
                    mask: Optional[NDArray], barriers: Optional[NDArray],
                    n_levels: int) -> _Pyramids:
    """All pyramids, as deep as both image pyramids go."""
    pl = build_pyramid(Lf, n_levels)
    pr = build_pyramid(Rf, n_levels)
    n = min(len(pl), len(pr))
    return _Pyramids(pl, pr, _mask_pyramid(~vL, n), _mask_pyramid(~vR, n),
                     _mask_pyramid(mask, n), _mask_pyramid(barriers, n))


@dataclass
class _Level:
    """What one pyramid level matches on: images, exclusions, components, features."""

    k: int
    scale: float
    left: NDArray
    right: NDArray
    valid_left: Optional[NDArray]
    valid_right: Optional[NDArray]
    barriers: Optional[NDArray]
    margin: int
    excl: Optional[NDArray]
    grouping: Grouping
    feature_kw: Dict[str, Any]
    fl: InterestPoints
    fr: InterestPoints
    masked: NDArray
    tiny: NDArray

    @property
    def ng(self) -> int:
        return self.grouping.n_groups


def _level_exclusion(run: _Run, pyr: _Pyramids, k: int, margin: int, valid_right,
                     prev_matched: NDArray, prev: Optional[CoarsePlanes] = None
                     ) -> Tuple[NDArray, Optional[NDArray]]:
    """Left pixels without stereo overlap, and all excluded pixels of level ``k``.

    Left pixels whose search range never reaches right-image data have nothing to match
    (not a failure); below the top, the range is the coarser level's measured disparities,
    and per pixel the range its own and neighbouring coarser planes span
    (:func:`_local_range`).
    """
    scale = 2.0 ** k
    Lk, Rk = pyr.left[k], pyr.right[k]
    no_overlap = ~_overlap_mask(valid_right, Rk.shape, Lk.shape, run.min_d / scale - 1.0,
                                run.max_d / scale + 1.0, margin)
    pm = prev_matched[np.isfinite(prev_matched[:, 0])]
    if pm.size:
        # sharper: the disparities the coarser level measured (its planes at their window
        # corners, ± the growing pull-in) instead of the a-priori range. Not per pixel: a
        # wrong coarse window must stay open for the neighbour check, not be masked
        corners = (pm[:, :1] + pm[:, 1:2] * np.array([-0.5, 0.5, -0.5, 0.5])
                   + pm[:, 2:3] * np.array([-0.5, -0.5, 0.5, 0.5]))
        lo_all = max(2.0 * float(corners.min()) - run.pull_grow, run.min_d / scale) - 1.0
        hi_all = min(2.0 * float(corners.max()) + run.pull_grow, run.max_d / scale) + 1.0
        no_overlap |= ~_overlap_mask(valid_right, Rk.shape, Lk.shape, lo_all, hi_all, margin)
    if prev is not None:
        # no margin here: a partner window that reaches over the right image's border can
        # still match (the drone pairs lost correct points along it with the margin)
        lo_px, hi_px = _local_range(run, prev, k, Lk.shape)
        no_overlap |= ~_overlap_mask(valid_right, Rk.shape, Lk.shape, lo_px, hi_px, 0)
    excl = None
    for m in (pyr.mask[k], pyr.barriers[k], no_overlap if no_overlap.any() else None):
        if m is not None:
            excl = m.copy() if excl is None else (excl | m)
    return no_overlap, excl


#: Block side (level px) of the per-pixel disparity intervals (:func:`_local_range`).
_RANGE_STEP = 4


def _local_range(run: _Run, prev: CoarsePlanes, k: int, shape: Tuple[int, int]
                 ) -> Tuple[NDArray, NDArray]:
    """Disparity interval (level-k px) each pixel can still take: the lowest and highest of
    the coarser level's own and neighbouring planes there (:meth:`CoarsePlanes.span`),
    widened by the growing pull-in (not by the finest level's object search upwards: with it
    most windows along the far edge stay open; objects that much above the coarser planes
    are not what these windows fail on).

    Why: on convergent pairs the disparity changes by hundreds of px across the image, so
    the range over the whole level reaches right-image data for windows along the overlap's
    far edge whose own partner lies outside the right image (issue 22). The neighbours'
    planes keep a wrong coarse window open. NaN (no plane anywhere) → the whole range.

    The planes are evaluated at the centres of ``step`` × ``step`` blocks (a plane moves
    less than a pixel across a block, far less than the pull-in added) and the blocks are
    filled with their centre's interval: the neighbour planes of every pixel would take five
    evaluations per pixel.
    """
    h, w = shape
    step = _RANGE_STEP
    rows, cols = np.mgrid[0:h:step, 0:w:step].astype(float)
    rows, cols = np.minimum(rows + step // 2, h - 1), np.minimum(cols + step // 2, w - 1)
    lo, hi = prev.span(cols.ravel(), rows.ravel())
    _, grow = _level_pulls(run, k)
    lo = np.where(np.isfinite(lo), lo - grow - 1.0, run.min_d / 2.0 ** k - 1.0)
    hi = np.where(np.isfinite(hi), hi + grow + 1.0, run.max_d / 2.0 ** k + 1.0)

    def blocks(a: NDArray) -> NDArray:
        a = a.reshape(rows.shape)
        return np.repeat(np.repeat(a, step, axis=0), step, axis=1)[:h, :w]

    return blocks(lo), blocks(hi)


def _component_masks(grouping: Grouping, shape: Tuple[int, int], mask: Optional[NDArray],
                     valid_left: Optional[NDArray], no_overlap: NDArray, margin: int,
                     ws: int) -> Tuple[NDArray, NDArray]:
    """Masked (≥ 90 % excluded or without data) and tiny (< ½ window usable) components.

    Neither counts as a failure: tiny ones are e.g. cut by the image border, where no point
    can lie.
    """
    ng = grouping.n_groups
    lab = grouping.labels.ravel()
    bad_px = np.zeros(shape, bool)
    if mask is not None:
        bad_px |= mask
    if valid_left is not None:
        bad_px |= ~valid_left
    bad_px |= no_overlap
    n_bad = np.bincount(lab, bad_px.ravel(), ng + 1)[1:]
    masked = n_bad >= 0.9 * np.maximum(grouping.area, 1)
    bad_px[:margin + 1, :] = bad_px[-margin - 1:, :] = True
    bad_px[:, :margin + 1] = bad_px[:, -margin - 1:] = True
    usable = grouping.area - np.bincount(lab, bad_px.ravel(), ng + 1)[1:]
    tiny = usable < 0.5 * ws * ws
    return masked, tiny


def _setup_level(run: _Run, pyr: _Pyramids, k: int, prev_matched: NDArray,
                 prev: Optional[CoarsePlanes] = None) -> _Level:
    """Exclusions, window components, Förstner features and component masks of level k
    (``prev``: the coarser level's filled planes, None at the top)."""
    opt, ws = run.opt, run.ws
    Lk, Rk = pyr.left[k], pyr.right[k]
    validL = ~pyr.nodata_left[k] if pyr.nodata_left[k] is not None else None
    validR = ~pyr.nodata_right[k] if pyr.nodata_right[k] is not None else None
    margin = run.margin0 if k == 0 else run.margin_coarse
    no_overlap, excl = _level_exclusion(run, pyr, k, margin, validR, prev_matched, prev)
    grouping = window_components(Lk.shape, ws, pyr.barriers[k])
    fkw = {"window": opt.interest_window, "q_min": opt.q_min, "w_factor": opt.w_factor,
           "nms_window": opt.nms_window, "margin": margin,
           "local_cell": 2 * ws if opt.local_cell is None else int(opt.local_cell),
           "local_floor": opt.local_floor}
    fl = detect_features(Lk, validL, excl, **fkw)
    fr = (detect_features(Rk, validR, None, **fkw) if run.use_right_features
          else _no_points())
    masked, tiny = _component_masks(grouping, Lk.shape, pyr.mask[k], validL, no_overlap,
                                    margin, ws)
    return _Level(k, 2.0 ** k, Lk, Rk, validL, validR, pyr.barriers[k], margin, excl,
                  grouping, fkw, fl, fr, masked, tiny)


def _seed_disparities(seeds: NDArray, run: _Run, lv: _Level, fb: Any
                      ) -> Tuple[NDArray, NDArray, int]:
    """Mean seed disparity per component (level px), the components with seeds, seeds used.

    Raises
    ------
    InputError
        When no start point lies inside the left epipolar image.
    """
    h0, w0 = run.shape0
    s = np.asarray(seeds, dtype=np.float64).reshape(-1, 3)
    inside = ((s[:, 0] >= -0.5) & (s[:, 0] < w0 - 0.5)
              & (s[:, 1] >= -0.5) & (s[:, 1] < h0 - 0.5)
              & np.isfinite(s).all(axis=1))
    if not inside.any():
        raise InputError(f"none of the {len(s)} start point(s) lies inside the "
                         f"left epipolar image ({w0} × {h0} px); "
                         "check the start points of this model")
    if not inside.all():
        fb.warning(f"{int((~inside).sum())} start point(s) outside the left "
                   "epipolar image are ignored")
    s = s[inside]
    ng = lv.ng
    gs = lv.grouping.of(to_level(s[:, 0], lv.k), to_level(s[:, 1], lv.k), nearest=True)
    ok = gs >= 0
    cnt = np.bincount(gs[ok], minlength=ng)
    sd = np.bincount(gs[ok], s[ok, 2] / lv.scale, ng)
    has = cnt > 0
    seed_d = np.full(ng, np.nan)
    seed_d[has] = sd[has] / cnt[has]
    return seed_d, has, int(ok.sum())


def _initial_modes(run: _Run, lv: _Level, prev: Optional[CoarsePlanes],
                   approx: Optional[Tuple[NDArray, float]], seeds: Optional[NDArray], fb: Any
                   ) -> Tuple[NDArray, NDArray, Any, Optional[int]]:
    """Prediction mode per component, seed disparities, coarse predictor, seeds used.

    Below the top level every component is predicted from the coarser level, except those
    it could not predict (nothing matched within reach there, e.g. a failed top level):
    they search the whole range, never zero points silently. At the top: the ``approx``
    grid, the seeds, else the range.
    """
    ng = lv.ng
    mode = np.zeros(ng, np.int8)
    seed_d = np.full(ng, np.nan)
    n_seeds: Optional[int] = None
    if prev is not None:
        mode[:] = COARSE
        c = lv.grouping.centres
        mode[~np.isfinite(prev.predict(c[:, 0], c[:, 1]))] = RANGE
        return mode, seed_d, prev, n_seeds
    coarse = None
    if approx is not None:
        coarse = ApproxGrid(np.asarray(approx[0], dtype=np.float64), float(approx[1]),
                             lv.k, lv.scale)
        mode[:] = COARSE
    if seeds is not None:
        seed_d, has, n_seeds = _seed_disparities(seeds, run, lv, fb)
        mode[has] = SEED
    elif approx is None:
        mode[:] = RANGE
    return mode, seed_d, coarse, n_seeds


@dataclass
class _LevelState:
    """The waves' bookkeeping of one level (per component unless noted)."""

    mode: NDArray
    seed_d: NDArray
    coarse: Any
    matched: NDArray
    plane: NDArray
    tried_nb: NDArray
    cascaded: NDArray
    suspect_done: NDArray
    todo: NDArray
    collected: _Collected
    st: Dict[str, Any]
    fallback_done: bool
    wave: int = 0
    big: Optional[Grouping] = None

    def predictor(self, run: _Run, lv: _Level) -> Predictor:
        """The predictor of the current wave (its own copy of the to-do set)."""
        mid_k = 0.5 * (run.min_d + run.max_d) / lv.scale
        half_k = 0.5 * (run.max_d - run.min_d) / lv.scale + 1.0
        ref, grow = _level_pulls(run, lv.k)
        return Predictor(lv.grouping, self.mode, self.plane, self.matched, self.seed_d,
                          self.coarse, mid_k, half_k, ref, grow, self.todo.copy())


def _level_pulls(run: _Run, k: int) -> Tuple[float, float]:
    """Pull-ins (from the coarser level, growing) of level ``k``: the finest level widens both
    to ``object_pull_in`` if given."""
    extra = run.opt.object_pull_in
    if k == 0 and extra:
        return max(run.pull_ref, float(extra)), max(run.pull_grow, float(extra))
    return run.pull_ref, run.pull_grow


def _new_state(lv: _Level, mode: NDArray, seed_d: NDArray, coarse: Any,
               top: int) -> _LevelState:
    """Empty bookkeeping of a level; its statistics start with the feature counts."""
    ng = lv.ng
    st = {"features_left": int(lv.fl.cols.size), "features_right": int(lv.fr.cols.size),
          "candidates": 0, "outliers": 0, "bidir_rejected": 0, "windows": int(ng),
          "windows_masked": int(lv.masked.sum()), "enlarged_recovered": 0,
          "densified_recovered": 0, "retry_recovered": 0, "waves": 0,
          "range_fallback": 0}
    return _LevelState(mode, seed_d, coarse, np.zeros(ng, bool), np.full((ng, 3), np.nan),
                       np.full(ng, -1, np.int64), np.zeros(ng, bool), np.zeros(ng, bool),
                       (mode != NONE) & ~lv.masked, _Collected(), st, lv.k != top)


def _matched_neighbours(grouping: Grouping, matched: NDArray) -> NDArray:
    """Number of matched neighbour components of every component (float)."""
    if not grouping.edges.size:
        return np.zeros(grouping.n_groups)
    return np.bincount(grouping.edges[:, 0], matched[grouping.edges[:, 1]], grouping.n_groups)


def _redo_suspects(run: _Run, lv: _Level, s: _LevelState) -> None:
    """Consistency between windows: a component whose plane disagrees with the median of
    (≥ 3) matched neighbours is redone from its neighbours, once."""
    tol = max(float(run.opt.neighbour_tol), run.pull_ref / 2.0)
    sus = suspect_components(s.plane, lv.grouping, s.matched & ~s.suspect_done, s.matched,
                              tol)
    if sus.any():
        s.suspect_done |= sus
        s.matched &= ~sus
        s.plane[sus] = np.nan
        s.collected.drop_groups(sus)
        s.mode[sus] = NEIGHBOURS
        s.tried_nb[sus] = -1
        s.todo = sus
        s.st["suspect_redone"] = s.st.get("suspect_redone", 0) + int(sus.sum())


def _next_todo(run: _Run, lv: _Level, s: _LevelState) -> bool:
    """Set the components of the next wave; False when the level is done.

    With nothing left: the suspects of the neighbour check, then (once, at the top level)
    the components never reached from the seeds/approximation, which search the range.
    """
    if not s.todo.any() and run.opt.neighbour_tol and run.opt.neighbour_tol > 0:
        _redo_suspects(run, lv, s)
    if s.todo.any():
        return True
    if s.fallback_done:
        return False
    s.fallback_done = True
    s.todo = (s.tried_nb < 0) & ~s.matched & ~lv.masked
    s.mode[s.todo] = RANGE
    s.st["range_fallback"] = int(s.todo.sum())
    return bool(s.todo.any())


def _match_wave(run: _Run, lv: _Level, s: _LevelState, predict: Predictor) -> NDArray:
    """One wave of :func:`.fbm.fbm_level` over the to-do set; returns its new failures."""
    todo_now = predict.todo
    retry = (s.mode == NEIGHBOURS) & (s.wave > 0)
    nb_count = _matched_neighbours(lv.grouping, s.matched)
    s.tried_nb[todo_now] = nb_count[todo_now].astype(np.int64)
    res = fbm_level(lv.left, lv.right, lv.fl, lv.fr, lv.grouping, predict,
                    ncc_window=run.opt.ncc_window, **run.level_kw)
    for key in ("candidates", "outliers", "bidir_rejected"):
        s.st[key] += res.stats[key]
    ok = todo_now & (res.n_accepted >= run.opt.min_points)
    sel = ok[np.maximum(res.group, 0)] & (res.group >= 0)
    s.collected.add(res, sel & ~retry[res.group], 0)
    s.collected.add(res, sel & retry[res.group], FLAG_RETRY)
    s.st["retry_recovered"] += int((ok & retry).sum())
    s.plane[ok] = res.plane[ok]
    s.matched |= ok
    return todo_now & ~ok & ~s.cascaded


def _enlarge(run: _Run, lv: _Level, s: _LevelState, predict: Predictor,
             failed: NDArray) -> None:
    """Failure cascade, step 1: match the failed components in 2 × larger windows.

    Matched components sharing a big window with a failed one give context (their own
    plane). ``failed`` loses the recovered components (in place).
    """
    opt, grouping, fl, ng = run.opt, lv.grouping, lv.fl, lv.ng
    s.cascaded |= failed
    if s.big is None:
        s.big = window_components(lv.left.shape, 2 * run.ws, lv.barriers)
    big = s.big
    gl_small = grouping.of(fl.cols, fl.rows)
    in_failed = (gl_small >= 0) & failed[np.maximum(gl_small, 0)]
    big_sel = np.zeros(big.n_groups, bool)
    gb = big.of(fl.cols, fl.rows)
    big_sel[gb[in_failed & (gb >= 0)]] = True
    ctx = (gb >= 0) & big_sel[np.maximum(gb, 0)] & (gl_small >= 0)
    context = np.zeros(ng, bool)
    context[gl_small[ctx]] = True
    context &= s.matched
    predict_big = functools.partial(predict, active=failed, context=context)
    res2 = fbm_level(lv.left, lv.right, fl, lv.fr, big, predict_big,
                     ncc_window=opt.ncc_window + 4, **run.level_kw)
    g2 = grouping.of(res2.col, res2.row)
    keep = (g2 >= 0) & failed[np.maximum(g2, 0)]
    cnt = np.bincount(g2[keep], minlength=ng)
    ok2 = failed & (cnt >= opt.min_points)
    if ok2.any():
        keep &= ok2[np.maximum(g2, 0)]
        res2.group = g2
        s.collected.add(res2, keep, FLAG_ENLARGED)
        s.plane[ok2] = points_planes(grouping, res2.col[keep], res2.row[keep],
                                      res2.disparity[keep], g2[keep])[ok2]
        s.matched |= ok2
        s.st["enlarged_recovered"] += int(ok2.sum())
    failed &= ~ok2


def _densify(run: _Run, lv: _Level, s: _LevelState, predict: Predictor,
             failed: NDArray) -> None:
    """Failure cascade, step 2: reduce the step (denser Förstner points) in failed windows.

    The points are detected only in the rows/columns of the failed windows (the thresholds
    become local there, as the seed's sub-image thresholds).
    """
    opt, ws, Lk, Rk = run.opt, run.ws, lv.left, lv.right
    s.cascaded |= failed
    dkw = dict(lv.feature_kw, w_factor=opt.w_factor / 4.0, q_min=min(opt.q_min, 0.5),
               nms_window=3)
    wi = lv.grouping.window_index[failed]
    nwx = -(-Lk.shape[1] // ws)
    pad = lv.margin + 4
    r0 = max(int(wi.min() // nwx) * ws - pad, 0)
    r1 = min(int(wi.max() // nwx + 1) * ws + pad, Lk.shape[0])
    c0 = max(int((wi % nwx).min()) * ws - pad, 0)
    c1 = min(int((wi % nwx).max() + 1) * ws + pad, Lk.shape[1])
    dfl = _detect_crop(Lk, lv.valid_left, lv.excl, r0, r1, c0, c1, dkw)
    dfr = (_detect_crop(Rk, lv.valid_right, None, r0, min(r1, Rk.shape[0]), 0,
                        Rk.shape[1], dkw) if run.use_right_features else _no_points())
    gd = lv.grouping.of(dfl.cols, dfl.rows)
    sub = (gd >= 0) & failed[np.maximum(gd, 0)]
    dfl_sub = InterestPoints(*(a[sub] for a in dfl))
    predict_dense = functools.partial(predict, active=failed)
    res3 = fbm_level(Lk, Rk, dfl_sub, dfr, lv.grouping, predict_dense,
                     ncc_window=opt.ncc_window, **run.level_kw)
    ok3 = failed & (res3.n_accepted >= opt.min_points)
    if ok3.any():
        sel3 = (res3.group >= 0) & ok3[np.maximum(res3.group, 0)]
        s.collected.add(res3, sel3, FLAG_DENSIFIED)
        s.plane[ok3] = res3.plane[ok3]
        s.matched |= ok3
        s.st["densified_recovered"] += int(ok3.sum())


@dataclass
class _Progress:
    """Progress over the levels, weighted by their pixel counts (4^-k)."""

    fb: Any
    cost: NDArray
    done: float = 0.0

    @property
    def total(self) -> float:
        return float(self.cost.sum())

    def wave(self, k: int, wave: int) -> None:
        self.fb.progress(100.0 * (self.done + self.cost[k] * min(0.9, 0.3 + 0.1 * wave))
                         / self.total)

    def level_done(self, k: int, lsm: bool) -> None:
        self.done += self.cost[k]
        self.fb.progress(100.0 * self.done / self.total * (0.9 if lsm else 1.0))


def _match_level(run: _Run, lv: _Level, s: _LevelState, progress: _Progress) -> None:
    """Waves until no component is left: match, failure cascade, come back from other
    sides (components whose matched neighbours grew since they were last tried)."""
    opt = run.opt
    while _next_todo(run, lv, s):
        predict = s.predictor(run, lv)
        failed = _match_wave(run, lv, s, predict)
        if failed.any() and opt.enlarge:
            _enlarge(run, lv, s, predict, failed)
        if failed.any() and opt.densify:
            _densify(run, lv, s, predict, failed)
        nb_count = _matched_neighbours(lv.grouping, s.matched)
        s.todo = ~s.matched & ~lv.masked & (nb_count > 0) & (nb_count > s.tried_nb)
        s.mode[s.todo] = NEIGHBOURS
        s.wave += 1
        progress.wave(lv.k, s.wave)
    s.st["waves"] = s.wave


def _level_points(lv: _Level, s: _LevelState, failures: List[NDArray]
                  ) -> Tuple[NDArray, ...]:
    """Accepted points of the level in level-0 px; statistics and failures recorded."""
    k, st = lv.k, s.st
    col, row, d, rho, sig, flags, _ = s.collected.arrays()
    fail = ~s.matched & ~lv.masked & ~lv.tiny
    st["failed_windows"] = int(fail.sum())
    n_eval = int((~lv.masked & ~lv.tiny).sum())
    st["failure_pct"] = round(100.0 * st["failed_windows"] / max(n_eval, 1), 3)
    st["accepted"] = int(col.size)
    if fail.any():
        c = lv.grouping.centres[fail]
        failures.append(np.stack([from_level(c[:, 0], k), from_level(c[:, 1], k),
                                  np.full(len(c), k, float)], 1))
    return (from_level(col, k), from_level(row, k), d * lv.scale,
            (sig * lv.scale).astype(np.float32), rho.astype(np.float32), flags,
            np.full(col.size, k, np.int8))


def _lsm_refine(run: _Run, Lf: NDArray, Rf: NDArray, pts: Tuple[NDArray, ...],
                total: Dict[str, Any]) -> Tuple[NDArray, ...]:
    """Epipolar LSM of the level-0 points; failed ones flagged or (``lsm_reject``) dropped.

    Seed §2.12: reject by the LSM thresholds — on real images nearly every gross FBM error
    (> 2 px) is among these points.
    """
    opt = run.opt
    col, row, disp, sig, rho, flags, level = pts
    sel = np.flatnonzero(level == 0)
    if not sel.size:
        return pts
    res = lsm_match(Lf, Rf, col[sel], row[sel], col[sel] - disp[sel], None,
                    window=run.lsm_window, model="epipolar", max_iter=opt.lsm_max_iter,
                    max_shift=opt.lsm_pull_in, min_corr=opt.lsm_min_rho,
                    max_sigma=opt.lsm_max_sigma)
    good = res.valid & np.isfinite(res.cols)
    gi = sel[good]
    disp[gi] = col[gi] - res.cols[good]
    sig[gi] = res.sigma_col[good]
    rho[gi] = res.corr[good]
    flags[gi] |= FLAG_LSM
    flags[sel[~good]] |= FLAG_LSM_FAILED
    total["lsm_tried"] = int(sel.size)
    total["lsm_failed"] = int((~good).sum())
    if opt.lsm_reject and (~good).any():
        keep = np.ones(col.size, bool)
        keep[sel[~good]] = False
        total["lsm_rejected"] = int((~keep).sum())
        return tuple(a[keep] for a in pts)
    return pts


def _grid_densify(run: _Run, Lf: NDArray, Rf: NDArray, lv: _Level, s: _LevelState,
                  pts: Tuple[NDArray, ...]) -> Tuple[Tuple[NDArray, ...], Dict[str, Any]]:
    """Level-0 grid densification appended to the points (see :func:`_grid_points`).

    Failed components are predicted from their neighbours' planes (wider search).
    """
    t_grid = time.perf_counter()
    g_plane = fill_planes(s.plane, lv.grouping, s.matched, lv.masked)
    ref, grow = _level_pulls(run, lv.k)
    g_pull = np.where(s.matched, ref, grow)
    g_parts, g_stats = _grid_points(Lf, Rf, lv.grouping, g_plane, g_pull, lv.excl,
                                    lv.valid_left, lv.margin, int(run.opt.grid_step), run.opt,
                                    run.lsm_window)
    if g_parts is not None:
        pts = tuple(np.concatenate([a, b]) for a, b in zip(pts, g_parts))
    g_stats["seconds"] = round(time.perf_counter() - t_grid, 3)
    return pts, g_stats


def _level0_finale(run: _Run, Lf: NDArray, Rf: NDArray, lv: _Level, s: _LevelState,
                   pts: Tuple[NDArray, ...], total: Dict[str, Any],
                   stats0: Dict[str, Any], fb: Any) -> Tuple[NDArray, ...]:
    """LSM of the level-0 points, then the grid densification; statistics recorded."""
    t_lsm = time.perf_counter()
    pts = _lsm_refine(run, Lf, Rf, pts, total)
    total["lsm_seconds"] = round(time.perf_counter() - t_lsm, 3)
    stats0["lsm_tried"] = total["lsm_tried"]
    if run.opt.grid_step and run.opt.grid_step > 0:
        fb.check()
        pts, g_stats = _grid_densify(run, Lf, Rf, lv, s, pts)
        total["grid"] = g_stats
        stats0["grid_points"] = g_stats["accepted"]
    stats0["lsm_failed"] = total["lsm_failed"]
    stats0["lsm_rejected"] = total.get("lsm_rejected", 0)
    return pts


def match_epipolar_fbm_lsm(left: NDArray, right: NDArray, min_d: float, max_d: float, *,
                           seeds: Optional[NDArray] = None, mask: Optional[NDArray] = None,
                           barriers: Optional[NDArray] = None,
                           approx: Optional[Tuple[NDArray, float]] = None,
                           options: Optional[FbmLsmOptions] = None,
                           feedback=None) -> EpipolarMatches:
    """Hierarchical feature-based matching (+ LSM) of an epipolar pair; all raw points.

    Parameters
    ----------
    left, right : (rows, cols) float32
        Grey epipolar images (rows correspond), NaN = no data. The widths may differ.
    min_d, max_d : float
        Disparity range d = col_l − col_r at level 0, px (used at the top level when there are
        no seeds and for components never reached from them).
    seeds : (n, 3) array, optional
        Operator start points: col, row, disparity at level 0.
    mask : bool array (left shape), optional
        True = do not match (exclusion areas, outside the boundary): no points there.
    barriers : bool array (left shape), optional
        True = breakline pixel: predictions never propagate across (window components).
    approx : (grid, step), optional
        Disparity approximation (level-0 px, NaN = unknown); ``grid[i, j]`` holds for the
        level-0 pixels with row in [i·step, (i+1)·step) and col in [j·step, (j+1)·step).
        Used at the top level instead of the range.
    options : FbmLsmOptions, optional
    feedback : Feedback, optional
        Progress (per wave and level) and cancellation.

    Returns
    -------
    EpipolarMatches
    """
    t_start = time.perf_counter()
    fb = ensure_feedback(feedback)
    opt = options or FbmLsmOptions()
    L0, R0 = _check_inputs(left, right, min_d, max_d, mask, barriers, seeds, approx)
    Lf, vL = fill_nodata(L0)
    Rf, vR = fill_nodata(R0)
    run = _run_constants(opt, min_d, max_d, L0.shape)
    pyr = _build_pyramids(Lf, Rf, vL, vR, mask, barriers, _level_count(run, L0, R0, vL, vR))
    n_levels = pyr.n_levels
    top = n_levels - 1
    progress = _Progress(fb, np.array([4.0 ** -k for k in range(n_levels)]))
    prev: Optional[CoarsePlanes] = None  # filled planes of the coarser level
    prev_matched = np.zeros((0, 3))
    stats_levels: Dict[str, Any] = {}
    failures: List[NDArray] = []
    out_parts: List[Tuple[NDArray, ...]] = []
    n_seeds_used = 0
    for k in range(top, -1, -1):
        t_level = time.perf_counter()
        lv = _setup_level(run, pyr, k, prev_matched, prev)
        mode, seed_d, coarse, n_seeds = _initial_modes(run, lv, prev, approx, seeds, fb)
        n_seeds_used = n_seeds if n_seeds is not None else n_seeds_used
        s = _new_state(lv, mode, seed_d, coarse, top)
        _match_level(run, lv, s, progress)
        pts = _level_points(lv, s, failures)
        # predictions for the next level everywhere (also into masked components, which
        # only sharpens the overlap there; nothing is matched in them)
        prev = CoarsePlanes(fill_planes(s.plane, lv.grouping, s.matched,
                                          np.zeros(lv.ng, bool)), lv.grouping)
        prev_matched = np.where(s.matched[:, None], s.plane, np.nan)  # measured planes only
        if k == 0 or opt.keep_coarse:
            out_parts.append(pts)
        s.st["seconds"] = round(time.perf_counter() - t_level, 3)
        stats_levels[str(k)] = s.st
        progress.level_done(k, opt.lsm)
        fb.info(f"FBM level {k}: {s.st['accepted']} points, {s.st['failed_windows']} failed "
                f"windows ({s.st['failure_pct']} %), {s.st['waves']} waves")

    pts = tuple(np.concatenate(p) for p in zip(*out_parts))
    total: Dict[str, Any] = {"levels": n_levels, "seeds_used": n_seeds_used,
                             "lsm_tried": 0, "lsm_failed": 0, "lsm_rejected": 0}
    if opt.lsm:
        pts = _level0_finale(run, Lf, Rf, lv, s, pts, total, stats_levels["0"], fb)
    fb.progress(100.0)
    fail_arr = np.concatenate(failures) if failures else np.zeros((0, 3))
    total["points"] = int(pts[0].size)
    total["failed_windows"] = len(fail_arr)
    total["failure_pct_level0"] = stats_levels["0"]["failure_pct"]
    total["seconds"] = round(time.perf_counter() - t_start, 3)
    return EpipolarMatches(*pts, {"levels": stats_levels, "total": total}, fail_arr)


def _overlap_width(valid_left: NDArray, valid_right: NDArray, min_d: float, max_d: float
                   ) -> float:
    """Width (level-0 px) of the left columns whose search range reaches right-image data.

    A left column c overlaps when some right column c − d, d ∈ [min_d, max_d], holds data in
    any row: c ∈ [c_r,min + min_d, c_r,max + max_d] ∩ the left columns with data.
    """
    cl = np.flatnonzero(valid_left.any(axis=0))
    cr = np.flatnonzero(valid_right.any(axis=0))
    if cl.size == 0 or cr.size == 0:
        return 0.0
    lo = max(float(cl[0]), cr[0] + min_d)
    hi = min(float(cl[-1]), cr[-1] + max_d)
    return max(hi - lo + 1.0, 0.0)


def _overlap_mask(valid_right: Optional[NDArray], right_shape: Tuple[int, int],
                  left_shape: Tuple[int, int], lo: float, hi: float, margin: int) -> NDArray:
    """Left pixels (r, c) with right data at (r, c − d) for some d ∈ [lo, hi] (level px).

    The right image's data (eroded by ``margin`` so that a correlation window fits) is summed
    cumulatively along the rows; a left pixel overlaps when the sum over the columns
    [c − hi, c − lo] is positive. Rows beyond the right image have no overlap. ``lo`` and
    ``hi`` are numbers or per-pixel arrays of the left shape.
    """
    h, w = left_shape
    hr, wr = right_shape
    vr = np.ones((hr, wr), bool) if valid_right is None else np.asarray(valid_right, bool)
    vr = vr.copy()
    m = int(margin)
    if m > 0:
        vr[:, :m] = vr[:, wr - m:] = False
        vr[:m, :] = vr[hr - m:, :] = False
        if valid_right is not None and not np.all(valid_right):
            vr &= ~ndimage.maximum_filter(~np.asarray(valid_right, bool), size=2 * m + 1,
                                          mode="constant", cval=True)
    rows = min(h, hr)
    cs = np.zeros((rows, wr + 1), np.int64)
    cs[:, 1:] = np.cumsum(vr[:rows], axis=1)
    c = np.broadcast_to(np.arange(w, dtype=np.float64), (h, w))[:rows]
    lo_r = np.broadcast_to(np.asarray(lo, np.float64), (h, w))[:rows]
    hi_r = np.broadcast_to(np.asarray(hi, np.float64), (h, w))[:rows]
    a = np.clip(np.ceil(c - hi_r), 0, wr).astype(np.int64)  # first right column (incl.)
    b = np.clip(np.floor(c - lo_r) + 1, 0, wr).astype(np.int64)  # last right column + 1
    out = np.zeros((h, w), bool)
    out[:rows] = (np.take_along_axis(cs, b, 1) - np.take_along_axis(cs, a, 1)) > 0
    return out


def _grid_nodes(Lf: NDArray, grouping: Grouping, plane: NDArray, pull: NDArray,
                excl: Optional[NDArray], valid: Optional[NDArray], margin: int, step: int
                ) -> Tuple[NDArray, NDArray, NDArray, NDArray]:
    """Grid nodes ``(step/2 + i·step)`` of components with a plane, away from no-data,
    exclusions, barriers and the image border: columns, rows, plane disparity, pull-in."""
    h, w = Lf.shape
    ok_px = np.ones((h, w), bool)
    if excl is not None:
        ok_px &= ~excl
    if valid is not None and not np.all(valid):
        ok_px &= ~ndimage.maximum_filter(~valid, size=2 * margin + 1, mode="constant",
                                         cval=True)
    ok_px[:margin + 1, :] = ok_px[h - margin - 1:, :] = False
    ok_px[:, :margin + 1] = ok_px[:, w - margin - 1:] = False
    r0 = step // 2
    rr, cc = np.mgrid[r0:h:step, r0:w:step]
    rr, cc = rr.ravel(), cc.ravel()
    sel = ok_px[rr, cc]
    rr, cc = rr[sel].astype(float), cc[sel].astype(float)
    g = grouping.of(cc, rr)
    d = eval_planes(plane, grouping, g, cc, rr)
    sel = np.isfinite(d)
    return cc[sel], rr[sel], d[sel], pull[g[sel]]


def _node_matches(Lf: NDArray, Rf: NDArray, cc: NDArray, rr: NDArray, lo: NDArray,
                  hi: NDArray, opt: FbmLsmOptions, lsm_window: int, st: Dict[str, Any],
                  above: Optional[NDArray] = None, window: Optional[int] = None,
                  bidir_tol: Optional[float] = None, back_half: Optional[NDArray] = None
                  ) -> Tuple[NDArray, Optional[_Lsm]]:
    """NCC search of nodes within [lo, hi] (px), LSM, then the right→left search over the
    same interval; the accepted nodes and the LSM result (indexed like the nodes).

    ``above``: the NCC peak must lie at or above this disparity (else the node is not kept);
    ``window``: the NCC window (default ``refine_window``); ``bidir_tol``: the right→left
    tolerance (default the option's); ``back_half``: the right→left search spans ± this
    around the found disparity (default: the interval [lo, hi] itself).
    ``st`` gets the counts ``ncc_ok``, ``lsm_ok`` and ``accepted`` added.
    """
    n = cc.size
    good = np.zeros(n, bool)
    win = int(opt.refine_window if window is None else window)
    res = ncc_epipolar(Lf, Rf, cc, rr, np.floor(lo), np.ceil(hi), window=win,
                       min_ncc=opt.rho_min, max_ratio=0.9)
    found = res.valid & np.isfinite(res.cols)
    if above is not None:
        found &= res.disparity >= above
    ok = np.flatnonzero(found)
    st["ncc_ok"] = st.get("ncc_ok", 0) + int(ok.size)
    if ok.size == 0:
        return good, None
    lsm = lsm_match(Lf, Rf, cc[ok], rr[ok], res.cols[ok], None, window=lsm_window,
                    model="epipolar", max_iter=opt.lsm_max_iter, max_shift=opt.lsm_pull_in,
                    min_corr=opt.lsm_min_rho, max_sigma=opt.lsm_max_sigma)
    acc = lsm.valid & np.isfinite(lsm.cols)
    st["lsm_ok"] = st.get("lsm_ok", 0) + int(acc.sum())
    tol = opt.bidir_tol if bidir_tol is None else bidir_tol
    if acc.any() and tol is not None and np.isfinite(tol):
        # right → left: occlusions and repetitive texture give a different best match back
        # (the bidirectional check of the FBM points, seed §2.8)
        gi = np.flatnonzero(acc)
        dd = cc[ok[gi]] - lsm.cols[gi]
        if back_half is None:
            b_lo, b_hi = np.floor(-hi[ok[gi]]), np.ceil(-lo[ok[gi]])
        else:
            b_lo, b_hi = np.floor(-dd - back_half[ok[gi]]), np.ceil(-dd + back_half[ok[gi]])
        back = ncc_epipolar(Rf, Lf, lsm.cols[gi], rr[ok[gi]], b_lo, b_hi, window=win,
                            min_ncc=opt.rho_min, max_ratio=1.0)
        agree = back.valid & (np.abs(-back.disparity - dd) <= tol)
        acc[gi[~agree]] = False
    good[ok[acc]] = True
    st["accepted"] = st.get("accepted", 0) + int(acc.sum())
    full = _empty_lsm(n)
    full.cols[ok], full.sigma[ok], full.corr[ok] = lsm.cols, lsm.sigma_col, lsm.corr
    return good, full


@dataclass
class _Lsm:
    """LSM results of grid nodes (right column, σ, ρ; NaN where not matched)."""

    cols: NDArray
    sigma: NDArray
    corr: NDArray

    def merged(self, other: _Lsm, sel: NDArray) -> _Lsm:
        """These results with ``other``'s at the nodes ``sel``."""
        return _Lsm(np.where(sel, other.cols, self.cols),
                    np.where(sel, other.sigma, self.sigma), np.where(sel, other.corr, self.corr))


def _empty_lsm(n: int) -> _Lsm:
    """LSM results of ``n`` nodes, none matched."""
    return _Lsm(np.full(n, np.nan), np.full(n, np.nan, np.float32),
                np.full(n, np.nan, np.float32))


def _grid_points(Lf: NDArray, Rf: NDArray, grouping: Grouping, plane: NDArray,
                 pull: NDArray, excl: Optional[NDArray], valid: Optional[NDArray],
                 margin: int, step: int, opt: FbmLsmOptions, lsm_window: int
                 ) -> Tuple[Optional[Tuple[NDArray, ...]], Dict[str, Any]]:
    """Level-0 grid densification (see ``FbmLsmOptions.grid_step``).

    Nodes (:func:`_grid_nodes`); prediction = the component's plane; NCC search
    (``refine_window``) within ± ``pull[component]`` px, peak ρ ≥ ``rho_min`` and ambiguity
    ≤ 0.9; then epipolar LSM, kept only when valid (σ_px, ρ, convergence) and the right→left
    search returns. With ``object_search``, nodes not kept search again *above* the plane
    (:func:`_upper_nodes`): objects stand on the ground, their disparity is larger.
    """
    st: Dict[str, Any] = {"nodes": 0, "ncc_ok": 0, "lsm_ok": 0, "accepted": 0}
    cc, rr, d, p = _grid_nodes(Lf, grouping, plane, pull, excl, valid, margin, step)
    st["nodes"] = int(rr.size)
    if rr.size == 0:
        return None, st
    good, lsm = _node_matches(Lf, Rf, cc, rr, d - p, d + p, opt, lsm_window, st, back_half=p)
    flags = np.full(cc.size, FLAG_GRID | FLAG_LSM, np.uint8)
    if opt.object_search:
        up, lsm_up = _upper_nodes(Lf, Rf, cc, rr, d, p, ~good, opt, lsm_window, st)
        if up.any():
            lsm = lsm_up if lsm is None else lsm.merged(lsm_up, up)
            good |= up
            flags[up] |= FLAG_UPPER
    if not good.any():
        return None, st
    n = int(good.sum())
    parts = (cc[good], rr[good], cc[good] - lsm.cols[good],
             lsm.sigma[good].astype(np.float32), lsm.corr[good].astype(np.float32),
             flags[good], np.zeros(n, np.int8))
    return parts, st


def _upper_nodes(Lf: NDArray, Rf: NDArray, cc: NDArray, rr: NDArray, d: NDArray, p: NDArray,
                 todo: NDArray, opt: FbmLsmOptions, lsm_window: int, st: Dict[str, Any]
                 ) -> Tuple[NDArray, Optional[_Lsm]]:
    """Nodes ``todo`` searched from ``d − p`` to ``d + object_search`` px, kept when the
    best peak lies above ``d + p/2``.

    A roof several metres above the ground plane of its windows lies beyond the pull-in of
    the wide-angle aerial models (≈ 4 px per metre of height, issue 19); on open terrain the
    node was matched near the plane already and is not searched again, so the wide band only
    meets the nodes the plane could not explain.
    """
    out = np.zeros(cc.size, bool)
    idx = np.flatnonzero(todo & (float(opt.object_search) > p))
    sub: Dict[str, Any] = {"nodes": int(idx.size)}
    st["upper"] = sub
    if idx.size == 0:
        return out, None
    # the whole interval, plane included: the peak above must be the best and unambiguous
    # (repetitive field texture has a second peak of about the same ρ near the plane)
    lo = d[idx] - p[idx]
    hi = d[idx] + float(opt.object_search)
    good, lsm = _node_matches(Lf, Rf, cc[idx], rr[idx], lo, hi, opt, lsm_window, sub,
                              above=d[idx] + 0.5 * p[idx],
                              window=int(opt.refine_window) + UPPER_WINDOW_ADD)
    full = _empty_lsm(cc.size) if lsm is None else _scatter(lsm, idx, cc.size)
    if lsm is not None:
        gi = idx[good]
        own = _own_pixel_upper(Lf, Rf, cc[gi], rr[gi], cc[gi] - full.cols[gi], d[gi], p[gi],
                               opt)
        out[gi[own]] = True
        sub["own_pixel_rejected"] = int((~own).sum())
    # the rim goes before the growing (a clean start) and after it (what grew past a wall)
    sub["rim_rejected"] = _drop_rim(cc, rr, out, full, int(opt.grid_step))
    _grow_upper(Lf, Rf, cc, rr, d, p, todo, out, full, opt, lsm_window, sub)
    sub["rim_rejected"] += _drop_rim(cc, rr, out, full, int(opt.grid_step))
    return out, full


def _drop_rim(cc: NDArray, rr: NDArray, out: NDArray, full: _Lsm, step: int) -> int:
    """Upper nodes ``out`` (in place) that the opening (:func:`_inner_nodes`) removes; their
    number."""
    up = np.flatnonzero(out)
    if up.size == 0:
        return 0
    inner = _inner_nodes(cc[up], rr[up], cc[up] - full.cols[up], step)
    out[up[~inner]] = False
    return int((~inner).sum())


def _scatter(lsm: _Lsm, idx: NDArray, n: int) -> _Lsm:
    """LSM results of the nodes ``idx`` placed into arrays of all ``n`` nodes (NaN elsewhere)."""
    out = _empty_lsm(n)
    out.cols[idx], out.sigma[idx], out.corr[idx] = lsm.cols, lsm.sigma, lsm.corr
    return out


#: Region growing of the upper nodes: rounds, and half width (px) of the search around the
#: mean disparity of a node's upper neighbours.
UPPER_GROW_ROUNDS = 8
UPPER_GROW_PX = 3.0
#: Right→left tolerance of a grown node (px): the narrow search is bound to its neighbours
#: already; weakly textured roofs put the back search's NCC peak up to a pixel off the LSM
#: value (with ``urban``'s 0.5 px four of five roof candidates failed there).
UPPER_GROW_BIDIR_PX = 1.0


def _grow_upper(Lf: NDArray, Rf: NDArray, cc: NDArray, rr: NDArray, d: NDArray, p: NDArray,
                todo: NDArray, out: NDArray, full: _Lsm, opt: FbmLsmOptions,
                lsm_window: int, sub: Dict[str, Any]) -> None:
    """Grow the upper nodes (``out``, ``full``; in place) over their roof: a node of ``todo``
    beside an upper node is searched within ± :data:`UPPER_GROW_PX` of its upper neighbours'
    mean disparity, with the same acceptance (above the plane, LSM, right→left, own pixel).

    The wide search of :func:`_upper_nodes` finds about a third of the roof nodes on the
    aerial block (weak roof texture gives other NCC peaks over 80 px); from a found node its
    neighbours need only a narrow, unambiguous search — the roof plane of the issue's "grid
    densification on the roof plane".
    """
    step = int(opt.grid_step)
    i = np.floor(rr / step).astype(np.int64)
    j = np.floor(cc / step).astype(np.int64)
    i, j = i - i.min() + 1, j - j.min() + 1
    shape = (int(i.max()) + 2, int(j.max()) + 2)
    tried = ~todo | out
    tol = None if opt.bidir_tol is None else max(float(opt.bidir_tol), UPPER_GROW_BIDIR_PX)
    grown = 0
    for _ in range(UPPER_GROW_ROUNDS):
        disp = np.full(shape, np.nan)
        up = np.flatnonzero(out)
        disp[i[up], j[up]] = cc[up] - full.cols[up]
        nb = np.stack([disp[i + di, j + dj] for di, dj in ((0, 1), (0, -1), (1, 0), (-1, 0))])
        has = np.isfinite(nb).any(axis=0)
        cand = np.flatnonzero(has & ~tried)
        if cand.size == 0:
            break
        tried[cand] = True
        pred = np.nanmean(nb[:, cand], axis=0)
        good, lsm = _node_matches(Lf, Rf, cc[cand], rr[cand], pred - UPPER_GROW_PX,
                                  pred + UPPER_GROW_PX, opt, lsm_window, sub,
                                  above=d[cand] + 0.5 * p[cand],
                                  window=int(opt.refine_window) + UPPER_WINDOW_ADD,
                                  bidir_tol=tol)
        if lsm is None or not good.any():
            break
        new = _scatter(lsm, cand, cc.size)
        gi = cand[good]
        own = _own_pixel_upper(Lf, Rf, cc[gi], rr[gi], cc[gi] - new.cols[gi], d[gi], p[gi],
                               opt)
        gi = gi[own]
        full.cols[gi], full.sigma[gi], full.corr[gi] = new.cols[gi], new.sigma[gi], new.corr[gi]
        out[gi] = True
        grown += int(gi.size)
    sub["grown"] = grown


#: Disparity difference (px) within which neighbouring upper nodes belong to one surface.
UPPER_NEIGHBOUR_PX = 2.0
#: Grow the eroded upper population back by one node (:func:`_inner_nodes`).
UPPER_REOPEN = True
#: The upward search's NCC window is this much larger than ``refine_window`` (px).
UPPER_WINDOW_ADD = 4


def _inner_nodes(cc: NDArray, rr: NDArray, disp: NDArray, step: int,
                 reopen: bool = UPPER_REOPEN) -> NDArray:
    """Upper nodes whose four grid neighbours are upper nodes of the same surface (within
    :data:`UPPER_NEIGHBOUR_PX`): the upper population eroded by one node, and (``reopen``)
    grown back by one node onto upper nodes of the same surface (a morphological opening).

    Ground nodes beside a wall that still match the roof (fattening, on the aerial block in
    lines along the walls, consistent with each other) form the rim of the population and
    touch no inner node; the roof's own rim touches its inner nodes and comes back.
    """
    if cc.size == 0:
        return np.zeros(0, bool)
    i = np.floor(rr / step).astype(np.int64)  # nodes at step/2 + k·step
    j = np.floor(cc / step).astype(np.int64)
    i, j = i - i.min() + 1, j - j.min() + 1
    shape = (int(i.max()) + 2, int(j.max()) + 2)
    grid = np.full(shape, np.nan)
    grid[i, j] = disp
    four = ((0, 1), (0, -1), (1, 0), (-1, 0))
    keep = np.ones(cc.size, bool)
    for di, dj in four:
        keep &= np.abs(grid[i + di, j + dj] - disp) <= UPPER_NEIGHBOUR_PX  # NaN fails
    if not reopen:
        return keep
    inner = np.full(shape, np.nan)
    inner[i[keep], j[keep]] = disp[keep]
    out = keep.copy()
    for di, dj in four:
        out |= np.abs(inner[i + di, j + dj] - disp) <= UPPER_NEIGHBOUR_PX
    return out


def _own_pixel_upper(Lf: NDArray, Rf: NDArray, cc: NDArray, rr: NDArray, d_up: NDArray,
                     d: NDArray, p: NDArray, opt: FbmLsmOptions) -> NDArray:
    """Upper matches whose own pixel is upper too (shiftable windows).

    A ground node within half a matching window of a roof edge matches the roof: the edge's
    contrast fills the window (foreground fattening). Windows ending at the node on its left,
    centred on it and ending on its right are correlated at the upper disparity and around
    the plane; the node stays upper only if the best of the six is an upper one — beside a
    wall the window on the far side of the edge sees ground only and prefers the plane.
    """
    win = max(3, int(opt.refine_window) - 2) | 1
    best_near = np.full(cc.size, -1.0)
    best_up = np.full(cc.size, -1.0)
    for shift in (-(win // 2), 0, win // 2):
        cs = cc + shift
        near = ncc_epipolar(Lf, Rf, cs, rr, np.floor(d - p), np.ceil(d + p), window=win,
                            min_ncc=-1.0, max_ratio=1.0)
        up = ncc_epipolar(Lf, Rf, cs, rr, np.floor(d_up) - 1, np.ceil(d_up) + 1, window=win,
                          min_ncc=-1.0, max_ratio=1.0)
        best_near = np.fmax(best_near, np.nan_to_num(near.ncc, nan=-1.0))
        best_up = np.fmax(best_up, np.nan_to_num(up.ncc, nan=-1.0))
    return best_up > best_near


def _no_points() -> InterestPoints:
    return InterestPoints(np.zeros(0), np.zeros(0), np.zeros(0, np.float32),
                          np.zeros(0, np.float32))


def _detect_crop(img: NDArray, valid: Optional[NDArray], excl: Optional[NDArray], r0: int,
                 r1: int, c0: int, c1: int, kw: dict) -> InterestPoints:
    """:func:`.fbm.detect_features` on a crop, in the coordinates of the whole image."""
    crop = (slice(r0, r1), slice(c0, c1))
    if r1 - r0 < 8 or c1 - c0 < 8:
        return _no_points()
    f = detect_features(img[crop], None if valid is None else valid[crop],
                        None if excl is None else excl[crop], **kw)
    return InterestPoints(f.cols + c0, f.rows + r0, f.w, f.q)

