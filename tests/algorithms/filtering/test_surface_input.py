"""Filter input, operator constraints and filter outputs (algorithms/filtering/surface_input)."""

from __future__ import annotations

import json

import numpy as np
import pytest
import rasterio
from affine import Affine
from shapely.geometry import LineString, Point, Polygon

from photodem.algorithms.errors import InputError
from photodem.algorithms.filtering.surface_input import (
    FilterConstraints,
    FilterInput,
    check_ground_points,
    grid_lowest,
    nice_spacing,
    point_labels,
    read_filter_constraints,
    read_filter_input,
    sample_bilinear,
    write_filter_outputs,
)
from photodem.algorithms.raster.io import write_raster
from photodem.algorithms.surface.gridding import Grid

CRS = "EPSG:25832"


def _dsm(path, z, x0=1000.0, y1=2000.0, s=1.0, crs=CRS):
    write_raster(path, np.asarray(z, np.float32), Affine(s, 0, x0, 0, -s, y1), crs)
    return path


def test_raster_input_nodata_and_grid(tmp_path) -> None:
    z = np.arange(12 * 15, dtype=np.float32).reshape(12, 15)
    z[2, 3] = np.nan
    inp = read_filter_input(_dsm(tmp_path / "d.tif", z, s=0.5))
    assert inp.source == "raster" and inp.points is None
    assert inp.grid.shape == (12, 15) and inp.grid.spacing == 0.5
    assert np.isnan(inp.z[2, 3]) and inp.z[0, 1] == 1.0 and inp.crs.to_epsg() == 25832


def test_bad_raster_input_is_one_line_error(tmp_path) -> None:
    with pytest.raises(InputError, match="no height") as err:
        read_filter_input(_dsm(tmp_path / "nan.tif", np.full((20, 20), np.nan)))
    assert "\n" not in str(err.value)
    (tmp_path / "junk.tif").write_bytes(b"not a tiff at all")
    with pytest.raises(InputError, match="Cannot read"):
        read_filter_input(tmp_path / "junk.tif")
    with pytest.raises(InputError, match="does not exist"):
        read_filter_input(tmp_path / "missing.tif")


