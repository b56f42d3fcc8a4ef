"""The georeferencing review dialog (pytest-qt): tables, residual map, edits, save."""

from __future__ import annotations

import json
import os
import shutil

import pytest

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
pytest.importorskip("pytestqt")

from photodem.algorithms.processing import registry
from photodem.algorithms.synthetic.polygon_scene import georef_case
from photodem.plugin.app.main_window import ToolboxWindow
from photodem.plugin.qt import QtCore
from photodem.plugin.widgets.georef_review import GeorefReviewDialog

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def result_folder(tmp_path_factory):
    root = tmp_path_factory.mktemp("review_gui")
    case = georef_case(root / "case", seed=5)
    out = root / "auto"
    registry.run("georeference_polygons", {
        "image": case["image"], "reference": case["reference"], "output": str(out)})
    return out


@pytest.fixture
def folder(result_folder, tmp_path):
    copy = tmp_path / "georef"
    shutil.copytree(result_folder, copy)
    return copy


def _shown(qtbot, folder) -> GeorefReviewDialog:
    """The review dialog of ``folder``, shown and exposed (no message boxes)."""
    dialog = GeorefReviewDialog(folder, message_boxes=False)
    qtbot.addWidget(dialog)
    dialog.show()
    qtbot.waitExposed(dialog)
    return dialog


def test_review_edits_update_the_fit_and_save(qtbot, folder) -> None:
    dialog = _shown(qtbot, folder)
    n = dialog.point_table.rowCount()
    assert n == len(dialog.review.points) >= 50
    assert dialog.pair_table.rowCount() == len(dialog.review.pairs) >= 6
    assert "RMSE" in dialog.summary.text() and dialog.save_button.isEnabled()
    rmse0 = dialog.fit.rmse_px
    # a point off → a check point; a pair rejected → its points drop out of the fit
    dialog.set_point_enabled(0, False)
    assert dialog.point_table.item(0, 2).text() == "check point (off)"
    assert "check points" in dialog.summary.text() and "not saved" in dialog.summary.text()
    dialog.set_pair_rejected(0, True)
    pair0 = dialog.review.pairs[0]["pair"]
    assert all(r["role"] == "rejected" for r in dialog.rows if r["pair"] == pair0)
    # the transform and the outlier switch
    dialog.kind_combo.setCurrentIndex(dialog.kind_combo.findData("projective"))
    assert dialog.review.kind == "projective" and dialog.fit.kind == "projective"
    dialog.outlier_box.setChecked(False)
    assert not dialog.review.drop_outliers
    # a manual point, far off: the largest residual, switched off by the button
    p = dialog.review.points[5]
    dialog.add_point([p.image[0] + 3.0, p.image[1], p.map[0], p.map[1]])
    assert dialog.point_table.rowCount() == n + 1
    assert max(dialog.rows, key=lambda r: r["residual_px"])["id"] == n
    dialog.switch_off_worst()
    assert not dialog.review.points[n].enabled
    assert dialog.fit.rmse_px < 2 * rmse0
    dialog.grab().save("/tmp/photodem_georef_review.png")
    with qtbot.waitSignal(dialog.saved, timeout=60000):
        assert dialog.save()
    assert not dialog.dirty and (folder / "report_auto.json").is_file()
    rep = json.loads((folder / "report.json").read_text())
    assert rep["transform"]["kind"] == "projective"
    assert rep["review"]["manual"] == [n] and n in rep["review"]["switched_off"]
    assert rep["review"]["rejected_pairs"] == [pair0]


def test_too_few_points_disable_save(qtbot, folder) -> None:
    dialog = GeorefReviewDialog(folder, message_boxes=False)
    qtbot.addWidget(dialog)
    for k in range(2, dialog.point_table.rowCount()):
        dialog.review.points[k].enabled = False
    dialog.refresh()
    assert not dialog.save_button.isEnabled()
    assert "needs at least 3 active" in dialog.summary.text()


def test_toolbox_opens_the_review(qtbot, folder, tmp_path) -> None:
    window = ToolboxWindow(message_boxes=False)
    qtbot.addWidget(window)
    assert window.review_action.text()
    dialog = window.open_georef_review(str(folder))
    assert isinstance(dialog, GeorefReviewDialog)
    qtbot.wait(100)  # the residual map's first draw, before the dialog is deleted
    dialog.close()
    assert window.open_georef_review(str(tmp_path / "empty")) is None
    assert "no georeferencing result" in window.statusBar().currentMessage()


def _survey_file(dialog, path, shift_px: float = 3.0) -> int:
    """Six control points as independent check points, their map points ``shift_px`` pixels
    east; one more point outside the image. Returns the number of points inside."""
    pixel = dialog.fit.pixel_size
    lines = ["name;col;row;x;y"]
    for k, p in enumerate(dialog.review.points[:6]):
        lines.append(f"S{k};{p.image[0]};{p.image[1]};{p.map[0] + shift_px * pixel};{p.map[1]}")
    lines.append("far;-50;10;0;0")
    path.write_text("\n".join(lines) + "\n")
    return 6


