"""dem_profile: sampling positions, heights on planes, line in another CRS, errors."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest
from affine import Affine

from photodem.algorithms.errors import InputError
from photodem.algorithms.processing import registry
from photodem.algorithms.quality.profile import (
    dem_profile,
    parse_coordinates,
    read_line,
    sample_line,
)
from photodem.algorithms.raster.io import write_raster

X0, Y0 = 400_000.0, 5_600_000.0


def _plane_dem(path: Path, cell: float, a: float, b: float, c: float,
               shape=(200, 300)) -> Path:
    rows, cols = np.indices(shape)
    x = X0 + (cols + 0.5) * cell
    y = Y0 - (rows + 0.5) * cell
    z = c + a * (x - X0) + b * (Y0 - y)
    return write_raster(path, z.astype(np.float64), Affine(cell, 0, X0, 0, -cell, Y0),
                        "EPSG:25832")


@pytest.fixture(scope="module")
def dems(tmp_path_factory):
    base = tmp_path_factory.mktemp("profile")
    fine = _plane_dem(base / "fine.tif", 0.5, 0.01, 0.02, 100.0)  # 150 × 100 m
    coarse = _plane_dem(base / "coarse.tif", 2.0, 0.01, 0.02, 101.0, (60, 80))  # 160 × 120 m
    return fine, coarse


def test_parse_coordinates_and_errors() -> None:
    np.testing.assert_array_equal(parse_coordinates("1,2; 3,4;5 6"), [[1, 2], [3, 4], [5, 6]])
    with pytest.raises(InputError, match="at least 2 vertices"):
        parse_coordinates("1,2")
    with pytest.raises(InputError, match="not 'x,y'"):
        parse_coordinates("1,2;3")
    with pytest.raises(InputError, match="zero length"):
        parse_coordinates("1,2;1,2")


def test_sample_line_positions() -> None:
    d, x, y = sample_line(np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 4.0]]), 1.5)
    np.testing.assert_allclose(d, [0, 1.5, 3, 4.5, 6, 7])  # the end point is included
    np.testing.assert_allclose(x, [0, 1.5, 3, 3, 3, 3])
    np.testing.assert_allclose(y, [0, 0, 0, 1.5, 3, 4])


def test_profile_heights_columns_and_plot(dems, tmp_path: Path) -> None:
    fine, coarse = dems
    coords = f"{X0 + 10},{Y0 - 10};{X0 + 110},{Y0 - 80}"
    r = dem_profile([fine, coarse], coordinates=coords, csv_path=tmp_path / "p.csv",
                    png_path=tmp_path / "p.png")
    length = float(np.hypot(100.0, 70.0))
    assert r["length"] == pytest.approx(length) and r["spacing"] == 0.5  # the finest cell
    assert r["samples"] == int(length / 0.5) + 2 and r["columns"] == ["fine", "coarse"]
    with open(tmp_path / "p.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0]) == ["distance", "x", "y", "fine", "coarse"]
    x = np.array([float(r_["x"]) for r_ in rows])
    y = np.array([float(r_["y"]) for r_ in rows])
    expect = 100.0 + 0.01 * (x - X0) + 0.02 * (Y0 - y)
    np.testing.assert_allclose([float(r_["fine"]) for r_ in rows], expect, atol=2e-4)
    np.testing.assert_allclose([float(r_["coarse"]) for r_ in rows], expect + 1.0, atol=2e-4)
    assert (tmp_path / "p.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_two_files_of_the_same_name_get_distinct_columns(dems, tmp_path: Path) -> None:
    fine, coarse = dems
    (tmp_path / "m1").mkdir()
    (tmp_path / "m2").mkdir()
    a = Path(write_raster(tmp_path / "m1" / "dtm.tif", *_read(fine)))
    b = Path(write_raster(tmp_path / "m2" / "dtm.tif", *_read(coarse)))
    r = dem_profile([a, b], coordinates=f"{X0 + 10},{Y0 - 10};{X0 + 60},{Y0 - 40}",
                    csv_path=tmp_path / "p.csv", png_path=tmp_path / "p.png")
    assert r["columns"] == ["m1/dtm", "m2/dtm"]


def _read(path):
    import rasterio

    with rasterio.open(path) as src:
        return src.read(1), src.transform, src.crs


def test_line_layer_in_another_crs_and_partial_cover(dems, tmp_path: Path) -> None:
    import fiona
    from rasterio.warp import transform

    fine, coarse = dems
    # from inside both DEMs to x = X0 + 155 (outside the fine DEM, inside the coarse one)
    lon, lat = transform("EPSG:25832", "EPSG:4326", [X0 + 20.0, X0 + 155.0], [Y0 - 50.0] * 2)
    pts = list(zip(lon, lat))
    path = tmp_path / "line.gpkg"
    schema = {"geometry": "LineString", "properties": {"id": "int"}}
    with fiona.open(str(path), "w", driver="GPKG", schema=schema, crs="EPSG:4326") as dst:
        dst.write({"geometry": {"type": "LineString", "coordinates": pts},
                   "properties": {"id": 1}})
    xy, crs = read_line(path)
    assert xy.shape == (2, 2) and crs
    out = tmp_path / "out"
    result = registry.run("dem_profile", {"dems": [str(fine), str(coarse)], "line": str(path),
                                          "spacing": 5.0, "output": str(out)})
    assert result["length"] == pytest.approx(135.0, abs=1e-3)
    assert result["samples"] == 28
    with open(out / "profile.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert rows[-1]["fine"] == "" and rows[-1]["coarse"] != ""
    assert float(rows[0]["coarse"]) == pytest.approx(101.0 + 0.2 + 1.0, abs=1e-3)


def test_profile_errors(dems, tmp_path: Path) -> None:
    import fiona

    fine, _ = dems
    with pytest.raises(InputError, match="does not cover"):
        dem_profile([fine], coordinates="0,0;10,10", csv_path=tmp_path / "a.csv",
                    png_path=tmp_path / "a.png")
    with pytest.raises(InputError, match="Give the profile line"):
        dem_profile([fine], csv_path=tmp_path / "a.csv", png_path=tmp_path / "a.png")
    path = tmp_path / "short.gpkg"
    schema = {"geometry": "LineString", "properties": {"id": "int"}}
    with fiona.open(str(path), "w", driver="GPKG", schema=schema, crs="EPSG:25832") as dst:
        dst.write({"geometry": {"type": "LineString", "coordinates": [(X0, Y0), (X0, Y0)]},
                   "properties": {"id": 1}})
    with pytest.raises(InputError):
        read_line(path)
    with pytest.raises(InputError, match="more than"):
        dem_profile([fine], coordinates=f"{X0},{Y0 - 1};{X0 + 100},{Y0 - 1}", spacing=1e-5,
                    csv_path=tmp_path / "a.csv", png_path=tmp_path / "a.png")
    assert not (tmp_path / "a.csv").exists()
