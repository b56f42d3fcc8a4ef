"""Finding a project's products (issue 18 §1): kinds, names, side products skipped."""

from __future__ import annotations

import os
from pathlib import Path

from photodem.algorithms.output_policy import write_marker
from photodem.algorithms.project.products import (
    PRODUCT_KINDS,
    classify,
    find_products,
    is_inside,
)


def _touch(path: Path, mtime: float = 0.0) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(b"")
    if mtime:
        os.utime(path, (mtime, mtime))
    return path


def _folder(root: Path, rel: str, algorithm: str, *names: str) -> Path:
    folder = root / "products" / rel
    for name in names:
        _touch(folder / name)
    write_marker(folder, algorithm, "2026-01-01T00:00:00")
    return folder


def test_kinds_names_and_side_products(tmp_path):
    _folder(tmp_path, "dsm/0101_0102", "match_model", "dsm.tif", "count.tif", "sigma.tif",
            "points.gpkg", "report.html")
    _folder(tmp_path, "dtm/m1", "filter_lowpass", "dtm.tif", "ndsm.tif", "mask.tif")
    _folder(tmp_path, "cmp", "dem_compare", "difference.tif", "hillshade.tif", "slope.tif")
    _touch(tmp_path / "products" / "ortho" / "0203.tif")
    _touch(tmp_path / "products" / "ortho" / "0203_visibility.tif")
    _touch(tmp_path / "products" / "mosaic" / "mosaic.tif")
    _touch(tmp_path / "products" / "mosaic" / "mosaic_seamlines.gpkg")
    _touch(tmp_path / "products" / "mosaic" / ".mosaic.123.abcdef01.partial.tif")  # staged
    found = [(p.kind, p.name, p.path.name) for p in find_products(tmp_path)]
    assert found == [("dsm", "0101_0102", "dsm.tif"), ("dtm", "m1", "dtm.tif"),
                     ("difference", "cmp", "difference.tif"), ("ortho", "0203", "0203.tif"),
                     ("mosaic", "mosaic", "mosaic.tif"),
                     ("seamlines", "mosaic", "mosaic_seamlines.gpkg")]
    assert {k for k, _, _ in found} == set(PRODUCT_KINDS)
    assert find_products(tmp_path)[0].algorithm == "match_model"


def test_newest_first_within_a_kind(tmp_path):
    old = _folder(tmp_path, "dsm/a", "match_model", "dsm.tif") / "dsm.tif"
    new = _folder(tmp_path, "dsm/b", "match_model", "dsm.tif") / "dsm.tif"
    os.utime(old, (1e9, 1e9))
    os.utime(new, (2e9, 2e9))
    assert [p.name for p in find_products(tmp_path)] == ["b", "a"]


def test_untagged_by_name_and_outside_files(tmp_path):
    assert classify(_touch(tmp_path / "elsewhere" / "dtm.tif")).kind == "dtm"
    assert classify(_touch(tmp_path / "elsewhere" / "notes.txt")) is None
    assert classify(tmp_path / "missing.tif") is None
    assert find_products(tmp_path / "no_project") == []


def test_is_inside(tmp_path):
    assert is_inside(tmp_path / "a" / "b.tif", tmp_path)
    assert not is_inside(tmp_path.parent / "x.tif", tmp_path)
