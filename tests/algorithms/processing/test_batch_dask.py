"""Batches on a real Dask cluster: a ``dask scheduler`` and two ``dask worker`` processes on
127.0.0.1, started here (issue 24)."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from photodem.algorithms.errors import InputError
from photodem.algorithms.feedback import Feedback
from photodem.algorithms.processing import batch

distributed = pytest.importorskip("distributed", reason="Dask distributed is not installed "
                                                         "(pip install \"photodem[dask]\")")
pytestmark = [pytest.mark.slow,
              pytest.mark.skipif(not sys.platform.startswith("linux"),
                                 reason="process groups and SIGKILL are POSIX")]

HERE = Path(__file__).resolve().parent
MODELS = ["0101_0102", "0202_0203"]
START_TIMEOUT_S = 40.0


def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(HERE), env.get("PYTHONPATH", "")])
    return env


def _start(args, log):
    """A Dask process in a session of its own (its nanny's worker process goes with it)."""
    return subprocess.Popen([sys.executable, "-m", *args], stdout=log, stderr=log, env=_env(),
                            start_new_session=True)


def _stop(procs):
    for proc in procs:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    for proc in procs:
        proc.wait(timeout=10)


@pytest.fixture
def project4(chain_project):
    """A project with four stereo models (a step of four tasks)."""
    return chain_project("abcde")


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """``(address, client)`` of a scheduler with two workers (one process, one thread each)."""
    folder = tmp_path_factory.mktemp("dask")
    file = folder / "scheduler.json"
    log = open(folder / "dask.log", "w")  # noqa: SIM115
    procs = [_start(["distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", "0",
                     "--dashboard-address", "127.0.0.1:0", "--scheduler-file", str(file)], log)]
    try:
        deadline = time.monotonic() + START_TIMEOUT_S
        while not file.exists() and time.monotonic() < deadline:
            assert procs[0].poll() is None, (folder / "dask.log").read_text()
            time.sleep(0.1)
        for name in ("w1", "w2"):
            procs.append(_start(["distributed.cli.dask_worker", "--scheduler-file", str(file),
                                 "--nworkers", "1", "--nthreads", "1", "--memory-limit", "0",
                                 "--host", "127.0.0.1", "--no-dashboard", "--name", name], log))
        client = distributed.Client(scheduler_file=str(file), set_as_default=False)
        client.wait_for_workers(2, timeout=START_TIMEOUT_S)
        yield json.loads(file.read_text())["address"], client
        client.close()
    finally:
        _stop(procs)
        log.close()


def _tiny_batch(root, project, **head):
    steps = [{"algorithm": "epipolar_pair", "name": "epipolar", "models": MODELS,
              "params": {"output": "{project}/products/epipolar/{model}"}},
             {"algorithm": "match_model", "name": "match", "models": MODELS,
              "params": {"output": "{project}/products/dsm/{model}"}}]
    return batch.plan_batch({"batch": {"project": str(project), **head}, "steps": steps},
                            base_dir=root, run_dir=root / "run")


def _hashes(folder):
    """The products: GeoTIFFs by their SHA-256, other files (JSON and GeoPackages that name
    their paths or times) by name."""
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            if p.suffix == ".tif" else "present"
            for p in sorted(Path(folder).rglob("*")) if p.is_file()}


def _statuses(summary):
    return {f"{t['step']}/{Path(str(t['item'])).name}": t["status"] for t in summary["tasks"]}


def test_a_block_on_the_cluster_equals_the_local_run(cluster, tiny_block, tmp_path):
    address, _ = cluster
    results = {}
    for where in ("local", "cluster"):
        root = tmp_path / where
        project = root / "block"
        shutil.copytree(tiny_block, project)
        plan = _tiny_batch(root, project)
        summary = batch.run_batch(plan, workers=1,
                                  scheduler=address if where == "cluster" else None)
        on_disk = json.loads((root / "run" / "summary.json").read_text())
        results[where] = (_statuses(on_disk), _hashes(project / "products"), summary)
    local, remote = results["local"], results["cluster"]
    assert set(local[0].values()) == {"done"} and remote[0] == local[0]
    assert remote[1] == local[1]
    assert sum(k.endswith("dsm.tif") for k in local[1]) == 2
    assert remote[2]["scheduler"] == address and remote[2]["workers"] == 2
    text = (tmp_path / "cluster" / "run" / "batch.log").read_text()
    assert "Dask dashboard: http://127.0.0.1:" in text
    assert text.count("started on worker tcp://127.0.0.1:") == 4


