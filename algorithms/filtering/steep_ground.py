r"""Ground on steep vegetated slopes: the candidates' plane test and a trend-following fill.

Both filters end with ground *candidates*: the cells they kept. Under a closed canopy on a
30–45° slope, a few per cent of the cells hold a ground return and about a fifth of the
candidates are shrubs or low crowns 1.7–5 m up, which the filters' windows cannot tell from the
slope; and the membrane (Laplace) fill of the holes between the candidates runs flat where
the slope goes on (at the data border: 10 m beyond the last ground cell on a 45° slope is
10 m of error). The ``steep`` presets therefore finish with two steps.

**Plane test** (:func:`refine_ground`). Every candidate is compared with the least-squares
plane through the candidates of a square window of side :math:`2R` around it
(:func:`.lowpass.plane_smooth`, box filters: the cost does not depend on ``R``); candidates
more than :math:`t_k` above it are dropped, and the plane is fitted again with the rest, for a
falling schedule :math:`t_1 > t_2 > \dots` (e.g. 1.5, 0.8, 0.5, 0.4 m). The plane takes the
slope, so a 45° slope does not masquerade as vegetation, and because the candidates on the
ground outnumber the shrubs (about 4 : 1), the first plane lies less than a metre above the
ground; each pass drops the highest candidates and lowers the plane. The terrain's own
curvature :math:`\kappa` lifts the plane by at most :math:`\kappa R^2/2` above a crest
(≈ 0.15 m for R = 8 m on the test scene's spurs), well inside the last tolerance. The test
only judges candidates with at least ``min_count`` candidates in their window, and only where
the candidates are sparse: at most :data:`SPARSE_SHARE` of the valid cells of the window (under
a closed canopy about 7 %). Where most cells are ground (open terrain), the filters need no
help, and the plane would cut the upper edge of every terrace and retaining wall: on the
filter tests' steep hillside with walls and houses (``steep_scene``) the ungated test lowered
the low-pass kappa of the ``steep`` preset from 96.4 % to 83.7 % (Type I 0.02 → 3.5 %); gated it
is 96.4 %.

**Trend fill** (:func:`trend_fill`). Heights :math:`z = T + r`: the trend :math:`T` is the
least-squares plane through the ground cells of a window of side ``W`` (e.g. 30 m) around
every cell — a plane extrapolates the slope at the border and across gaps —, and the
residuals :math:`r` of the ground cells are filled by the membrane
(:func:`.lowpass.membrane_fill`), which is harmless for residuals that scatter about zero.
Cells whose window holds too few ground cells take the plane of a window twice (then four
times) as wide, and beyond that the membrane fill of the trend itself.

On the synthetic steep forest (:mod:`..synthetic.forest_scene`, small, 0.5 m grid) the
low-pass filter's candidates (3920 cells, 882 of them 1–5 m up) keep 3035 cells with 8 not on
the ground after the plane test (R = 8 m), and the DTM RMS falls from 1.70 m to 0.12 m with the
trend fill (1.13 m with the membrane fill of only the true ground cells); linear
prediction's ground cells give 0.16 m. A 30 m trend window beats 20 m (0.12 against 0.16 m,
lowest −0.6 against −4.3 m): near the border a 20 m window may hold ground cells only along a
line, whose plane tilts at random. On the 400 m bench scene (1.2 M points): 0.09 m low-pass,
0.06 m linear prediction.
"""

from __future__ import annotations

from typing import Any, Optional, Sequence

import numpy as np
from numpy.typing import NDArray
from scipy.ndimage import uniform_filter

Array = NDArray[Any]

#: Fewest candidates in a window for the plane test to judge the centre cell.
MIN_PLANE_CELLS = 6
#: The plane test judges only where at most this share of the valid cells in the window are
#: candidates (ground returns under a closed canopy: about 7 %; open terrain: most cells).
SPARSE_SHARE = 0.5
#: Fewest ground cells in a window for a trend plane there (fewer, e.g. along a line at the
#: border, tilt the plane at random).
MIN_TREND_CELLS = 20
#: How often the trend's window is doubled where it holds fewer than the fewest cells.
TREND_WIDENINGS = 2


