r"""Statistics of height differences: the DEM-quality tables of the methods notes.

For differences :math:`\Delta h_i = h_i^{DEM} - h_i^{ref}` (NaN ignored), :func:`difference_stats`
gives

.. math::

   \bar{\Delta h} = \frac{1}{n}\sum \Delta h_i, \qquad
   s = \sqrt{\frac{\sum (\Delta h_i - \bar{\Delta h})^2}{n-1}}, \qquad
   \mathrm{RMS} = \sqrt{\frac{1}{n}\sum \Delta h_i^2}, \qquad
   \mathrm{NMAD} = 1.4826\;\mathrm{median}\,|\Delta h_i - \mathrm{median}(\Delta h)|

``std`` is the *sample* standard deviation about the mean (``ddof=1``), as the seed's RMS of
eq. (3-8) (a standard deviation with :math:`P^*-1`); ``rms`` is about zero, so that
:math:`\mathrm{RMS}^2 \approx \bar{\Delta h}^2 + s^2`. ``q68 … q99`` are quantiles of
:math:`|\Delta h|` with numpy's default linear interpolation between order statistics;
``share_0_25/0_5/1`` are the fractions with :math:`|\Delta h| \le` 0.25/0.5/1 m; the histogram
counts :math:`|\Delta h|` in 0.5 m classes ``[0, 0.5), [0.5, 1.0), …, [4.5, 5.0]`` plus ``over``
(:math:`|\Delta h| > 5` m), the format of seed-002-003 Anhang 3. With a flying height *H* the
length-like statistics are repeated in ‰ of *H* (:math:`1000\,x/H`).

:class:`DifferenceAccumulator` gives the same numbers window by window with bounded memory, overall
and per group (land-cover class, slope class). Moments, extremes, shares and the 0.5 m histogram
are always exact (pairwise-combined mean and :math:`M_2`, Chan et al. 1979). The order statistics
(median, NMAD, quantiles) are exact while the kept values fit ``memory_budget``; beyond it every
store switches to a sparse histogram of bin width ``bin_width`` (default 0.5 mm) whose bins stand
for their centres, so each order statistic is within ``bin_width / 2`` (0.25 mm) of the exact one
and the NMAD within :math:`1.4826 \cdot` ``bin_width`` (0.74 mm). If the occupied bins exceed
``max_bins`` the width doubles (reported as ``precision.bin_width``).

:func:`isprs_matching_stats` gives the external measures of the ISPRS WG III/4 matching test
(seed-000 §5.2, eq. 3-1 … 3-8).
"""

from __future__ import annotations

import math
from typing import Any, Dict, List, Mapping, Optional, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Slope class limits in degrees (per-slope statistics).
SLOPE_CLASSES_DEG = (0, 5, 10, 20, 30, 45, 90)
#: Labels of the slope classes, ``"0–5°"`` … ``"45–90°"``.
SLOPE_LABELS = tuple(
    f"{a}–{b}°" for a, b in zip(SLOPE_CLASSES_DEG[:-1], SLOPE_CLASSES_DEG[1:])
)
#: Edges of the |Δh| histogram (m): 0.5 m classes to 5 m, plus "over".
HIST_EDGES = tuple(0.5 * i for i in range(11))
#: |Δh| thresholds (m) of the shares ``share_0_25``, ``share_0_5``, ``share_1``.
SHARE_LIMITS = {"share_0_25": 0.25, "share_0_5": 0.5, "share_1": 1.0}
#: Quantile levels of |Δh|.
QUANTILES = {"q68": 0.68, "q90": 0.90, "q95": 0.95, "q99": 0.99}
#: Statistics that are lengths (converted to ‰ of the flying height).
LENGTH_KEYS = ("mean", "median", "std", "rms", "nmad", "min", "max", "q68", "q90", "q95", "q99")
NMAD_FACTOR = 1.4826


def slope_class_index(slope_deg: ArrayLike) -> NDArray[np.float64]:
    """Index (0 … 5) of the slope class of each slope (degrees) in :data:`SLOPE_CLASSES_DEG`.

    Classes are ``[0, 5), [5, 10), …, [45, 90]``; NaN stays NaN.
    """
    s = np.asarray(slope_deg, dtype=float)
    idx = np.digitize(s, SLOPE_CLASSES_DEG[1:-1]).astype(float)
    idx[~np.isfinite(s)] = np.nan
    return idx


