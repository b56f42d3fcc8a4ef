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
from photodem.algorithms.georef.products import (
    image_residuals,
    points_source,
    residual_scale,
    skipped_note,
)
from photodem.algorithms.georef.review import (
    Review,
    ReviewPoint,
    load_review,
    read_check_points,
    save_review,
)
from photodem.algorithms.processing import registry
from photodem.algorithms.synthetic.polygon_scene import georef_case

pytestmark = pytest.mark.slow


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


# -- independent check points from a file ---------------------------------------------------------
#: Image → map of the closed-form cases: 30° rotation, 2 map units per pixel, y up.
_C, _S = np.cos(np.radians(30)), np.sin(np.radians(30))
AFFINE = np.array([[2 * _C, -2 * _S, 1000.0], [-2 * _S, -2 * _C, 5000.0], [0.0, 0.0, 1.0]])
CHECK_IMAGE = [(10.0, 20.0), (50.0, 80.0), (90.0, 30.0), (70.0, 70.0)]


def _map(col: float, row: float) -> tuple:
    x, y, _ = AFFINE @ np.array([col, row, 1.0])
    return float(x), float(y)


def _exact_review(tmp_path) -> Review:
    """Control points exactly on AFFINE, in a 100 × 100 image."""
    import pyproj

    points = [ReviewPoint((c, r), _map(c, r), pair=0)
              for c in (0.0, 33.0, 66.0, 99.0) for r in (0.0, 50.0, 99.0)]
    return Review(folder=tmp_path, name="exact", crs_wkt=pyproj.CRS.from_epsg(32632).to_wkt(),
                  points=points, drop_outliers=False,
                  report={"image": {"width": 100, "height": 100}})


def _points_text(sep: str, header: str, convention: str = "centre") -> str:
    """The check points of CHECK_IMAGE in a file of the given layout."""
    lines = [header]
    for k, (c, r) in enumerate(CHECK_IMAGE, start=1):
        x, y = _map(c, r)
        if convention == "qgis":
            sx, sy = points_source(c, r)
        elif convention == "gdal":
            sx, sy = c + 0.5, r + 0.5
        else:
            sx, sy = c, r
        fields = {"id": f"P{k}", "col": sx, "row": sy, "x": x, "y": y}
        lines.append(sep.join(str(fields[f]) for f in header.lower().split("|")))
    return "\n".join(lines).replace("|", sep) + "\n"


@pytest.mark.parametrize("sep, header, convention", [
    (",", "col|row|x|y", "centre"),
    (";", "id|col|row|x|y", "centre"),
    ("\t", "id|col|row|x|y", "centre"),
    ("  ", "col|row|x|y", "centre"),
    (",", "id|col|row|x|y", "gdal"),  # relabelled below as pixel,line
    (",", "id|col|row|x|y", "qgis"),
])
def test_check_point_files_in_every_layout(tmp_path, sep, header, convention) -> None:
    text = _points_text(sep, header, convention)
    if convention != "centre":  # corner-based: the QGIS/GDAL column names
        text = text.replace("col", "pixel", 1).replace("row", "line", 1).replace(
            f"{sep}x{sep}y", f"{sep}mapX{sep}mapY", 1)
    path = tmp_path / "check.txt"
    path.write_text(text)
    points, skipped = read_check_points(path, 100, 100)
    assert not skipped and len(points) == len(CHECK_IMAGE)
    assert np.allclose([p.image for p in points], CHECK_IMAGE, atol=1e-9)
    assert np.allclose([p.map for p in points], [_map(*ij) for ij in CHECK_IMAGE])
    assert [p.id for p in points] == ([f"P{k}" for k in range(1, 5)] if "id" in header
                                      else ["2", "3", "4", "5"])  # else: the line numbers


def test_qgis_points_file_reads_back_to_the_control_points(folder) -> None:
    """The folder's own .points file (written by this project) gives the image coordinates
    of the control points again; as check points their residuals are the fit's."""
    review = load_review(folder)
    review.import_check_points(folder / f"{review.name}.points")
    assert len(review.check_points) == len(review.points)
    assert np.allclose([p.image for p in review.check_points], review.image_xy(), atol=1e-5)
    fit = review.fit()
    check = review.independent_check(fit)
    res = fit.extras["all_residuals_map"]
    assert check["rmse_m"] == pytest.approx(np.sqrt(np.mean(np.sum(res * res, axis=1))),
                                            abs=1e-5)
    assert check["rmse_px"] == pytest.approx(check["rmse_m"] / fit.pixel_size)


