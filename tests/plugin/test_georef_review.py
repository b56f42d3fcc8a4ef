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
from photodem.plugin.widgets.georef_review import GeorefReviewDialog


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


def test_review_edits_update_the_fit_and_save(qtbot, folder) -> None:
    dialog = GeorefReviewDialog(folder, message_boxes=False)
    qtbot.addWidget(dialog)
    dialog.show()
    qtbot.waitExposed(dialog)
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
