"""Vertex editing, feature deletion and re-drape on the standalone map view (issue 21),
driven by mouse events on a real MapView."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np
import pytest

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
pytest.importorskip("pytestqt")

import rasterio
from rasterio.transform import from_origin
from shapely.geometry import LineString, Point, Polygon

from photodem.algorithms.errors import InputError
from photodem.algorithms.project.edits import create_edits
from photodem.algorithms.project.model import Project
from photodem.plugin.qt import QtCore, QtGui
from photodem.plugin.widgets.edit_session import EditSession
from photodem.plugin.widgets.map_vertex_tools import (
    DeleteFeatureTool,
    VertexTool,
    moved,
    redrape,
    vertices,
    without_vertex,
)
from photodem.plugin.widgets.map_view import MapView

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests/: the shared click table
from edit_clicks import CLICKS, EXTENT, SURFACE, surface_z

Qt = QtCore.Qt
CRS = str(SURFACE["crs"])


def write_surface(path: Path) -> Path:
    """The exact plane of :data:`SURFACE` as a float64 GeoTIFF (with its nodata box)."""
    xmin, ymin, xmax, ymax = SURFACE["bounds"]
    res = float(SURFACE["res"])
    cols, rows = int((xmax - xmin) / res), int((ymax - ymin) / res)
    xx, yy = np.meshgrid(xmin + (np.arange(cols) + 0.5) * res,
                         ymax - (np.arange(rows) + 0.5) * res)
    z = surface_z(xx, yy)
    bx0, by0, bx1, by1 = SURFACE["nodata_box"]
    z[(xx > bx0) & (xx < bx1) & (yy > by0) & (yy < by1)] = -9999.0
    with rasterio.open(path, "w", driver="GTiff", width=cols, height=rows, count=1,
                       dtype="float64", transform=from_origin(xmin, ymax, res, res),
                       nodata=-9999.0, crs=CRS) as dst:
        dst.write(z, 1)
    return path


@pytest.fixture(scope="module")
def block(tiny_block) -> Path:
    """The tiny synthetic block: a real project for the edit checks (read only)."""
    return tiny_block


@pytest.fixture(scope="module")
def surface(tmp_path_factory) -> Path:
    return write_surface(tmp_path_factory.mktemp("surface") / "plane.tif")


@pytest.fixture
def session(tmp_path, qtbot) -> EditSession:
    """A session on an empty edits.gpkg with the features of the shared click table."""
    create_edits(tmp_path / "edits.gpkg", CRS)
    s = EditSession(tmp_path)
    for case in CLICKS:
        layer, clicks = case["layer"], case["clicks"]
        if case["geometry"] == "Point":
            x, y = clicks[0]
            z = surface_z(x, y)
            geometry = Point(x, y) if layer == "start_points" else Point(x, y, z)
            attrs = dict(case["attributes"], **({"height": z} if layer == "start_points" else {}))
        elif case["geometry"] == "Polygon":
            geometry, attrs = Polygon(clicks), case["attributes"]
        elif layer == "breaklines":
            geometry = LineString([(x, y, surface_z(x, y) + 1.0) for x, y in clicks])
            attrs = case["attributes"]
        else:
            geometry, attrs = LineString(clicks), case["attributes"]
        s.add(layer, geometry, attrs)
    s.save()
    return s


@pytest.fixture
def view(qtbot, session):
    v = MapView()
    v.resize(560, 700)
    qtbot.addWidget(v)
    v.show()
    qtbot.waitExposed(v)
    v.set_crs(CRS)
    for layer in session.layers():
        v.add_vector(session.source(layer), f"edit:{layer}", name=layer)
    v.set_extent(EXTENT)
    return v


def pixel_of(view, x, y) -> QtCore.QPoint:
    p = view.view_state().to_pixel(x, y)
    return QtCore.QPoint(int(p.x()), int(p.y()))


def map_of(view, pos: QtCore.QPoint):
    """The map point a click at ``pos`` lands on (the pixel's centre)."""
    return view.view_state().to_map(pos.x() + 0.5, pos.y() + 0.5)


def drag(qtbot, view, start: QtCore.QPoint, end: QtCore.QPoint) -> None:
    qtbot.mousePress(view, Qt.LeftButton, pos=start)
    for k in (1, 2, 3):
        pos = start + (end - start) * (k / 3.0)
        event = QtGui.QMouseEvent(QtCore.QEvent.MouseMove, QtCore.QPointF(pos), Qt.NoButton,
                                  Qt.LeftButton, Qt.NoModifier)
        QtCore.QCoreApplication.sendEvent(view, event)
    qtbot.mouseRelease(view, Qt.LeftButton, pos=end)


# -- Qt-free geometry ---------------------------------------------------------------------------
def test_move_and_delete_keep_rings_closed_and_z() -> None:
    square = Polygon([(0, 0), (4, 0), (4, 4), (0, 4)])
    keys = [k for k, _ in vertices(square)]
    assert len(keys) == 4  # the closing vertex is not a vertex of its own
    first = moved(square, keys[0], -1, -1)
    assert next(iter(first.exterior.coords)) == list(first.exterior.coords)[-1] == (-1, -1)
    assert len(without_vertex(square, keys[1]).exterior.coords) == 4
    line = LineString([(0, 0, 5), (1, 1, 6), (2, 0, 7)])
    assert list(moved(line, (0, 0, 1), 9, 9).coords)[1] == (9, 9, 6)  # Z kept
    assert list(moved(line, (0, 0, 1), 9, 9, 1.5).coords)[1] == (9, 9, 1.5)
    with pytest.raises(InputError, match="at least 3"):
        without_vertex(Polygon([(0, 0), (1, 0), (0, 1)]), (0, 0, 1))
    with pytest.raises(InputError, match="at least 2"):
        without_vertex(LineString([(0, 0), (1, 1)]), (0, 0, 0))


# -- mouse events on the map view --------------------------------------------------------------
def test_drag_moves_exactly_the_clicked_vertex_to_the_release_point(qtbot, view, session,
                                                                   surface) -> None:
    before = session.feature("breaklines", 1)[0]
    x, y = list(before.coords)[1][:2]
    tool = VertexTool(view, session, "breaklines", surface=str(surface))
    view.set_tool(tool)
    count = session.undo_stack.count()
    start = pixel_of(view, x, y)
    end = start + QtCore.QPoint(37, 23)
    drag(qtbot, view, start, end)
    after = session.feature("breaklines", 1)[0]
    mx, my = map_of(view, end)
    coords = list(after.coords)
    assert coords[1][:2] == pytest.approx((mx, my), abs=1e-9)
    assert coords[1][2] == pytest.approx(surface_z(mx, my), abs=1e-6)  # re-sampled
    assert coords[0] == next(iter(before.coords)) and coords[2] == list(before.coords)[2]
    assert session.undo_stack.count() == count + 1
    assert session.undo_stack.undoText() == "Move vertex"
    session.undo_stack.undo()
    assert session.feature("breaklines", 1)[0].equals(before)
    qtbot.mouseClick(view, Qt.LeftButton, pos=start)  # a click without a drag: nothing
    assert session.undo_stack.count() == count + 1 and session.undo_stack.canRedo()
    assert session.feature("breaklines", 1)[0].equals(before)


def test_move_without_surface_keeps_z_and_polygon_closed(qtbot, view, session) -> None:
    before = session.feature("exclusion_areas", 1)[0]
    x, y = before.exterior.coords[0]
    view.set_tool(VertexTool(view, session, "exclusion_areas"))
    start = pixel_of(view, x, y)
    end = start + QtCore.QPoint(-15, 12)
    drag(qtbot, view, start, end)
    ring = list(session.feature("exclusion_areas", 1)[0].exterior.coords)
    assert ring[0] == pytest.approx(map_of(view, end)) and ring[0] == ring[-1]
    assert ring[1:-1] == list(before.exterior.coords)[1:-1]
    # a ground point moved without surface keeps its Z
    gx, gy, gz = session.features("ground_points")[0][1].coords[0]
    view.set_tool(VertexTool(view, session, "ground_points"))
    start = pixel_of(view, gx, gy)
    drag(qtbot, view, start, start + QtCore.QPoint(5, 5))
    assert session.features("ground_points")[0][1].coords[0][2] == gz


def test_moved_start_point_takes_the_surface_height(qtbot, view, session, surface) -> None:
    (fid, p, _attrs), = session.features("start_points")
    view.set_tool(VertexTool(view, session, "start_points", surface=str(surface)))
    start = pixel_of(view, p.x, p.y)
    end = start + QtCore.QPoint(20, -10)
    drag(qtbot, view, start, end)
    g, a = session.feature("start_points", fid)
    mx, my = map_of(view, end)
    assert (g.x, g.y) == pytest.approx((mx, my)) and a["height"] == pytest.approx(
        surface_z(mx, my), abs=1e-6)
    assert a["note"] == "seed"


def test_delete_vertex_refused_for_a_triangle(qtbot, view, session) -> None:
    fid = session.add("boundaries", Polygon([(402280, 5674660), (402310, 5674660),
                                             (402290, 5674690)]), {"name": "tri"})
    count = session.undo_stack.count()
    tool = VertexTool(view, session, "boundaries")
    view.set_tool(tool)
    qtbot.mouseClick(view, Qt.RightButton, pos=pixel_of(view, 402310, 5674660))
    assert "at least 3" in tool.last_message
    assert session.undo_stack.count() == count
    assert len(session.feature("boundaries", fid)[0].exterior.coords) == 4
    # a square loses a corner (right click), then one more by the Delete key is refused
    square = session.features("boundaries")[0]
    x, y = square[1].exterior.coords[2]
    qtbot.mouseClick(view, Qt.RightButton, pos=pixel_of(view, x, y))
    assert len(session.feature("boundaries", square[0])[0].exterior.coords) == 4
    assert session.undo_stack.undoText() == "Delete vertex"
    x, y = session.feature("boundaries", square[0])[0].exterior.coords[0]
    QtCore.QCoreApplication.sendEvent(view, QtGui.QMouseEvent(
        QtCore.QEvent.MouseMove, QtCore.QPointF(pixel_of(view, x, y)), Qt.NoButton,
        Qt.NoButton, Qt.NoModifier))
    qtbot.keyClick(view, Qt.Key_Delete)
    assert "at least 3" in tool.last_message


def test_move_that_crosses_another_breakline_is_refused(qtbot, view, session) -> None:
    session.add("breaklines", LineString([(402285, 5674640, 50), (402285, 5674680, 50)]),
                {"kind": "breakline"})
    count = session.undo_stack.count()
    tool = VertexTool(view, session, "breaklines")
    view.set_tool(tool)
    start = pixel_of(view, 402285, 5674680)
    drag(qtbot, view, start, pixel_of(view, 402285, 5674725))  # across breakline 1
    assert "crosses" in tool.last_message and session.undo_stack.count() == count


def test_move_outside_the_block_is_refused_with_a_project(qtbot, view, session, block) -> None:
    tool = VertexTool(view, session, "seamlines", project=Project.load(block))
    view.set_tool(tool)
    (fid, _line, _), = session.features("seamlines")
    count = session.undo_stack.count()
    assert tool.move_vertex(fid, (0, 0, 0), 402000.0, 5673000.0)  # partly outside: a warning
    assert "partly outside" in tool.last_message
    assert not tool.move_vertex(fid, (0, 0, 1), 402000.0, 5673100.0)  # all outside: refused
    assert "refused" in tool.last_message and "outside" in tool.last_message
    assert session.undo_stack.count() == count + 1


def test_delete_feature_tool(qtbot, view, session) -> None:
    view.set_tool(DeleteFeatureTool(view, session, "exclusion_areas"))
    qtbot.mouseClick(view, Qt.LeftButton, pos=pixel_of(view, 402290, 5674660))  # inside
    assert session.features("exclusion_areas") == []
    assert session.undo_stack.undoText() == "Delete exclusion area"
    assert view.layer_by_kind("edit:exclusion_areas").features() == []  # drawn again
    qtbot.mouseClick(view, Qt.LeftButton, pos=pixel_of(view, 402250, 5674780))  # nothing
    assert session.undo_stack.undoText() == "Delete exclusion area"
    session.undo_stack.undo()
    assert len(session.features("exclusion_areas")) == 1


def test_redrape_equals_the_surface_as_one_command(session, surface, tmp_path) -> None:
    (fid, point, _), = session.features("ground_points")
    session.replace("ground_points", fid, Point(point.x, point.y, 0.0))
    count = session.undo_stack.count()
    assert redrape(session, str(surface)) == 2  # the breakline (Z + 1 m), the ground point
    assert session.undo_stack.count() == count + 1
    for x, y, z in session.features("breaklines")[0][1].coords:
        assert z == pytest.approx(surface_z(x, y), abs=1e-6)
    for layer in ("ground_points", "check_points"):
        x, y, z = session.features(layer)[0][1].coords[0]
        assert z == pytest.approx(surface_z(x, y), abs=1e-6)
    session.undo_stack.undo()
    assert session.features("breaklines")[0][1].coords[0][2] == pytest.approx(
        surface_z(*CLICKS[5]["clicks"][0]) + 1.0)
    # a vertex on nodata: nothing changes, the feature is named
    session.add("ground_points", Point(402337.0, 5674742.0, 50.0), {"note": "hole"})
    count = session.undo_stack.count()
    with pytest.raises(InputError, match="nodata"):
        redrape(session, str(surface))
    assert session.undo_stack.count() == count
