"""The quality panel's tools on the standalone map and the docks of the main window (issue 21):
a polygon drawn on the map gives the statistics of ``set_area`` with the same polygon, a line
its profile, a click the identify table; blunders go into the edit session."""

from __future__ import annotations

import importlib
import os
import shutil
from pathlib import Path

import pytest

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
pytest.importorskip("pytestqt")

from shapely.geometry import Polygon

from photodem.plugin.qt import QtCore, QtGui, QtWidgets, pyqtSignal
from photodem.plugin.widgets.map_qc_tools import QcAreaTool, QcIdentifyTool, QcLineTool
from photodem.plugin.widgets.map_view import MapView
from photodem.plugin.widgets.qc_panel import QcPanel

QtTest = importlib.import_module(QtCore.__name__.rsplit(".", 1)[0] + ".QtTest")
Qt = QtCore.Qt
AREA = [(402270.0, 5674650.0), (402330.0, 5674650.0), (402330.0, 5674720.0),
        (402270.0, 5674720.0)]
EXTENT = (402230.0, 5674615.0, 402370.0, 5674790.0)


@pytest.fixture(scope="module")
def block(tiny_block) -> Path:
    return tiny_block


@pytest.fixture
def root(tmp_path, block) -> Path:
    target = tmp_path / "block"
    shutil.copytree(block, target)
    return target


@pytest.fixture
def mapped(qtbot, root):
    view = MapView()
    view.resize(560, 700)
    qtbot.addWidget(view)
    view.show()
    qtbot.waitExposed(view)
    view.set_crs("EPSG:25832")
    view.set_extent(EXTENT)
    panel = QcPanel()
    qtbot.addWidget(panel)
    panel.set_project(root)
    panel.set_inputs(dem=str(root / "truth" / "dsm.tif"), reference=str(root / "truth" / "dtm.tif"))
    return view, panel


def click(view, x, y, right=False):
    p = view.view_state().to_pixel(x, y)
    point = QtCore.QPoint(round(p.x()), round(p.y()))
    QtTest.QTest.mouseClick(view, Qt.RightButton if right else Qt.LeftButton, Qt.NoModifier,
                            point)
    return view.view_state().to_map(point.x() + 0.5, point.y() + 0.5)


def test_drawn_area_gives_the_statistics_of_set_area(mapped):
    view, panel = mapped
    view.set_tool(QcAreaTool(view, panel))
    hits = [click(view, *xy) for xy in AREA]
    click(view, *AREA[-1], right=True)
    assert panel.wait(60000)
    drawn = panel.statistics
    assert drawn is not None and "m²" in panel.area_label
    assert panel.area.equals(Polygon(hits))
    panel.set_area(Polygon(hits).wkt, "typed")
    assert panel.wait(60000)
    assert panel.statistics["stats"] == drawn["stats"]


def test_drawn_line_gives_the_profile_and_a_click_identifies(mapped):
    view, panel = mapped
    view.set_tool(QcLineTool(view, panel))
    hits = [click(view, 402260.0, 5674680.0), click(view, 402340.0, 5674730.0)]
    QtTest.QTest.keyClick(view, Qt.Key_Return)
    assert panel.profile is not None
    assert panel.line.tolist() == [list(h) for h in hits]
    view.set_tool(QcIdentifyTool(view, panel))
    x, _ = click(view, 402300.0, 5674700.0)
    assert f"{x:.2f}" in panel.identify_text.text()
    assert panel.identify_table.rowCount() >= 2


class DockWindow(QtWidgets.QMainWindow):
    """The main window's contract for the docks (part M's window provides the same)."""

    project_opened = pyqtSignal(str)

    def __init__(self) -> None:
        super().__init__()
        self.message_boxes = False
        self.settings = None
        self.form = None
        self.batch_dialog = None
        self.edit_session = None
        self.project_root = None
        self.map_view = MapView(self)
        self.setCentralWidget(self.map_view)

    def open_project(self, root: Path) -> None:
        from photodem.plugin.widgets.edit_session import EditSession

        self.project_root, self.edit_session = root, EditSession(root, self)
        self.map_view.set_crs("EPSG:25832")
        self.map_view.add_raster(str(root / "truth" / "dsm.tif"), "dsm", "DSM")
        for layer in self.edit_session.layers():
            self.map_view.add_vector(self.edit_session.source(layer), f"edit:{layer}",
                                     name=layer)
        self.edit_session.changed.connect(
            lambda layer: self.map_view.layer_by_kind(f"edit:{layer}").reload())
        self.map_view.set_extent(EXTENT)
        self.project_opened.emit(str(root))

    def open_batch_dialog(self, project=None):
        from photodem.plugin.app.main_window import ToolboxWindow

        return ToolboxWindow.open_batch_dialog(self, project)

    def _batch_in_background(self) -> None:
        pass

    def _batch_finished(self, summary) -> None:
        pass


