"""Synthetic size ``aerial``: windows of a real wide-angle film geometry (B_px ≈ 4600 px).

The block is generated once per module with a 512 px window (the flight geometry is that of the
full 1024 px size; only the rendered window is smaller) to keep the module fast.
"""

from __future__ import annotations

import csv
import warnings
from pathlib import Path

import numpy as np
import pytest

rasterio = pytest.importorskip("rasterio")
pytest.importorskip("fiona")

from photodem.algorithms.errors import InputError  # noqa: E402
from photodem.algorithms.geometry.camera import Camera  # noqa: E402
from photodem.algorithms.geometry.epipolar import EpipolarPair  # noqa: E402
from photodem.algorithms.geometry.orientation import ExteriorOrientation  # noqa: E402
from photodem.algorithms.geometry.projection import world_to_pixel  # noqa: E402
from photodem.algorithms.processing import registry  # noqa: E402
from photodem.algorithms.project.model import Project  # noqa: E402
from photodem.algorithms.synthetic.block import build_scene, generate_block  # noqa: E402
from photodem.algorithms.synthetic.flight import SIZES, window_camera  # noqa: E402
from photodem.algorithms.synthetic.texture import PAD_FACTOR  # noqa: E402

WINDOW = 512
FRAME, FOCAL_MM, PIXEL_MM, GSD = 11500, 153.0, 0.020, 0.15


def _read(path: Path) -> np.ndarray:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # images are not georeferenced on purpose
        with rasterio.open(path) as src:
            return src.read()


@pytest.fixture(scope="module")
def block(tmp_path_factory):
    out = tmp_path_factory.mktemp("aerial") / "block"
    result = generate_block(out, size="aerial", terrain="gentle", seed=5, window=WINDOW)
    return result, Project.load(out)


@pytest.fixture(scope="module")
def truth_points(block):
    """Truth DSM points (N, 3) on a regular grid over the truth raster."""
    result, _ = block
    with rasterio.open(result.truth["dsm"]) as src:
        z = src.read(1).astype(float)
        t = src.transform
    rr, cc = np.mgrid[0:z.shape[0]:7, 0:z.shape[1]:7]
    x = t.c + (cc + 0.5) * t.a
    y = t.f + (rr + 0.5) * t.e
    return np.column_stack([x.ravel(), y.ravel(), z[rr, cc].ravel()])


def _inside(cam: Camera, col: np.ndarray, row: np.ndarray, margin: float = 0.0) -> np.ndarray:
    return ((col >= margin - 0.5) & (col <= cam.width - 0.5 - margin)
            & (row >= margin - 0.5) & (row <= cam.height - 0.5 - margin))


# -- the window camera: closed forms ---------------------------------------------------------------
def test_window_camera_is_the_frame_shifted() -> None:
    """Window pixel (c, r) is frame pixel (c0 + c, r0 + r), with distortion centred on the
    frame's principal point (which lies outside the window)."""
    frame = Camera("f", FRAME, FRAME, FOCAL_MM, (PIXEL_MM, PIXEL_MM), principal_point=(0.01, -0.02),
                   k1=-0.05, k2=0.01, p1=1e-4, p2=-2e-4)
    c0, r0, w, h = 9000, 4700, 700, 500
    win = window_camera(frame, "w", c0, r0, w, h)
    assert (win.width, win.height) == (w, h)
    rng = np.random.default_rng(0)
    col, row = rng.uniform(-0.5, w - 0.5, 200), rng.uniform(-0.5, h - 0.5, 200)
    assert np.allclose(win.pixel_to_camera(col, row), frame.pixel_to_camera(col + c0, row + r0),
                       atol=1e-9)
    p = frame.pixel_to_camera(col + c0, row + r0) * 3.7
    cw, rw = win.camera_to_pixel(p)
    cf, rf = frame.camera_to_pixel(p)
    assert np.allclose(cw + c0, cf, atol=1e-7) and np.allclose(rw + r0, rf, atol=1e-7)
    # the principal point (frame pixel ≈ centre) lies outside the window
    pc, pr = win.image_to_pixel(0.0, 0.0)
    assert not _inside(win, pc, pr)
    assert Camera.from_dict("w", win.to_dict()) == win
    with pytest.raises(InputError, match="window size"):
        SIZES["aerial"].with_window(32)
    with pytest.raises(InputError, match="windowed"):
        build_scene("tiny", window=128)


