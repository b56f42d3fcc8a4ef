"""``photodem demo`` runs the whole chain: block → epipolar pairs → DSMs → merge → DTM → true
ortho mosaic, and georeferences an image against polygons."""

from __future__ import annotations

from pathlib import Path

import pytest

from photodem.algorithms.demo import run_demo
from photodem.algorithms.errors import PhotodemError


@pytest.mark.slow
def test_demo_runs_the_whole_chain_on_a_tiny_block(tmp_path) -> None:
    s = run_demo(tmp_path / "demo", size="tiny")
    surfaces = s["surfaces"]
    assert len(surfaces["models"]) == len(s["models"]) >= 2
    assert all(m["coverage_pct"] > 90 for m in surfaces["models"])
    assert Path(surfaces["dsm_merged"]).is_file() and Path(surfaces["dtm"]).is_file()
    dtm = surfaces["dtm_vs_truth"]
    assert dtm["count"] > 0 and abs(dtm["mean"]) < 1.0
    text = Path(s["summary"]).read_text(encoding="utf-8")
    assert "DTM | true DTM" in text and "merged DSM" in text
    assert s["georef"]["corner_error_px"] < 1.0 and "Georeferencing against polygons" in text
    # issue 19: object rows of every model DSM and the merged DSM, true-ortho occlusions
    objects = surfaces["objects"]
    assert [r["dsm"] for r in objects] == [m["name"] for m in s["models"]] + ["merged"]
    for r in objects:
        assert set(r) >= {"interior_0_5_pct", "objects_0_5_pct", "open_0_5_pct", "iou",
                          "wall_gsd", "buildings", "interior_buildings_0_5_pct",
                          "interior_crowns_0_5_pct"}
        assert r["open_0_5_pct"] is not None and 0.0 <= r["open_0_5_pct"] <= 100.0
    occ = surfaces["mosaic"]["occlusion"]
    assert len(occ["images"]) == s["images"]
    kept = list((Path(surfaces["dsm_merged"]).parent / "orthos").glob("*_visibility.tif"))
    assert len(kept) == s["images"] and occ["all"]["cells"] > 0
    assert occ["all"]["cells"] == sum(a["cells"] for a in occ["images"])
    assert "object interior within 0.5 m" in text and "truth visibility" in text
    assert "on tree crowns" in text


def test_demo_refuses_a_foreign_folder(tmp_path) -> None:
    (tmp_path / "mine.txt").write_text("operator data", encoding="utf-8")
    with pytest.raises(PhotodemError, match="not an earlier PhotoDEM demo"):
        run_demo(tmp_path, size="tiny")
    assert (tmp_path / "mine.txt").read_text(encoding="utf-8") == "operator data"