def _import_through_file_dialog(qtbot, dialog, monkeypatch, path) -> None:
    from photodem.plugin.qt import QtCore, QtWidgets

    monkeypatch.setattr(QtWidgets.QFileDialog, "getOpenFileName",
                        lambda *args, **kwargs: (str(path), ""))
    qtbot.mouseClick(dialog.import_button, QtCore.Qt.LeftButton)


def test_import_independent_check_points(qtbot, folder, monkeypatch, tmp_path) -> None:
    dialog = _shown(qtbot, folder)
    n = dialog.point_table.rowCount()
    matrix = dialog.fit.matrix.copy()
    inside = _survey_file(dialog, tmp_path / "survey.csv")
    _import_through_file_dialog(qtbot, dialog, monkeypatch, tmp_path / "survey.csv")
    assert dialog.point_table.rowCount() == n + inside
    assert dialog.point_table.item(n, 1).text() == "S0"
    assert dialog.point_table.item(n, 2).text() == "check (independent)"
    assert not dialog.point_table.item(n, 0).flags() & QtCore.Qt.ItemIsUserCheckable
    assert (dialog.fit.matrix == matrix).all()  # never in the fit
    check = dialog.check
    assert check["count"] == inside and check["rmse_px"] == pytest.approx(3.0, abs=0.5)
    text = dialog.summary.text()
    assert f"{inside} independent check points: RMSE <b>{check['rmse_px']:.3f} px</b>" in text
    assert "Skipped check points outside the image (1): far." in text and dialog.dirty
    # their own colour and legend entry on the residual map
    assert "check (independent)" in [t.get_text() for t in dialog.axes.get_legend().get_texts()]
    dialog.point_table.selectRow(n + 2)  # a selected check point is drawn too
    assert len(dialog.axes.lines[-1].get_xdata()) == 1  # the yellow ring
    qtbot.wait(50)  # the summary's new height laid out
    dialog.grab().save("/tmp/photodem_georef_review_check.png")
    with qtbot.waitSignal(dialog.saved, timeout=60000):
        assert dialog.save()
    rep = json.loads((folder / "report.json").read_text())
    assert rep["review"]["independent_check"]["count"] == inside
    # a second session sees them again
    again = GeorefReviewDialog(folder, message_boxes=False)
    qtbot.addWidget(again)
    assert again.point_table.rowCount() == n + inside
    assert again.check["rmse_m"] == pytest.approx(check["rmse_m"], abs=1e-4)
    assert "outside the image (1): far" in again.summary.text()
    # a bad file: the message, the points imported before stay
    (tmp_path / "bad.csv").write_text("col,row,x,y\n1,2,drei,4\n")
    _import_through_file_dialog(qtbot, again, monkeypatch, tmp_path / "bad.csv")
    assert "line 2: x 'drei' is not a number" in again.summary.text()
    assert len(again.review.check_points) == inside


def test_import_check_points_in_german(qtbot, folder, monkeypatch, tmp_path, german,
                                       shots_dir) -> None:
    """The German dialog (the committed .ts compiled with lrelease, as the build does)."""
    german()
    dialog = _shown(qtbot, folder)
    assert dialog.import_button.text() == "Kontrollpunkte importieren…"
    n = dialog.point_table.rowCount()
    _survey_file(dialog, tmp_path / "survey.csv")
    _import_through_file_dialog(qtbot, dialog, monkeypatch, tmp_path / "survey.csv")
    assert dialog.point_table.item(n, 2).text() == "Kontrollpunkt (unabhängig)"
    assert "6 unabhängige Kontrollpunkte: RMSE <b>" in dialog.summary.text()
    assert "außerhalb des Bildes übersprungen (1): far." in dialog.summary.text()
    qtbot.wait(50)  # the summary's new height laid out
    dialog.grab().save(str(shots_dir / "photodem_georef_review_check_de.png"))
    dialog.dirty = False


def test_review_shows_the_evidence(qtbot, folder) -> None:
    """The automatic result's evidence above the tables: verified, then marked UNVERIFIED."""
    dialog = _shown(qtbot, folder)
    text = dialog.evidence_label.text()
    assert "Verified: yes" in text and "% of the image, 4 of 4 quadrants" in text
    assert "corners disagree by" in text and "edge peak ratio" in text
    dialog.grab().save("/tmp/photodem_georef_review_evidence.png")
    rep = json.loads((folder / "report.json").read_text())
    rep["verified"] = False
    rep["evidence"]["reasons"] = ["the corners disagree by 5.3 px between halves"]
    (folder / "report.json").write_text(json.dumps(rep))
    marked = GeorefReviewDialog(folder, message_boxes=False)
    qtbot.addWidget(marked)
    assert "UNVERIFIED</b> — the corners disagree by 5.3 px" in marked.evidence_label.text()


def _as_keypoint_result(folder) -> int:
    """The folder's report turned into a keypoint stage's: its points without object pairs
    (``pair = -1``), no pairs. Returns the number of points."""
    rep = json.loads((folder / "report.json").read_text())
    rep["stage"] = "keypoints"
    for g in rep["gcps"]:
        g["pair"] = -1
    rep["pairs"], rep["icp"] = [], []
    (folder / "report.json").write_text(json.dumps(rep))
    return len(rep["gcps"])


