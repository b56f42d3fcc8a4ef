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


@pytest.fixture(autouse=True)
def own_settings(tmp_path_factory):
    """Each test starts from empty settings of its own and leaves the application's names as
    they were.

    Why: ``QSettings`` of the user scope live in the operator's home and outlive the run, and the
    application's names are process-wide: a window of one module remembered a project that a
    window of a later module opened with (issue: ``test_opening_a_project_fills_the_forms``
    failed after ``test_map_window``'s start of the toolbox).
    """
    try:
        from photodem.plugin.qt import QtCore
    except ImportError:  # no Qt: nothing to isolate
        yield
        return
    settings, app = QtCore.QSettings, QtCore.QCoreApplication
    folder = str(tmp_path_factory.mktemp("settings"))
    for fmt in (settings.NativeFormat, settings.IniFormat):
        for scope in (settings.UserScope, settings.SystemScope):
            settings.setPath(fmt, scope, folder)
    names = (app.organizationName(), app.applicationName())
    yield
    app.setOrganizationName(names[0])
    app.setApplicationName(names[1])
