"""Batch safety (issue 16, point 5): lost workers, the parent's death, the lock, run folders."""

from __future__ import annotations

import datetime as dt
import json
import os
import random
import re
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from photodem.algorithms.errors import InputError
from photodem.algorithms.feedback import Feedback
from photodem.algorithms.output_policy import PRODUCT_MARKER
from photodem.algorithms.processing import batch

HERE = Path(__file__).resolve().parent
linux_only = pytest.mark.skipif(not sys.platform.startswith("linux"),
                                reason="SIGKILL and /proc are Linux features")


@pytest.fixture
def project4(chain_project):
    """A project with four stereo models (a step of four tasks)."""
    return chain_project("abcde")


def _config(project, steps, **head):
    return {"batch": {"project": str(project), **head}, "steps": steps}


def _sleep_step(**params):
    return {"algorithm": "fake_sleep_write", "name": "sleep",
            "params": {"seconds": 0.05, "output": "{project}/products/{step}/{model}.json",
                       **params}}


def _die_steps(marks, deaths):
    """A step of four tasks whose b_c worker dies ``deaths`` times, and a step after it."""
    return [
        {"algorithm": "fake_die", "name": "work",
         "params": {"die": "b_c", "deaths": deaths, "marks": str(marks), "seconds": 0.3,
                    "output": "{project}/products/{step}/{model}.txt"}},
        {"algorithm": "fake_fail_on", "name": "next",
         "params": {"output": "{project}/products/{step}/{model}.txt"}},
    ]


def _statuses(summary):
    return {f"{t['step']}/{t['item']}": t["status"] for t in summary["tasks"]}


def _files(folder):
    """The product files below ``folder``, without the hidden marks of non-GeoTIFF products."""
    return sorted(str(p.relative_to(folder)) for p in Path(folder).rglob("*")
                  if p.is_file() and not p.name.endswith(PRODUCT_MARKER))


# -- a lost worker costs only its own task -----------------------------------------------------
@linux_only
def test_a_killed_worker_costs_only_its_task_which_runs_again(fake_algs, project4, tmp_path):
    plan = batch.plan_batch(_config(project4, _die_steps(tmp_path / "marks", 1), workers=2),
                            run_dir=tmp_path / "run")
    summary = batch.run_batch(plan)
    assert summary["status"] == "done", summary
    assert set(_statuses(summary).values()) == {"done"}
    assert len(list((tmp_path / "marks").iterdir())) == 1  # b_c's first worker died
    assert (project4 / "products" / "work" / "b_c.txt").read_text() == "b_c"
    assert (project4 / "products" / "next" / "b_c.txt").is_file()  # the next step ran
    text = (tmp_path / "run" / "batch.log").read_text()
    assert "work/b_c: its worker tcp://" in text
    assert "running the task once more, on worker tcp://" in text
    assert json.loads((tmp_path / "run" / "summary.json").read_text())["status"] == "done"


@linux_only
def test_a_task_whose_worker_dies_twice_fails_and_the_batch_goes_on(fake_algs, project4,
                                                                     tmp_path):
    plan = batch.plan_batch(_config(project4, _die_steps(tmp_path / "marks", 2), workers=2),
                            run_dir=tmp_path / "run")
    summary = batch.run_batch(plan)
    status = _statuses(summary)
    assert status.pop("work/b_c") == "failed" and status.pop("next/b_c") == "failed"
    assert set(status.values()) == {"done"}  # the three other models, in both steps
    assert summary["status"] == "failed"  # truthful: not "cancelled"
    assert summary["counts"] == {"done": 6, "skipped": 0, "failed": 2, "cancelled": 0}
    errors = {f"{t['step']}/{t['item']}": t["error"] for t in summary["tasks"]}
    assert "the worker running it died" in errors["work/b_c"]
    assert "the second time for this task" in errors["work/b_c"]
    assert "not run because step 'work' failed" in errors["next/b_c"]
    assert len(list((tmp_path / "marks").iterdir())) == 2
    assert not (project4 / "products" / "work" / "b_c.txt").exists()


def test_an_operator_error_is_not_run_again(fake_algs, project4, tmp_path):
    step = {"algorithm": "fake_fail_on", "name": "check",
            "params": {"fail": "a_b", "output": "{project}/products/{step}/{model}.txt"}}
    plan = batch.plan_batch(_config(project4, [step], workers=2), run_dir=tmp_path / "run")
    summary = batch.run_batch(plan)
    assert _statuses(summary)["check/a_b"] == "failed"
    text = (tmp_path / "run" / "batch.log").read_text()
    assert text.count("check/a_b: started on worker") == 1
    assert (tmp_path / "run" / "check" / "a_b.log").read_text().count("fake_fail_on {") == 1


# -- processes outside the test process ------------------------------------------------------
def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(HERE), env.get("PYTHONPATH", "")])
    env["PHOTODEM_EXTRA_ALGORITHMS"] = "_fake_algs"
    return env