def test_xyz_text_any_separator_extra_columns_lowest_point(tmp_path) -> None:
    rows = ["# x y z label"]
    rng = np.random.default_rng(0)
    pts = []
    for i in range(40):
        x, y = 500.0 + (i % 8) * 2.0 + 0.3, 800.0 + (i // 8) * 2.0 + 0.4
        z = 10.0 + rng.uniform()
        pts.append((x, y, z))
        sep = (" ", ",", ";", "\t")[i % 4]
        rows.append(sep.join([f"{x:.2f}", f"{y:.2f}", f"{z:.3f}", "1", "extra"]))
    # a second, higher point in the first cell: the lowest wins
    rows.append(f"{pts[0][0] + 0.1:.2f} {pts[0][1] + 0.1:.2f} {pts[0][2] + 5:.3f} 1")
    path = tmp_path / "p.xyz"
    path.write_text("\n".join(rows) + "\n")
    inp = read_filter_input(path, spacing=2.0)
    assert inp.source == "points" and inp.points.shape == (41, 3) and inp.crs is None
    assert inp.grid.spacing == 2.0 and (inp.point_cells >= 0).all()
    c0 = inp.point_cells[0]
    assert inp.point_cells[-1] == c0
    assert inp.z.reshape(-1)[c0] == pytest.approx(pts[0][2], abs=1e-3)
    # default spacing: about the mean point spacing, rounded
    assert read_filter_input(path).grid.spacing == 2.0
    assert nice_spacing(1.13) == 1.0 and nice_spacing(0.23) == 0.25


def test_too_few_points_and_unknown_crs(tmp_path) -> None:
    path = tmp_path / "few.txt"
    path.write_text("1 2 3\n4 5 6\n7 8 9\n")
    with pytest.raises(InputError, match="only 3 valid point"):
        read_filter_input(path)
    many = tmp_path / "many.txt"
    many.write_text("\n".join(f"{i} {i % 5} {i * 0.1}" for i in range(30)))
    with pytest.raises(InputError, match="Unknown CRS"):
        read_filter_input(many, crs="EPSG:999999")


def test_grid_lowest_cells() -> None:
    xyz = np.array([[0.5, 0.5, 3.0], [0.6, 0.4, 1.0], [2.5, 1.5, 7.0], [np.nan, 0, 0]])
    z, grid, cells = grid_lowest(xyz, 1.0)
    assert grid.shape == (2, 3)
    assert cells[0] == cells[1] and cells[3] == -1
    assert z.reshape(-1)[cells[0]] == 1.0 and z.reshape(-1)[cells[2]] == 7.0


def _project(tmp_path):
    from photodem.algorithms.project.edits import add_features, create_edits
    from photodem.algorithms.project.model import Project

    prj = Project(root=tmp_path / "prj", name="prj", crs=CRS)
    prj.save()
    create_edits(prj.edits_path, CRS)
    add_features(prj.edits_path, "exclusion_areas", [
        (Polygon([(1002, 1990), (1006, 1990), (1006, 1994), (1002, 1994)]), {"action": "keep"}),
        (Polygon([(1010, 1990), (1014, 1990), (1014, 1994), (1010, 1994)]),
         {"action": "remove"}),
        (Polygon([(1010, 1985), (1012, 1985), (1012, 1987), (1010, 1987)]), {"action": None}),
    ])
    add_features(prj.edits_path, "ground_points", [(Point(1003.5, 1996.5, 42.0), {})])
    add_features(prj.edits_path, "breaklines",
                 [(LineString([(1000, 1980.5, 5.0), (1020, 1980.5, 5.0)]), {"kind": "edge"})])
    return prj.root


def test_constraints_from_project(tmp_path) -> None:
    grid = Grid(Affine(1, 0, 1000, 0, -1, 2000), 20, 20, 1.0)
    cons = read_filter_constraints(_project(tmp_path), grid)
    assert cons.keep.sum() == 16 and cons.keep[6:10, 2:6].all()
    assert cons.remove.sum() == 16 + 4 and cons.remove[6:10, 10:14].all()
    assert cons.ground_points.tolist() == [[1003.5, 1996.5, 42.0]]
    assert len(cons.breaklines) == 1 and cons.barrier[19].all() and not cons.barrier[:18].any()
    assert np.nanmax(cons.barrier_z) == pytest.approx(5.0)
    empty = read_filter_constraints(None, grid)
    assert not empty.keep.any() and empty.ground_points.shape == (0, 3)


def test_check_ground_points_and_bilinear() -> None:
    grid = Grid(Affine(1, 0, 0, 0, -1, 10), 10, 10, 1.0)
    rows, cols = np.mgrid[0:10, 0:10]
    dtm = (2.0 * (cols + 0.5) + 3.0 * (10 - rows - 0.5)).astype(np.float32)  # z = 2x + 3y
    gp = np.array([[4.5, 4.5, 2 * 4.5 + 3 * 4.5], [1.5, 8.5, 0.0], [50.0, 5.0, 1.0]])
    bad = check_ground_points(dtm, grid, gp, 0.1)
    assert [b["index"] for b in bad] == [1, 2] and bad[1]["status"] == "outside"
    assert bad[0]["dh"] == pytest.approx(2 * 1.5 + 3 * 8.5)
    x, y = np.array([3.2, 7.9]), np.array([6.1, 2.3])
    assert np.allclose(sample_bilinear(dtm, grid, x, y), 2 * x + 3 * y, atol=1e-4)


def test_write_outputs_points_and_raster(tmp_path) -> None:
    path = tmp_path / "p.txt"
    xs, ys = np.meshgrid(np.arange(10) + 0.5, np.arange(10) + 0.5)
    zs = np.full(xs.shape, 5.0)
    zs[3, 3] = 9.0  # one object point
    np.savetxt(path, np.column_stack([xs.ravel(), ys.ravel(), zs.ravel()]))
    inp = read_filter_input(path, spacing=1.0, crs=CRS)
    dtm = np.full(inp.grid.shape, 5.0, np.float32)
    out = write_filter_outputs(tmp_path / "out", inp, dtm, np.isfinite(inp.z) & (inp.z < 8.0),
                               {"ground_tolerance_m": 0.5, "iterations": [
                                   {"iteration": 1, "eliminated_share": 0.01}]})
    labels = np.loadtxt(out["labels"], dtype=int)
    assert labels.tolist() == [1 if i == 33 else 0 for i in range(100)]
    assert out["mask"] is None and json.loads((tmp_path / "out" / "report.json").read_text())[
        "points_object"] == 1
    assert "<img" in (tmp_path / "out" / "report.html").read_text()
    with rasterio.open(out["ndsm"]) as src:
        assert src.read(1).max() == pytest.approx(4.0) and src.crs.to_epsg() == 25832
    # raster: mask 0 ground, 1 object, 255 no data; an existing folder is never overwritten
    z = np.full((6, 6), 3.0, np.float32)
    z[0, 0] = np.nan
    rin = read_filter_input(_dsm(tmp_path / "d.tif", z))
    ground = np.ones((6, 6), bool)
    ground[2, 2] = False
    out2 = write_filter_outputs(tmp_path / "out2", rin, z, ground, {},
                                extra_rasters={"diff_01": z})
    with rasterio.open(out2["mask"]) as src:
        m = src.read(1)
    assert m[0, 0] == 255 and m[2, 2] == 1 and m[1, 1] == 0 and out2["labels"] is None
    assert (tmp_path / "out2" / "diff_01.tif").is_file()
    with pytest.raises(InputError, match="not empty"):
        write_filter_outputs(tmp_path / "out2", rin, z, ground, {})


def test_empty_constraints_shape() -> None:
    grid = Grid(Affine(1, 0, 0, 0, -1, 4), 5, 4, 1.0)
    c = FilterConstraints.empty(grid)
    assert c.keep.shape == c.remove.shape == c.barrier.shape == (4, 5)


def test_low_outliers_net_cut_is_slope_invariant() -> None:
    from photodem.algorithms.filtering.surface_input import low_outliers

    rows, cols = np.mgrid[0:60, 0:60].astype(float)
    steep = 100.0 + 1.0 * cols + 0.7 * rows  # 122 % slope: nothing is a pit
    assert not low_outliers(steep, 0.5).any()
    # a 4 m retaining wall across the slope: the foot of the wall is no pit either
    wall = steep + np.where(rows >= 30, 4.0, 0.0)
    assert not low_outliers(wall, 0.5).any()
    z = steep.copy()
    # on a 122 % slope the window's lowest neighbours lie 3.4 m below the centre: the test
    # sees blunders deeper than that plus the depth (on flat ground: deeper than the depth)
    z[10, 10] -= 8.0  # single blunder
    z[40, 40] -= 9.0  # a pair of blunders
    z[40, 41] -= 8.0
    z[20, 50] -= 1.0  # shallower than the depth: stays
    z[5, 30] = np.nan
    got = low_outliers(z, 1.5)
    assert set(zip(*np.nonzero(got))) == {(10, 10), (40, 40), (40, 41)}
    flat = np.full((30, 30), 5.0)
    flat[15, 15] -= 2.0
    flat[0, 0] -= 2.0  # a border cell has no neighbours above/left: not judged
    assert set(zip(*np.nonzero(low_outliers(flat, 1.5)))) == {(15, 15)}


def test_grey_opening_keeps_slopes_and_removes_narrow_objects() -> None:
    from photodem.algorithms.filtering.surface_input import grey_opening

    rows, cols = np.mgrid[0:50, 0:70].astype(float)
    slope = 100.0 + 0.8 * cols - 0.5 * rows + 3.0 * (cols > 35)  # with a 3 m wall
    z = slope.copy()
    z[3, 3] = np.nan
    got = grey_opening(z, 9)
    # slopes and the wall exactly, up to the raster border (point reflection)
    assert np.nanmax(np.abs(got - slope)) < 1e-3 and np.isnan(got[3, 3])
    flat = 50.0 + 0.02 * cols
    z = flat.copy()
    z[10:18, 20:27] += 6.0  # 7 cells wide: narrower than 9, removed
    z[30:45, 45:62] += 6.0  # 15 cells: wider than 9, stays (its uphill rim as low as that)
    got = grey_opening(z, 9)
    # on a slope the object leaves a shelf at the ground height of its uphill edge
    assert np.abs(got[10:18, 20:27] - flat[10:18, 20:27]).max() <= 0.02 * 8 + 1e-3
    assert np.abs(got[30:45, 45:62] - z[30:45, 45:62]).max() <= 0.02 * 8 + 1e-3


def test_point_labels_tolerance_grows_with_slope(tmp_path) -> None:
    from photodem.algorithms.filtering.surface_input import dtm_slope

    g = Grid(Affine(1.0, 0, 0.0, 0, -1.0, 40.0), 40, 40, 1.0)
    _, cols = np.mgrid[0:40, 0:40].astype(float)
    dtm = (10.0 + 0.8 * cols).astype(np.float32)  # 80 % slope along x
    assert np.allclose(dtm_slope(dtm, 1.0), 0.8)
    x = np.array([20.5, 20.5, 20.5, 20.5])
    y = np.array([20.5, 20.5, 20.5, 20.5])
    zd = 10.0 + 0.8 * 20.0
    # tolerance 0.5 m, + 1.25 · 0.8 · 1 m = 1.5 m with the slope allowance
    z = zd + np.array([0.4, 1.2, -1.4, 1.6])
    inp = FilterInput(dtm, g, None, points=np.column_stack([x, y, z]), source="points")
    assert point_labels(inp, dtm, 0.5).tolist() == [0, 1, 1, 1]
    assert point_labels(inp, dtm, 0.5, 1.25).tolist() == [0, 0, 0, 1]


def test_lowest_point_of_a_ground_cell_is_ground() -> None:
    from photodem.algorithms.filtering.surface_input import lowest_points

    # two cells: a ground cell whose lowest point lies 2 m above a DTM that passes beside it
    # (smoothed over a bank), with a bush point above it; an object cell
    xyz = np.array([[0.5, 0.5, 12.0], [0.6, 0.4, 14.0], [1.5, 0.5, 20.0], [1.4, 0.6, 20.0]])
    zg, grid, cells = grid_lowest(xyz, 1.0)
    inp = FilterInput(zg, grid, None, points=xyz, point_cells=cells, source="points")
    assert sorted(lowest_points(inp).tolist()) == [0, 2]  # ties: the first point
    dtm = np.full(grid.shape, 10.0, np.float32)
    ground = np.array([[True, False]])
    assert point_labels(inp, dtm, 0.5).tolist() == [1, 1, 1, 1]
    assert point_labels(inp, dtm, 0.5, ground=ground).tolist() == [0, 1, 1, 1]


def test_ground_bumps_flag_narrow_low_objects_not_slopes_ridges_or_terraces() -> None:
    from photodem.algorithms.filtering.surface_input import ground_bumps

    rows, cols = np.mgrid[0:60, 0:80].astype(float)
    rng = np.random.default_rng(3)
    # 60 % slopes up to a sharp ridge and a 2 m terrace step: the terrain (and the surface)
    surface = 100.0 + 0.6 * cols - 1.2 * np.maximum(cols - 60, 0) + 2.0 * (rows > 30)
    z = surface + rng.normal(0.0, 0.05, cols.shape)
    # tolerance 0.5 m + 1.25 · 0.6 · 1 m = 1.25 m on the slope
    z[10:12, 10:12] += 1.6  # a bush 2 m wide
    z[40, 20] += 1.4  # a single low object cell
    z[45:60, 30:50] += 1.6  # a platform wider than the 5 m window: not a bump
    support = np.ones(z.shape, bool)
    support[5, 5] = False  # not judged, no support
    got = ground_bumps(z, support, surface, 1.0, 0.5, 1.25)
    assert got[10:12, 10:12].all() and got[40, 20]
    assert got.sum() == 5  # nothing on the slopes, the ridge, the terrace step, the platform
    # the opening cuts the ridge (by slope × half the window): allowed for by the surface's cut
    flat = ground_bumps(z, support, np.full(z.shape, np.nan), 1.0, 0.5, 1.25)
    assert flat[:, 58:63].any()
    # the window is in metres: at 0.5 m cells the bush is 4 cells wide and still a bump
    x = np.mgrid[0:120, 0:160][1] * 0.5
    fine_surface = 100.0 + 0.3 * x
    fine = fine_surface + rng.normal(0.0, 0.05, x.shape)
    fine[20:24, 20:24] += 1.6
    got = ground_bumps(fine, np.ones(fine.shape, bool), fine_surface, 0.5, 0.5, 1.25)
    assert got[20:24, 20:24].all() and got.sum() == 16


def test_ground_bumps_allow_for_the_noise_of_a_matched_dsm() -> None:
    from photodem.algorithms.filtering.surface_input import ground_bumps

    rng = np.random.default_rng(5)
    surface = np.full((200, 200), 50.0)
    z = surface + rng.normal(0.0, 0.15, surface.shape)  # σ = half the tolerance
    z[100:103, 100:103] += 1.0
    got = ground_bumps(z, np.ones(z.shape, bool), surface, 0.5, 0.3, 1.0)
    # noise lifts every cell above the opening (by ≈ 1.8 σ with 11 × 11 cells): without the
    # typical lift almost half of the cells would go, a bias of the DTM; with it, the 2 σ tail
    assert got[100:103, 100:103].all() and got.mean() < 0.04
