"""The batch dialog (pytest-qt): run, cancel, resume, same summary as ``photodem batch``."""

from __future__ import annotations

import json
import os
import subprocess
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
from photodem.algorithms.project import toml_io  # noqa: E402
from photodem.plugin.qt import QSettings, Qt  # noqa: E402
from photodem.plugin.widgets import batch_dialog as bd  # noqa: E402

MODELS = ["0101_0102", "0102_0103"]


@pytest.fixture(scope="module")
def tiny_block(tmp_path_factory):
    """A tiny synthetic block (≈ 4 s), shared by the tests of this module."""
    root = tmp_path_factory.mktemp("blk") / "block"
    registry.run("synthetic_block", {"output": str(root), "size": "tiny"})
    return root


@pytest.fixture
def settings(tmp_path):
    return QSettings(str(tmp_path / "settings.ini"), QSettings.IniFormat)


@pytest.fixture
def dialog(qtbot, settings):
    def make(project=None, **kwargs):
        d = bd.BatchDialog(project, settings=settings, **kwargs)
        d.report = messages.append
        d.opened = []
        d.open_url = lambda url: d.opened.append(url.toLocalFile())
        qtbot.addWidget(d)
        d.show()
        made.append(d)
        return d

    messages: list = []
    made: list = []
    make.messages = messages
    yield make
    for d in made:
        d.cancel()
        d.wait(60000)


def _summary_core(summary):
    """The fields of a summary that do not depend on time (skipped = done: complete)."""
    tasks = [{k: t[k] for k in ("step", "algorithm", "item", "outputs", "hash", "error")}
             | {"complete": t["status"] in ("done", "skipped")} for t in summary["tasks"]]
    return {"file": summary["file"], "project": summary["project"],
            "status": summary["status"], "tasks": tasks}


def _choose(d, steps, models, workers=1):
    for step, check in d.step_checks.items():
        check.setChecked(step in steps)
    d.set_checked_models(models)
    d.workers_spin.setValue(workers)


def test_run_cancel_resume_equals_the_cli(qtbot, dialog, tiny_block):
    d = dialog(tiny_block)
    names = [d.table.item(r, bd.COL_MODEL).text() for r in range(d.table.rowCount())]
    assert set(MODELS) <= set(names), names
    assert d.table.item(0, bd.COL_EPI).text() == "not run"
    _choose(d, {"epipolar_pair", "match_model"}, MODELS)
    started = []

    def cancel_in_match(index, pct):
        task = d._plan.tasks[index] if d._plan is not None else None
        if task is not None and task.algorithm == "match_model" and pct > 0 and not started:
            started.append(index)
            d.cancel()

    with qtbot.waitSignal(d.batch_started, timeout=10000):
        assert d.run()
    d.worker.task_progress.connect(cancel_in_match)
    assert not d.run_button.isEnabled() and d.cancel_button.isEnabled()
    with qtbot.waitSignal(d.batch_finished, timeout=120000):
        pass
    assert started, "the cancel came too late"
    first = d.summary
    assert first["status"] == "cancelled"
    assert [t["status"] for t in first["tasks"]][:2] == ["done", "done"]
    batch_file = d.batch_file
    assert batch_file.parent == tiny_block.resolve() / ".photodem" / "batches"
    assert d.resume_button.isEnabled()

    with qtbot.waitSignal(d.batch_finished, timeout=120000):
        assert d.resume()
    final = d.summary
    assert final["status"] == "done" and final["counts"]["skipped"] == 2
    assert final["counts"]["done"] == 2
    for row in range(d.table.rowCount()):
        name = d.table.item(row, bd.COL_MODEL).text()
        if name in MODELS:
            assert d.table.item(row, bd.COL_STATE).text() == "done"
            assert d.table.item(row, bd.COL_MATCH).text() == "done"
            assert d.table.cellWidget(row, bd.COL_PROGRESS).value() == 1000
    dsms = [p for p in d.products if p.endswith("dsm.tif")]
    assert len(dsms) == 2 and d.product_list.count() == len(d.products)
    d.product_list.setCurrentRow(0)
    d.product_folder.click()
    assert d.opened[-1] == str(Path(d.products[0]).parent)
    row = next(r.row for n, r in d._rows.items() if n == MODELS[0])
    d.table.cellDoubleClicked.emit(row, 0)
    assert d.opened[-1].endswith(f"match_model/{MODELS[0]}.log")

    # the same batch from the command line, computing everything again
    cli = subprocess.run([sys.executable, "-m", "photodem.algorithms.cli_entry", "batch",
                          str(batch_file), "--workers", "1", "--no-resume", "--json"],
                         capture_output=True, text=True, timeout=300)
    if cli.returncode != 0 and "No module named" in cli.stderr:
        cli = subprocess.run([str(Path(sys.executable).with_name("photodem")), "batch",
                              str(batch_file), "--workers", "1", "--no-resume", "--json"],
                             capture_output=True, text=True, timeout=300)
    assert cli.returncode == 0, cli.stderr[-2000:]
    by_cli = json.loads(Path(json.loads(cli.stdout)["summary"]).read_text())
    assert by_cli["counts"]["done"] == 4
    assert _summary_core(by_cli) == _summary_core(final)


