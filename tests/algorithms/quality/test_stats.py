"""Difference statistics, the streaming accumulator and the ISPRS matching statistics."""

from __future__ import annotations

import math

import numpy as np
import pytest

from photodem.algorithms.quality.stats import (
    SLOPE_CLASSES_DEG,
    SLOPE_LABELS,
    DifferenceAccumulator,
    difference_stats,
    isprs_matching_stats,
    slope_class_index,
)

KEYS = ("mean", "median", "std", "rms", "nmad", "min", "max", "q68", "q90", "q95", "q99")


def _numpy_stats(d):
    d = d[np.isfinite(d)]
    a = np.abs(d)
    med = np.median(d)
    return {
        "count": d.size, "mean": d.mean(), "median": med, "std": d.std(ddof=1),
        "rms": np.sqrt(np.mean(d**2)), "nmad": 1.4826 * np.median(np.abs(d - med)),
        "min": d.min(), "max": d.max(), "q68": np.quantile(a, 0.68),
        "q90": np.quantile(a, 0.90), "q95": np.quantile(a, 0.95), "q99": np.quantile(a, 0.99),
        "share_0_25": np.mean(a <= 0.25), "share_0_5": np.mean(a <= 0.5),
        "share_1": np.mean(a <= 1.0),
    }


def test_constant_bias_closed_form():
    s = difference_stats(np.full(1000, 1.5), flying_height=1500.0)
    assert s["count"] == 1000
    for k in ("mean", "median", "rms", "min", "max", "q68", "q90", "q95", "q99"):
        assert s[k] == pytest.approx(1.5, abs=1e-12)
    assert s["std"] == pytest.approx(0.0, abs=1e-12)
    assert s["nmad"] == 0.0
    assert (s["share_0_25"], s["share_0_5"], s["share_1"]) == (0.0, 0.0, 0.0)
    assert s["histogram"]["counts"] == [0, 0, 0, 1000, 0, 0, 0, 0, 0, 0]
    assert s["histogram"]["over"] == 0
    assert s["histogram"]["edges"] == [0.5 * i for i in range(11)]
    assert s["permille"]["mean"] == pytest.approx(1.0)  # 1.5 m of 1500 m = 1 ‰


def test_tilted_plane_and_blunders_match_numpy():
    # Δh of a tilted plane on a grid, with planted blunders and holes
    y, x = np.mgrid[0:200, 0:300].astype(float)
    d = 0.2 + 0.003 * x - 0.002 * y
    d[::37, ::41] = 25.0
    d[5, :50] = -12.0
    d[100:110, 100:110] = np.nan
    s = difference_stats(d)
    ref = _numpy_stats(d.ravel())
    for k, v in ref.items():
        assert s[k] == pytest.approx(v, abs=1e-9), k
    a = np.abs(d[np.isfinite(d)])
    counts, _ = np.histogram(a, bins=np.arange(11) * 0.5)
    assert s["histogram"]["counts"] == counts.tolist()
    assert s["histogram"]["over"] == int(np.sum(a > 5))
    assert s["max"] == 25.0 and s["min"] == -12.0
    assert sum(s["histogram"]["counts"]) + s["histogram"]["over"] == s["count"]


def test_json_ready_and_empty():
    import json

    s = difference_stats([np.nan, np.inf], flying_height=1000)
    assert s["count"] == 0 and s["mean"] is None and s["permille"]["rms"] is None
    json.dumps(s, allow_nan=False)
    s = difference_stats(np.random.default_rng(0).normal(size=50))
    json.dumps(s, allow_nan=False)
    assert all(type(s[k]) is float for k in KEYS)
    assert difference_stats([2.0])["std"] is None


def test_slope_classes():
    assert SLOPE_CLASSES_DEG == (0, 5, 10, 20, 30, 45, 90)
    assert SLOPE_LABELS[0] == "0–5°" and SLOPE_LABELS[-1] == "45–90°"
    idx = slope_class_index([0, 4.99, 5, 19, 44.9, 45, 90, np.nan])
    assert idx[:7].tolist() == [0, 0, 1, 2, 4, 5, 5] and np.isnan(idx[7])


def _data(seed=1, n=60_000):
    rng = np.random.default_rng(seed)
    d = rng.normal(0.1, 0.3, n)
    d[rng.random(n) < 0.02] += rng.normal(0, 8, 1)  # blunders
    d[rng.random(n) < 0.01] = np.nan
    cls = rng.integers(1, 4, n).astype(float)
    cls[rng.random(n) < 0.05] = np.nan  # cells in no class
    slope = slope_class_index(rng.uniform(0, 60, n))
    return d, cls, slope


