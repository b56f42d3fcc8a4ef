"""Batch throughput on Dask distributed (issue 24): models per minute with 1 and 2 workers on
this machine, and the batch's own cost per task (scheduler, state file, logs).

- **Throughput.** The four stereo models of the ``tiny`` synthetic block, each through
  ``epipolar_pair`` → ``match_model`` (fbm_lsm, general), with ``workers = 1`` (in the batch
  process, no Dask) and ``workers = 2`` (a ``LocalCluster`` of two processes, one thread
  each). Models per minute = 4 / wall time of ``run_batch`` (cluster start and stop
  included); the ratio says how far two workers scale on this machine (2 cores, shared).
- **Scaling of the engine.** The same with the ``small`` block (larger models: seconds of
  matching each; its four models twice, into two product folders, so that eight model runs
  keep two workers busy until the end) in a fresh process per run whose numeric libraries
  (OpenCV, BLAS) are pinned to one thread, with 1 worker (the batch process) and 2 Dask
  workers: the ratio says how the batch scales per single-threaded worker, which is what a
  cluster of N machines adds — free of OpenCV's own threading, which lets one in-process
  worker already use both cores of this machine.
- **The machine's ceiling.** One model matched by one single-threaded ``photodem`` process,
  then by two such processes at once (no Dask): two cores that share caches, memory bandwidth
  and a clock do not double the throughput, and this ratio is what any engine can reach here.
- **Cost per task.** A batch of many quick tasks run once, then again with everything
  complete: the second run submits every task to Dask (each returns ``skipped`` unless a
  dependency failed), so its wall time over the number of tasks is the batch's own cost per
  task (Dask scheduling and transfer, result records, batch.log) without the cluster start,
  which is measured apart.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, Dict, List

MODELS_STEPS = ("epipolar_pair", "match_model")
#: Steps of quick tasks (epipolar resampling of the tiny block's 4 models each).
QUICK_STEPS = 12


def _plan(project: Path, run: Path, steps: List[Dict[str, Any]], workers: int) -> Any:
    from photodem.algorithms.processing import batch

    return batch.plan_batch({"batch": {"project": str(project), "workers": workers},
                             "steps": steps}, run_dir=run)


def _model_steps(tag: str) -> List[Dict[str, Any]]:
    return [{"algorithm": "epipolar_pair", "name": "epipolar", "models": "all",
             "params": {"output": f"{{project}}/products/{tag}/epipolar/{{model}}"}},
            {"algorithm": "match_model", "name": "match", "models": "all",
             "params": {"output": f"{{project}}/products/{tag}/dsm/{{model}}"}}]


def _throughput(project: Path, tmp: Path, workers: int) -> Dict[str, Any]:
    from photodem.algorithms.processing import batch

    plan = _plan(project, tmp / f"run-w{workers}", _model_steps(f"w{workers}"), workers)
    n_models = len({t.item for t in plan.tasks})
    t0 = time.perf_counter()
    summary = batch.run_batch(plan, resume=False)
    wall = time.perf_counter() - t0
    busy = sum(t["duration_s"] for t in summary["tasks"])
    return {"case": f"{n_models} models, epipolar + match", "workers": workers,
            "status": summary["status"], "wall_s": round(wall, 2),
            "task_time_s": round(busy, 2),
            "models_per_min": round(60.0 * n_models / wall, 2)}


#: A batch run in a fresh process (its thread settings apply from the start).
_CHILD = """
import json, sys, time
from photodem.algorithms.processing import batch
config, run = json.loads(sys.argv[1]), sys.argv[2]
plan = batch.plan_batch(config, run_dir=run)
t0 = time.perf_counter()
summary = batch.run_batch(plan, resume=False)
print(json.dumps({"wall": time.perf_counter() - t0, "status": summary["status"],
                  "busy": sum(t["duration_s"] for t in summary["tasks"]),
                  "models": len({t.item for t in plan.tasks})}))
"""


#: Numeric libraries pinned to one thread (a single-threaded worker).
_ONE_THREAD = {"OPENCV_FOR_THREADS_NUM": "1", "OMP_NUM_THREADS": "1",
               "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


def _single_threaded(project: Path, tmp: Path, workers: int) -> Dict[str, Any]:
    """One batch with ``workers`` single-threaded workers (1: in the batch process); the
    block's models are run twice (two product folders)."""
    tag = f"st{workers}"
    steps = [step for rep in ("a", "b") for step in _model_steps(f"{tag}{rep}")]
    for step in steps[2:]:
        step["name"] += "-again"
    config = {"batch": {"project": str(project), "workers": workers, "scheduler": "local"},
              "steps": steps}
    env = dict(os.environ, **_ONE_THREAD)
    out = subprocess.run([sys.executable, "-c", _CHILD, json.dumps(config),
                          str(tmp / f"run-{tag}")], env=env, capture_output=True, text=True,
                         check=True, timeout=3600)
    res = json.loads(out.stdout.strip().splitlines()[-1])
    runs = 2 * res["models"]
    return {"case": f"{runs} model runs (small block), 1 thread per worker",
            "workers": workers, "status": res["status"], "wall_s": round(res["wall"], 2),
            "task_time_s": round(res["busy"], 2),
            "models_per_min": round(60.0 * runs / res["wall"], 2)}


