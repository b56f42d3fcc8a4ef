"""The standalone map view: transforms, navigation, tools, vector layers (pytest-qt)."""

from __future__ import annotations

import os

import pytest

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
pytest.importorskip("pytestqt")

from shapely.geometry import LineString, Point, Polygon

from photodem.algorithms.errors import InputError
from photodem.plugin.qt import QtCore, QtGui
from photodem.plugin.widgets.map_layer import MapLayer, MapTool
from photodem.plugin.widgets.map_styles import DEFAULT_STYLE, STYLES_DIR, parse_qml, style_for_kind
from photodem.plugin.widgets.map_vectors import VectorLayer
from photodem.plugin.widgets.map_view import MapView, length_text, nice_length

Qt = QtCore.Qt
EXTENT = (500000.0, 5400000.0, 500400.0, 5400300.0)


@pytest.fixture
def view(qtbot):
    v = MapView()
    v.resize(400, 300)
    qtbot.addWidget(v)
    v.show()
    qtbot.waitExposed(v)
    v.set_crs("EPSG:25832")
    v.set_extent(EXTENT)
    return v


def features():
    return [(1, Point(500100, 5400100), {"name": "SP1", "height": 120.5}),
            (2, LineString([(500200, 5400000), (500200, 5400300)]), {"kind": "breakline"}),
            (3, Polygon([(500300, 5400200), (500380, 5400200), (500380, 5400280),
                         (500300, 5400280)]), {"action": "exclude", "note": "roof"})]


def pixel_of(view, x, y):
    p = view.view_state().to_pixel(x, y)
    return QtCore.QPoint(int(p.x()), int(p.y()))


def move(widget, pos, buttons=Qt.NoButton):
    """A mouse move with buttons held (QTest's mouseMove sends none offscreen)."""
    event = QtGui.QMouseEvent(QtCore.QEvent.MouseMove, QtCore.QPointF(pos), Qt.NoButton,
                              buttons, Qt.NoModifier)
    QtCore.QCoreApplication.sendEvent(widget, event)


def test_round_trip_and_square_pixels(view):
    state = view.view_state()
    assert state.width == 400 and state.height == 300
    for x, y in ((500123.4, 5400234.5), (500000.0, 5400300.0)):
        p = state.to_pixel(x, y)
        assert state.to_map(p.x(), p.y()) == pytest.approx((x, y))
    xmin, ymin, xmax, ymax = state.extent
    assert (xmax - xmin) / 400 == pytest.approx((ymax - ymin) / 300)
    view.resize(600, 300)
    state = view.view_state()
    xmin, ymin, xmax, ymax = state.extent
    assert (xmax - xmin) / 600 == pytest.approx((ymax - ymin) / 300)


def test_wheel_zoom_keeps_point_under_cursor(view, qtbot):
    pos = QtCore.QPointF(97.0, 211.0)
    before = view.view_state().to_map(pos.x(), pos.y())
    mupp = view.map_units_per_pixel()
    event = QtGui.QWheelEvent(pos, view.mapToGlobal(pos.toPoint()), QtCore.QPoint(0, 0),
                              QtCore.QPoint(0, 120), Qt.NoButton, Qt.NoModifier,
                              Qt.NoScrollPhase, False)
    QtCore.QCoreApplication.sendEvent(view, event)
    assert view.map_units_per_pixel() == pytest.approx(mupp / 1.25)
    assert view.view_state().to_map(pos.x(), pos.y()) == pytest.approx(before)


