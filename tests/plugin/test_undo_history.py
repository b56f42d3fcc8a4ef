"""The undo history list, the Edit menu's Undo/Redo and the edit layers on the map (issue 21)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
pytest.importorskip("pytestqt")

from shapely.geometry import Point

from photodem.algorithms.project.edits import create_edits
from photodem.plugin.qt import QtCore, QtGui, QtWidgets
from photodem.plugin.widgets.edit_session import EditSession, show_edits
from photodem.plugin.widgets.map_view import MapView
from photodem.plugin.widgets.undo_history import UndoHistory, edit_actions

X0, Y0 = 402300.0, 5674700.0


@pytest.fixture
def session(tmp_path: Path, qtbot) -> EditSession:
    create_edits(tmp_path / "edits.gpkg", "EPSG:25832")
    return EditSession(tmp_path)


def test_history_lists_the_commands_and_its_buttons_undo(session, qtbot) -> None:
    history = UndoHistory(session)
    qtbot.addWidget(history)
    assert history.view.emptyLabel() == "<empty>"
    assert not history.undo_button.isEnabled() and not history.redo_button.isEnabled()
    assert history.status.text() == "All edits saved."
    session.add("start_points", Point(X0, Y0), {"height": 50.0})
    session.add("check_points", Point(X0 + 1, Y0, 50.0), {"id": "CP"})
    model = history.view.model()
    assert [model.index(r, 0).data() for r in range(model.rowCount())] == \
        ["<empty>", "Add start point", "Add check point"]
    assert history.undo_button.isEnabled() and history.status.text() == "Unsaved edits."
    qtbot.mouseClick(history.undo_button, QtCore.Qt.LeftButton)
    assert session.features("check_points") == [] and history.redo_button.isEnabled()
    qtbot.mouseClick(history.redo_button, QtCore.Qt.LeftButton)
    assert len(session.features("check_points")) == 1
    history.view.setCurrentIndex(model.index(0, 0))  # a click on "<empty>": back to the file
    assert session.features("start_points") == [] and not session.dirty
    history.set_session(None)
    assert history.status.text() == "No project open." and not history.undo_button.isEnabled()


def test_edit_actions_have_the_shortcuts(session, qtbot) -> None:
    window = QtWidgets.QMainWindow()
    qtbot.addWidget(window)
    undo, redo = edit_actions(session, window)
    assert undo.shortcut() == QtGui.QKeySequence(QtGui.QKeySequence.Undo)
    assert [s.toString() for s in redo.shortcuts()] == ["Ctrl+Y", "Ctrl+Shift+Z"]
    assert not undo.isEnabled()
    session.add("ground_points", Point(X0, Y0, 50.0), {"note": "n"})
    assert undo.isEnabled() and undo.text() == "Undo Add ground point"
    undo.trigger()
    assert session.features("ground_points") == [] and redo.text() == "Redo Add ground point"


def test_show_edits_draws_the_session_and_follows_it(session, qtbot) -> None:
    view = MapView()
    qtbot.addWidget(view)
    view.set_crs("EPSG:25832")
    layers = show_edits(view, session)
    assert [layer.kind for layer in layers] == [f"edit:{n}" for n in session.layers()]
    assert layers[0].name == "Start points" and view.layers()[0] is layers[0]
    fid = session.add("start_points", Point(X0, Y0), {"height": 50.0})
    assert [f[0] for f in view.layer_by_kind("edit:start_points").features()] == [fid]
    session.undo_stack.undo()
    assert view.layer_by_kind("edit:start_points").features() == []
    assert len(show_edits(view, session)) == 7 and len(view.layers()) == 7  # replaced
