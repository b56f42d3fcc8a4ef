"""Re-drape of one edit feature (shared by the QGIS and the standalone tools, issue 21)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import rasterio
from rasterio.transform import from_origin
from shapely.geometry import LineString, MultiLineString, Point

from photodem.algorithms.errors import InputError
from photodem.algorithms.project.edit_tools import REDRAPE_LAYERS, redrape_feature


def plane(x, y):
    return 100.0 + 0.01 * (np.asarray(x) - 1000.0) - 0.02 * (np.asarray(y) - 2000.0)


@pytest.fixture(scope="module")
def surface(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("plane") / "plane.tif"
    xx, yy = np.meshgrid(1000 + np.arange(100) + 0.5, 2100 - np.arange(100) - 0.5)
    z = plane(xx, yy)
    z[50, 50] = -9999.0
    with rasterio.open(path, "w", driver="GTiff", width=100, height=100, count=1,
                       dtype="float64", transform=from_origin(1000, 2100, 1, 1), nodata=-9999.0,
                       crs="EPSG:25832") as dst:
        dst.write(z, 1)
    return path


def test_every_layer_gets_the_surface_heights(surface: Path) -> None:
    line = LineString([(1010.2, 2010.7, 0.0), (1030.9, 2040.1, 0.0)])
    answer = redrape_feature(surface, "breaklines", line)
    assert answer.ok and answer.height is None
    for x, y, z in answer.geometry.coords:
        assert z == pytest.approx(float(plane(x, y)), abs=1e-9)
    multi = redrape_feature(surface, "breaklines", MultiLineString([line, [(1060, 2060),
                                                                           (1070, 2070)]]))
    assert multi.geometry.geom_type == "MultiLineString" and multi.geometry.has_z
    start = redrape_feature(surface, "start_points", Point(1020.5, 2030.25), crs="EPSG:25832")
    assert start.geometry is None and start.height == pytest.approx(float(plane(1020.5, 2030.25)))
    ground = redrape_feature(surface, "ground_points", Point(1020.5, 2030.25, 7.0))
    assert ground.geometry.coords[0] == pytest.approx((1020.5, 2030.25, start.height))
    assert set(REDRAPE_LAYERS) == {"breaklines", "start_points", "ground_points", "check_points"}


def test_no_height_says_why_and_bad_layers_are_refused(surface: Path) -> None:
    hole = redrape_feature(surface, "check_points", Point(1050.5, 2049.5, 1.0))
    assert not hole.ok and "nodata" in hole.reason and hole.geometry is None
    out = redrape_feature(surface, "breaklines", LineString([(1010, 2010), (900, 2010)]))
    assert "outside" in out.reason
    with pytest.raises(InputError, match="no heights"):
        redrape_feature(surface, "seamlines", LineString([(1010, 2010), (1020, 2010)]))
