"""Fixtures of the standalone window's tests (pytest-qt, offscreen)."""

from __future__ import annotations

import os

import pytest

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")


@pytest.fixture
def window(qtbot):
    """The standalone main window, shown; afterwards its run is awaited, unsaved edits are
    discarded and the map's layers closed."""
    pytest.importorskip("pytestqt")
    from photodem.plugin.app.main_window import ToolboxWindow

    w = ToolboxWindow(message_boxes=False)
    qtbot.addWidget(w)
    w.show()
    qtbot.waitExposed(w)
    yield w
    w.run_panel.wait(120000)
    if w.edit_session is not None:
        w.edit_session.ask = lambda parent, session: "discard"
    w.map_view.clear_layers()
