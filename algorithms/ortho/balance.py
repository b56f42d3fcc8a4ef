r"""Radiometric balancing of orthophotos: gain/offset per image and band over all overlaps.

Model
    The balanced value of image :math:`i`, band :math:`b` is :math:`v' = g_{ib}\,v + o_{ib}`.
    For every overlapping pair :math:`(i, j)` the statistics of the cells valid in both give,
    per band, with :math:`m_{ij}, s_{ij}` the mean and standard deviation of image :math:`i`
    over that common area (:math:`n_{ij}` cells, weight :math:`w_{ij} = n_{ij}/\max n`):

    .. math::  \sqrt{w_{ij}}\,(g_i\,s_{ij} - g_j\,s_{ji}) = 0 \qquad
               \sqrt{w_{ij}}\,(g_i\,m_{ij} + o_i - g_j\,m_{ji} - o_j) = 0

    (the balanced images have the same spread and the same mean in every overlap). Gains are
    solved first by least squares with the datum :math:`\frac1N\sum g_i = 1` (or
    :math:`g_r = 1` for a reference image :math:`r`), then offsets with
    :math:`\sum o_i = 0` (or :math:`o_r = 0`), each through its normal equations with a Lagrange
    multiplier for the datum of every group of images connected by overlaps (an image
    without overlaps keeps :math:`g = 1, o = 0`). Matching moments rather than regressing pixel on
    pixel avoids the regression bias towards small gains with noisy images.
    Gains are rounded to :math:`10^{-6}` and offsets to :math:`10^{-4}` DN so that the mosaic
    does not depend on the last bits of the linear-algebra library.

Histogram matching (optional)
    After gain/offset, each image's distribution in its overlaps is mapped onto the pooled
    distribution of all images in all overlaps by quantile mapping (257 quantiles,
    piecewise linear), per band.

The statistics come from the seam grid of the mosaic (block averages of the orthos, see
:mod:`.mosaic`), so their cost does not grow with the mosaic's resolution.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np
from numpy.typing import NDArray

Array = NDArray[Any]

#: Balancing modes.
BALANCE_MODES = ("none", "gain_offset", "histogram")
#: Fewest common cells for a pair to enter the adjustment.
MIN_OVERLAP = 25
#: Quantiles of the histogram matching.
N_QUANTILES = 257


@dataclass
class BalanceImage:
    """Samples of one ortho on a common grid: ``bands`` (b, h, w) at offset ``row, col``.

    ``valid`` (h, w) marks usable cells (completely valid and visible).
    """

    row: int
    col: int
    bands: Array
    valid: Array


@dataclass
class PairStats:
    """Moments of one overlap: images ``i < j``, ``n`` common cells, per band (b,) arrays."""

    i: int
    j: int
    n: int
    mean_i: Array
    mean_j: Array
    std_i: Array
    std_j: Array


def _common(a: BalanceImage, b: BalanceImage) -> Optional[Tuple[Array, Array]]:
    """Values (bands, n) of both images on the cells valid in both, or None without overlap."""
    ha, wa = a.valid.shape
    hb, wb = b.valid.shape
    r0, r1 = max(a.row, b.row), min(a.row + ha, b.row + hb)
    c0, c1 = max(a.col, b.col), min(a.col + wa, b.col + wb)
    if r1 <= r0 or c1 <= c0:
        return None
    sa = (slice(r0 - a.row, r1 - a.row), slice(c0 - a.col, c1 - a.col))
    sb = (slice(r0 - b.row, r1 - b.row), slice(c0 - b.col, c1 - b.col))
    m = a.valid[sa] & b.valid[sb]
    if not m.any():
        return None
    return a.bands[:, sa[0], sa[1]][:, m], b.bands[:, sb[0], sb[1]][:, m]


def overlap_stats(images: Sequence[BalanceImage], min_overlap: int = MIN_OVERLAP
                  ) -> List[PairStats]:
    """Moments of every overlapping pair with at least ``min_overlap`` common cells."""
    out = []
    for i in range(len(images)):
        for j in range(i + 1, len(images)):
            common = _common(images[i], images[j])
            if common is None or common[0].shape[1] < min_overlap:
                continue
            vi, vj = (c.astype(np.float64) for c in common)
            out.append(PairStats(i, j, int(vi.shape[1]), vi.mean(axis=1), vj.mean(axis=1),
                                 vi.std(axis=1), vj.std(axis=1)))
    return out


def _components(pairs: Sequence[PairStats], n: int) -> List[List[int]]:
    """Connected groups of images (through overlaps), each sorted."""
    parent = list(range(n))

    def root(a: int) -> int:
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for p in pairs:
        parent[root(p.i)] = root(p.j)
    groups: Dict[int, List[int]] = {}
    for k in range(n):
        groups.setdefault(root(k), []).append(k)
    return sorted(groups.values())


def _solve_datum(rows: List[Tuple[int, float, int, float, float, float]], n: int,
                 prior: float, reference: Optional[int], groups: List[List[int]]) -> Array:
    r"""Least squares :math:`\min \sum w (a x_i - b x_j - c)^2` with the datum of the module.

    ``rows`` holds ``(i, a, j, b, c, w)``; the datum, per group of connected images, is
    :math:`\sum x = |group|\cdot prior` (or :math:`x_r = prior` in the group of the
    reference), so an image without overlaps keeps ``prior``.
    """
    N = np.zeros((n, n))
    rhs = np.zeros(n)
    for i, a, j, b, c, w in rows:
        # equation a·x_i − b·x_j = c with weight w
        N[i, i] += w * a * a
        N[j, j] += w * b * b
        N[i, j] -= w * a * b
        N[j, i] -= w * a * b
        rhs[i] += w * a * c
        rhs[j] -= w * b * c
    m = len(groups)
    K = np.zeros((n + m, n + m))
    K[:n, :n] = N
    total = np.zeros(m)
    for g, members in enumerate(groups):
        if reference is not None and reference in members:
            K[n + g, reference] = K[reference, n + g] = 1.0
            total[g] = prior
        else:
            K[n + g, members] = 1.0
            K[members, n + g] = 1.0
            total[g] = len(members) * prior
    sol = np.linalg.solve(K, np.concatenate([rhs, total]))
    return sol[:n]


def solve_gain_offset(pairs: Sequence[PairStats], n_images: int, n_bands: int,
                      reference: Optional[int] = None) -> Tuple[Array, Array]:
    """Gains and offsets (n_images, n_bands) from the overlap moments (see the module notes)."""
    gains = np.ones((n_images, n_bands))
    offsets = np.zeros((n_images, n_bands))
    if not pairs or n_images < 2:
        return gains, offsets
    nmax = max(p.n for p in pairs)
    groups = _components(pairs, n_images)
    for b in range(n_bands):
        grow = [(p.i, float(p.std_i[b]), p.j, float(p.std_j[b]), 0.0, p.n / nmax)
                for p in pairs]
        g = np.round(_solve_datum(grow, n_images, 1.0, reference, groups), 6)
        orow = [(p.i, 1.0, p.j, 1.0,
                 float(g[p.j] * p.mean_j[b] - g[p.i] * p.mean_i[b]), p.n / nmax)
                for p in pairs]
        o = np.round(_solve_datum(orow, n_images, 0.0, reference, groups), 4)
        gains[:, b] = g
        offsets[:, b] = o
    return gains, offsets


def apply_balance(values: Array, gain: Array, offset: Array,
                  lut: Optional[Tuple[Array, Array]] = None) -> Array:
    """Balanced float32 values of one image (b, …) with per-band ``gain``, ``offset``, LUT.

    ``lut`` is ``(source quantiles, target quantiles)``, each (b, q), from
    :func:`histogram_luts`.
    """
    v = values.astype(np.float32)
    shape = (-1,) + (1,) * (v.ndim - 1)
    out = v * gain.astype(np.float32).reshape(shape) + offset.astype(np.float32).reshape(shape)
    if lut is not None:
        src_q, dst_q = lut
        for b in range(out.shape[0]):
            out[b] = np.interp(out[b], src_q[b], dst_q[b]).astype(np.float32)
    return out


def _overlap_values(images: Sequence[BalanceImage], gains: Array, offsets: Array
                    ) -> List[List[Array]]:
    """Balanced values (bands, n) of every image in its overlaps with all others."""
    per_image: List[List[Array]] = [[] for _ in images]
    for i in range(len(images)):
        for j in range(i + 1, len(images)):
            common = _common(images[i], images[j])
            if common is None:
                continue
            per_image[i].append(apply_balance(common[0], gains[i], offsets[i]))
            per_image[j].append(apply_balance(common[1], gains[j], offsets[j]))
    return per_image


def _strictly_increasing(q: Array) -> Array:
    q = np.maximum.accumulate(q.astype(np.float64))
    return q + np.arange(q.size) * 1e-6  # np.interp needs increasing sample points


def histogram_luts(images: Sequence[BalanceImage], gains: Array, offsets: Array
                   ) -> List[Optional[Tuple[Array, Array]]]:
    """Quantile-mapping LUT per image onto the pooled overlap distribution (module notes)."""
    per_image = _overlap_values(images, gains, offsets)
    levels = np.linspace(0.0, 1.0, N_QUANTILES)
    pooled = [np.concatenate(v, axis=1) for v in per_image if v]
    if not pooled:
        return [None] * len(images)
    allv = np.concatenate(pooled, axis=1)
    ref = np.stack([np.quantile(allv[b], levels) for b in range(allv.shape[0])])
    luts: List[Optional[Tuple[Array, Array]]] = []
    for vals in per_image:
        if not vals:
            luts.append(None)
            continue
        v = np.concatenate(vals, axis=1)
        src = np.stack([_strictly_increasing(np.quantile(v[b], levels))
                        for b in range(v.shape[0])])
        luts.append((src, ref))
    return luts


def overlap_differences(images: Sequence[BalanceImage], gains: Array, offsets: Array,
                        luts: Optional[Sequence[Optional[Tuple[Array, Array]]]] = None,
                        min_overlap: int = MIN_OVERLAP) -> List[Dict[str, Any]]:
    """Per overlapping pair and band: mean and mean absolute difference ``i − j`` (DN)."""
    out = []
    for i in range(len(images)):
        for j in range(i + 1, len(images)):
            common = _common(images[i], images[j])
            if common is None or common[0].shape[1] < min_overlap:
                continue
            a = apply_balance(common[0], gains[i], offsets[i], luts[i] if luts else None)
            b = apply_balance(common[1], gains[j], offsets[j], luts[j] if luts else None)
            d = a.astype(np.float64) - b.astype(np.float64)
            out.append({"i": i, "j": j, "n": int(d.shape[1]),
                        "mean": [round(float(x), 3) for x in d.mean(axis=1)],
                        "mean_abs": [round(float(x), 3) for x in np.abs(d).mean(axis=1)]})
    return out


def summarise(diffs: Sequence[Dict[str, Any]]) -> Dict[str, Optional[float]]:
    """Cell-weighted mean |mean difference| and mean |difference| over all pairs and bands."""
    if not diffs:
        return {"mean_difference": None, "mean_abs_difference": None}
    w = np.array([d["n"] for d in diffs], np.float64)
    md = np.array([np.mean(np.abs(d["mean"])) for d in diffs])
    ma = np.array([np.mean(d["mean_abs"]) for d in diffs])
    return {"mean_difference": round(float((w * md).sum() / w.sum()), 3),
            "mean_abs_difference": round(float((w * ma).sum() / w.sum()), 3)}


def balance_images(images: Sequence[BalanceImage], mode: str = "gain_offset",
                   reference: Optional[int] = None, names: Optional[Sequence[str]] = None
                   ) -> Tuple[Array, Array, List[Optional[Tuple[Array, Array]]], Dict[str, Any]]:
    """Estimate the balancing of a set of orthos and report it.

    Parameters
    ----------
    images : sequence of BalanceImage
        Samples of the orthos on a common grid.
    mode : {"none", "gain_offset", "histogram"}
    reference : int, optional
        Index of the image kept unchanged; default: mean gain 1, mean offset 0.
    names : sequence of str, optional
        Image names for the report.

    Returns
    -------
    gains, offsets : ndarray (n_images, n_bands)
    luts : list
        Per image ``None`` or the quantile LUT of :func:`histogram_luts`.
    report : dict
        ``mode, reference, images`` (name, gains, offsets), ``pairs`` (per overlap: names,
        cells, mean and mean |difference| per band before and after), ``before``/``after``
        (:func:`summarise`).
    """
    if mode not in BALANCE_MODES:
        raise ValueError(f"balance mode {mode!r} not in {BALANCE_MODES}")
    n = len(images)
    n_bands = images[0].bands.shape[0] if images else 0
    names = list(names) if names is not None else [str(k) for k in range(n)]
    gains = np.ones((n, n_bands))
    offsets = np.zeros((n, n_bands))
    luts: List[Optional[Tuple[Array, Array]]] = [None] * n
    if mode != "none":
        gains, offsets = solve_gain_offset(overlap_stats(images), n, n_bands, reference)
        if mode == "histogram":
            luts = histogram_luts(images, gains, offsets)
    before = overlap_differences(images, np.ones_like(gains), np.zeros_like(offsets))
    after = overlap_differences(images, gains, offsets, luts)
    pairs = []
    for b_, a_ in zip(before, after):
        pairs.append({"image_a": names[b_["i"]], "image_b": names[b_["j"]], "cells": b_["n"],
                      "mean_before": b_["mean"], "mean_abs_before": b_["mean_abs"],
                      "mean_after": a_["mean"], "mean_abs_after": a_["mean_abs"]})
    report = {
        "mode": mode,
        "reference": None if reference is None else names[reference],
        "images": [{"image": names[k], "gains": [float(x) for x in gains[k]],
                    "offsets": [float(x) for x in offsets[k]],
                    "histogram_matched": luts[k] is not None} for k in range(n)],
        "pairs": pairs,
        "before": summarise(before),
        "after": summarise(after),
    }
    return gains, offsets, luts, report


__all__ = [
    "BALANCE_MODES",
    "BalanceImage",
    "PairStats",
    "apply_balance",
    "balance_images",
    "histogram_luts",
    "overlap_differences",
    "overlap_stats",
    "solve_gain_offset",
    "summarise",
]