def _ceiling(project: Path, tmp: Path) -> Dict[str, Any]:
    """The machine's ceiling: one model matched by one, then by two single-threaded
    processes at once (no Dask); throughput ratio = 2 × one's time / the pair's wall time."""
    from photodem.algorithms.processing import registry

    model = registry.run("project_info", {"project": str(project)})["models"][0]["name"]
    exe = str(Path(sys.executable).with_name("photodem"))
    env = dict(os.environ, **_ONE_THREAD)

    def command(tag: str) -> List[str]:
        return [exe, "run", "match_model", "--project", str(project), "--model", model,
                "--output", str(tmp / "ceiling" / tag), "--quiet"]

    t0 = time.perf_counter()
    subprocess.run(command("one"), env=env, check=True, capture_output=True, timeout=3600)
    one = time.perf_counter() - t0
    t0 = time.perf_counter()
    procs = [subprocess.Popen(command(tag), env=env, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL) for tag in ("two-a", "two-b")]
    codes = [p.wait(timeout=3600) for p in procs]
    two = time.perf_counter() - t0
    if any(codes):
        raise RuntimeError(f"match_model exited with {codes}")
    return {"case": f"machine ceiling: model {model} matched by 1 and by 2 processes at once",
            "one_process_s": round(one, 2), "two_processes_wall_s": round(two, 2),
            "ratio": round(2.0 * one / two, 3)}


def _overhead(project: Path, tmp: Path) -> Dict[str, Any]:
    from photodem.algorithms.processing import batch, batch_dask

    steps = [{"algorithm": "epipolar_pair", "name": f"e{i}", "models": "all",
              "params": {"output": f"{{project}}/products/quick/e{i}/{{model}}"}}
             for i in range(QUICK_STEPS)]
    batch.run_batch(_plan(project, tmp / "quick-1", steps, 2))  # makes the products
    t0 = time.perf_counter()
    with batch_dask.connect(2, None):
        pass
    start_stop = time.perf_counter() - t0
    plan = _plan(project, tmp / "quick-2", steps, 2)
    t0 = time.perf_counter()
    summary = batch.run_batch(plan)
    wall = time.perf_counter() - t0
    n = len(plan.tasks)
    per_task = (wall - start_stop) / n
    return {"case": f"{n} tasks, all complete (resumed)", "workers": 2,
            "status": f"{summary['counts']['skipped']} skipped", "wall_s": round(wall, 2),
            "cluster_start_stop_s": round(start_stop, 2),
            "overhead_per_task_ms": round(1000.0 * per_task, 1)}


def run() -> dict:
    try:
        import distributed  # noqa: F401  # optional: the Dask path needs it
    except ImportError:
        return {"skipped": "Dask distributed is not installed (pip install \"photodem[dask]\")"}
    from photodem.algorithms.processing import registry

    with tempfile.TemporaryDirectory(prefix="bench-batch-dask-") as tmp_name:
        tmp = Path(tmp_name)
        project = tmp / "block"
        registry.run("synthetic_block", {"output": str(project), "size": "tiny"})
        one = _throughput(project, tmp, 1)
        two = _throughput(project, tmp, 2)
        cost = _overhead(project, tmp)
        small = tmp / "small"
        registry.run("synthetic_block", {"output": str(small), "size": "small"})
        st_one = _single_threaded(small, tmp, 1)
        st_two = _single_threaded(small, tmp, 2)
        ceiling = _ceiling(small, tmp)
    ratio = one["wall_s"] / two["wall_s"] if two["wall_s"] else float("nan")
    st_ratio = st_one["wall_s"] / st_two["wall_s"] if st_two["wall_s"] else float("nan")
    per_model_s = 60.0 / one["models_per_min"]
    notes = [
        f"2 workers / 1 worker: {ratio:.2f}× the models per minute on this machine "
        "(2 cores shared with other processes; the ratio is bounded by 2 and by the cores "
        "free during the run). The tiny models take seconds: the workers' first imports "
        "(≈ 1–2 s of CPU each, counted in their first task) and the cluster's start and stop "
        "weigh more than they would for large models.",
        f"Scaling of the engine (small block, one thread per worker, cluster start "
        f"included): 2 workers / 1 worker = {st_ratio:.2f}× the models per minute; the "
        f"machine's ceiling (two single-threaded processes at once, no Dask) is "
        f"{ceiling['ratio']:.2f}×, so the engine reaches {st_ratio / ceiling['ratio']:.0%} "
        "of what two processes can on these cores.",
        f"Per model (1 worker, tiny block): {per_model_s:.1f} s; the batch's own cost per "
        f"task on Dask: {cost['overhead_per_task_ms']:.0f} ms, cluster start + stop "
        f"{cost['cluster_start_stop_s']:.1f} s.",
        "Projection for 4 000 models of the large size (≈ 60 s each, issue 24): "
        "4 000 × 60 s / N workers = 67 h / N, e.g. 8.3 h on 8 workers, 2.1 h on 32; the "
        "per-task cost above (× 2 tasks per model) is < 0.1 % of that. What limits scaling: "
        "the shared storage's bandwidth (each model reads 2 images and writes its epipolar "
        "pair and DSM), the batch's resume state (rewritten after every task) and the "
        "scheduler's per-task cost.",
    ]
    return {"title": "Batch on Dask distributed: models per minute, cost per task",
            "rows": [one, two, st_one, st_two, ceiling, cost], "notes": notes}
