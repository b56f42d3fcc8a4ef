"""Run from the map in the standalone window: the context menu of the stereo models under a
right click, and the project opened on the map in the toolbox's forms (pytest-qt, offscreen)."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path
from typing import List

import pytest

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
pytest.importorskip("pytestqt")

from photodem.plugin.app.main_window import ToolboxWindow
from photodem.plugin.qt import QtCore, QtWidgets

Qt = QtCore.Qt
ENTRIES = ["Match this model…", "Epipolar pair", "Filter its DSM…"]


@pytest.fixture(scope="module")
def tiny(tiny_block, tmp_path_factory) -> Path:
    """A copy of the tiny synthetic project for this module (its tests write into it)."""
    out = tmp_path_factory.mktemp("tiny") / "project"
    shutil.copytree(tiny_block, out)
    return out




@pytest.fixture
def menus(monkeypatch) -> List[QtWidgets.QMenu]:
    """The menus opened by ``exec_`` (recorded, not shown: a test can't answer them)."""
    opened: List[QtWidgets.QMenu] = []
    monkeypatch.setattr(QtWidgets.QMenu, "exec_", lambda self, *a: opened.append(self))
    return opened


def _model_centroid(window, name: str):
    layer = window.map_view.layer_by_kind("stereo_models")
    for _fid, geometry, attributes in layer.features():
        if attributes["name"] == name:
            return geometry.centroid
    raise AssertionError(name)


def _right_press(qtbot, window, x: float, y: float) -> None:
    """A right press on the pixel of the map point (x, y)."""
    at = window.map_view.view_state().to_pixel(x, y)
    qtbot.mousePress(window.map_view, Qt.RightButton, pos=QtCore.QPoint(int(at.x()), int(at.y())))


def _entry(menu: QtWidgets.QMenu, model: str, text: str) -> QtWidgets.QAction:
    """The action ``text`` in the sub-menu of ``model``."""
    for action in menu.actions():
        sub = action.menu()
        if sub is not None and sub.title() == f"Stereo model {model}":
            return next(a for a in sub.actions() if a.text() == text)
    raise AssertionError(f"{model} not in {[a.text() for a in menu.actions()]}")


def _values(window) -> dict:
    return window.form.values()


def _open(qtbot, window, tiny, model: str, menus) -> QtWidgets.QMenu:
    window.open_project(tiny)
    c = _model_centroid(window, model)
    _right_press(qtbot, window, c.x, c.y)
    assert menus, "no menu opened"
    return menus[-1]


def test_right_press_lists_the_models_under_it(window, tiny, menus, qtbot):
    menu = _open(qtbot, window, tiny, "0101_0102", menus)
    titles = [a.text() for a in menu.actions()]
    assert "Stereo model 0101_0102" in titles
    sub = next(a.menu() for a in menu.actions() if a.text() == "Stereo model 0101_0102")
    assert [a.text() for a in sub.actions()] == ENTRIES
    # where two models overlap, both are offered
    layer = window.map_view.layer_by_kind("stereo_models")
    shapes = {a["name"]: g for _f, g, a in layer.features()}
    inside = shapes["0101_0102"].intersection(shapes["0102_0103"]).representative_point()
    _right_press(qtbot, window, inside.x, inside.y)
    titles = [a.text() for a in menus[-1].actions()]
    assert {"Stereo model 0101_0102", "Stereo model 0102_0103"} <= set(titles), titles
    # outside the block: no menu
    count = len(menus)
    xmin, ymin, _xmax, _ymax = window.map_view.extent()
    _right_press(qtbot, window, xmin + 1, ymin + 1)
    assert len(menus) == count


def test_a_tool_using_right_presses_gets_them(window, tiny, menus, qtbot):
    from photodem.plugin.widgets.map_layer import MapTool

    class Grabbing(MapTool):
        def press(self, event, x, y):
            return True

    window.open_project(tiny)
    window.map_view.set_tool(Grabbing(window.map_view))
    c = _model_centroid(window, "0101_0102")
    _right_press(qtbot, window, c.x, c.y)
    assert menus == []


def test_match_this_model_fills_the_form(window, tiny, menus, qtbot):
    menu = _open(qtbot, window, tiny, "0201_0202", menus)
    _entry(menu, "0201_0202", "Match this model…").trigger()
    assert window.algorithm.id == "match_model"
    values = _values(window)
    assert values["project"] == str(tiny.resolve())
    assert values["model"] == "0201_0202"
    assert values["output"] == str(tiny.resolve() / "products" / "dsm" / "0201_0202")
    combo = window.form.editor("model")
    assert [combo.itemText(i) for i in range(combo.count())] == [
        "0101_0102", "0102_0103", "0201_0202", "0202_0203"]
    assert not window.run_panel.is_running()  # it does not run


def test_epipolar_pair_runs_and_keeps_the_project_on_the_map(window, tiny, menus, qtbot):
    menu = _open(qtbot, window, tiny, "0102_0103", menus)
    _entry(menu, "0102_0103", "Epipolar pair").trigger()
    assert window.algorithm.id == "epipolar_pair"
    qtbot.waitUntil(lambda: window.run_panel.status in ("done", "failed"), timeout=120000)
    assert window.run_panel.status == "done", window.run_panel.result
    qtbot.waitUntil(lambda: not window.run_panel.is_running(), timeout=10000)
    folder = tiny.resolve() / "products" / "epipolar" / "0102_0103"
    assert (folder / "left.tif").is_file()
    assert str(folder / "left.tif") in window.run_panel.output_paths()  # in the results
    # the epipolar images have no CRS: they do not take the project off the map
    assert window.map_view.layer_by_kind("stereo_models") is not None
    assert window.map_view.crs() == "EPSG:25832"
    assert "left.tif" in window.statusBar().currentMessage()


def test_filter_its_dsm_needs_a_dsm_then_fills_the_form(window, tiny, menus, qtbot):
    model = "0202_0203"
    menu = _open(qtbot, window, tiny, model, menus)
    before = window.algorithm
    _entry(menu, model, "Filter its DSM…").trigger()
    assert window.algorithm is before  # no form shown
    text = window.statusBar().currentMessage()
    assert "no DSM yet" in text and model in text
    dsm = tiny.resolve() / "products" / "dsm" / model / "dsm.tif"
    dsm.parent.mkdir(parents=True)
    shutil.copy(tiny / "truth" / "dsm.tif", dsm)
    try:
        _entry(menu, model, "Filter its DSM…").trigger()
        assert window.algorithm.id == "filter_lowpass"
        values = _values(window)
        assert values["input"] == str(dsm)
        assert values["project"] == str(tiny.resolve())
        assert values["output"] == str(tiny.resolve() / "products" / "dtm" / model)
    finally:
        shutil.rmtree(dsm.parent)


def test_opening_a_project_fills_the_forms(window, tiny, tmp_path):
    window.select_algorithm("match_model")
    assert not window.form.project()
    window.open_project(tiny)
    assert window.form.project() == str(tiny.resolve())
    combo = window.form.editor("model")
    assert combo.count() == 4  # the models of the project are listed
    window.select_algorithm("epipolar_pair")  # a later form gets it too
    assert window.form.project() == str(tiny.resolve())
    # the operator's typed value stays when the form changes
    window.form.set_values({"project": str(tmp_path)})
    window.select_algorithm("match_model")
    assert window.form.project() == str(tmp_path)


def test_the_maps_project_wins_over_the_remembered_one(tiny, tmp_path, qtbot):
    settings = QtCore.QSettings(str(tmp_path / "settings.ini"), QtCore.QSettings.IniFormat)
    settings.setValue("PhotoDEM/project", str(tmp_path / "elsewhere"))
    settings.setValue("PhotoDEM/params/match_model", json.dumps(
        {"project": "/remembered", "model": "0909_0910", "output": "/remembered/out"}))
    settings.setValue("PhotoDEM/params/epipolar_pair", json.dumps(
        {"project": str(tiny / "project.toml"), "model": "0102_0103", "scale": 0.5}))
    w = ToolboxWindow(message_boxes=False, settings=settings)
    qtbot.addWidget(w)
    try:
        w.open_project(tiny)
        w.select_algorithm("match_model")
        assert w.form.project() == str(tiny.resolve())
        values = w.form.values()  # what was remembered for the other project is gone
        assert values["model"] == "0101_0102" and "output" not in values
        w.form = None  # no carrying over: the remembered values of the same project stay
        w.select_algorithm("epipolar_pair")
        assert w.form.values()["model"] == "0102_0103" and w.form.values()["scale"] == 0.5
    finally:
        w.edit_session.ask = lambda parent, session: "discard"
        w.map_view.clear_layers()


def test_a_matched_dsm_appears_on_the_map_and_in_the_surfaces(window, tiny, menus, qtbot):
    model = "0101_0102"
    menu = _open(qtbot, window, tiny, model, menus)
    _entry(menu, model, "Match this model…").trigger()
    window.run_current()
    qtbot.waitUntil(lambda: window.run_panel.status in ("done", "failed"), timeout=300000)
    assert window.run_panel.status == "done", window.run_panel.result
    qtbot.waitUntil(lambda: not window.run_panel.is_running(), timeout=10000)
    dsm = tiny.resolve() / "products" / "dsm" / model / "dsm.tif"
    try:
        assert dsm.is_file()
        assert window.map_view.layer_by_path(dsm) is not None
        box = window.editing_toolbar.surface_box
        assert str(dsm) in [box.itemData(i) for i in range(box.count())]
    finally:
        shutil.rmtree(dsm.parent)
