r"""Statistics of a DEM against a reference where the operator looks (the QC panel's numbers).

:func:`area_statistics` is :func:`~.compare.compare_dems` with an ``area`` (a polygon drawn on
the map, the visible extent or the whole model): the same windows, the same accumulator, so the
numbers are those of ``dem_compare`` restricted to the cells whose centres lie in the area.
It adds what a panel shows beside them: the class names (:func:`~.class_legend.
read_class_legend`) and a histogram of the signed :math:`\Delta h` in fine fixed bins
(:data:`HIST_STEP` from :data:`HIST_RANGE`), which :func:`rebin_histogram` coarsens to the range
a plot needs (e.g. median ± 4 NMAD) without another pass over the rasters.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Dict, Optional, Tuple, Union

import numpy as np
from numpy.typing import NDArray

from ..feedback import Feedback
from .compare import class_names_of, compare_dems

PathLike = Union[str, Path]

#: Range (m) and bin width (m) of the signed Δh histogram gathered while comparing.
HIST_RANGE: Tuple[float, float] = (-20.0, 20.0)
HIST_STEP = 0.01


class SignedHistogram:
    """Counts of Δh in :data:`HIST_STEP` bins over :data:`HIST_RANGE`, plus under/over counts."""

    def __init__(self) -> None:
        n = round((HIST_RANGE[1] - HIST_RANGE[0]) / HIST_STEP)
        self.edges = np.linspace(HIST_RANGE[0], HIST_RANGE[1], n + 1)
        self.counts = np.zeros(n, np.int64)
        self.under = 0
        self.over = 0

    def add(self, dz: NDArray[Any]) -> None:
        """Add the finite values of ``dz`` (any shape)."""
        d = np.asarray(dz, dtype=np.float64).ravel()
        d = d[np.isfinite(d)]
        self.under += int(np.count_nonzero(d < self.edges[0]))
        self.over += int(np.count_nonzero(d > self.edges[-1]))
        self.counts += np.histogram(d, bins=self.edges)[0]

    def hook(self, row: int, col: int, dz: NDArray[Any]) -> None:
        """The ``on_window`` callback of :func:`~.compare.compare_dems`."""
        self.add(dz)

    def to_dict(self) -> Dict[str, Any]:
        return {"edges": self.edges.tolist(), "counts": self.counts.tolist(),
                "under": self.under, "over": self.over}


def rebin_histogram(hist: Dict[str, Any], lo: float, hi: float, bins: int = 60
                    ) -> Tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Coarser histogram over ``[lo, hi]`` from the fine one (bins wholly outside are dropped).

    Fine bins are assigned to the coarse bin holding their centre, so the coarse counts are
    exact when the coarse edges fall on fine edges.
    """
    edges = np.asarray(hist["edges"], dtype=float)
    counts = np.asarray(hist["counts"], dtype=np.int64)
    centres = 0.5 * (edges[:-1] + edges[1:])
    out_edges = np.linspace(float(lo), float(hi), int(bins) + 1)
    keep = (centres >= out_edges[0]) & (centres <= out_edges[-1])
    idx = np.clip(np.searchsorted(out_edges, centres[keep], side="right") - 1, 0, bins - 1)
    return out_edges, np.bincount(idx, weights=counts[keep], minlength=bins).astype(np.int64)


def area_statistics(dem: PathLike, reference: PathLike, area: Any = None, *,
                    classes: Optional[PathLike] = None, class_field: Optional[str] = None,
                    class_legend: Optional[PathLike] = None, window_size: int = 1024,
                    feedback: Optional[Feedback] = None) -> Dict[str, Any]:
    """Statistics of Δh = DEM − reference in an area, overall, per class and per slope class.

    Parameters
    ----------
    dem, reference : path
        The DEM to check and the reference (any grids/CRS, as :func:`~.compare.compare_dems`).
    area : shapely polygon, WKT or (xmin, ymin, xmax, ymax), optional
        In the reference CRS; None = the whole common area.
    classes, class_field : optional
        Class raster or polygons (+ attribute), as ``dem_compare``.
    class_legend : path, optional
        Names of the codes of a class raster (default: the style beside the raster).
    window_size : int
        Processing window edge (cells).
    feedback : Feedback, optional
        Progress; cancelling raises :class:`~photodem.algorithms.errors.Cancelled`.

    Returns
    -------
    dict
        The :func:`~.compare.compare_dems` result plus ``"histogram"`` (signed Δh,
        :class:`SignedHistogram`) and ``"class_names"`` (code → name, for
        :func:`~.class_legend.class_label`); ``per_class`` stays keyed by code as in
        ``dem_compare``.
    """
    hist = SignedHistogram()
    res = compare_dems(dem, reference, classes=classes, class_field=class_field, area=area,
                       window_size=window_size, on_window=hist.hook, feedback=feedback)
    res["class_names"] = class_names_of(classes, class_legend)
    res["histogram"] = hist.to_dict()
    return res


__all__ = ["HIST_RANGE", "HIST_STEP", "SignedHistogram", "area_statistics", "rebin_histogram"]
