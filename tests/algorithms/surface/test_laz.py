"""LAZ: a compressed point cloud written and read back (points, classification, CRS) by the
point writer, the points reader and the filters' input; a clear error without a LAZ backend.

Tier A installs ``laspy[lazrs]``; tier B installs laspy and lazrs from PyPI into
``.venv-qgis`` (Debian packages neither) — where that failed the tests skip with the reason.
"""

from __future__ import annotations

import numpy as np
import pytest
from pyproj import CRS

from photodem.algorithms.errors import InputError
from photodem.algorithms.filtering.surface_input import read_filter_input
from photodem.algorithms.project.points_io import read_points
from photodem.algorithms.surface.point_output import write_points

laspy = pytest.importorskip("laspy", reason="laspy is not installed (pip install "
                                            "\"laspy[lazrs]\"; tier B: make venv-qgis)")


def needs_laz_backend() -> None:
    if not laspy.LazBackend.detect_available():
        pytest.skip("laspy has no LAZ backend (pip install lazrs); LAS works without one")


def slope_with_trees(n: int = 4000, seed: int = 3):
    """Ground points on a 30 % slope (class 2) and canopy points 15 m above (class 5)."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(400_000.0, 400_100.0, n)
    y = rng.uniform(5_500_000.0, 5_500_100.0, n)
    ground = rng.random(n) < 0.3
    z = 200.0 + 0.3 * (x - 400_000.0) + np.where(ground, 0.0, 15.0 + rng.normal(0, 2, n))
    cls = np.where(ground, 2, 5).astype(np.uint8)
    return x, y, z, cls


def test_laz_written_and_read_back(tmp_path) -> None:
    needs_laz_backend()
    x, y, z, cls = slope_with_trees()
    path = write_points(tmp_path / "forest.laz", x, y, z,
                        {"classification": cls, "sigma_z": np.full(len(x), 0.05)},
                        "EPSG:25832", chunk=1500)
    head = path.read_bytes()[:400]
    assert head[:4] == b"LASF"
    las = laspy.read(str(path))
    assert las.header.are_points_compressed  # really LAZ, not LAS with another name
    assert las.header.point_count == len(x)
    np.testing.assert_array_equal(np.asarray(las.classification), cls)
    np.testing.assert_allclose(np.asarray(las["sigma_z"]), 0.05)
    assert las.header.parse_crs().to_epsg() == 25832
    assert path.stat().st_size < write_points(tmp_path / "forest.las", x, y, z,
                                              {"classification": cls}, "EPSG:25832"
                                              ).stat().st_size

    pts = read_points(path)
    assert len(pts) == len(x) and CRS.from_wkt(pts.crs).to_epsg() == 25832
    np.testing.assert_allclose(pts.x, x, atol=0.0005 + 1e-9)
    np.testing.assert_allclose(pts.z, z, atol=0.0005 + 1e-9)

    inp = read_filter_input(path, spacing=2.0)
    assert CRS.from_user_input(inp.crs).to_epsg() == 25832
    assert np.nanmin(inp.z) == pytest.approx(z.min(), abs=0.001)


def test_las_works_without_laz_backend(tmp_path, monkeypatch) -> None:
    monkeypatch.setattr(laspy.LazBackend, "detect_available", staticmethod(lambda: ()))
    x, y, z, cls = slope_with_trees(500)
    path = write_points(tmp_path / "p.las", x, y, z, {"classification": cls}, "EPSG:25832")
    assert len(read_points(path)) == 500
    with pytest.raises(InputError, match=r"no LAZ backend.*pip install \"laspy\[lazrs\]\""):
        write_points(tmp_path / "p.laz", x, y, z, {"classification": cls}, "EPSG:25832")
    assert not (tmp_path / "p.laz").exists()
    (tmp_path / "q.laz").write_bytes(path.read_bytes())
    for read in (read_points, read_filter_input):
        with pytest.raises(InputError, match=r"'q.laz'.*lazrs.*pip install"):
            read(tmp_path / "q.laz")