def _start_cli_batch(file, *args):
    return subprocess.Popen([sys.executable, "-m", "photodem.algorithms.cli", "batch",
                             str(file), "--quiet", *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=_env())


_LOG_RECORD = re.compile(r"^\d{4}-\d\d-\d\d \d\d:\d\d:\d\d")


def _without_dask_records(err: str) -> str:
    """``err`` without the records of Dask's own loggers (``… - distributed.<name> - …`` and
    the lines that follow up to the next record): on a loaded machine a worker's missed
    heartbeat is logged with a traceback, which is no failure of the batch."""
    kept, dask = [], False
    for line in err.splitlines(keepends=True):
        if _LOG_RECORD.match(line):
            dask = " - distributed." in line
        if not dask:
            kept.append(line)
    return "".join(kept)



def test_dask_log_records_are_told_from_our_tracebacks():
    dask = ("2026-11-27 03:10:11,123 - distributed.worker - ERROR - Failed to communicate with "
            "scheduler during heartbeat.\nTraceback (most recent call last):\n  File \"x\"\n"
            "OSError: Timed out\n")
    ours = "Traceback (most recent call last):\n  File \"batch.py\"\nKeyError: 'a'\n"
    assert _without_dask_records(dask) == ""
    assert _without_dask_records("photodem: 4 tasks\n" + dask) == "photodem: 4 tasks\n"
    assert "Traceback" in _without_dask_records(ours + dask)


def _write_batch(project, run, step, workers=2):
    file = project.parent / "b.toml"
    params = "".join(f"{k} = {json.dumps(v)}\n" for k, v in step["params"].items())
    file.write_text(f'[batch]\nproject = "{project}"\nworkers = {workers}\noutput = "{run}"\n'
                    f'[[steps]]\nalgorithm = "{step["algorithm"]}"\nname = "{step["name"]}"\n'
                    f"[steps.params]\n{params}")
    return file


def _worker_pids(run, n, proc, timeout=60.0):
    """The pids of the first ``n`` tasks' workers, from batch.log, once they run."""
    log = Path(run) / "batch.log"
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        text = log.read_text() if log.exists() else ""
        pids = [int(line.rsplit(" ", 1)[-1].rstrip(")")) for line in text.splitlines()
                if "started on worker" in line]
        if len(pids) >= n:
            return pids[:n]
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.1)
    raise AssertionError(f"no {n} workers started: {log.read_text() if log.exists() else ''}")


def _proc_stat(pid):
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[-1].split()
    except OSError:
        return None


