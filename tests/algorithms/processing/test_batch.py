"""Batch runner: planning, running in-process and on worker processes, resume, cancel."""

from __future__ import annotations

import json
import sys
import threading
import time

import pytest

from photodem.algorithms.errors import InputError
from photodem.algorithms.feedback import Feedback
from photodem.algorithms.processing import batch
from photodem.algorithms.project import toml_io


def _config(project_dir, steps, **head):
    return {"batch": {"project": str(project_dir), **head}, "steps": steps}


def _sleep_step(**params):
    return {"algorithm": "fake_sleep_write", "name": "sleep",
            "params": {"seconds": 0.05, "output": "{project}/products/{step}/{model}.json",
                       **params}}


def _fail_step():
    return {"algorithm": "fake_fail_on", "name": "check", "models": ["a_b", "b_c"],
            "params": {"fail": "a_b", "output": "{project}/products/{step}/{model}.txt"}}


def test_plan_expands_models_and_placeholders(fake_algs, project_dir, tmp_path):
    plan = batch.plan_batch(_config(project_dir, [_sleep_step(note="{run}|{step}|{model}")]),
                            run_dir=tmp_path / "run")
    assert [t.item for t in plan.tasks] == ["a_b", "b_c", "c_d"]
    t = plan.tasks[1]
    assert t.params["model"] == "b_c"
    assert t.params["project"] == str(project_dir.resolve())
    assert t.params["output"] == f"{project_dir.resolve()}/products/sleep/b_c.json"
    assert t.params["note"] == f"{(tmp_path / 'run').resolve()}|sleep|b_c"
    assert t.log == (tmp_path / "run").resolve() / "sleep" / "b_c.log"
    assert t.key == "sleep/b_c"
    # default run folder: <project>/runs/<timestamp>
    plan = batch.plan_batch(_config(project_dir, [_sleep_step()]))
    assert plan.run_dir.parent == project_dir.resolve() / "runs"


@pytest.mark.parametrize(("steps", "message"), [
    ([{"algorithm": "nope"}], "No algorithm"),
    ([{"algorithm": "fake_sleep_write", "models": ["x_y"]}], "not in the project"),
    ([{"algorithm": "fake_sleep_write", "images": "all"}], "iterates over models"),
    ([{"algorithm": "fake_crash", "models": "all"}], "does not iterate"),
    ([{"algorithm": "fake_crash", "params": {"x": "{model}"}}], "does not run per model"),
    ([{"algorithm": "fake_crash", "nmae": "x"}], "unknown key"),
    ([{"algorithm": "fake_crash"}, {"algorithm": "fake_crash"}], "two steps are named"),
    ([], "no [[steps]]"),
])
def test_plan_errors_are_operator_errors(fake_algs, project_dir, steps, message):
    with pytest.raises(InputError, match=message.replace("[", r"\[")):
        batch.plan_batch(_config(project_dir, steps))


def test_load_batch_relative_project_and_bad_workers(fake_algs, project_dir):
    file = project_dir.parent / "b.toml"
    file.write_text('[batch]\nproject = "proj"\nworkers = 0\n[[steps]]\nalgorithm = "fake_crash"\n')
    with pytest.raises(InputError, match="workers"):
        batch.load_batch(file)
    file.write_text('[batch]\nproject = "proj"\noutput = "{project}/runs/x"\n'
                    '[[steps]]\nalgorithm = "fake_crash"\n')
    plan = batch.load_batch(file)
    assert plan.project == project_dir.resolve()
    assert plan.run_dir == project_dir.resolve() / "runs" / "x"
    with pytest.raises(InputError, match="not a PhotoDEM project"):
        batch.plan_batch({"batch": {"project": str(project_dir / "missing")},
                          "steps": [{"algorithm": "fake_crash"}]})


