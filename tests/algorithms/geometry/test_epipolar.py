"""epipolar: normal-case resampling of a pair, mappings, triangulation."""

from __future__ import annotations

import csv

import numpy as np
import pytest

from photodem.algorithms.geometry.camera import Camera
from photodem.algorithms.geometry.epipolar import EpipolarPair
from photodem.algorithms.geometry.orientation import ExteriorOrientation
from photodem.algorithms.geometry.projection import world_to_pixel
from photodem.algorithms.raster.sample import DemSampler


def _pair(cam_l: Camera, cam_r: Camera, scale: float = 1.0) -> EpipolarPair:
    # realistic tilts up to ±3°, different κ, a slightly bent flight line
    eo_l = ExteriorOrientation.from_opk([0.0, 0.0, 1000.0], 2.7, -2.9, 3.5)
    eo_r = ExteriorOrientation.from_opk([75.0, 6.0, 1012.0], -3.0, 2.2, -6.0)
    return EpipolarPair.from_orientations(cam_l, eo_l, cam_r, eo_r, scale=scale,
                                          names=("a", "b"))


def _truth_points(pair: EpipolarPair, n: int = 5000):
    rng = np.random.default_rng(31)
    X = np.column_stack([rng.uniform(-40, 120, n), rng.uniform(-80, 80, n),
                         rng.uniform(-60, 150, n)])
    obs = []
    keep = np.ones(n, bool)
    for cam, eo in zip(pair.cameras, pair.eos):
        c, r = world_to_pixel(X, cam, eo)
        keep &= (c >= 0) & (c <= cam.width - 1) & (r >= 0) & (r <= cam.height - 1)
        obs.append((c, r))
    return X[keep], [(c[keep], r[keep]) for c, r in obs]


def test_y_parallax_of_truth_points(distorted_camera):
    cam_r = Camera("r", 2000, 1500, 101.0, (0.01, 0.01), principal_point=(-0.05, 0.03),
                   k1=0.06, k2=-0.03, p1=-1e-4, p2=2e-4)
    pair = _pair(distorted_camera, cam_r)
    X, ((cl, rl), (cr, rr)) = _truth_points(pair)
    assert len(X) > 1000
    el_c, el_r = pair.from_original("left", cl, rl)
    er_c, er_r = pair.from_original("right", cr, rr)
    y_par = np.abs(el_r - er_r)
    assert y_par.max() < 0.05
    # the original images are far from epipolar: their rows differ by many pixels
    assert np.max(np.abs(rl - rr)) > 20
    # all points fall inside the epipolar images
    for c, r, (w, h) in ((el_c, el_r, pair.sizes[0]), (er_c, er_r, pair.sizes[1])):
        assert c.min() >= -0.5 and c.max() <= w - 0.5 and r.min() >= -0.5 and r.max() <= h - 0.5
    # triangulation from epipolar coordinates gives the truth back
    P = pair.epipolar_point_to_world(el_c, 0.5 * (el_r + er_r), er_c)
    np.testing.assert_allclose(P, X, atol=1e-3)
    # disparity form, and the world → epipolar projection
    P2 = pair.disparity_to_world(el_c - er_c, el_c, el_r)
    np.testing.assert_allclose(P2, X, atol=2e-3)
    wc, wr = pair.world_to_epipolar(X, "right")
    np.testing.assert_allclose(wc, er_c, atol=1e-6)
    np.testing.assert_allclose(wr, er_r, atol=1e-6)
    lo, hi = pair.disparity_range(-60, 150)
    assert lo < np.median(el_c - er_c) < hi


def test_mappings_round_trip_and_homography(distorted_camera, plain_camera):
    pair = _pair(distorted_camera, distorted_camera, scale=0.5)
    rng = np.random.default_rng(32)
    for side, cam in zip(("left", "right"), pair.cameras):
        c, r = rng.uniform(0, cam.width - 1, 2000), rng.uniform(0, cam.height - 1, 2000)
        ec, er = pair.from_original(side, c, r)
        oc, orow = pair.to_original(side, ec, er)
        assert np.max(np.hypot(oc - c, orow - r)) < 1e-6
    # without distortion the homography alone is the map
    plain = _pair(plain_camera, plain_camera)
    ec, er = rng.uniform(0, 1000, 100), rng.uniform(0, 1000, 100)
    q = plain.homographies[1] @ np.vstack([ec, er, np.ones(100)])
    oc, orow = plain.to_original("right", ec, er)
    np.testing.assert_allclose(q[:2] / q[2], np.vstack([oc, orow]), atol=1e-9)
    assert pair.focal_px == pytest.approx(0.5 * plain.focal_px)
    # serialisation
    again = EpipolarPair.from_dict(pair.to_dict())
    np.testing.assert_allclose(again.to_original("left", ec, er),
                               pair.to_original("left", ec, er), atol=1e-9)