# -- the block -------------------------------------------------------------------------------------
def test_geometry_and_outputs(block) -> None:
    result, project = block
    spec = SIZES["aerial"]
    assert (spec.frame, spec.focal_mm, spec.pixel_mm) == (FRAME, FOCAL_MM, PIXEL_MM)
    out = result.outputs()
    assert out["images"] == 3 and out["models"] == 2
    H = GSD * FOCAL_MM / PIXEL_MM  # 1147.5 m
    assert out["gsd_m"] == pytest.approx(GSD) and out["flying_height_m"] == pytest.approx(H)
    assert out["base_px"] == pytest.approx(4600, rel=0.05)
    assert out["b_h"] == pytest.approx(0.6, rel=0.05)
    assert len(project.images) == 3 and len(project.cameras) == 3
    for rec in project.images:
        cam = project.camera_of(rec)
        assert (cam.width, cam.height) == (WINDOW, WINDOW)
        assert cam.focal_length == FOCAL_MM and cam.pixel_size == (PIXEL_MM, PIXEL_MM)
        img = _read(project.image_path(rec))
        assert img.shape == (3, WINDOW, WINDOW) and img.dtype == np.uint8
        assert 30 < img.mean() < 200 and img.std() > 10
    # outer windows sit ≈ ±B_px/2·… off the frame centre: principal points ≈ ∓92 mm along x
    xp = [project.camera_of(r).principal_point[0] for r in project.images]
    assert xp[0] < -85 and abs(xp[1]) < 10 and xp[2] > 85
    preset = project.presets["synthetic"]
    assert preset["frame_px"] == [FRAME, FRAME] and set(preset["windows"]) == {"0101", "0102",
                                                                              "0103"}


def test_models_detected(block) -> None:
    from photodem.algorithms.project.stereo_models import detect_stereo_models
    from photodem.algorithms.raster.sample import DemSampler

    result, project = block
    assert [m.name for m in project.models] == ["0101_0102", "0102_0103"]
    with rasterio.open(result.truth["dtm"]) as src:
        dem = DemSampler(src.read(1), src.transform)
    found = {m.name: m for m in detect_stereo_models(project, dem=dem, in_strip_only=True)}
    for m in project.models:
        assert m.kind == "in-strip" and m.name in found
        assert m.overlap > 0.9  # the windows cover the same ground patch
        assert m.b_h == pytest.approx(0.6, rel=0.05)
        base_px = m.base / m.gsd
        assert base_px == pytest.approx(4600, rel=0.05), base_px
        assert project.presets["synthetic"]["models"][m.name]["base_px"] == pytest.approx(
            base_px, abs=0.1)


def test_truth_points_project_into_all_three_windows(block, truth_points) -> None:
    """The ground patch is seen by all three windows, and each window is its frame shifted."""
    from photodem.algorithms.synthetic.flight import make_camera

    _, project = block
    frame = make_camera(SIZES["aerial"], "frame")
    windows = project.presets["synthetic"]["windows"]
    seen = np.ones(len(truth_points), dtype=bool)
    for rec in project.images:
        cam = project.camera_of(rec)
        col, row = world_to_pixel(truth_points, cam, rec.eo)
        fc, fr = world_to_pixel(truth_points, frame, rec.eo)
        c0, r0 = windows[rec.name]
        assert np.allclose(col + c0, fc, atol=1e-6) and np.allclose(row + r0, fr, atol=1e-6)
        seen &= _inside(cam, col, row)
    # the truth grid covers the windows with a margin; ≥ 40 % of it is seen by all three
    assert seen.mean() > 0.4, seen.mean()
    # the patch centre (planned nadir of the middle image) is seen near every window centre
    centre = truth_points[seen][:, :2].mean(axis=0)
    for rec in project.images:
        cam = project.camera_of(rec)
        z = float(np.median(truth_points[seen, 2]))
        col, row = world_to_pixel(np.array([[*centre, z]]), cam, rec.eo)
        assert _inside(cam, col, row, margin=0.3 * WINDOW)


def _centroid(grey: np.ndarray, col: float, row: float, r_px: float) -> tuple:
    h, w = grey.shape
    rr, cc = np.mgrid[0:h, 0:w]
    c, r = col, row
    for _ in range(3):
        d = np.hypot(cc - c, rr - r)
        background = np.median(grey[(d >= r_px + 1.2) & (d <= PAD_FACTOR * r_px - 1.2)])
        core = d <= r_px + 1.5
        wgt = np.clip(grey[core] - background, 0.0, None)
        c = float((wgt * cc[core]).sum() / wgt.sum())
        r = float((wgt * rr[core]).sum() / wgt.sum())
    return c, r


