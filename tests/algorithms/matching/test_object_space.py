"""Object-space multi-image LSM: a small rendered scene with a known surface.

The scene: a smooth analytic surface (±1.5 m hills and a 3 % slope) with band-limited texture,
rendered by the synthetic ray caster (box PSF, per-image gain/offset, vignetting, noise 2 DN)
into three 240 × 240 px frame images along X (GSD 0.2 m, H = 48 m, bases 12 and 24 m:
B/H = 0.25 / 0.5). The start DSM is the truth plus a 0.5 m bump and a 0.15 m wave.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
import rasterio
from _three_frames import BASE, CRS, FLY, GSD, X0, Y0, ZT, write_three_frames
from affine import Affine
from shapely.geometry import box

from photodem.algorithms.errors import Cancelled, InputError
from photodem.algorithms.feedback import Feedback
from photodem.algorithms.geometry.orientation import ExteriorOrientation
from photodem.algorithms.matching.object_space import refine_object_space
from photodem.algorithms.matching.object_space_window import (
    ImageWindow,
    _screen,
    _second_difference_rows,
    _visibility,
)
from photodem.algorithms.processing import registry
from photodem.algorithms.project.edits import add_features
from photodem.algorithms.project.model import ImageRecord, Project
from photodem.algorithms.raster.io import write_raster


def truth(x, y):
    u, v = np.asarray(x) - X0, np.asarray(y) - Y0
    return ZT + 1.5 * np.sin(2 * np.pi * u / 37.0) * np.cos(2 * np.pi * v / 29.0) + 0.03 * u


def start_error(u, v):
    return 0.5 * np.exp(-(u ** 2 + v ** 2) / (2 * 4.0 ** 2)) + 0.15 * np.sin(u / 3.0 + v / 5.0)


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    root = tmp_path_factory.mktemp("object_space") / "project"
    write_three_frames(root, truth, "os")
    # start DSM: 24 m × 24 m at 0.4 m, truth + smooth error
    spacing, half_dsm = 0.4, 12.0
    m = int(2 * half_dsm / spacing)
    t = Affine(spacing, 0, X0 - half_dsm, 0, -spacing, Y0 + half_dsm)
    cols, rows = np.meshgrid(np.arange(m) + 0.5, np.arange(m) + 0.5)
    x, y = t * (cols, rows)
    z_true = truth(x, y)
    write_raster(root / "start.tif", (z_true + start_error(x - X0, y - Y0)).astype(np.float32),
                 transform=t, crs=CRS)
    return {"root": root, "dsm": root / "start.tif", "truth": z_true, "x": x, "y": y}


def _errors(scene, path):
    with rasterio.open(path) as src:
        z = src.read(1)
    inner = np.zeros(z.shape, bool)
    inner[3:-3, 3:-3] = True  # one geometry facet off the border
    return z - scene["truth"], inner


# -- numerics ---------------------------------------------------------------------------------
def test_curvature_rows_vanish_on_planes() -> None:
    R = _second_difference_rows(5, 7)
    rr, cc = np.mgrid[0:5, 0:7]
    assert R.shape == (5 * 5 + 3 * 7, 35)
    assert np.allclose(R @ (3.0 + 0.2 * rr - 0.7 * cc).ravel(), 0.0)
    assert np.allclose(R @ (cc ** 2).ravel().astype(float), np.where(
        np.arange(R.shape[0]) < 25, 2.0, 0.0))


def test_visibility_box_shadow_closed_form() -> None:
    """A 4 m box on flat ground, seen from far away at t = 0.5 m horizontal per m of rise
    (towards +X): the ground within 4·0.5 = 2 m west of the box is hidden, the rest visible;
    the one-cell walls are grazing for a nadir view."""
    n, sp = 60, 0.5
    surf = np.zeros((n, n))
    surf[20:40, 20:40] = 4.0
    x_first, y_first = 0.25, 29.75  # cell (0, 0) centre
    rr, cc = np.mgrid[0:n, 0:n]
    X = (x_first + cc * sp).ravel().astype(float)
    Y = (y_first - rr * sp).ravel().astype(float)
    Z = surf.ravel()
    far = ExteriorOrientation.from_opk([15.0 + 5000.0, 15.0, 10000.0], 0, 0, 0)
    nadir = ExteriorOrientation.from_opk([15.0, 15.0, 10000.0], 0, 0, 0)
    wins = [ImageWindow("far", None, far, 0, 0), ImageWindow("nadir", None, nadir, 0, 0)]
    vis = _visibility(wins, X, Y, Z, surf, x_first, y_first, sp).reshape(2, n, n)
    west_wall = x_first + 20 * sp - 0.5 * sp  # X of the box's west face
    d = west_wall - (x_first + cc * sp)  # horizontal distance to the face (west of it > 0)
    rows_box = (rr >= 22) & (rr < 38)
    hidden = rows_box & (d > 0.5) & (d < 1.6)
    seen = rows_box & (d > 2.4) & (d < 8.0)
    assert not vis[0][hidden].any()
    assert vis[0][seen].all() and vis[1][hidden | seen].all()
    assert vis[0][25:35, 23:37].all() and vis[1][25:35, 23:37].all()  # the roof
    assert not vis[1][rows_box & (cc == 19)].any()  # the wall ramp: grazing


def test_screen_flags_a_disturbed_image() -> None:
    rng = np.random.default_rng(4)
    n = 4000
    G = 100 + 30 * rng.standard_normal(n)
    h0, h1 = np.array([0.0, 5.0, -3.0]), np.array([1.0, 0.8, 1.25])
    g = (G[None, :] - h0[:, None]) / h1[:, None] + rng.standard_normal((3, n))
    g[2, 123] += 60.0  # a "car" in one image
    g[1, 77:80] = np.nan  # not seen
    seen = np.isfinite(g)
    rej = _screen(g, np.zeros((3, n)), seen, h0, h1, np.zeros(n), 4.0)
    assert rej[123] and rej.sum() <= 1 + 0.002 * n


# -- the synthetic scene ----------------------------------------------------------------------
def test_refinement_approaches_truth_with_consistent_sigma(scene, tmp_path) -> None:
    res = refine_object_space(scene["root"], scene["dsm"], tmp_path / "out")
    e0, inner = _errors(scene, scene["dsm"])
    e1, _ = _errors(scene, res["dsm"])
    with rasterio.open(res["sigma"]) as src:
        sig = src.read(1)
        assert src.crs is not None and src.dtypes[0] == "float32"
    ok = inner & np.isfinite(e1)
    assert ok.sum() > 0.95 * inner.sum()
    rms0 = float(np.sqrt(np.mean(e0[ok] ** 2)))
    rms1 = float(np.sqrt(np.mean(e1[ok] ** 2)))
    px_per_m = 2 * BASE / FLY / GSD  # parallax of the widest pair per metre of height
    med_sig = float(np.median(sig[ok]))
    print(f"RMS before {rms0:.3f} m = {rms0 * px_per_m:.2f} px = {1000 * rms0 / FLY:.2f} ‰ H, "
          f"after {rms1:.3f} m = {rms1 * px_per_m:.2f} px = {1000 * rms1 / FLY:.2f} ‰ H; "
          f"median σ_Z {med_sig:.3f} m, σ0 {res['metrics']['sigma0_grey_median']:.2f} GL")
    # measured: 0.196 → 0.064 m (0.49 → 0.16 px of parallax, 4.1 → 1.3 ‰ H), σ_Z 0.078 m
    assert rms1 < 0.5 * rms0
    assert abs(float(np.mean(e1[ok]))) < 0.03
    assert 0.5 < rms1 / med_sig < 2.0  # predicted σ within ×2 of the empirical error
    # most errors inside the 2.58 σ band
    assert np.mean(np.abs(e1[ok]) < 2.58 * sig[ok]) > 0.85
    m = res["metrics"]
    assert m["failures"] == 0 and m["refined_cells"] == int(np.isfinite(e1).sum())
    assert 1.0 < m["sigma0_grey_median"] < 15.0
    import json

    rep = json.loads(Path(res["report"]).read_text())
    assert rep["tiles"][0]["images"] == ["img0", "img1", "img2"]
    assert all(1 <= k <= 8 for k in rep["tiles"][0]["iterations"])


def test_three_images_beat_two(scene, tmp_path) -> None:
    _, inner = _errors(scene, scene["dsm"])
    out = {}
    for name, imgs in (("two", ["img0", "img1"]), ("three", None)):
        res = refine_object_space(scene["root"], scene["dsm"], tmp_path / name, images=imgs)
        e, _ = _errors(scene, res["dsm"])
        ok = inner & np.isfinite(e)
        out[name] = (float(np.sqrt(np.mean(e[ok] ** 2))), res["metrics"]["sigma_z_median_m"])
    print(f"2 images: RMS {out['two'][0]:.3f} m, σ {out['two'][1]:.3f} m; "
          f"3 images: RMS {out['three'][0]:.3f} m, σ {out['three'][1]:.3f} m")
    assert out["three"][0] < out["two"][0]
    assert out["three"][1] < out["two"][1]


def test_exclusion_is_nan_and_cancel_leaves_nothing(scene, tmp_path) -> None:
    proj = tmp_path / "project"
    shutil.copytree(scene["root"], proj)
    add_features(proj / "edits.gpkg", "exclusion_areas",
                 [(box(X0 - 3, Y0 - 3, X0 + 3, Y0 + 3), {"action": "exclude"})])
    res = registry.run("refine_object_space", {"project": str(proj),
                                               "dsm": str(proj / "start.tif")})
    assert Path(res["dsm"]).parent == proj / "products" / "dsm_refined" / "start"
    with rasterio.open(res["dsm"]) as src:
        z = src.read(1)
    inside = (np.abs(scene["x"] - X0) < 2.9) & (np.abs(scene["y"] - Y0) < 2.9)
    assert inside.sum() > 150 and np.isnan(z[inside]).all()
    assert np.isfinite(z[~inside]).mean() > 0.9

    fb = Feedback()
    fb._on_progress = lambda p: fb.cancel() if p > 20 else None
    with pytest.raises(Cancelled):
        refine_object_space(proj, proj / "start.tif", tmp_path / "cancelled", feedback=fb,
                            tile=20)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["project"]


def test_bad_input_is_one_line_error(scene, tmp_path) -> None:
    with pytest.raises(InputError, match="at least two images"):
        refine_object_space(scene["root"], scene["dsm"], tmp_path / "o", images=["img1"])
    with pytest.raises(InputError, match="does not exist"):
        refine_object_space(scene["root"], tmp_path / "missing.tif", tmp_path / "o")
    assert not (tmp_path / "o").exists()


def test_no_iteration_reproduces_the_input(scene, tmp_path) -> None:
    res = refine_object_space(scene["root"], scene["dsm"], tmp_path / "o", max_iter=0)
    with rasterio.open(scene["dsm"]) as a, rasterio.open(res["dsm"]) as b:
        z0, z1 = a.read(1), b.read(1)
    ok = np.isfinite(z1)
    assert ok.mean() > 0.9 and np.array_equal(z0[ok], z1[ok])


def test_window_cameras_give_the_same_surface(scene, tmp_path) -> None:
    """Images cut to windows of their frames (principal point far from the window centre, as
    the synthetic aerial block renders them) must refine the same surface as the full frames."""
    from photodem.algorithms.geometry.camera import Camera as Cam

    proj = Project.load(scene["root"])
    root = tmp_path / "win"
    (root / "images").mkdir(parents=True)
    cams, recs = {}, []
    for k, rec in enumerate(proj.images):
        cam = proj.camera_of(rec)
        # windows that hold the DSM and its overlap in every image, at even offsets (the
        # pyramid lattice); 100 px off-centre at most
        c0, r0, w, h = (100, 40, 140, 160) if k == 0 else (40, 36, 160, 164) if k == 1 \
            else (0, 40, 140, 160)
        with rasterio.open(proj.image_path(rec)) as src:
            img = src.read(window=((r0, r0 + h), (c0, c0 + w)))
        write_raster(root / "images" / f"{rec.name}.tif", img)
        px, py = cam.pixel_size
        pp = (cam.principal_point[0] - (c0 + (w - 1) / 2 - (cam.width - 1) / 2) * px,
              cam.principal_point[1] + (r0 + (h - 1) / 2 - (cam.height - 1) / 2) * py)
        cams[f"w{k}"] = Cam(f"w{k}", w, h, focal_length=cam.focal_length,
                            pixel_size=cam.pixel_size, principal_point=pp)
        recs.append(ImageRecord(rec.name, f"images/{rec.name}.tif", f"w{k}", rec.eo))
    Project(root=root, name="win", crs=CRS, cameras=cams, images=recs,
            terrain_height=ZT).save()
    full = refine_object_space(scene["root"], scene["dsm"], tmp_path / "full")
    win = refine_object_space(root, scene["dsm"], tmp_path / "window")
    e_full, inner = _errors(scene, full["dsm"])
    e_win, _ = _errors(scene, win["dsm"])
    ok = inner & np.isfinite(e_full) & np.isfinite(e_win)
    rms = [float(np.sqrt(np.mean(e[ok] ** 2))) for e in (e_full, e_win)]
    diff = float(np.sqrt(np.mean((e_full[ok] - e_win[ok]) ** 2)))
    print(f"full frames RMS {rms[0]:.3f} m, windows {rms[1]:.3f} m, difference {diff:.4f} m")
    assert ok.sum() > 0.9 * inner.sum() and abs(rms[1] - rms[0]) < 0.002 and diff < 0.005