def test_resample_bilinear_all_bands_in_chunks(distorted_camera):
    pair = _pair(distorted_camera, distorted_camera, scale=0.25)
    cam = pair.cameras[0]
    rows, cols = np.mgrid[0:cam.height, 0:cam.width].astype(np.float32)
    img = np.stack([cols, rows])  # bilinear is exact on linear functions
    out, valid = pair.resample(img, "left", chunk_rows=37)
    mc, mr = pair.original_map("left")
    assert out.shape == (2, pair.sizes[0][1], pair.sizes[0][0])
    assert valid.mean() > 0.5
    np.testing.assert_array_equal(valid, np.isfinite(mc))
    inner = valid & (mc >= 0) & (mr >= 0) & (mc <= cam.width - 1) & (mr <= cam.height - 1)
    np.testing.assert_allclose(out[0][inner], mc[inner], atol=2e-3)
    np.testing.assert_allclose(out[1][inner], mr[inner], atol=2e-3)
    assert np.all(out[:, ~valid] == 0)
    u8, ok = pair.resample((img[0] % 256).astype(np.uint8), "left")
    assert u8.dtype == np.uint8 and u8.ndim == 2 and ok.shape == u8.shape


def _ngi(ngi_block):
    cam = Camera("dmc", 640, 1152, 120.0, (0.144, 0.144))
    eos = {}
    with open(ngi_block / "io" / "ngi_xyz_opk.csv", newline="") as fh:
        for row in csv.DictReader(fh):
            eos[row["filename"][-8:-4]] = ExteriorOrientation.from_opk(
                [float(row["x"]), float(row["y"]), float(row["z"])],
                float(row["omega"]), float(row["phi"]), float(row["kappa"]), "degrees")
    return cam, eos


def test_ngi_pair_y_parallax(ngi_block):
    cam, eos = _ngi(ngi_block)
    pair = EpipolarPair.from_orientations(cam, eos["0182"], cam, eos["0184"])
    dem = DemSampler.from_file(ngi_block / "ngi" / "dem.tif")
    h, w = dem.shape
    rows, cols = np.mgrid[0:h, 0:w]
    t = dem.transform
    x = t.c + (cols + 0.5) * t.a
    y = t.f + (rows + 0.5) * t.e
    X = np.column_stack([x.ravel(), y.ravel(), dem.array.ravel()])
    X = X[np.isfinite(X[:, 2])]
    cl, rl = world_to_pixel(X, cam, pair.eos[0])
    cr, rr = world_to_pixel(X, cam, pair.eos[1])
    both = ((cl >= 0) & (cl <= 639) & (rl >= 0) & (rl <= 1151)
            & (cr >= 0) & (cr <= 639) & (rr >= 0) & (rr <= 1151))
    assert both.sum() > 10000  # about 14 000 DEM cells are seen by both
    _, el = pair.from_original("left", cl[both], rl[both])
    _, er = pair.from_original("right", cr[both], rr[both])
    assert np.max(np.abs(el - er)) < 0.05
    assert pair.base == pytest.approx(2616.0, abs=5.0)


@pytest.mark.filterwarnings("ignore::rasterio.errors.NotGeoreferencedWarning")
def test_ngi_epipolar_images_agree_at_dem_points(ngi_block):
    import rasterio

    from photodem.algorithms.raster.sample import bilinear_grid

    cam, eos = _ngi(ngi_block)
    pair = EpipolarPair.from_orientations(cam, eos["0182"], cam, eos["0184"])
    grey = []
    for side, name in (("left", "0182"), ("right", "0184")):
        with rasterio.open(ngi_block / "ngi" / f"3324c_2015_1004_05_{name}_RGB.tif") as src:
            img = src.read()
        out, valid = pair.resample(img, side)
        g = out.astype(float).mean(axis=0)
        grey.append(np.where(valid, g, np.nan))
    dem = DemSampler.from_file(ngi_block / "ngi" / "dem.tif")
    h, w = dem.shape
    rows, cols = np.mgrid[0:h, 0:w]
    t = dem.transform
    X = np.column_stack([(t.c + (cols + 0.5) * t.a).ravel(), (t.f + (rows + 0.5) * t.e).ravel(),
                         dem.array.ravel()])
    el_c, el_r = pair.world_to_epipolar(X, "left")
    er_c, er_r = pair.world_to_epipolar(X, "right")
    a = bilinear_grid(grey[0], el_c, el_r)
    b = bilinear_grid(grey[1], er_c, er_r)
    ok = np.isfinite(a) & np.isfinite(b)
    assert ok.sum() > 10000
    assert np.corrcoef(a[ok], b[ok])[0, 1] >= 0.9
