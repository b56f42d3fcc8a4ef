"""point_compare: the point formats, bilinear residuals on a plane, outside points, errors."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest
from affine import Affine

from photodem.algorithms.errors import InputError
from photodem.algorithms.processing import registry
from photodem.algorithms.project.points_io import read_points
from photodem.algorithms.quality.points import point_compare, sample_dem
from photodem.algorithms.raster.io import write_raster

CELL = 1.0
T = Affine(CELL, 0.0, 1000.0, 0.0, -CELL, 2000.0)
SHAPE = (300, 400)  # x 1000…1400, y 1700…2000


def _height(x, y):
    """The plane of the test DEM: bilinear interpolation reproduces it exactly."""
    return 50.0 + 0.02 * (np.asarray(x) - 1000.0) - 0.01 * (np.asarray(y) - 1700.0)


@pytest.fixture(scope="module")
def dem(tmp_path_factory) -> Path:
    rows, cols = np.indices(SHAPE)
    x = T.c + (cols + 0.5) * CELL
    y = T.f - (rows + 0.5) * CELL
    z = _height(x, y).astype(np.float64)
    z[10:20, 10:20] = np.nan  # a nodata hole (world x 1010…1020, y 1980…1990)
    return write_raster(tmp_path_factory.mktemp("dem") / "dem.tif", z, T, "EPSG:25832")


def test_sample_dem_is_exact_on_a_plane_across_blocks(dem: Path) -> None:
    rng = np.random.default_rng(3)
    x = rng.uniform(1030.0, 1399.0, 500)
    y = rng.uniform(1700.6, 1960.0, 500)
    z = sample_dem(dem, x, y, block=64)  # many blocks, including their borders
    np.testing.assert_allclose(z, _height(x, y), atol=1e-9)
    # outside the hull of cell centres, and next to nodata
    assert np.isnan(sample_dem(dem, [999.0, 1000.2, 1401.0], [1800.0, 1800.0, 1800.0])).all()
    assert np.isnan(sample_dem(dem, [1015.0], [1985.0]))[0]


def test_xyz_text_with_ids_comments_and_extra_columns(tmp_path: Path) -> None:
    path = tmp_path / "cp.txt"
    path.write_text("# check points\nCP1 1100.5 1800.25 52.0 extra 7\n"
                    "CP2,1200.0,1900.0,53.5  # comment\n\nbad line\nCP3\t1300\t1750\t51\n")
    pts = read_points(path)
    assert pts.ids == ["CP1", "CP2", "CP3"] and pts.skipped == 1
    np.testing.assert_allclose(pts.x, [1100.5, 1200.0, 1300.0])
    np.testing.assert_allclose(pts.z, [52.0, 53.5, 51.0])
    path.write_text("1100 1800 52 9 9\n1200 1900 53\n")
    pts = read_points(path)
    assert pts.ids == ["1", "2"] and pts.crs is None


def test_csv_with_header_finds_columns_by_name(tmp_path: Path) -> None:
    path = tmp_path / "cp.csv"
    path.write_text("Name;Hochwert;Rechtswert;Height;Quality\nA;1800;1100;52.5;good\n"
                    "B;1900;1200;53.0;ok\n")
    pts = read_points(path)
    assert pts.ids == ["A", "B"]
    np.testing.assert_allclose(pts.x, [1100.0, 1200.0])
    np.testing.assert_allclose(pts.y, [1800.0, 1900.0])
    path.write_text("a,b,c\n1,2,3\n")
    with pytest.raises(InputError, match="no x/y/z columns"):
        read_points(path)


def test_geopackage_3d_points_and_z_field(tmp_path: Path) -> None:
    import fiona

    p3 = tmp_path / "p3.gpkg"
    schema = {"geometry": "3D Point", "properties": {"id": "str"}}
    with fiona.open(str(p3), "w", driver="GPKG", schema=schema, crs="EPSG:25832") as dst:
        dst.write({"geometry": {"type": "Point", "coordinates": (1100.0, 1800.0, 52.0)},
                   "properties": {"id": "P1"}})
    pts = read_points(p3)
    assert pts.ids == ["P1"] and pts.z[0] == 52.0 and pts.crs
    p2 = tmp_path / "p2.gpkg"
    schema = {"geometry": "Point", "properties": {"name": "str", "elevation": "float"}}
    with fiona.open(str(p2), "w", driver="GPKG", schema=schema, crs="EPSG:25832") as dst:
        dst.write({"geometry": {"type": "Point", "coordinates": (1100.0, 1800.0)},
                   "properties": {"name": "Q", "elevation": 51.5}})
    pts = read_points(p2)
    assert pts.ids == ["Q"] and pts.z[0] == 51.5


def test_point_compare_residuals_and_statistics(dem: Path, tmp_path: Path) -> None:
    rng = np.random.default_rng(7)
    x = rng.uniform(1050.0, 1350.0, 40)
    y = rng.uniform(1710.0, 1950.0, 40)
    dz_true = rng.normal(0.1, 0.05, 40)
    z = _height(x, y) - dz_true  # DEM − point = dz_true
    lines = [f"P{i} {x[i]:.6f} {y[i]:.6f} {z[i]:.9f}" for i in range(40)]
    lines += ["OUT1 5000 5000 10", "HOLE 1015 1985 50"]
    src = tmp_path / "points.xyz"
    src.write_text("\n".join(lines) + "\n")
    result = point_compare(src, dem, residuals_path=tmp_path / "res.csv", flying_height=1000.0)
    assert result["points"] == 42 and result["used"] == 40
    assert result["outside"] == 1 and result["nodata"] == 1 and result["outside_ids"] == ["OUT1"]
    stats = result["stats"]
    expected = np.round(dz_true, 9)
    assert stats["count"] == 40
    assert stats["mean"] == pytest.approx(float(np.mean(expected)), abs=1e-6)
    assert stats["rms"] == pytest.approx(float(np.sqrt(np.mean(expected ** 2))), abs=1e-6)
    assert stats["permille"]["rms"] == pytest.approx(stats["rms"], abs=1e-6)  # H = 1000 m
    with open(tmp_path / "res.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0]) == ["id", "x", "y", "z", "dem_z", "dz", "status"]
    assert rows[-2]["status"] == "outside" and rows[-2]["dem_z"] == "" and rows[-2]["dz"] == ""
    assert rows[-1]["status"] == "nodata"
    np.testing.assert_allclose([float(r["dz"]) for r in rows[:40]], dz_true, atol=1e-4)


def test_point_compare_errors(dem: Path, tmp_path: Path) -> None:
    empty = tmp_path / "empty.txt"
    empty.write_text("# nothing\nfoo bar\n")
    with pytest.raises(InputError, match="no valid row"):
        point_compare(empty, dem, residuals_path=tmp_path / "r.csv")
    far = tmp_path / "far.txt"
    far.write_text("1 1 1\n2 2 2\n")
    with pytest.raises(InputError, match="None of the 2 points"):
        point_compare(far, dem, residuals_path=tmp_path / "r.csv")
    assert not (tmp_path / "r.csv").exists()


def test_point_compare_algorithm_writes_its_folder(dem: Path, tmp_path: Path) -> None:
    src = tmp_path / "p.csv"
    src.write_text("id,x,y,z\nA,1100,1800,52.0\nB,1200,1900,52.0\n")
    out = tmp_path / "out"
    result = registry.run("point_compare", {"points": str(src), "dem": str(dem),
                                            "output": str(out)})
    assert result["points"] == 2 and result["used"] == 2 and result["outside"] == 0
    assert result["stats"]["mean"] == pytest.approx(
        float(np.mean(_height([1100, 1200], [1800, 1900]) - 52.0)), abs=1e-9)
    names = sorted(p.name for p in out.iterdir())
    assert names == [".photodem-product.json", "residuals.csv", "stats.csv", "stats.json"]
    with pytest.raises(InputError):  # bad input leaves the earlier result untouched
        registry.run("point_compare", {"points": str(tmp_path / "empty.txt"), "dem": str(dem),
                                       "output": str(out)})
