"""Keypoint stage: an image against a georeferenced raster (orthophoto, satellite scene).

1. Both images to 8 bit by a robust stretch (0.5–99.5 % percentiles), on a pyramid level of
   at most :data:`MAX_DETECT_PX` pixels.
2. SIFT keypoints (OpenCV ≥ 4.4; AKAZE, else ORB where SIFT is missing) in the reference, the
   image and the image mirrored left–right (descriptors are not mirror-invariant, so a mirrored
   image is matched as its mirror image; the better of both is kept).
3. Lowe's ratio test (0.8), then MAGSAC (``cv2.USAC_MAGSAC``; RANSAC in older OpenCV) for the
   affine (or projective) image → reference map.
4. Guided refinement at full resolution: the reference is warped into the image frame by the
   current estimate and a grid of image patches is located in it by normalised
   cross-correlation within a few pixels (sub-pixel peak; a patch whose contrast is inverted
   counts too: seasonal change inverts some classes). The patch positions that agree with one
   affine (projective) map are the control points — spread over the cloud-free, overlapping
   part of the image by construction.

Clouds, haze and land-cover change only cost matches: they are outliers of both robust steps.
The stage fails (:class:`~..errors.GeometryError`, with its figures) when too few keypoints or
patches agree; the pipeline then tries the segmentation-based stages.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple, Union

import cv2
import numpy as np
from numpy.typing import NDArray

from ..errors import GeometryError, InputError
from ..feedback import Feedback
from .correspondence import apply
from .fit import fit_matrix, fit_transform, inverse_for_resampling
from .reference_layer import load_reference
from .refinement import ControlPoint
from .result import GeorefResult

PathLike = Union[str, Path]
Array = NDArray[np.float64]

#: Largest image (pixels) keypoints are detected on; larger ones: a pyramid level.
MAX_DETECT_PX = 2.0e6
#: Largest image (pixels) the guided refinement warps the reference into.
MAX_REFINE_PX = 6.0e6
#: Most keypoints kept per image (the strongest).
MAX_KEYPOINTS = 4000
#: Lowe's ratio of the best to the second-best descriptor distance.
RATIO = 0.8
#: Fewest keypoint inliers of the robust fit (fewer: the stage fails).
MIN_INLIERS = 10
#: Fewest refined patches that agree with one transform (fewer: the stage fails).
MIN_PATCHES = 30
#: Smallest |NCC| of a refined patch.
MIN_NCC = 0.5
#: Detectors tried by ``detector="auto"``, best first.
DETECTORS = ("sift", "akaze", "orb")


@dataclass
class KeypointMatch:
    """The image → reference-pixel map of the keypoint stage and its control points.

    Image and reference coordinates are level-0 pixels, pixel centres at integers.
    """

    transform: Array  #: 3 × 3 image → reference pixel after the refinement
    initial: Array  #: 3 × 3 of the keypoint fit
    image_xy: Array  #: (n, 2) control points in the image
    ref_xy: Array  #: (n, 2) the same points in the reference
    ncc: Array  #: (n,) |NCC| of each point's patch
    counts: Dict[str, Any] = field(default_factory=dict)


def to_byte(grey: Array, low: float = 0.5, high: float = 99.5
            ) -> Tuple[NDArray[np.uint8], NDArray[np.uint8]]:
    """8-bit image (``low``–``high`` percentiles stretched to 0–255) and its valid-pixel mask
    (255 where finite; eroded by 2 px so that no keypoint sits on the border of no-data)."""
    a = np.asarray(grey, np.float64)
    ok = np.isfinite(a)
    if not ok.any():
        raise InputError.of("The image has no valid pixels.")
    lo, hi = np.percentile(a[ok], [low, high])
    scale = 255.0 / (hi - lo) if hi > lo else 1.0
    out = np.clip((np.where(ok, a, lo) - lo) * scale, 0, 255).round().astype(np.uint8)
    mask = cv2.erode(ok.astype(np.uint8) * 255, np.ones((5, 5), np.uint8))
    return out, mask


def pyramid_level(shape: Tuple[int, ...], max_px: float) -> int:
    """The first pyramid level (factor 2 each) with at most ``max_px`` pixels."""
    level = 0
    while shape[0] * shape[1] / 4.0**level > max_px:
        level += 1
    return level


def reduce(img: NDArray[Any], level: int) -> NDArray[Any]:
    """Level ``level`` by area averaging: level-L pixel j covers level-0 pixels j·2^L …
    j·2^L + 2^L − 1 (centre at j·2^L + (2^L − 1)/2)."""
    if level == 0:
        return img
    f = 2**level
    h, w = img.shape[0] // f, img.shape[1] // f
    return cv2.resize(img[:h * f, :w * f], (w, h), interpolation=cv2.INTER_AREA)


def to_level0(xy: Array, level: int) -> Array:
    """Level-``level`` pixel coordinates → level 0 (see :func:`reduce`)."""
    f = 2.0**level
    return np.asarray(xy, np.float64) * f + (f - 1.0) / 2.0


def make_detector(name: str = "auto") -> Tuple[Any, int, str]:
    """(OpenCV detector, descriptor norm, its name): ``auto`` = the first of
    :data:`DETECTORS` this OpenCV has."""
    names = DETECTORS if name == "auto" else (name,)
    for n in names:
        if n == "sift" and hasattr(cv2, "SIFT_create"):
            return cv2.SIFT_create(nfeatures=MAX_KEYPOINTS), cv2.NORM_L2, n
        if n == "akaze" and hasattr(cv2, "AKAZE_create"):
            return cv2.AKAZE_create(), cv2.NORM_HAMMING, n
        if n == "orb":
            return cv2.ORB_create(MAX_KEYPOINTS), cv2.NORM_HAMMING, n
    raise InputError.of("Unknown keypoint detector '{value}'; use auto, {options}.",
                        value=name, options=", ".join(DETECTORS))


def detect(img8: NDArray[np.uint8], mask: NDArray[np.uint8], det: Any
           ) -> Tuple[Array, Optional[NDArray[Any]]]:
    """Keypoint positions (level pixels) and descriptors (at most :data:`MAX_KEYPOINTS`, the
    strongest)."""
    kps, desc = det.detectAndCompute(img8, mask)
    if desc is None or not kps:
        return np.zeros((0, 2)), None
    if len(kps) > MAX_KEYPOINTS:
        keep = np.argsort([-k.response for k in kps], kind="stable")[:MAX_KEYPOINTS]
        kps = [kps[i] for i in keep]
        desc = desc[keep]
    return np.array([k.pt for k in kps], np.float64), desc


def ratio_matches(d_img: NDArray[Any], d_ref: NDArray[Any], norm: int, ratio: float = RATIO
                  ) -> NDArray[np.int64]:
    """(m, 2) index pairs (image, reference) passing Lowe's ratio test (brute force)."""
    if d_img is None or d_ref is None or len(d_img) < 2 or len(d_ref) < 2:
        return np.zeros((0, 2), np.int64)
    knn = cv2.BFMatcher(norm).knnMatch(d_img, d_ref, k=2)
    pairs = [(m[0].queryIdx, m[0].trainIdx) for m in knn
             if len(m) == 2 and m[0].distance < ratio * m[1].distance]
    return np.array(pairs, np.int64).reshape(-1, 2)


