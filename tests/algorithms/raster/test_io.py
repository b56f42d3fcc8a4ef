"""Raster outputs: overview rule and Cloud-Optimised GeoTIFFs written through a scratch file."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

rasterio = pytest.importorskip("rasterio")

from rasterio.enums import ColorInterp, Resampling  # noqa: E402

from photodem.algorithms.raster.io import (  # noqa: E402
    GTIFF_PROFILE,
    cog_output,
    overview_factors,
)


def test_overview_factors_stop_near_one_block() -> None:
    assert overview_factors(255, 100) == []
    assert overview_factors(512, 40) == [2]
    assert overview_factors(1208, 685) == [2, 4]
    assert overview_factors(20000, 20000) == [2, 4, 8, 16, 32, 64]


def _profile(data: np.ndarray) -> dict:
    return dict(GTIFF_PROFILE, width=data.shape[2], height=data.shape[1], count=data.shape[0],
                dtype="uint8", crs="EPSG:25832", predictor=2,
                transform=rasterio.Affine(0.5, 0, 400000, 0, -0.5, 5600000))


def _write(path: Path, data: np.ndarray, profile: dict) -> None:
    with rasterio.open(path, "w", **profile) as dst:
        dst.write(data)
        dst.colorinterp = [ColorInterp.red, ColorInterp.green, ColorInterp.blue,
                           ColorInterp.alpha]
        dst.update_tags(PHOTODEM_IMAGE="x")
        dst.build_overviews(overview_factors(dst.width, dst.height), Resampling.average)


def test_cog_output_has_the_cog_layout_and_keeps_everything(tmp_path: Path) -> None:
    rng = np.random.default_rng(3)
    data = rng.integers(0, 255, (4, 700, 900), dtype=np.uint8)
    plain = tmp_path / "plain.tif"
    _write(plain, data, _profile(data))
    with cog_output(tmp_path / "cog.tif", _profile(data)) as (scratch, profile):
        assert profile["compress"] == "none"  # the only compression is the copy's
        _write(scratch, data, profile)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cog.tif", "plain.tif"]
    with rasterio.open(tmp_path / "cog.tif") as cog, rasterio.open(plain) as ref:
        assert cog.tags(ns="IMAGE_STRUCTURE")["LAYOUT"] == "COG"
        assert "LAYOUT" not in ref.tags(ns="IMAGE_STRUCTURE")
        assert cog.overviews(1) == [2] and cog.block_shapes[0] == (256, 256)
        assert cog.compression == ref.compression
        assert cog.tags(ns="IMAGE_STRUCTURE")["PREDICTOR"] == "2"
        assert cog.colorinterp == ref.colorinterp and cog.tags()["PHOTODEM_IMAGE"] == "x"
        assert cog.crs == ref.crs and cog.transform == ref.transform
        assert np.array_equal(cog.read(), data)
        assert np.array_equal(cog.read(1, out_shape=(350, 450)), ref.read(1, out_shape=(350, 450)))


def test_cog_output_leaves_nothing_on_failure(tmp_path: Path) -> None:
    target = tmp_path / "out.tif"
    target.write_bytes(b"earlier result")
    data = np.zeros((4, 300, 300), np.uint8)
    with pytest.raises(RuntimeError), cog_output(target, _profile(data)) as (scratch, profile):
        _write(scratch, data, profile)
        raise RuntimeError("cancelled")
    assert [p.name for p in tmp_path.iterdir()] == ["out.tif"]
    assert target.read_bytes() == b"earlier result"


def test_gtiff_profile_tiles_large_rasters_only() -> None:
    from photodem.algorithms.raster.io import gtiff_profile

    big = gtiff_profile(300, 400, 2, "uint16", "EPSG:25832", nodata=0, predictor=2)
    assert big["tiled"] and big["blockxsize"] == 256 and big["crs"] == "EPSG:25832"
    assert (big["width"], big["height"], big["count"], big["dtype"]) == (300, 400, 2, "uint16")
    assert big["nodata"] == 0 and big["predictor"] == 2 and big["compress"] == "deflate"
    small = gtiff_profile(300, 255)
    assert not small["tiled"] and "blockxsize" not in small and "crs" not in small
    assert small["dtype"] == "float32" and small["count"] == 1
    assert "crs" not in gtiff_profile(300, 300, crs="")  # image space: no CRS
