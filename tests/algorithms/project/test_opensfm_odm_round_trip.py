"""Round trips of the orientation importers against a synthetic truth: OpenSfM (topocentric),
an ODM project (UTM-with-offset reconstruction.json, reconstruction.topocentric.json,
coords.txt) and orthority's exterior GeoJSON / OPK CSV with its interior YAML, for nadir and
tilted (10–35°) frames; and the bug of issue 22 (ODM's grid-aligned reconstruction.json read as
topocentric, the block turned by the grid convergence)."""

from __future__ import annotations

import dataclasses
import json
import math
import shutil
from pathlib import Path

import numpy as np
import pyproj
import pytest

from photodem.algorithms.errors import InputError
from photodem.algorithms.geometry.orientation import (
    ExteriorOrientation,
    matrix_to_axis_angle,
    opensfm_to_patb,
    opk_to_matrix,
)
from photodem.algorithms.project.exporters import write_odm, write_opensfm, write_orthority
from photodem.algorithms.project.importers import (
    detect_exterior_format,
    import_project,
    read_opensfm,
)
from photodem.algorithms.project.importers_opensfm import (
    FRAME_ODM_UTM,
    FRAME_TOPOCENTRIC,
    OdmGeoref,
    eigen_angle_axis,
    enu_to_crs,
    enu_to_odm_utm,
    locate_opensfm,
    odm_affine,
    odm_utm_to_enu,
    parse_odm_coords,
)
from photodem.algorithms.project.model import Project

CM = 0.01
ARCSEC = math.radians(1.0 / 3600.0)


@pytest.fixture(scope="module")
def nadir(tiny_block: Path) -> Project:
    return Project.load(tiny_block)


def tilted_copy(project: Project, shift=(0.0, 0.0)) -> Project:
    """The project with every frame tilted 10–35° towards a varying azimuth (centres kept,
    shifted by ``shift``)."""
    images = []
    for i, rec in enumerate(project.images):
        tilt, azimuth = 10.0 + 25.0 * (i % 4) / 3.0, 67.0 * i
        turn = opk_to_matrix(0.0, 0.0, azimuth) @ opk_to_matrix(tilt, 0.0, 0.0) \
            @ opk_to_matrix(0.0, 0.0, -azimuth)
        eo = ExteriorOrientation(rec.eo.position + (*shift, 0.0), turn @ rec.eo.rotation)
        images.append(dataclasses.replace(rec, eo=eo))
    return dataclasses.replace(project, images=images)


@pytest.fixture(scope="module")
def tilted(nadir: Project) -> Project:
    return tilted_copy(nadir)


def far_east_copy(project: Project) -> Project:
    """The tilted block moved to easting 585 km, where the grid convergence of zone 32 is
    ≈ 0.9° as at the user's site."""
    mean_x = float(np.mean([rec.eo.position[0] for rec in project.images]))
    return tilted_copy(project, shift=(585000.0 - mean_x, 0.0))


def rotation_angle(a: np.ndarray, b: np.ndarray) -> float:
    """Angle (rad) of the rotation between two rotation matrices."""
    c = (np.trace(a.T @ b) - 1.0) / 2.0
    s = np.linalg.norm([(a.T @ b - b.T @ a)[i] for i in ((2, 1), (0, 2), (1, 0))]) / 2.0
    return math.atan2(s, c)


def worst(images, truth: Project):
    """Largest centre distance (m) and rotation difference (rad) of imported images."""
    by_name = {rec.name: rec.eo for rec in truth.images}
    assert sorted(by_name) == sorted(img.name for img in images)
    dist = max(float(np.linalg.norm(img.eo.position - by_name[img.name].position))
               for img in images)
    angle = max(rotation_angle(img.eo.rotation, by_name[img.name].rotation) for img in images)
    return dist, angle


def check_cameras(cameras, truth: Project) -> None:
    for name, cam in truth.cameras.items():
        got = cameras[name]
        assert got.focal_length_px == pytest.approx(cam.focal_length_px, rel=1e-12)
        for got_pp, pp, px in zip(got.principal_point, cam.principal_point, cam.pixel_size):
            assert got_pp / got.pixel_size[0] == pytest.approx(pp / px, abs=1e-9)
        assert (got.k1, got.k2, got.k3, got.p1, got.p2) == (cam.k1, cam.k2, cam.k3, cam.p1,
                                                            cam.p2)


