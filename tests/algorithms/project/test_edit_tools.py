"""The Qt-free core of the editing tools (issue 18 §4): heights from a surface, draping, crossing
and polygon checks, one edit's validation, snapping, the models at a point."""

from __future__ import annotations

import warnings
from pathlib import Path

import fiona
import numpy as np
import pyproj
import pytest
import rasterio
from affine import Affine
from shapely.geometry import LineString, MultiLineString, Point, Polygon, mapping

from photodem.algorithms.errors import InputError
from photodem.algorithms.geometry.camera import Camera
from photodem.algorithms.geometry.orientation import ExteriorOrientation
from photodem.algorithms.project import edit_tools
from photodem.algorithms.project.edit_checks import (
    block_area,
    check_new_breakline,
    check_new_polygon,
    errors,
    models_at,
    plausible_heights,
    validate_edit,
)
from photodem.algorithms.project.edit_tools import (
    NODATA,
    OUTSIDE,
    drape_line,
    mosaic_seamlines,
    sample_height,
    snap_to_lines,
)
from photodem.algorithms.project.model import ImageRecord, Project
from photodem.algorithms.project.stereo_models import block_footprints, manual_model

# -- an analytic DEM: z = A + B·x + C·y + D·x·y is reproduced exactly by bilinear interpolation
A, B, C, D = 250.0, 0.03, -0.02, 1e-5
X0, Y0, CELL, W, H = 500000.0, 5400000.0, 2.0, 60, 40
NODATA_CELL = (10, 20)  # row, col


def analytic(x, y):
    x = np.asarray(x, dtype=float) - X0  # local coordinates keep the product term small
    y = np.asarray(y, dtype=float) - Y0
    return A + B * x + C * y + D * x * y


def _write_dem(path: Path, crs: object = "EPSG:25832", nodata: float = -9999.0) -> Path:
    t = Affine(CELL, 0.0, X0, 0.0, -CELL, Y0)
    cols, rows = np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5)
    x, y = t * (cols, rows)
    z = analytic(x, y)
    z[NODATA_CELL] = nodata
    profile = {"driver": "GTiff", "width": W, "height": H, "count": 1, "dtype": "float64",
               "transform": t, "nodata": nodata}
    if crs is not None:
        profile["crs"] = crs
    with rasterio.open(path, "w", **profile) as dst:
        dst.write(z, 1)
    return path


@pytest.fixture(scope="module")
def dem(tmp_path_factory) -> Path:
    return _write_dem(tmp_path_factory.mktemp("dem") / "dsm.tif")


# -- sample_height -------------------------------------------------------------------------------
@pytest.mark.parametrize("dx, dy", [(3.3, -7.7), (60.123, -41.9), (101.01, -3.14159),
                                    (1.0, -1.0), (118.999, -78.999)])
def test_sample_height_is_the_analytic_surface(dem: Path, dx: float, dy: float) -> None:
    x, y = X0 + dx, Y0 + dy  # off the grid, inside the hull of cell centres
    s = sample_height(dem, x, y)
    assert s.ok and s.reason is None
    assert s.z == pytest.approx(float(analytic(x, y)), abs=1e-6)


def test_sample_height_in_another_crs_is_reprojected(dem: Path) -> None:
    x, y = X0 + 55.55, Y0 - 33.33
    lon, lat = pyproj.Transformer.from_crs("EPSG:25832", "EPSG:4326",
                                           always_xy=True).transform(x, y)
    s = sample_height(dem, lon, lat, crs="EPSG:4326")
    assert s.z == pytest.approx(float(analytic(x, y)), abs=1e-6)
    assert sample_height(dem, x, y, crs="EPSG:25832").z == pytest.approx(s.z, abs=1e-6)
    # metres taken for degrees: no position in the surface's CRS, outside, and no warning
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert sample_height(dem, x, y, crs="EPSG:4326").cause == OUTSIDE