def _empty_stats() -> Dict[str, Any]:
    out: Dict[str, Any] = {"count": 0}
    for k in ("mean", "median", "std", "rms", "nmad", "min", "max", *QUANTILES, *SHARE_LIMITS):
        out[k] = None
    out["histogram"] = {"edges": list(HIST_EDGES), "counts": [0] * 10, "over": 0}
    return out


def _add_permille(out: Dict[str, Any], flying_height: Optional[float]) -> Dict[str, Any]:
    if flying_height is not None:
        h = float(flying_height)
        if not h > 0:
            raise ValueError("flying_height must be positive")
        out["permille"] = {
            k: (None if out[k] is None else 1000.0 * out[k] / h) for k in LENGTH_KEYS
        }
    return out


def _abs_histogram(a: NDArray[np.float64]) -> tuple:
    """Counts of |Δh| (already absolute) in the 0.5 m classes, and the count above 5 m."""
    counts, _ = np.histogram(a, bins=np.asarray(HIST_EDGES))
    return counts.astype(np.int64), int(np.count_nonzero(a > HIST_EDGES[-1]))


def difference_stats(dz: ArrayLike, flying_height: Optional[float] = None) -> Dict[str, Any]:
    """Statistics of a set of height differences (see the module text for the formulas).

    Parameters
    ----------
    dz : array_like
        Differences DEM − reference in metres, any shape; NaN and ±inf are ignored.
    flying_height : float, optional
        Flying height above ground *H* (m); adds ``permille`` (length-like statistics in ‰ H).

    Returns
    -------
    dict
        ``count, mean, median, std, rms, nmad, min, max, q68, q90, q95, q99, share_0_25,
        share_0_5, share_1, histogram {"edges", "counts", "over"}`` [, ``permille``] — plain
        Python numbers; ``None`` where undefined (no values; ``std`` with one value).
    """
    d = np.asarray(dz, dtype=np.float64).ravel()
    d = d[np.isfinite(d)]
    n = int(d.size)
    if n == 0:
        return _add_permille(_empty_stats(), flying_height)
    a = np.abs(d)
    med = float(np.median(d))
    counts, over = _abs_histogram(a)
    out: Dict[str, Any] = {
        "count": n,
        "mean": float(np.mean(d)),
        "median": med,
        "std": float(np.std(d, ddof=1)) if n > 1 else None,
        "rms": float(np.sqrt(np.mean(d * d))),
        "nmad": float(NMAD_FACTOR * np.median(np.abs(d - med))),
        "min": float(d.min()),
        "max": float(d.max()),
    }
    qs = np.quantile(a, list(QUANTILES.values()))
    out.update({k: float(v) for k, v in zip(QUANTILES, qs)})
    out.update({k: float(np.count_nonzero(a <= lim)) / n for k, lim in SHARE_LIMITS.items()})
    out["histogram"] = {"edges": list(HIST_EDGES), "counts": [int(c) for c in counts],
                        "over": over}
    return _add_permille(out, flying_height)


# -- streaming ------------------------------------------------------------------------------------


def _weighted_quantile(values: NDArray[np.float64], weights: NDArray[np.int64],
                       q: Sequence[float]) -> NDArray[np.float64]:
    """numpy's linear quantile of a sample given as distinct values with repeat counts."""
    order = np.argsort(values, kind="stable")
    v = values[order]
    cum = np.cumsum(weights[order])
    n = int(cum[-1])
    pos = (n - 1) * np.asarray(q, dtype=float)
    lo = np.floor(pos).astype(np.int64)
    hi = np.minimum(lo + 1, n - 1)
    # the k-th order statistic (0-based) is the first value whose cumulative count exceeds k
    vlo = v[np.searchsorted(cum, lo, side="right")]
    vhi = v[np.searchsorted(cum, hi, side="right")]
    return vlo + (pos - lo) * (vhi - vlo)