@pytest.fixture(params=["nadir", "tilted"])
def truth(request, nadir: Project, tilted: Project) -> Project:
    return nadir if request.param == "nadir" else tilted


def test_opensfm_round_trip(truth: Project, tmp_path: Path) -> None:
    path = write_opensfm(truth, tmp_path / "osfm")
    block = read_opensfm(tmp_path / "osfm", crs=truth.crs)
    dist, angle = worst(block.images, truth)
    assert dist < 0.1 * CM and angle < 0.01 * ARCSEC  # measured: 0.12 mm (ETRS89 GRS80 vs WGS 84)
    assert block.checks["frame"] == FRAME_TOPOCENTRIC
    assert block.checks["gps_max_m"] < 1e-5 and abs(block.checks["gps_rotation_deg"]) < 1e-6
    check_cameras(block.cameras, truth)
    # the whole import, CRS defaulting to WGS 84 UTM 32N (numerically ETRS89's, see exporters)
    project, warnings = import_project(tmp_path / "p", truth.root / "images", path)
    assert project.crs == "EPSG:32632" and "OpenSfM frame: topocentric" in warnings[0]
    dist, angle = worst(project.images, truth)  # EPSG:32632 numbers = EPSG:25832 numbers
    assert dist < CM and angle < ARCSEC


@pytest.mark.parametrize("entry", ["root", "opensfm", "reconstruction.json",
                                   "reconstruction.topocentric.json"])
def test_odm_round_trip(truth: Project, tmp_path: Path, entry: str) -> None:
    root = write_odm(truth, tmp_path / "odm")
    georef = parse_odm_coords(root / "odm_georeferencing" / "coords.txt")
    assert georef.crs == "EPSG:32632"
    path = {"root": root, "opensfm": root / "opensfm"}.get(entry, root / "opensfm" / entry)
    block = read_opensfm(path, crs=truth.crs)
    expected = FRAME_TOPOCENTRIC if entry.endswith("topocentric.json") else FRAME_ODM_UTM
    assert block.checks["frame"] == expected
    dist, angle = worst(block.images, truth)
    assert dist < CM and angle < ARCSEC, (dist, math.degrees(angle) * 3600)
    assert block.checks["gps_max_m"] < 1e-3 and abs(block.checks["gps_rotation_deg"]) < 1e-5
    assert "CHECK THE FRAME" not in block.warnings[0]
    check_cameras(block.cameras, truth)


def test_odm_reconstruction_alone_is_recognised_by_its_gps(nadir: Project, tmp_path: Path
                                                          ) -> None:
    """A copied reconstruction.json (with reference_lla.json, no coords.txt, no topocentric
    file): ODM's whole-metre reference and the GPS positions decide the frame."""
    truth = far_east_copy(nadir)
    root = write_odm(truth, tmp_path / "odm")
    alone = tmp_path / "alone"
    alone.mkdir()
    for name in ("reconstruction.json", "reference_lla.json"):
        shutil.copy(root / "opensfm" / name, alone / name)
    assert locate_opensfm(alone / "reconstruction.json").frame is None
    block = read_opensfm(alone / "reconstruction.json", crs=truth.crs)
    assert block.checks["frame"] == FRAME_ODM_UTM and "closer to the GPS" in block.warnings[0]
    dist, angle = worst(block.images, truth)
    assert dist < CM and angle < ARCSEC


def test_issue22_odm_utm_file_is_not_turned_by_the_convergence(nadir: Project,
                                                               tmp_path: Path) -> None:
    """The user's bug: ODM's reconstruction.json is UTM minus the coords.txt offset, already
    grid-aligned. Read right, the centres equal the file's own GPS positions; read as
    topocentric (the old importer), they are turned by the grid convergence, and the check
    says so loudly."""
    truth = far_east_copy(nadir)
    root = write_odm(truth, tmp_path / "odm")
    block = read_opensfm(root)
    gamma = pyproj.Proj("EPSG:32632").get_factors(*_lon_lat(truth)).meridian_convergence
    assert abs(gamma) > 0.8  # the block lies where the user's did: ≈ 0.9°
    assert block.crs == "EPSG:32632" and block.checks["frame"] == FRAME_ODM_UTM
    assert block.checks["gps_max_m"] < CM
    assert abs(block.checks["gps_rotation_deg"]) < 1e-4
    assert "CHECK THE FRAME" not in block.warnings[0]
    dist, angle = worst(block.images, truth)
    assert dist < CM and angle < ARCSEC
    wrong = read_opensfm(root / "opensfm" / "reconstruction.json", frame="topocentric")
    assert abs(abs(wrong.checks["gps_rotation_deg"]) - abs(gamma)) < 0.01
    assert "CHECK THE FRAME" in wrong.warnings[0]
    assert wrong.checks["gps_max_m"] > 0.3  # 0.68 m at the edge of this small block


