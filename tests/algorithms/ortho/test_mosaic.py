"""Mosaic of orthos in the shared format: seams, occlusion fill, balancing, feathering, tiles."""

from __future__ import annotations

import json
import tracemalloc
from pathlib import Path
from types import SimpleNamespace
from typing import Optional, Tuple

import numpy as np
import pytest
import rasterio
from affine import Affine
from rasterio.enums import ColorInterp
from scipy import ndimage
from shapely.geometry import LineString, box

from photodem.algorithms.errors import InputError
from photodem.algorithms.ortho.mosaic import mosaic_orthos, read_ortho_info

CRS = "EPSG:32633"
GSD = 0.5
X0, Y1 = 500000.0, 5600120.0  # mosaic corner: 200 m × 120 m, 400 × 240 cells
BUILDING = box(X0 + 92, Y1 - 80, X0 + 108, Y1 - 50)  # straddles the nadir boundary x = 100 m


def texture(h: int, w: int, seed: int = 1) -> np.ndarray:
    """Smooth random texture, 20…230 DN, plus a gentle gradient."""
    rng = np.random.default_rng(seed)
    t = ndimage.gaussian_filter(rng.normal(size=(h, w)), 3.0)
    t = (t - t.min()) / (t.max() - t.min())
    return 20 + 170 * t + np.linspace(0, 40, w)[None, :]


def write_ortho(path: Path, data: np.ndarray, alpha: np.ndarray, col0: int,
                centre: Tuple[float, float], name: str) -> Path:
    """An ortho in the shared format (bands + alpha, tags, visibility sibling)."""
    data = data[None] if data.ndim == 2 else data
    nb, h, w = data.shape
    tr = Affine(GSD, 0, X0 + col0 * GSD, 0, -GSD, Y1)
    prof = {"driver": "GTiff", "width": w, "height": h, "count": nb + 1, "dtype": "uint8",
            "crs": CRS, "transform": tr, "tiled": True, "blockxsize": 128,
            "blockysize": 128}
    with rasterio.open(path, "w", **prof) as dst:
        dst.write(np.clip(np.rint(data), 0, 255).astype(np.uint8), list(range(1, nb + 1)))
        dst.write(alpha.astype(np.uint8), nb + 1)
        interp = [ColorInterp.red, ColorInterp.green, ColorInterp.blue] if nb == 3 \
            else [ColorInterp.gray]
        dst.colorinterp = [*interp, ColorInterp.alpha]
        dst.update_tags(PHOTODEM_IMAGE=name, PHOTODEM_CAMERA_X=str(centre[0]),
                        PHOTODEM_CAMERA_Y=str(centre[1]), PHOTODEM_CAMERA_Z="1000",
                        PHOTODEM_TRUE_ORTHO="0")
    vis = np.where(alpha > 0, 1, 0).astype(np.uint8)
    with rasterio.open(path.with_name(f"{path.stem}_visibility.tif"), "w",
                       **{**prof, "count": 1}) as dst:
        dst.write(vis, 1)
    return path


def two_orthos(folder: Path, b_fn=None, a_fn=None, occluded: Optional[Tuple] = None,
               bands: Tuple[int, int] = (1, 1)) -> Tuple[Path, Path, np.ndarray]:
    """A (x 0–130 m, nadir x = 40 m) and B (x 70–200 m, nadir x = 160 m) over one texture."""
    T = texture(240, 400)
    a = T[:, :260] if a_fn is None else a_fn(T[:, :260])
    b = T[:, 140:] if b_fn is None else b_fn(T[:, 140:])
    alpha_a = np.full(a.shape, 255, np.uint8)
    alpha_b = np.full(b.shape, 255, np.uint8)
    if occluded is not None:  # (r0, r1, c0, c1) of the mosaic, occluded in A
        r0, r1, c0, c1 = occluded
        alpha_a[r0:r1, c0:c1] = 0
    if bands[0] == 3:
        a = np.stack([a, a * 0.9, a * 0.8])
    if bands[1] == 3:
        b = np.stack([b, b * 0.9, b * 0.8])
    pa = write_ortho(folder / "A.tif", a, alpha_a, 0, (X0 + 40, Y1 - 60), "A")
    pb = write_ortho(folder / "B.tif", b, alpha_b, 140, (X0 + 160, Y1 - 60), "B")
    return pa, pb, T


def surfaces(folder: Path) -> Tuple[Path, Path]:
    """DTM (100 m) and DSM with the building (+10 m) on a 0.5 m grid."""
    from rasterio.features import rasterize

    tr = Affine(GSD, 0, X0, 0, -GSD, Y1)
    dtm = np.full((240, 400), 100.0, np.float32)
    bmask = rasterize([(BUILDING, 1)], out_shape=dtm.shape, transform=tr) > 0
    dsm = dtm + 10.0 * bmask
    prof = {"driver": "GTiff", "width": 400, "height": 240, "count": 1, "dtype": "float32",
            "crs": CRS, "transform": tr}
    paths = []
    for name, arr in (("dtm.tif", dtm), ("dsm.tif", dsm)):
        with rasterio.open(folder / name, "w", **prof) as dst:
            dst.write(arr.astype(np.float32), 1)
        paths.append(folder / name)
    return paths[0], paths[1]


