"""The standalone map's editing tools driven by mouse events (issue 21): every entry of the
shared click table (``tests/edit_clicks.py``) writes the same feature as the QGIS tool, read
back from the saved ``edits.gpkg``; refusals, repairs, interpolated heights and warnings too."""

from __future__ import annotations

import math
import os
import shutil
import sys
from pathlib import Path

import pytest

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
pytest.importorskip("pytestqt")

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests/: the shared click table
import importlib

from edit_clicks import (
    BOW_TIE,
    CLICKS,
    CROSSING_BREAKLINE,
    EXTENT,
    INTERPOLATED,
    OUTSIDE_MODELS,
    FakeAsk,
    check_written,
    surface_z,
    write_mosaic_seamlines,
    write_surface,
)

from photodem.plugin.qt import QtCore, QtGui, QtWidgets
from photodem.plugin.widgets.edit_session import EditSession
from photodem.plugin.widgets.map_edit_tools import LineCaptureTool, editing_toolbar
from photodem.plugin.widgets.map_view import MapView

QtTest = importlib.import_module(QtCore.__name__.rsplit(".", 1)[0] + ".QtTest")
Qt = QtCore.Qt


@pytest.fixture(scope="module")
def block(tiny_block) -> Path:
    """The tiny synthetic block (each test edits a copy)."""
    return tiny_block


class Window(QtWidgets.QMainWindow):
    """The main window's contract for the tools: ``map_view`` and ``edit_session``."""

    def __init__(self, root: Path) -> None:
        super().__init__()
        self.message_boxes = False
        self.messages = []
        self.map_view = MapView(self)
        self.setCentralWidget(self.map_view)
        self.edit_session = EditSession(root, self)
        self.edit_session.changed.connect(  # as the main window does
            lambda layer: self.map_view.layer_by_kind(f"edit:{layer}").reload())


@pytest.fixture
def work(tmp_path, block, qtbot):
    root = tmp_path / "block"
    shutil.copytree(block, root)
    window = Window(root)
    qtbot.addWidget(window)
    view = window.map_view
    view.set_crs("EPSG:25832")
    for layer in window.edit_session.layers():
        view.add_vector(window.edit_session.source(layer), f"edit:{layer}", name=layer)
    window.resize(1300, 900)
    window.show()
    qtbot.waitExposed(window)
    view.set_extent(EXTENT)
    ask = FakeAsk()
    bar = editing_toolbar(window, ask=ask)
    window.addToolBar(bar)
    window.addToolBar(bar.more)
    bar.set_project(root)
    bar.set_surface(write_surface(tmp_path / "plane_dsm.tif"), "plane DSM")
    bar.message = bar.context.message = lambda text, level="warning": window.messages.append(
        (level, text))
    return {"root": root, "window": window, "view": view, "bar": bar, "ask": ask,
            "session": window.edit_session}


def click(view, x: float, y: float, right: bool = False):
    """A click on the map at (x, y); returns the map point of the clicked pixel."""
    p = view.view_state().to_pixel(x, y)
    point = QtCore.QPoint(round(p.x()), round(p.y()))
    QtTest.QTest.mouseMove(view, point)
    QtTest.QTest.mouseClick(view, Qt.RightButton if right else Qt.LeftButton, Qt.NoModifier,
                            point)
    return view.view_state().to_map(point.x() + 0.5, point.y() + 0.5)


def draw(work, layer: str, clicks, finish: bool = True):
    tool = work["bar"].activate(layer)
    assert tool is not None and work["view"].tool() is tool, work["window"].messages
    hits = [click(work["view"], x, y) for x, y in clicks]
    if finish and len(clicks) > 1:
        click(work["view"], *clicks[-1], right=True)
    return hits


def saved(work, layer: str):
    import fiona
    from shapely.geometry import shape

    path = work["session"].save()
    with fiona.open(path, layer=layer) as src:
        return [(shape(f["geometry"]), dict(f["properties"])) for f in src]


def texts(work) -> str:
    return " ".join(text for _, text in work["window"].messages)


@pytest.mark.parametrize("case", CLICKS, ids=[c["layer"] for c in CLICKS])
def test_tool_writes_what_the_qgis_tool_writes(work, case):
    layer = case["layer"]
    work["ask"].answer = dict(case["answer"])
    hits = draw(work, layer, case["clicks"])
    session = work["session"]
    assert len(session.features(layer)) == 1, (texts(work), work["ask"].calls)
    session.undo_stack.undo()
    assert session.features(layer) == []
    session.undo_stack.redo()
    check_written(case, hits, saved(work, layer))


