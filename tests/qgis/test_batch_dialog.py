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