def test_outer_half_cell_takes_the_edge_value(dem: Path) -> None:
    # between the raster's edge and the first cell centre: the edge cell's column value
    s = sample_height(dem, X0 + 0.4, Y0 - 10.0)
    assert s.z == pytest.approx(float(analytic(X0 + 1.0, Y0 - 10.0)), abs=1e-6)


@pytest.mark.parametrize("x, y", [(X0 - 0.01, Y0 - 10.0), (X0 + 10.0, Y0 + 0.5),
                                  (X0 + W * CELL + 1.0, Y0 - 10.0), (0.0, 0.0)])
def test_outside_the_raster_says_so(dem: Path, x: float, y: float) -> None:
    s = sample_height(dem, x, y)
    assert s.z is None and s.cause == OUTSIDE
    assert "outside the surface 'dsm.tif'" in s.reason and "type the height" in s.reason


def test_nodata_says_so(dem: Path) -> None:
    r, c = NODATA_CELL
    x, y = X0 + (c + 0.5) * CELL, Y0 - (r + 0.5) * CELL
    for dx, dy in [(0.0, 0.0), (0.7, 0.3), (-1.5, -0.2)]:  # on and next to the cell
        s = sample_height(dem, x + dx, y + dy)
        assert s.z is None and s.cause == NODATA and "nodata" in s.reason
    # two cells away the neighbours are valid again
    assert sample_height(dem, x + 2.5, y).z == pytest.approx(float(analytic(x + 2.5, y)),
                                                             abs=1e-6)


def test_surface_without_crs_and_a_point_with_one(tmp_path: Path) -> None:
    path = _write_dem(tmp_path / "nocrs.tif", crs=None)
    with pytest.raises(InputError, match=r"'nocrs\.tif' has no CRS"):
        sample_height(path, X0 + 5, Y0 - 5, crs="EPSG:25832")
    # without a point CRS the point is taken in the surface's coordinates
    assert sample_height(path, X0 + 5, Y0 - 5).ok


def test_missing_surface(tmp_path: Path) -> None:
    with pytest.raises(InputError, match=r"'.*gone\.tif' not found"):
        sample_height(tmp_path / "gone.tif", 0, 0)


def test_only_a_window_is_read(dem: Path, monkeypatch) -> None:
    seen = []
    real = rasterio.io.DatasetReader.read

    def spy(self, *args, **kwargs):
        seen.append(kwargs.get("window"))
        return real(self, *args, **kwargs)

    monkeypatch.setattr(rasterio.io.DatasetReader, "read", spy)
    sample_height(dem, X0 + 30.3, Y0 - 20.2)
    assert len(seen) == 1 and seen[0] is not None
    assert seen[0].width <= 2 and seen[0].height <= 2


def test_far_apart_points_are_read_one_small_window_each(dem: Path, monkeypatch) -> None:
    seen = []
    real = rasterio.io.DatasetReader.read

    def spy(self, *args, **kwargs):
        seen.append(kwargs.get("window"))
        return real(self, *args, **kwargs)

    coords = [(X0 + 3.3, Y0 - 3.3), (X0 + 61.7, Y0 - 41.1), (X0 + 117.5, Y0 - 77.7)]
    whole = drape_line(dem, coords)
    monkeypatch.setattr(rasterio.io.DatasetReader, "read", spy)
    monkeypatch.setattr(edit_tools, "MAX_WINDOW_CELLS", 16)
    split = drape_line(dem, coords)
    assert len(seen) == 3 and all(w.width * w.height <= 4 for w in seen)
    assert [c[2] for c in split.coords] == pytest.approx([c[2] for c in whole.coords], abs=1e-9)


def test_unreadable_surface_and_unknown_crs(dem: Path, tmp_path: Path) -> None:
    bad = tmp_path / "text.tif"
    bad.write_text("not a raster")
    with pytest.raises(InputError, match=r"text\.tif"):
        sample_height(bad, 0, 0)
    with pytest.raises(InputError, match="not understood"):
        sample_height(dem, X0 + 5, Y0 - 5, crs="EPSG:999999")