def _lon_lat(project: Project):
    c = np.mean([rec.eo.position for rec in project.images], axis=0)
    t = pyproj.Transformer.from_crs(project.crs, "EPSG:4326", always_xy=True)
    return t.transform(c[0], c[1])


@pytest.mark.parametrize("kind", ["geojson", "csv"])
def test_orthority_round_trip(truth: Project, tmp_path: Path, kind: str) -> None:
    files = write_orthority(truth, tmp_path / "oty")
    assert detect_exterior_format(files[kind]) == ("oty" if kind == "geojson" else "csv")
    project, _ = import_project(tmp_path / "p", truth.root / "images", files[kind],
                                files["yaml"], angle_unit="degrees")
    assert pyproj.CRS(project.crs) == pyproj.CRS(truth.crs)
    dist, angle = worst(project.images, truth)
    assert dist < 1e-6 and angle < 1e-3 * ARCSEC
    check_cameras(project.cameras, truth)
    assert [r.camera for r in project.images] == [r.camera for r in truth.images]


def test_odm_errors(tmp_path: Path) -> None:
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputError, match="neither an ODM project"):
        read_opensfm(tmp_path / "empty")
    coords = tmp_path / "coords.txt"
    coords.write_text("WGS84 UTM 99X\n1 2\n")
    with pytest.raises(InputError, match="WGS84 UTM"):
        parse_odm_coords(coords)
    coords.write_text("'+proj=utm +zone=33 +datum=WGS84 +units=m +no_defs'\n440143 4588391\n")
    georef = parse_odm_coords(coords)
    assert georef.offset == (440143.0, 4588391.0)
    assert pyproj.CRS(georef.crs).to_epsg(min_confidence=70) == 32633
    rec = tmp_path / "osfm" / "reconstruction.json"
    rec.parent.mkdir()
    rec.write_text(json.dumps([{"cameras": {}, "shots": {}}]))
    with pytest.raises(InputError, match="reference_lla"):
        read_opensfm(rec)


def test_older_odm_model_geo_file_without_topocentric_file(tilted: Project, tmp_path: Path
                                                           ) -> None:
    """Older ODM: the CRS and offset in odm_georeferencing_model_geo.txt; an archive without
    reconstruction.topocentric.json: the GPS positions decide, the offset comes from the file."""
    root = write_odm(tilted, tmp_path / "odm")
    geo = root / "odm_georeferencing"
    (geo / "coords.txt").rename(geo / "odm_georeferencing_model_geo.txt")
    (root / "opensfm" / "reconstruction.topocentric.json").unlink()
    block = read_opensfm(root, crs=tilted.crs)
    assert block.checks["frame"] == FRAME_ODM_UTM
    assert "odm_georeferencing_model_geo.txt" in block.warnings[0]
    dist, angle = worst(block.images, tilted)
    assert dist < CM and angle < ARCSEC


ANGLES = [(0.0, 0.0, 0.0), (180.0, 0.0, 0.0), (30.0, 5.0, 70.0), (-20.0, 25.0, -150.0),
          (10.0, -35.0, 120.0), (179.0, 1.0, 3.0), (0.0, 0.0, 180.0), (90.0, 0.0, 0.0)]


def test_eigen_angle_axis_of_rotations_is_the_axis_angle() -> None:
    for angles in ANGLES:  # both of Eigen's branches: trace > 0 and the largest diagonal
        R = opk_to_matrix(*angles)
        got, want = eigen_angle_axis(R), matrix_to_axis_angle(R)
        assert rotation_angle(opk_to_matrix(0, 0, 0), R) == pytest.approx(np.linalg.norm(got))
        if np.linalg.norm(want) < math.pi - 1e-6:  # at 180° ±axis are the same rotation
            np.testing.assert_allclose(got, want, atol=1e-12)


