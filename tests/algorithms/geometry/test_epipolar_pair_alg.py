"""The epipolar_pair algorithm on a small hand-made project."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import rasterio
from affine import Affine

from photodem.algorithms.errors import Cancelled, InputError
from photodem.algorithms.feedback import Feedback
from photodem.algorithms.geometry.camera import Camera
from photodem.algorithms.geometry.epipolar import EpipolarPair
from photodem.algorithms.geometry.orientation import ExteriorOrientation
from photodem.algorithms.geometry.projection import ray_at_height
from photodem.algorithms.processing import registry
from photodem.algorithms.project.model import ImageRecord, Project, StereoModel
from photodem.algorithms.raster.io import write_raster
from photodem.algorithms.raster.sample import bilinear

pytestmark = pytest.mark.filterwarnings(
    "ignore::rasterio.errors.NotGeoreferencedWarning")

TEXTURE_T = Affine(2.0, 0.0, -300.0, 0.0, -2.0, 300.0)  # 2 m texels over 600 m × 600 m


def _texture():
    rng = np.random.default_rng(41)
    return rng.uniform(20, 235, (3, 300, 300))


def _render(cam, eo, tex):
    rows, cols = np.mgrid[0:cam.height, 0:cam.width]
    X = ray_at_height(cols, rows, 0.0, cam, eo)  # a flat textured ground at Z = 0
    bands = [bilinear(t, TEXTURE_T, X[..., 0], X[..., 1]) for t in tex]
    return np.clip(np.rint(np.nan_to_num(np.stack(bands), nan=0.0)), 0, 255).astype(np.uint8)


@pytest.fixture
def small_project(tmp_path: Path) -> Project:
    cam = Camera("cam", 240, 180, 20.0, (0.02, 0.02), k1=-0.05, p2=1e-4)
    eos = [ExteriorOrientation.from_opk([-30.0, 0.0, 500.0], 1.5, -2.0, 2.0),
           ExteriorOrientation.from_opk([30.0, 3.0, 505.0], -2.0, 1.0, -3.0)]
    tex = _texture()
    images = []
    for name, eo in zip(("a", "b"), eos):
        path = tmp_path / "images" / f"{name}.tif"
        write_raster(path, _render(cam, eo, tex))
        images.append(ImageRecord(name, f"images/{name}.tif", "cam", eo))
    project = Project(root=tmp_path / "proj_root", name="tiny", crs="EPSG:32633",
                      cameras={"cam": cam}, images=images,
                      models=[StereoModel("a_b", "a", "b")], terrain_height=0.0)
    # image paths relative to the project folder
    project.root = tmp_path
    project.save()
    return Project.load(tmp_path)


def test_epipolar_pair_writes_consistent_products(small_project):
    alg = registry.get("epipolar_pair")
    assert alg.iterates_over == "model" and alg.group == "Geometry"
    out = registry.run("epipolar_pair", {"project": str(small_project.root), "model": "a_b"})
    folder = Path(out["folder"])
    assert folder == small_project.root / "products" / "epipolar" / "a_b"
    for key in ("left", "right", "left_map", "right_map", "metadata"):
        assert Path(out[key]).is_file()
    assert out["y_parallax_check_px"] < 1e-6
    meta = json.loads(Path(out["metadata"]).read_text())
    assert meta["model"] == "a_b" and meta["images"] == {"left": "a", "right": "b"}
    pair = EpipolarPair.from_dict(meta)
    with rasterio.open(out["left"]) as src:
        assert src.count == 4 and src.dtypes[0] == "uint8"
        assert [src.width, src.height] == out["size"]
        left = src.read()
    with rasterio.open(out["right"]) as src:
        right = src.read()
    with rasterio.open(out["left_map"]) as src:
        assert src.count == 2 and src.dtypes[0] == "float32"
        lmap = src.read()
    assert np.array_equal(np.isfinite(lmap[0]), left[3] == 255)
    mc, mr = pair.original_map("left")
    np.testing.assert_allclose(lmap[0], mc, atol=1e-3)
    np.testing.assert_allclose(lmap[1], mr, atol=1e-3)
    # the flat ground seen at the same row: left pixel → ground → right epipolar pixel
    rows, cols = np.nonzero(left[3] == 255)
    oc, orow = pair.to_original("left", cols, rows)
    ground = ray_at_height(oc, orow, 0.0, pair.cameras[0], pair.eos[0])
    rc, rr = pair.world_to_epipolar(ground, "right")
    np.testing.assert_allclose(rr, rows, atol=1e-6)  # no y-parallax
    ok = np.isfinite(rc)
    vals = bilinear(right[0].astype(float), Affine.identity(), rc[ok] + 0.5, rr[ok] + 0.5)
    alpha_r = bilinear((right[3] == 255).astype(float), Affine.identity(), rc[ok] + 0.5,
                       rr[ok] + 0.5)
    good = np.isfinite(vals) & (alpha_r == 1.0)
    a = left[0][rows[ok][good], cols[ok][good]].astype(float)
    b = vals[good]
    assert good.sum() > 5000
    ncc = np.corrcoef(a, b)[0, 1]
    assert ncc > 0.95, ncc


def test_cancel_leaves_no_output(small_project):
    feedback = Feedback()
    feedback._on_progress = lambda pct: feedback.cancel()
    target = small_project.root / "products" / "epipolar" / "a_b"
    with pytest.raises(Cancelled):
        registry.run("epipolar_pair", {"project": str(small_project.root), "model": "a_b"},
                     feedback)
    assert not target.exists()
    parent = target.parent
    assert not parent.exists() or not any(parent.iterdir())


def test_bad_model_and_existing_output(small_project, tmp_path):
    with pytest.raises(InputError, match="not in project"):
        registry.run("epipolar_pair", {"project": str(small_project.root), "model": "x_y"})
    out = tmp_path / "custom"
    out.mkdir()
    (out / "keep.txt").write_text("x")
    with pytest.raises(InputError, match="did not write"):
        registry.run("epipolar_pair", {"project": str(small_project.root), "model": "a_b",
                                       "output": str(out), "scale": 0.5})
    assert (out / "keep.txt").read_text() == "x"  # the operator's folder is untouched


def test_rerun_replaces_own_product(small_project, tmp_path):
    out = tmp_path / "epi"
    params = {"project": str(small_project.root), "model": "a_b", "output": str(out),
              "scale": 0.5}
    first = registry.run("epipolar_pair", params)
    stamp = (out / "epipolar.json").stat().st_mtime_ns
    second = registry.run("epipolar_pair", params)
    assert first == second
    assert (out / "epipolar.json").stat().st_mtime_ns >= stamp
    assert not [p for p in tmp_path.iterdir() if "partial" in p.name]  # no staging left