def test_checkpoint_discs_render_at_their_projection(block) -> None:
    """Rendering through the shifted principal points is exact: the bright check-point discs
    appear where the window cameras project their centres (oblique outer views included)."""
    from photodem.algorithms.geometry.dem_intersection import intersect_rays_dem
    from photodem.algorithms.raster.sample import DemSampler

    result, project = block
    with rasterio.open(result.truth["dsm"]) as src:
        dsm = DemSampler(src.read(1), src.transform)
    with open(result.project / "truth/checkpoints.csv", newline="") as fh:
        points = np.array([[float(r["x"]), float(r["y"]), float(r["z"])]
                           for r in csv.DictReader(fh)])
    disc_r = float(project.presets["synthetic"]["disc_radius_m"])
    errors, per_image = [], {}
    for rec in project.images:
        cam = project.camera_of(rec)
        grey = _read(project.image_path(rec)).astype(float).sum(axis=0)
        col, row = world_to_pixel(points, cam, rec.eo)
        for k, p in enumerate(points):
            dist = float(np.linalg.norm(p - rec.eo.position))
            r_px = disc_r / (dist * cam.pixel_size[0] / cam.focal_length)
            if not _inside(cam, col[k:k + 1], row[k:k + 1], PAD_FACTOR * r_px + 3)[0]:
                continue
            # fully visible: the rays to the centre and to the pad rim meet the DSM there (a
            # crown or a chimney may hide part of the pad in an oblique view)
            ang = np.linspace(0.0, 2.0 * np.pi, 16, endpoint=False)
            rim = np.column_stack([p[0] + PAD_FACTOR * disc_r * np.cos(ang),
                                   p[1] + PAD_FACTOR * disc_r * np.sin(ang)])
            targets = np.vstack([p, np.column_stack([rim, dsm.height(rim[:, 0], rim[:, 1])])])
            hits = intersect_rays_dem(rec.eo.position, targets - rec.eo.position, dsm)
            if not np.all(np.linalg.norm(hits - targets, axis=1) < 0.02):  # occluded
                continue
            c, r = _centroid(grey, col[k], row[k], r_px)
            errors.append(np.hypot(c - col[k], r - row[k]))
            per_image[rec.name] = per_image.get(rec.name, 0) + 1
    errors = np.asarray(errors)
    assert set(per_image) == {"0101", "0102", "0103"}, per_image
    print(f"aerial disc centroids: n={errors.size} max={errors.max():.3f} px "
          f"rms={np.sqrt(np.mean(errors ** 2)):.3f} px")
    assert errors.max() < 0.15, errors


@pytest.mark.parametrize("model", ["0101_0102", "0102_0103"])
def test_epipolar_pair_of_windows(block, truth_points, model: str) -> None:
    """Epipolar images of two windows are window-sized (not frame-sized), and truth points seen
    in both windows fall on the same epipolar row and triangulate back to themselves."""
    _, project = block
    m = project.model(model)
    rl, rr = project.image(m.left), project.image(m.right)
    cl, cr = project.camera_of(rl), project.camera_of(rr)
    pair = EpipolarPair.from_orientations(cl, rl.eo, cr, rr.eo)
    for w, h in pair.sizes:
        assert w <= 1.3 * WINDOW and h <= 1.3 * WINDOW, pair.sizes
    col_l, row_l = world_to_pixel(truth_points, cl, rl.eo)
    col_r, row_r = world_to_pixel(truth_points, cr, rr.eo)
    both = _inside(cl, col_l, row_l) & _inside(cr, col_r, row_r)
    assert both.mean() > 0.4
    el, fl = pair.from_original("left", col_l[both], row_l[both])
    er, fr = pair.from_original("right", col_r[both], row_r[both])
    assert np.abs(fl - fr).max() < 0.05
    for (w, h), c, r in (((pair.sizes[0]), el, fl), ((pair.sizes[1]), er, fr)):
        assert c.min() >= -0.5 and c.max() <= w - 0.5 and r.min() >= -0.5 and r.max() <= h - 0.5
    xyz = pair.epipolar_point_to_world(el, 0.5 * (fl + fr), er)
    assert np.abs(xyz - truth_points[both]).max() < 1e-4
    # the parallax is the full B_px-scale parallax, the disparities span only the relief:
    # Δd ≈ B_px · ΔZ / H (tens of px), whatever the window offsets
    parallax = (el - pair.cx[0]) - (er - pair.cx[1])
    base_px = m.base / m.gsd
    assert np.median(parallax) == pytest.approx(base_px, rel=0.03)
    d = el - er
    assert np.ptp(d) < 1.2 * base_px * np.ptp(truth_points[both, 2]) / m.height_above_ground
    # world_to_epipolar (what disparity ranges are made from) agrees with the pixel route
    wl, vl = pair.world_to_epipolar(truth_points[both], "left")
    wr, vr = pair.world_to_epipolar(truth_points[both], "right")
    assert np.abs(wl - el).max() < 1e-6 and np.abs(wr - er).max() < 1e-6
    assert np.abs(vl - fl).max() < 1e-6 and np.abs(vr - fr).max() < 1e-6
    # the resampled images cover most of the epipolar frame
    for side, rec in (("left", rl), ("right", rr)):
        img = _read(project.image_path(rec))
        epi, valid = pair.resample(img[1], side)
        assert epi.shape == pair.sizes[SIDE[side]][::-1] and valid.mean() > 0.6


SIDE = {"left": 0, "right": 1}


def test_registry_offers_aerial() -> None:
    alg = registry.get("synthetic_block")
    size = next(p for p in alg.parameters if p.name == "size")
    assert "aerial" in size.options and "base" in size.help
    assert {"base_px", "b_h"} <= {o.name for o in alg.outputs}


def test_exterior_orientation_is_realistic(block) -> None:
    _, project = block
    for rec in project.images:
        omega, phi, kappa = rec.eo.opk()
        assert abs(omega) <= 2.0 and abs(phi) <= 2.0 and abs(kappa) <= 2.0
        assert isinstance(rec.eo, ExteriorOrientation)