def robust_fit(src: Array, dst: Array, kind: str, threshold: float
               ) -> Tuple[Optional[Array], NDArray[np.bool_]]:
    """MAGSAC (RANSAC where OpenCV lacks it) affine or projective ``src`` → ``dst``: the
    3 × 3 matrix (``None`` when none is found) and the inlier mask."""
    method = getattr(cv2, "USAC_MAGSAC", cv2.RANSAC)
    n_min = 4 if kind == "projective" else 3
    if len(src) < n_min + 1:
        return None, np.zeros(len(src), bool)
    s, d = np.float32(src), np.float32(dst)
    if kind == "projective":
        M, inl = cv2.findHomography(s, d, method, threshold, maxIters=5000, confidence=0.999)
    else:
        M, inl = cv2.estimateAffine2D(s, d, method=method, ransacReprojThreshold=threshold,
                                      maxIters=5000, confidence=0.999)
        M = None if M is None else np.vstack([M, [0.0, 0.0, 1.0]])
    if M is None or inl is None:
        return None, np.zeros(len(src), bool)
    return np.asarray(M, np.float64), inl.ravel().astype(bool)


def keypoint_fit(img8: NDArray[np.uint8], img_mask: NDArray[np.uint8],
                 ref8: NDArray[np.uint8], ref_mask: NDArray[np.uint8], kind: str = "affine",
                 detector: str = "auto") -> Tuple[Optional[Array], Dict[str, Any]]:
    """Keypoints, ratio test and robust fit, the image as it is and mirrored (left–right).

    Returns the image → reference 3 × 3 of the better try (more inliers; ``None`` when no try
    has :data:`MIN_INLIERS`) on level-0 pixels, and the figures (``counts``).
    """
    det, norm, name = make_detector(detector)
    li = pyramid_level(img8.shape, MAX_DETECT_PX)
    lr = pyramid_level(ref8.shape, MAX_DETECT_PX)
    p_ref, d_ref = detect(reduce(ref8, lr), reduce(ref_mask, lr), det)
    small, small_mask = reduce(img8, li), reduce(img_mask, li)
    counts: Dict[str, Any] = {"detector": name, "keypoints_reference": len(p_ref)}
    best: Tuple[Optional[Array], int, bool] = (None, 0, False)
    for mirrored in (False, True):
        im = small[:, ::-1] if mirrored else small
        mk = small_mask[:, ::-1] if mirrored else small_mask
        p_img, d_img = detect(np.ascontiguousarray(im), np.ascontiguousarray(mk), det)
        if mirrored:
            p_img[:, 0] = small.shape[1] - 1 - p_img[:, 0]
        pairs = ratio_matches(d_img, d_ref, norm)
        src, dst = to_level0(p_img[pairs[:, 0]], li), to_level0(p_ref[pairs[:, 1]], lr)
        # threshold: 3 px of the coarser detection level, in reference pixels
        M, inl = robust_fit(src, dst, kind, 3.0 * 2.0**max(li, lr))
        key = "_mirrored" if mirrored else ""
        counts.update({f"keypoints_image{key}": len(p_img), f"matches{key}": len(pairs),
                       f"inliers{key}": int(inl.sum())})
        if M is not None and inl.sum() > best[1]:
            best = (M, int(inl.sum()), mirrored)
    M, n_inl, mirrored = best
    counts["mirrored"] = mirrored
    n_match = counts["matches_mirrored" if mirrored else "matches"]
    counts["inlier_share"] = round(n_inl / n_match, 4) if n_match else 0.0
    counts["pyramid_levels"] = [li, lr]
    return (M if n_inl >= MIN_INLIERS else None), counts


