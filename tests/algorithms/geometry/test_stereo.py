"""Stereo-model geometry and detection against closed forms on a synthetic block."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from affine import Affine

from photodem.algorithms.errors import GeometryError
from photodem.algorithms.geometry.camera import Camera
from photodem.algorithms.geometry.orientation import ExteriorOrientation
from photodem.algorithms.geometry.projection import world_to_pixel
from photodem.algorithms.geometry.stereo import (
    dominant_direction,
    footprint_and_height,
    image_footprint,
)
from photodem.algorithms.project.model import ImageRecord, Project
from photodem.algorithms.project.stereo_models import (
    block_footprints,
    detect_stereo_models,
    manual_model,
    model_geometry,
    overlap_polygon,
)
from photodem.algorithms.raster.io import write_raster

# f = 10 mm, 1000 × 800 px of 0.01 mm: at H = 1000 m the footprint is 1000 m × 800 m, GSD 1 m
CAM = Camera("c", 1000, 800, 10.0, (0.01, 0.01))
H = 1000.0


def block(base: float = 400.0, spacing: float = 560.0, n: int = 4, strips: int = 2,
          terrain: float = 0.0) -> Project:
    images = []
    for s in range(strips):
        for i in range(n):
            name = f"s{s}_{i:02d}"
            eo = ExteriorOrientation.from_opk([i * base, -s * spacing, terrain + H], 0, 0, 0)
            images.append(ImageRecord(name, f"{name}.tif", "c", eo))
    # deliberately shuffled: detection must not depend on the input order
    images = [images[k] for k in np.random.default_rng(1).permutation(len(images))]
    return Project(root=Path("/nonexistent"), name="t", crs="EPSG:32633", cameras={"c": CAM},
                   images=images, terrain_height=terrain)


def test_footprint_vertical_closed_form() -> None:
    eo = ExteriorOrientation.from_opk([100.0, 200.0, 1100.0], 0, 0, 0)
    fp = image_footprint(CAM, eo, height=100.0)
    assert fp.area == pytest.approx(1000.0 * 800.0, rel=1e-12)
    minx, miny, maxx, maxy = fp.bounds
    assert (minx, miny, maxx, maxy) == pytest.approx((-400.0, -200.0, 600.0, 600.0), abs=1e-9)


def test_footprint_tilted_projects_back_to_outline() -> None:
    cam = Camera("d", 600, 400, 12.0, (0.02, 0.02), k1=-0.05, p1=0.001)
    eo = ExteriorOrientation.from_opk([0.0, 0.0, 800.0], 5.0, -7.0, 30.0)
    fp = image_footprint(cam, eo, height=50.0)
    xy = np.asarray(fp.exterior.coords)[:-1]
    pts = np.column_stack([xy, np.full(len(xy), 50.0)])
    col, row = world_to_pixel(pts, cam, eo)
    # every outline point lies on the image border (distortion included)
    on_border = np.minimum.reduce([np.abs(col + 0.5), np.abs(col - 599.5),
                                   np.abs(row + 0.5), np.abs(row - 399.5)])
    assert on_border.max() < 1e-6


def test_footprint_on_dem_iterates_to_mean_height(tmp_path: Path) -> None:
    # a plane sloping in x: z = 200 + 0.05 x on a 10 m grid around the footprint
    x = np.arange(-1000.0, 1000.0, 10.0) + 5.0
    y = np.arange(1000.0, -1000.0, -10.0) - 5.0
    X, _ = np.meshgrid(x, y)
    dem = (200.0 + 0.05 * X).astype(np.float32)
    path = write_raster(tmp_path / "dem.tif", dem, Affine(10, 0, -1000, 0, -10, 1000),
                        crs="EPSG:32633")
    eo = ExteriorOrientation.from_opk([0.0, 0.0, 1200.0], 0, 0, 0)
    fp, h = footprint_and_height(CAM, eo, dem=path)
    # symmetric footprint around x = 0 on a plane: mean height = 200 m
    assert h == pytest.approx(200.0, abs=0.02)
    assert fp.area == pytest.approx(1000.0 * 800.0, rel=1e-4)
    with pytest.raises(GeometryError):
        footprint_and_height(CAM, ExteriorOrientation.from_opk([1e5, 0, 1200], 0, 0, 0),
                             dem=path)


def test_model_geometry_closed_form() -> None:
    p = block(terrain=150.0)
    m = model_geometry(p, "s0_01", "s0_00")  # given in the wrong order
    assert (m.left, m.right) == ("s0_00", "s0_01")
    assert m.name == "s0_00_s0_01"
    assert m.base == pytest.approx(400.0)
    assert m.height_above_ground == pytest.approx(H)
    assert m.b_h == pytest.approx(0.4)
    assert m.overlap == pytest.approx(0.6, abs=1e-9)
    assert m.gsd == pytest.approx(1.0)
    ov = overlap_polygon(p, "s0_00", "s0_01")
    assert ov.area == pytest.approx(600.0 * 800.0, rel=1e-9)


def test_left_right_follows_image_x_axis() -> None:
    p = block()
    for rec in p.images:  # fly west with kappa = 180°: image x points west
        rec.eo = ExteriorOrientation.from_opk(rec.eo.position, 0, 0, 180)
    m = model_geometry(p, "s0_00", "s0_01")
    assert (m.left, m.right) == ("s0_01", "s0_00")


def test_detect_block() -> None:
    p = block()
    models = detect_stereo_models(p)
    kinds = [m.kind for m in models]
    assert kinds == ["in-strip"] * 6 + ["cross-strip"] * 4
    # strips north to south, west to east
    assert [m.name for m in models[:3]] == ["s0_00_s0_01", "s0_01_s0_02", "s0_02_s0_03"]
    assert all(m.overlap == pytest.approx(0.6) for m in models[:6])
    cross = models[6:]
    assert all(m.overlap == pytest.approx(0.3) and m.b_h == pytest.approx(0.56) for m in cross)
    assert len(detect_stereo_models(p, in_strip_only=True)) == 6
    assert detect_stereo_models(p, min_overlap=0.7) == []
    assert len(detect_stereo_models(p, b_h_range=(0.5, 1.0))) == 4


def test_detect_neighbours_first_with_high_overlap() -> None:
    p = block(base=200.0, n=5, strips=1)  # 80 % forward overlap
    models = detect_stereo_models(p)
    assert [m.kind for m in models] == ["in-strip"] * 9
    # 4 neighbours (80 %), then the pairs two (60 %) and three apart (40 %)
    assert [round(m.overlap, 6) for m in models[:4]] == [0.8] * 4
    assert sorted(round(m.overlap, 6) for m in models[4:]) == [0.4, 0.4, 0.6, 0.6, 0.6]


def test_dominant_direction_is_axial_and_robust() -> None:
    a = np.radians([0.5, 179.0, -1.0, 1.5, 90.0])
    d = np.degrees(dominant_direction(a, np.radians(20)))
    assert min(d, 180 - d) < 1.0


def test_manual_model_and_no_overlap() -> None:
    p = block()
    m = manual_model(p, "s0_00", "s1_00")
    assert m.kind == "manual" and m.overlap == pytest.approx(0.3)
    with pytest.raises(GeometryError):
        manual_model(p, "s0_00", "s0_03")


def test_block_footprints_uses_project_terrain() -> None:
    p = block(terrain=300.0)
    fps = block_footprints(p)
    assert all(h == 300.0 and f.area == pytest.approx(8e5) for f, h in fps.values())


def test_image_labels_drop_shared_parts() -> None:
    from photodem.algorithms.project.stereo_models import image_labels

    ngi = ["3324c_2015_1004_05_0182_RGB", "3324c_2015_1004_05_0184_RGB",
           "3324c_2015_1004_06_0251_RGB", "3324c_2015_1004_06_0253_RGB"]
    assert list(image_labels(ngi).values()) == ["0182", "0184", "0251", "0253"]
    assert image_labels(["s0_00", "s0_01", "s1_00"]) == {
        "s0_00": "s0_00", "s0_01": "s0_01", "s1_00": "s1_00"}
    assert image_labels(["IMG_1.tif", "IMG_2.tif"]) == {"IMG_1.tif": "1", "IMG_2.tif": "2"}
    assert image_labels(["a", "a_b"]) == {"a": "a", "a_b": "b"}