@pytest.mark.parametrize("easting", [500000.0, 585000.0])
def test_odm_pose_model_inverts_exactly_far_from_the_reference(easting: float) -> None:
    """ODM's pose of a camera 1 km from the reference is inverted to 1e-6 m and 1e-6″; as ODM's
    own tools read it (no scale factor), it lies 0.35–0.44 m off on and near the central
    meridian."""
    crs = "EPSG:32632"
    lon, lat = pyproj.Transformer.from_crs(crs, "EPSG:4326", always_xy=True).transform(
        easting, 5674700.0)
    ref = (lat, lon, 0.0)
    georef = OdmGeoref(crs, (easting, 5674700.0), "test")
    A, b = odm_affine(ref, georef)
    for i, angles in enumerate(ANGLES):
        eo = ExteriorOrientation.from_opk([700.0 - 300 * i, 700.0, 120.0], *angles)
        rotation, translation = enu_to_odm_utm(eo, A, b)
        back = odm_utm_to_enu(rotation, translation, A, b)
        assert np.abs(back.position - eo.position).max() < 1e-6
        assert rotation_angle(back.rotation, eo.rotation) < 1e-6 * ARCSEC
    eo = ExteriorOrientation.from_opk([707.0, 707.0, 120.0], 5.0, -3.0, 40.0)
    as_odm = opensfm_to_patb(*enu_to_odm_utm(eo, A, b)).position + (*georef.offset, 0.0)
    gap = np.linalg.norm((enu_to_crs(eo.position, ref, crs) - as_odm)[:2])
    assert 0.3 < gap < 0.5


def test_bad_shot_is_an_input_error(tmp_path: Path) -> None:
    lla = {"latitude": 51.0, "longitude": 9.0, "altitude": 100.0}
    rec = tmp_path / "reconstruction.json"
    rec.write_text(json.dumps([{"cameras": {}, "reference_lla": lla,
                                "shots": {"a.jpg": {"rotation": [0, 0], "camera": "c"}}}]))
    with pytest.raises(InputError, match=r"shot 'a\.jpg' needs rotation"):
        read_opensfm(rec)


def _orthority_param_io():
    return pytest.importorskip("orthority.param_io",
                               reason="orthority is not installed (make .venv-bench)")


def _max_differences(ext: dict, truth: Project):
    """Largest centre distance (m) and ω/φ/κ difference (rad, wrapped) of orthority's
    exterior parameters against the truth."""
    by_name = {rec.name: rec.eo for rec in truth.images}
    dist = max(float(np.linalg.norm(np.subtract(e["xyz"], by_name[Path(k).stem].position)))
               for k, e in ext.items())
    angle = max(float(np.abs((np.subtract(e["opk"], by_name[Path(k).stem].opk("radians"))
                              + math.pi) % (2 * math.pi) - math.pi).max()) for k, e in ext.items())
    return dist, angle


def test_orthority_reads_our_orthority_files_as_we_do(tilted: Project, tmp_path: Path) -> None:
    param_io = _orthority_param_io()
    files = write_orthority(tilted, tmp_path / "oty")
    for ext in (param_io.OtyReader(files["geojson"]).read_ext_param(),
                param_io.CsvReader(files["csv"], crs=tilted.crs).read_ext_param()):
        dist, angle = _max_differences(ext, tilted)
        assert dist < 1e-9 and angle < 1e-12
    cams = param_io.read_oty_int_param(files["yaml"])
    for name, cam in tilted.cameras.items():
        assert cams[name]["focal_len"] == cam.focal_length
        assert tuple(cams[name]["im_size"]) == (cam.width, cam.height)


def test_orthority_reads_our_odm_file_as_odm_does(tilted: Project, tmp_path: Path) -> None:
    """orthority adds reconstruction.json's coordinates to reference_lla's UTM position: right
    for ODM's grid-aligned file (as ODM's own tools read it), not for a topocentric one."""
    param_io = _orthority_param_io()
    root = write_odm(tilted, tmp_path / "odm")
    reader = param_io.OsfmReader(root / "opensfm" / "reconstruction.json", crs="EPSG:32632")
    dist, angle = _max_differences(reader.read_ext_param(), tilted)
    block = read_opensfm(root)
    assert dist < block.checks["odm_linear_gap_m"] + 1e-3 and angle < 2 * ARCSEC
