"""project_create / project_info through the registry, on the NGI block and a small block."""

from __future__ import annotations

from pathlib import Path

import fiona
import numpy as np
import pytest
import rasterio
from scipy.ndimage import map_coordinates

from photodem.algorithms.errors import InputError
from photodem.algorithms.feedback import Feedback
from photodem.algorithms.geometry.projection import world_to_pixel
from photodem.algorithms.processing import registry
from photodem.algorithms.project.edits import EDIT_LAYERS
from photodem.algorithms.project.model import Project

pytestmark = pytest.mark.filterwarnings("ignore::rasterio.errors.NotGeoreferencedWarning")
NGI_STRIP_MODELS = {
    ("3324c_2015_1004_05_0182_RGB", "3324c_2015_1004_05_0184_RGB"),
    ("3324c_2015_1004_06_0251_RGB", "3324c_2015_1004_06_0253_RGB"),
}


def create_ngi(ngi: Path, out: Path, **extra) -> dict:
    params = {"images": ngi / "ngi", "exterior": ngi / "io" / "ngi_xyz_opk.csv",
              "interior": ngi / "io" / "ngi_int_param.yaml", "dem": ngi / "ngi" / "dem.tif",
              "output": out}
    params.update(extra)
    return registry.run("project_create", {k: str(v) for k, v in params.items()}, Feedback())


def grey_at(path: Path, col: np.ndarray, row: np.ndarray) -> np.ndarray:
    with rasterio.open(path) as src:
        grey = src.read().astype(float).mean(axis=0)
    return map_coordinates(grey, [row, col], order=1, mode="nearest")


def test_ngi_block(ngi_block: Path, tmp_path: Path) -> None:
    out = create_ngi(ngi_block, tmp_path / "ngi")
    assert out["images"] == 4 and out["cameras"] == 1 and out["warnings"] == []
    project = Project.load(out["project"])
    assert (Path(out["project"]) / "edits.gpkg").is_file()
    strip = [m for m in project.models if m.kind == "in-strip"]
    assert {(m.left, m.right) for m in strip} == NGI_STRIP_MODELS
    assert project.models[:2] == strip  # in-strip models first
    for m in strip:
        assert 0.25 <= m.overlap <= 0.35, m
        assert m.b_h == pytest.approx(0.54, abs=0.02), m
        assert m.height_above_ground == pytest.approx(4850, abs=100)

    # NCC of both images sampled at the projections of the reference DEM cells
    with rasterio.open(ngi_block / "ngi" / "dem.tif") as src:
        z = src.read(1, masked=True).astype(float).filled(np.nan)
        rows, cols = np.mgrid[0:src.height, 0:src.width]
        xs, ys = rasterio.transform.xy(src.transform, rows.ravel(), cols.ravel())
    pts = np.column_stack([np.asarray(xs), np.asarray(ys), z.ravel()])
    pts = pts[np.isfinite(pts[:, 2])]
    for m in strip:
        values, inside = [], np.ones(len(pts), bool)
        for name in (m.left, m.right):
            cam = project.camera_of(name)
            col, row = world_to_pixel(pts, cam, project.image(name).eo)
            inside &= (col >= 0) & (col <= cam.width - 1) & (row >= 0) & (row <= cam.height - 1)
            values.append((project.image_path(name), col, row))
        g = [grey_at(p, c[inside], r[inside]) for p, c, r in values]
        ncc = np.corrcoef(g[0], g[1])[0, 1]
        print(f"{m.name}: {inside.sum()} cells, NCC {ncc:.3f}, overlap {m.overlap:.3f}, "
              f"B/H {m.b_h:.3f}")
        assert inside.sum() > 10000
        assert ncc >= 0.9

    info = registry.run("project_info", {"project": out["project"]})
    assert info["name"] == "ngi"
    assert len(info["images"]) == 4 and all(i["exists"] for i in info["images"])
    first = info["images"][0]
    assert first["kappa"] == pytest.approx(-179.087) and first["z"] == pytest.approx(5258.308)
    cam = info["cameras"]["Integraph DMC"]
    assert cam["focal_length_mm"] == 120.0 and cam["pixel_size_mm"][0] == pytest.approx(0.144)
    names = {(d["left"], d["right"]) for d in info["models"] if d["kind"] == "in-strip"}
    assert names == NGI_STRIP_MODELS
    assert {d["name"] for d in info["models"] if d["kind"] == "in-strip"} == {
        "0182_0184", "0251_0253"}
    assert {"b_h", "overlap_pct", "gsd_m", "height_above_ground_m", "base_m"} <= set(
        info["models"][0])
    assert info["validation"] == {"errors": [], "warnings": []}


def test_ngi_text_and_terrain_height(ngi_block: Path, tmp_path: Path) -> None:
    # the plain text list with the CRS as a parameter and a constant terrain height
    prj = (ngi_block / "io" / "ngi_xyz_opk.prj").read_text()
    out = create_ngi(ngi_block, tmp_path / "p", exterior=ngi_block / "ngi" / "camera_pos_ori.txt",
                     crs=prj, dem="", terrain_height=400)
    models = Project.load(out["project"]).models
    assert {(m.left, m.right) for m in models if m.kind == "in-strip"} == NGI_STRIP_MODELS