class _SparseHistogram:
    """Counts of values in bins ``[k·w, (k+1)·w)`` kept only for occupied bins."""

    def __init__(self, bin_width: float, max_bins: int) -> None:
        self.width = float(bin_width)
        self.max_bins = int(max_bins)
        self.keys = np.zeros(0, np.int64)
        self.counts = np.zeros(0, np.int64)

    def _merge(self, keys: NDArray[np.int64], counts: NDArray[np.int64]) -> None:
        u, inv = np.unique(keys, return_inverse=True)
        self.keys = u
        self.counts = np.bincount(inv.ravel(), weights=counts, minlength=u.size).astype(np.int64)

    def add(self, values: NDArray[np.float64]) -> None:
        if values.size == 0:
            return
        scaled = np.clip(np.floor(values / self.width), -2.0**62, 2.0**62)  # no int64 overflow
        k, c = np.unique(scaled.astype(np.int64), return_counts=True)
        self._merge(np.concatenate([self.keys, k]), np.concatenate([self.counts, c]))
        while self.keys.size > self.max_bins:  # coarsen: halve the resolution, merge pairs
            self.width *= 2.0
            self._merge(np.floor_divide(self.keys, 2), self.counts)

    def centres(self) -> NDArray[np.float64]:
        return (self.keys.astype(np.float64) + 0.5) * self.width


class _GroupStore:
    """Exact streaming moments plus either the values themselves or a sparse histogram."""

    def __init__(self) -> None:
        self.n = 0
        self.mean = 0.0
        self.m2 = 0.0
        self.sumsq = 0.0
        self.min = math.inf
        self.max = -math.inf
        self.hist = np.zeros(10, np.int64)
        self.over = 0
        self.shares = dict.fromkeys(SHARE_LIMITS, 0)
        self.values: Optional[List[NDArray[np.float64]]] = []
        self.sparse: Optional[_SparseHistogram] = None

    @property
    def kept(self) -> int:
        return sum(v.size for v in self.values) if self.values is not None else 0

    def add(self, d: NDArray[np.float64]) -> None:
        nb = int(d.size)
        if nb == 0:
            return
        mb = float(d.mean())
        m2b = float(np.sum((d - mb) ** 2))
        n = self.n + nb
        delta = mb - self.mean
        # Chan et al.: pairwise combination of mean and sum of squared deviations
        self.m2 += m2b + delta * delta * self.n * nb / n
        self.mean += delta * nb / n
        self.n = n
        self.sumsq += float(np.dot(d, d))
        self.min = min(self.min, float(d.min()))
        self.max = max(self.max, float(d.max()))
        a = np.abs(d)
        c, o = _abs_histogram(a)
        self.hist += c
        self.over += o
        for k, lim in SHARE_LIMITS.items():
            self.shares[k] += int(np.count_nonzero(a <= lim))
        if self.values is not None:
            self.values.append(d.copy())
        else:
            self.sparse.add(d)

    def to_sparse(self, bin_width: float, max_bins: int) -> None:
        if self.values is None:
            return
        self.sparse = _SparseHistogram(bin_width, max_bins)
        for v in self.values:
            self.sparse.add(v)
        self.values = None

    def result(self, flying_height: Optional[float]) -> Dict[str, Any]:
        if self.n == 0:
            return _add_permille(_empty_stats(), flying_height)
        if self.values is not None:
            d = np.concatenate(self.values) if len(self.values) != 1 else self.values[0]
            return difference_stats(d, flying_height)
        n = self.n
        out: Dict[str, Any] = {
            "count": n,
            "mean": self.mean,
            "median": None,
            "std": math.sqrt(self.m2 / (n - 1)) if n > 1 else None,
            "rms": math.sqrt(self.sumsq / n),
            "nmad": None,
            "min": self.min,
            "max": self.max,
        }
        v, w = self.sparse.centres(), self.sparse.counts
        med = float(_weighted_quantile(v, w, [0.5])[0])
        out["median"] = med
        out["nmad"] = float(NMAD_FACTOR * _weighted_quantile(np.abs(v - med), w, [0.5])[0])
        qs = _weighted_quantile(np.abs(v), w, list(QUANTILES.values()))
        out.update({k: float(x) for k, x in zip(QUANTILES, qs)})
        out.update({k: c / n for k, c in self.shares.items()})
        out["histogram"] = {"edges": list(HIST_EDGES), "counts": [int(c) for c in self.hist],
                            "over": int(self.over)}
        return _add_permille(out, flying_height)


