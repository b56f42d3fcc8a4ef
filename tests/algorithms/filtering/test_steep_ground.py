"""The steep presets' plane test of the ground cells and the trend fill (steep_ground)."""

from __future__ import annotations

import numpy as np

from photodem.algorithms.filtering.lowpass import membrane_fill
from photodem.algorithms.filtering.steep_ground import refine_ground, trend_fill


def _slope(shape=(160, 160), spacing=0.5) -> np.ndarray:
    """A 45° plane (1 m/m along the columns, 0.3 along the rows), heights in metres."""
    rows, cols = np.mgrid[0:shape[0], 0:shape[1]].astype(float) * spacing
    return 100.0 + 1.0 * cols + 0.3 * rows


def test_refine_drops_shrubs_keeps_the_sloping_ground() -> None:
    rng = np.random.default_rng(5)
    truth = _slope()
    z = truth + rng.normal(0.0, 0.03, truth.shape)
    ground = rng.random(truth.shape) < 0.05  # sparse ground returns
    shrub = ~ground & (rng.random(truth.shape) < 0.012)  # a fifth of the candidates
    z[shrub] += rng.uniform(1.5, 5.0, shrub.sum())
    cand = ground | shrub
    kept = refine_ground(z, cand, 0.5, 8.0, (1.5, 0.8, 0.5, 0.4))
    assert not (kept & ~cand).any()
    assert (kept & shrub).sum() <= 0.05 * shrub.sum()  # ≥ 95 % of the shrubs dropped
    assert (ground & ~kept).sum() <= 0.01 * ground.sum()  # ≤ 1 % of the ground lost
    prot = np.zeros_like(cand)
    prot[shrub] = True  # protected cells (manual ground points) stay
    assert refine_ground(z, cand, 0.5, 8.0, (0.5,), protected=prot)[shrub].all()
    assert np.array_equal(refine_ground(z, cand, 0.5, 0.0, (0.5,)), cand)  # 0 = off


def test_refine_leaves_dense_ground_and_its_terrace_edges() -> None:
    z = _slope()
    z[:, 80:] += 3.0  # a 3 m retaining wall across the slope, open ground everywhere
    cand = np.ones(z.shape, bool)
    cand[::7, ::5] = False  # a few objects removed by the filter
    assert np.array_equal(refine_ground(z, cand, 0.5, 8.0, (1.5, 0.8, 0.5, 0.4)), cand)
    sparse = np.zeros(z.shape, bool)
    sparse[::4, ::4] = True  # 6 % of the cells: the upper edge is judged (and lost)
    assert not refine_ground(z, sparse, 0.5, 8.0, (1.5, 0.8, 0.5, 0.4))[:, 80:84].any()


def test_trend_fill_follows_the_slope_where_the_membrane_runs_flat() -> None:
    truth = _slope()
    known = np.zeros(truth.shape, bool)
    known[::6, :121:6] = True  # ground only on the left 60 m; the right 20 m are a gap
    values = np.where(known, truth, np.nan)
    filled = trend_fill(values, known, 0.5, 30.0)
    assert np.array_equal(filled[known], truth[known].astype(np.float32))
    assert np.abs(filled - truth).max() < 0.01  # a plane is reproduced, also 20 m out
    flat = membrane_fill(values, known)
    assert np.abs(flat - truth).max() > 10.0  # what the plain membrane does there


def test_only_the_steep_presets_take_the_steps() -> None:
    from photodem.algorithms.filtering.lowpass import lowpass_parameters
    from photodem.algorithms.filtering.presets import (
        LINEAR_PREDICTION_PRESETS,
        LOWPASS_PRESETS,
        PRESET_NAMES,
    )

    for name in PRESET_NAMES:
        on = name == "steep"
        assert (LOWPASS_PRESETS[name].get("refine_radius_m", 0.0) > 0) == on
        assert (LINEAR_PREDICTION_PRESETS[name].get("refine_radius", 0.0) > 0) == on
        assert ("trend_window_m" in lowpass_parameters(name).report()) == on
