"""Area-based global search: the fallback when no image region matches a polygon as an object.

The object stage needs image regions that *are* the reference objects (IoU ≳ 0.9). Where the
objects are not homogeneous in the image (glaciers: dark debris-covered tongues, seasonal snow
beyond the outlines) no region matches, yet the scene as a whole still agrees with the map.
This stage compares the image with the polygons rendered as a raster, still without
approximate values:

1. **Features** on both sides: the gradient magnitude of the Gaussian-smoothed image and of
   the filled polygon mask (both then respond at the outlines; brightness levels and
   contrast do not matter).
2. **Rotation and scale** by Fourier–Mellin: magnitude spectra (radial window, log
   magnitude, middle frequencies) are translation-invariant; in log-polar coordinates a
   rotation and a scale become a shift, found by phase correlation. Several peaks, each with
   its 180° twin, for the image and for its mirror image, are candidates.
3. **Translation** of each candidate by masked normalised cross-correlation (FFT) with the
   polygons rendered in the image frame; its peak also ranks the candidates.
4. **Refinement**: ECC (``cv2.findTransformECC``, affine) of the image feature against the
   polygons rendered in the image geometry, coarse to fine, re-rendering after each step.

When ECC does not confirm the result (the glacier mask of the Everest scene: its outline
does not pin the image), a second search uses the *individual* polygons' outlines — the
boundaries between touching polygons follow ridges and illumination edges in the image:

5. **Boundary-orientation search** (:func:`orientation_search`): for every rotation (both
   handednesses) and scale of a grid, the image's doubled-angle gradient field, averaged
   into the cells of a raster over the reference, is correlated (FFT, all shifts) with the
   outlines' doubled-angle normals; placements rank by the cosine over its chance level.
6. **Refinement** (:func:`refine_orientation`): the best placements are refined (affine,
   Powell) to maximise the agreement of image gradients with the outline normals along the
   outlines, coarse to fine; the chosen one must score high and stand clearly ahead of the
   best other placement (:func:`boundary_search`).

The result is an image → map affine; control points are a grid of image points mapped
through it (:func:`grid_control_points`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Sequence, Tuple

import cv2
import numpy as np
from numpy.typing import NDArray
from rasterio.features import rasterize
from scipy import fft as sfft
from scipy import ndimage, optimize
from scipy.signal import fftconvolve
from shapely.geometry import Polygon

from .correspondence import apply
from .refinement import ControlPoint

#: Cells along the longer side of the reference extent in the search raster.
SEARCH_CELLS = 512
#: Rotation/scale peaks tried per handedness (each also with its 180° twin).
PEAKS = 5


Array = NDArray[np.float64]


@dataclass
class AreaResult:
    """The area-based estimate and how it was found."""

    transform: Array  # 3 × 3 image (col, row; centres at integers) → map
    ncc: float  # masked NCC of the best candidate at the search resolution
    ecc: float  # ECC correlation after the refinement (full resolution)
    mirrored: bool
    candidates: List[Dict[str, float]] = field(default_factory=list)


def translation(dx: float, dy: float) -> Array:
    """3 × 3 translation matrix."""
    return np.array([[1.0, 0.0, dx], [0.0, 1.0, dy], [0.0, 0.0, 1.0]])


def similarity(angle: float, scale: float) -> Array:
    """3 × 3 rotation by ``angle`` (radians) times ``scale`` about the origin."""
    c, s = math.cos(angle) * scale, math.sin(angle) * scale
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def render_mask(rings: Sequence[Array], to_pixel: Array, shape: Tuple[int, int]) -> Array:
    """Fill polygons (outer rings, map coordinates) into a raster.

    Parameters
    ----------
    rings : sequence of (n, 2) arrays
        Map coordinates.
    to_pixel : (3, 3) array
        Map → raster (col, row) with pixel centres at integers (any affine, also mirrored).
    shape : (rows, cols)

    Returns
    -------
    ndarray of float64
        1 inside a polygon, 0 outside.
    """
    geoms = []
    for r in rings:
        p = Polygon(apply(to_pixel, r) + 0.5)  # rasterio: pixel corners at integers
        if not p.is_valid:
            p = p.buffer(0)
        if not p.is_empty:
            geoms.append((p, 1))
    if not geoms:
        return np.zeros(shape)
    return rasterize(geoms, out_shape=shape, fill=0, dtype="uint8").astype(np.float64)


def edge_feature(a: Array, sigma: float, valid: Optional[NDArray[np.bool_]] = None) -> Array:
    """Gradient magnitude of ``a`` smoothed by a Gaussian of ``sigma`` px.

    Invalid pixels (no data) are filled by normalised convolution first, and the feature is
    zero within ~2σ of them, so the no-data border makes no edge. Gradients rather than
    grey values: the polygons' objects may be brighter or darker than their surroundings.
    """
    a = np.asarray(a, float)
    if valid is None:
        valid = np.isfinite(a)
    num = ndimage.gaussian_filter(np.where(valid, a, 0.0), sigma)
    den = ndimage.gaussian_filter(valid.astype(float), sigma)
    g = np.where(den > 1e-6, num / np.maximum(den, 1e-6), 0.0)
    # Gaussian derivatives: nearly isotropic (central differences favour the pixel axes,
    # which would show in both spectra as a false match at 0° / 90°, scale 1)
    out = ndimage.gaussian_gradient_magnitude(g, 1.0)
    return np.where(_core(valid, sigma), out, 0.0)


def _core(valid: NDArray[np.bool_], sigma: float) -> NDArray[np.bool_]:
    if valid.all():
        return valid
    return ndimage.binary_erosion(valid, iterations=max(1, math.ceil(2 * sigma)) + 1)


def _window(shape: Tuple[int, int]) -> Array:
    # radial Hann on the inscribed disc: a rectangular window's cross-shaped spectrum would
    # turn with the image and pull the rotation towards 0° and 90°
    h, w = shape
    r = np.hypot(*np.meshgrid((np.arange(w) - (w - 1) / 2) / (w / 2),
                              (np.arange(h) - (h - 1) / 2) / (h / 2)))
    return np.where(r < 1.0, 0.5 * (1.0 + np.cos(np.pi * np.minimum(r, 1.0))), 0.0)


def log_polar_spectrum(a: Array, n: int, angles: int = 720, radii: int = 512) -> Array:
    """Log-polar resampled log-magnitude spectrum of ``a`` (zero-padded to n × n).

    Rows are angles over 0–360° (the spectrum is point-symmetric, so half would do; the full
    circle keeps the phase correlation periodic), columns log radius from 1 to n/2.
    """
    pad = np.zeros((n, n))
    h, w = a.shape
    pad[:h, :w] = (a - a.mean()) * _window(a.shape)
    mag = np.log1p(np.abs(np.fft.fftshift(np.fft.fft2(pad))))
    lp = cv2.warpPolar(mag.astype(np.float32), (radii, angles), (n / 2.0, n / 2.0), n / 2.0,
                       cv2.WARP_POLAR_LOG | cv2.INTER_LINEAR).astype(np.float64)
    # the mean over angles (the spectrum's radial fall-off, the window's spectrum) is the
    # same for any rotation and would pull the correlation to 0° / scale 1: remove it
    lp -= lp.mean(axis=0, keepdims=True)
    # keep the middle frequencies: the lowest carry the window and the extent, the highest
    # the pixel grid (square-symmetric, the same in both rasters) and noise
    r = np.exp(np.arange(radii) * math.log(n / 2.0) / radii)
    lp[:, (r < n / 128) | (r > n / 8)] = 0.0
    return lp


def correlation_peaks(a: Array, b: Array, count: int, window_cols: bool = True,
                      exclude: int = 4) -> List[Tuple[float, float, float]]:
    """Half-whitened phase correlation of equally sized arrays: the strongest peaks (drow,
    dcol, height).

    ``b`` shifted by (drow, dcol) matches ``a``; shifts are signed (wrapped to ± half the size)
    and refined to sub-pixel by a parabola through the neighbours.
    """
    if window_cols:  # the radius axis is not periodic
        wc = np.hanning(a.shape[1])[None, :]
        a, b = a * wc, b * wc
    A = np.fft.fft2(a - a.mean())
    B = np.fft.fft2(b - b.mean())
    R = A * np.conj(B)
    # half-whitened (|R|^½): the pure phase correlation (|R|^1) weights every frequency alike,
    # noise-level ones included, and its true peak on log-polar spectra came out at the noise
    # floor — found or missed with round-off differences between OpenCV builds
    R /= np.sqrt(np.abs(R)) + 1e-12
    c = np.real(np.fft.ifft2(R))
    out = []
    work = c.copy()
    rows, cols = c.shape
    for _ in range(count):
        i, j = np.unravel_index(int(np.argmax(work)), c.shape)
        h = float(c[i, j])
        di = _parabola(c[(i - 1) % rows, j], h, c[(i + 1) % rows, j])
        dj = _parabola(c[i, (j - 1) % cols], h, c[i, (j + 1) % cols])
        si = (i + di + rows / 2) % rows - rows / 2
        sj = (j + dj + cols / 2) % cols - cols / 2
        out.append((si, sj, h))
        ii = np.arange(i - exclude, i + exclude + 1) % rows
        jj = np.arange(j - exclude, j + exclude + 1) % cols
        work[np.ix_(ii, jj)] = -np.inf
    return out


def _parabola(lo: float, mid: float, hi: float) -> float:
    d = lo - 2 * mid + hi
    return 0.0 if d >= 0 else float(0.5 * (lo - hi) / d)


def rotation_scale_candidates(img: Array, ref: Array, n: int, count: int = PEAKS
                              ) -> List[Tuple[float, float, float]]:
    """Rotation (radians) and scale of similarity maps ref cell → image pixel, best first.

    Returns (angle, scale, peak) with ``img(x) ≈ ref(S⁻¹ x)`` for ``S = similarity(angle,
    scale)`` about some point; the angle is ambiguous by 180° (both are to be tried).
    """
    angles, radii = 720, 512
    li = log_polar_spectrum(img, n, angles, radii)
    lr = log_polar_spectrum(ref, n, angles, radii)
    base = math.log(n / 2.0) / radii  # log-radius per column (cv2.warpPolar, log mode)
    out = []
    for drow, dcol, h in correlation_peaks(li, lr, count):
        angle = 2 * math.pi * drow / angles
        scale = math.exp(-dcol * base)  # the image's spectrum is the reference's shrunk by 1/s
        out.append((angle, scale, h))
    return out


def masked_ncc(ref: Array, tmpl: Array, mask: NDArray[np.bool_]) -> Tuple[Array, int, int]:
    """Normalised cross-correlation of a masked template at every shift over ``ref`` (FFT).

    Shifts reach beyond ``ref`` by the template size (``ref`` counts as zero there: no
    polygons). Shifts with no ``ref`` structure under the template get −1.

    Returns
    -------
    ncc : ndarray, shape (H + h − 1, W + w − 1)
        ``ncc[i, j]``: template origin at ref (row, col) = (i − h + 1, j − w + 1).
    h, w : int
        Template size.
    """
    m = mask.astype(float)
    n = m.sum()
    t = np.where(mask, tmpl - tmpl[mask].mean(), 0.0)
    tt = float(np.sum(t * t))
    flip = (slice(None, None, -1), slice(None, None, -1))
    num = fftconvolve(ref, t[flip], mode="full")
    s1 = fftconvolve(ref, m[flip], mode="full")
    s2 = fftconvolve(ref * ref, m[flip], mode="full")
    var = np.maximum(s2 - s1 * s1 / n, 0.0)
    floor = 1e-6 * n * float(ref.var())  # FFT round-off where ref is empty
    ncc = np.where(var > floor, num / np.sqrt(np.maximum(var, 1e-12) * max(tt, 1e-12)), -1.0)
    h, w = tmpl.shape
    return ncc, h, w


def search_grid(rings: Sequence[Array], cells: int = SEARCH_CELLS) -> Tuple[Array, Tuple[int, int]]:
    """Map → cell matrix and shape of a raster over the reference extent.

    The cell is chosen so the longer side of the extent has ``cells`` cells (the scale is
    recovered anyway; this only fixes the working resolution). Rows run north to south.
    """
    pts = np.vstack(rings)
    x0, y0 = pts.min(axis=0)
    x1, y1 = pts.max(axis=0)
    c = max(x1 - x0, y1 - y0) / cells
    shape = (math.ceil((y1 - y0) / c) + 1, math.ceil((x1 - x0) / c) + 1)
    to_cell = np.array([[1 / c, 0.0, -x0 / c - 0.5], [0.0, -1 / c, y1 / c - 0.5],
                        [0.0, 0.0, 1.0]])
    return to_cell, shape


def downsample(grey: Array, factor: float) -> Tuple[Array, NDArray[np.bool_], Array]:
    """Image reduced by ``factor`` (area mean), its valid mask and the level-0 → level matrix."""
    valid = np.isfinite(grey)
    h, w = grey.shape
    size = (max(8, round(w / factor)), max(8, round(h / factor)))
    num = cv2.resize(np.where(valid, grey, 0.0), size, interpolation=cv2.INTER_AREA)
    den = cv2.resize(valid.astype(np.float64), size, interpolation=cv2.INTER_AREA)
    small = np.where(den > 0.99, num / np.maximum(den, 1e-9), np.nan)
    fx, fy = size[0] / w, size[1] / h
    # pixel centres at integers: u_level = (u0 + 0.5)·f − 0.5
    L = np.array([[fx, 0.0, 0.5 * fx - 0.5], [0.0, fy, 0.5 * fy - 0.5], [0.0, 0.0, 1.0]])
    return small, np.isfinite(small), L


def score_candidate(feat: Array, valid: NDArray[np.bool_], rings: Sequence[Array],
                    to_cell: Array, A: Array, sigma: float) -> Tuple[Array, float]:
    """Translation and score of a rotation/scale candidate, compared in the image frame.

    The polygons are rendered through ``A`` (ref cell → image pixel, no translation) onto a
    canvas that holds all of them, made into a ``feature`` like the image, and the image
    feature is slid over it
    (masked NCC). Comparing in the image frame keeps the sample (the image's valid pixels)
    the same for every candidate, so the scores of different scales are comparable.

    Returns
    -------
    S : (3, 3) array
        Ref cell → image pixel, with the translation.
    ncc : float
    """
    pts = apply(A @ to_cell, np.vstack(rings))
    o = np.floor(pts.min(axis=0)) - 3 * sigma
    size = np.ceil(pts.max(axis=0) - o + 3 * sigma).astype(int) + 1
    canvas = render_mask(rings, translation(*(-o)) @ A @ to_cell, (int(size[1]), int(size[0])))
    canvas = edge_feature(canvas, sigma, np.ones(canvas.shape, bool))
    ncc, h, w = masked_ncc(canvas, feat, valid)
    i, j = np.unravel_index(int(np.argmax(ncc)), ncc.shape)
    best = float(ncc[i, j])
    di = _parabola(ncc[i - 1, j], best, ncc[i + 1, j]) if 0 < i < ncc.shape[0] - 1 else 0.0
    dj = _parabola(ncc[i, j - 1], best, ncc[i, j + 1]) if 0 < j < ncc.shape[1] - 1 else 0.0
    origin = np.array([j + dj - w + 1, i + di - h + 1])  # image (0, 0) on the canvas
    return translation(*(-origin)) @ translation(*(-o)) @ A, best


def refine_ecc(grey: Array, rings: Sequence[Array], T: Array, sigma: float = 1.5,
               cells: int = SEARCH_CELLS, rounds: int = 2,
               deadline: float = math.inf) -> Tuple[Array, float]:
    """Affine refinement of image → map ``T`` by ECC, coarse (≈ ``cells`` px) to full size.

    The polygons are rendered in the image geometry of the current ``T`` each round (no
    interpolation of a rendered raster), and ``cv2.findTransformECC`` aligns the image
    feature to them.

    Returns
    -------
    T : (3, 3) array
        Refined level-0 image pixel → map.
    cc : float
        ECC correlation coefficient of the last (full-size) round; 0 when ECC failed or
        ``deadline`` (``time.perf_counter()`` time) passed before the last round.
    """
    # a coarse level first widens ECC's capture range for the search's ~1° / 2 % steps
    factors = sorted({max(1.0, max(grey.shape) / c) for c in (cells // 4, cells)} | {1.0},
                     reverse=True)
    crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-6)
    cc = 0.0
    for factor in factors:
        small, valid, L = downsample(grey, factor)
        feat = edge_feature(small, sigma, valid).astype(np.float32)
        core = _core(valid, sigma).astype(np.uint8)  # the feature's own no-data margin
        for _ in range(rounds):
            if time.perf_counter() >= deadline:  # out of time: no confirmed result
                return T, 0.0
            to_pixel = L @ np.linalg.inv(T)
            ref = edge_feature(render_mask(rings, to_pixel, small.shape), sigma,
                               np.ones(small.shape, bool)).astype(np.float32)
            W = np.eye(2, 3, dtype=np.float32)
            try:
                cc, W = cv2.findTransformECC(ref, feat, W, cv2.MOTION_AFFINE, crit, core, 1)
            except cv2.error:
                return T, 0.0
            W3 = np.vstack([W.astype(np.float64), [0.0, 0.0, 1.0]])
            # feat(W x) ≈ ref(x): the image's true level → map is T_level · W⁻¹
            T = T @ np.linalg.inv(L) @ np.linalg.inv(W3) @ L
    return T, float(cc)


def area_search(grey: Array, rings: Sequence[Array], sigma: float = 1.5,
                cells: int = SEARCH_CELLS, peaks: int = PEAKS,
                deadline: float = math.inf) -> AreaResult:
    """Image → map affine from the image and the reference polygons alone.

    Parameters
    ----------
    grey : (rows, cols) array
        Image grey values, NaN = no data.
    rings : sequence of (n, 2) arrays
        Outer rings of the reference polygons, map coordinates (projected CRS).
    sigma : float
        Smoothing of the features (px of the working resolution).
    cells : int
        Working resolution: cells along the longer side of the reference extent and of the
        image for the global search.
    peaks : int
        Fourier–Mellin peaks tried per handedness (each with its 180° twin).
    deadline : float
        ``time.perf_counter()`` time after which no further candidate is scored nor refined
        (the result then has correlation 0).

    Returns
    -------
    AreaResult
    """
    to_cell, shape = search_grid(rings, cells)
    ref = edge_feature(render_mask(rings, to_cell, shape), sigma, np.ones(shape, bool))
    small, valid, L = downsample(grey, max(1.0, max(grey.shape) / cells))
    feat = edge_feature(small, sigma, valid)
    n = 1 << math.ceil(math.log2(max(max(shape), max(small.shape))))
    w = small.shape[1]
    flip = np.array([[-1.0, 0.0, w - 1.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    best: Optional[Tuple[float, Array, bool]] = None
    cands: List[Dict[str, float]] = []
    for mirrored in (False, True):
        f = feat[:, ::-1] if mirrored else feat
        v = valid[:, ::-1] if mirrored else valid
        for angle, scale, peak in rotation_scale_candidates(f, ref, n, peaks):
            for a in (angle, angle + math.pi):
                if time.perf_counter() >= deadline:
                    break
                S, ncc = score_candidate(f, v, rings, to_cell, similarity(a, scale), sigma)
                cands.append({"angle_deg": round(math.degrees(a) % 360, 3),
                              "scale": round(scale, 5), "mirrored": mirrored,
                              "peak": round(peak, 5), "ncc": round(ncc, 4)})
                if best is None or ncc > best[0]:
                    F = flip if mirrored else np.eye(3)
                    best = (ncc, np.linalg.inv(to_cell) @ np.linalg.inv(S) @ F @ L, mirrored)
    if best is None or time.perf_counter() >= deadline:  # out of time: no result
        return AreaResult(np.eye(3) if best is None else best[1], 0.0, 0.0, False, cands)
    T, cc = refine_ecc(grey, rings, best[1], sigma, cells, deadline=deadline)
    return AreaResult(T, best[0], cc, best[2], cands)


def grid_control_points(T: Array, valid: NDArray[np.bool_], count: int = 10
                        ) -> List[ControlPoint]:
    """Control points of the area-based result: a ``count`` × ``count`` grid of valid image
    pixels mapped through ``T`` (marked ``pair = -1``: no object pair behind them)."""
    rows, cols = valid.shape
    out = []
    for r in np.linspace(0, rows - 1, count):
        for c in np.linspace(0, cols - 1, count):
            if valid[round(r), round(c)]:
                m = apply(T, np.array([[c, r]]))[0]
                out.append(ControlPoint(image=(float(c), float(r)), map=(float(m[0]),
                                        float(m[1])), residual=0.0, pair=-1, sharp=False))
    return out


# --- boundary orientation: the individual polygons' outlines against image edge directions ---
#
# Where the polygons tile the terrain (glaciers meeting at ice divides, parcels, stands), the
# boundaries *between* adjacent polygons follow visible edges — ridges, illumination changes —
# that the dissolved mask does not contain. The cue is the direction of those edges, not
# brightness or edge strength: the image gradient at a boundary is parallel to the boundary's
# normal whether the polygon is brighter or darker. Directions are compared as doubled angles
# (e^{2iφ}: polarity-free), so the score of a placement is a complex correlation (FFT) of the
# rendered boundary normals with the image's doubled-angle gradient field.

#: Cells along the longer side of the reference extent for the boundary-orientation search.
ORIENT_CELLS = 128
#: Image diagonal over the reference extent's diagonal: the scales searched (the image must
#: show a good part of the reference area; no other assumption on the scale).
EXTENT_RATIO = (0.3, 1.0)
#: Rotation and log-scale step × the image's half-diagonal (cells): the image corners move by
#: at most about half this many cells between neighbouring candidates.
ORIENT_STEP = 3.0
#: Fewest image half-diagonal cells (coarser candidates are not searched).
MIN_RADIUS_CELLS = 12.0


def boundary_samples(rings: Sequence[Array], spacing: float
                     ) -> Tuple[Array, Array, Array]:
    """Points along polygon outlines every ~``spacing`` map units.

    Returns
    -------
    points : (n, 2) array
        Segment midpoints of the subdivided outlines.
    angles : (n,) array
        Direction of the outline at each point (radians, map frame).
    weights : (n,) array
        Outline length each point stands for.
    """
    pts, ang, wts = [], [], []
    for r in rings:
        r = np.asarray(r, float)[:, :2]
        d = np.diff(r, axis=0)
        L = np.hypot(d[:, 0], d[:, 1])
        ok = L > 0
        if not ok.any():
            continue
        r0, d, L = r[:-1][ok], d[ok], L[ok]
        n = np.maximum(1, np.ceil(L / spacing)).astype(int)
        seg = np.repeat(np.arange(len(d)), n)
        k = np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)
        t = (k + 0.5) / n[seg]
        pts.append(r0[seg] + t[:, None] * d[seg])
        ang.append(np.arctan2(d[seg, 1], d[seg, 0]))
        wts.append((L / n)[seg])
    if not pts:
        return np.zeros((0, 2)), np.zeros(0), np.zeros(0)
    return np.vstack(pts), np.concatenate(ang), np.concatenate(wts)


def _directions(T: Array, pts: Array, angles: Array) -> Array:
    """Angles of directions ``angles`` at ``pts`` after the affine part of ``T``."""
    d = np.c_[np.cos(angles), np.sin(angles)] @ T[:2, :2].T
    return np.arctan2(d[:, 1], d[:, 0])


def boundary_orientation_raster(rings: Sequence[Array], to_cell: Array, shape: Tuple[int, int],
                                sigma: float = 0.7) -> NDArray[np.complex128]:
    """Doubled-angle normals of the outlines rendered in a raster (complex, weighted by length).

    Each outline point adds (length) · e^{2iψ}, ψ the outline's normal in the raster frame,
    bilinearly into the four nearest cells; the raster is then Gaussian-smoothed (``sigma``
    cells), which tolerates the search's steps. Opposite normals give the same value.
    """
    c = abs(np.linalg.det(to_cell[:2, :2])) ** -0.5  # map units per cell
    pts, ang, wts = boundary_samples(rings, c / 4)
    out = np.zeros(shape, complex)
    if not len(pts):
        return out
    q = apply(to_cell, pts)
    psi = _directions(to_cell, pts, ang) + math.pi / 2
    val = wts / c * np.exp(2j * psi)
    j0, i0 = np.floor(q[:, 0]).astype(int), np.floor(q[:, 1]).astype(int)
    fx, fy = q[:, 0] - j0, q[:, 1] - i0
    for di, dj, w in ((0, 0, (1 - fy) * (1 - fx)), (0, 1, (1 - fy) * fx), (1, 0, fy * (1 - fx)),
                      (1, 1, fy * fx)):
        ii, jj = i0 + di, j0 + dj
        ok = (ii >= 0) & (ii < shape[0]) & (jj >= 0) & (jj < shape[1])
        np.add.at(out, (ii[ok], jj[ok]), w[ok] * val[ok])
    if sigma > 0:
        out = ndimage.gaussian_filter(out.real, sigma) + 1j * ndimage.gaussian_filter(out.imag,
                                                                                      sigma)
    return out


def gradient_orientation(a: Array, valid: Optional[NDArray[np.bool_]] = None,
                         sigma: float = 0.0) -> NDArray[np.complex128]:
    """Doubled-angle gradient field |g| e^{2iφ} of ``a`` (φ the gradient direction, x = column,
    y = row), after an optional Gaussian of ``sigma`` px; zero within two pixels of no data."""
    a = np.asarray(a, float)
    if valid is None:
        valid = np.isfinite(a)
    fill = float(np.mean(a[valid])) if valid.any() else 0.0
    g = np.where(valid, a, fill)
    if sigma > 0:
        g = ndimage.gaussian_filter(g, sigma)
    gy, gx = np.gradient(g)
    z = (gx + 1j * gy) ** 2 / (np.hypot(gx, gy) + 1e-12)
    core = valid if valid.all() else ndimage.binary_erosion(valid, iterations=2)
    return np.where(core, z, 0.0)


def orientation_score(z: NDArray[np.complex128], T: Array, pts: Array, angles: Array,
                      weights: Array) -> float:
    """Weighted mean of cos 2Δ over the outline points inside the image.

    Δ is the angle between the image gradient (``z`` from :func:`gradient_orientation`,
    interpolated bilinearly) and the outline normal mapped into the image by ``T⁻¹`` (``T``:
    image pixel → map); the weights are outline length × gradient magnitude. 1: every edge
    runs along the outlines; 0: no relation.
    """
    Ti = np.linalg.inv(T)
    q = apply(Ti, pts)
    rows, cols = z.shape
    ok = (q[:, 0] >= 0) & (q[:, 0] <= cols - 1) & (q[:, 1] >= 0) & (q[:, 1] <= rows - 1)
    if not ok.any():
        return 0.0
    coords = [q[ok, 1], q[ok, 0]]
    zr = ndimage.map_coordinates(z.real, coords, order=1)
    zi = ndimage.map_coordinates(z.imag, coords, order=1)
    psi = _directions(Ti, pts[ok], angles[ok]) + math.pi / 2
    w = weights[ok]
    den = float(np.sum(np.hypot(zr, zi) * w))  # Σ w·|g|
    num = float(np.sum((zr * np.cos(2 * psi) + zi * np.sin(2 * psi)) * w))  # Σ w·|g|·cos 2Δ
    return num / den if den > 0 else 0.0


@dataclass
class OrientationCandidate:
    """A placement of the image in the reference cell raster and its score."""

    transform: Array  # 3 × 3 image pixel → map
    score: float  # cosine of the doubled-angle fields at the search resolution
    angle_deg: float
    scale: float  # cells per image pixel
    mirrored: bool
    cells: float = 0.0  # image cells that carry a gradient (the sample of the cosine)

    @property
    def z(self) -> float:
        """The cosine in units of its chance level, ≈ 1/√cells: placements of a small image
        (few cells) reach high cosines by chance, so placements rank by ``score · √cells``."""
        return self.score * math.sqrt(self.cells)


def orientation_search(grey: Array, boundaries: Sequence[Array], cells: int = ORIENT_CELLS,
                       extent_ratio: Tuple[float, float] = EXTENT_RATIO,
                       step: float = ORIENT_STEP, keep: int = 5, smooth: float = 1.0,
                       deadline: float = math.inf) -> List[OrientationCandidate]:
    """Brute-force similarity search of the image against the outlines' directions.

    Every rotation (both handednesses) and scale on a grid whose steps move the image corners
    by about ``step``/2 cells; for each, the image's doubled-angle gradient field (computed
    at full resolution, σ = 1 px, then averaged over half a cell and warped into the
    reference cell raster, its angles turned with the image) is correlated (FFT, all shifts)
    with the rendered outline normals (:func:`boundary_orientation_raster`), normalised as a
    cosine (the outline energy under the image and the image's field energy). Averaging the
    fine field keeps the direction of sharp ridges that a gradient of the coarse image loses
    (Everest at 315 m cells: the truth ranked 602nd and worse for two small-scale cases with
    coarse gradients, first with the averaged field). Placements rank by the cosine times
    √(cells of the image): a small image reaches high cosines by chance. Shifts where the
    image covers less than a quarter of the best-covered shift's outline energy are not
    scored (a few chance outlines at the reference's edge would be noise).

    Parameters
    ----------
    grey : (rows, cols) array
        Image, NaN = no data.
    boundaries : sequence of (n, 2) arrays
        Outlines of the individual (not dissolved) polygons, map coordinates.
    extent_ratio : (low, high)
        Scales searched: the image's diagonal is ``low``–``high`` times the reference
        extent's diagonal.
    deadline : float
        ``time.perf_counter()`` time after which no further rotation/scale is tried (the
        placements found so far are returned).

    Returns
    -------
    list of OrientationCandidate
        The best ``keep`` placements, best first, at least ~3 cells apart or at different
        rotations/scales.
    """
    if not len(boundaries):
        return []
    to_cell, shape = search_grid(boundaries, cells)
    pad = 4
    to_cell = translation(pad, pad) @ to_cell
    shape = (shape[0] + 2 * pad, shape[1] + 2 * pad)
    normals = boundary_orientation_raster(boundaries, to_cell, shape, smooth)
    rows, cols = grey.shape
    valid0 = np.isfinite(grey)
    z0 = gradient_orientation(grey, valid0, 1.0)
    half_img = 0.5 * math.hypot(rows, cols)
    half_ref = 0.5 * math.hypot(*shape)
    q_lo = max(extent_ratio[0] * half_ref, MIN_RADIUS_CELLS) / half_img
    q_hi = extent_ratio[1] * half_ref / half_img
    big = math.ceil(2 * q_hi * half_img) + 4
    FS = (sfft.next_fast_len(shape[0] + big), sfft.next_fast_len(shape[1] + big))
    FO = sfft.fft2(normals.astype(np.complex64), FS)
    FE = sfft.rfft2(np.abs(normals).astype(np.float32) ** 2, FS)
    corners = np.array([[0.0, 0.0], [cols - 1.0, 0.0], [cols - 1.0, rows - 1.0],
                        [0.0, rows - 1.0]])
    found: List[OrientationCandidate] = []
    q = q_lo
    while (q <= q_hi * (1 + 1e-9) or not found) and time.perf_counter() < deadline:
        r = q * half_img
        # the fine field averaged over a cell (Gaussian of half a cell before the warp)
        zf = [(ndimage.gaussian_filter(p, 0.5 / q) if q < 1 else p).astype(np.float32)
              for p in (z0.real, z0.imag)]
        n_rot = max(8, math.ceil(2 * math.pi * r / step))
        for mirrored in (False, True):
            F = np.diag([-1.0, 1.0, 1.0]) if mirrored else np.eye(3)
            for k in range(n_rot):
                if time.perf_counter() >= deadline:  # out of time: the placements so far
                    break
                a = 2 * math.pi * k / n_rot
                A = similarity(a, q) @ F
                c = apply(A, corners)
                o = -c.min(axis=0) + 2
                size = np.ceil(c.max(axis=0) - c.min(axis=0) + 4).astype(int)
                M = (translation(*o) @ A)[:2].astype(np.float32)
                dsize = (int(size[0]), int(size[1]))
                vm = cv2.warpAffine(valid0.astype(np.float32), M, dsize,
                                    flags=cv2.INTER_LINEAR) > 0.999
                wr, wi = (cv2.warpAffine(p, M, dsize, flags=cv2.INTER_LINEAR) for p in zf)
                # the field turns with the image: mirrored φ → π − φ, rotated φ → φ + a
                z = (wr - 1j * wi if mirrored else wr + 1j * wi) * np.exp(2j * a)
                z = np.where(cv2.erode(vm.astype(np.uint8), np.ones((3, 3), np.uint8)) > 0,
                             z, 0).astype(np.complex64)
                zz = float(np.sum(np.abs(z) ** 2))
                if zz <= 0:
                    continue
                core = (z != 0).astype(np.float32)
                num = sfft.ifft2(FO * np.conj(sfft.fft2(z, FS))).real
                energy = sfft.irfft2(FE * np.conj(sfft.rfft2(core, FS)), FS)
                floor = 0.25 * float(energy.max())
                if floor <= 0:
                    continue
                score = np.where(energy > floor, num / np.sqrt(np.maximum(energy, floor) * zz),
                                 -1.0)
                i, j = np.unravel_index(int(np.argmax(score)), score.shape)
                di = i if i < FS[0] // 2 else i - FS[0]
                dj = j if j < FS[1] // 2 else j - FS[1]
                S = translation(dj, di) @ translation(*o) @ A  # image pixel → cell
                found.append(OrientationCandidate(np.linalg.inv(to_cell) @ S,
                                                  float(score[i, j]), math.degrees(a), q,
                                                  mirrored, float(core.sum())))
        q *= 1 + step / r
    found.sort(key=lambda c: -c.z)
    out: List[OrientationCandidate] = []
    centre = np.array([[(cols - 1) / 2, (rows - 1) / 2]])
    cell = abs(np.linalg.det(to_cell[:2, :2])) ** -0.5
    for cand in found:
        p = apply(cand.transform, centre)[0]
        if any(np.hypot(*(apply(o.transform, centre)[0] - p)) < 3 * cell
               and o.mirrored == cand.mirrored for o in out):
            continue
        out.append(cand)
        if len(out) >= keep:
            break
    return out


def refine_orientation(grey: Array, boundaries: Sequence[Array], T: Array,
                       sigmas: Sequence[float] = (8.0, 4.0, 2.0, 1.0), spacing: float = 1.0,
                       model: str = "affine",
                       fields: Optional[Dict[float, NDArray[np.complex128]]] = None
                       ) -> Tuple[Array, float]:
    """Affine (or similarity, ``model``) refinement of image → map ``T`` along the outlines'
    directions: maximises :func:`orientation_score` (the aligned edge *strength* instead was
    closer on clean synthetic edges but farther on Everest; docs/decisions.md). Coarse to
    fine (Gaussian ``sigmas`` in image pixels); the parameters are the displacements (pixels)
    of three image corners (similarity: shift, rotation and scale as displacements),
    optimised by Powell's method (to 0.01 px at σ ≤ 2 px, 0.1 px above). The outline points
    are ``spacing`` image pixels apart. ``fields`` caches :func:`gradient_orientation` per σ
    across calls on the same image.

    Returns
    -------
    T : (3, 3) array
    score : float
        :func:`orientation_score` at the finest level.
    """
    rows, cols = grey.shape
    px = math.sqrt(abs(np.linalg.det(T[:2, :2])))
    pts, ang, wts = boundary_samples(boundaries, px * spacing)
    ctrl = np.array([[0.0, 0.0], [cols - 1.0, 0.0], [0.0, rows - 1.0]])
    Ac = np.c_[ctrl, np.ones(3)]
    fields = {} if fields is None else fields

    def moves(x: Array) -> Array:
        return (_corner_moves(Ac, ctrl, x) if model == "affine" else
                _similarity_moves(x, cols, rows))

    for sg in sigmas:
        if sg not in fields:
            fields[sg] = gradient_orientation(grey, np.isfinite(grey), sg)
        z = fields[sg]

        def cost(x: Array, z: Array = z, T: Array = T) -> float:
            return -orientation_score(z, T @ np.linalg.inv(moves(x)), pts, ang, wts)

        r = optimize.minimize(cost, np.zeros(6 if model == "affine" else 4), method="Powell",
                              options={"xtol": 0.01 if sg <= 2 else 0.1, "ftol": 1e-7})
        T = T @ np.linalg.inv(moves(r.x))
    return T, orientation_score(z, T, pts, ang, wts)


def _similarity_moves(x: Array, cols: int, rows: int) -> Array:
    """Shift (x[0], x[1]) px, rotation and scale about the image centre, the latter two as
    the displacement (px) they cause at the image's half-diagonal."""
    rad = 0.5 * math.hypot(cols, rows)
    c = np.array([(cols - 1) / 2, (rows - 1) / 2])
    S = similarity(x[2] / rad, 1.0 + x[3] / rad)
    S[:2, 2] = c - S[:2, :2] @ c + x[:2]
    return S


def _corner_moves(Ac: Array, ctrl: Array, x: Array) -> Array:
    """The affine that moves the three image points ``ctrl`` by ``x`` (pixels, flattened)."""
    M = np.linalg.solve(Ac, ctrl + x.reshape(3, 2)).T
    return np.vstack([M, [0.0, 0.0, 1.0]])


#: Search placements refined at the coarse levels before the best is refined to full size.
SCREEN = 6
#: Orientation score an affine refinement must add to a similarity's to be kept (Everest,
#: a similarity scene: the affine adds 0.000–0.004 and moves the corners 0.5–1 px).
AFFINE_GAIN = 0.01


@dataclass
class BoundaryResult:
    """The boundary-orientation estimate and how it was found."""

    transform: Array  # 3 × 3 image (col, row; centres at integers) → map
    score: float  # orientation score after the full refinement (σ = 1 px)
    screen: float  # its score after the coarse refinement (σ = 4 px)
    runner_up: float  # best coarse-refined score of a placement elsewhere (> 3 cells away)
    search_score: float  # cosine of the chosen placement at the search resolution
    mirrored: bool
    candidates: List[Dict[str, float]] = field(default_factory=list)

    @property
    def gap(self) -> float:
        """How far the chosen placement stands out: screen − runner-up."""
        return self.screen - self.runner_up


def boundary_search(grey: Array, boundaries: Sequence[Array], cells: int = ORIENT_CELLS,
                    screen: int = SCREEN, deadline: float = math.inf) -> BoundaryResult:
    """Image → map affine from the image's edge directions and the individual outlines.

    :func:`orientation_search` proposes the ``screen`` best placements; each is refined at
    the coarse levels (similarity, σ = 8 and 4 px, outline points every 2 px) — at the search
    resolution the right placement is often only just ahead or behind, refined it stands
    out — and the best is refined to σ = 1 px (similarity; then affine, kept if it raises
    the score by ``AFFINE_GAIN``); placements that ended within three search cells of it
    (at an image corner) are refined too, and the best final score wins. The runner-up is
    the best coarse-refined placement farther away: the gap between the two says whether
    the choice is unique (a fit to unrelated outlines reaches similar scores at several
    places). ``deadline``: ``time.perf_counter()`` time after which no further placement is
    refined (out of time before any: score 0).
    """
    cands = orientation_search(grey, boundaries, cells, keep=screen, deadline=deadline)
    if not cands or time.perf_counter() >= deadline:
        return BoundaryResult(np.eye(3), 0.0, 0.0, 0.0, 0.0, False)
    rows, cols = grey.shape
    corners = np.array([[0.0, 0.0], [cols - 1.0, 0.0], [0.0, rows - 1.0],
                        [cols - 1.0, rows - 1.0]])
    fields: Dict[float, NDArray[np.complex128]] = {}  # gradient fields per σ, computed once
    screened = []
    for c in cands:
        if screened and time.perf_counter() >= deadline:
            break
        T, sc = refine_orientation(grey, boundaries, c.transform, sigmas=(8.0, 4.0),
                                   spacing=2.0, model="similarity", fields=fields)
        screened.append((sc, T, c))
    screened.sort(key=lambda t: -t[0])
    sc0, T0, best = screened[0]
    if time.perf_counter() >= deadline:  # out of time before the full refinement: score 0
        return BoundaryResult(T0, 0.0, sc0, 0.0, best.score, best.mirrored)
    # placements within three search cells of the best are the same one (local optima of
    # the coarse refinement): each is refined in full, the best final score wins; the
    # runner-up is the best placement elsewhere
    near = 3.0 / best.scale
    basin: List[Array] = []
    others: List[float] = []
    for s, T, _ in screened:
        if np.abs(apply(np.linalg.inv(T0) @ T, corners) - corners).max() <= near:
            basin.append(T)
        else:
            others.append(s)
    finals = []
    for Tb in basin:
        T, score = refine_orientation(grey, boundaries, Tb, sigmas=(2.0, 1.0),
                                      model="similarity", fields=fields)
        finals.append((score, T))
    score, T = max(finals, key=lambda t: t[0])
    # an affine only where it explains clearly more than a similarity: its two extra
    # parameters otherwise fit local differences between outlines and edges
    Ta, score_a = refine_orientation(grey, boundaries, T, sigmas=(1.0,), fields=fields)
    if score_a >= score + AFFINE_GAIN:
        T, score = Ta, score_a
    info = [{"angle_deg": round(c.angle_deg, 2), "scale": round(c.scale, 5),
             "mirrored": c.mirrored, "search": round(c.score, 4), "refined": round(s, 4)}
            for s, _, c in screened]
    return BoundaryResult(T, score, sc0, max(others, default=0.0), best.score, best.mirrored,
                          info)
