"""The standalone toolbox: forms from specs, running, progress, result and cancel (pytest-qt)."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import pytest

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
pytest.importorskip("pytestqt")

FAKES = Path(__file__).resolve().parents[1] / "algorithms" / "processing"
if str(FAKES) not in sys.path:
    sys.path.insert(0, str(FAKES))

import _fake_algs  # noqa: E402

from photodem.algorithms.processing import registry  # noqa: E402
from photodem.plugin.app.main_window import ToolboxWindow  # noqa: E402
from photodem.plugin.qt import Qt, QtWidgets  # noqa: E402
from photodem.plugin.widgets.parameter_form import ParameterForm, PathEdit  # noqa: E402


@pytest.fixture
def fakes(monkeypatch):
    _fake_algs.install(monkeypatch)


@pytest.fixture
def project(chain_project):
    return chain_project("abc")


@pytest.fixture
def window(qtbot, fakes):
    w = ToolboxWindow(message_boxes=False)
    qtbot.addWidget(w)
    w.show()
    qtbot.waitExposed(w)
    yield w
    w.run_panel.cancel()
    w.run_panel.wait(10000)


def test_form_for_every_algorithm(qtbot, fakes):
    for alg in registry.algorithms().values():
        form = ParameterForm(alg)
        qtbot.addWidget(form)
        values = form.values()
        assert set(values) <= {p.name for p in alg.parameters}
        for p in alg.parameters:  # defaults show up as values; nothing required is invented
            form.editor(p.name)
            if p.default not in (None, ""):
                assert p.name in values, (alg.id, p.name)


def test_typed_values_give_raw_parameters(qtbot, fakes, project):
    form = ParameterForm(registry.get("fake_sleep_write"))
    qtbot.addWidget(form)
    assert form.values() == {"seconds": 0.2, "steps": 10, "mode": "fast", "shout": False}
    project_edit = form.editor("project")
    assert isinstance(project_edit, PathEdit)
    qtbot.keyClicks(project_edit.line_edit, str(project))
    qtbot.waitUntil(lambda: form.editor("model").count() == 2, timeout=3000)
    assert form.editor("model").currentText() == "a_b"
    form.editor("model").setCurrentIndex(1)
    seconds = form.editor("seconds")
    assert seconds.suffix() == " s" and seconds.maximum() == 60
    seconds.selectAll()
    qtbot.keyClicks(seconds, "1.5")
    qtbot.keyClick(seconds, Qt.Key_Enter)
    form.editor("steps").setValue(7)
    form.editor("mode").setCurrentIndex(2)
    qtbot.keyClick(form.editor("shout"), Qt.Key_Space)
    qtbot.keyClicks(form.editor("note"), "hello")
    qtbot.keyClicks(form.editor("output").line_edit, "/tmp/x.json")
    assert form.values() == {"project": str(project), "model": "b_c", "seconds": 1.5,
                             "steps": 7, "mode": "exact", "shout": True, "note": "hello",
                             "output": "/tmp/x.json"}
    form2 = ParameterForm(registry.get("fake_chatty"))
    qtbot.addWidget(form2)
    form2.set_values({"extent": [0, 0, 10, 5], "crs": "EPSG:25832", "flag": True})
    assert form2.values() == {"factor": 2.0, "extent": "0,0,10,5", "crs": "EPSG:25832",
                              "flag": True}


def test_browse_button_uses_dialog(qtbot, monkeypatch):
    edit = PathEdit("save", (".tif",))
    qtbot.addWidget(edit)
    monkeypatch.setattr(QtWidgets.QFileDialog, "getSaveFileName",
                        staticmethod(lambda *a, **k: ("/tmp/out.tif", "")))
    qtbot.mouseClick(edit.button, Qt.LeftButton)
    assert edit.text() == "/tmp/out.tif"


def test_window_runs_and_shows_result(qtbot, window, project, tmp_path):
    groups = [window.tree.topLevelItem(i).text(0) for i in range(window.tree.topLevelItemCount())]
    assert "Testing" in groups
    form = window.select_algorithm("fake_sleep_write")
    assert window.statusBar().currentMessage() == "Fake: sleep and write"  # its name, not id
    out = tmp_path / "gui.json"
    form.set_values({"project": str(project), "model": "b_c", "output": str(out),
                     "seconds": 0.5, "steps": 20})
    progress = []
    window.run_panel.progress_bar.valueChanged.connect(progress.append)
    with qtbot.waitSignal(window.run_panel.run_finished, timeout=10000) as blocker:
        qtbot.mouseClick(window.run_panel.run_button, Qt.LeftButton)
        assert not window.run_panel.run_button.isEnabled()
    assert blocker.args[0] == "done"
    assert blocker.args[1] == {"output": str(out), "value": 1.0}
    assert json.loads(out.read_text())["model"] == "b_c"
    assert any(0 < v < 1000 for v in progress) and progress[-1] == 1000
    result = window.run_panel.result_view
    assert [result.topLevelItem(i).text(0) for i in range(result.topLevelItemCount())] == [
        "output", "value"]
    assert "model b_c done" in window.run_panel.log_view.toPlainText()
    assert window.statusBar().currentMessage() == "Fake: sleep and write finished."
    assert window.run_panel.run_button.isEnabled() and form.isEnabled()
    window.grab().save("/tmp/photodem_toolbox.png")


def test_cancel_mid_run_leaves_no_output(qtbot, window, project, tmp_path):
    form = window.select_algorithm("fake_sleep_write")
    out = tmp_path / "cancelled.json"
    form.set_values({"project": str(project), "model": "a_b", "output": str(out),
                     "seconds": 20, "steps": 400})
    qtbot.mouseClick(window.run_panel.run_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: window.run_panel.progress_bar.value() > 0, timeout=10000)
    with qtbot.waitSignal(window.run_panel.run_finished, timeout=10000) as blocker:
        qtbot.mouseClick(window.run_panel.cancel_button, Qt.LeftButton)
    assert blocker.args[0] == "cancelled"
    assert list(tmp_path.glob("*.json")) == [] and list(tmp_path.glob(".*")) == []
    assert "Cancelled" in window.run_panel.log_view.toPlainText()


def test_operator_error_and_bug_are_shown_in_log(qtbot, window, tmp_path):
    window.select_algorithm("fake_chatty")
    window.form.set_values({"input": str(tmp_path / "missing.tif")})
    with qtbot.waitSignal(window.run_panel.run_finished, timeout=10000) as blocker:
        window.run_current()
    assert blocker.args[0] == "failed" and "does not exist" in blocker.args[1]
    assert "Error: Parameter 'input'" in window.run_panel.log_view.toPlainText()
    window.select_algorithm("fake_crash")
    with qtbot.waitSignal(window.run_panel.run_finished, timeout=10000) as blocker:
        window.run_current()
    assert blocker.args[0] == "failed" and "ZeroDivisionError" in blocker.args[1]
    assert "Unexpected error" in window.run_panel.log_view.toPlainText()


def test_runs_back_to_back_and_wait_returns(qtbot, window, tmp_path):
    # A run counts as finished only once its thread has ended: starting the next run at once
    # used to drop the last reference to a thread still winding down (SIGABRT, 1 run in 6).
    window.select_algorithm("fake_chatty")
    window.form.set_values({"input": str(tmp_path / "missing.tif")})
    for _ in range(30):
        with qtbot.waitSignal(window.run_panel.run_finished, timeout=10000) as blocker:
            window.run_current()
        assert blocker.args[0] == "failed" and not window.run_panel.is_running()
    # The GUI thread blocked in wait() does not keep the thread from ending.
    window.run_current()
    assert window.run_panel.wait(5000)


def test_filter_hides_algorithms(qtbot, window):
    qtbot.keyClicks(window.filter_edit, "crash")
    testing = next(window.tree.topLevelItem(i) for i in range(window.tree.topLevelItemCount())
                   if window.tree.topLevelItem(i).text(0) == "Testing")
    visible = [testing.child(j).text(0) for j in range(testing.childCount())
               if not testing.child(j).isHidden()]
    assert visible == ["Fake: crash"]
