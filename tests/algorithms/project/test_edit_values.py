"""Values of edits.gpkg that were used silently (issue 16, point 7): refused or repaired with a
warning that reaches the operator."""

from __future__ import annotations

import shutil
import warnings
from pathlib import Path

import fiona
import pytest
from shapely.geometry import LineString, Polygon

from photodem.algorithms import cli
from photodem.algorithms.crs_check import check_surface_crs, same_horizontal_crs
from photodem.algorithms.errors import InputError
from photodem.algorithms.feedback import Feedback
from photodem.algorithms.input_errors import InputWarning
from photodem.algorithms.processing import registry
from photodem.algorithms.project.edits import (
    check_action,
    create_edits,
    read_constraints,
    read_geometries,
    read_layer,
    repair_polygon,
)

BOWTIE = Polygon([(0, 0), (10, 10), (10, 0), (0, 10)])
SQUARE = Polygon([(0, 0), (10, 0), (10, 10), (0, 10)])


def _write(path: Path, layer: str, rows: list) -> None:
    """Append raw rows (bypassing add_features' checks, as QGIS would) to a layer."""
    from shapely.geometry import mapping

    from photodem.algorithms.project.edits import EDIT_LAYERS

    fields = EDIT_LAYERS[layer][1]
    with fiona.open(str(path), "a", driver="GPKG", layer=layer) as dst:
        dst.writerecords([{"geometry": mapping(g),
                           "properties": {k: p.get(k) for k in fields}} for g, p in rows])


@pytest.fixture
def edits(tmp_path: Path) -> Path:
    return create_edits(tmp_path / "edits.gpkg", "EPSG:25832")


# -- exclusion actions -------------------------------------------------------------------------
@pytest.mark.parametrize("value, expected", [
    (None, None), ("", None), ("  ", None), ("keep", "keep"), ("KEEP ", "keep"),
    ("remove", "remove"), ("Exclude", "exclude"),
])
def test_known_actions(value, expected) -> None:
    assert check_action(value, "x") == expected


@pytest.mark.parametrize("value", ["delete", "keepp", "0", "remove;keep"])
def test_unknown_action_is_refused_naming_the_feature(edits: Path, value: str) -> None:
    _write(edits, "exclusion_areas", [(SQUARE, {"action": "keep", "note": ""}),
                                      (SQUARE, {"action": value, "note": ""})])
    for read in (lambda: read_layer(edits, "exclusion_areas"),
                 lambda: read_constraints(edits, "EPSG:25832")):
        with pytest.raises(InputError) as info:
            read()
        text = str(info.value)
        assert "exclusion_areas" in text and "feature 2" in text and value in text
        assert "keep, remove, exclude" in text


def test_actions_are_normalised(edits: Path) -> None:
    _write(edits, "exclusion_areas", [(SQUARE, {"action": " Keep", "note": ""})])
    assert read_layer(edits, "exclusion_areas")[0][1]["action"] == "keep"
    assert read_constraints(edits)[0] == []  # keep areas are no exclusions for matching


# -- invalid polygons --------------------------------------------------------------------------
def test_a_bow_tie_is_repaired_with_a_warning(edits: Path) -> None:
    _write(edits, "exclusion_areas", [(BOWTIE, {"action": "remove", "note": ""})])
    with pytest.warns(InputWarning, match=r"exclusion_areas, feature 1.*invalid"):
        (geom, _), = read_layer(edits, "exclusion_areas")
    assert geom.is_valid and geom.area == pytest.approx(50.0)  # both triangles kept
    with pytest.warns(InputWarning, match="boundaries"):
        _write(edits, "boundaries", [(BOWTIE, {"name": "b"})])
        (poly,) = read_geometries(edits, ("Polygon",), None, ("boundaries",))
    assert poly.is_valid


def test_repair_polygon_leaves_valid_polygons_alone() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert repair_polygon(SQUARE, "x") is SQUARE


