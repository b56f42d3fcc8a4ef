"""The HTML/JSON/CSV report, and dem_compare end to end on the synthetic truth (acceptance)."""

from __future__ import annotations

import base64
import csv
import json
import re
from pathlib import Path

import numpy as np
import pytest
import rasterio
from affine import Affine

from photodem.algorithms.errors import Cancelled, InputError
from photodem.algorithms.feedback import Feedback
from photodem.algorithms.processing import registry
from photodem.algorithms.quality.report import (
    box_summary,
    csv_rows,
    read_decimated,
    signed_histogram,
    stats_entries,
    write_report,
)
from photodem.algorithms.quality.stats import difference_stats
from photodem.algorithms.raster.io import write_raster

T = Affine(1.0, 0.0, 400_000.0, 0.0, -1.0, 5_600_000.0)


@pytest.fixture(scope="module")
def rasters(tmp_path_factory):
    base = tmp_path_factory.mktemp("report")
    rng = np.random.default_rng(5)
    dz = rng.normal(0.1, 0.3, (400, 600))
    dz[:50, :50] = np.nan
    dz[300:320, 300:320] += 8.0  # a block of blunders
    diff = write_raster(base / "difference.tif", dz.astype(np.float32), T, "EPSG:25832")
    hs = write_raster(base / "hillshade.tif",
                      rng.integers(1, 256, (400, 600)).astype(np.uint8), T, "EPSG:25832",
                      nodata=0)
    return base, diff, hs, dz.astype(np.float32).astype(np.float64)


def test_signed_histogram_is_exact_by_strips(rasters) -> None:
    _, diff, _, dz = rasters
    h = signed_histogram(diff, 2.0, 40, window_rows=37)
    v = dz[np.isfinite(dz)]
    np.testing.assert_array_equal(h["counts"], np.histogram(v, bins=np.linspace(-2, 2, 41))[0])
    assert h["over"] == int(np.count_nonzero(v > 2.0))
    assert h["under"] == int(np.count_nonzero(v < -2.0))


def test_read_decimated_bounds_the_size(rasters) -> None:
    _, diff, _, _ = rasters
    arr, transform, crs = read_decimated(diff, max_pixels=100)
    assert arr.shape == (67, 100)
    assert transform.a == pytest.approx(6.0) and transform.c == T.c and crs == "EPSG:25832"


def test_box_summary_from_statistics() -> None:
    stats = {"count": 5, "median": 1.0, "nmad": 1.4826 * 0.5, "min": -3.0, "max": 9.0,
             "q95": 2.0, "mean": 1.5}
    box = box_summary("a", stats)
    assert box["q1"] == pytest.approx(0.5) and box["q3"] == pytest.approx(1.5)
    assert box["whislo"] == -2.0 and box["whishi"] == 2.0 and box["fliers"] == [-3.0, 9.0]
    assert stats_entries({"x": stats, "y": {"stats": stats}, "z": 3}) == [("x", stats),
                                                                          ("y", stats)]


def test_report_is_self_contained_with_units(rasters, tmp_path: Path) -> None:
    _, diff, hs, dz = rasters
    stats = difference_stats(dz, flying_height=1500.0)
    result = {"stats": stats, "shift": {"dx": 0.5, "dy": -0.25, "dz": 0.1, "iterations": 3,
                                        "converged": True},
              "per_class": {"1": difference_stats(dz[:200], 1500.0),
                            "2": difference_stats(dz[200:], 1500.0)},
              "per_slope": {"0–5°": difference_stats(dz[:, :300], 1500.0),
                            "5–10°": difference_stats(dz[:, 300:], 1500.0)},
              "grid": {"crs": "EPSG:25832", "width": 600, "height": 400}}
    page = write_report(tmp_path / "r.html", result, dem="dsm.tif", reference="ref.tif",
                        difference=diff, hillshade=hs, flying_height=1500.0).read_text()
    images = re.findall(r'src="data:image/png;base64,([^"]+)"', page)
    assert len(images) == 4  # histograms, map, boxes by class, error vs slope
    assert all(base64.b64decode(i)[:8] == b"\x89PNG\r\n\x1a\n" for i in images)
    assert "http" not in page and "<script" not in page  # nothing fetched from outside
    for text in ("Δh = DEM − reference", "‰ H", "|Δh| [m]", "&gt; 5.0", "dsm.tif",
                 "co-registration shift", "slope class [°]", "RMS ‰ H"):
        assert text in page, text
    # the same inputs give the same bytes (the faces compare report files byte by byte)
    again = write_report(tmp_path / "r2.html", result, dem="dsm.tif", reference="ref.tif",
                         difference=diff, hillshade=hs, flying_height=1500.0).read_text()
    assert again == page
    rows = csv_rows(result, 1500.0)
    assert rows[0][:4] == ["scope", "name", "count", "mean"] and "n_over_5" in rows[0]
    assert [r[0] for r in rows[1:]] == ["all", "class", "class", "slope", "slope"]
    assert float(rows[1][rows[0].index("rms_permille")]) == pytest.approx(
        1000 * stats["rms"] / 1500.0, abs=1e-6)