def test_accumulator_exact_equals_in_memory():
    d, cls, slope = _data()
    acc = DifferenceAccumulator()
    for part in np.array_split(np.arange(d.size), 7):
        acc.add(d[part], groups={"class": cls[part], "slope": slope[part]})
    res = acc.result(flying_height=800.0)
    assert res["precision"]["exact"]
    whole = difference_stats(d, flying_height=800.0)
    for k in KEYS:
        assert res["stats"][k] == pytest.approx(whole[k], abs=1e-6), k
    assert list(res["per_class"]) == ["1", "2", "3"]
    for key, st in res["per_class"].items():
        ref = difference_stats(d[cls == float(key)])
        for k in KEYS:
            assert st[k] == pytest.approx(ref[k], abs=1e-6), (key, k)
        assert st["histogram"] == ref["histogram"]
    assert list(res["per_slope"]) == ["0", "1", "2", "3", "4", "5"]
    assert res["per_slope"]["2"]["count"] == int(np.sum((slope == 2) & np.isfinite(d)))


def test_accumulator_fallback_within_documented_precision():
    d, cls, slope = _data(seed=2)
    acc = DifferenceAccumulator(memory_budget=8 * 5000)  # forces the histogram fallback
    for part in np.array_split(np.arange(d.size), 9):
        acc.add(d[part], groups={"class": cls[part], "slope": slope[part]})
    res = acc.result()
    assert not res["precision"]["exact"]
    w = res["precision"]["bin_width"]
    assert w == pytest.approx(0.0005)
    whole = difference_stats(d)
    for k in ("mean", "std", "rms", "min", "max"):  # moments stay exact
        assert res["stats"][k] == pytest.approx(whole[k], abs=1e-9), k
    for k in ("median", "q68", "q90", "q95", "q99"):
        assert abs(res["stats"][k] - whole[k]) <= w / 2 + 1e-12, k
    assert abs(res["stats"]["nmad"] - whole["nmad"]) <= 1.4826 * w + 1e-12
    assert res["stats"]["histogram"] == whole["histogram"]
    for key, st in res["per_class"].items():
        ref = difference_stats(d[cls == float(key)])
        assert abs(st["median"] - ref["median"]) <= w / 2 + 1e-12
        assert abs(st["q95"] - ref["q95"]) <= w / 2 + 1e-12
        assert st["share_0_5"] == pytest.approx(ref["share_0_5"], abs=1e-12)


def test_accumulator_coarsens_bins():
    rng = np.random.default_rng(3)
    d = rng.uniform(-1000, 1000, 20_000)
    acc = DifferenceAccumulator(memory_budget=0, max_bins=1000)
    acc.add(d)
    res = acc.result()
    w = res["precision"]["bin_width"]
    assert w > 0.0005
    assert abs(res["stats"]["median"] - np.median(d)) <= w / 2 + 1e-9


def test_isprs_hand_made_vector():
    d = [0.0, 0.1, -0.1, 0.3, -0.2, 0.1, 0.0, 3.0, -0.1, 0.0, 10.0, np.nan]
    s = isprs_matching_stats(d, abs_bound=2.5)
    # sorted: -0.2 -0.1 -0.1 0 0 0 0.1 0.1 0.3 3 10  → MED = 0
    # |d - MED| sorted: 0 0 0 .1 .1 .1 .1 .2 .3 3 10 → MAD = 0.1
    assert s["P"] == 11
    assert (s["MIN"], s["MAX"]) == (-0.2, 10.0)
    assert s["MED"] == 0.0
    assert s["MAD"] == pytest.approx(0.1)
    assert s["sigma_MAD"] == pytest.approx(0.1 / 0.6745)
    # bounds ±0.4448: 3.0 and 10.0 are N+ outliers
    assert (s["N-"], s["N+"]) == (0, 2)
    assert s["N%"] == pytest.approx(200 / 11)
    assert (s["K-"], s["K+"], s["K%"]) == (0, 2, pytest.approx(200 / 11))
    assert s["P*"] == 9
    assert s["Bias"] == pytest.approx(0.1 / 9)
    ssq = 0.04 + 0.01 + 0.01 + 0.01 + 0.01 + 0.09 - 9 * (0.1 / 9) ** 2
    assert s["RMS"] == pytest.approx(math.sqrt(ssq / 8))
    s2 = isprs_matching_stats(d)
    assert s2["K-"] is None and s2["K%"] is None
    assert isprs_matching_stats(d, abs_bound=5.0)["K+"] == 1
    assert isprs_matching_stats([])["P"] == 0