def test_a_killed_worker_costs_only_a_second_run_of_its_task(fake_algs, cluster, project4,
                                                              tmp_path):
    address, _ = cluster
    step = {"algorithm": "fake_sleep_write", "name": "sleep",
            "params": {"seconds": 1.5, "steps": 15,
                       "output": "{project}/products/{step}/{model}.json"}}
    plan = batch.plan_batch({"batch": {"project": str(project4), "scheduler": address},
                             "steps": [step]}, run_dir=tmp_path / "run")
    killed = []

    class KillFirst(Feedback):
        def task_progress(self, index, pct):  # the first task started: kill its worker
            if not killed and 0 < pct < 50:
                line = next(x for x in (tmp_path / "run" / "batch.log").read_text()
                            .splitlines() if "started on worker" in x)
                killed.append(int(line.rsplit(" ", 1)[-1].rstrip(")")))
                os.kill(killed[0], signal.SIGKILL)

    summary = batch.run_batch(plan, KillFirst())
    assert killed and summary["status"] == "done", summary
    assert summary["counts"]["done"] == 4
    text = (tmp_path / "run" / "batch.log").read_text()
    assert "was lost; running the task once more" in text
    for name in ("a_b", "b_c", "c_d", "d_e"):
        data = json.loads((project4 / "products" / "sleep" / f"{name}.json").read_text())
        assert data["model"] == name


def test_an_operator_error_ends_failed_without_a_second_run(fake_algs, cluster, project4,
                                                            tmp_path):
    address, _ = cluster
    steps = [{"algorithm": "fake_fail_on", "name": "check", "models": ["a_b", "b_c"],
              "params": {"fail": "a_b", "output": "{project}/products/{step}/{model}.txt"}},
             {"algorithm": "fake_fail_on", "name": "next", "models": ["a_b", "b_c"],
              "params": {"output": "{project}/products/{step}/{model}.txt"}}]
    plan = batch.plan_batch({"batch": {"project": str(project4)}, "steps": steps},
                            run_dir=tmp_path / "run")
    summary = batch.run_batch(plan, scheduler=address)
    assert _statuses(summary) == {"check/a_b": "failed", "check/b_c": "done",
                                  "next/a_b": "failed", "next/b_c": "done"}
    errors = {f"{t['step']}/{t['item']}": t["error"] for t in summary["tasks"]}
    assert "a_b is broken" in errors["check/a_b"]
    assert "not run because step 'check' failed for model 'a_b'" in errors["next/a_b"]
    log = (tmp_path / "run" / "check" / "a_b.log").read_text()
    assert log.count("attempt of batch") == 1 and "a_b is broken" in log
    assert not (tmp_path / "run" / "next" / "a_b.log").exists()


def test_a_worker_that_cannot_see_the_project_stops_the_batch_before_any_task(
        fake_algs, cluster, project4, tmp_path):
    """A third worker in a mount namespace of its own, with an empty file system over the
    folder that holds the project: it cannot see the project."""
    if shutil.which("unshare") is None:
        pytest.skip("no unshare: cannot give a worker a file system view of its own")
    address, client = cluster
    hidden = project4.parent
    script = (f"mount -t tmpfs none {hidden} && exec {sys.executable} -m "
              f"distributed.cli.dask_worker {address} --nworkers 1 --nthreads 1 "
              "--memory-limit 0 --host 127.0.0.1 --no-dashboard --name blind")
    blind = subprocess.Popen(["unshare", "--mount", "--propagation", "private", "sh", "-c",
                              script], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                             env=_env(), start_new_session=True)
    try:
        try:
            client.wait_for_workers(3, timeout=START_TIMEOUT_S)
        except Exception:  # dask's TimeoutError
            if blind.poll() is not None:
                pytest.skip(f"cannot start a worker in its own mount namespace: "
                            f"{blind.stderr.read().decode()[-200:]}")
            raise
        step = {"algorithm": "fake_sleep_write", "name": "sleep",
                "params": {"output": "{project}/products/{step}/{model}.json"}}
        plan = batch.plan_batch({"batch": {"project": str(project4)}, "steps": [step]},
                                run_dir=tmp_path / "run")
        with pytest.raises(InputError) as info:
            batch.run_batch(plan, scheduler=address)
        message = str(info.value)
        assert "\n" not in message
        assert "Dask worker tcp://127.0.0.1:" in message and f"'{project4}'" in message
        assert "shared file system" in message
        assert not (project4 / "products").exists()  # no task ran
        assert not (project4 / ".photodem" / "batch.lock").exists()
    finally:
        _stop([blind])
        deadline = time.monotonic() + 20
        while len(client.scheduler_info()["workers"]) > 2 and time.monotonic() < deadline:
            time.sleep(0.2)
