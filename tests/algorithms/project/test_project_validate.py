"""Validation: one operator-readable message per error case; edits.gpkg."""

from __future__ import annotations

from pathlib import Path

import fiona
import numpy as np
import pytest
from shapely.geometry import LineString, Point, Polygon

from photodem.algorithms.errors import InputError
from photodem.algorithms.geometry.camera import Camera
from photodem.algorithms.geometry.orientation import ExteriorOrientation
from photodem.algorithms.project.edits import EDIT_LAYERS, add_features, create_edits, read_layer
from photodem.algorithms.project.model import ImageRecord, Project
from photodem.algorithms.project.validate import validate_project
from photodem.algorithms.raster.io import write_raster

pytestmark = pytest.mark.filterwarnings("ignore::rasterio.errors.NotGeoreferencedWarning")
CAM = Camera("c", 100, 80, 1.0, (0.01, 0.01))  # footprint 1000 m × 800 m at H = 1000 m


def make_project(tmp_path: Path, n: int = 3) -> Project:
    p = Project(root=tmp_path, name="v", crs="EPSG:32633", cameras={"c": CAM},
                terrain_height=100.0)
    for i in range(n):
        name = f"im{i}"
        write_raster(tmp_path / f"{name}.tif", np.zeros((80, 100), np.uint8))
        eo = ExteriorOrientation.from_opk([400.0 * i, 0.0, 1100.0], 0.5, -0.5, 0.0)
        p.images.append(ImageRecord(name, f"{name}.tif", "c", eo))
    return p


def only_error(rep, *words: str) -> str:
    assert len(rep.errors) == 1, rep.errors
    for w in words:
        assert w in rep.errors[0], rep.errors[0]
    return rep.errors[0]


def test_valid_project(tmp_path: Path) -> None:
    rep = validate_project(make_project(tmp_path))
    assert rep.ok and rep.warnings == []
    rep.raise_if_errors()


def test_missing_image(tmp_path: Path) -> None:
    p = make_project(tmp_path)
    (tmp_path / "im1.tif").unlink()
    only_error(validate_project(p), "im1", "not found")
    assert validate_project(p, check_files=False).ok


def test_image_size_differs(tmp_path: Path) -> None:
    p = make_project(tmp_path)
    write_raster(tmp_path / "im2.tif", np.zeros((100, 80), np.uint8))
    only_error(validate_project(p), "im2", "80 × 100 px", "100 × 80 px", "swapped")


def test_tilt_above_max_tilt_is_a_warning(tmp_path: Path) -> None:
    p = make_project(tmp_path)
    p.images[0].eo = ExteriorOrientation.from_opk(p.images[0].eo.position, 45.0, 0.0, 0.0)
    rep = validate_project(p, stereo_partners=False)
    assert rep.ok
    assert len(rep.warnings) == 1
    assert all(w in rep.warnings[0] for w in ("im0", "omega = 45.000°", "max_tilt", "angle unit"))
    assert validate_project(p, max_tilt=50.0, stereo_partners=False).warnings == []


@pytest.mark.parametrize("omega, phi", [(120.0, 0.0), (0.0, -95.0), (180.0, 0.0), (91.0, 10.0)])
def test_camera_looking_up_is_refused(tmp_path: Path, omega: float, phi: float) -> None:
    p = make_project(tmp_path)
    p.images[0].eo = ExteriorOrientation.from_opk(p.images[0].eo.position, omega, phi, 0.0)
    only_error(validate_project(p, max_tilt=90.0), "im0", "horizon", "angle unit")


def test_camera_below_terrain_and_absurd_height(tmp_path: Path) -> None:
    p = make_project(tmp_path)
    p.images[1].eo = ExteriorOrientation(np.array([400.0, 0.0, 50.0]), np.eye(3))
    only_error(validate_project(p), "im1", "not above the terrain height")
    p.images[1].eo = ExteriorOrientation(np.array([400.0, 0.0, 5.0e6]), np.eye(3))
    only_error(validate_project(p), "im1", "km above")


def test_camera_below_dem(tmp_path: Path) -> None:
    from affine import Affine

    p = make_project(tmp_path)
    dem = np.full((300, 300), 200.0, np.float32)
    dem[:, 170:] = 1500.0  # a plateau under im2 (x ≥ 700 m), above the camera
    path = write_raster(tmp_path / "dem.tif", dem, Affine(10, 0, -1000, 0, -10, 1500),
                        crs="EPSG:32633")
    rep = validate_project(p, dem=path)
    only_error(rep, "im2", "not above the DEM")


def test_crs_errors(tmp_path: Path) -> None:
    p = make_project(tmp_path)
    p.crs = ""
    only_error(validate_project(p), "no CRS")
    p.crs = "EPSG:999999"
    only_error(validate_project(p), "not understood")
    p.crs = "EPSG:4326"
    only_error(validate_project(p), "geographic")


def test_duplicate_names_and_unknown_camera(tmp_path: Path) -> None:
    p = make_project(tmp_path)
    p.images[2].name = "im0"
    only_error(validate_project(p), "'im0' occurs 2 times")
    p = make_project(tmp_path)
    p.images[2].camera = "other"
    only_error(validate_project(p), "im2", "camera 'other'")


def test_all_errors_are_listed(tmp_path: Path) -> None:
    p = make_project(tmp_path)
    p.crs = ""
    p.images[2].camera = "other"
    rep = validate_project(p)
    assert len(rep.errors) == 2
    with pytest.raises(InputError) as info:
        rep.raise_if_errors()
    assert "2 errors" in str(info.value) and "other" in str(info.value)


def test_image_without_stereo_partner(tmp_path: Path) -> None:
    p = make_project(tmp_path)
    p.images[2].eo = ExteriorOrientation.from_opk([5000.0, 0.0, 1100.0], 0, 0, 0)
    rep = validate_project(p)
    assert rep.ok
    assert len(rep.warnings) == 1 and "'im2' has no stereo partner" in rep.warnings[0]


def test_edits_gpkg(tmp_path: Path) -> None:
    path = create_edits(tmp_path / "edits.gpkg", "EPSG:32633")
    assert fiona.listlayers(str(path)) == list(EDIT_LAYERS)
    with fiona.open(str(path), layer="breaklines") as src:
        assert src.schema["geometry"] == "3D LineString"
        assert "32633" in str(src.crs) or "UTM zone 33N" in src.crs_wkt
    with pytest.raises(InputError, match="exists"):
        create_edits(path, "EPSG:32633")
    add_features(path, "breaklines", [(LineString([(0, 0, 1), (5, 5, 2)]), {"kind": "edge"})])
    add_features(path, "exclusion_areas",
                 [(Polygon([(0, 0), (1, 0), (1, 1)]), {"action": "remove", "note": "lake"})])
    add_features(path, "check_points", [(Point(1, 2, 3), {"id": "CP1"})])
    (line, props), = read_layer(path, "breaklines")
    assert line.has_z and props == {"kind": "edge", "note": None}
    assert read_layer(path, "exclusion_areas")[0][1]["action"] == "remove"
    assert read_layer(path, "check_points")[0][0].z == 3
    assert read_layer(path, "seamlines") == []
    with pytest.raises(InputError):
        add_features(path, "exclusion_areas", [(Polygon([(0, 0), (1, 0), (1, 1)]),
                                                {"action": "delete"})])
    with pytest.raises(InputError):
        read_layer(path, "nope")
