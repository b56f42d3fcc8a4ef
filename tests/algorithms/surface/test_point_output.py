"""Point output: GeoPackage and LAS round trips, CRS kept, atomic, clear errors."""

from __future__ import annotations

import numpy as np
import pytest

from photodem.algorithms.errors import InputError
from photodem.algorithms.project.points_io import read_points
from photodem.algorithms.surface import point_output
from photodem.algorithms.surface.point_output import write_points


def _points(n: int = 500):
    rng = np.random.default_rng(7)
    x = rng.uniform(500_000.0, 502_000.0, n)
    y = rng.uniform(5_700_000.0, 5_702_000.0, n)
    z = rng.uniform(100.0, 300.0, n)
    fields = {
        "sigma_z": rng.uniform(0.01, 0.5, n).astype(np.float32),
        "rho": rng.uniform(0.5, 1.0, n),
        "flags": rng.integers(0, 8, n).astype(np.uint8),
        "level": rng.integers(0, 4, n).astype(np.int16),
        "n": rng.integers(1, 60, n).astype(np.int64),
        "outlier": rng.random(n) < 0.1,
    }
    return x, y, z, fields


def _no_partials(folder) -> None:
    assert not [p for p in folder.iterdir() if "partial" in p.name]


def test_geopackage_round_trip(tmp_path) -> None:
    fiona = pytest.importorskip("fiona")
    x, y, z, fields = _points()
    x[3] = np.nan  # skipped
    path = write_points(tmp_path / "points.gpkg", x, y, z, fields, "EPSG:25832", chunk=128)
    _no_partials(tmp_path)
    assert fiona.listlayers(str(path)) == ["points"]
    with fiona.open(str(path)) as src:
        assert "Point" in str(src.schema["geometry"]) and len(src) == 499
        assert set(src.schema["properties"]) == set(fields)
        from pyproj import CRS

        assert CRS.from_wkt(src.crs_wkt).to_epsg() == 25832
        feats = list(src)
    ok = np.isfinite(x)
    got = np.array([f["geometry"]["coordinates"] for f in feats])
    np.testing.assert_allclose(got, np.c_[x[ok], y[ok], z[ok]], atol=1e-6)
    for name, values in fields.items():
        col = np.array([f["properties"][name] for f in feats])
        np.testing.assert_allclose(col, values[ok].astype(float), rtol=1e-6)
    # read_points reads it back with the CRS
    pts = read_points(path)
    assert len(pts) == 499 and CRS.from_user_input(pts.crs).to_epsg() == 25832
    np.testing.assert_allclose(pts.z, z[ok], atol=1e-6)


def test_las_round_trip_and_read_points(tmp_path) -> None:
    laspy = pytest.importorskip("laspy", reason="laspy is not installed (tier B has none)")
    x, y, z, fields = _points(3000)
    fields["classification"] = np.full(3000, 2, np.uint8)  # a standard LAS dimension
    path = write_points(tmp_path / "points.las", x, y, z, fields, "EPSG:25832", chunk=1000)
    _no_partials(tmp_path)
    las = laspy.read(str(path))
    assert str(las.header.version) == "1.4" and las.header.point_format.id == 6
    assert las.header.point_count == 3000
    np.testing.assert_allclose(las.header.scales, [0.001] * 3)
    np.testing.assert_allclose(np.asarray(las.x), x, atol=0.0005 + 1e-9)
    np.testing.assert_allclose(np.asarray(las.z), z, atol=0.0005 + 1e-9)
    assert set(las.point_format.extra_dimension_names) == set(fields) - {"classification"}
    np.testing.assert_array_equal(np.asarray(las.classification), 2)
    for name in ("sigma_z", "rho", "flags", "level", "n"):
        np.testing.assert_array_equal(np.asarray(las[name]), fields[name])
    np.testing.assert_array_equal(np.asarray(las["outlier"]), fields["outlier"].astype(np.uint8))
    assert las.header.parse_crs().to_epsg() == 25832
    # bounds in the header (written by the chunked writer)
    np.testing.assert_allclose(las.header.mins, [x.min(), y.min(), z.min()], atol=0.001)
    pts = read_points(path)
    assert len(pts) == 3000 and pts.ids[0] == "1" and pts.ids[-1] == "3000"
    np.testing.assert_allclose(pts.y, y, atol=0.0005 + 1e-9)
    from pyproj import CRS

    assert CRS.from_wkt(pts.crs).to_epsg() == 25832


def test_las_point_compare_accepts_las(tmp_path) -> None:
    pytest.importorskip("laspy", reason="laspy is not installed (tier B has none)")
    from affine import Affine

    from photodem.algorithms.quality.points import point_compare
    from photodem.algorithms.raster.io import write_raster

    t = Affine(1.0, 0.0, 500_000.0, 0.0, -1.0, 5_700_100.0)
    dem = write_raster(tmp_path / "dem.tif", np.full((100, 100), 50.0, np.float32), t,
                       "EPSG:25832")
    rng = np.random.default_rng(1)
    x = rng.uniform(500_010.0, 500_090.0, 200)
    y = rng.uniform(5_700_010.0, 5_700_090.0, 200)
    pts = write_points(tmp_path / "p.las", x, y, np.full(200, 49.9), None, "EPSG:25832")
    res = point_compare(pts, dem, residuals_path=tmp_path / "res.csv")
    assert res["used"] == 200 and res["stats"]["mean"] == pytest.approx(0.1, abs=1e-3)


def test_missing_laspy_and_bad_suffix(tmp_path, monkeypatch) -> None:
    with pytest.raises(InputError, match=r"\.gpkg"):
        write_points(tmp_path / "points.csv", [0.0], [0.0], [0.0], {}, None)

    def no_laspy():
        raise InputError("LAS/LAZ files need the Python package laspy: install laspy")

    monkeypatch.setattr(point_output, "_import_laspy", no_laspy)
    with pytest.raises(InputError, match="install laspy"):
        write_points(tmp_path / "points.las", [0.0], [0.0], [0.0], {}, None)
    assert not list(tmp_path.iterdir())


def test_laspy_absent_message(tmp_path, monkeypatch) -> None:
    import builtins

    real_import = builtins.__import__

    def fake_import(name, *args, **kwargs):
        if name == "laspy":
            raise ImportError("no laspy")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", fake_import)
    with pytest.raises(InputError, match="install laspy"):
        write_points(tmp_path / "p.las", [0.0], [0.0], [0.0])
    (tmp_path / "q.las").write_bytes(b"not a las file")
    with pytest.raises(InputError, match="install laspy"):
        read_points(tmp_path / "q.las")


def test_bad_fields(tmp_path) -> None:
    with pytest.raises(InputError, match="values"):
        write_points(tmp_path / "p.gpkg", [0.0, 1.0], [0.0, 1.0], [0.0, 1.0], {"a": [1.0]})
    with pytest.raises(InputError, match="reserved"):
        write_points(tmp_path / "p.gpkg", [0.0], [0.0], [0.0], {"z": [1.0]})
    with pytest.raises(InputError, match="CRS"):
        write_points(tmp_path / "p.gpkg", [0.0], [0.0], [0.0], None, "not a crs")
    assert not list(tmp_path.iterdir())