def test_run_in_process_failures_logs_summary_and_resume(fake_algs, project_dir, tmp_path):
    steps = [_fail_step(), _sleep_step()]
    plan = batch.plan_batch(_config(project_dir, steps), run_dir=tmp_path / "r1")
    seen = []
    summary = batch.run_batch(plan, Feedback(on_progress=seen.append), workers=1)
    status = {(t["step"], t["item"]): t["status"] for t in summary["tasks"]}
    assert status == {("check", "a_b"): "failed", ("check", "b_c"): "done",
                      ("sleep", "a_b"): "failed", ("sleep", "b_c"): "done",
                      ("sleep", "c_d"): "done"}
    assert summary["status"] == "failed"
    assert summary["counts"] == {"done": 3, "skipped": 0, "failed": 2, "cancelled": 0}
    errors = {(t["step"], t["item"]): t["error"] for t in summary["tasks"]}
    assert "a_b is broken" in errors[("check", "a_b")]
    assert "not run because step 'check' failed" in errors[("sleep", "a_b")]
    assert seen and seen[-1] == pytest.approx(100.0) and seen == sorted(seen)
    on_disk = json.loads((tmp_path / "r1" / "summary.json").read_text())
    assert on_disk["counts"] == summary["counts"]
    assert "a_b is broken" in (tmp_path / "r1" / "check" / "a_b.log").read_text()
    assert "model b_c done" in (tmp_path / "r1" / "sleep" / "b_c.log").read_text()
    assert (project_dir / "products" / "sleep" / "c_d.json").is_file()
    assert not (project_dir / "products" / "sleep" / "a_b.json").exists()

    # resume: completed tasks are skipped, the failed ones run again
    (project_dir / "products" / "sleep" / "c_d.json").unlink()  # an output went missing
    plan = batch.plan_batch(_config(project_dir, steps), run_dir=tmp_path / "r2")
    summary = batch.run_batch(plan, workers=1)
    status = {(t["step"], t["item"]): t["status"] for t in summary["tasks"]}
    assert status[("check", "b_c")] == "skipped"
    assert status[("sleep", "b_c")] == "skipped"
    assert status[("sleep", "c_d")] == "done"
    assert status[("check", "a_b")] == "failed"
    skipped = next(t for t in summary["tasks"] if t["status"] == "skipped")
    assert skipped["outputs"]["output"].endswith(".txt")

    # changed parameters or --no-resume: run again
    steps[1]["params"]["seconds"] = 0.01
    plan = batch.plan_batch(_config(project_dir, steps), run_dir=tmp_path / "r3")
    summary = batch.run_batch(plan, workers=1)
    status = {(t["step"], t["item"]): t["status"] for t in summary["tasks"]}
    assert status[("sleep", "b_c")] == "done" and status[("check", "b_c")] == "skipped"
    summary = batch.run_batch(plan, workers=1, resume=False)
    assert summary["counts"]["skipped"] == 0


def test_run_on_two_worker_processes(fake_algs, project_dir, tmp_path):
    plan = batch.plan_batch(_config(project_dir, [_sleep_step(seconds=0.3)], workers=2),
                            run_dir=tmp_path / "run")
    seen = []
    start = time.perf_counter()
    summary = batch.run_batch(plan, Feedback(on_progress=seen.append))
    elapsed = time.perf_counter() - start
    assert summary["status"] == "done", summary
    assert summary["workers"] == 2
    for name in ("a_b", "b_c", "c_d"):
        data = json.loads((project_dir / "products" / "sleep" / f"{name}.json").read_text())
        assert data["model"] == name
    assert seen[-1] == pytest.approx(100.0)
    assert any(0 < p < 100 for p in seen)  # intra-task progress came through the queue
    assert elapsed < 20


def _no_outputs(project_dir):
    products = project_dir / "products"
    return [] if not products.exists() else [p for p in products.rglob("*") if p.is_file()]


def test_cancel_in_process_leaves_no_output(fake_algs, project_dir, tmp_path):
    plan = batch.plan_batch(_config(project_dir, [_sleep_step(seconds=2.0, steps=100)]),
                            run_dir=tmp_path / "run")
    feedback = Feedback()
    feedback._on_progress = lambda pct: feedback.cancel() if pct > 5 else None
    summary = batch.run_batch(plan, feedback, workers=1)
    assert summary["status"] == "cancelled"
    assert summary["counts"]["cancelled"] == 3
    assert _no_outputs(project_dir) == []


def test_cancel_worker_processes_leaves_no_output(fake_algs, project_dir, tmp_path):
    second = dict(_sleep_step(seconds=0.1), name="after")  # waits for the first: not run
    plan = batch.plan_batch(_config(project_dir, [_sleep_step(seconds=20.0, steps=400), second],
                                    workers=2), run_dir=tmp_path / "run")
    class CancelWhenRunning(Feedback):
        def task_progress(self, index, pct):  # a task reported progress: it runs
            if pct > 0:
                self.cancel()

    feedback = CancelWhenRunning()
    timer = threading.Timer(15.0, feedback.cancel)  # in case no progress came through
    timer.start()
    start = time.perf_counter()
    summary = batch.run_batch(plan, feedback)
    timer.cancel()
    assert summary["status"] == "cancelled"
    assert [t["status"] for t in summary["tasks"]] == ["cancelled"] * 6
    logs = [(tmp_path / "run" / "sleep" / f"{m}.log").read_text()
            for m in ("a_b", "b_c") if (tmp_path / "run" / "sleep" / f"{m}.log").exists()]
    assert any("Cancelled" in text or "cancel" in text.lower() for text in logs), logs
    # stopped cooperatively, not after 20 s (the local Dask cluster's start and stop: 2–5 s)
    assert time.perf_counter() - start < 12.0
    assert _no_outputs(project_dir) == []


