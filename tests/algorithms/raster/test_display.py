"""Rasters for the screen (algorithms/raster/display.py): levels, tiles, reprojection, colours."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest
import rasterio
from affine import Affine
from raster_files import CRS, RES, X0, Y0, write_raster
from rasterio.enums import Resampling
from rasterio.warp import transform as warp_points

from photodem.algorithms.errors import InputError
from photodem.algorithms.quality.rasters import DIFFERENCE_CLASSES
from photodem.algorithms.raster import display
from photodem.algorithms.raster.display import TILE, TileGrid


def _dem(width: int, height: int) -> np.ndarray:
    rows, cols = np.mgrid[0:height, 0:width]
    return (50.0 + 0.02 * cols + 5.0 * np.sin(rows / 17.0) * np.cos(cols / 23.0)
            ).astype(np.float32)


_write = write_raster  # the shared writer


# -- level choice ---------------------------------------------------------------------------------
def test_level_choice_follows_the_zoom() -> None:
    grid = TileGrid.make((0.0, 0.0), (0.5, 0.5), (20000, 20000))
    assert grid.levels == 8  # 20000 / 2**7 = 156 ≤ 256
    assert grid.level_for(0.25) == 0  # zoomed in beyond full resolution
    assert grid.level_for(0.5) == 0
    assert grid.level_for(0.75) == 0  # 1.5 × coarser: level 1 would be upsampled too much
    assert grid.level_for(0.9) == 1  # 1.8 × coarser: level 1, drawn 11 % enlarged
    assert grid.level_for(1.0) == 1
    assert grid.level_for(1.7) == 2  # within the 25 % tolerance of level 2 (2.0)
    assert grid.level_for(4.0) == 3
    assert grid.level_for(1e6) == grid.levels - 1


def test_tiles_in_view_are_on_a_fixed_grid() -> None:
    grid = TileGrid.make((100.0, 1000.0), (1.0, 1.0), (1000, 600))
    tiles = grid.tiles_in((100.0, 1000.0 - 300.0, 100.0 + 300.0, 1000.0), 0)
    assert tiles == [(0, 0), (1, 0), (0, 1), (1, 1)]
    assert grid.tile_bounds(0, 1, 1) == (356.0, 488.0, 612.0, 744.0)
    # outside the raster: no tile; level 2 holds the raster in one row of tiles
    assert grid.tiles_in((-1e5, -1e5, 0.0, 0.0), 0) == []
    assert grid.tiles_in((100.0, 400.0, 1100.0, 1000.0), 2) == [(0, 0)]


# -- reading --------------------------------------------------------------------------------------
@pytest.mark.parametrize("overviews", [(2, 4, 8), ()])
def test_tile_equals_a_rasterio_decimated_read(tmp_path, overviews) -> None:
    z = _dem(1024, 768)
    path = _write(tmp_path / "dem.tif", z, overviews=overviews)
    with rasterio.open(path) as src:
        info = display.raster_info(src)
        grid = display.tile_grid(info, CRS)
        for level in (0, 1, 2):
            lw, lh = grid.level_size(level)
            whole = src.read(1, out_shape=(lh, lw), resampling=Resampling.nearest)
            for col, row in grid.tiles_in(info.bounds, level):
                tile = display.read_tile(src, info, grid, "dsm", (level, col, row))[0]
                part = whole[row * TILE:(row + 1) * TILE, col * TILE:(col + 1) * TILE]
                h, w = part.shape
                np.testing.assert_array_equal(tile[:h, :w], part)
                assert np.isnan(tile[h:, :]).all() and np.isnan(tile[:, w:]).all()


def test_hillshade_tiles_join_without_seams(tmp_path) -> None:
    z = _dem(600, 300)
    z[100:110, 250:270] = np.nan  # nodata across a tile border
    path = _write(tmp_path / "dem.tif", z, nodata=float("nan"))
    with rasterio.open(path) as src:
        info = display.raster_info(src)
        grid = display.tile_grid(info, CRS)
        style = display.make_style(src, info, "dsm")
        mosaic = np.zeros((2 * TILE, 3 * TILE, 4), dtype=np.uint8)
        for col, row in grid.tiles_in(info.bounds, 0):
            rgba = display.render_tile(src, info, grid, style, (0, col, row), CRS)
            mosaic[row * TILE:(row + 1) * TILE, col * TILE:(col + 1) * TILE] = rgba
    padded = np.pad(z.astype(np.float64), 1, constant_values=np.nan)
    whole = display.dem_rgba(padded, RES, RES, *style.stats[0])
    np.testing.assert_array_equal(mosaic[:300, :600], whole)
    assert (mosaic[100:110, 250:270, 3] == 0).all()  # nodata transparent


def test_reprojected_tile_puts_a_corner_pixel_where_it_belongs(tmp_path) -> None:
    """A raster in EPSG:4326 on a 25832 map: its top-left 3 × 3 block lands at its UTM place."""
    lon0, lat0, step = 9.0, 51.0, 0.0001
    z = np.zeros((200, 300), dtype=np.float32)
    z[:3, :3] = 1000.0
    path = _write(tmp_path / "geo.tif", z, crs="EPSG:4326",
                  transform=Affine(step, 0, lon0, 0, -step, lat0))
    with rasterio.open(path) as src:
        info = display.raster_info(src)
        assert display.needs_warp(info, CRS)
        grid = display.tile_grid(info, CRS)
        xs, ys = warp_points("EPSG:4326", CRS, [lon0 + 1.5 * step], [lat0 - 1.5 * step])
        col, row = ~grid.level_transform(0) * (xs[0], ys[0])
        key = (0, int(col // TILE), int(row // TILE))
        tile = display.read_tile(src, info, grid, "dsm", key, 0, CRS)[0]
        assert tile[int(row) % TILE, int(col) % TILE] == 1000.0
        # and a point well inside the raster is not the corner block
        xs, ys = warp_points("EPSG:4326", CRS, [lon0 + 150 * step], [lat0 - 100 * step])
        c2, r2 = ~grid.level_transform(0) * (xs[0], ys[0])
        tile2 = display.read_tile(src, info, grid, "dsm", (0, int(c2 // TILE), int(r2 // TILE)),
                                  0, CRS)[0]
        assert tile2[int(r2) % TILE, int(c2) % TILE] == 0.0
        assert display.read_value(src, info, xs[0], ys[0], CRS) == [0.0]


def test_read_value_is_the_pixel_value_and_nan_for_nodata(tmp_path) -> None:
    z = _dem(300, 200)
    z[50, 60] = -9999.0
    path = _write(tmp_path / "dem.tif", z, nodata=-9999.0)
    with rasterio.open(path) as src:
        info = display.raster_info(src)
        for col, row in [(0, 0), (299, 199), (123, 77), (60, 50)]:
            x, y = src.transform * (col + 0.5, row + 0.5)
            value = display.read_value(src, info, x, y, CRS)[0]
            expected = next(src.sample([(x, y)]))[0]
            if expected == -9999.0:
                assert math.isnan(value)
            else:
                assert value == expected
        assert display.read_value(src, info, X0 - 1.0, Y0, CRS) is None


# -- bad input ------------------------------------------------------------------------------------
def test_unreadable_raster_is_an_input_error_naming_the_file(tmp_path) -> None:
    bad = tmp_path / "broken_dsm.tif"
    bad.write_bytes(b"II*\x00 not really a tiff")
    with pytest.raises(InputError, match=r"broken_dsm\.tif"):
        display.open_raster(bad)
    with pytest.raises(InputError, match=r"missing\.tif"):
        display.open_raster(tmp_path / "missing.tif")


def test_raster_without_crs_is_in_pixel_coordinates(tmp_path) -> None:
    rgb = np.random.default_rng(1).integers(0, 255, (3, 100, 150), dtype=np.uint8)
    path = _write(tmp_path / "image.tif", rgb, crs=None, transform=Affine.identity())
    with rasterio.open(path) as src:
        info = display.raster_info(src)
    assert not info.has_crs
    assert info.bounds == (0.0, -100.0, 150.0, 0.0)  # x = col, y = −row
    assert display.guess_kind(info, path) == "image"
    assert not display.needs_warp(info, CRS)


# -- colours --------------------------------------------------------------------------------------
def test_difference_colours_are_the_qml_stops() -> None:
    root = ET.parse(display.STYLES / "dem_difference.qml").getroot()
    items = root.findall(".//colorrampshader/item")
    ramp = display.difference_ramp()
    assert ramp.discrete and len(ramp.values) == len(items) == len(DIFFERENCE_CLASSES)
    for item, (bound, colour, _) in zip(items, DIFFERENCE_CLASSES):
        value = float(item.get("value"))
        assert value == bound
        hexa = item.get("color")
        expected = [int(hexa[i:i + 2], 16) for i in (1, 3, 5)] + [255]
        below = value - 0.01 if math.isfinite(value) else 1e6
        assert display.apply_ramp(ramp, np.array([below])).tolist() == [expected]
        if math.isfinite(value):  # a value on the bound belongs to its class (≤)
            assert display.apply_ramp(ramp, np.array([value])).tolist() == [expected]
        assert hexa == colour
    assert display.apply_ramp(ramp, np.array([np.nan]))[0, 3] == 0


def test_elevation_ramp_is_blended_half_over_the_hillshade() -> None:
    ramp = display.elevation_ramp()
    assert ramp.opacity == 0.5 and not ramp.discrete
    flat = np.full((5, 5), 10.0)
    rgba = display.dem_rgba(flat, 1.0, 1.0, 10.0, 20.0)  # lowest colour over a flat shade
    grey = 255.0 * math.sin(math.radians(45.0))
    low = ramp.colors[0, :3].astype(float)
    np.testing.assert_allclose(rgba[1, 1, :3], 0.5 * low + 0.5 * grey, atol=1.0)
    assert (rgba[..., 3] == 255).all()


def test_rgb_with_alpha_and_16_bit_stretch(tmp_path) -> None:
    rgba = np.zeros((4, 64, 64), dtype=np.uint8)
    rgba[:3] = 120
    rgba[3, :, :32] = 255  # right half transparent
    path = tmp_path / "ortho.tif"
    _write(path, rgba)
    with rasterio.open(path, "r+") as dst:
        dst.colorinterp = [rasterio.enums.ColorInterp.red, rasterio.enums.ColorInterp.green,
                           rasterio.enums.ColorInterp.blue, rasterio.enums.ColorInterp.alpha]
    with rasterio.open(path) as src:
        info = display.raster_info(src)
        assert info.alpha_band == 4 and info.rgb_bands == (1, 2, 3)
        grid = display.tile_grid(info, CRS)
        style = display.make_style(src, info, "ortho")
        out = display.render_tile(src, info, grid, style, (0, 0, 0), CRS)
    assert (out[:64, :32, 3] == 255).all() and (out[:64, 32:, 3] == 0).all()
    assert (out[:64, :32, :3] == 120).all()
    wide = np.linspace(0, 4000, 64 * 64, dtype=np.uint16).reshape(64, 64)
    grey = display.image_rgba(wide[None].astype(np.float32), [(100.0, 3900.0)], False)
    assert grey[0, 0, 0] == 0 and grey[-1, -1, 0] == 255 and grey[32, 0, 0] == grey[32, 0, 2]


def test_external_overviews_leave_the_raster_untouched(tmp_path) -> None:
    path = _write(tmp_path / "big.tif", _dem(2100, 300))
    before = path.read_bytes()
    with rasterio.open(path) as src:
        assert display.raster_info(src).needs_overviews
    ovr = display.build_external_overviews(path)
    assert ovr == tmp_path / "big.tif.ovr" and ovr.is_file()
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["big.tif", "big.tif.ovr"]
    with rasterio.open(path) as src:
        info = display.raster_info(src)
        assert info.overviews and not info.needs_overviews
    with pytest.raises(InputError, match="exists already"):
        display.build_external_overviews(path)