def test_crossing_breakline_refused_and_marked(work):
    first = next(c for c in CLICKS if c["layer"] == "breaklines")
    draw(work, "breaklines", first["clicks"])
    draw(work, "breaklines", CROSSING_BREAKLINE)
    assert len(work["session"].features("breaklines")) == 1
    assert "refused" in texts(work)
    (x, y), = work["bar"].context.marks
    assert abs(x - 402285.0) < 1.0 and abs(y - 5674707.5) < 1.0
    assert len(saved(work, "breaklines")) == 1


def test_bow_tie_refused_or_repaired_with_consent(work):
    work["ask"].answer = {"repair": False, "action": "exclude"}
    draw(work, "exclusion_areas", BOW_TIE)
    assert work["session"].features("exclusion_areas") == []
    assert "refused" in texts(work) and "Self-intersection" in texts(work)
    work["ask"].answer = {"repair": True, "action": "exclude"}
    draw(work, "exclusion_areas", BOW_TIE)
    assert len(work["session"].features("exclusion_areas")) == 2
    work["session"].undo_stack.undo()  # the two triangles are one step
    assert work["session"].features("exclusion_areas") == []
    work["session"].undo_stack.redo()
    rows = saved(work, "exclusion_areas")
    assert len(rows) == 2 and all(g.is_valid and p["action"] == "exclude" for g, p in rows)


def test_interpolated_breakline(work):
    work["bar"].set_z_mode("interpolate")
    work["ask"].answer = {"heights": [INTERPOLATED["ends"][0], None, INTERPOLATED["ends"][1]]}
    hits = draw(work, "breaklines", INTERPOLATED["clicks"])
    assert work["ask"].calls[-1][2] == [True, False, True]
    (line, _), = saved(work, "breaklines")
    s = [0.0, math.dist(hits[0], hits[1])]
    s.append(s[1] + math.dist(hits[1], hits[2]))
    z0, z1 = INTERPOLATED["ends"]
    assert [c[2] for c in line.coords] == pytest.approx([z0 + (z1 - z0) * v / s[-1] for v in s],
                                                        abs=1e-6)


def test_start_point_outside_the_models_warns_and_asks_a_height(work):
    work["ask"].answer = {"height": 48.0}
    draw(work, "start_points", [OUTSIDE_MODELS])
    kind, prefilled, message = work["ask"].calls[-1]
    assert kind == "height" and prefilled is None and "outside every stereo model" in message
    assert "outside every stereo model" in texts(work)
    (_, props), = saved(work, "start_points")
    assert props["height"] == 48.0


def test_keys_backspace_escape_enter(work):
    case = next(c for c in CLICKS if c["layer"] == "boundaries")
    work["ask"].answer = dict(case["answer"])
    tool = work["bar"].activate("boundaries")
    view = work["view"]
    for xy in case["clicks"]:
        click(view, *xy)
    click(view, 402300.0, 5674700.0)
    QtTest.QTest.keyClick(view, Qt.Key_Backspace)
    assert len(tool.vertices) == 4
    QtTest.QTest.keyClick(view, Qt.Key_Escape)
    assert tool.vertices == [] and work["session"].features("boundaries") == []
    hits = [click(view, *xy) for xy in case["clicks"]]
    QtTest.QTest.keyClick(view, Qt.Key_Return)
    check_written(case, hits, saved(work, "boundaries"))


def test_seamline_snaps_to_a_mosaic_seamline_on_the_map(work, tmp_path):
    path = write_mosaic_seamlines(tmp_path / "mosaic_seamlines.gpkg")
    work["view"].add_vector(path, "seamlines", name="mosaic seamlines", layer="seamlines")
    case = next(c for c in CLICKS if c["layer"] == "seamlines")
    draw(work, "seamlines", case["clicks"])
    (line, _), = saved(work, "seamlines")
    assert [c[0] for c in line.coords] == pytest.approx([402301.0, 402301.0], abs=1e-6)


