"""Tier B: the batch dialog inside QGIS 3.22 — a QgsTask that is cancelled, resumed, ends like
``photodem batch`` on the file it wrote, and adds its products to the workspace."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Iterator

import pytest
from _qgis_helpers import copy_block

pytestmark = pytest.mark.qgis

MODELS = ["0101_0102", "0102_0103"]


@pytest.fixture
def ws_iface(qgis_iface) -> Iterator:
    from photodem.plugin.qgis.workspace import forget_workspace

    yield qgis_iface
    forget_workspace()


def _core(summary):
    """What does not depend on time (skipped = done: the task is complete)."""
    return [(t["step"], t["algorithm"], t["item"], t["hash"], t["outputs"], t["error"],
             t["status"] in ("done", "skipped")) for t in summary["tasks"]]


def test_batch_task_cancel_resume_products(qtbot, ws_iface, tiny_block, tmp_path) -> None:
    from qgis.core import QgsApplication, QgsProject

    from photodem.plugin.qgis import batch_actions
    from photodem.plugin.qgis.workspace import open_workspace
    from photodem.plugin.widgets import batch_dialog as bd

    root = copy_block(tiny_block, tmp_path, "blk")
    ws = open_workspace(ws_iface, root)
    menu = batch_actions.BatchMenu(ws_iface, "PhotoDEM", batch_actions.QIcon())
    menu.register()
    assert menu.action in ws_iface.menus["PhotoDEM"]
    menu.action.trigger()
    d = menu.dialog
    qtbot.addWidget(d)
    assert d.project_folder() == root.resolve()  # the workspace's project
    d.report = lambda text: pytest.fail(text)
    for step, check in d.step_checks.items():
        check.setChecked(step in ("epipolar_pair", "match_model"))
    d.set_checked_models(MODELS)
    d.workers_spin.setValue(1)
    cancelled = []

    def cancel_in_match(index, pct):
        if d._plan.tasks[index].algorithm == "match_model" and pct > 0 and not cancelled:
            cancelled.append(index)
            d.cancel()

    with qtbot.waitSignal(d.batch_finished, timeout=120000):
        assert d.run()
        d.worker.task_progress.connect(cancel_in_match)
        tasks = QgsApplication.taskManager().tasks()
        assert any(t.description().startswith("PhotoDEM batch") for t in tasks)
    assert cancelled and d.summary["status"] == "cancelled"

    d.ask_close = lambda: bd.CLOSE_BACKGROUND  # closing keeps the task running
    with qtbot.waitSignal(d.batch_finished, timeout=120000):
        assert d.resume()
        d.close()
        assert not d.isVisible() and d.is_running()
    from qgis.core import QgsSettings

    remembered = QgsSettings()  # what the dialog remembers, in QGIS's own settings
    assert remembered.value("PhotoDEM/last_project") == str(root.resolve())
    assert set(remembered.value("PhotoDEM/batch/steps")) == {"epipolar_pair", "match_model"}
    final = d.summary
    assert final["status"] == "done" and final["counts"] == {
        "done": 2, "skipped": 2, "failed": 0, "cancelled": 0}

    dsm = str(root.resolve() / "products" / "dsm" / MODELS[0] / "dsm.tif")
    sources = [layer.source() for layer in QgsProject.instance().mapLayers().values()]
    assert dsm in sources, sources  # the products are on the map, in the workspace
    assert ws.root == root.resolve()
    assert any("Batch done" in item.text() for item in ws_iface.messageBar().items())

    cli = subprocess.run([sys.executable, "-m", "photodem.algorithms.cli_entry", "batch",
                          str(d.batch_file), "--workers", "1", "--no-resume", "--json"],
                         capture_output=True, text=True, timeout=300)
    assert cli.returncode == 0, cli.stderr[-2000:]
    by_cli = json.loads(Path(json.loads(cli.stdout)["summary"]).read_text())
    assert by_cli["status"] == "done" and _core(by_cli) == _core(final)
    menu.unregister()


def test_task_manager_cancel_reaches_the_batch(qtbot, ws_iface, chain_project,
                                               monkeypatch) -> None:
    """The cancel button of QGIS's task manager (QgsTask.cancel) stops the batch."""
    fakes = Path(__file__).resolve().parents[1] / "algorithms" / "processing"
    monkeypatch.syspath_prepend(str(fakes))
    import _fake_algs

    from photodem.plugin.qgis import batch_actions

    _fake_algs.install(monkeypatch)
    root = chain_project("abc")
    file = root / "slow.toml"
    file.write_text('[batch]\nproject = "."\nworkers = 1\n[[steps]]\n'
                    'algorithm = "fake_sleep_write"\n[steps.params]\nseconds = 3\nsteps = 60\n'
                    'output = "{project}/products/{step}/{model}.json"\n')
    d = batch_actions.open_batch_dialog(ws_iface, str(root))
    qtbot.addWidget(d)
    assert d.open_batch_file(str(file))
    original = batch_actions.start_batch_task

    def start(worker):
        task = original(worker)
        # the task manager's cancel button calls QgsTask.cancel: here once the first task runs
        worker.task_progress.connect(lambda index, pct: task.cancel() if pct > 0 else None)
        return task

    d.start_worker = start
    with qtbot.waitSignal(d.batch_finished, timeout=60000):
        assert d.run()
    assert d.summary["status"] == "cancelled"
    assert [t["status"] for t in d.summary["tasks"]] == ["cancelled", "cancelled"]
    assert not (root / "products").exists()  # the cancelled task left nothing behind

    # cancelled right after it was queued: QGIS either skips run() (the dialog says so) or
    # runs it with the cancel already set
    def start_cancelled(worker):
        task = original(worker)
        task.cancel()
        return task

    d.start_worker = start_cancelled
    with qtbot.waitSignal(d.batch_finished, timeout=60000):
        assert d.resume()
    assert not d.is_running()
    if d.summary is None:
        assert "cancelled before it started" in d.log_view.toPlainText()
    else:
        assert d.summary["counts"]["cancelled"] == 2


def test_scheduler_typed_in_qgis_goes_into_the_batch_file(qtbot, ws_iface, tiny_block,
                                                           tmp_path) -> None:
    """The Scheduler field of the dialog opened from QGIS's menu, typed with key events."""
    from qgis.PyQt.QtCore import Qt
    from qgis.PyQt.QtTest import QTest

    from photodem.algorithms.project import toml_io
    from photodem.plugin.qgis import batch_actions
    from photodem.plugin.qgis.workspace import open_workspace

    root = copy_block(tiny_block, tmp_path, "blk")
    open_workspace(ws_iface, root)
    menu = batch_actions.BatchMenu(ws_iface, "PhotoDEM", batch_actions.QIcon())
    menu.register()
    menu.action.trigger()
    d = menu.dialog
    qtbot.addWidget(d)
    d.show()
    QTest.mouseClick(d.scheduler_edit, Qt.LeftButton)
    QTest.keyClicks(d.scheduler_edit, "tcp://10.0.0.5:8786")
    written = toml_io.loads(d.write_batch_file().read_text())
    assert written["batch"]["scheduler"] == "tcp://10.0.0.5:8786"
    d.scheduler_edit.clear()  # empty: this machine, nothing in the file
    assert "scheduler" not in toml_io.loads(d.write_batch_file().read_text())["batch"]