def test_template_is_a_valid_batch_file(fake_algs, project_dir):
    text = batch.batch_template(project_dir)
    config = toml_io.loads(text)
    assert config["batch"]["project"] == str(project_dir)
    assert config["steps"]
    for step in config["steps"]:
        assert step["algorithm"]


# -- batches over image files (no project) -------------------------------------------------------
def _scenes(root):
    (root / "scenes").mkdir(parents=True)
    for name in ("s2", "s1", "bad3"):
        (root / "scenes" / f"{name}.tif").write_bytes(b"x" * len(name))
    (root / "other").mkdir()
    (root / "other" / "s9.tif").write_bytes(b"y")
    return root


def _file_step(files, **params):
    return {"algorithm": "fake_file_size", "name": "size", "files": files,
            "params": {"output": "{run}/{step}/{file}.txt", **params}}


def test_plan_over_files_without_a_project(fake_algs, tmp_path):
    root = _scenes(tmp_path / "b")
    config = {"batch": {"workers": 1},
              "steps": [_file_step(["scenes/s*.tif", "other/s9.tif", "scenes/s1.tif"])]}
    plan = batch.plan_batch(config, base_dir=root)
    assert plan.project is None
    assert plan.run_dir.parent == root.resolve() / "runs"  # beside the batch file
    assert plan.state_home == root.resolve()
    # sorted per pattern, each file once, {file} = the name without suffix
    assert [t.name for t in plan.tasks] == ["s1", "s2", "s9"]
    t = plan.tasks[0]
    assert t.params["image"] == str((root / "scenes" / "s1.tif").resolve())
    assert t.params["output"] == f"{plan.run_dir}/size/s1.txt"
    assert t.key == "size/s1" and t.log == plan.run_dir / "size" / "s1.log"
    assert batch.plan_batch({"steps": [_file_step("scenes/*.tif")]}, base_dir=root
                            ).to_dict()["project"] is None


@pytest.mark.parametrize(("step", "message"), [
    (_file_step(None), "needs files"),
    (_file_step("nothing/*.tif"), "no file matches"),
    (_file_step(["scenes/missing.tif"]), "does not exist"),
    (_file_step(["scenes/s1.tif", "other/s1.tif"]), "does not exist"),
    (_file_step("scenes/*.tif", output="{project}/x/{file}"), "has no project"),
    (_file_step("scenes/*.tif", output="{model}"), "does not run per model"),
    ({"algorithm": "fake_sleep_write", "models": "all"}, "needs a project"),
    ({"algorithm": "fake_file_size", "models": "all"}, "iterates over files"),
    ({"algorithm": "fake_crash", "files": "scenes/*.tif"}, "does not iterate"),
])
def test_file_batch_errors_are_operator_errors(fake_algs, tmp_path, step, message):
    root = _scenes(tmp_path / "b")
    with pytest.raises(InputError, match=message):
        batch.plan_batch({"steps": [step]}, base_dir=root)


def test_file_names_must_be_unique(fake_algs, tmp_path):
    root = _scenes(tmp_path / "b")
    (root / "other" / "s1.tif").write_bytes(b"z")
    with pytest.raises(InputError, match="same name"):
        batch.plan_batch({"steps": [_file_step(["scenes/s1.tif", "other/s1.tif"])]},
                         base_dir=root)


def test_file_batch_runs_past_a_failure_and_resumes(fake_algs, tmp_path):
    root = _scenes(tmp_path / "b")
    file = root / "batch.toml"
    file.write_text('[batch]\nworkers = 1\noutput = "runs/one"\n[[steps]]\n'
                    'algorithm = "fake_file_size"\nname = "size"\nfiles = "scenes/*.tif"\n'
                    '[steps.params]\noutput = "out/{step}/{file}.txt"\n')
    summary = batch.run_batch(batch.load_batch(file))
    assert summary["status"] == "failed" and summary["project"] is None
    status = {r["item"].rsplit("/", 1)[-1]: r["status"] for r in summary["tasks"]}
    assert status == {"bad3.tif": "failed", "s1.tif": "done", "s2.tif": "done"}
    assert (root / "out" / "size" / "s2.txt").read_text() == "2"
    assert not (root / "out" / "size" / "bad3.txt").exists()
    assert (root / ".photodem" / "batch-state.json").is_file()
    again = batch.run_batch(batch.load_batch(file, run_dir=root / "runs" / "two"))
    assert again["counts"]["skipped"] == 2 and again["counts"]["failed"] == 1


