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

The result is an image → map affine; control points are a grid of image points mapped
through it (:func:`grid_control_points`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np
from numpy.typing import NDArray

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
    from rasterio.features import rasterize
    from shapely.geometry import Polygon

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
    from scipy import ndimage

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
    from scipy import ndimage

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
    import cv2

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
    from scipy.signal import fftconvolve

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
    import cv2

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
               cells: int = SEARCH_CELLS, rounds: int = 2) -> Tuple[Array, float]:
    """Affine refinement of image → map ``T`` by ECC, coarse (≈ ``cells`` px) to full size.

    The polygons are rendered in the image geometry of the current ``T`` each round (no
    interpolation of a rendered raster), and ``cv2.findTransformECC`` aligns the image
    feature to them.

    Returns
    -------
    T : (3, 3) array
        Refined level-0 image pixel → map.
    cc : float
        ECC correlation coefficient of the last (full-size) round; 0 when ECC failed.
    """
    import cv2

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
                cells: int = SEARCH_CELLS, peaks: int = PEAKS) -> AreaResult:
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
                S, ncc = score_candidate(f, v, rings, to_cell, similarity(a, scale), sigma)
                cands.append({"angle_deg": round(math.degrees(a) % 360, 3),
                              "scale": round(scale, 5), "mirrored": mirrored,
                              "peak": round(peak, 5), "ncc": round(ncc, 4)})
                if best is None or ncc > best[0]:
                    F = flip if mirrored else np.eye(3)
                    best = (ncc, np.linalg.inv(to_cell) @ np.linalg.inv(S) @ F @ L, mirrored)
    assert best is not None
    T, cc = refine_ecc(grey, rings, best[1], sigma, cells)
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
