"""Background runs: a PhotoDEM algorithm as a task of QGIS's task manager, in real QGIS."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Dict, List

import pytest
from _qgis_helpers import copy_block

pytestmark = pytest.mark.qgis

MODEL = "0101_0102"


@pytest.fixture(scope="module")
def tiny_project(tmp_path_factory, tiny_block) -> Path:
    """The tiny synthetic project (6 images, 4 in-strip stereo models)."""
    root = copy_block(tiny_block, tmp_path_factory.mktemp("bg"), "block")
    return root


class StandInWorkspace:
    """The workspace contract's ``add_products``, recording what it was given."""

    def __init__(self) -> None:
        self.added: List[List[str]] = []

    def add_products(self, paths) -> list:
        self.added.append(list(paths))
        return []


@pytest.fixture
def workspace(monkeypatch) -> StandInWorkspace:
    from photodem.plugin.qgis import background

    stand_in = StandInWorkspace()
    monkeypatch.setattr(background, "current_workspace", lambda: stand_in)
    return stand_in


def _wait(qtbot, calls: list, timeout_ms: int = 120000) -> None:
    qtbot.waitUntil(lambda: len(calls) > 0, timeout=timeout_ms)


def test_match_model_runs_as_a_task_and_hands_its_dsm_to_the_workspace(
        qgis_iface, provider, tiny_project, workspace, qtbot):
    from qgis.core import QgsApplication

    from photodem.plugin.qgis.background import run_in_background, running_tasks

    calls: List[Any] = []
    task = run_in_background("match_model", {"project": str(tiny_project), "model": MODEL},
                             lambda ok, results: calls.append((ok, dict(results))),
                             iface=qgis_iface)
    assert task in QgsApplication.taskManager().tasks()
    assert MODEL in task.description()
    assert running_tasks()
    _wait(qtbot, calls)
    ok, results = calls[0]
    assert ok is True
    dsm = Path(results["dsm"])
    assert dsm == tiny_project / "products" / "dsm" / MODEL / "dsm.tif"
    assert dsm.is_file()
    assert workspace.added and str(dsm) == workspace.added[0][0]
    assert all(Path(p).suffix in (".tif", ".gpkg") for p in workspace.added[0])
    assert not running_tasks()


def test_cancel_ends_with_false_and_leaves_no_product(
        qgis_iface, provider, tiny_project, workspace, qtbot):
    from qgis.core import QgsTask

    from photodem.plugin.qgis.background import run_in_background

    model = "0201_0202"
    calls: List[Any] = []
    progress: List[float] = []
    task = run_in_background("match_model", {"project": str(tiny_project), "model": model},
                             lambda ok, results: calls.append((ok, dict(results))),
                             iface=qgis_iface)
    task.progressChanged.connect(lambda value: progress.append(float(value)))
    # cancel while it runs (after the first progress), like the task manager's cancel button
    qtbot.waitUntil(lambda: bool(task.status() == QgsTask.Running and progress), timeout=60000)
    task.cancel()
    _wait(qtbot, calls)
    assert calls[0][0] is False
    assert workspace.added == []
    out = tiny_project / "products" / "dsm" / model
    assert not out.exists() or not any(out.iterdir())
    texts = [w.text() for w in qgis_iface.messageBar().items()]
    assert any("cancel" in t.lower() for t in texts), texts


def test_a_failing_run_reports_in_the_message_bar(qgis_iface, provider, tiny_project,
                                                  workspace, qtbot):
    from photodem.plugin.qgis.background import run_in_background

    calls: List[Any] = []
    run_in_background("match_model", {"project": str(tiny_project), "model": "nope_nope"},
                      lambda ok, results: calls.append((ok, dict(results))), iface=qgis_iface)
    _wait(qtbot, calls)
    assert calls == [(False, {})]
    texts = [w.text() for w in qgis_iface.messageBar().items()]
    assert any("nope_nope" in t for t in texts), texts
    assert workspace.added == []


def test_without_a_workspace_products_go_to_the_map(qgis_iface, provider, tiny_project,
                                                    monkeypatch):
    from qgis.core import QgsProject

    from photodem.plugin.qgis import background

    monkeypatch.setattr(background, "current_workspace", lambda: None)
    dsm = tiny_project / "truth" / "dsm.tif"
    layers = background.add_products([str(dsm)])
    assert len(layers) == 1 and layers[0].isValid()
    assert QgsProject.instance().mapLayer(layers[0].id()) is not None


def test_product_paths_are_the_existing_raster_and_vector_outputs(tmp_path):
    from photodem.plugin.qgis.background import product_paths

    dsm = tmp_path / "dsm.tif"
    dsm.write_bytes(b"x")
    results: Dict[str, Any] = {"dsm": str(dsm), "count": str(tmp_path / "missing.tif"),
                               "report": str(dsm), "metrics": "{}"}
    assert product_paths("match_model", results) == [str(dsm)]
    assert product_paths("no_such_algorithm", results) == []


def test_a_task_that_cannot_start_still_calls_back(qgis_iface, provider, tiny_project,
                                                   workspace, qtbot, monkeypatch):
    """QgsProcessingAlgRunnerTask cancels itself when preparing the algorithm fails."""
    from qgis.core import QgsApplication, QgsProcessingAlgRunnerTask

    from photodem.plugin.qgis import background

    def failing_prepare(*args):
        task = QgsProcessingAlgRunnerTask(*args)
        task.cancel()
        return task

    monkeypatch.setattr(background, "QgsProcessingAlgRunnerTask", failing_prepare)
    calls: List[Any] = []
    task = background.run_in_background(
        "match_model", {"project": str(tiny_project), "model": MODEL},
        lambda ok, results: calls.append((ok, dict(results))), iface=qgis_iface)
    assert task not in QgsApplication.taskManager().tasks()
    _wait(qtbot, calls, 5000)
    assert calls == [(False, {})] and workspace.added == []
    assert not background.running_tasks()