def test_keys_pan_and_zoom(view, qtbot):
    xmin, ymin, xmax, ymax = view.extent()
    quarter = (xmax - xmin) / 4
    qtbot.keyClick(view, Qt.Key_Right)
    assert view.extent()[0] == pytest.approx(xmin + quarter)
    qtbot.keyClick(view, Qt.Key_Left)
    qtbot.keyClick(view, Qt.Key_Up)
    assert view.extent()[0] == pytest.approx(xmin)
    assert view.extent()[1] == pytest.approx(ymin + (ymax - ymin) / 4)
    mupp = view.map_units_per_pixel()
    qtbot.keyClick(view, Qt.Key_Plus)
    assert view.map_units_per_pixel() == pytest.approx(mupp / 1.25)
    qtbot.keyClick(view, Qt.Key_Minus)
    assert view.map_units_per_pixel() == pytest.approx(mupp)


def test_drag_pans(view, qtbot):
    before = view.extent()
    qtbot.mousePress(view, Qt.LeftButton, pos=QtCore.QPoint(100, 100))
    move(view, QtCore.QPoint(130, 90), Qt.LeftButton)
    qtbot.mouseRelease(view, Qt.LeftButton, pos=QtCore.QPoint(130, 90))
    mupp = view.map_units_per_pixel()
    after = view.extent()
    assert after[0] == pytest.approx(before[0] - 30 * mupp)
    assert after[1] == pytest.approx(before[1] - 10 * mupp)


class ClickTool(MapTool):
    def __init__(self):
        super().__init__()
        self.points = []
        self.active = None

    def activate(self):
        self.active = True

    def deactivate(self):
        self.active = False

    def press(self, event, x, y):
        if event.button() == Qt.LeftButton:
            self.points.append((x, y))
            self.changed.emit()
            return True
        return False

    def paint(self, painter, view):
        for x, y in self.points:
            painter.drawEllipse(view.to_pixel(x, y), 3, 3)


def test_tool_gets_clicks_at_pixel_centres(view, qtbot):
    tool = ClickTool()
    view.set_tool(tool)
    assert tool.active and tool.view is view and view.tool() is tool
    before = view.extent()
    qtbot.mouseClick(view, Qt.LeftButton, pos=QtCore.QPoint(40, 50))
    assert tool.points == [pytest.approx(view.view_state().to_map(40.5, 50.5))]
    assert view.extent() == before  # the tool used the press: no pan
    view.grab()  # paints the rubber band without error
    view.set_tool(None)
    assert tool.active is False and tool.view is None


def test_cursor_moved(view, qtbot):
    seen = []
    view.cursor_moved.connect(lambda x, y: seen.append((x, y)))
    move(view, QtCore.QPoint(200, 150))
    assert seen and seen[-1] == pytest.approx(view.view_state().to_map(200.5, 150.5))


def test_vector_from_callable_label_and_feature_at(view, qtbot):
    data = features()
    layer = view.add_vector(lambda: data, "edit:exclusion_areas", name="edits")
    assert isinstance(layer, VectorLayer) and view.layers() == [layer]
    assert view.layer_by_kind("edit:exclusion_areas") is layer
    assert layer.bounds() == pytest.approx((500100, 5400000, 500380, 5400300))
    view.grab()  # paint once: value_at's tolerance follows the drawn scale
    mupp = view.map_units_per_pixel()
    assert layer.value_at(500100 + 2 * mupp, 5400100) == "SP1"
    assert layer.value_at(500100 + 9 * mupp, 5400100) is None
    assert layer.value_at(500340, 5400240) == "roof"  # inside the polygon: its note
    assert layer.feature_at(500201, 5400150, 2.0)[0] == 2
    # a click through a tool gives the label of the feature under it
    tool = ClickTool()
    view.set_tool(tool)
    qtbot.mouseClick(view, Qt.LeftButton, pos=pixel_of(view, 500100, 5400100))
    assert layer.value_at(*tool.points[0]) == "SP1"
    data.append((4, Point(500050, 5400050), {"id": "CP7"}))
    with qtbot.waitSignal(layer.changed):
        layer.reload()
    assert layer.value_at(500050, 5400050) == "CP7"


