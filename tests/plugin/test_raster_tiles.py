"""RasterLayer of the standalone map (pytest-qt): tiles in threads, cache, values, bad input."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest
import rasterio
from affine import Affine

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
pytest.importorskip("pytestqt")

from raster_files import CRS, RES, X0, Y0, write_raster

from photodem.algorithms.errors import InputError
from photodem.algorithms.raster.display import TILE
from photodem.plugin.qt import QtGui
from photodem.plugin.widgets import raster_tiles
from photodem.plugin.widgets.map_layer import ViewState
from photodem.plugin.widgets.raster_tiles import RasterLayer, TileCache

NODATA = -9999.0


_write = write_raster  # the shared writer


@pytest.fixture
def dem(tmp_path):
    rows, cols = np.mgrid[0:700, 0:900]
    z = (50.0 + 0.02 * cols + 4.0 * np.sin(rows / 13.0)).astype(np.float32)
    z[300:340, 400:460] = NODATA
    return _write(tmp_path / "dsm.tif", z, nodata=NODATA)


def _fit(layer, width=600, height=450):
    b = layer.bounds()
    s = max((b[2] - b[0]) / width, (b[3] - b[1]) / height) * 1.02
    cx, cy = (b[0] + b[2]) / 2, (b[1] + b[3]) / 2
    crs = layer.map_crs if layer.has_crs else ""
    return ViewState((cx - width / 2 * s, cy - height / 2 * s, cx + width / 2 * s,
                      cy + height / 2 * s), width, height, crs)


def _paint(layer, view):
    image = QtGui.QImage(view.width, view.height, QtGui.QImage.Format_ARGB32_Premultiplied)
    image.fill(0)
    painter = QtGui.QPainter(image)
    layer.paint(painter, view)
    painter.end()
    return image


def test_dem_is_drawn_in_threads_and_nodata_stays_transparent(qapp, dem) -> None:
    layer = RasterLayer(dem, map_crs=CRS)
    try:
        assert layer.kind == "dsm" and layer.has_crs and not layer.needs_overviews
        view = _fit(layer)
        _paint(layer, view)  # requests the tiles
        assert layer.wait(10000)
        assert layer.missing() == 0
        image = _paint(layer, view)
        inside = view.to_pixel(X0 + 100 * RES, Y0 - 100 * RES)
        hole = view.to_pixel(X0 + 430 * RES, Y0 - 320 * RES)
        assert image.pixelColor(int(inside.x()), int(inside.y())).alpha() == 255
        assert image.pixelColor(int(hole.x()), int(hole.y())).alpha() == 0
        assert image.pixelColor(0, 0).alpha() == 0  # beside the raster
    finally:
        layer.close()


def test_value_at_is_the_raster_value(qapp, dem) -> None:
    layer = RasterLayer(dem, map_crs=CRS, name="DSM test")
    try:
        with rasterio.open(dem) as src:
            for col, row in [(0, 0), (899, 699), (123, 456), (410, 310)]:
                x, y = src.transform * (col + 0.5, row + 0.5)
                expected = float(next(src.sample([(x, y)]))[0])
                text = layer.value_at(x, y)
                if expected == NODATA:
                    assert text == "DSM test: nodata"
                    assert math.isnan(layer.sample(x, y)[0])
                else:
                    assert text == f"DSM test: {expected:.2f} m"
                    assert layer.sample(x, y) == [pytest.approx(expected)]
        assert layer.value_at(X0 - 1.0, Y0 + 1.0) is None
    finally:
        layer.close()


def test_rgb_value_and_no_crs_layer_in_pixel_coordinates(qapp, tmp_path) -> None:
    rgb = np.zeros((3, 50, 80), dtype=np.uint8)
    rgb[0], rgb[1], rgb[2] = 10, 20, 30
    path = _write(tmp_path / "frame.tif", rgb, crs=None, transform=Affine.identity())
    layer = RasterLayer(path, map_crs=CRS)
    try:
        assert not layer.has_crs and layer.kind == "image"
        assert layer.bounds() == (0.0, -50.0, 80.0, 0.0)
        assert layer.value_at(5.5, -7.5) == "frame: 10,20,30"
        view = _fit(layer)
        assert view.crs == ""
        _paint(layer, view)
        assert layer.wait(10000)
        image = _paint(layer, view)
        centre = view.to_pixel(40.0, -25.0)
        colour = image.pixelColor(int(centre.x()), int(centre.y()))
        assert (colour.red(), colour.green(), colour.blue()) == (10, 20, 30)
    finally:
        layer.close()


def test_unreadable_raster_raises_input_error_with_its_name(qapp, tmp_path) -> None:
    bad = tmp_path / "damaged_mosaic.tif"
    bad.write_bytes(b"\x00" * 100)
    with pytest.raises(InputError, match=r"damaged_mosaic\.tif"):
        RasterLayer(bad)


def test_cache_is_bounded_and_least_recently_used_goes_first() -> None:
    tile = QtGui.QImage(TILE, TILE, QtGui.QImage.Format_RGBA8888)
    cache = TileCache(max_bytes=3 * tile.sizeInBytes())
    for i in range(3):
        cache.put((1, (0, i, 0)), QtGui.QImage(tile))
    assert cache.get((1, (0, 0, 0))) is not None  # now the most recent
    for i in range(3, 10):
        cache.put((1, (0, i, 0)), QtGui.QImage(tile))
        assert cache.nbytes <= cache.max_bytes and len(cache) <= 3
    assert (1, (0, 0, 0)) not in cache and (1, (0, 9, 0)) in cache
    cache.put((2, (0, 0, 0)), QtGui.QImage(tile))
    cache.drop(1)
    assert len(cache) == 1 and cache.nbytes == tile.sizeInBytes()


def test_zoom_in_draws_the_coarser_tile_until_the_fine_one_arrives(qapp, dem) -> None:
    layer = RasterLayer(dem, map_crs=CRS)
    try:
        whole = _fit(layer, 200, 150)  # a coarse level
        _paint(layer, whole)
        assert layer.wait(10000)
        cx, cy = X0 + 100 * RES, Y0 - 100 * RES
        close = ViewState((cx - 30.0, cy - 20.0, cx + 30.0, cy + 20.0), 600, 400, CRS)
        assert layer._source.grid.level_for(close.map_units_per_pixel) == 0
        image = _paint(layer, close)  # fine tiles are not there yet
        assert image.pixelColor(300, 200).alpha() == 255
        assert layer.wait(10000)
    finally:
        layer.close()


def test_a_tile_that_left_the_view_is_not_rendered(qapp, dem) -> None:
    layer = RasterLayer(dem, map_crs=CRS)
    try:
        source = layer._source
        source.wanted = frozenset({(0, 0, 0)})
        assert source.render((0, 1, 1)) is None  # stale: dropped before reading
        assert source.render((0, 0, 0)).width() == TILE
    finally:
        layer.close()


def test_build_overviews_into_the_sidecar(qapp, tmp_path) -> None:
    z = np.tile(np.arange(2100, dtype=np.float32), (300, 1))
    path = _write(tmp_path / "wide_dsm.tif", z)
    before = path.read_bytes()
    layer = RasterLayer(path, map_crs=CRS)
    try:
        assert layer.needs_overviews
        ovr = layer.build_overviews()
        assert ovr.name == "wide_dsm.tif.ovr" and not layer.needs_overviews
        assert path.read_bytes() == before
        view = _fit(layer)
        _paint(layer, view)
        assert layer.wait(10000)
    finally:
        layer.close()


def test_a_raster_in_another_crs_is_placed_on_the_map(qapp, tmp_path) -> None:
    z = np.full((100, 100), 7.0, dtype=np.float32)
    path = _write(tmp_path / "utm31.tif", z, crs="EPSG:32631",
                  transform=Affine(1.0, 0, 700000.0, 0, -1.0, 5650000.0))
    layer = RasterLayer(path, kind="dtm", map_crs=CRS)
    try:
        b = layer.bounds()
        assert 250000 < b[0] < 300000  # UTM 31 east of 6° E lands west on the 32 N grid
        x, y = (b[0] + b[2]) / 2, (b[1] + b[3]) / 2
        assert layer.value_at(x, y).endswith("7.00 m")
        view = _fit(layer)
        _paint(layer, view)
        assert layer.wait(10000)
        image = _paint(layer, view)
        centre = view.to_pixel(x, y)
        assert image.pixelColor(int(centre.x()), int(centre.y())).alpha() == 255
    finally:
        layer.close()


def test_the_pool_is_shared(qapp) -> None:
    assert raster_tiles.thread_pool() is raster_tiles.thread_pool()
    assert raster_tiles.thread_pool().maxThreadCount() >= 2


def test_a_dropped_tile_wanted_again_is_asked_for_anew(qapp, dem) -> None:
    layer = RasterLayer(dem, map_crs=CRS)
    try:
        source, key = layer._source, (0, 0, 0)
        source.wanted = frozenset({key})
        layer._tile_done(source, key, None)  # dropped as stale while the view came back
        assert key in layer._pending
        assert layer.wait(10000) and layer.missing() == 0
    finally:
        layer.close()


def test_a_failing_tile_is_not_retried(qapp, dem, monkeypatch) -> None:
    layer = RasterLayer(dem, map_crs=CRS)
    try:
        def broken(*args, **kwargs):
            raise OSError("disk gone")

        monkeypatch.setattr(raster_tiles.display, "render_tile", broken)
        view = _fit(layer)
        _paint(layer, view)
        assert layer.wait(10000)  # nothing pending: the failures are final
        assert layer.missing() > 0 and layer._failed
        _paint(layer, view)
        assert not layer._pending
    finally:
        layer.close()