def _warp(ref: NDArray[np.float32], M: Array, shape: Tuple[int, int]) -> NDArray[np.float32]:
    """The reference in the image frame (image pixel x → reference pixel M·x; NaN outside),
    smoothed first where a reference pixel is smaller than an image pixel."""
    s = float(np.sqrt(abs(np.linalg.det(M[:2, :2]))))
    src = cv2.GaussianBlur(ref, (0, 0), 0.45 * np.sqrt(s * s - 1.0)) if s > 1.2 else ref
    flags = cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP
    h, w = shape
    if abs(M[2, 0]) + abs(M[2, 1]) > 0:
        return cv2.warpPerspective(src, M, (w, h), flags=flags, borderMode=cv2.BORDER_CONSTANT,
                                   borderValue=float("nan"))
    return cv2.warpAffine(src, M[:2], (w, h), flags=flags, borderMode=cv2.BORDER_CONSTANT,
                          borderValue=float("nan"))


def _peak(surface: Array) -> Optional[Tuple[float, float, float]]:
    """Sub-pixel extremum (dx, dy from the centre, |NCC|) of a correlation surface: the
    larger of maximum and −minimum (inverted contrast), not on the border."""
    hi, lo = float(surface.max()), float(surface.min())
    s = surface if hi >= -lo else -surface
    r, c = np.unravel_index(int(np.argmax(s)), s.shape)
    if not (0 < r < s.shape[0] - 1 and 0 < c < s.shape[1] - 1):
        return None

    def vertex(a: float, b: float, c_: float) -> float:
        den = a - 2 * b + c_
        return 0.5 * (a - c_) / den if den < 0 else 0.0

    dx = c + vertex(s[r, c - 1], s[r, c], s[r, c + 1]) - (s.shape[1] - 1) / 2
    dy = r + vertex(s[r - 1, c], s[r, c], s[r + 1, c]) - (s.shape[0] - 1) / 2
    return float(dx), float(dy), float(s[r, c])


