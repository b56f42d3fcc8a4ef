r"""Gaussian image pyramids (factor 2) and coordinate conversion between levels.

Level 0 is the image itself; level k+1 is level k smoothed with a Gaussian (σ ≈ 1 px of level k,
against aliasing) and then reduced by averaging 2 × 2 blocks. Block averaging puts the centre of
pixel c of level k+1 exactly between pixels 2c and 2c+1 of level k, which is what our convention
(pixel centres at integer coordinates) requires:

.. math:: x_0 = (x_k + 0.5)\,2^k - 0.5, \qquad x_k = (x_0 + 0.5)\,2^{-k} - 0.5

for columns and rows alike. A level has :math:`\lceil n / 2^k \rceil` pixels along an axis of n
pixels; an odd edge is padded by repeating the last row or column before the block average.
"""

from __future__ import annotations

import math
from typing import List, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage

#: Gaussian σ (pixels of the finer level) applied before each 2 × 2 reduction
DEFAULT_SIGMA = 1.0


def reduce_level(image: NDArray, sigma: float = DEFAULT_SIGMA) -> NDArray:
    """One pyramid step: Gaussian smoothing, then the mean of 2 × 2 blocks (float32).

    Parameters
    ----------
    image : (rows, cols) array
        Finite grey values (NaN is not supported: fill nodata before building a pyramid).
    sigma : float
        Gaussian σ in pixels of ``image``; 0 disables smoothing (pure 2 × 2 binning).

    Returns
    -------
    (ceil(rows/2), ceil(cols/2)) float32 array.
    """
    img = np.asarray(image, dtype=np.float32)
    if img.ndim != 2:
        raise ValueError("reduce_level expects a 2-D image")
    if sigma > 0:
        img = ndimage.gaussian_filter(img, sigma, mode="nearest")
    rows, cols = img.shape
    if rows % 2 or cols % 2:  # repeat the last row/column so that every block is complete
        img = np.pad(img, ((0, rows % 2), (0, cols % 2)), mode="edge")
    r2, c2 = img.shape[0] // 2, img.shape[1] // 2
    blocks = img.reshape(r2, 2, c2, 2)
    return (0.25 * blocks.sum(axis=(1, 3), dtype=np.float32)).astype(np.float32, copy=False)


def build_pyramid(image: NDArray, levels: int, sigma: float = DEFAULT_SIGMA) -> List[NDArray]:
    """Gaussian pyramid ``[level 0, level 1, …, level levels-1]`` (all float32).

    Parameters
    ----------
    image : (rows, cols) array
        Level 0 (converted to float32; the input is not modified).
    levels : int
        Number of levels including level 0 (≥ 1). Reduction stops early, without error, once a
        level would have fewer than 2 pixels along an axis.
    sigma : float
        Gaussian σ (pixels of the finer level) before each reduction.
    """
    if levels < 1:
        raise ValueError("levels must be at least 1")
    out = [np.asarray(image, dtype=np.float32)]
    for _ in range(levels - 1):
        if min(out[-1].shape) < 4:
            break
        out.append(reduce_level(out[-1], sigma))
    return out


def level_shape(shape: tuple, level: int) -> tuple:
    """Shape of pyramid level ``level`` of an image of ``shape``: ceil(n / 2^level) per axis."""
    f = 2 ** int(level)
    return tuple(-(-int(n) // f) for n in shape)


def to_level(coord: ArrayLike, level: int) -> NDArray:
    """Level-0 pixel coordinate(s) → the same point on ``level``: (x + 0.5)/2^k − 0.5."""
    return (np.asarray(coord, dtype=np.float64) + 0.5) / (2.0 ** level) - 0.5


def from_level(coord: ArrayLike, level: int) -> NDArray:
    """Pixel coordinate(s) on ``level`` → level 0: (x + 0.5)·2^k − 0.5."""
    return (np.asarray(coord, dtype=np.float64) + 0.5) * (2.0 ** level) - 0.5


def convert_level(coord: ArrayLike, src_level: int, dst_level: int) -> NDArray:
    """Pixel coordinate(s) on ``src_level`` → ``dst_level`` (either direction)."""
    return (np.asarray(coord, dtype=np.float64) + 0.5) * (2.0 ** (src_level - dst_level)) - 0.5


def scale_distance(distance: ArrayLike, src_level: int, dst_level: int) -> NDArray:
    """A length or disparity (no offset) from ``src_level`` to ``dst_level``: d·2^(src−dst)."""
    return np.asarray(distance, dtype=np.float64) * (2.0 ** (src_level - dst_level))


def levels_for_disparity(disparity_range: float, pull_in: float = 2.0,
                         min_size: Optional[int] = None, shape: Optional[tuple] = None,
                         max_levels: int = 12) -> int:
    r"""Number of pyramid levels so that the search on the top level is within the pull-in range.

    The uncertainty (width) of the disparity, ``disparity_range`` px on level 0, shrinks to
    :math:`r / 2^{L-1}` on the top level L−1; we want it ≤ ``pull_in`` px (≈ 2 px for LSM, about a
    quarter of the window for FBM), so

    .. math:: L = 1 + \max(0, \lceil \log_2(r / p) \rceil)

    Parameters
    ----------
    disparity_range : float
        Expected disparity (parallax) uncertainty on level 0, pixels (max − min).
    pull_in : float
        Largest uncertainty the top-level matcher can handle, pixels of that level.
    min_size, shape : int, tuple, optional
        If both are given, the top level keeps at least ``min_size`` pixels along the shorter axis
        of ``shape`` (fewer levels are returned then).
    max_levels : int
        Upper bound on the result.
    """
    if pull_in <= 0:
        raise ValueError("pull_in must be positive")
    r = abs(float(disparity_range))
    levels = 1 if r <= pull_in else 1 + math.ceil(math.log2(r / pull_in) - 1e-12)
    if min_size is not None and shape is not None:
        while levels > 1 and min(level_shape(shape, levels - 1)) < min_size:
            levels -= 1
    return int(max(1, min(levels, max_levels)))