def _label_key(label: Any) -> str:
    if isinstance(label, (float, np.floating)) and float(label).is_integer():
        return str(int(label))
    if isinstance(label, (np.integer,)):
        return str(int(label))
    return str(label)


def _sort_key(key: str) -> tuple:
    try:
        return (0, float(key), key)
    except ValueError:
        return (1, 0.0, key)


class DifferenceAccumulator:
    """Difference statistics overall and per group, fed window by window.

    Parameters
    ----------
    memory_budget : int
        Bytes of difference values kept for exact order statistics (all stores together; a
        value is kept once overall and once per grouping). Beyond it every store switches to a
        sparse histogram (see the module text for the precision).
    bin_width : float
        Bin width (m) of the fallback histograms; order statistics are then within
        ``bin_width / 2``, the NMAD within ``1.4826 · bin_width``.
    max_bins : int
        Occupied bins per store before the bin width doubles.

    Examples
    --------
    >>> acc = DifferenceAccumulator()
    >>> acc.add(dz_window, groups={"class": labels, "slope": slope_labels})  # doctest: +SKIP
    >>> acc.result(flying_height=1000.0)  # {"stats", "per_class", "per_slope", "precision"}
    ...                                   # doctest: +SKIP
    """

    def __init__(self, memory_budget: int = 512 * 2**20, bin_width: float = 0.0005,
                 max_bins: int = 2_000_000) -> None:
        self.memory_budget = int(memory_budget)
        self.bin_width = float(bin_width)
        self.max_bins = int(max_bins)
        self.total = _GroupStore()
        self.groups: Dict[str, Dict[str, _GroupStore]] = {}
        self.exact = True
        self._kept_bytes = 0

    def _stores(self) -> List[_GroupStore]:
        return [self.total] + [s for g in self.groups.values() for s in g.values()]

    def add(self, dz: ArrayLike, groups: Optional[Mapping[str, ArrayLike]] = None) -> None:
        """Add differences (any shape; NaN/inf ignored) with optional per-cell group labels.

        ``groups`` maps a grouping name (``"class"``, ``"slope"``) to labels of the same shape
        as ``dz``; labels that are NaN, ``None`` or ``""`` put the cell in no group of that
        grouping. Results are keyed by ``str(label)`` (integral numbers without ``.0``).
        """
        d = np.asarray(dz, dtype=np.float64).ravel()
        ok = np.isfinite(d)
        dv = d[ok]
        self.total.add(dv)
        added = dv.size
        for name, labels in (groups or {}).items():
            lab = np.asarray(labels).ravel()
            if lab.shape != d.shape:
                raise ValueError(f"labels of group '{name}' do not have the shape of dz")
            lab = lab[ok]
            if lab.dtype.kind == "f":
                valid = np.isfinite(lab)
            elif lab.dtype.kind in "OUS":
                valid = np.array([x is not None and x != "" for x in lab], dtype=bool) \
                    if lab.dtype.kind == "O" else lab != lab.dtype.type("")
            else:
                valid = np.ones(lab.shape, bool)
            lab, dg = lab[valid], dv[valid]
            if dg.size == 0:
                self.groups.setdefault(name, {})
                continue
            # sort once by label, then slice: one pass for all labels of this window
            order = np.argsort(lab, kind="stable")
            lab, dg = lab[order], dg[order]
            uniq, start = np.unique(lab, return_index=True)
            stops = np.append(start[1:], lab.size)
            store = self.groups.setdefault(name, {})
            for u, a, b in zip(uniq, start, stops):
                key = _label_key(u.item() if hasattr(u, "item") else u)
                if key not in store:
                    store[key] = _GroupStore()
                    if not self.exact:
                        store[key].to_sparse(self.bin_width, self.max_bins)
                store[key].add(dg[a:b])
            added += dg.size
        if self.exact:
            self._kept_bytes += 8 * added
            if self._kept_bytes > self.memory_budget:
                for s in self._stores():
                    s.to_sparse(self.bin_width, self.max_bins)
                self.exact = False
                self._kept_bytes = 0

    def result(self, flying_height: Optional[float] = None) -> Dict[str, Any]:
        """``{"stats": …, "per_<group>": {label: stats}, "precision": {"exact", "bin_width"}}``.

        ``per_class`` and ``per_slope`` are always present (empty when not fed).
        """
        out: Dict[str, Any] = {"stats": self.total.result(flying_height),
                               "per_class": {}, "per_slope": {}}
        for name, store in self.groups.items():
            out[f"per_{name}"] = {k: store[k].result(flying_height)
                                  for k in sorted(store, key=_sort_key)}
        widths = [s.sparse.width for s in self._stores() if s.sparse is not None]
        width = None if self.exact else max(widths, default=self.bin_width)
        out["precision"] = {"exact": self.exact, "bin_width": width}
        return out