def test_vector_from_gpkg_reprojected(view, tmp_path):
    fiona = pytest.importorskip("fiona")
    path = tmp_path / "v.gpkg"
    schema = {"geometry": "Point", "properties": {"name": "str"}}
    with fiona.open(str(path), "w", driver="GPKG", layer="pts", crs="EPSG:4326",
                    schema=schema) as dst:
        dst.write({"geometry": {"type": "Point", "coordinates": (9.0, 48.75)},
                   "properties": {"name": "A"}})
    layer = view.add_vector(path, "vector", layer="pts")
    x0, y0, _x1, _y1 = layer.bounds()
    assert x0 == pytest.approx(500000, abs=1) and 5_390_000 < y0 < 5_410_000
    assert layer.name == "pts" and layer.has_crs
    assert layer.value_at(x0, y0) == "A"


class PixelLayer(MapLayer):
    has_crs = False

    def bounds(self):
        return (0, -100, 200, 0)

    def paint(self, painter, view):
        pass


def test_pixel_and_map_coordinates_never_mix(view):
    view.add_vector(features, "edit:start_points")
    with pytest.raises(InputError, match="no coordinate reference system"):
        view.add_layer(PixelLayer("scan", "image"))
    view.clear_layers()
    view.add_layer(PixelLayer("scan", "image"))
    assert view.crs() == ""
    with pytest.raises(InputError, match="pixel coordinates"):
        view.add_vector(features, "edit:start_points")


def test_layers_order_zoom_and_cache(view, qtbot):
    calls = []

    class Counting(MapLayer):
        def bounds(self):
            return (0.0, 0.0, 100.0, 50.0)

        def paint(self, painter, state):
            calls.append(painter.opacity())

    a, b = Counting("a", "vector"), Counting("b", "vector")
    with qtbot.waitSignal(view.layers_changed):
        view.add_layer(a)
    view.add_layer(b, index=1)
    assert view.layers() == [a, b]
    view.move_layer(b, 0)
    assert view.layers() == [b, a]
    b.opacity = 0.5
    view.grab()
    assert sorted(calls) == [0.5, 1.0]
    calls.clear()
    view.grab()
    assert calls == []  # nothing changed: the cached pixmap is reused
    view.zoom_full()
    xmin, ymin, xmax, ymax = view.extent()
    assert xmin <= 0 and xmax >= 100 and ymin <= 0 and ymax >= 50
    view.remove_layer(a)
    assert view.layers() == [b]


def test_scale_bar_lengths():
    assert nice_length(137.0) == 100.0
    assert nice_length(0.37) == pytest.approx(0.2)
    assert nice_length(5100.0) == 5000.0
    assert length_text(2000.0) == "2 km"
    assert length_text(50.0) == "50 m"


def test_styles_from_our_qml():
    exclusion = style_for_kind("edit:exclusion_areas")
    assert exclusion.attribute == "action"
    assert set(exclusion.categories) >= {"keep", "remove", "exclude"}
    keep = exclusion.symbol_for({"action": "keep"})
    assert keep.pen[:3] == (26, 152, 80)
    assert exclusion.symbol_for({"action": "remove"}) != keep
    start = style_for_kind("edit:start_points")
    assert start.symbol.marker == "cross2"
    assert style_for_kind("footprints").label_field == "image"
    for qml in STYLES_DIR.glob("*.qml"):
        if qml.stem.startswith(("edit_", "footprints", "stereo_models", "seamlines")):
            parse_qml(qml)  # every vector style of ours reads


def test_unreadable_style_falls_back(tmp_path, caplog, monkeypatch):
    from photodem.plugin.widgets import map_styles

    bad = tmp_path / "edit_broken.qml"
    bad.write_text("<qgis><not closed")
    monkeypatch.setattr(map_styles, "STYLES_DIR", tmp_path)
    map_styles.style_for_kind.cache_clear()
    try:
        assert map_styles.style_for_kind("edit:broken") is DEFAULT_STYLE
        assert "edit_broken.qml" in caplog.text
    finally:
        map_styles.style_for_kind.cache_clear()