def test_project_create_errors_and_warnings(tmp_path: Path) -> None:
    images = tmp_path / "images"
    images.mkdir()
    (tmp_path / "cam.yaml").write_text(
        "c:\n  type: pinhole\n  im_size: [100, 80]\n  focal_len: 1.0\n  sensor_size: [1, 0.8]\n")
    (tmp_path / "ext.csv").write_text(
        "filename,x,y,z,omega,phi,kappa\na,0,0,1000,0,0,0\nb,400,0,1000,50,0,0\n")
    with pytest.raises(InputError) as info:
        registry.run("project_create", {
            "images": str(images), "exterior": str(tmp_path / "ext.csv"),
            "interior": str(tmp_path / "cam.yaml"), "crs": "EPSG:32633",
            "output": str(tmp_path / "p")})
    text = str(info.value)
    assert "'a': file" in text and "'b': file" in text and "omega" not in text
    assert not (tmp_path / "p").exists()

    for name in ("a", "b"):
        with rasterio.open(images / f"{name}.tif", "w", driver="GTiff", width=100, height=80,
                           count=1, dtype="uint8") as dst:
            dst.write(np.zeros((1, 80, 100), np.uint8))
    (tmp_path / "ext.csv").write_text(
        "filename,x,y,z,omega,phi,kappa\na,0,0,1000,0,0,0\nb,4000,0,1000,0,0,0\n")
    fb = Feedback()
    out = registry.run("project_create", {
        "images": str(images), "exterior": str(tmp_path / "ext.csv"),
        "interior": str(tmp_path / "cam.yaml"), "crs": "EPSG:32633",
        "output": str(tmp_path / "p")}, fb)
    assert out["models"] == []
    assert any("0 m" in w for w in out["warnings"])
    assert sum("no stereo partner" in w for w in out["warnings"]) == 2
    assert fb.warnings == out["warnings"]
    project = Project.load(out["project"])
    assert project.image("a").path == str((images / "a.tif").resolve())
    assert fiona.listlayers(str(project.edits_path)) == list(EDIT_LAYERS)


def test_project_create_from_opensfm(tmp_path: Path) -> None:
    import json

    from photodem.algorithms.geometry.orientation import ExteriorOrientation

    shots = {}
    for i in range(3):  # vertical images 60 m apart at 100 m: 40 % overlap, B/H 0.6
        rot, t = ExteriorOrientation.from_opk([60.0 * i, 0.0, 100.0], 0, 0, 0).to_opensfm()
        shots[f"IMG_{i}.JPG"] = {"rotation": rot.tolist(), "translation": t.tolist(),
                                 "camera": "cam"}
    rec = [{"cameras": {"cam": {"projection_type": "perspective", "width": 400, "height": 300,
                                "focal": 1.0, "k1": 0.0, "k2": 0.0}},
            "shots": shots,
            "reference_lla": {"latitude": 48.0, "longitude": 16.0, "altitude": 0.0}}]
    (tmp_path / "reconstruction.json").write_text(json.dumps(rec))
    with pytest.raises(InputError, match="IMG_0"):  # no image files: every one is reported
        registry.run("project_create", {
            "images": str(tmp_path), "exterior": str(tmp_path / "reconstruction.json"),
            "output": str(tmp_path / "p")})
    for i in range(3):
        with rasterio.open(tmp_path / f"IMG_{i}.JPG", "w", driver="GTiff", width=400,
                           height=300, count=1, dtype="uint8") as dst:
            dst.write(np.zeros((1, 300, 400), np.uint8))
    out = registry.run("project_create", {
        "images": str(tmp_path), "exterior": str(tmp_path / "reconstruction.json"),
        "terrain_height": "0", "output": str(tmp_path / "p")})
    project = Project.load(out["project"])
    assert project.crs == "EPSG:32633"
    assert [m.kind for m in project.models][:2] == ["in-strip", "in-strip"]
    assert project.models[0].b_h == pytest.approx(0.6, rel=1e-3)


def test_stereo_models_thresholds_and_manual_pairs(ngi_block: Path, tmp_path: Path) -> None:
    ngi = ngi_block
    out = tmp_path / "ngi"
    registry.run("project_create", {
        "images": str(ngi / "ngi"), "exterior": str(ngi / "io" / "ngi_xyz_opk.csv"),
        "interior": str(ngi / "io" / "ngi_int_param.yaml"), "angle_unit": "degrees",
        "dem": str(ngi / "ngi" / "dem.tif"), "output": str(out)})
    edits = (out / "edits.gpkg").read_bytes()
    only_strip = registry.run("stereo_models", {"project": str(out), "in_strip_only": True})
    assert [m["name"] for m in only_strip["models"]] == ["0182_0184", "0251_0253"]
    assert only_strip["unpaired"] == []
    # a B/H window that excludes the cross-strip pairs (B/H ≈ 0.86) but keeps in-strip (0.54)
    narrow = registry.run("stereo_models", {"project": str(out), "b_h_max": 0.7})
    assert {m["kind"] for m in narrow["models"]} == {"in-strip"}
    # nothing detected, one pair by hand (short labels accepted)
    manual = registry.run("stereo_models", {"project": str(out), "detect": False,
                                            "manual": "0184, 0251"})
    assert [(m["name"], m["kind"]) for m in manual["models"]] == [("0184_0251", "manual")]
    assert len(manual["unpaired"]) == 2
    info = registry.run("project_info", {"project": str(out)})
    assert [m["name"] for m in info["models"]] == ["0184_0251"]
    assert (out / "edits.gpkg").read_bytes() == edits  # the operator's edits are untouched
    with pytest.raises(InputError, match="two image names"):
        registry.run("stereo_models", {"project": str(out), "manual": "0182"})
    with pytest.raises(InputError, match="not in project"):
        registry.run("stereo_models", {"project": str(out), "manual": "0182,9999"})
    with pytest.raises(InputError, match="must be below"):
        registry.run("stereo_models", {"project": str(out), "b_h_min": 0.8, "b_h_max": 0.5})
