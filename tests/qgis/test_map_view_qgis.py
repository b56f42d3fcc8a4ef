"""Tier B: the standalone map (view, vector and raster layers, layer list, main window with a
project) works with Debian's Qt/PyQt and libraries (shapely 1.8, fiona 1.9) under QGIS 3.22's
Python (issue 21)."""

from __future__ import annotations

from pathlib import Path

import pytest

pytestmark = pytest.mark.qgis


def test_map_view_draws_and_navigates(qgis_app, tmp_path: Path) -> None:
    from shapely.geometry import Point, Polygon

    from photodem.plugin.qt import BINDING, QtCore, QtGui
    from photodem.plugin.widgets.map_layer import MapTool
    from photodem.plugin.widgets.map_layers import LayerList
    from photodem.plugin.widgets.map_view import MapView

    assert BINDING == "qgis.PyQt"
    view = MapView()
    view.resize(400, 300)
    view.show()
    view.set_crs("EPSG:25832")
    data = [(1, Point(500100, 5400100), {"name": "SP1"}),
            (2, Polygon([(500300, 5400200), (500380, 5400200), (500380, 5400280)]),
             {"action": "exclude"})]
    layer = view.add_vector(lambda: data, "edit:exclusion_areas")
    panel = LayerList(view)
    assert panel.list.count() == 1
    view.zoom_full()
    image = view.grab().toImage()
    assert image.width() == 400
    view.grab()  # value_at's tolerance follows the last drawing
    assert layer.value_at(500100, 5400100) == "SP1"
    pos = QtCore.QPointF(100.0, 80.0)
    before = view.view_state().to_map(pos.x(), pos.y())
    wheel = QtGui.QWheelEvent(pos, view.mapToGlobal(pos.toPoint()), QtCore.QPoint(0, 0),
                              QtCore.QPoint(0, 120), QtCore.Qt.NoButton, QtCore.Qt.NoModifier,
                              QtCore.Qt.NoScrollPhase, False)
    QtCore.QCoreApplication.sendEvent(view, wheel)
    assert view.view_state().to_map(pos.x(), pos.y()) == pytest.approx(before)

    class Clicks(MapTool):
        def __init__(self) -> None:
            super().__init__()
            self.points: list = []

        def press(self, event, x, y):
            self.points.append((x, y))
            return True

    tool = Clicks()
    view.set_tool(tool)
    press = QtGui.QMouseEvent(QtCore.QEvent.MouseButtonPress, QtCore.QPointF(20, 30),
                              QtCore.Qt.LeftButton, QtCore.Qt.LeftButton, QtCore.Qt.NoModifier)
    QtCore.QCoreApplication.sendEvent(view, press)
    assert tool.points == [pytest.approx(view.view_state().to_map(20.5, 30.5))]
    view.close()


def test_main_window_opens_the_tiny_project(qgis_app, tmp_path: Path) -> None:
    import rasterio

    from photodem.algorithms.processing import registry
    from photodem.algorithms.project.edits import EDIT_LAYERS
    from photodem.plugin.app.main_window import ToolboxWindow

    root = tmp_path / "tiny"
    registry.run("synthetic_block", {"output": str(root), "size": "tiny"})
    window = ToolboxWindow(message_boxes=False)
    window.show()
    assert window.open_project(root)
    kinds = [layer.kind for layer in window.map_view.layers()]
    assert kinds == [f"edit:{n}" for n in EDIT_LAYERS] + ["stereo_models", "footprints",
                                                           "dsm", "dtm"]
    assert window.map_view.wait_rendered(15000)
    dsm = window.map_view.layer_by_kind("dsm")
    with rasterio.open(dsm.path) as src:
        x, y = src.xy(src.height // 2, src.width // 2)
        value = float(src.read(1)[src.height // 2, src.width // 2])
    assert window.value_under(x, y) == f"{dsm.name}: {value:.2f} m"
    window.grab().save(str(tmp_path / "window.png"))
    window.edit_session.ask = lambda parent, session: "discard"
    window.close()