# -- ISPRS matching-test statistics ---------------------------------------------------------------


def isprs_matching_stats(d: ArrayLike, abs_bound: Optional[float] = None) -> Dict[str, Any]:
    r"""External accuracy measures of the ISPRS WG III/4 matching test (seed-000 §5.2).

    .. math::

       \mathrm{MIN} = \min d_i,\quad \mathrm{MAX} = \max d_i,\quad
       \mathrm{MED} = \mathrm{median}\,d_i,\quad
       \mathrm{MAD} = \mathrm{median}\,|d_i - \mathrm{MED}|,\quad
       \sigma_{MAD} = \mathrm{MAD} / 0.6745

    N−/N+ count the differences below/above :math:`\mathrm{MED} \mp 3\sigma_{MAD}` (N% of P);
    K−/K+ those below/above :math:`\mp` ``abs_bound`` (ISPRS: 8 px). Bias and RMS use the
    :math:`P^*` inliers of the N test:

    .. math::

       \mathrm{Bias} = \frac{1}{P^*}\sum d_i, \qquad
       \mathrm{RMS} = \sqrt{\frac{\sum (d_i - \mathrm{Bias})^2}{P^* - 1}}

    (a standard deviation, not an RMS about zero).

    Parameters
    ----------
    d : array_like
        Differences (participant − reference), NaN ignored; any unit (px, m).
    abs_bound : float, optional
        Absolute bound k of the K test; K values are ``None`` without it.

    Returns
    -------
    dict
        ``P, MIN, MAX, MED, MAD, sigma_MAD, N-, N+, N%, K-, K+, K%, P*, Bias, RMS``
        (percentages in per cent of P).
    """
    x = np.asarray(d, dtype=np.float64).ravel()
    x = x[np.isfinite(x)]
    p = int(x.size)
    keys = ("MIN", "MAX", "MED", "MAD", "sigma_MAD", "N-", "N+", "N%", "K-", "K+", "K%",
            "P*", "Bias", "RMS")
    if p == 0:
        return {"P": 0, **dict.fromkeys(keys)}
    med = float(np.median(x))
    mad = float(np.median(np.abs(x - med)))
    sigma = mad / 0.6745
    lo, hi = med - 3.0 * sigma, med + 3.0 * sigma
    n_minus, n_plus = int(np.count_nonzero(x < lo)), int(np.count_nonzero(x > hi))
    inl = x[(x >= lo) & (x <= hi)]
    ps = int(inl.size)
    bias = float(inl.mean()) if ps else None
    rms = float(math.sqrt(np.sum((inl - bias) ** 2) / (ps - 1))) if ps > 1 else None
    out: Dict[str, Any] = {
        "P": p, "MIN": float(x.min()), "MAX": float(x.max()), "MED": med, "MAD": mad,
        "sigma_MAD": sigma, "N-": n_minus, "N+": n_plus, "N%": 100.0 * (n_minus + n_plus) / p,
        "K-": None, "K+": None, "K%": None, "P*": ps, "Bias": bias, "RMS": rms,
    }
    if abs_bound is not None:
        k = abs(float(abs_bound))
        km, kp = int(np.count_nonzero(x < -k)), int(np.count_nonzero(x > k))
        out.update({"K-": km, "K+": kp, "K%": 100.0 * (km + kp) / p})
    return out
