"""Coverage figures say what was measured: both methods report the shares of the model area
that are measured, interpolated and empty (adding up to 100 %), fbm_lsm its failed windows at
the finest level, and the run log line says them (a tiny synthetic model)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from photodem.algorithms.feedback import Feedback
from photodem.algorithms.processing import registry

pytestmark = pytest.mark.slow
MODEL = "0102_0103"


@pytest.fixture(scope="module")
def block(tmp_path_factory):
    out = tmp_path_factory.mktemp("coverage_split") / "block"
    return registry.run("synthetic_block", {"size": "tiny", "terrain": "gentle", "seed": 3,
                                            "output": str(out)})


def run(block, method: str, out: Path) -> tuple:
    fb = Feedback()
    res = registry.run("match_model", {"project": block["project"], "model": MODEL,
                                       "method": method, "output": str(out)}, fb)
    return res, fb


def check_split(m: dict) -> None:
    total = m["measured_pct"] + m["interpolated_pct"] + m["empty_pct"]
    assert total == pytest.approx(100.0, abs=1e-9)
    assert m["coverage_pct"] == pytest.approx(m["measured_pct"] + m["interpolated_pct"])
    assert min(m["measured_pct"], m["interpolated_pct"], m["empty_pct"]) >= 0.0


@pytest.mark.parametrize("method", ["fbm_lsm", "dense"])
def test_measured_interpolated_empty(block, tmp_path, method: str) -> None:
    res, fb = run(block, method, tmp_path / method)
    m = res["metrics"]
    check_split(m)
    # holes were filled: the old single figure (coverage) overstates what was measured
    assert m["interpolated_pct"] > 0.0 and m["measured_pct"] < m["coverage_pct"]
    line = next(t for t in fb.lines if t.startswith(f"Model {MODEL}:") and "measured" in t)
    assert f"measured {m['measured_pct']:.1f} %" in line
    assert f"interpolated {m['interpolated_pct']:.1f} %" in line
    if method == "fbm_lsm":
        assert 0.0 <= m["failed_windows_finest_pct"] <= 100.0
        assert "failed windows at the finest level" in line
    else:
        assert "valid disparities" in line and "filled_pct" not in m
    with open(res["report"], encoding="utf-8") as f:
        assert json.load(f)["metrics"]["interpolated_pct"] == pytest.approx(
            m["interpolated_pct"])
    html = Path(res["report_html"]).read_text(encoding="utf-8")
    assert "interpolated" in html and "empty" in html
    print(f"{method}: measured {m['measured_pct']:.1f} %, interpolated "
          f"{m['interpolated_pct']:.1f} %, empty {m['empty_pct']:.1f} %, coverage "
          f"{m['coverage_pct']:.1f} %")