@pytest.fixture
def window(qtbot, root):
    from edit_clicks import FakeAsk

    from photodem.plugin.app.docks import install_editing

    w = DockWindow()
    qtbot.addWidget(w)
    install_editing(w, ask=FakeAsk())
    w.resize(1500, 950)
    w.show()
    qtbot.waitExposed(w)
    w.open_project(root)
    return w


@pytest.fixture(autouse=True)
def _click_table_on_path():
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    yield
    sys.path.remove(str(Path(__file__).resolve().parents[1]))


def test_docks_follow_the_project_and_blunders_go_into_the_session(window, root):
    from photodem.plugin.app.docks import QUALITY_DOCK, batch_dock, quality_dock

    bar = window.editing_toolbar
    assert bar.context is not None and bar.actions_["breaklines"].isEnabled()
    assert window.undo_history.session is window.edit_session
    assert bar.undo_actions[0].text().startswith("Undo")
    panel = quality_dock(window).widget()
    assert window.findChild(QtWidgets.QDockWidget, QUALITY_DOCK).widget() is panel
    assert panel.project_root == root
    before = (root / "edits.gpkg").read_bytes()
    panel.set_inputs(dem=str(root / "truth" / "dsm.tif"), reference=str(root / "truth" / "dtm.tif"))
    from photodem.algorithms.quality.qc_blunders import find_blunders

    # the truth DSM's buildings are "blunders" against the DTM (the panel's own search uses
    # k·NMAD, zero here: the DSM equals the DTM on open ground)
    panel.blunders = find_blunders(root / "truth" / "dsm.tif", root / "truth" / "dtm.tif",
                                   threshold=2.0)
    assert panel.blunders["spots"]
    assert panel.blunder_to_exclusion(0, "remove")
    assert len(window.edit_session.features("exclusion_areas")) == 1
    assert (root / "edits.gpkg").read_bytes() == before  # only *Save edits* writes
    window.edit_session.undo_stack.undo()
    assert window.edit_session.features("exclusion_areas") == []
    tool = bar.activate("qc_area")
    assert isinstance(tool, QcAreaTool) and not bar.actions_["breaklines"].isChecked()
    dock = batch_dock(window, str(root))
    assert dock.widget() is window.batch_dialog and dock.isVisible()


@pytest.mark.parametrize("lang", ["en", "de"])
def test_screenshot_docks(qtbot, root, lang, shots_dir, german):
    from edit_clicks import CLICKS, FakeAsk

    from photodem.plugin.app.docks import batch_dock, install_editing, quality_dock
    from photodem.plugin.i18n import install_translator

    if lang == "de":
        german()
    try:
        w = DockWindow()
        qtbot.addWidget(w)
        ask = FakeAsk()
        install_editing(w, ask=ask)
        w.resize(1600, 1000)
        w.show()
        qtbot.waitExposed(w)
        w.open_project(root)
        for case in CLICKS[:6]:
            ask.answer = dict(case["answer"])
            w.editing_toolbar.activate(case["layer"])
            for xy in case["clicks"]:
                click(w.map_view, *xy)
            if len(case["clicks"]) > 1:
                click(w.map_view, *case["clicks"][-1], right=True)
        panel = quality_dock(w).widget()
        panel.set_inputs(dem=str(root / "truth" / "dsm.tif"),
                         reference=str(root / "truth" / "dtm.tif"))
        w.editing_toolbar.activate("qc_area")
        for xy in AREA:
            click(w.map_view, *xy)
        click(w.map_view, *AREA[-1], right=True)
        assert panel.wait(60000)
        batch_dock(w, str(root))
        w.map_view.wait_rendered(5000)
        QtWidgets.QApplication.processEvents()
        assert w.grab().save(str(shots_dir / f"docks_{lang}.png"))
        quality_dock(w).raise_()  # the statistics of the drawn area
        QtWidgets.QApplication.processEvents()
        assert w.grab().save(str(shots_dir / f"docks_quality_{lang}.png"))
        QtGui.QGuiApplication.processEvents()
    finally:
        install_translator("en")