def refine_ground(z: Array, ground: Array, spacing: float, radius_m: float,
                  tolerances_m: Sequence[float], protected: Optional[Array] = None,
                  valid: Optional[Array] = None, min_count: int = MIN_PLANE_CELLS,
                  sparse_share: float = SPARSE_SHARE) -> Array:
    """Drop sparse ground candidates that stand above the local plane of the candidates.

    Parameters
    ----------
    z : ndarray (h, w)
        Heights (NaN = no data).
    ground : ndarray of bool (h, w)
        The candidates.
    spacing : float
        Cell size (m).
    radius_m : float
        Half side ``R`` (m) of the plane's window; 0 = no test.
    tolerances_m : sequence of float
        Heights (m) above the plane beyond which a candidate is dropped, one pass each.
    protected : ndarray of bool, optional
        Candidates never dropped (manual ground points, keep areas).
    valid : ndarray of bool, optional
        Cells with data (default: finite ``z``), for the candidates' share.
    min_count : int
        Fewest candidates in a window for the plane to judge.
    sparse_share : float
        Only candidates whose window holds at most this share of candidates among the
        valid cells are judged.

    Returns
    -------
    ndarray of bool
        The remaining candidates (a subset of ``ground``).
    """
    from .lowpass import plane_smooth  # lazy: lowpass imports this module

    keep = np.asarray(ground, bool) & np.isfinite(z)
    if radius_m <= 0 or not tolerances_m:
        return keep
    radius = max(1, round(float(radius_m) / float(spacing)))
    safe = np.zeros_like(keep) if protected is None else np.asarray(protected, bool)
    has = np.isfinite(z) if valid is None else np.asarray(valid, bool)
    size = 2 * radius + 1
    share = uniform_filter(keep.astype(np.float32), size) / np.maximum(
        uniform_filter(has.astype(np.float32), size), 1e-6)
    safe = safe | (share > sparse_share)  # dense ground: open terrain, terraces, walls
    for tol in tolerances_m:
        plane = plane_smooth(z, keep, radius, min_count=min_count)
        with np.errstate(invalid="ignore"):
            high = keep & ~safe & (z - plane > float(tol))
        keep &= ~high
    return keep


def trend_fill(values: Array, known: Array, spacing: float, window_m: float,
               barrier: Optional[Array] = None, barrier_z: Optional[Array] = None,
               min_count: int = MIN_TREND_CELLS) -> Array:
    """Fill the unknown cells as a local plane trend plus the membrane fill of the residuals.

    Parameters
    ----------
    values : ndarray (h, w)
        Heights (used where ``known``).
    known : ndarray of bool (h, w)
        The fixed cells (ground).
    spacing : float
        Cell size (m).
    window_m : float
        Side ``W`` (m) of the trend's window.
    barrier, barrier_z : ndarray, optional
        Breakline cells and their heights (NaN for 2-D lines), as for
        :func:`.lowpass.membrane_fill`.
    min_count : int
        Fewest known cells in a window for a trend there.

    Returns
    -------
    ndarray float32 (h, w)
        The surface; equal to ``values`` at the known cells.
    """
    from .lowpass import membrane_fill, plane_smooth  # lazy: lowpass imports this module

    known = np.asarray(known, bool) & np.isfinite(values)
    radius = max(1, round(float(window_m) / float(spacing) / 2.0))
    trend = plane_smooth(values, known, radius, min_count=min_count).astype(np.float64)
    has = np.isfinite(trend)
    for _ in range(TREND_WIDENINGS):  # too little ground around: the plane of a wider window
        if has.all():
            break
        radius *= 2
        wider = plane_smooth(values, known, radius, min_count=min_count)
        trend = np.where(has, trend, wider)
        has = np.isfinite(trend)
    if not has.any():
        return membrane_fill(values, known, barrier, barrier_z)
    if not has.all():  # windows without enough ground: the trend is filled like a surface
        trend = membrane_fill(trend, has, barrier).astype(np.float64)
    resid = np.where(known, np.asarray(values, np.float64) - trend, np.nan)
    bres = None if barrier_z is None else np.asarray(barrier_z, np.float64) - trend
    out = trend + membrane_fill(resid, known, barrier, bres)
    out[known] = np.asarray(values)[known]
    return out.astype(np.float32)


__all__ = ["MIN_PLANE_CELLS", "MIN_TREND_CELLS", "SPARSE_SHARE", "TREND_WIDENINGS",
           "refine_ground", "trend_fill"]
