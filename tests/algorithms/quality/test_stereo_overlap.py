"""The frames' overlap on a surface: a roof near the overlap's edge leaves one frame."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from affine import Affine
from shapely.geometry import Point, box

from photodem.algorithms.geometry.camera import Camera
from photodem.algorithms.geometry.orientation import ExteriorOrientation
from photodem.algorithms.quality.stereo_overlap import inside_frames, stereo_overlap
from photodem.algorithms.raster.io import write_raster

X0, Y0, ZT, CELL = 500000.0, 5500000.0, 100.0, 0.1
NPX = 200  # principal distance 200 px, flying 20 m above ZT: 0.1 m pixels on the ground
CAM = Camera("cam", NPX, NPX, focal_length=NPX * 0.01, pixel_size=(0.01, 0.01))
FRAMES = [(CAM, ExteriorOrientation.from_opk([X0 + dx, Y0, ZT + 20.0], 0.0, 0.0, 0.0))
          for dx in (-5.0, 5.0)]


def _half_width(z: float) -> float:
    """Half the side of a frame's footprint at height ``z`` (pixel centres 0 … NPX − 1)."""
    return 0.5 * (NPX - 1) * (ZT + 20.0 - z) / NPX


def _surface(tmp_path: Path, roof: float) -> Path:
    """Flat ground at ZT, and for X > X0 + 1 m a roof ``roof`` m higher."""
    n = int(20.0 / CELL)
    xs = X0 - 10.0 + CELL * (np.arange(n) + 0.5)
    z = np.full((n, n), ZT, np.float32)
    z[:, xs > X0 + 1.0] += roof
    z[:5, :5] = np.nan  # nodata is in no frame
    path = tmp_path / f"dsm_{roof:g}.tif"
    write_raster(path, z[None], transform=Affine(CELL, 0, X0 - 10.0, 0, -CELL, Y0 + 10.0),
                 crs="EPSG:25832", nodata=np.nan)
    return path


def test_inside_frames_at_the_points_own_height() -> None:
    hw_ground, hw_roof = _half_width(ZT), _half_width(ZT + 4.0)
    pts = np.array([[X0 + 5 - hw_ground + 0.05, Y0, ZT],   # ground just inside both
                    [X0 + 5 - hw_ground - 0.05, Y0, ZT],   # ground just outside the right
                    [X0 - 5 + hw_roof - 0.05, Y0, ZT + 4],  # roof just inside the left
                    [X0 - 5 + hw_roof + 0.05, Y0, ZT + 4],  # roof just outside it
                    [X0, Y0, ZT + 30.0],                    # above the cameras
                    [X0, Y0, np.nan]])
    assert inside_frames(FRAMES, pts).tolist() == [True, False, True, False, False, False]


def test_stereo_overlap_shrinks_where_the_surface_stands_higher(tmp_path: Path) -> None:
    hw_ground, hw_roof = _half_width(ZT), _half_width(ZT + 4.0)
    flat = stereo_overlap(FRAMES, _surface(tmp_path, 0.0))
    roofed = stereo_overlap(FRAMES, _surface(tmp_path, 4.0))
    x_right = X0 - 5.0 + hw_roof  # the left frame's edge at roof height (2.96 m)
    assert flat.contains(Point(X0 + 3.5, Y0))
    assert not roofed.contains(Point(X0 + 3.5, Y0))      # roof beyond the left frame
    assert roofed.contains(Point(X0 + 2.5, Y0))
    assert roofed.contains(Point(X0 - 4.5, Y0 + 9.5))    # ground: the wide footprint
    assert not roofed.contains(Point(X0 + 2.0, Y0 + 9.5))  # roof: the narrow one
    assert not roofed.contains(Point(X0 - 9.8, Y0 + 9.8))  # nodata
    # the area within a cell's width along the edges of the analytic outline
    ground = (1.0 + hw_ground - 5.0) * 2 * hw_ground
    roof = (x_right - X0 - 1.0) * 2 * hw_roof
    assert abs(roofed.area - (ground + roof)) < 0.1 * 2 * (4 * hw_ground)
    clipped = stereo_overlap(FRAMES, _surface(tmp_path, 4.0), area=box(X0 - 1, Y0 - 1, X0 + 1,
                                                                      Y0 + 1))
    assert abs(clipped.area - 4.0) < 1e-6
    # read in bands of a few rows: the same cells, and one polygon — no slivers along the
    # bands' edges (a footprint across them must lie within it)
    banded = stereo_overlap(FRAMES, _surface(tmp_path, 4.0), cells_per_band=3 * 200)
    assert banded.symmetric_difference(roofed).area < 1e-6
    assert banded.geom_type == "Polygon"
    assert banded.contains(box(X0 - 4.0, Y0 - 7.0, X0 + 2.0, Y0 + 7.0))


def test_inside_frames_keeps_a_margin_from_the_border() -> None:
    # 1 px (0.1 m on the ground) inside the right frame's left border at the ground
    p = np.array([[X0 + 5 - _half_width(ZT) + 0.1, Y0, ZT]])
    assert inside_frames(FRAMES, p).tolist() == [True]
    assert inside_frames(FRAMES, p, margin_px=0.5).tolist() == [True]
    assert inside_frames(FRAMES, p, margin_px=2.0).tolist() == [False]
