"""interpolate_dem: exact planes, holes, breaklines, exclusions, boundaries, CRS and errors."""

from __future__ import annotations

from pathlib import Path

import fiona
import numpy as np
import pytest
import rasterio
from shapely.geometry import LineString, Polygon, mapping

from photodem.algorithms.errors import InputError
from photodem.algorithms.processing import registry
from photodem.algorithms.surface.interpolate import interpolate_dem

CRS = "EPSG:25832"


def _lattice(path: Path, fn, n: int = 40, s: float = 1.0, keep=None) -> str:
    """Points at the cell centres of an n × n grid of side s starting at (0, 0)."""
    c = (np.arange(n) + 0.5) * s
    x, y = np.meshgrid(c, c)
    x, y = x.ravel(), y.ravel()
    ok = np.ones(x.size, bool) if keep is None else keep(x, y)
    np.savetxt(path, np.c_[x[ok], y[ok], fn(x[ok], y[ok])], fmt="%.6f")
    return str(path)


def _vector(path: Path, geoms, kind: str, props=None) -> str:
    schema = {"geometry": kind, "properties": {"action": "str"}}
    with fiona.open(str(path), "w", driver="GPKG", crs=CRS, schema=schema) as dst:
        for g, p in zip(geoms, props or [None] * len(geoms)):
            dst.write({"geometry": mapping(g), "properties": {"action": p}})
    return str(path)


def _dem(path) -> np.ndarray:
    with rasterio.open(path) as src:
        return src.read(1)


def plane(x, y):
    return 50.0 + 0.1 * x - 0.2 * y


def test_plane_with_hole_is_exact(tmp_path) -> None:
    hole = lambda x, y: ~((np.abs(x - 20) < 8) & (np.abs(y - 20) < 8))  # noqa: E731
    pts = _lattice(tmp_path / "p.xyz", plane, keep=hole)
    res = interpolate_dem(pts, tmp_path / "dem.tif", 1.0, crs=CRS)
    z = _dem(res["dem"])
    assert z.shape == (40, 40) and res["coverage"] == 1.0
    c = np.arange(40) + 0.5
    truth = plane(c[None, :], c[::-1, None])  # row 0 is the north edge
    assert np.allclose(z, truth, atol=1e-3)  # a plane is harmonic: the membrane is exact
    assert res["filled"] == 16 * 16 and res["measured"] == 1600 - 256
    cnt = _dem(res["count"])
    assert cnt[20, 20] == 0 and cnt[0, 0] == 1
    with rasterio.open(res["dem"]) as src:
        assert src.crs.to_epsg() == 25832 and src.dtypes[0] == "float32"


def test_median_per_cell_and_max_gap(tmp_path) -> None:
    # three points in one 2 m cell: 1, 2, 30 → median 2; a 10 m gap stays empty at max_gap 4
    p = tmp_path / "p.csv"
    p.write_text("x,y,z\n0.5,0.5,1\n1.0,1.0,2\n1.5,1.5,30\n19.5,19.5,5\n")
    res = interpolate_dem(p, tmp_path / "d.tif", 2.0, crs=CRS, max_gap=4.0)
    z = _dem(res["dem"])
    assert z[-1, 0] == 2.0 and z[0, -1] == 5.0 and np.isnan(z[5, 5])
    assert res["used"] == 4 and _dem(res["count"])[-1, 0] == 3


def test_breakline_keeps_the_step(tmp_path) -> None:
    step = lambda x, y: np.where(x < 25, 0.0, 10.0)  # noqa: E731
    band = lambda x, y: (x < 20) | (x > 30)  # noqa: E731
    pts = _lattice(tmp_path / "p.xyz", step, n=50, keep=band)
    line = _vector(tmp_path / "bl.gpkg", [LineString([(25.0, -5.0), (25.0, 55.0)])],
                   "LineString")
    res = interpolate_dem(pts, tmp_path / "d.tif", 1.0, crs=CRS, breaklines=line)
    z = _dem(res["dem"])
    assert np.allclose(z[:, :24], 0.0) and np.allclose(z[:, 26:], 10.0)
    smeared = _dem(interpolate_dem(pts, tmp_path / "n.tif", 1.0, crs=CRS)["dem"])
    assert np.abs(smeared[:, 20:30] - np.where(np.arange(20, 30) < 25, 0, 10)).max() > 2.0


