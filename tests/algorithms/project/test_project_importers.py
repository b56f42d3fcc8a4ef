"""Importers: OPK CSV/text with camera YAML, OpenSfM reconstruction.json."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pyproj
import pytest

from photodem.algorithms.errors import InputError
from photodem.algorithms.geometry.orientation import ExteriorOrientation
from photodem.algorithms.project.importers import (
    crs_to_enu,
    detect_exterior_format,
    enu_to_crs,
    find_image_file,
    import_project,
    read_interior_yaml,
    read_opensfm,
    read_opk_csv,
    read_opk_text,
    transform_pose,
)

YAML = """\
Cam A:
    type: pinhole
    im_size: [640, 1152]
    focal_len: 120.0
    sensor_size: [92.16, 165.888]
    cx: 0.0
    cy: 0.0
cam_b:
    type: brown
    im_size: [400, 300]
    focal_len: 0.5
    cx: 0.01
    cy: 0.02
    k1: -0.1
    p2: 0.001
"""
PROJ = "+proj=utm +zone=33 +datum=WGS84 +units=m +no_defs"


def write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


def test_interior_yaml(tmp_path: Path) -> None:
    cams = read_interior_yaml(write(tmp_path / "int.yaml", YAML))
    a, b = cams["Cam A"], cams["cam_b"]
    assert a.focal_length == 120.0 and a.pixel_size == pytest.approx((0.144, 0.144))
    # normalised focal length: f_px = focal_len · max(w, h)
    assert b.focal_length_px == pytest.approx(0.5 * 400)
    assert b.k1 == -0.1 and b.p2 == 0.001
    # principal point: normalised offsets (y down) from the centre, × max(w, h) in pixels
    col, row = b.camera_to_pixel(np.array([0.0, 0.0, -1.0]))
    assert float(col) == pytest.approx(199.5 + 0.01 * 400)
    assert float(row) == pytest.approx(149.5 + 0.02 * 400)


def test_opk_csv_header_extra_columns_prj(tmp_path: Path) -> None:
    csv = write(tmp_path / "ext.csv",
                "filename,quality,x,y,z,omega,phi,kappa\n"
                "img1.tif,good,500000.0,5400000.0,1500.0,1.0,-2.0,90.0\n"
                "img2,ok,500400.0,5400000.0,1510.0,0.5,0.5,-179.0\n")
    write(tmp_path / "ext.prj", PROJ)
    block = read_opk_csv(csv, angle_unit="degrees")
    assert pyproj.CRS(block.crs).to_epsg(min_confidence=70) == 32633
    assert [i.name for i in block.images] == ["img1", "img2"]
    assert block.images[0].eo.position == pytest.approx([500000.0, 5400000.0, 1500.0])
    assert block.images[0].eo.opk() == pytest.approx((1.0, -2.0, 90.0))
    # an explicit CRS wins over the .prj, with a warning
    block = read_opk_csv(csv, angle_unit="degrees", crs="EPSG:32634")
    assert block.crs == "EPSG:32634" and block.warnings


def test_opk_csv_without_header_in_gon(tmp_path: Path) -> None:
    csv = write(tmp_path / "ext.csv", "a;1;2;1000;100;-50;200\nb;3;4;1000;0;0;0\n")
    block = read_opk_csv(csv, angle_unit="gon", crs="EPSG:32633")
    assert block.images[0].eo.opk("degrees") == pytest.approx((90.0, -45.0, 180.0))
    assert block.images[0].eo.opk("gon") == pytest.approx((100.0, -50.0, 200.0))


def test_opk_text_radians_with_comments(tmp_path: Path) -> None:
    txt = write(tmp_path / "pos.txt",
                "# name x y z omega phi kappa\n"
                "im_1  10.0 20.0 900.0  0.01 -0.02 3.0  # first\n\n"
                "im_2\t30.0 20.0 900.0 0.0 0.0 -1.5\n")
    block = read_opk_text(txt, angle_unit="radians", crs="EPSG:32633")
    assert [i.name for i in block.images] == ["im_1", "im_2"]
    assert block.images[0].eo.opk("radians") == pytest.approx((0.01, -0.02, 3.0))
    assert detect_exterior_format(txt) == "text"


def test_angle_unit_is_required_and_checked(tmp_path: Path) -> None:
    csv = write(tmp_path / "e.csv", "a,1,2,3,0,0,0\n")
    with pytest.raises(InputError, match="angle unit"):
        read_opk_csv(csv, angle_unit="grad")


def test_import_project_matches_files_and_cameras(tmp_path: Path) -> None:
    images = tmp_path / "images"
    images.mkdir()
    (images / "img1.tif").write_bytes(b"")
    (images / "IMG2.TIF").write_bytes(b"")
    write(tmp_path / "int.yaml", YAML)
    csv = write(tmp_path / "ext.csv",
                "filename,x,y,z,omega,phi,kappa,camera\n"
                "img1,0,0,1000,0,0,0,Cam A\n"
                "img2.tif,400,0,1000,0,0,0,cam_b\n"
                "img3,800,0,1000,0,0,0,cam_b\n")
    p, _ = import_project(tmp_path / "proj", images, csv, tmp_path / "int.yaml",
                          crs="EPSG:32633", angle_unit="degrees")
    assert [(r.name, r.camera) for r in p.images] == [
        ("img1", "Cam A"), ("img2", "cam_b"), ("img3", "cam_b")]
    assert p.image_path("img1") == (images / "img1.tif").resolve()
    assert p.image_path("img2") == (images / "IMG2.TIF").resolve()
    assert not p.image_path("img3").exists()  # reported later by validation
    assert find_image_file(images, "img1.tif") == images / "img1.tif"


def test_import_errors(tmp_path: Path) -> None:
    write(tmp_path / "int.yaml", YAML)
    csv = write(tmp_path / "ext.csv", "a,0,0,1000,0,0,0\n")
    with pytest.raises(InputError, match="No CRS"):
        import_project(tmp_path / "p", tmp_path, csv, tmp_path / "int.yaml",
                       angle_unit="degrees")
    with pytest.raises(InputError, match="camera"):  # two cameras, no camera column
        import_project(tmp_path / "p", tmp_path, csv, tmp_path / "int.yaml",
                       crs="EPSG:32633", angle_unit="degrees")
    with pytest.raises(InputError, match="interior"):
        import_project(tmp_path / "p", tmp_path, csv, None, crs="EPSG:32633",
                       angle_unit="degrees")


REF = (48.2, 16.3, 180.0)  # UTM zone 33 N


def reconstruction(poses: dict, crs: str) -> list:
    """An OpenSfM reconstruction built from PATB poses in ``crs``."""
    shots = {}
    for name, eo in poses.items():
        enu = transform_pose(eo, lambda p: crs_to_enu(p, REF, crs))
        rot, t = enu.to_opensfm()
        shots[name] = {"rotation": rot.tolist(), "translation": t.tolist(), "camera": "v2 cam"}
    cams = {"v2 cam": {"projection_type": "brown", "width": 4000, "height": 3000,
                       "focal_x": 0.8, "focal_y": 0.8, "c_x": 0.002, "c_y": -0.001,
                       "k1": -0.01, "k2": 0.002, "p1": 0.0001, "p2": -0.0002, "k3": 0.0}}
    lla = {"latitude": REF[0], "longitude": REF[1], "altitude": REF[2]}
    return [{"cameras": cams, "shots": shots, "reference_lla": lla}]


def test_enu_round_trip() -> None:
    pts = np.array([[0.0, 0.0, 0.0], [1500.0, -2500.0, 400.0]])
    utm = enu_to_crs(pts, REF, "EPSG:32633")
    assert np.abs(crs_to_enu(utm, REF, "EPSG:32633") - pts).max() < 1e-6


def test_opensfm_against_known_patb_pose(tmp_path: Path) -> None:
    crs = "EPSG:32633"
    centre = enu_to_crs(np.zeros(3), REF, crs)
    poses = {
        "DJI_0001.JPG": ExteriorOrientation.from_opk(centre + [1200.0, -3000.0, 800.0],
                                                     2.0, -3.0, 37.0),
        "DJI_0002.JPG": ExteriorOrientation.from_opk(centre + [-2500.0, 400.0, 650.0],
                                                     -1.0, 0.5, -150.0),
    }
    path = tmp_path / "reconstruction.json"
    path.write_text(json.dumps(reconstruction(poses, crs)))
    assert detect_exterior_format(path) == "opensfm"
    block = read_opensfm(path)
    assert block.crs == crs  # default: UTM zone of reference_lla
    cam = block.cameras["v2 cam"]
    assert cam.focal_length_px == pytest.approx(0.8 * 4000)
    assert (cam.k1, cam.p2) == (-0.01, -0.0002)
    for img in block.images:
        truth = poses[img.name + ".JPG"]
        assert np.abs(img.eo.position - truth.position).max() < 1e-3
        assert np.abs(np.subtract(img.eo.opk(), truth.opk())).max() < 1e-6


def test_opensfm_rotation_carries_grid_convergence(tmp_path: Path) -> None:
    crs = "EPSG:32633"
    centre = enu_to_crs(np.array([0.0, 0.0, 1000.0]), REF, crs)
    # a vertical camera with kappa = 0 in the topocentric frame at the reference point
    rot, t = ExteriorOrientation.from_opk([0.0, 0.0, 1000.0], 0, 0, 0).to_opensfm()
    rec = reconstruction({}, crs)
    rec[0]["shots"]["a.jpg"] = {"rotation": rot.tolist(), "translation": t.tolist(),
                                "camera": "v2 cam"}
    path = tmp_path / "reconstruction.json"
    path.write_text(json.dumps(rec))
    eo = read_opensfm(path).images[0].eo
    assert eo.position == pytest.approx(centre, abs=1e-6)
    gamma = pyproj.Proj(crs).get_factors(REF[1], REF[0]).meridian_convergence
    # grid north is rotated by the convergence against true north: kappa takes it up
    _, _, kappa = eo.opk()
    assert abs(abs(kappa) - abs(gamma)) < 1e-6
    assert abs(gamma) > 0.5  # 16.3° E in zone 33 (15° E) at 48° N: γ ≈ 0.97°