def test_keypoint_points_are_not_manual(qtbot, folder) -> None:
    """Control points of the keypoint stage (no object pair) are labelled as keypoints, with
    their own colour and legend entry; only points the operator adds are manual, also after
    saving and opening again."""
    from photodem.plugin.widgets.georef_review import STAGE_POINT_COLOUR

    n = _as_keypoint_result(folder)
    dialog = _shown(qtbot, folder)
    assert all(not p.manual and p.origin == "keypoints" for p in dialog.review.points)
    assert {dialog.point_table.item(r, 3).text() for r in range(n)} == {"keypoints"}
    legend = [t.get_text() for t in dialog.axes.get_legend().get_texts()]
    assert "control point (keypoints)" in legend and "control point" not in legend
    assert any(line.get_color() == STAGE_POINT_COLOUR for line in dialog.axes.lines)
    p = dialog.review.points[3]
    dialog.add_point([p.image[0] + 0.2, p.image[1], p.map[0], p.map[1]])
    assert dialog.point_table.item(n, 3).text() == "manual"
    dialog.grab().save("/tmp/photodem_georef_review_keypoints.png")
    with qtbot.waitSignal(dialog.saved, timeout=60000):
        assert dialog.save()
    rep = json.loads((folder / "report.json").read_text())
    assert rep["review"]["manual"] == [n]
    again = GeorefReviewDialog(folder, message_boxes=False)
    qtbot.addWidget(again)
    assert [p.origin for p in again.review.points] == ["keypoints"] * n + ["manual"]
    assert again.point_table.item(0, 3).text() == "keypoints"


def test_unverified_reasons_go_through_the_translation(monkeypatch) -> None:
    """The gate's reasons are built from their keys and figures with translatable format
    strings; a report without the keys shows the core's sentences."""
    from photodem.algorithms.georef import evidence
    from photodem.plugin.widgets import georef_review

    items = [["spread", {"hull_pct": 13.2, "min_hull_pct": 25.0, "quadrants": 1,
                         "min_quadrants": 2}],
             ["local_offsets", {"quadrants": [[1, 2.26]], "max_px": 1.5}]]
    ev = {"reasons": [evidence.reason_text(k, v) for k, v in items], "reason_items": items,
          "hull_share": 0.132, "quadrants": 1, "independent_points": True}
    report = {"verified": False, "evidence": ev}
    english = georef_review.evidence_html(report)
    assert "UNVERIFIED</b> — the control points cover 13 % of the image (needs ≥ 25 %)" in english
    assert "in the top right quadrant (2.3 px) (at most 1.5 px)" in english
    monkeypatch.setattr(georef_review, "tr", lambda text: f"«{text}»")
    marked = georef_review.evidence_html(report)
    assert "«the control points cover 13 % of the image (needs ≥ 25 %) and 1 of 4" in marked
    assert "the «top right quadrant (2.3 px)» (at most 1.5 px)»" in marked
    old = georef_review.evidence_html({"verified": False, "evidence": {
        "reasons": ["the corners disagree by 5.3 px between halves"]}})
    assert "</b> — the corners disagree by 5.3 px between halves" in old


def test_every_reason_of_the_gate_has_a_translatable_text() -> None:
    """The dialog knows every reason key of the core, with the same figures."""
    import string

    from photodem.algorithms.georef import evidence
    from photodem.plugin.widgets import georef_review

    ours = georef_review.reason_texts()
    assert set(ours) == set(evidence.REASON_TEXTS)
    for key, text in evidence.REASON_TEXTS.items():
        fields = {f for _, f, _, _ in string.Formatter().parse(text) if f}
        assert fields == {f for _, f, _, _ in string.Formatter().parse(ours[key]) if f}, key


def test_area_result_on_footprints_shows_its_reason_in_both_languages(qtbot, folder, german,
                                                                      shots_dir) -> None:
    """An area-stage result against building footprints written unverified: the dialog gives
    the gate's reason, in English and in German (screenshots of both)."""
    from photodem.algorithms.georef import evidence

    rep = json.loads((folder / "report.json").read_text())
    rep["verified"] = False
    rep["evidence"]["reason_items"] = [["buildings_area", {}]]
    rep["evidence"]["reasons"] = [evidence.reason_text("buildings_area", {})]
    (folder / "report.json").write_text(json.dumps(rep))
    dialog = _shown(qtbot, folder)
    assert "building footprints cannot confirm a result" in dialog.evidence_label.text()
    dialog.grab().save(str(shots_dir / "photodem_georef_review_buildings_area.png"))
    german()
    german_dialog = _shown(qtbot, folder)
    assert "Gebäudegrundrisse können ein Ergebnis" in german_dialog.evidence_label.text()
    german_dialog.grab().save(str(shots_dir / "photodem_georef_review_buildings_area_de.png"))
    german_dialog.dirty = False