def read_mosaic(path: Path) -> Tuple[np.ndarray, np.ndarray]:
    with rasterio.open(path) as src:
        data = src.read()
        assert src.colorinterp[-1] == ColorInterp.alpha
    return data[:-1].astype(np.float64), data[-1]


def source_map(mosaic: np.ndarray, T: np.ndarray, offset_b: float) -> np.ndarray:
    """0 where the mosaic shows A (= T), 1 where B (= T + offset), −1 elsewhere."""
    ta = np.clip(np.rint(T), 0, 255)
    tb = np.clip(np.rint(T + offset_b), 0, 255)
    return np.where(mosaic == ta, 0, np.where(mosaic == tb, 1, -1))


def test_reads_the_shared_format(tmp_path: Path) -> None:
    pa, _, _ = two_orthos(tmp_path)
    info = read_ortho_info(pa)
    assert info.name == "A" and info.alpha == 2 and info.colour == [1]
    assert info.centre == (X0 + 40, Y1 - 60) and info.centre_from_tags


def test_auto_seams_avoid_the_building(tmp_path: Path) -> None:
    pa, pb, T = two_orthos(tmp_path, b_fn=lambda t: t + 50)
    dtm, dsm = surfaces(tmp_path)
    out = tmp_path / "mosaic.tif"
    res = mosaic_orthos([pa, pb], out, balance="none", feather=0.0, dsm=dsm, dtm=dtm)
    assert res["seams"]["seam_cells_on_objects_before"] > 0  # the nadir seam cuts it
    assert res["seams"]["seam_cells_on_objects_after"] == 0
    data, alpha = read_mosaic(out)
    assert (alpha == 255).all()
    import rasterio

    with rasterio.open(out) as ds:  # the deliverable is a Cloud-Optimised GeoTIFF
        assert ds.tags(ns="IMAGE_STRUCTURE").get("LAYOUT") == "COG"
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []
    src = source_map(data[0], T, 50)
    assert (src >= 0).all()
    from rasterio.features import rasterize

    bmask = rasterize([(BUILDING, 1)], out_shape=src.shape,
                      transform=Affine(GSD, 0, X0, 0, -GSD, Y1)) > 0
    assert len(np.unique(src[bmask])) == 1  # the whole roof from one image
    # nadir regions far from the seam are unchanged
    assert (src[:, :140] == 0).all() and (src[:, 260:] == 1).all()
    # the seamline vector avoids the footprint, polygons carry the image names
    import fiona
    from shapely.geometry import shape

    with fiona.open(res["seamlines"], layer="seamlines") as f:
        lines = [shape(r["geometry"]) for r in f]
    assert lines and not any(ln.intersects(BUILDING.buffer(-0.01)) for ln in lines)
    with fiona.open(res["seamlines"], layer="footprints") as f:
        assert sorted(r["properties"]["image"] for r in f) == ["A", "B"]


def test_occluded_cells_filled_from_the_other_image(tmp_path: Path) -> None:
    occ = (100, 140, 160, 180)  # rows, cols (mosaic) in A's part of the overlap
    pa, pb, T = two_orthos(tmp_path, b_fn=lambda t: t + 50, occluded=occ)
    out = tmp_path / "mosaic.tif"
    res = mosaic_orthos([pa, pb], out, balance="none", feather=0.0, seamlines="nadir")
    data, alpha = read_mosaic(out)
    src = source_map(data[0], T, 50)
    r0, r1, c0, c1 = occ
    assert (alpha[r0:r1, c0:c1] == 255).all()
    assert (src[r0:r1, c0:c1] == 1).all()  # filled from B
    assert (src[:, 150:200][src[:, 150:200] >= 0].size > 0)
    assert (src[r1:, 150:200] == 0).all()  # around it still A
    assert 0.0 <= res["filled_pct"] < 1.0
    # on a coarser seam grid the partial cells are filled at full resolution
    occ = (101, 139, 161, 179)
    pa, pb, T = two_orthos(tmp_path, b_fn=lambda t: t + 50, occluded=occ)
    mosaic_orthos([pa, pb], out, balance="none", feather=0.0, seamlines="nadir",
                  seam_cells=50)
    src = source_map(read_mosaic(out)[0][0], T, 50)
    r0, r1, c0, c1 = occ
    assert (src[r0:r1, c0:c1] == 1).all() and (src[r1 + 8:, 150:190] == 0).all()


