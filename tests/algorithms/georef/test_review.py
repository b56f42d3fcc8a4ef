"""Operator review of a georeferencing result: points off, pairs rejected, manual points,
another transform, products written again (nothing of the automatic result lost)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
import rasterio

from photodem.algorithms.errors import InputError
from photodem.algorithms.georef.fit import corner_error
from photodem.algorithms.georef.review import load_review, save_review
from photodem.algorithms.processing import registry
from photodem.algorithms.synthetic.polygon_scene import georef_case


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    root = tmp_path_factory.mktemp("review")
    case = georef_case(root / "case", seed=5)
    out = root / "auto"
    res = registry.run("georeference_polygons", {
        "image": case["image"], "reference": case["reference"], "output": str(out)})
    return case, out, res


@pytest.fixture
def folder(result, tmp_path):
    copy = tmp_path / "georef"
    shutil.copytree(result[1], copy)
    return copy


def test_loaded_review_reproduces_the_automatic_fit(result, folder) -> None:
    _case, _out, res = result
    review = load_review(folder)
    assert review.kind == "affine" and review.drop_outliers
    assert len(review.points) >= res["n_gcps"]  # the robust step may have dropped some
    assert len(review.pairs) == res["n_pairs"] and "icp_rms_px" in review.pairs[0]
    fit = review.fit()
    assert np.allclose(fit.matrix, np.array(res["transform"]["matrix"]), rtol=1e-9, atol=1e-6)
    assert fit.rmse_px == pytest.approx(res["rmse_px"], rel=1e-6)
    assert {r["role"] for r in review.table(fit)} <= {"control", "outlier"}


def test_points_off_and_rejected_pairs_become_check_points(folder) -> None:
    review = load_review(folder)
    review.points[0].enabled = False
    pair = review.points[-1].pair
    review.set_pair_rejected(pair)
    fit = review.fit()
    rows = review.table(fit)
    assert rows[0]["role"] == "check" and np.isfinite(rows[0]["residual_px"])
    assert all(r["role"] == "rejected" for r in rows if r["pair"] == pair)
    assert not fit.used[[k for k, r in enumerate(rows) if r["pair"] == pair]].any()
    rmse, n = review.check_rmse(fit)
    assert n >= 2 and rmse < 2 * fit.pixel_size  # correct points check well
    review.set_pair_rejected(pair, False)
    assert review.active()[-1]


def test_manual_point_outlier_and_transform_choice(result, folder) -> None:
    case = result[0]
    review = load_review(folder)
    truth = case["truth"]
    good = truth @ np.array([10.0, 20.0, 1.0])
    review.add_point((10.0, 20.0), (good[0], good[1]))
    bad = truth @ np.array([100.0, 100.0, 1.0])
    review.add_point((100.0, 100.0), (bad[0] + 40 * review.fit().pixel_size, bad[1]))
    rows = review.table()
    assert rows[-2]["manual"] and rows[-2]["role"] == "control"
    assert rows[-1]["role"] == "outlier" and rows[-1]["residual_px"] > 30
    review.drop_outliers = False
    assert review.table()[-1]["role"] == "control"
    review.drop_outliers = True
    for kind in ("projective", "poly2"):
        review.kind = kind
        fit = review.fit()
        assert corner_error(fit, truth, case["width"], case["height"]).max() < 1.0
    with pytest.raises(InputError, match="four finite numbers"):
        review.add_point((1.0, float("nan")), (0.0, 0.0))


def test_save_rewrites_products_and_keeps_the_automatic_result(result, folder) -> None:
    case = result[0]
    original = (folder / "report.json").read_text()
    review = load_review(folder)
    review.points[1].enabled = False
    review.kind = "projective"
    paths = save_review(review)
    assert json.loads((folder / "report_auto.json").read_text()) == json.loads(original)
    rep = json.loads(Path(paths["report"]).read_text())
    assert rep["transform"]["kind"] == "projective"
    assert rep["review"]["switched_off"] == [1] and rep["review"]["check_points"] >= 1
    lines = Path(paths["points"]).read_text().splitlines()
    assert lines[3].split(",")[4] == "0"  # point 1: enable column off for the Georeferencer
    assert "Reviewed by the operator" in (folder / "report.html").read_text()
    assert (folder / "residuals.png").is_file() and (folder / "overlay.png").is_file()
    with rasterio.open(paths["image"]) as src:
        assert src.crs.to_epsg() == 32632
    # the saved state loads again; a second save keeps the automatic report as it was
    again = load_review(folder)
    assert again.kind == "projective" and not again.points[1].enabled
    fit = again.fit()
    assert corner_error(fit, case["truth"], case["width"], case["height"]).max() < 0.5
    again.kind = "affine"
    save_review(again)
    assert json.loads((folder / "report_auto.json").read_text()) == json.loads(original)


def test_bad_states_write_nothing(folder, tmp_path) -> None:
    before = {p.name: p.read_bytes() for p in folder.iterdir() if p.is_file()}
    review = load_review(folder)
    for p in review.points[3:]:
        p.enabled = False
    review.kind = "poly2"
    with pytest.raises(InputError, match="at least 6 active"):
        save_review(review)
    assert {p.name: p.read_bytes() for p in folder.iterdir() if p.is_file()} == before
    with pytest.raises(InputError, match="holds no georeferencing result"):
        load_review(tmp_path)
