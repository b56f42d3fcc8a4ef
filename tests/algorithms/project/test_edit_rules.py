"""The rules of a new edit shared by the QGIS toolbar and the standalone map (issue 21):
point heights, polygon repair, breakline crossings and heights, seamline snapping, validation."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import pytest
from shapely.geometry import LineString, Polygon

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # tests/: the shared click table
from edit_clicks import (
    BOW_TIE,
    CLICKS,
    CROSSING_BREAKLINE,
    INTERPOLATED,
    ON_NODATA,
    OUTSIDE_MODELS,
    surface_z,
    write_surface,
)

from photodem.algorithms.errors import InputError
from photodem.algorithms.project import edit_rules
from photodem.algorithms.project.model import Project


@pytest.fixture(scope="module")
def block(tmp_path_factory):
    """The tiny synthetic block and the analytic plane beside it."""
    from photodem.algorithms.processing import registry

    root = tmp_path_factory.mktemp("rules") / "block"
    registry.run("synthetic_block", {"output": str(root), "size": "tiny"})
    surface = write_surface(root.parent / "plane.tif")
    return Project.load(root), str(surface)


def breakline_coords():
    return next(c for c in CLICKS if c["layer"] == "breaklines")["clicks"]


def test_point_start_has_the_surface_height(block):
    project, surface = block
    x, y = CLICKS[0]["clicks"][0]
    z, reason = edit_rules.sample_surface(surface, x, y, project.crs)
    start = edit_rules.point_start(project, "start_points", x, y, z, reason)
    assert not start.outside_models and start.z == pytest.approx(surface_z(x, y), abs=1e-6)


def test_start_point_outside_the_models_gets_a_typed_height(block):
    project, surface = block
    z, reason = edit_rules.sample_surface(surface, *OUTSIDE_MODELS, project.crs)
    assert z is not None  # the surface covers it, but no model does
    start = edit_rules.point_start(project, "start_points", *OUTSIDE_MODELS, z, reason)
    assert start.outside_models and start.z is None
    ground = edit_rules.point_start(project, "ground_points", *OUTSIDE_MODELS, z, reason)
    assert not ground.outside_models and ground.z == z


def test_nodata_has_no_height_and_a_reason(block):
    project, surface = block
    z, reason = edit_rules.sample_surface(surface, *ON_NODATA, project.crs)
    assert z is None and "nodata" in reason
    assert edit_rules.sample_surface(None, *ON_NODATA, project.crs) == (None, "")


@pytest.mark.parametrize("layer,key", [("ground_points", "note"), ("check_points", "id")])
def test_point_features(layer, key):
    geometry, attributes = edit_rules.point_feature(layer, 1.0, 2.0, 3.0, "x")
    assert (geometry.x, geometry.y, geometry.z) == (1.0, 2.0, 3.0) and attributes == {key: "x"}
    start, attributes = edit_rules.point_feature("start_points", 1.0, 2.0, 3.0, "")
    assert not start.has_z and attributes == {"height": 3.0, "note": None}


def test_bow_tie_is_refused_or_repaired_in_two_parts():
    check = edit_rules.polygon_check(Polygon(BOW_TIE))
    assert check.problems and "Self-intersection" in check.text
    assert check.locations and check.locations[0] == pytest.approx((402300.0, 5674700.0))
    parts = edit_rules.polygon_parts(check.repaired)
    assert len(parts) == 2 and all(p.is_valid for p in parts)
    assert not edit_rules.polygon_check(Polygon(CLICKS[3]["clicks"])).problems


def test_polygon_attributes():
    assert edit_rules.polygon_attributes("exclusion_areas", ("keep", "")) == {
        "action": "keep", "note": None}
    assert edit_rules.polygon_attributes("boundaries", "A") == {"name": "A"}


def test_crossing_breakline_is_found():
    existing = [LineString(breakline_coords())]
    crossings = edit_rules.breakline_crossings(CROSSING_BREAKLINE, existing)
    assert len(crossings) == 1
    x, y = crossings[0].location
    assert abs(x - 402285.0) < 1.0 and abs(y - 5674707.5) < 1.0
    assert not edit_rules.breakline_crossings(INTERPOLATED["clicks"], existing)


def test_breakline_draped_typed_and_interpolated(block):
    project, surface = block
    coords = breakline_coords()
    drape = edit_rules.breakline_prefill(surface, coords, "drape", project.crs)
    assert drape.editable == [False] * 3
    assert drape.heights == pytest.approx([surface_z(*xy) for xy in coords], abs=1e-6)
    typed = edit_rules.breakline_prefill(surface, coords, "typed", project.crs)
    assert typed.editable == [True] * 3 and typed.heights == drape.heights
    over_nodata = edit_rules.breakline_prefill(surface, [coords[0], ON_NODATA], "drape",
                                               project.crs)
    assert over_nodata.editable == [False, True] and over_nodata.reason
    inter = edit_rules.breakline_prefill(None, INTERPOLATED["clicks"], "interpolate")
    assert inter.editable == [True, False, True] and inter.heights == [None] * 3
    z0, z1 = INTERPOLATED["ends"]
    line, attributes = edit_rules.breakline_feature(INTERPOLATED["clicks"], [z0, None, z1],
                                                    "interpolate", "breakline")
    pts = INTERPOLATED["clicks"]
    s = [0.0, math.dist(pts[0], pts[1]), math.dist(pts[0], pts[1]) + math.dist(pts[1], pts[2])]
    assert [c[2] for c in line.coords] == pytest.approx([z0 + (z1 - z0) * v / s[-1] for v in s])
    assert attributes == {"kind": "breakline"}
    with pytest.raises(InputError, match="needs a height"):
        edit_rules.breakline_feature(coords, [1.0, None, 2.0], "typed", "breakline")


def test_seamline_snaps_within_the_tolerance():
    mosaic = [LineString([(402301.0, 5674600.0), (402301.0, 5674800.0)])]
    clicks = next(c for c in CLICKS if c["layer"] == "seamlines")["clicks"]
    line, attributes = edit_rules.seamline_feature(clicks, mosaic, 2.0)
    assert [c[0] for c in line.coords] == pytest.approx([402301.0, 402301.0])
    far, _ = edit_rules.seamline_feature(clicks, mosaic, 0.5)
    assert [c[0] for c in far.coords] == [402300.0, 402300.0] and attributes == {}


def test_verdict_refuses_outside_the_block_and_passes_a_good_point(block):
    project, _ = block
    geometry, attributes = edit_rules.point_feature("ground_points", 402232.0, 5674785.0, 50.0)
    bad, _ = edit_rules.verdict("ground_points", geometry, attributes, project)
    assert bad and "outside the project's block" in bad[0].message
    x, y = CLICKS[1]["clicks"][0]
    geometry, attributes = edit_rules.point_feature("ground_points", x, y, surface_z(x, y))
    assert edit_rules.verdict("ground_points", geometry, attributes, project)[0] == []