def test_relative_raster_lists_are_taken_from_the_batch_file_folder(tmp_path):
    # "a.tif,b.tif" is split as the parameter splits it, then every part is anchored
    from photodem.algorithms.processing import registry

    alg = registry.algorithms()["dsm_merge"]
    base = tmp_path / "b"
    expected = [str(base.resolve() / "a.tif"), str(base.resolve() / "m" / "b.tif")]
    assert batch._anchored(alg, "inputs", "a.tif, m/b.tif", base) == expected
    assert batch._anchored(alg, "inputs", ["a.tif", "m/b.tif"], base) == expected


# -- Dask (issue 24): what needs no cluster ------------------------------------------------------
def _task(index, step, item=None, kind=None):
    return batch.Task(index=index, step=step, algorithm="x", item=item,
                      item_kind=kind if item is not None else None, params={}, log=None)


def test_a_task_waits_for_the_earlier_steps_of_its_item_and_for_steps_without_items():
    from photodem.algorithms.processing.batch_dask import dependencies

    tasks = [_task(0, "epi", "a", "model"), _task(1, "epi", "b", "model"),
             _task(2, "match", "a", "model"), _task(3, "match", "b", "model"),
             _task(4, "merge"),
             _task(5, "ortho", "1", "image"), _task(6, "ortho", "2", "image"),
             _task(7, "check", "a", "model")]
    assert dependencies(tasks) == {
        0: [], 1: [], 2: [0], 3: [1],  # model b is not held up by model a
        4: [0, 1, 2, 3],  # a step without items waits for everything before it
        5: [0, 1, 2, 3, 4], 6: [0, 1, 2, 3, 4],  # another kind of item: every earlier task
        7: [0, 2, 4, 5, 6],
    }


def test_without_dask_more_workers_say_how_to_install_it(fake_algs, project_dir, tmp_path,
                                                         monkeypatch, capsys):
    from photodem.algorithms import cli

    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed fails
    plan = batch.plan_batch(_config(project_dir, [_sleep_step()], workers=2),
                            run_dir=tmp_path / "run")
    with pytest.raises(InputError, match=r'pip install "photodem\[dask\]"') as info:
        batch.run_batch(plan)
    assert "apt install python3-distributed" in str(info.value)
    assert not (tmp_path / "run").exists()  # refused before the lock and the run folder
    assert not (project_dir / ".photodem" / "batch.lock").exists()
    file = project_dir.parent / "b.toml"
    file.write_text(toml_io.dumps(_config(project_dir, [_sleep_step()], workers=2,
                                          output=str(tmp_path / "run"))))
    assert cli.main(["batch", str(file), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "python3-distributed" in err
    assert cli.main(["batch", str(file), "--quiet", "--workers", "1"]) == 0  # in-process


@pytest.mark.parametrize("address", ["tcp://10.0.0.5", "tcp://a b:8786", "http://x/y:1"])
def test_a_bad_scheduler_address_is_an_operator_error(fake_algs, project_dir, address):
    with pytest.raises(InputError, match="tcp://host:port"):
        batch.plan_batch(_config(project_dir, [_sleep_step()], scheduler=address))


def test_the_command_line_scheduler_wins_over_the_batch_file(fake_algs, project_dir, capsys):
    from photodem.algorithms import cli

    file = project_dir.parent / "b.toml"
    file.write_text(toml_io.dumps(_config(project_dir, [_sleep_step()],
                                          scheduler="tcp://10.0.0.5:8786")))
    assert batch.load_batch(file).scheduler == "tcp://10.0.0.5:8786"
    assert cli.main(["batch", str(file), "--dry-run"]) == 0
    assert "scheduler: tcp://10.0.0.5:8786" in capsys.readouterr().out
    assert cli.main(["batch", str(file), "--dry-run", "--scheduler", "tcp://h:1"]) == 0
    assert "scheduler: tcp://h:1" in capsys.readouterr().out
    for local in ("", "local"):
        assert cli.main(["batch", str(file), "--dry-run", "--scheduler", local]) == 0
        assert "scheduler: this machine" in capsys.readouterr().out


def test_an_unreachable_scheduler_is_one_line(fake_algs, project_dir, tmp_path, monkeypatch):
    pytest.importorskip("distributed")
    import socket

    from photodem.algorithms.processing import batch_dask

    monkeypatch.setattr(batch_dask, "CONNECT_TIMEOUT_S", 1.0)
    with socket.socket() as s:  # a free port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    plan = batch.plan_batch(_config(project_dir, [_sleep_step()]), run_dir=tmp_path / "run")
    with pytest.raises(InputError, match="Cannot reach the Dask scheduler") as info:
        batch.run_batch(plan, scheduler=f"tcp://127.0.0.1:{port}")
    assert "\n" not in str(info.value)
    assert not (project_dir / ".photodem" / "batch.lock").exists()
