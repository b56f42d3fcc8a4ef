"""Keypoint stage: an image against an image reference (multi-temporal synthetic pairs)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from photodem.algorithms.errors import GeometryError, InputError
from photodem.algorithms.georef.fit import corner_error
from photodem.algorithms.georef.keypoints import make_detector, spread, to_byte
from photodem.algorithms.georef.pipeline import (
    GeorefOptions,
    georeference,
    run_georeference_polygons,
)
from photodem.algorithms.synthetic.image_pairs import image_pair_case
from photodem.algorithms.synthetic.polygon_scene import make_scene, write_image, write_scene

SIZE = 500  # target 500 × 500 px, reference 700 × 700 px


@pytest.fixture(scope="module")
def pairs(tmp_path_factory):
    """Three small cases: rotated (not mirrored) under 55 % cloud, mirrored, 12-bit."""
    root = tmp_path_factory.mktemp("pairs")
    return {
        "clouds": image_pair_case(root / "clouds", seed=2, width=SIZE, height=SIZE,
                                  cloud_share=0.55),
        "mirrored": image_pair_case(root / "mirrored", seed=1, width=SIZE, height=SIZE),
        "12bit": image_pair_case(root / "12bit", seed=6, width=SIZE, height=SIZE, bits=12),
    }


def _corner_px(res, case) -> float:
    return float(corner_error(res.fit, case["truth"], case["width"], case["height"]).max())


@pytest.mark.slow
@pytest.mark.parametrize("name", ["clouds", "mirrored", "12bit"])
def test_corners_within_a_pixel(pairs, name) -> None:
    case = pairs[name]
    res = georeference(case["image"], case["reference"])
    assert res.stage == "keypoints"
    assert _corner_px(res, case) <= 1.0
    assert res.counts["mirrored"] == case["mirrored"]
    assert res.counts["gcps"] >= 30 and res.fit.rmse_px < 0.5
    # the control points spread over the cloud-free overlap, not one corner of it
    xy = np.array([g.image for g in res.gcps])
    assert np.ptp(xy[:, 0]) > 0.5 * SIZE and np.ptp(xy[:, 1]) > 0.5 * SIZE


@pytest.mark.slow
def test_projective_and_products(pairs, tmp_path) -> None:
    case = pairs["clouds"]
    opts = GeorefOptions(search="keypoints", transform="projective")
    summary = run_georeference_polygons(case["image"], case["reference"], tmp_path / "out",
                                        opts)
    T = np.array(summary["transform"]["matrix"])
    assert corner_error(T, case["truth"], SIZE, SIZE).max() <= 1.0
    rep = json.loads(Path(summary["report"]).read_text())
    assert rep["stage"] == "keypoints" and rep["parameters"]["detector"] == "auto"
    assert "patches located in the reference" in Path(summary["report"]).with_suffix(
        ".html").read_text()


@pytest.mark.slow
def test_unrelated_reference_fails_with_the_figures(pairs) -> None:
    img = pairs["clouds"]["image"]
    other = pairs["mirrored"]["reference"]
    with pytest.raises(GeometryError) as err:
        georeference(img, other, search="keypoints")
    assert "keypoint" in str(err.value) and "inliers" in err.value.counts


@pytest.mark.slow
def test_unrelated_reference_falls_back_to_objects_then_fails(pairs, monkeypatch) -> None:
    """``auto``: the object chain after a failed keypoint stage, one message for both (the
    object chain replaced by its failure: on these landscapes it takes minutes)."""
    from photodem.algorithms.georef import pipeline

    def no_objects(*args, **kwargs):
        raise GeometryError("Georeferencing failed: no two hypotheses are geometrically "
                            "consistent (image objects 7). Check that …", {"image_objects": 7})

    monkeypatch.setattr(pipeline, "_object_stage", no_objects)
    with pytest.raises(GeometryError) as err:
        georeference(pairs["12bit"]["image"], pairs["mirrored"]["reference"])
    msg = str(err.value)
    assert "no two hypotheses" in msg and "Before it, the keypoint stage found no result" in msg
    assert "inliers" in err.value.counts and err.value.counts["image_objects"] == 7


def test_keypoints_need_a_raster_reference(tmp_path) -> None:
    ref = write_scene(make_scene(0, n_forest=2, n_field=1, n_lake=1), tmp_path / "m.gpkg")
    img = tmp_path / "img.tif"
    write_image(img, np.full((20, 20), 100, np.uint8))
    with pytest.raises(InputError, match="raster"):
        georeference(img, ref, search="keypoints")
    with pytest.raises(InputError, match="detector"):
        georeference(img, ref, detector="surf")


def test_helpers() -> None:
    a = np.array([[np.nan, 0.0], [50.0, 1000.0]])
    b, mask = to_byte(a)
    assert b.dtype == np.uint8 and b[1, 1] == 255 and mask[0, 0] == 0
    assert make_detector("orb")[2] == "orb" and make_detector()[2] in ("sift", "akaze", "orb")
    xy = np.array([[1.0, 1.0], [2.0, 2.0], [90.0, 90.0]])
    keep = spread(xy, np.array([0.5, 0.9, 0.7]), (100, 100), 2)
    assert keep.tolist() == [1, 2]
