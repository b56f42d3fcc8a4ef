"""How reports name files: project-relative or absolute paths, distinct short names."""

from __future__ import annotations

from pathlib import Path

from photodem.algorithms.quality.names import distinct_names, report_path


def test_report_path_is_project_relative_inside_a_project(tmp_path: Path) -> None:
    project = tmp_path / "block_7"
    (project / "products" / "dsm" / "m1").mkdir(parents=True)
    (project / "project.toml").write_text("", encoding="utf-8")
    inside = project / "products" / "dsm" / "m1" / "dsm.tif"
    assert report_path(inside) == "block_7/products/dsm/m1/dsm.tif"
    outside = tmp_path / "loose" / "dtm.tif"
    assert report_path(outside) == outside.absolute().as_posix()


def test_distinct_names_add_folders_only_where_needed() -> None:
    names = distinct_names(["/p/m1/dtm.tif", "/p/m2/dtm.tif", "/p/m1/dsm.tif",
                            "/q/x/m1/dtm.tif"])
    assert names == ["p/m1/dtm", "m2/dtm", "dsm", "x/m1/dtm"]
    assert len(set(names)) == 4
    assert distinct_names(["/a/dtm.tif", "/a/dtm.tif"]) == ["dtm", "dtm_2"]
    assert distinct_names(["fine.tif", "coarse.tif"]) == ["fine", "coarse"]