def _descendants(pid):
    """Pids (with their start times) of all processes below ``pid``."""
    children = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            fields = _proc_stat(int(entry.name))
            if fields:
                children.setdefault(int(fields[1]), []).append((int(entry.name), fields[19]))
    found, todo = [], [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            found.append(child)
            todo.append(child[0])
    return found


def _alive(pid, start):
    fields = _proc_stat(pid)
    return fields is not None and fields[19] == start and fields[0] != "Z"


@linux_only
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM])
def test_a_worker_killed_from_outside_is_replaced(fake_algs, project4, tmp_path, sig):
    run = tmp_path / "run"
    file = _write_batch(project4, run, _sleep_step(seconds=2.0, steps=20))
    proc = _start_cli_batch(file)
    victim = _worker_pids(run, 1, proc)[0]
    while not (run / "sleep" / "a_b.log").exists():
        time.sleep(0.05)  # the worker runs its task
    time.sleep(0.3)
    os.kill(victim, sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, err
    assert "Traceback" not in _without_dask_records(err)
    summary = json.loads((run / "summary.json").read_text())
    assert summary["status"] == "done" and summary["counts"]["done"] == 4
    text = (run / "batch.log").read_text()
    assert ": its worker tcp://" in text and "running the task once more" in text
    assert len(_files(project4 / "products")) == 4


@linux_only
def test_killing_the_batch_parent_ends_its_workers_and_a_rerun_takes_over(fake_algs, project4,
                                                                          tmp_path):
    run = tmp_path / "run"
    # two progress reports in 60 s: the workers learn of the death by the signal, not the pipe
    file = _write_batch(project4, run, _sleep_step(seconds=60.0, steps=2))
    proc = _start_cli_batch(file)
    _worker_pids(run, 2, proc)
    logs = [run / "sleep" / f"{m}.log" for m in ("a_b", "b_c")]
    deadline = time.monotonic() + 30
    while not all(p.exists() for p in logs) and time.monotonic() < deadline:
        time.sleep(0.05)  # both workers run their task (not merely start up)
    family = _descendants(proc.pid)
    assert len(family) >= 2
    proc.send_signal(signal.SIGKILL)
    proc.communicate(timeout=10)
    deadline = time.monotonic() + 6.0
    while any(_alive(*p) for p in family) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not [p for p in family if _alive(*p)], "processes outlived the batch"
    assert _files(project4 / "products") == []  # the cancelled tasks wrote nothing
    lock = project4 / ".photodem" / "batch.lock"
    assert json.loads(lock.read_text())["pid"] == proc.pid  # left behind by the kill

    file = _write_batch(project4, tmp_path / "run2", _sleep_step(seconds=0.05))
    rerun = _start_cli_batch(file)
    _, err = rerun.communicate(timeout=60)
    assert rerun.returncode == 0, err
    assert "took over the stale lock" in (tmp_path / "run2" / "batch.log").read_text()
    assert not lock.exists()
    assert len(_files(project4 / "products")) == 4


# -- the lock --------------------------------------------------------------------------------------
def _lock(project):
    return project / ".photodem" / "batch.lock"


def test_a_second_batch_on_the_project_is_refused_naming_the_first(fake_algs, project4,
                                                                   tmp_path):
    first = batch.plan_batch(_config(project4, [_sleep_step(seconds=0.4)]),
                             run_dir=tmp_path / "run1")
    done = {}
    thread = threading.Thread(target=lambda: done.update(batch.run_batch(first, workers=1)))
    thread.start()
    try:
        deadline = time.monotonic() + 10
        while not _lock(project4).exists() and time.monotonic() < deadline:
            time.sleep(0.01)
        second = batch.plan_batch(_config(project4, [_sleep_step()]), run_dir=tmp_path / "run2")
        with pytest.raises(InputError) as info:
            batch.run_batch(second, workers=1)
    finally:
        thread.join()
    message = str(info.value)
    assert f"another batch (pid {os.getpid()}, started " in message
    assert f"run folder {tmp_path / 'run1'})" in message
    assert "is running on this project; wait for it to finish or stop it" in message
    assert "\n" not in message
    assert not (tmp_path / "run2").exists()  # refused before anything was written
    assert done["status"] == "done"
    assert not _lock(project4).exists()  # released


def _dead_pid():
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def _write_lock(project, **info):
    _lock(project).parent.mkdir(parents=True, exist_ok=True)
    _lock(project).write_text(json.dumps({"host": socket.gethostname(), "started": "earlier",
                                          "run": "/somewhere/runs/old", **info}))


@pytest.mark.skipif(os.name == "nt", reason="no liveness probe on Windows")
def test_a_stale_lock_is_taken_over_with_a_log_line(fake_algs, project4, tmp_path):
    pid = _dead_pid()
    _write_lock(project4, pid=pid)
    plan = batch.plan_batch(_config(project4, [_sleep_step()]), run_dir=tmp_path / "run")
    summary = batch.run_batch(plan, workers=1)
    assert summary["status"] == "done"
    text = (tmp_path / "run" / "batch.log").read_text()
    assert f"took over the stale lock {_lock(project4)} of batch pid {pid}" in text
    assert not _lock(project4).exists()


@pytest.mark.parametrize(("info", "age", "message"), [
    ({"pid": 1, "host": "elsewhere"}, 0, "(pid 1 on host elsewhere, started earlier"),
    ({"pid": "own"}, 0, "run folder /somewhere/runs/old) is running"),
    (None, 0, "its lock is being written"),
])
def test_a_live_or_foreign_or_fresh_unreadable_lock_refuses(fake_algs, project4, tmp_path,
                                                            info, age, message):
    if info is None:
        _lock(project4).parent.mkdir(parents=True)
        _lock(project4).write_text("")
    else:
        _write_lock(project4, **{**info, "pid": os.getpid() if info["pid"] == "own"
                                 else info["pid"]})
    plan = batch.plan_batch(_config(project4, [_sleep_step()]), run_dir=tmp_path / "run")
    with pytest.raises(InputError, match=r"delete '.*batch\.lock'") as exc:
        batch.run_batch(plan, workers=1)
    assert message in str(exc.value)
    assert _lock(project4).exists()  # not ours: left alone


def test_an_old_unreadable_lock_is_stale(fake_algs, project4, tmp_path):
    _lock(project4).parent.mkdir(parents=True)
    _lock(project4).write_text("{")
    old = time.time() - 600
    os.utime(_lock(project4), (old, old))
    plan = batch.plan_batch(_config(project4, [_sleep_step()]), run_dir=tmp_path / "run")
    assert batch.run_batch(plan, workers=1)["status"] == "done"


def test_the_lock_is_released_on_an_interrupt(fake_algs, project4, tmp_path):
    def interrupt(pct):
        if pct > 10:
            raise KeyboardInterrupt

    plan = batch.plan_batch(_config(project4, [_sleep_step(seconds=1.0, steps=50)]),
                            run_dir=tmp_path / "run")
    with pytest.raises(KeyboardInterrupt):
        batch.run_batch(plan, Feedback(on_progress=interrupt), workers=1)
    assert not _lock(project4).exists()
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["status"] == "cancelled"


def test_a_batch_over_files_locks_beside_its_resume_state(fake_algs, tmp_path):
    root = tmp_path / "b"
    (root / "scenes").mkdir(parents=True)
    (root / "scenes" / "s1.tif").write_bytes(b"x")
    config = {"steps": [{"algorithm": "fake_file_size", "name": "size",
                         "files": "scenes/*.tif", "params": {"output": "{run}/{step}/{file}"}}]}
    _write_lock(root, pid=os.getpid())
    with pytest.raises(InputError, match="on the batch files of"):
        batch.run_batch(batch.plan_batch(config, base_dir=root), workers=1)
    _lock(root).unlink()
    assert batch.run_batch(batch.plan_batch(config, base_dir=root), workers=1)["status"] == "done"
    assert not _lock(root).exists()


def test_cli_refuses_a_locked_project_in_one_line_and_dry_run_takes_no_lock(
        fake_algs, project4, tmp_path, capsys):
    from photodem.algorithms import cli

    file = _write_batch(project4, tmp_path / "run", _sleep_step(), workers=1)
    _write_lock(project4, pid=os.getpid())
    assert cli.main(["batch", str(file), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("photodem: error: another batch (pid ")
    _lock(project4).unlink()
    assert cli.main(["batch", str(file), "--dry-run"]) == 0
    assert not _lock(project4).exists() and not (tmp_path / "run").exists()


# -- run folders and late cancels ------------------------------------------------------------------
def test_batches_started_in_the_same_second_get_their_own_run_folders(fake_algs, project4):
    now = dt.datetime(2026, 11, 25, 21, 0, 0)
    steps = [_sleep_step(note="{run}")]
    plans = [batch.plan_batch(_config(project4, steps), now=now) for _ in range(3)]
    assert len({p.run_dir for p in plans}) == 1  # planned alike: none exists yet
    runs = [batch.run_batch(p, workers=1, resume=False)["run"] for p in plans]
    names = [Path(r).name for r in runs]
    assert names == ["20261125-210000", "20261125-210000-2", "20261125-210000-3"]
    last = plans[-1]
    assert last.tasks[0].params["note"] == runs[-1]  # {run} follows the new folder
    assert last.tasks[0].log.parent.parent == Path(runs[-1])
    assert (Path(runs[-1]) / "sleep" / "a_b.log").is_file()
    assert "exists already; this run writes to" in (Path(runs[-1]) / "batch.log").read_text()
    assert json.loads((Path(runs[0]) / "summary.json").read_text())["run"] == runs[0]


def test_a_named_run_folder_may_be_reused(fake_algs, project4, tmp_path):
    for _ in range(2):
        plan = batch.plan_batch(_config(project4, [_sleep_step()]), run_dir=tmp_path / "run")
        assert batch.run_batch(plan, workers=1)["run"] == str((tmp_path / "run").resolve())


def test_run_folder_that_cannot_be_created_is_an_operator_error(fake_algs, project4, tmp_path):
    plan = batch.plan_batch(_config(project4, [_sleep_step()]), run_dir=tmp_path / "file" / "r")
    (tmp_path / "file").write_text("x")  # after planning, which refuses it (see below)
    with pytest.raises(InputError, match="Cannot create the run folder"):
        batch.run_batch(plan, workers=1)
    assert not _lock(project4).exists()


@pytest.mark.parametrize("workers", [1, 2])
def test_a_cancel_after_the_last_task_changes_nothing(fake_algs, project4, tmp_path, workers):
    feedback = Feedback()
    finished = []

    def on_log(level, message):  # Ctrl-C right after the last task was recorded
        if ": done in" in message:
            finished.append(message)
        if len(finished) == 4:
            feedback.cancel()

    feedback._on_log = on_log
    plan = batch.plan_batch(_config(project4, [_sleep_step()]), run_dir=tmp_path / "run")
    summary = batch.run_batch(plan, feedback, workers=workers)
    assert feedback.is_canceled()
    assert summary["status"] == "done"
    assert set(_statuses(summary).values()) == {"done"}


@pytest.mark.skipif(os.name == "nt", reason="no liveness probe on Windows")
def test_two_batches_taking_over_one_stale_lock_get_it_once(fake_algs, project4, tmp_path):
    plan = batch.plan_batch(_config(project4, [_sleep_step()]), run_dir=tmp_path / "run")
    dead = _dead_pid()
    for _ in range(20):
        _write_lock(project4, pid=dead)
        barrier = threading.Barrier(2)
        outcomes = []

        def take(barrier=barrier, outcomes=outcomes):
            barrier.wait()
            try:
                outcomes.append(batch._acquire_lock(plan)[0])
            except InputError as exc:
                outcomes.append(str(exc))

        threads = [threading.Thread(target=take) for _ in range(2)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        taken = [o for o in outcomes if isinstance(o, Path)]
        refused = [o for o in outcomes if isinstance(o, str)]
        assert len(taken) == 1 and len(refused) == 1, outcomes
        assert "another batch (pid" in refused[0]
        assert json.loads(_lock(project4).read_text())["pid"] == os.getpid()
        _lock(project4).unlink()


# -- Ctrl-C at random moments ---------------------------------------------------------------
@linux_only
@pytest.mark.parametrize("moment", [round(random.Random(16 + i).uniform(1.0, 4.0), 2)
                                    for i in range(5)])
@pytest.mark.slow
def test_ctrl_c_at_a_random_moment_leaves_what_the_summary_says(fake_algs, project4, tmp_path,
                                                                moment):
    run = tmp_path / "run"
    file = _write_batch(project4, run, _sleep_step(seconds=0.6, steps=12))
    proc = _start_cli_batch(file)
    time.sleep(moment)
    family = _descendants(proc.pid)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert "Traceback" not in _without_dask_records(err)
    products = project4 / "products" / "sleep"
    on_disk = set(_files(products)) if products.exists() else set()
    if (run / "summary.json").exists():
        summary = json.loads((run / "summary.json").read_text())
        if summary["status"] == "cancelled":
            assert proc.returncode == 130, err
        else:  # all done; an interrupt after the batch's end may still end the interpreter
            assert proc.returncode in (0, -signal.SIGINT), err
        done = {f"{t['item']}.json" for t in summary["tasks"] if t["status"] == "done"}
        assert on_disk == done  # complete products only, and each one recorded
        assert set(_statuses(summary).values()) <= {"done", "cancelled"}
    else:  # interrupted before the batch began
        assert proc.returncode == 130 and on_disk == set()
        done = set()
    for name in on_disk:
        assert json.loads((products / name).read_text())["model"] == name[:-5]
    assert not _lock(project4).exists()
    deadline = time.monotonic() + 6.0
    while any(_alive(*p) for p in family) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not [p for p in family if _alive(*p)], "processes outlived the batch"

    rerun = _start_cli_batch(_write_batch(project4, tmp_path / "run2",
                                          _sleep_step(seconds=0.6, steps=12)))
    _, err = rerun.communicate(timeout=60)
    assert rerun.returncode == 0, err
    summary = json.loads((tmp_path / "run2" / "summary.json").read_text())
    assert summary["counts"]["skipped"] == len(done)
    assert set(_files(products)) == {f"{m}.json" for m in ("a_b", "b_c", "c_d", "d_e")}


# -- bad batch files: one line, exit 2, nothing written -------------------------------------
_HEAD = '[batch]\nproject = "proj"\n'
_STEP = '[[steps]]\nalgorithm = "fake_sleep_write"\n'
_OUT = '[steps.params]\noutput = "{project}/p/{model}.json"\n'
_GOOD = _HEAD + _STEP + _OUT
BAD_BATCH_FILES = [
    ("batch-not-table", 'batch = 5\n' + _STEP + _OUT, "batch must be a table"),
    ("steps-single-brackets", _HEAD + '[steps]\nalgorithm = "fake_crash"\n', "two brackets"),
    ("steps-string", 'steps = "x"\n', "no [[steps]]"),
    ("empty", "", "no [[steps]]"),
    ("step-not-table", "steps = [1]\n", "step 1 is not a table"),
    ("unknown-table", "[x]\n" + _GOOD, "unknown table(s) x"),
    ("unknown-batch-key", _HEAD + "wrokers = 2\n" + _STEP + _OUT, "unknown key(s) wrokers"),
    ("unknown-step-key", _HEAD + _STEP + 'modles = "all"\n' + _OUT, "unknown key(s) modles"),
    ("project-number", '[batch]\nproject = 5\n' + _STEP + _OUT, "project = 5 in [batch]"),
    ("project-missing", '[batch]\nproject = "nope"\n' + _STEP + _OUT, "not a PhotoDEM project"),
    ("project-is-file", '[batch]\nproject = "runfile"\n' + _STEP + _OUT, "runfile"),
    ("workers-zero", _HEAD + "workers = 0\n" + _STEP + _OUT, "workers = 0"),
    ("workers-negative", _HEAD + "workers = -3\n" + _STEP + _OUT, "workers = -3"),
    ("workers-bool", _HEAD + "workers = true\n" + _STEP + _OUT, "workers = True"),
    ("workers-float", _HEAD + "workers = 2.5\n" + _STEP + _OUT, "workers = 2.5"),
    ("workers-string", _HEAD + 'workers = "2"\n' + _STEP + _OUT, "workers = '2'"),
    ("output-list", _HEAD + 'output = ["a"]\n' + _STEP + _OUT, "output = ['a'] in [batch]"),
    ("algorithm-list", _HEAD + '[[steps]]\nalgorithm = ["fake_crash"]\n', "algorithm = ['fake"),
    ("algorithm-missing", _HEAD + '[[steps]]\nname = "x"\n', "needs algorithm"),
    ("algorithm-unknown", _HEAD + '[[steps]]\nalgorithm = "fake_nope"\n', "No algorithm"),
    ("name-number", _HEAD + _STEP + "name = 5\n" + _OUT, "name = 5 in step 1"),
    ("name-path", _HEAD + _STEP + 'name = "../x"\n' + _OUT, "may hold only letters"),
    ("name-twice", _GOOD + _STEP + _OUT, "two steps are named"),
    ("models-number", _HEAD + _STEP + "models = 5\n" + _OUT, 'must be "all" or a list'),
    ("models-unknown", _HEAD + _STEP + 'models = ["x_y"]\n' + _OUT, "not in the project"),
    ("models-dotdot", _HEAD + _STEP + 'models = ["../../x"]\n' + _OUT, "not in the project"),
    ("images-on-models", _HEAD + _STEP + 'images = "all"\n' + _OUT, "iterates over models"),
    ("files-no-iteration", _HEAD + '[[steps]]\nalgorithm = "fake_crash"\nfiles = "*.tif"\n',
     "does not iterate"),
    ("files-no-match", '[[steps]]\nalgorithm = "fake_file_size"\nfiles = "none/*.tif"\n'
     '[steps.params]\noutput = "{run}/{file}"\n', "no file matches"),
    ("files-number", '[[steps]]\nalgorithm = "fake_file_size"\nfiles = 5\n'
     '[steps.params]\noutput = "{run}/{file}"\n', "files must be a pattern"),
    ("params-not-table", _HEAD + _STEP + "params = 5\n", "params of step"),
    ("param-unknown", _GOOD + "secnods = 1\n", "unknown parameter(s) secnods"),
    ("param-not-number", _GOOD + 'seconds = "abc"\n', "'abc' is not a valid number"),
    ("param-out-of-range", _GOOD + "seconds = 1e6\n", "outside the allowed range"),
    ("param-not-finite", _GOOD + "seconds = nan\n", "finite number"),
    ("param-bad-enum", _GOOD + 'mode = "warp"\n', "not one of fast, slow, exact"),
    ("param-bad-bool", _GOOD + 'shout = "perhaps"\n', "yes/no value"),
    ("param-not-whole", _GOOD + "steps = 2.5\n", "whole number"),
    ("param-output-missing", _HEAD + _STEP, "Parameter 'output'"),
    ("placeholder-image", _GOOD + 'note = "{image}"\n', "does not run per image"),
    ("placeholder-no-project", _STEP.replace("fake_sleep_write", "fake_chatty")
     + '[steps.params]\ninput = "{project}/x"\n', "has no project"),
    ("not-utf8", b'[[steps]]\nalgorithm = "\xff"\n', "Cannot read batch file"),
    ("bad-toml", "[[steps]\n", "Cannot read batch file"),
]


def _hashes(root):
    import hashlib

    return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
            if p.is_file() else "folder" for p in Path(root).rglob("*")}


def _cli(capsys, *argv):
    from photodem.algorithms import cli

    code = cli.main(list(argv))
    return code, capsys.readouterr().err


@pytest.mark.parametrize(("text", "message"), [c[1:] for c in BAD_BATCH_FILES],
                         ids=[c[0] for c in BAD_BATCH_FILES])
def test_a_bad_batch_file_is_one_line_and_writes_nothing(fake_algs, project4, capsys, text,
                                                         message):
    root = project4.parent
    (root / "runfile").write_text("x")
    file = root / "b.toml"
    file.write_bytes(text if isinstance(text, bytes) else text.encode("utf-8"))
    before = _hashes(root)
    code, err = _cli(capsys, "batch", str(file), "--quiet")
    assert code == 2, err
    assert err.count("\n") == 1 and err.startswith("photodem: error: ") and "Traceback" not in err
    assert message in err
    assert _hashes(root) == before  # inputs unchanged, nothing beside them


@pytest.mark.parametrize(("setup", "message"), [
    ("missing", "does not exist"),
    ("folder", "does not exist"),
    ("lock-live", "another batch (pid "),
    ("lock-foreign", "on host elsewhere"),
    ("run-is-file", "runfile' is a file, but a folder is expected"),
    ("run-inside-file", "which is a file; choose a path in a folder"),
])
def test_a_batch_that_cannot_start_is_one_line_and_writes_nothing(fake_algs, project4, capsys,
                                                                  setup, message):
    root = project4.parent
    (root / "runfile").write_text("x")
    file = root / "b.toml"
    output = {"run-is-file": "runfile", "run-inside-file": "runfile/r"}.get(setup, "runs/r")
    file.write_text(_HEAD + f'output = "{output}"\n' + _STEP + _OUT)
    if setup == "missing":
        file = root / "nope.toml"
    elif setup == "folder":
        file = root / "proj"
    elif setup.startswith("lock"):
        _write_lock(project4, pid=os.getpid() if setup == "lock-live" else 1,
                    **({"host": "elsewhere"} if setup == "lock-foreign" else {}))
    before = _hashes(root)
    code, err = _cli(capsys, "batch", str(file), "--quiet")
    assert code == 2, err
    assert err.count("\n") == 1 and err.startswith("photodem: error: ") and "Traceback" not in err
    assert message in err
    after = _hashes(root)
    assert after == before, set(after) ^ set(before)


@pytest.mark.skipif(os.name == "nt", reason="no liveness probe on Windows")
def test_temporary_files_of_killed_batches_are_removed_and_named(fake_algs, project4, tmp_path):
    dead = _dead_pid()
    state = project4 / ".photodem"
    run = tmp_path / "run"
    state.mkdir()
    run.mkdir()
    stale = [state / f".batch-state.json.{dead}.0123abcd.partial",
             state / f".batch.lock.{dead}.0123abcd.partial",
             run / f".summary.json.{dead}.0123abcd.partial"]
    for path in stale:
        path.write_text("{")
    alive = state / f".batch-state.json.{os.getppid()}.0123abcd.partial"  # a live writer's
    alive.write_text("{")
    mine = state / "notes.tmp"  # not a staging name: kept
    mine.write_text("x")
    plan = batch.plan_batch(_config(project4, [_sleep_step()]), run_dir=run)
    assert batch.run_batch(plan, workers=1)["status"] == "done"
    assert sorted(p.name for p in state.iterdir()) == sorted(
        [alive.name, "batch-state.json", "notes.tmp"])
    assert not any(path.exists() for path in stale)
    text = (run / "batch.log").read_text()
    for path in stale:
        assert f"Removed the leftover '{path}' of process {dead}, no longer running." in text


@linux_only
def test_two_batches_started_together_run_each_task_once(fake_algs, project4, tmp_path):
    file = project4.parent / "b.toml"  # default run folders: runs/<timestamp>/
    file.write_text(_HEAD + "workers = 2\n" + '[[steps]]\nalgorithm = "fake_sleep_write"\n'
                    'name = "sleep"\n[steps.params]\nseconds = 1.0\n'
                    'output = "{project}/products/{step}/{model}.json"\n')
    procs = [_start_cli_batch(file) for _ in range(2)]
    results = [(p.wait(timeout=90), p.communicate()[1]) for p in procs]
    codes = sorted(code for code, _ in results)
    assert codes in ([0, 0], [0, 2]), results
    for code, err in results:
        assert "Traceback" not in _without_dask_records(err)
        if code == 2:
            assert "another batch (pid " in err and err.count("\n") == 1
    runs = sorted((project4 / "runs").iterdir())
    assert len(runs) == codes.count(0)  # a refused batch makes no run folder
    done = [line for run in runs for line in (run / "batch.log").read_text().splitlines()
            if ": done in" in line]
    assert len(done) == 4  # each task once: the second batch (if it ran) resumed them all
    assert all((run / "summary.json").is_file() for run in runs)
    assert not _lock(project4).exists()


# -- outputs checked while planning (issue 16, points 1 and 3) --------------------------------
_IMAGE = """
[[images]]
name = "x1"
path = "{path}"
camera = "c"
position = [0.0, 0.0, 100.0]
opk = [0.0, 0.0, 0.0]
"""


@pytest.fixture
def project_with_outside_image(project4):
    """``project4`` with an image that lives outside the project, in ``<tmp>/imgs/``."""
    image = project4.parent / "imgs" / "x1.tif"
    image.parent.mkdir()
    image.write_bytes(b"II*\x00 not really a tiff")
    with open(project4 / "project.toml", "a", encoding="utf-8") as fh:
        fh.write(_IMAGE.replace("{path}", image.as_posix()))
    return project4


@pytest.mark.parametrize(("output", "message"), [
    ("{project}", "is or contains a PhotoDEM project"),
    (".", "is or contains a PhotoDEM project"),  # the batch file's folder holds the project
    ("{project}/images", "(images)"),
    ("{project}/images/r", "(images)"),
    ("{project}/.photodem", "(.photodem)"),
    ("{project}/edits.gpkg", "(edits.gpkg)"),
    ("{project}/project.toml", "is a file, but a folder is expected"),
    ("imgs", "is or contains the input"),
    ("imgs/x1.tif", "is a file, but a folder is expected"),
    ("runfile", "is a file, but a folder is expected"),
])
def test_a_forbidden_run_folder_is_refused_before_anything_is_written(
        fake_algs, project_with_outside_image, capsys, output, message):
    root = project_with_outside_image.parent
    (root / "runfile").write_text("x")
    file = root / "b.toml"
    file.write_text(_HEAD + f'output = "{output}"\n' + _STEP + _OUT)
    before = _hashes(root)
    code, err = _cli(capsys, "batch", str(file), "--quiet")
    assert code == 2, err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith("photodem: error: Batch file: [batch] output (where the batch writes "
                          "its logs): ")
    assert message in err
    assert _hashes(root) == before  # no run folder, no log, no lock, the project intact


def test_a_forbidden_run_folder_given_to_the_planner_is_refused(fake_algs, project4):
    with pytest.raises(InputError, match=r"^Batch file: the run folder \(where the batch "
                                         r"writes its logs\): .* is or contains a PhotoDEM"):
        batch.plan_batch(_config(project4, [_sleep_step()]), run_dir=project4)


def test_a_reused_run_folder_is_no_replaced_output(fake_algs, project4, tmp_path):
    run = tmp_path / "run"
    run.mkdir()
    (run / "notes.txt").write_text("the operator's")  # written into, never replaced
    plan = batch.plan_batch(_config(project4, [_sleep_step()]), run_dir=run)
    assert batch.run_batch(plan, workers=1)["status"] == "done"
    assert (run / "notes.txt").read_text() == "the operator's"


def _plan_error(project, step, run):
    with pytest.raises(InputError) as info:
        batch.plan_batch(_config(project, [step]), run_dir=run)
    return str(info.value)


@pytest.mark.parametrize(("output", "message"), [
    ("{project}/images/{model}.json", "(images)"),
    ("{project}/project.toml", "(project.toml)"),
    ("{project}/.photodem/{model}.json", "(.photodem)"),
    ("{tmp}/imgs/x1.tif", "is or contains the input"),
    ("{tmp}/notes.txt", "exists and is a file PhotoDEM did not write"),
    ("{tmp}/other.json", "exists and is a product of 'fake_fail_on'"),
    ("{tmp}/folder", "is a folder, but a file is expected"),
    ("{tmp}/file/{model}.json", "which is a file; choose a path in a folder"),
    ("{run}", "contains the run folder"),
    ("{tmp}", "contains the run folder"),
])
def test_a_forbidden_step_output_is_refused_while_planning(
        fake_algs, project_with_outside_image, tmp_path, output, message):
    from photodem.algorithms.output_policy import file_mark, write_marker

    project = project_with_outside_image
    tmp = project.parent
    (tmp / "notes.txt").write_text("the operator's")
    (tmp / "other.json").write_text("{}")
    write_marker(tmp, "fake_fail_on", "now", name=file_mark(tmp / "other.json").name)
    (tmp / "folder").mkdir()
    (tmp / "file").write_text("x")
    run = tmp / "run"
    before = _hashes(tmp)
    text = _plan_error(project, _sleep_step(output=output.replace("{tmp}", str(tmp))), run)
    assert text.startswith("Batch file: step 'sleep' (fake_sleep_write), model 'a_b': "
                           "Parameter 'output': "), text
    assert message in text
    assert "\n" not in text
    assert _hashes(tmp) == before and not run.exists()


@pytest.mark.parametrize(("output", "message"), [
    ("{project}", "is or contains a PhotoDEM project"),
    ("{tmp}", "is or contains a PhotoDEM project"),
    ("{project}/images", "(images)"),
    ("{tmp}/imgs", "is or contains the input"),
    ("{run}/..", "contains the run folder"),
])
def test_a_forbidden_folder_output_is_refused_while_planning(project_with_outside_image, output,
                                                             message):
    project = project_with_outside_image
    tmp = project.parent
    step = {"algorithm": "epipolar_pair", "name": "epi", "models": ["b_c"],
            "params": {"output": output.replace("{tmp}", str(tmp))}}
    text = _plan_error(project, step, tmp.with_name(tmp.name + "-runs") / "r")
    assert text.startswith("Batch file: step 'epi' (epipolar_pair), model 'b_c': "
                           "Parameter 'output': "), text
    assert message in text


def test_a_step_output_that_is_an_input_made_by_an_earlier_step_is_refused(fake_algs, project4,
                                                                            tmp_path):
    made = "{project}/products/sleep/a_b.json"  # does not exist yet: step 'sleep' makes it
    steps = [_sleep_step(), {"algorithm": "fake_file_size", "name": "size",
                             "params": {"image": made, "output": made}}]
    with pytest.raises(InputError, match=r"^Batch file: step 'size' \(fake_file_size\): "
                                         r"Parameter 'output': .* is or contains the input"):
        batch.plan_batch(_config(project4, steps), run_dir=tmp_path / "run")


def test_a_refused_step_output_runs_no_task_in_the_cli(fake_algs, project4, capsys):
    root = project4.parent
    file = root / "b.toml"
    file.write_text(_GOOD + '[[steps]]\nalgorithm = "fake_fail_on"\n[steps.params]\n'
                    'output = "{project}/images/{model}.txt"\n')
    before = _hashes(root)
    code, err = _cli(capsys, "batch", str(file), "--quiet")
    assert code == 2 and err.count("\n") == 1, err
    assert err.startswith("photodem: error: Batch file: step 'fake_fail_on' (fake_fail_on), "
                          "model 'a_b': Parameter 'output': ")
    assert _hashes(root) == before  # the first step did not run either


def test_inputs_that_an_earlier_step_makes_are_not_looked_for(fake_algs, project4, tmp_path):
    steps = [_sleep_step(), {"algorithm": "fake_file_size", "name": "size",
                             "params": {"image": "{project}/products/sleep/a_b.json",
                                        "output": "{project}/products/size/a_b.txt"}}]
    plan = batch.plan_batch(_config(project4, steps), run_dir=tmp_path / "run")
    summary = batch.run_batch(plan, workers=1)
    assert summary["status"] == "done", summary
    assert (project4 / "products" / "size" / "a_b.txt").is_file()


def test_a_project_that_an_earlier_step_makes_leaves_its_derived_output_to_the_run(project4,
                                                                                  tmp_path):
    steps = [{"algorithm": "synthetic_block", "params": {"output": "{run}/synth"}},
             {"algorithm": "epipolar_pair", "params": {"project": "{run}/synth",
                                                       "model": "0101_0102"}}]
    plan = batch.plan_batch(_config(project4, steps), run_dir=tmp_path / "run")
    assert [t.algorithm for t in plan.tasks] == ["synthetic_block", "epipolar_pair"]


def test_derived_outputs_are_checked_while_planning(project4, tmp_path):
    (project4 / "products" / "epipolar").mkdir(parents=True)
    (project4 / "products" / "epipolar" / "b_c").write_text("not a folder")
    step = {"algorithm": "epipolar_pair", "name": "epi"}  # default: products/epipolar/<model>
    text = _plan_error(project4, step, tmp_path / "run")
    assert text.startswith("Batch file: step 'epi' (epipolar_pair), model 'b_c': "), text
    assert "is a file, but a folder is expected" in text


def test_planning_reads_the_project_a_fixed_number_of_times(project4, tmp_path, monkeypatch):
    from photodem.algorithms.processing import spec
    from photodem.algorithms.project import toml_io

    reads = []
    loads = toml_io.loads
    monkeypatch.setattr(toml_io, "loads", lambda text: reads.append(1) or loads(text))
    monkeypatch.setattr(spec, "_PROJECTS", {})
    step = {"algorithm": "epipolar_pair", "name": "epi"}  # derived outputs load the project
    plan = batch.plan_batch(_config(project4, [step]), run_dir=tmp_path / "run")
    assert len(plan.tasks) == 4
    assert len(reads) == 2  # the batch's own load and the output checks' one, not one per task
    text = (project4 / "project.toml").read_text()
    (project4 / "project.toml").write_text(text + "\n")  # a changed file is read again
    spec.project_files(project4)
    assert len(reads) == 3