# -- acceptance: the synthetic block's truth DSM against its truth DTM -----------------------------
@pytest.fixture(scope="module")
def truth(tmp_path_factory):
    out = tmp_path_factory.mktemp("truth") / "block"
    return registry.run("synthetic_block", {"output": str(out), "size": "tiny"})


@pytest.mark.slow
def test_truth_dsm_against_dtm_per_class(truth, tmp_path: Path) -> None:
    import fiona
    from rasterio.features import rasterize
    from shapely.geometry import shape

    out = tmp_path / "cmp"
    r = registry.run("dem_compare", {"dem": truth["truth_dsm"], "reference": truth["truth_dtm"],
                                     "classes": truth["truth_landcover"], "output": str(out),
                                     "flying_height": truth["flying_height_m"]})
    per = r["per_class"]
    # open terrain, road, water/ditch, embankment, field: DSM = DTM exactly
    for code in ("1", "2", "5", "6", "7"):
        s = per[code]
        assert s["count"] > 0
        assert s["min"] == 0.0 and s["max"] == 0.0 and s["mean"] == 0.0 and s["rms"] == 0.0
    # buildings: per cell the roof height above the platform
    with fiona.open(truth["truth_buildings"]) as src:
        buildings = [(shape(f["geometry"]), f["properties"]) for f in src]
    with rasterio.open(r["difference"]) as src:
        diff, transform = src.read(1), src.transform
    b = per["3"]
    assert b["min"] >= min(p["height"] for _, p in buildings) - 1e-3
    assert b["max"] <= max(p["ridge_height"] for _, p in buildings) + 1e-3
    flat = [(g, p) for g, p in buildings if p["roof"] == "flat"]
    assert flat
    for geom, props in flat:  # cells well inside a flat roof: Δh = the building height
        inner = rasterize([(geom.buffer(-0.5), 1)], out_shape=diff.shape,
                          transform=transform).astype(bool)
        assert inner.sum() > 100
        np.testing.assert_allclose(diff[inner], props["height"], atol=2e-3)
    # trees: positive up to the highest crown
    t = per["4"]
    assert t["min"] > 0.0 and t["max"] <= 20.0 + 1e-3
    # everything was written, and the style sits beside the difference model
    names = sorted(p.name for p in out.iterdir())
    assert names == [".photodem-product.json", "completeness.csv", "difference.qml",
                     "difference.tif", "hillshade.tif", "report.html", "slope.tif", "stats.csv",
                     "stats.json"]
    saved = json.loads((out / "stats.json").read_text())
    assert saved["dem"] == "dsm.tif" and saved["files"]["difference"] == "difference.tif"
    # the legend style beside the land-cover raster names the codes; the report shows the
    # project-relative paths of the compared files
    assert r["class_names"]["3"] == "building" and saved["class_names"]["4"] == "tree / forest"
    page = (out / "report.html").read_text(encoding="utf-8")
    assert "building (3)" in page and "road (2)" in page
    project = Path(truth["project"]).name
    assert f"{project}/truth/dsm.tif" in page and f"{project}/truth/dtm.tif" in page
    assert saved["per_class"]["3"]["count"] == b["count"] and r["shift"] is None
    with open(out / "stats.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [row["name"] for row in rows if row["scope"] == "class"] == list(per)


@pytest.mark.slow
def test_dem_compare_bad_input_and_cancel(truth, tmp_path: Path) -> None:
    params = {"dem": truth["truth_dsm"], "reference": truth["truth_dtm"],
              "classes": truth["truth_buildings"], "class_field": "nope",
              "output": str(tmp_path / "bad")}
    with pytest.raises(InputError, match=r"no attribute 'nope'.*roof") as err:
        registry.run("dem_compare", params)
    assert "\n" not in str(err.value)
    assert not (tmp_path / "bad").exists()
    fb = Feedback(on_progress=lambda pct: fb.cancel() if pct > 50 else None)
    with pytest.raises(Cancelled):
        registry.run("dem_compare", {"dem": truth["truth_dsm"],
                                     "reference": truth["truth_dtm"],
                                     "output": str(tmp_path / "cancelled")}, fb)
    assert list(tmp_path.iterdir()) == []