def test_failed_models_show_their_reason_and_run_again_alone(qtbot, dialog, chain_project,
                                                             monkeypatch):
    _fake_algs.install(monkeypatch)
    root = chain_project("abc")
    d = dialog(root)
    batch_file = root / "my-batch.toml"
    batch_file.write_text(
        '[batch]\nproject = "."\nworkers = 1\n[[steps]]\nalgorithm = "fake_fail_on"\n'
        'models = ["a_b", "b_c"]\n[steps.params]\nfail = "b_c"\n'
        'output = "{project}/products/{step}/{model}.txt"\n')
    assert d.open_batch_file(str(batch_file))
    assert d.checked_models() == ["a_b", "b_c"]
    assert not d.step_checks["match_model"].isEnabled()  # the file runs as written
    with qtbot.waitSignal(d.batch_finished, timeout=30000):
        d.run()
    assert d.summary["status"] == "failed"
    state = d.table.item(d._rows["b_c"].row, bd.COL_STATE).text()
    assert state.startswith("failed: model b_c is broken")
    assert d.rerun_button.isEnabled()
    batch_file.write_text(batch_file.read_text().replace('fail = "b_c"', 'fail = ""'))
    with qtbot.waitSignal(d.batch_finished, timeout=30000):
        assert d.rerun_failed()
    assert [t["item"] for t in d.summary["tasks"]] == ["b_c"]
    assert d.summary["status"] == "done"
    assert d.table.item(d._rows["b_c"].row, bd.COL_STATE).text() == "done"
    assert d.table.item(d._rows["a_b"].row, bd.COL_STATE).text() == "done"  # from before


def test_image_list_batch_file(qtbot, dialog, tmp_path, monkeypatch):
    _fake_algs.install(monkeypatch)
    scenes = tmp_path / "scenes"
    scenes.mkdir()
    for name, size in (("s1.tif", 1), ("s2.tif", 22)):
        (scenes / name).write_bytes(b"x" * size)
    file = tmp_path / "files.toml"
    file.write_text('[batch]\nworkers = 1\n[[steps]]\nalgorithm = "fake_file_size"\n'
                    'files = "scenes/*.tif"\n[steps.params]\n'
                    'output = "out/{step}/{file}.txt"\n')
    d = dialog()
    assert d.open_batch_file(str(file))
    assert [d.table.item(r, bd.COL_MODEL).text() for r in range(2)] == ["s1", "s2"]
    with qtbot.waitSignal(d.batch_finished, timeout=30000):
        d.run()
    assert d.summary["status"] == "done"
    assert (tmp_path / "out" / "fake_file_size" / "s2.txt").read_text() == "22"
    assert d.table.item(1, bd.COL_STATE).text() == "done"