def test_decimal_commas_with_semicolons(tmp_path) -> None:
    path = tmp_path / "tabelle.csv"
    path.write_text("Nr;Spalte;Zeile;Rechtswert;Hochwert\n7;12,5;40;500123,25;5400456,5\n")
    (point,), _ = read_check_points(path)
    assert point.id == "7" and point.image == (12.5, 40.0) and point.map == (500123.25, 5400456.5)


def test_a_points_file_in_another_crs_is_refused(tmp_path) -> None:
    review = _exact_review(tmp_path)
    path = tmp_path / "other.points"
    text = _points_text(",", "id|col|row|x|y", "qgis").replace("col", "sourceX", 1).replace(
        "row", "sourceY", 1).replace(",x,y", ",mapX,mapY", 1)
    path.write_text("#CRS: EPSG:25833\n" + text)
    with pytest.raises(InputError, match="another CRS"):
        review.import_check_points(path)
    path.write_text("#CRS: EPSG:32632\n" + text)
    assert not review.import_check_points(path) and len(review.check_points) == 4


@pytest.mark.parametrize("text, message", [
    (None, "does not exist"),
    ("# only a comment\n\n", "holds no check points"),
    ("col,row,x,y\n", "has a header but no check points"),
    ("1,2,3,4\n5,6,7,8\n", "has no header line"),
    ("col,row,height\n1,2,3\n", "lacks map x, map y"),
    ("x,y\n1,2\n", "lacks image column, image row"),
    ("col;row;x;y\n1;2;3;4\n1;zwei;3;4\n", "line 3: row 'zwei' is not a number"),
    ("col,row,x,y\n1,2,3\n", "line 2: y '' is not a number"),
    ("pixel,line,mapX,mapY\n1,-2,3,4\n1,2,3,4\n", "mixes positive and negative"),
    ("col,row,x,y\n-5,2,3,4\n200,2,3,4\n", "None of the 2 check points"),
])
def test_bad_check_point_files_say_what_is_wrong(tmp_path, text, message) -> None:
    path = tmp_path / "check.csv"
    if text is not None:
        path.write_text(text)
    with pytest.raises(InputError, match=message) as info:
        read_check_points(path, 100, 100)
    assert "\n" not in str(info.value)


def test_points_outside_the_image_are_skipped_with_a_warning(tmp_path) -> None:
    path = tmp_path / "check.csv"
    path.write_text("id,col,row,x,y\na,-0.5,0,1,2\nb,-0.6,0,1,2\nc,99.5,99.5,1,2\n"
                    "d,10,100,1,2\n")
    points, skipped = read_check_points(path, 100, 100)
    assert [p.id for p in points] == ["a", "c"]  # the pixel edges belong to the image
    assert skipped == ["b", "d"]
    assert skipped_note(skipped) == "Skipped check points outside the image (2): b, d."


def test_independent_check_rmse_closed_form(tmp_path) -> None:
    """Check points displaced by known map offsets: residuals 5, 5, 1, 1 map units →
    RMSE √13 map units = √13 / 2 px (2 map units per pixel); the fit is untouched."""
    review = _exact_review(tmp_path)
    offsets = [(3.0, 4.0), (-4.0, 3.0), (0.0, -1.0), (1.0, 0.0)]
    path = tmp_path / "check.csv"
    path.write_text("id,col,row,x,y\n" + "".join(
        f"P{k},{c},{r},{_map(c, r)[0] + dx},{_map(c, r)[1] + dy}\n"
        for k, ((c, r), (dx, dy)) in enumerate(zip(CHECK_IMAGE, offsets))))
    before = review.fit()
    assert review.import_check_points(path) == []
    fit = review.fit()
    assert np.allclose(fit.matrix, before.matrix) and np.allclose(fit.matrix, AFFINE)
    assert fit.pixel_size == pytest.approx(2.0)
    check = review.independent_check(fit)
    assert check["count"] == 4
    assert check["rmse_m"] == pytest.approx(np.sqrt(13.0), abs=1e-9)
    assert check["rmse_px"] == pytest.approx(np.sqrt(13.0) / 2, abs=1e-9)
    # residual = fitted − measured = −offset, in map units and in pixels
    for p, (dx, dy) in zip(check["points"], offsets):
        assert (p["dx_map"], p["dy_map"]) == pytest.approx((-dx, -dy), abs=1e-4)
        assert p["residual_px"] == pytest.approx(np.hypot(dx, dy) / 2, abs=1e-5)
    inverse = np.linalg.inv(AFFINE[:2, :2])  # the residual drawn in the image
    assert (check["points"][0]["dcol"], check["points"][0]["drow"]) == pytest.approx(
        tuple(inverse @ [-3.0, -4.0]), abs=1e-9)
    assert review.check_rmse(fit)[1] == 0  # not the check points the operator took out