# -- drape_line ----------------------------------------------------------------------------------
def test_drape_line_follows_the_surface(dem: Path) -> None:
    coords = [(X0 + 5.5, Y0 - 5.25, 999.0), (X0 + 77.7, Y0 - 30.1), (X0 + 110.0, Y0 - 70.3)]
    d = drape_line(dem, coords)
    assert d.ok and d.reason is None
    for (x, y, z), c in zip(d.coords, coords):
        assert (x, y) == c[:2]
        assert z == pytest.approx(float(analytic(x, y)), abs=1e-6)
    assert d.line().has_z


def test_drape_line_reports_vertices_without_height(dem: Path) -> None:
    r, c = NODATA_CELL
    on_nodata = (X0 + (c + 0.5) * CELL, Y0 - (r + 0.5) * CELL)
    d = drape_line(dem, [(X0 + 5, Y0 - 5), on_nodata, (X0 - 50, Y0 - 5)])
    assert d.missing == [1, 2]
    assert "2 of 3 vertices" in d.reason and "1 outside it, 1 on nodata" in d.reason
    assert np.isnan(d.coords[1][2]) and np.isfinite(d.coords[0][2])


def test_interpolate_between_end_heights() -> None:
    d = drape_line(None, [(0, 0), (3, 4), (3, 10)], mode="interpolate", end_heights=(10, 21))
    assert [z for _, _, z in d.coords] == pytest.approx([10.0, 15.0, 21.0])


@pytest.mark.parametrize("kwargs, match", [
    ({"mode": "interpolate"}, "Type the heights of the first and the last vertex"),
    ({"mode": "interpolate", "end_heights": (1.0, float("nan"))}, "must be numbers"),
    ({"mode": "sideways"}, "not one of drape, interpolate"),
    ({"mode": "drape"}, "Choose a surface"),
])
def test_drape_line_bad_input(kwargs, match) -> None:
    with pytest.raises(InputError, match=match):
        drape_line(None, [(0, 0), (1, 1)], **kwargs)


def test_drape_line_needs_two_vertices(dem: Path) -> None:
    with pytest.raises(InputError, match="at least two vertices"):
        drape_line(dem, [(X0 + 1, Y0 - 1)])


# -- crossings and polygons ---------------------------------------------------------------------
def test_new_breakline_crossing_an_existing_one_is_marked() -> None:
    existing = [LineString([(0, 20), (10, 20)]), LineString([(0, 10, 1), (10, 0, 2)])]
    problems = check_new_breakline(LineString([(0, 0, 1), (10, 10, 2)]), existing)
    assert len(problems) == 1
    assert problems[0].location == pytest.approx((5.0, 5.0))
    assert "crosses breakline 2 at (5.00, 5.00)" in problems[0].message


def test_new_breakline_continuing_one_is_allowed_but_a_t_junction_is_not() -> None:
    existing = [LineString([(0, 0), (10, 0)])]
    assert check_new_breakline(LineString([(10, 0), (20, 5)]), existing) == []
    t = check_new_breakline(LineString([(5, 0), (5, 10)]), existing)
    assert len(t) == 1 and t[0].location == pytest.approx((5.0, 0.0))


def test_new_breakline_crossing_itself() -> None:
    problems = check_new_breakline(LineString([(0, 0), (10, 10), (10, 0), (0, 10)]), [])
    assert [p.location for p in problems] == [pytest.approx((5.0, 5.0))]
    assert "crosses itself at (5.00, 5.00)" in problems[0].message


def test_closed_breakline_is_not_a_crossing() -> None:
    ring = LineString([(0, 0), (10, 0), (10, 10), (0, 0)])
    assert check_new_breakline(ring, []) == []


