"""The main window's map: opening a project, the value under the cursor, Show on map, bad
rasters, the layer list (pytest-qt, offscreen)."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
pytest.importorskip("pytestqt")

import numpy as np
import rasterio
from rasterio.transform import from_origin
from shapely.geometry import Point

from photodem.algorithms.project.edits import EDIT_LAYERS
from photodem.plugin.qt import QtCore, QtGui, QtWidgets
from photodem.plugin.widgets.map_layers import LayerList

Qt = QtCore.Qt
EXPECTED_KINDS = [f"edit:{name}" for name in EDIT_LAYERS] + [
    "stereo_models", "footprints", "dsm", "dtm"]


@pytest.fixture(scope="module")
def tiny(tiny_block, tmp_path_factory) -> Path:
    """A copy of the tiny synthetic project for this module (its tests write into it)."""
    out = tmp_path_factory.mktemp("tiny") / "project"
    shutil.copytree(tiny_block, out)
    return out




def test_open_project_lists_the_expected_layers(window, tiny, qtbot):
    with qtbot.waitSignal(window.project_opened) as blocker:
        assert window.open_project(tiny)
    assert blocker.args == [str(tiny.resolve())]
    view = window.map_view
    assert [layer.kind for layer in view.layers()] == EXPECTED_KINDS
    assert window.project_root == tiny.resolve()
    assert window.edit_session is not None and not window.edit_session.read_only
    assert view.crs() == "EPSG:25832"
    assert window.crs_label.text() == "EPSG:25832"
    assert window.layer_list.list.count() == len(EXPECTED_KINDS)
    footprints = view.layer_by_kind("footprints")
    assert {f[2]["image"] for f in footprints.features()} == {
        "0101", "0102", "0103", "0201", "0202", "0203"}
    xmin, ymin, xmax, ymax = view.extent()  # zoomed to the block
    fx0, fy0, fx1, fy1 = footprints.bounds()
    assert xmin <= fx0 and xmax >= fx1 and ymin <= fy0 and ymax >= fy1
    assert (xmax - xmin) < 3 * (fx1 - fx0) or (ymax - ymin) < 3 * (fy1 - fy0)
    assert view.wait_rendered(10000)


def test_edits_are_drawn_from_the_session(window, tiny, qtbot):
    window.open_project(tiny)
    layer = window.map_view.layer_by_kind("edit:start_points")
    assert layer.features() == []
    x, y = window.map_view.view_state().to_map(100, 100)
    with qtbot.waitSignal(layer.changed):
        fid = window.edit_session.add("start_points", Point(x, y), {"height": 55.0})
    assert [f[0] for f in layer.features()] == [fid]
    window.edit_session.undo_stack.undo()
    assert layer.features() == []


def test_value_under_cursor_equals_the_raster_value(window, tiny, qtbot):
    window.open_project(tiny)
    view = window.map_view
    dsm = view.layer_by_kind("dsm")
    with rasterio.open(dsm.path) as src:
        band = src.read(1)
        row, col = src.height // 3, src.width // 2
        x, y = src.xy(row, col)
        expected = float(band[row, col])
    view.set_extent((x - 20, y - 20, x + 20, y + 20))
    point = view.view_state().to_pixel(x, y)
    moved = []
    view.cursor_moved.connect(lambda mx, my: moved.append((mx, my)))
    QtCore.QCoreApplication.sendEvent(view, QtGui.QMouseEvent(
        QtCore.QEvent.MouseMove, QtCore.QPointF(int(point.x()), int(point.y())), Qt.NoButton,
        Qt.NoButton, Qt.NoModifier))
    mx, my = moved[-1]
    with rasterio.open(dsm.path) as src:
        r, c = src.index(mx, my)
        at_cursor = float(src.read(1)[r, c])
    assert window.value_label.text() == f"{dsm.name}: {at_cursor:.2f} m"
    assert dsm.sample(x, y)[0] == pytest.approx(expected)
    assert window.coord_label.text() == f"{mx:.2f}, {my:.2f} m"
    assert window.scale_label.text().startswith("1:")


def test_show_on_map_adds_the_output_and_zooms_to_it(window, tiny, qtbot):
    dtm = tiny / "truth" / "dtm.tif"
    panel = window.run_panel
    panel.setEnabled(True)  # as after a run (it is off until an algorithm is chosen)
    panel.show_result({"dtm": str(dtm), "note": "x"})
    item = panel.result_view.topLevelItem(0)
    button = panel.result_view.itemWidget(item, 2).findChild(QtWidgets.QToolButton, "showOnMap")
    assert button is not None and button.text() == "Show on map"
    second = panel.result_view.topLevelItem(1)
    assert panel.result_view.itemWidget(second, 2) is None  # not a file
    with qtbot.waitSignal(panel.show_on_map):
        button.click()
    layer = window.map_view.layer_by_path(dtm)
    assert layer is not None and layer.kind == "dtm" and layer.visible
    assert window.map_view.crs()  # the raster's CRS became the map's
    layer.visible = False
    button.click()  # again: no second layer, visible again
    assert len(window.map_view.layers()) == 1 and layer.visible
    assert window.add_run_outputs([str(tiny / "truth" / "dsm.tif"), str(tiny / "project.toml")])
    assert [lay.kind for lay in window.map_view.layers()] == ["dsm", "dtm"]


def test_raster_without_crs_is_shown_alone_with_a_warning(window, tiny, tmp_path):
    window.open_project(tiny)
    plain = tmp_path / "scan.tif"
    with rasterio.open(plain, "w", driver="GTiff", width=40, height=30, count=1,
                       dtype="uint8") as dst:
        dst.write(np.arange(1200, dtype="uint8").reshape(1, 30, 40))
    layer = window.add_map_file(plain)
    assert layer is not None and window.map_view.layers() == [layer]
    assert not window.map_view.is_georeferenced()
    assert "no coordinate reference system" in window.statusBar().currentMessage()
    assert window.scale_label.text() == "pixels"
    # a georeferenced raster brings the map back to the project's CRS
    dsm = window.add_map_file(tiny / "truth" / "dsm.tif")
    assert dsm is not None and window.map_view.layers() == [dsm]
    assert window.map_view.crs() == "EPSG:25832"


def test_unreadable_raster_gives_a_message(window, tmp_path):
    bad = tmp_path / "broken.tif"
    bad.write_bytes(b"not a tiff at all")
    assert window.add_map_file(bad) is None
    assert "broken.tif" in window.statusBar().currentMessage()
    assert window.map_view.layers() == []


def test_not_a_project_and_moved_project(window, tiny, tmp_path):
    assert not window.open_project(tmp_path)
    assert "not a PhotoDEM project" in window.statusBar().currentMessage()
    moved = tmp_path / "moved"
    shutil.copytree(tiny, moved)
    assert window.open_project(moved)
    assert [layer.kind for layer in window.map_view.layers()] == EXPECTED_KINDS
    assert all(layer.path is None or Path(layer.path).resolve().is_relative_to(moved.resolve())
               for layer in window.map_view.layers())


def test_unsaved_edits_are_asked_about_on_close(window, tiny):
    window.open_project(tiny)
    session = window.edit_session
    session.add("start_points", Point(*window.map_view.view_state().to_map(5, 5)),
                {"height": 1.0})
    asked = []
    session.ask = lambda parent, s: asked.append(1) or "cancel"
    assert not window.close_project()
    assert asked and window.edit_session is session and window.map_view.layers()
    window.close()
    assert window.isVisible()  # cancelled: the window stays
    session.ask = lambda parent, s: "discard"


def test_layer_list_visibility_order_opacity(window, tiny, qtbot):
    window.open_project(tiny)
    view, panel = window.map_view, window.layer_list
    assert isinstance(panel, LayerList)
    first = view.layers()[0]
    item = panel.list.item(0)
    item.setCheckState(Qt.Unchecked)
    assert not first.visible
    first.visible = True
    assert panel.list.item(0).checkState() == Qt.Checked
    panel.list.setCurrentRow(0)
    panel.down_button.click()
    assert view.layers()[1] is first and panel.current_layer() is first
    panel.up_button.click()
    assert view.layers()[0] is first
    panel.opacity_slider.setValue(40)
    assert first.opacity == pytest.approx(0.4)
    dsm = view.layer_by_kind("dsm")
    panel.select_layer(dsm)
    assert panel.opacity_slider.value() == 100
    panel.zoom_to_current()
    assert view.extent()[0] <= dsm.bounds()[0]
    menu = panel.context_menu()
    assert [a.text() for a in menu.actions() if a.text()] == [
        "Zoom to layer", "Move up", "Move down", "Remove layer"]
    panel.remove_current()
    assert view.layer_by_kind("dsm") is None and panel.list.count() == len(EXPECTED_KINDS) - 1


def test_big_raster_without_overviews_offers_to_build_them(window, tmp_path):
    big = tmp_path / "big.tif"
    with rasterio.open(big, "w", driver="GTiff", width=2100, height=2100, count=1,
                       dtype="uint8", crs="EPSG:25832",
                       transform=from_origin(400000, 5700000, 1, 1)) as dst:
        dst.write(np.full((1, 2100, 2100), 7, dtype="uint8"))
    layer = window.add_map_file(big)
    assert layer is not None and layer.needs_overviews
    assert "Build overviews" in window.statusBar().currentMessage()
    window.layer_list.select_layer(layer)
    assert "Build overviews" in [a.text() for a in window.layer_list.context_menu().actions()]
    assert window.layer_list.build_overviews_current()
    assert not layer.needs_overviews and (tmp_path / "big.tif.ovr").is_file()
    assert "Build overviews" not in [a.text() for a in
                                     window.layer_list.context_menu().actions()]


def test_a_finished_run_puts_its_rasters_on_the_map(window, tiny):
    dsm = tiny / "truth" / "dsm.tif"
    window.run_panel.show_result({"dsm": str(dsm), "report": str(tiny / "project.toml")})
    window._on_run_finished("done", {"dsm": str(dsm)})
    assert [layer.path for layer in window.map_view.layers()] == [dsm.resolve()]
    window._on_run_finished("done", {"dsm": str(dsm)})  # not twice
    assert len(window.map_view.layers()) == 1


def test_corrupt_edits_are_shown_read_only(window, tiny, tmp_path):
    broken = tmp_path / "broken"
    shutil.copytree(tiny, broken)
    edits = broken / "edits.gpkg"
    edits.write_bytes(b"SQLite format 3\x00" + b"\x00" * 200)
    before = edits.read_bytes()
    assert window.open_project(broken)
    assert window.edit_session.read_only
    assert "edits" in window.statusBar().currentMessage()
    assert [layer.kind for layer in window.map_view.layers()] == EXPECTED_KINDS
    assert window.close_project()
    assert edits.read_bytes() == before  # nothing written


def test_gui_command_opens_a_project_given_on_the_command_line(tiny, qtbot):
    from photodem.plugin.app import main as app_main

    assert app_main.main(["photodem"], project=str(tiny / "project.toml")) == 0
    window = app_main._windows.pop()
    qtbot.addWidget(window)
    assert window.project_root == tiny.resolve()
    assert window.map_view.layer_by_kind("footprints") is not None
    window.edit_session.ask = lambda parent, session: "discard"
    window.map_view.clear_layers()


def test_gui_command_leaves_a_running_application_unnamed(tiny, qtbot):
    """The toolbox started in a running application has settings of its own; the application
    keeps its names, so later windows of it remember nothing (module order of the tests)."""
    from photodem.plugin.app import main as app_main
    from photodem.plugin.app.main_window import ToolboxWindow
    from photodem.plugin.widgets.parameter_form import SETTINGS_PROJECT

    app = QtCore.QCoreApplication
    before = (app.organizationName(), app.applicationName())
    assert app_main.main(["photodem"]) == 0
    window = app_main._windows.pop()
    qtbot.addWidget(window)
    assert (app.organizationName(), app.applicationName()) == before
    assert window.settings.organizationName() == app_main.ORGANIZATION
    window.settings.setValue(SETTINGS_PROJECT, str(tiny))
    later = ToolboxWindow(message_boxes=False)
    qtbot.addWidget(later)
    later.select_algorithm("match_model")
    assert later.settings is None and not later.form.project()


def test_added_raster_goes_under_the_vectors_and_becomes_the_surface(window, tiny, tmp_path):
    window.open_project(tiny)
    view, bar = window.map_view, window.editing_toolbar
    truth_dsm = str((tiny / "truth" / "dsm.tif").resolve())
    assert bar.surface_box.currentData() == truth_dsm  # the newest DSM, not the DTM
    newer = tmp_path / "dsm_new.tif"
    shutil.copy(tiny / "truth" / "dsm.tif", newer)
    layer = window.add_map_file(newer)
    kinds = [other.kind for other in view.layers()]
    index = view.layers().index(layer)
    vectors = [i for i, kind in enumerate(kinds)
               if kind.startswith("edit:") or kind in ("stereo_models", "footprints")]
    assert index == max(vectors) + 1  # above the other rasters, under every vector
    assert bar.surface_box.currentData() == str(newer.resolve())
    bar.set_surface(truth_dsm)  # the operator's choice stays when layers change
    window.add_map_file(tiny / "truth" / "dtm.tif")
    assert bar.surface_box.currentData() == truth_dsm