def test_closing_while_running_asks(qtbot, dialog, chain_project, monkeypatch):
    _fake_algs.install(monkeypatch)
    root = chain_project("abc")
    file = root / "slow.toml"
    file.write_text('[batch]\nproject = "."\nworkers = 1\n[[steps]]\n'
                    'algorithm = "fake_sleep_write"\n[steps.params]\nseconds = 3\nsteps = 60\n'
                    'output = "{project}/products/{step}/{model}.json"\n')
    d = dialog(root)
    assert d.open_batch_file(str(file))
    d.ask_close = lambda: bd.CLOSE_STAY
    d.run()
    d.close()
    assert d.isVisible() and d.is_running()
    d.ask_close = lambda: bd.CLOSE_BACKGROUND
    with qtbot.waitSignal(d.backgrounded, timeout=5000):
        d.close()
    assert not d.isVisible() and d.is_running()  # still running, hidden
    d.ask_close = lambda: bd.CLOSE_CANCEL
    d.show()
    with qtbot.waitSignal(d.batch_finished, timeout=30000):
        d.close()
    assert d.summary["status"] == "cancelled"


def test_choices_are_remembered(qtbot, dialog, settings, tiny_block):
    d = dialog(tiny_block)
    _choose(d, {"match_model", "dsm_merge", "filter"}, MODELS, workers=3)
    d.filter_preset.setCurrentIndex(d.filter_preset.findData("urban"))
    d.scheduler_edit.setText("tcp://10.0.0.5:8786")
    written = toml_io.loads(d.write_batch_file().read_text())
    assert written["batch"]["scheduler"] == "tcp://10.0.0.5:8786"
    d.close()
    again = dialog()
    assert again.project_edit.text() == str(tiny_block.resolve())
    assert {s for s, c in again.step_checks.items() if c.isChecked()} == {
        "match_model", "dsm_merge", "filter"}
    assert again.filter_preset.currentData() == "urban"
    assert again.workers_spin.value() == 3
    assert again.scheduler_edit.text() == "tcp://10.0.0.5:8786"
    again.scheduler_edit.setText("")  # empty: this machine, no scheduler in the file
    assert "scheduler" not in toml_io.loads(again.write_batch_file().read_text())["batch"]


def test_bad_input_is_reported(qtbot, dialog, tmp_path):
    d = dialog(tmp_path)
    assert not d.run_button.isEnabled()  # no project.toml there
    bad = tmp_path / "bad.toml"
    bad.write_text("[[steps]]\nalgorithm = \"no_such_algorithm\"\n")
    assert not d.open_batch_file(str(bad))
    assert "no_such_algorithm" in dialog.messages[-1]
    assert Qt.Checked  # the module imports Qt for the check states


def test_main_window_shows_a_batch_running_in_the_background(qtbot, settings, chain_project,
                                                             monkeypatch):
    from photodem.plugin.app.main_window import ToolboxWindow

    _fake_algs.install(monkeypatch)
    root = chain_project("abc")
    file = root / "slow.toml"
    file.write_text('[batch]\nproject = "."\nworkers = 1\n[[steps]]\n'
                    'algorithm = "fake_sleep_write"\n[steps.params]\nseconds = 3\nsteps = 60\n'
                    'output = "{project}/products/{step}/{model}.json"\n')
    w = ToolboxWindow(message_boxes=False, settings=settings)
    qtbot.addWidget(w)
    w.show()
    d = w.open_batch_dialog(str(root))
    assert d.project_folder() == root.resolve() and d.open_batch_file(str(file))
    d.run()
    d.ask_close = lambda: bd.CLOSE_BACKGROUND
    d.close()
    assert w.batch_button.isVisible() and not d.isVisible()
    w.batch_button.click()  # shows the running dialog again
    assert d.isVisible() and w.open_batch_dialog() is d
    d.hide()
    with qtbot.waitSignal(d.batch_finished, timeout=30000):
        d.cancel()
    assert not w.batch_button.isVisible()
    assert "cancelled" in w.statusBar().currentMessage()
    d.wait(10000)