def test_bow_tie_polygon_gets_a_repaired_candidate() -> None:
    bowtie = Polygon([(0, 0), (10, 10), (10, 0), (0, 10)])
    check = check_new_polygon(bowtie)
    assert not check.ok and check.repaired is not None and check.repaired.is_valid
    assert check.repaired.area == pytest.approx(50.0)
    assert "Self-intersection" in check.problems[0].message
    assert check.problems[0].location == pytest.approx((5.0, 5.0))
    assert check_new_polygon(Polygon([(0, 0), (1, 0), (1, 1)])).ok


# -- snapping ------------------------------------------------------------------------------------
def test_snap_prefers_a_vertex_within_tolerance() -> None:
    lines = [LineString([(0, 0), (10, 0)]), LineString([(0, 3), (10, 3)])]
    s = snap_to_lines((9.5, 0.4), lines, tolerance=1.0)
    assert s.point == (10.0, 0.0) and s.line == 0 and s.vertex
    s = snap_to_lines((5.0, 2.2), lines, tolerance=1.0)
    assert s.point == pytest.approx((5.0, 3.0)) and s.line == 1 and not s.vertex
    assert s.distance == pytest.approx(0.8)
    assert snap_to_lines((5.0, 1.5), lines, tolerance=1.0) is None


def test_snap_to_multilines_and_bad_tolerance() -> None:
    lines = [MultiLineString([[(0, 0), (1, 0)], [(5, 5), (6, 5)]]), Point(0, 0)]
    assert snap_to_lines((5.2, 5.3), lines, 0.5).point == (5.0, 5.0)
    with pytest.raises(InputError, match="tolerance must be positive"):
        snap_to_lines((0, 0), lines, 0)


def test_mosaic_seamlines_are_snapping_targets(tmp_path: Path) -> None:
    path = tmp_path / "seamlines.gpkg"
    schema = {"geometry": "MultiLineString", "properties": {"image_a": "str"}}
    with fiona.open(str(path), "w", driver="GPKG", layer="seamlines", schema=schema,
                    crs="EPSG:25832") as dst:
        dst.write({"geometry": mapping(MultiLineString([[(0, 0), (0, 100)]])),
                   "properties": {"image_a": "a"}})
    lines = mosaic_seamlines(path, "EPSG:25832")
    assert len(lines) == 1
    assert snap_to_lines((0.3, 50.0), lines, 1.0).point == pytest.approx((0.0, 50.0))
    with pytest.raises(InputError, match="does not exist"):
        mosaic_seamlines(tmp_path / "none.gpkg")


# -- the block -----------------------------------------------------------------------------------
CAM = Camera("c", 100, 80, 1.0, (0.01, 0.01))  # footprint 1000 m × 800 m at H = 1000 m


@pytest.fixture
def project(tmp_path: Path) -> Project:
    """Three vertical images along x (400 m apart), terrain 100 m, flying height 1000 m."""
    p = Project(root=tmp_path, name="e", crs="EPSG:25832", cameras={"c": CAM},
                terrain_height=100.0)
    for i in range(3):
        eo = ExteriorOrientation.from_opk([400.0 * i, 0.0, 1100.0], 0.0, 0.0, 0.0)
        p.images.append(ImageRecord(f"im{i}", f"im{i}.tif", "c", eo))
    p.models = [manual_model(p, "im0", "im1"), manual_model(p, "im1", "im2")]
    return p


def test_models_at(project: Project) -> None:
    pairs = lambda ms: [(m.left, m.right) for m in ms]  # noqa: E731
    assert pairs(models_at(project, 400.0, 0.0)) == [("im0", "im1"), ("im1", "im2")]
    assert pairs(models_at(project, 700.0, 100.0)) == [("im1", "im2")]
    assert models_at(project, -300.0, 0.0) == []  # only im0 sees it
    assert models_at(project, 400.0, 500.0) == []  # beside the strip