def guided_patches(img: NDArray[np.float32], warped: NDArray[np.float32], radius: int,
                   half: int = 12, spacing: Optional[int] = None) -> Tuple[Array, Array, Array]:
    """Grid patches of ``img`` located in ``warped`` (the reference in the image frame) within
    ± ``radius`` px: patch centres, their shifts (add to get the warped position) and |NCC|.
    Patches without contrast, or whose window leaves the reference, are skipped."""
    h, w = img.shape
    step = spacing or max(16, min(h, w) // 40)
    m = half + radius
    pts, shifts, scores = [], [], []
    for y in range(m, h - m, step):
        for x in range(m, w - m, step):
            patch = img[y - half:y + half + 1, x - half:x + half + 1]
            win = warped[y - m:y + m + 1, x - m:x + m + 1]
            if not (np.isfinite(patch).all() and np.isfinite(win).all()):
                continue
            if patch.std() < 2.0 or win.std() < 2.0:  # grey values 0–255: no contrast
                continue
            pk = _peak(cv2.matchTemplate(win, patch, cv2.TM_CCOEFF_NORMED))
            if pk is None or pk[2] < MIN_NCC:
                continue
            pts.append((x, y))
            shifts.append(pk[:2])
            scores.append(pk[2])
    return (np.array(pts, np.float64).reshape(-1, 2), np.array(shifts).reshape(-1, 2),
            np.array(scores, np.float64))


def refine(grey_img: Array, grey_ref: Array, M: Array, kind: str, radius: int
           ) -> KeypointMatch:
    """Guided refinement of the image → reference map ``M`` (two passes: ± ``radius`` px,
    then ± 2 px). Returns the map and the agreeing patches (image and reference points)."""
    level = pyramid_level(grey_img.shape, MAX_REFINE_PX)
    img = reduce(np.asarray(grey_img, np.float32), level)
    ref = np.asarray(grey_ref, np.float32)
    f = 2.0**level
    # M on level-L image pixels: x0 = f·x + (f − 1)/2
    S = np.array([[f, 0, (f - 1) / 2], [0, f, (f - 1) / 2], [0, 0, 1.0]])
    T = M @ S
    tested = 0
    inl = np.zeros(0, bool)
    pts = ref_pts = scores = np.zeros((0, 2))
    for r, tol in ((max(radius, 2), 1.5), (2, 0.75)):
        pts, shifts, scores = guided_patches(img, _warp(ref, T, img.shape), r)
        tested = len(pts)
        ref_pts = apply(T, pts + shifts)
        s = float(np.sqrt(abs(np.linalg.det(T[:2, :2]))))
        T_new, inl = robust_fit(pts, ref_pts, kind, tol * s)
        if T_new is None or inl.sum() < MIN_PATCHES:
            break
        T = fit_matrix(pts[inl], ref_pts[inl], "projective" if kind == "projective"
                       else "affine")
    counts = {"patches": tested, "patches_agreeing": int(inl.sum()),
              "refine_level": level}
    n = int(inl.sum())
    return KeypointMatch(T @ np.linalg.inv(S), M, to_level0(pts[inl], level) if n else pts[:0],
                         ref_pts[inl] if n else ref_pts[:0], scores[inl] if n else scores[:0],
                         counts)


def spread(xy: Array, score: Array, shape: Tuple[int, int], count: int) -> NDArray[np.int64]:
    """Indices of at most ``count`` points spread over the image: the best-scoring point of
    each cell of a grid with about ``count`` cells."""
    if len(xy) <= count:
        return np.arange(len(xy))
    h, w = shape
    cell = np.sqrt(h * w / count)
    key = (xy[:, 1] // cell).astype(np.int64) * (int(w // cell) + 2) + (xy[:, 0] // cell)
    order = np.lexsort((-score, key))
    first = np.r_[True, np.diff(key[order]) != 0]
    return np.sort(order[first])


def match_image(grey_img: Array, grey_ref: Array, kind: str = "affine",
                detector: str = "auto", feedback: Optional[Feedback] = None) -> KeypointMatch:
    """Image → reference pixel map of two grey images (level 0, NaN = no data).

    Raises
    ------
    GeometryError
        Too few keypoint inliers or agreeing patches (the exception's ``counts`` hold the
        figures).
    """
    fb = feedback or Feedback()
    img8, img_mask = to_byte(grey_img)
    ref8, ref_mask = to_byte(grey_ref)
    M, counts = keypoint_fit(img8, img_mask, ref8, ref_mask, kind, detector)
    fb.check()
    fb.progress(60)
    n_inl = counts["inliers_mirrored" if counts["mirrored"] else "inliers"]
    fb.info(f"Keypoints ({counts['detector']}): {counts['keypoints_image']} in the image, "
            f"{counts['keypoints_reference']} in the reference; {counts['matches']} / "
            f"{counts['matches_mirrored']} matches (image / mirrored), {n_inl} inliers "
            f"({100 * counts['inlier_share']:.0f} %).")
    if M is None:
        raise GeometryError(f"only {n_inl} keypoint inliers (at least {MIN_INLIERS} needed)",
                            counts)
    # the keypoint fit is good to a few detection-level pixels
    radius = int(np.ceil(4 * 2.0 ** max(counts["pyramid_levels"])))
    km = refine(grey_img, grey_ref, M, kind, radius)
    fb.progress(90)
    km.counts = {**counts, **km.counts}
    if len(km.image_xy) < MIN_PATCHES:
        raise GeometryError(f"only {len(km.image_xy)} image patches agree with the keypoint "
                            f"transform (at least {MIN_PATCHES} needed)", km.counts)
    return km


def keypoint_result(grey: Array, image_info: Dict[str, Any], reference: PathLike,
                    kind: str = "affine", detector: str = "auto", max_gcps: int = 500,
                    parameters: Optional[Dict[str, Any]] = None, t0: Optional[float] = None,
                    feedback: Optional[Feedback] = None) -> GeorefResult:
    """The keypoint stage as a :class:`GeorefResult` (``stage = "keypoints"``): control
    points are the agreeing patches, at most ``max_gcps`` spread over the image; the final
    fit of ``kind`` (affine, projective, poly2) on them."""
    fb = feedback or Feedback()
    t0 = time.perf_counter() if t0 is None else t0
    ref_grey, to_map, crs, ref_info = load_reference(reference)
    km = match_image(grey, ref_grey, "projective" if kind == "projective" else "affine",
                     detector, fb)
    keep = spread(km.image_xy, km.ncc, grey.shape, max_gcps)
    img_xy, map_xy = km.image_xy[keep], apply(to_map, km.ref_xy[keep])
    fit = fit_transform(img_xy, map_xy, kind)
    res = np.hypot(*fit.extras["all_residuals_map"].T)
    gcps = [ControlPoint(image=(float(a[0]), float(a[1])), map=(float(b[0]), float(b[1])),
                         residual=float(r), pair=-1, sharp=False)
            for a, b, r in zip(img_xy, map_xy, res)]
    counts = {**km.counts, "gcps": int(fit.used.sum()), "gcps_sharp": 0,
              "verified_pairs": 0}
    warnings: List[str] = []
    fb.info(f"Keypoint stage: {counts['patches_agreeing']} of {counts['patches']} patches "
            f"agree, {counts['gcps']} control points, RMSE {fit.rmse_px:.2f} px "
            f"({fit.rmse_map:.2f} m).")
    return GeorefResult(
        fit=fit, inverse_fit=inverse_for_resampling(fit, img_xy, map_xy), gcps=gcps, crs=crs,
        global_transform=to_map @ km.initial, joint=to_map @ km.transform,
        search=to_map @ km.initial, counts=counts, reference=ref_info,
        reference_kind="raster", image_info=image_info, grey=grey, warnings=warnings,
        seconds=time.perf_counter() - t0, stage="keypoints", parameters=parameters or {})