def test_read_only_edits_refuse_the_tools(work, tmp_path, qtbot):
    root = work["root"]
    (root / "edits.gpkg").write_bytes(b"not a geopackage")
    window = Window(root)
    qtbot.addWidget(window)
    assert window.edit_session.read_only
    bar = editing_toolbar(window, ask=FakeAsk())
    bar.set_project(root)
    bar.context.message = lambda text, level="warning": window.messages.append((level, text))
    assert bar.activate("ground_points") is None
    assert not bar.actions_["ground_points"].isChecked()
    assert "read-only" in " ".join(t for _, t in window.messages)
    assert (root / "edits.gpkg").read_bytes() == b"not a geopackage"


def test_vertex_delete_and_redrape_from_the_toolbar(work):
    from photodem.plugin.widgets.map_vertex_tools import DeleteFeatureTool, VertexTool

    work["ask"].answer = {"height": 30.0}
    (hx, hy), = draw(work, "ground_points", [(402300.0, 5674700.0)])
    assert isinstance(work["bar"].activate("vertex:ground_points"), VertexTool)
    assert not work["bar"].actions_["ground_points"].isChecked()
    assert work["bar"].redrape() == 1
    (_, geometry, _), = work["session"].features("ground_points")
    assert geometry.z == pytest.approx(surface_z(hx, hy), abs=1e-6)
    work["session"].undo_stack.undo()
    assert work["session"].features("ground_points")[0][1].z == 30.0
    assert isinstance(work["bar"].activate("delete:ground_points"), DeleteFeatureTool)
    click(work["view"], hx, hy)
    assert work["session"].features("ground_points") == []


def test_no_project_disables_the_tools(work):
    work["bar"].set_project(None)
    assert not work["bar"].actions_["start_points"].isEnabled()
    assert work["bar"].activate("start_points") is None


@pytest.mark.parametrize("lang", ["en", "de"])
def test_screenshot_capture_in_progress(work, lang, shots_dir, german):
    from photodem.plugin.i18n import install_translator

    window = work["window"]
    if lang == "de":
        german()
        window.removeToolBar(work["bar"])
        window.removeToolBar(work["bar"].more)
        bar = editing_toolbar(window, ask=work["ask"])
        window.addToolBar(bar)
        window.addToolBarBreak()
        window.addToolBar(bar.more)
        bar.set_project(work["root"])
        bar.context.message = lambda text, level="warning": window.statusBar().showMessage(text)
        work["bar"] = bar
    try:
        dsm = work["view"].add_raster(str(work["root"] / "truth" / "dsm.tif"), "dsm", "DSM")
        work["view"].move_layer(dsm, len(work["view"].layers()) - 1)  # under the edits
        for case in CLICKS[:6]:
            work["ask"].answer = dict(case["answer"])
            draw(work, case["layer"], case["clicks"])
        draw(work, "breaklines", CROSSING_BREAKLINE)  # refused: its crossing stays marked
        work["ask"].answer = {"action": "remove"}
        work["bar"].activate("exclusion_areas")
        for xy in [(402305.0, 5674720.0), (402325.0, 5674720.0), (402325.0, 5674735.0)]:
            click(work["view"], *xy)
        hover(work, 402312.0, 5674748.0)
        work["view"].wait_rendered(5000)
        QtWidgets.QApplication.processEvents()
        assert window.grab().save(str(shots_dir / f"capture_{lang}.png"))
    finally:
        install_translator("en")


def _pixel(work, x, y) -> QtCore.QPoint:
    p = work["view"].view_state().to_pixel(x, y)
    return QtCore.QPoint(round(p.x()), round(p.y()))


def hover(work, x: float, y: float) -> None:
    """The cursor over (x, y) without a button (QTest's mouseMove sends nothing offscreen)."""
    event = QtGui.QMouseEvent(QtCore.QEvent.MouseMove, QtCore.QPointF(_pixel(work, x, y)),
                              Qt.NoButton, Qt.NoButton, Qt.NoModifier)
    QtCore.QCoreApplication.sendEvent(work["view"], event)


def test_line_tool_rubber_band_follows_the_cursor(work):
    tool = work["bar"].activate("breaklines")
    assert isinstance(tool, LineCaptureTool)
    click(work["view"], 402270.0, 5674700.0)
    hover(work, 402300.0, 5674700.0)
    assert tool.hover == pytest.approx((402300.0, 5674700.0), abs=0.5)