def test_plausible_heights(project: Project) -> None:
    assert plausible_heights(project) == pytest.approx((-400.0, 600.0))
    project.terrain_height = None  # from the models' flying heights
    assert plausible_heights(project) == pytest.approx((-400.0, 600.0))


def test_valid_edits_have_no_problem(project: Project) -> None:
    fp = block_footprints(project)
    area = block_area(project, fp)
    assert area.bounds == pytest.approx((-500.0, -400.0, 1300.0, 400.0))
    square = Polygon([(0, 0), (50, 0), (50, 50), (0, 50)])
    edits = [("start_points", Point(400, 0), {"height": 102.5}),
             ("exclusion_areas", square, {"action": "Keep "}),
             ("breaklines", LineString([(0, 0, 101), (30, 40, 103)]), {"kind": "breakline"}),
             ("ground_points", Point(10, 10, 99.0), {}),
             ("check_points", Point(10, 10, 99.0), {"id": "CP1"}),
             ("seamlines", LineString([(400, -300), (400, 300)]), {}),
             ("boundaries", square, {"name": "b"})]
    for layer, geom, attrs in edits:
        assert validate_edit(layer, geom, attrs, project, footprints=fp) == [], layer


@pytest.mark.parametrize("layer, geom, attrs, words", [
    ("exclusion_areas", Polygon([(0, 0), (5, 0), (5, 5)]), {"action": "delete"},
     ["action 'delete' is not one of keep, remove, exclude"]),
    ("start_points", Point(0, 0), {"colour": "red"}, ["has no field(s) colour"]),
    ("start_points", Point(0, 0), {"height": float("nan")}, ["height 'nan' is not a height"]),
    ("start_points", Point(0, 0), {"height": "abc"}, ["height 'abc' is not a height"]),
    ("start_points", Point(0, 0), {"height": 5000.0}, ["5000.00 m lies outside the plausible",
                                                       "-400.0 to 600.0 m"]),
    ("ground_points", Point(0, 0), {}, ["needs 3-D points"]),
    ("breaklines", Point(0, 0, 1), {}, ["takes LineString features, not Point"]),
    ("breaklines", LineString([(0, 0, 100), (5, 5, float("inf"))]), {}, ["Z 'inf'"]),
    ("start_points", Point(5000, 0), {"height": 100.0}, ["outside the project's block"]),
    ("exclusion_areas", Polygon([(0, 0), (10, 10), (10, 0), (0, 10)]), {},
     ["polygon is invalid", "Self-intersection"]),
    ("nonsense", Point(0, 0), {}, ["'nonsense' is not an edit layer"]),
])
def test_bad_edits_are_refused(project: Project, layer, geom, attrs, words) -> None:
    problems = errors(validate_edit(layer, geom, attrs, project))
    assert len(problems) == 1, problems
    for w in words:
        assert w in problems[0].message


def test_warnings_do_not_refuse(project: Project) -> None:
    flat = validate_edit("breaklines", LineString([(0, 0), (5, 5)]), {}, project)
    assert [p.severity for p in flat] == ["warning"] and "no heights (2-D)" in flat[0].message
    half = validate_edit("exclusion_areas", Polygon([(1200, 0), (1400, 0), (1400, 50)]), {},
                         project)
    assert [p.severity for p in half] == ["warning"] and "partly outside" in half[0].message
    assert half[0].location is not None
    alone = validate_edit("start_points", Point(-300, 0), {"height": 100.0}, project)
    assert [p.severity for p in alone] == ["warning"]
    assert "outside every stereo model" in alone[0].message
    kind = validate_edit("breaklines", LineString([(0, 0, 100), (5, 5, 101)]), {"kind": "hedge"},
                         project)
    assert [p.severity for p in kind] == ["warning"]
    assert "kind 'hedge' is not one of breakline, structure_line" in kind[0].message
    assert validate_edit("breaklines", LineString([(0, 0, 100), (5, 5, 101)]),
                         {"kind": "Structure_Line"}, project) == []