def test_balancing_recovers_known_gain_and_offset(tmp_path: Path) -> None:
    pa, pb, _ = two_orthos(tmp_path, b_fn=lambda t: 1.2 * t - 15)
    out = tmp_path / "mosaic.tif"
    res = mosaic_orthos([pa, pb], out, balance="gain_offset", reference="A")
    report = json.loads(Path(res["report"]).read_text())
    before, after = report["before"], report["after"]
    assert before["mean_difference"] > 5
    assert after["mean_difference"] <= 2.0 and after["mean_abs_difference"] <= 2.0
    gb = report["images"][1]["gains"][0]
    ob = report["images"][1]["offsets"][0]
    assert gb == pytest.approx(1 / 1.2, rel=0.01)
    assert ob == pytest.approx(15 / 1.2, abs=1.0)
    assert report["images"][0]["gains"] == [1.0] and report["images"][0]["offsets"] == [0.0]


def test_feathering_is_a_smooth_ramp(tmp_path: Path) -> None:
    pa, pb, _ = two_orthos(tmp_path, a_fn=lambda t: np.full(t.shape, 100.0),
                           b_fn=lambda t: np.full(t.shape, 160.0))
    out = tmp_path / "mosaic.tif"
    mosaic_orthos([pa, pb], out, balance="none", feather=10.0, seamlines="nadir")
    data, _ = read_mosaic(out)
    row = data[0, 120]
    steps = np.diff(row)
    assert (steps >= 0).all() and steps.max() <= 60 / 20 + 1  # 20 cells wide, no jump
    ramp = np.nonzero((row > 100) & (row < 160))[0]
    assert 18 <= ramp.size <= 21 and abs(ramp.mean() - 199.5) <= 1.0
    assert (data[0, :, :185] == 100).all() and (data[0, :, 215:] == 160).all()


def test_operator_seamlines_are_honoured(tmp_path: Path) -> None:
    from photodem.algorithms.project.edits import add_features, create_edits

    pa, pb, T = two_orthos(tmp_path, b_fn=lambda t: t + 50)
    edits = create_edits(tmp_path / "edits.gpkg", CRS)
    add_features(edits, "seamlines", [(LineString([(X0 + 85, Y1 + 10), (X0 + 85, Y1 - 130)]),
                                       {"note": "along the road"})])
    project = SimpleNamespace(edits_path=edits)
    out = tmp_path / "mosaic.tif"
    res = mosaic_orthos([pa, pb], out, balance="none", feather=0.0, seamlines="edits",
                        project=project)
    assert res["seams"]["mode"] == "operator"
    data, _ = read_mosaic(out)
    src = source_map(data[0], T, 50)
    assert (src[:, :170] == 0).all() and (src[:, 170:] == 1).all()  # cut at x = 85 m
    # a polygon with an image attribute wins (the footprints layer can be edited and reused)
    import fiona
    from shapely.geometry import mapping

    poly = box(X0 + 110, Y1 - 40, X0 + 125, Y1 - 20)
    schema = {"geometry": "Polygon", "properties": {"image": "str"}}
    with fiona.open(tmp_path / "mine.gpkg", "w", driver="GPKG", schema=schema,
                    crs="EPSG:32633") as f:
        f.write({"geometry": mapping(poly), "properties": {"image": "A"}})
    out2 = tmp_path / "mosaic2.tif"
    mosaic_orthos([pa, pb], out2, balance="none", feather=0.0,
                  seamlines=str(tmp_path / "mine.gpkg"))
    src2 = source_map(read_mosaic(out2)[0][0], T, 50)
    assert (src2[40:80, 220:250] == 0).all()
    assert (src2[:, 260:] == 1).all() and (src2[:, :140] == 0).all()


def test_different_band_counts_give_one_clear_error(tmp_path: Path) -> None:
    pa, pb, _ = two_orthos(tmp_path, bands=(3, 1))
    with pytest.raises(InputError) as err:
        mosaic_orthos([pa, pb], tmp_path / "m.tif")
    msg = str(err.value)
    assert "different band counts" in msg and "A.tif: 3" in msg and "\n" not in msg
    assert not (tmp_path / "m.tif").exists()


def test_tiles_give_the_same_mosaic_and_bounded_memory(tmp_path: Path) -> None:
    pa, pb, _ = two_orthos(tmp_path, b_fn=lambda t: 1.1 * t + 5)
    dtm, dsm = surfaces(tmp_path)
    big = tmp_path / "big.tif"
    small = tmp_path / "small.tif"
    opts = {"feather": 4.0, "dsm": dsm, "dtm": dtm, "seam_cells": 100}
    peaks, results = [], []
    for path, tile in ((big, 1024), (small, 64)):
        tracemalloc.start()
        results.append(mosaic_orthos([pa, pb], path, tile=tile, **opts))
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
    r1, r2 = results
    assert r1["seam_factor"] == r2["seam_factor"] == 4
    assert r2["seams"]["seam_cells_on_objects_after"] == 0
    a, b = read_mosaic(big), read_mosaic(small)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    # the tiles bound the memory: 64-cell tiles need a fraction of the one-tile run
    assert peaks[1] < 0.3 * peaks[0], peaks
