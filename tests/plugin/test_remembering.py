"""The standalone toolbox remembers (pytest-qt): last project, the input of each parameter, the
window layout; switching algorithms keeps project and input; results offer Open / Show in
folder / Open report."""

from __future__ import annotations

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

from photodem.plugin.app.main_window import ToolboxWindow  # noqa: E402
from photodem.plugin.qt import QSettings  # noqa: E402


@pytest.fixture
def fakes(monkeypatch):
    _fake_algs.install(monkeypatch)


@pytest.fixture
def settings(tmp_path):
    return QSettings(str(tmp_path / "toolbox.ini"), QSettings.IniFormat)


@pytest.fixture
def make_window(qtbot, fakes, settings):
    made = []

    def make():
        w = ToolboxWindow(message_boxes=False, settings=settings)
        qtbot.addWidget(w)
        w.show()
        made.append(w)
        return w

    yield make
    for w in made:
        w.run_panel.cancel()
        w.run_panel.wait(10000)


def test_input_project_and_layout_are_remembered(qtbot, make_window, chain_project,
                                                 tmp_path):
    project = chain_project("abc")
    w = make_window()
    form = w.select_algorithm("fake_sleep_write")
    form.set_values({"project": str(project), "model": "b_c", "seconds": 0.1,
                     "note": "keep me", "output": str(tmp_path / "o.json")})
    w.resize(900, 640)
    w.splitter.setSizes([250, 650])
    sizes = w.splitter.sizes()
    w.close()

    again = make_window()
    assert again.algorithm.id == "fake_sleep_write"  # the algorithm shown last
    values = again.form.values()
    assert values["project"] == str(project) and values["model"] == "b_c"
    assert values["note"] == "keep me" and values["seconds"] == 0.1
    assert again.size().width() == 900 and again.splitter.sizes() == sizes


def test_switching_algorithms_keeps_project_and_input(qtbot, make_window, chain_project):
    project = chain_project("abc")
    w = make_window()
    form = w.select_algorithm("fake_sleep_write")
    form.set_values({"project": str(project), "model": "b_c", "note": "x"})
    other = w.select_algorithm("fake_fail_on")
    assert other.values()["project"] == str(project)
    assert other.values()["model"] == "b_c"
    back = w.select_algorithm("fake_sleep_write")  # its own input comes back
    assert back.values()["note"] == "x"
    chatty = w.select_algorithm("fake_chatty")  # no project parameter: nothing to keep
    assert "project" not in chatty.values()


def test_last_project_fills_a_new_form(qtbot, make_window, settings, chain_project):
    project = chain_project("abc")
    settings.setValue("PhotoDEM/last_project", str(project))
    w = make_window()
    assert w.select_algorithm("fake_fail_on").values()["project"] == str(project)


def test_result_outputs_open_show_in_folder_and_report(qtbot, make_window, chain_project,
                                                       tmp_path):
    project = chain_project("abc")
    w = make_window()
    opened = []
    w.run_panel.open_url = lambda url: opened.append(url.toString()) or True
    form = w.select_algorithm("fake_sleep_write")
    out = tmp_path / "res.json"
    form.set_values({"project": str(project), "model": "a_b", "output": str(out)})
    with qtbot.waitSignal(w.run_panel.run_finished, timeout=10000):
        w.run_current()
    panel = w.run_panel
    assert panel.output_paths() == [str(out)]
    item = panel.result_view.topLevelItem(0)
    buttons = panel.result_view.itemWidget(item, 2).findChildren(
        type(panel.result_view.itemWidget(item, 2).layout().itemAt(0).widget()))
    assert [b.text() for b in buttons] == ["Open", "Show in folder"]
    buttons[0].click()
    buttons[1].click()
    assert opened == [f"file://{out}", f"file://{tmp_path}"]
    assert not panel.report_button.isEnabled()  # this algorithm writes no report
    report = tmp_path / "report.html"
    report.write_text("<html></html>")
    panel._payload = {"report_html": str(report)}
    panel.show_result(panel._payload)
    assert panel.report_button.isEnabled()
    panel.report_button.click()
    assert opened[-1] == f"file://{report}"