def test_exclusions_and_boundary(tmp_path) -> None:
    pts = _lattice(tmp_path / "p.xyz", plane)
    excl = _vector(tmp_path / "ex.gpkg",
                   [Polygon([(5, 5), (15, 5), (15, 15), (5, 15)]),
                    Polygon([(25, 25), (35, 25), (35, 35), (25, 35)])],
                   "Polygon", ["exclude", "keep"])
    bnd = _vector(tmp_path / "b.gpkg", [Polygon([(0, 0), (30, 0), (30, 40), (0, 40)])],
                  "Polygon")
    res = interpolate_dem(pts, tmp_path / "d.tif", 1.0, crs=CRS, exclusions=excl,
                          boundary=bnd)
    z = _dem(res["dem"])
    assert z.shape == (40, 30)
    assert np.isnan(z[40 - 15:40 - 5, 5:15]).all()  # excluded (rows count from the north)
    assert np.isfinite(z[40 - 35:40 - 25, 25:30]).all()  # 'keep' is no exclusion
    assert np.isfinite(z).sum() == 40 * 30 - 100


def test_points_crs_and_errors(tmp_path) -> None:
    gpkg = tmp_path / "pts.gpkg"
    schema = {"geometry": "3D Point", "properties": {}}
    with fiona.open(str(gpkg), "w", driver="GPKG", crs=CRS, schema=schema) as dst:
        for x, y in [(500000.5, 5500000.5), (500009.5, 5500009.5), (500000.5, 5500009.5)]:
            dst.write({"geometry": {"type": "Point", "coordinates": (x, y, 7.0)},
                       "properties": {}})
    res = interpolate_dem(gpkg, tmp_path / "d.tif", 1.0)
    with rasterio.open(res["dem"]) as src:
        assert src.crs.to_epsg() == 25832
    assert np.allclose(_dem(res["dem"]), 7.0)
    xyz = tmp_path / "p.xyz"
    xyz.write_text("1 2 3\n4 5 6\n")
    empty = tmp_path / "e.xyz"
    empty.write_text("# nothing\n")
    for kwargs, text in [
        ({"points": str(empty)}, "holds no points"),
        ({"points": str(xyz)}, "carry no CRS"),
        ({"points": str(xyz), "crs": CRS, "spacing": 0.0}, "spacing must be positive"),
        ({"points": str(xyz), "crs": "nonsense"}, "is not a CRS"),
        ({"points": str(xyz), "crs": CRS, "boundary": str(tmp_path / "none.gpkg")},
         "does not exist"),
    ]:
        kw = {"spacing": 1.0, "output": tmp_path / "o" / "d.tif", **kwargs}
        with pytest.raises(InputError, match=text) as err:
            interpolate_dem(**kw)
        assert "\n" not in str(err.value)
    assert not (tmp_path / "o").exists() or list((tmp_path / "o").iterdir()) == []


def test_registry_run(tmp_path) -> None:
    pts = _lattice(tmp_path / "p.xyz", plane, n=10)
    res = registry.run("interpolate_dem", {"points": pts, "output": str(tmp_path / "d.tif"),
                                           "spacing": 2.0, "crs": CRS})
    assert set(res) == {"dem", "count", "points", "used", "filled", "coverage"}
    assert res["points"] == res["used"] == 100 and res["coverage"] == 1.0


def test_project_edits_are_honoured(tmp_path) -> None:
    from photodem.algorithms.project.edits import add_features, create_edits
    from photodem.algorithms.project.model import Project

    prj = Project(root=tmp_path / "prj", name="prj", crs=CRS)
    (tmp_path / "prj").mkdir()
    prj.save()
    create_edits(prj.edits_path, CRS)
    add_features(prj.edits_path, "exclusion_areas",
                 [(Polygon([(5, 5), (15, 5), (15, 15), (5, 15)]), {"action": "exclude"})])
    add_features(prj.edits_path, "boundaries",
                 [(Polygon([(0, 0), (40, 0), (40, 30), (0, 30)]), {})])
    step = lambda x, y: np.where(x < 25, 0.0, 10.0)  # noqa: E731
    pts = _lattice(tmp_path / "p.xyz", step, keep=lambda x, y: (x < 20) | (x > 30))
    add_features(prj.edits_path, "breaklines",
                 [(LineString([(25, -5, 5.0), (25, 45, 5.0)]), {"kind": "edge"})])
    res = interpolate_dem(pts, tmp_path / "d.tif", 1.0, project=tmp_path / "prj")
    z = _dem(res["dem"])
    assert z.shape == (30, 40)  # clipped to the boundary's extent, CRS from the project
    assert np.isnan(z[30 - 15:30 - 5, 5:15]).all() and np.isfinite(z).sum() == 1200 - 100
    assert np.allclose(z[:, 20:25], 0.0) and np.allclose(z[:, 26:31], 10.0)
    assert np.allclose(z[:, 25], 5.0)  # the 3-D breakline's own height on its cells