def test_a_polygon_with_nothing_left_is_refused() -> None:
    flat = Polygon([(0, 0), (10, 0), (20, 0), (0, 0)])
    with pytest.raises(InputError, match="redraw"):
        repair_polygon(flat, "'edits.gpkg' layer boundaries, feature 3")


# -- breaklines --------------------------------------------------------------------------------
def test_a_2d_breakline_is_used_as_barrier_with_a_warning(edits: Path) -> None:
    _write(edits, "breaklines", [(LineString([(0, 0, 5), (10, 10, 6)]), {"kind": "a"})])
    with warnings.catch_warnings():
        warnings.simplefilter("error", InputWarning)
        (line3,) = read_constraints(edits)[2]
    assert line3.has_z
    tmp = edits.with_name("flat.gpkg")
    with fiona.open(str(tmp), "w", driver="GPKG", layer="breaklines", crs="EPSG:25832",
                    schema={"geometry": "LineString", "properties": {"kind": "str"}}) as dst:
        dst.write({"geometry": {"type": "LineString", "coordinates": [(0, 0), (10, 10)]},
                   "properties": {"kind": "edge"}})
    with pytest.warns(InputWarning, match=r"breaklines, feature 1.*no heights"):
        (line2,) = read_geometries(tmp, ("LineString",), None, ("breaklines",))
    assert not line2.has_z


# -- the warning reaches the operator through the run's feedback ------------------------------
@pytest.fixture(scope="module")
def block(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("edits") / "p"
    registry.run("synthetic_block", {"output": str(root), "size": "tiny"})
    return root


def _project_with(block: Path, tmp_path: Path, layer: str, rows: list) -> Path:
    p = tmp_path / "p"
    shutil.copytree(block, p)
    _write(p / "edits.gpkg", layer, rows)
    return p


@pytest.mark.slow
def test_repair_warning_reaches_the_feedback(block: Path, tmp_path: Path) -> None:
    x0, y0 = 402290.0, 5674690.0
    bow = Polygon([(x0, y0), (x0 + 10, y0 + 10), (x0 + 10, y0), (x0, y0 + 10)])
    p = _project_with(block, tmp_path, "exclusion_areas", [(bow, {"action": "remove"})])
    fb = Feedback()
    registry.run("filter_lowpass", {"input": str(block / "truth" / "dsm.tif"),
                                    "project": str(p), "output": str(tmp_path / "f")}, fb)
    assert any("invalid" in w and "exclusion_areas" in w for w in fb.warnings), fb.warnings


@pytest.mark.slow
def test_unknown_action_through_the_cli(block: Path, tmp_path: Path, capsys) -> None:
    x0, y0 = 402290.0, 5674690.0
    sq = Polygon([(x0, y0), (x0 + 10, y0), (x0 + 10, y0 + 10), (x0, y0 + 10)])
    p = _project_with(block, tmp_path, "exclusion_areas", [(sq, {"action": "delete"})])
    out = tmp_path / "f"
    code = cli.main(["run", "filter_lowpass", "--input", str(block / "truth" / "dsm.tif"),
                     "--project", str(p), "--output", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err and err.count("photodem: error:") == 1, err
    assert "'delete'" in err and "feature 1" in err
    assert not out.exists()


# -- surfaces in another CRS -------------------------------------------------------------------
def test_check_surface_crs() -> None:
    from rasterio.crs import CRS

    assert check_surface_crs("d.tif", CRS.from_epsg(25832), "EPSG:25832")
    assert not check_surface_crs("d.tif", None, "EPSG:25832")  # none: caller warns
    assert check_surface_crs("d.tif", CRS.from_epsg(3857), "")  # no project CRS: no check
    with pytest.raises(InputError) as info:
        check_surface_crs("d.tif", CRS.from_epsg(3857), "EPSG:25832", "DSM")
    assert "EPSG:3857" in str(info.value) and "EPSG:25832" in str(info.value)
    assert same_horizontal_crs(CRS.from_user_input("EPSG:25832+5783"), "EPSG:25832")