def test_independent_check_points_survive_save_and_load(result, folder, tmp_path) -> None:
    truth = result[0]["truth"]
    review = load_review(folder)
    pixel = review.fit().pixel_size
    cols = np.array([20.0, 150.0, 300.0])
    rows = np.array([40.0, 200.0, 120.0])
    mapped = (truth @ np.vstack([cols, rows, np.ones(3)]))[:2].T
    path = tmp_path / "survey.csv"
    # every point 2 pixels east of its true place: RMSE 2 px
    path.write_text("name\tcol\trow\teasting\tnorthing\n" + "".join(
        f"S{k}\t{c}\t{r}\t{x + 2 * pixel}\t{y}\n"
        for k, (c, r, (x, y)) in enumerate(zip(cols, rows, mapped))))
    review.import_check_points(path)
    paths = save_review(review)
    rep = json.loads(Path(paths["report"]).read_text())
    check = rep["review"]["independent_check"]
    assert check["count"] == 3 and check["file"] == str(path.resolve())
    assert check["rmse_px"] == pytest.approx(2.0, abs=0.3)  # plus the fit's own error
    assert [p["id"] for p in check["points"]] == ["S0", "S1", "S2"]
    html = (folder / "report.html").read_text()
    assert "Independent check points" in html and "survey.csv" in html
    # residuals.png draws them (tab:purple triangles and vectors)
    from matplotlib.image import imread

    rgb = imread(folder / "residuals.png")[..., :3]
    purple = np.all(np.abs(rgb - np.array([0x94, 0x67, 0xBD]) / 255) < 0.05, axis=-1)
    assert purple.sum() > 20
    again = load_review(folder)
    assert again.check_file == str(path.resolve())
    assert [(p.id, p.image) for p in again.check_points] == \
        [(p.id, p.image) for p in review.check_points]
    assert again.independent_check(again.fit())["rmse_m"] == pytest.approx(check["rmse_m"],
                                                                           abs=1e-4)


@pytest.mark.parametrize("longest, extent, share, expected", [
    (0.5, 1000.0, 0.1, 200.0),   # 100 / 0.5 = 200 exactly
    (0.3, 1000.0, 0.1, 200.0),   # 333 → the round 200 below it
    (3.0, 1000.0, 0.08, 20.0),   # 26.7 → 20
    (40.0, 100.0, 0.1, 0.2),     # 0.25 → 0.2: long residuals are shortened
    (0.0, 1000.0, 0.1, 1.0),     # nothing to scale
])
def test_residual_scale_is_round_and_never_too_long(longest, extent, share, expected) -> None:
    res = np.array([[0.0, longest], [longest / 2, 0.0]])
    k = residual_scale(res, extent, share)
    assert k == pytest.approx(expected)
    if longest:
        assert k * longest <= share * extent + 1e-9


def test_image_residuals_closed_form_for_an_affine() -> None:
    # the map residual taken into the image is A⁻¹·res for x = A·(col, row) + t
    from photodem.algorithms.georef.fit import fit_transform

    A = np.array([[2.0, 0.3], [-0.4, -1.5]])
    img = np.array([[0, 0], [100, 0], [0, 80], [100, 80], [50, 40]], float)
    fit = fit_transform(img, img @ A.T + [500.0, 900.0], "affine")
    res_map = np.array([[1.0, 0.0], [0.0, 1.0], [0.5, -0.5], [2.0, 1.0], [0.0, 0.0]])
    np.testing.assert_allclose(image_residuals(fit, img, res_map),
                               res_map @ np.linalg.inv(A).T, atol=1e-9)
