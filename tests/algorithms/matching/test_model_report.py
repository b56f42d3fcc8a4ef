"""The per-model matching report: JSON + self-contained HTML with tables and three maps."""

from __future__ import annotations

import base64
import json
import re

import numpy as np
import pytest
from affine import Affine

from photodem.algorithms.matching.model_report import (
    coverage_classes,
    levels_table,
    write_model_report,
)
from photodem.algorithms.raster.io import write_raster

T = Affine(2.0, 0.0, 400_000.0, 0.0, -2.0, 5_600_400.0)


@pytest.fixture(scope="module")
def rasters(tmp_path_factory):
    base = tmp_path_factory.mktemp("model")
    yy, xx = np.mgrid[0:200, 0:300]
    z = (100.0 + 0.05 * xx + 5.0 * np.sin(yy / 15.0)).astype(np.float32)
    z[150:180, 20:60] = np.nan  # a gap
    count = np.where(np.isfinite(z), (xx + yy) % 5, 0).astype(np.uint16)  # 0 = interpolated
    sigma = np.where(np.isfinite(z), 0.1 + 0.001 * xx, np.nan).astype(np.float32)
    return {
        "dsm": write_raster(base / "dsm.tif", z, T, "EPSG:25832"),
        "count": write_raster(base / "count.tif", count, T, "EPSG:25832", nodata=None),
        "sigma": write_raster(base / "sigma.tif", sigma, T, "EPSG:25832"),
    }


REPORT = {
    "model": "0182_0184",
    "method": "fbm_lsm",
    "images": ["0182", "0184"],
    "crs": "EPSG:25832",
    "flying_height_m": 1500.0,
    "metrics": {"points": 123456, "points_failed": 789, "coverage_pct": 97.25,
                "spacing_m": 2.0, "height_range_m": [90.0, 130.0], "extra_thing": "x"},
    "levels": [
        {"level": 3, "features": 1200, "candidates": 5400, "windows": 100,
         "failed_windows": 7, "accepted": 1100, "outliers": 12, "lsm_tried": 900,
         "lsm_failed": 30},
        {"level": 2, "features": 5000, "windows": 400, "failed_windows": 20,
         "failure_pct": 5.0, "accepted": 4700},
    ],
    "reduction": {"sigma1_m": 0.30, "sigma2_m": np.float64(0.1), "points_raw": 123456,
                  "points_reduced": 4000, "outliers": 321, "cell_m": 6.0, "mode": "l1"},
    "seconds": {"matching": 12.5, "reduction": 1.5, "total": 15.0},
    "options": {"preset": "hilly", "window": 11, "nan_value": float("nan")},
}


def _images(page: str):
    return re.findall(r'src="data:image/png;base64,([A-Za-z0-9+/=]+)"', page)


def test_report_writes_json_and_html_with_tables_and_three_maps(tmp_path, rasters) -> None:
    from shapely.geometry import box

    fails = np.array([[400_100.0, 5_600_300.0], [400_400.0, 5_600_100.0]])
    out = write_model_report(tmp_path / "rep", REPORT, dsm=rasters["dsm"],
                             sigma=rasters["sigma"], count=rasters["count"], failures=fails,
                             exclusions=[box(400_500.0, 5_600_050.0, 400_560.0, 5_600_100.0)])
    assert set(out) == {"json", "html"}
    data = json.loads(out["json"].read_text(encoding="utf-8"))
    assert data["model"] == "0182_0184" and data["reduction"]["sigma2_m"] == 0.1
    assert data["options"]["nan_value"] is None  # NaN → null: valid JSON
    page = out["html"].read_text(encoding="utf-8")
    images = _images(page)
    assert len(images) == 3
    for b64 in images:
        assert base64.b64decode(b64)[:8] == b"\x89PNG\r\n\x1a\n"
    # headline: counts, coverage, σ1/σ2 in m and ‰ H (0.30 m / 1500 m = 0.200 ‰)
    for text in ("0182_0184", "fbm_lsm", "123\u202f456", "4\u202f000", "789", "97.2 %",
                 "0.300 m = 0.200 ‰ H", "0.100 m = 0.067 ‰ H", "15.0 s", "hilly"):
        assert text in page, text
    # the per-level table: generic columns, failure share derived where missing
    assert "lsm tried" in page and "failed windows" in page
    assert "7.0 %" in page and "5.0 %" in page
    assert not [p for p in (tmp_path / "rep").iterdir() if "partial" in p.name]


def test_missing_keys_do_not_crash(tmp_path, rasters) -> None:
    out = write_model_report(tmp_path / "min", {}, dsm=rasters["dsm"])
    page = out["html"].read_text(encoding="utf-8")
    assert len(_images(page)) == 2  # no σ map without a σ raster
    assert "No per-level statistics" in page
    assert json.loads(out["json"].read_text(encoding="utf-8")) == {}
    odd = {"levels": ["not a dict", {"level": 1}], "metrics": None, "reduction": "?",
           "seconds": {"a": "slow"}, "images": None}
    out = write_model_report(tmp_path / "odd", odd, dsm=rasters["dsm"],
                             sigma=tmp_path / "missing.tif")
    assert "<table" in out["html"].read_text(encoding="utf-8")


def test_coverage_classes() -> None:
    z = np.array([[1.0, 1.0], [np.nan, 1.0]])
    count = np.array([[3.0, 0.0], [0.0, 1.0]])
    excl = np.array([[False, False], [False, True]])
    np.testing.assert_array_equal(coverage_classes(z, count, excl), [[1, 2], [3, 4]])
    np.testing.assert_array_equal(coverage_classes(z, None, None), [[1, 1], [3, 1]])


def test_levels_table_is_generic() -> None:
    table = levels_table([{"module": "fbm", "b": 1}, {"a_pct": 12.345, "module": "lsm"}])
    head = re.findall(r"<th>(.*?)</th>", table)
    assert head == ["module", "b", "a [%]"]
    assert "12.3 %" in table


def test_coverage_sentence_says_what_the_slant_passes_measured() -> None:
    from photodem.algorithms.matching.model_report import coverage_sentence

    plain = {"measured_pct": 70.0, "interpolated_pct": 2.0, "empty_pct": 28.0,
             "valid_disparity_pct": 75.0}
    assert "slant" not in coverage_sentence(plain)
    text = coverage_sentence({**plain, "slant_measured_pct": 4.25})
    assert "measured 70.0 % (slant passes alone 4.2 %)" in text
    text = coverage_sentence({**plain, "slant_measured_pct": 4.25, "guided_measured_pct": 1.5})
    assert "measured 70.0 % (slant passes alone 4.2 %; guided pass 1.5 %)" in text
