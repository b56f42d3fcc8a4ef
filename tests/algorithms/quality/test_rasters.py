"""Hillshade, slope and the difference style: closed forms, window independence, the QML."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
import rasterio
from affine import Affine

from photodem.algorithms.errors import Cancelled, InputError
from photodem.algorithms.feedback import Feedback
from photodem.algorithms.quality.rasters import (
    DIFFERENCE_CLASSES,
    difference_style_qml,
    horn_gradient,
    shade,
    slope_degrees,
    style_path,
    write_difference_style,
    write_hillshade,
    write_slope,
)
from photodem.algorithms.raster.io import write_raster

CELL = 2.0
T = Affine(CELL, 0.0, 500_000.0, 0.0, -CELL, 5_600_000.0)


def _plane(a: float, b: float, shape=(300, 520)) -> np.ndarray:
    """z = a·x + b·y on the grid T (x east, y north)."""
    rows, cols = np.indices(shape)
    x = T.c + (cols + 0.5) * CELL
    y = T.f - (rows + 0.5) * CELL
    return (a * (x - T.c) + b * (y - T.f) + 100.0).astype(np.float64)


def test_horn_gradient_of_a_plane_is_exact() -> None:
    z = _plane(0.3, -0.2, (12, 14))
    p, q = horn_gradient(z, CELL, CELL)
    assert p.shape == (10, 12)
    np.testing.assert_allclose(p, 0.3, atol=1e-12)
    np.testing.assert_allclose(q, -0.2, atol=1e-12)
    np.testing.assert_allclose(slope_degrees(p, q), math.degrees(math.atan(math.hypot(0.3, 0.2))))


def test_shade_closed_forms() -> None:
    # flat ground: sin(altitude)
    assert shade(np.zeros(1), np.zeros(1), 315.0, 45.0)[0] == pytest.approx(math.sin(math.pi / 4))
    # a slope facing the sun at 45° under a sun at 45°: normal and light coincide → 1
    p = np.array([1.0 / math.sqrt(2)])  # rises towards the south-east: faces north-west
    q = np.array([-1.0 / math.sqrt(2)])
    assert shade(p, q, 315.0, 45.0)[0] == pytest.approx(1.0)
    # the opposite slope is in full shadow
    assert shade(-p, -q, 315.0, 45.0)[0] == 0.0


def test_slope_raster_windows_equal_one_window_and_edges(tmp_path: Path) -> None:
    z = _plane(0.1, 0.25) + 0.5 * np.sin(np.indices((300, 520))[1] / 7.0)
    z = z.astype(np.float32)
    z[100:104, 200:203] = np.nan
    dem = write_raster(tmp_path / "dem.tif", z, T, "EPSG:25832")
    small = write_slope(dem, tmp_path / "slope_256.tif", window_size=200)  # → 256 windows
    big = write_slope(dem, tmp_path / "slope_big.tif", window_size=4096)
    with rasterio.open(small) as a, rasterio.open(big) as b:
        sa, sb = a.read(1), b.read(1)
        assert a.dtypes[0] == "float32" and a.crs == b.crs and a.transform == T
    np.testing.assert_array_equal(sa, sb)
    # nodata spreads by exactly one cell (Horn's 3 × 3)
    assert np.isnan(sa[99:105, 199:204]).all()
    assert np.isfinite(sa[97, 199:204]).all() and np.isfinite(sa[100:104, 197]).all()
    # interior against the closed form of the plane part is checked above; edges are defined
    assert np.isfinite(sa[0]).all() and np.isfinite(sa[:, -1]).all()


def test_hillshade_uint8_with_nodata_zero(tmp_path: Path) -> None:
    z = _plane(0.0, 0.0, (40, 50)).astype(np.float32)
    z[5, 5] = np.nan
    dem = write_raster(tmp_path / "flat.tif", z, T, "EPSG:25832")
    out = write_hillshade(dem, tmp_path / "hs.tif")
    with rasterio.open(out) as src:
        hs = src.read(1)
        assert src.dtypes[0] == "uint8" and src.nodata == 0
    assert hs[5, 5] == 0 and hs[4, 4] == 0
    assert hs[20, 20] == 1 + round(254 * math.sin(math.radians(45.0)))


def test_geographic_dem_uses_metres(tmp_path: Path) -> None:
    # 1 m per 0.5° … rather: a plane rising 1 m per cell eastwards at 60° N, cells 0.0001°
    deg = 1e-4
    t = Affine(deg, 0.0, 10.0, 0.0, -deg, 60.0)
    cols = np.indices((20, 20))[1].astype(np.float32)
    dem = write_raster(tmp_path / "geo.tif", cols, t, "EPSG:4326")
    with rasterio.open(write_slope(dem, tmp_path / "s.tif")) as src:
        s = src.read(1)[10, 10]
    lat = 60.0 - 10.5 * deg
    dx = deg * 111_320.0 * math.cos(math.radians(lat))
    assert s == pytest.approx(math.degrees(math.atan(1.0 / dx)), rel=1e-5)


def test_cancel_leaves_no_raster(tmp_path: Path) -> None:
    dem = write_raster(tmp_path / "dem.tif", _plane(0.1, 0.1).astype(np.float32), T,
                       "EPSG:25832")
    fb = Feedback()
    fb.cancel()
    with pytest.raises(Cancelled):
        write_slope(dem, tmp_path / "slope.tif", window_size=256, feedback=fb)
    assert not any(p.name.startswith(("slope", ".slope")) for p in tmp_path.iterdir())
    with pytest.raises(InputError):
        write_hillshade(tmp_path / "missing.tif", tmp_path / "hs.tif")


def test_difference_style_file_matches_the_classes(tmp_path: Path) -> None:
    assert style_path().read_text(encoding="utf-8") == difference_style_qml()
    root = ET.fromstring(difference_style_qml().split("\n", 1)[1])
    shader = root.find(".//colorrampshader")
    assert shader is not None and shader.get("colorRampType") == "DISCRETE"
    items = shader.findall("item")
    assert len(items) == len(DIFFERENCE_CLASSES)
    values = [float(i.get("value")) for i in items]
    assert values == sorted(values) and values[-1] == math.inf
    # the neutral class is −0.25…+0.25, blue below, red above
    neutral = values.index(0.25)
    assert values[neutral - 1] == -0.25 and items[neutral].get("color") == "#ffffbf"
    assert values[0] == -5.0 and values[-2] == 5.0
    rgb = [tuple(int(i.get("color")[k:k + 2], 16) for k in (1, 3, 5)) for i in items]
    assert all(b > r for r, _, b in rgb[:neutral]) and all(r > b for r, _, b in rgb[neutral + 1:])
    raster = tmp_path / "difference.tif"
    qml = write_difference_style(raster)
    assert qml == tmp_path / "difference.qml" and qml.read_text() == difference_style_qml()
