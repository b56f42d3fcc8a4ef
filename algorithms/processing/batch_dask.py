"""Batch tasks on Dask distributed: a ``LocalCluster`` on this machine or a scheduler's cluster.

:mod:`.batch` plans a batch, keeps its resume state, lock, logs and summary; this module runs
its tasks when it has more than one worker or a scheduler (``workers = 1`` without a scheduler
runs in the batch's process, without Dask).

- **Tasks and dependencies.** Every task (model × step, or file × step) is one Dask task. Its
  dependencies are the tasks of earlier steps for the same model/image/file, every task of an
  earlier step without items (merge, filter, mosaic: those depend on everything before them)
  and every task of an earlier step over another kind of item (a step over images after a
  step over models). So model A can be matched while model B is still resampled.
- **Failures.** A task whose dependency for the same item failed is not run: it ends
  ``failed`` ("not run because step 'match' failed for model 'A'"), as in :mod:`.batch`. The
  task function returns its result record (:func:`.batch.execute_task`); an operator error is
  a record with status ``failed``, not an exception, so Dask never runs it again.
- **Lost workers.** A worker process that dies while running a task (killed, out of memory) is
  replaced by its nanny and the scheduler runs the task on another worker; the batch log says
  so. Each run of a task writes an ``attempt`` line to the task's log (on the shared
  storage): a task whose worker died :data:`MAX_ATTEMPTS` (2) times ends ``failed`` with the
  reason at its next start. Dask's own limit (``distributed.scheduler.allowed-failures``;
  5 on a local cluster, the scheduler's setting on a cluster, Dask's default 3) counts the
  tasks waiting on a dying worker too, so it is kept above ours.
- **Cancel.** A cancel sets a Dask ``Event`` that the running tasks' feedback checks (their
  staged outputs are discarded) and cancels the tasks not started; a local cluster whose tasks
  do not stop within ``grace`` seconds is closed, which kills its workers.
- **Parent death.** The local cluster's scheduler and nannies live in the batch process; its
  worker processes exit as soon as that process is gone (a pipe the worker watches closes).
- **Shared storage.** On a scheduler's cluster every worker must see the project folder and
  the run folder at the same paths (a shared file system); this is checked on every worker
  before the first task runs.
"""

from __future__ import annotations

import contextlib
import os
import queue
import time
import uuid
from pathlib import Path
from typing import Any, Callable, Dict, Iterator, List, Optional, Sequence, Set, Tuple

from ..errors import InputError
from ..feedback import Feedback
from ..raster import tiled_dask
from ..raster.tiled_dask import local_cluster
from . import registry
from .batch import Task, execute_task, no_result

#: What to do when Dask distributed is missing (one line, for the CLI, QGIS and the GUI).
INSTALL_HINT = ("a batch with more than one worker or a scheduler needs Dask distributed: "
                "pip install \"photodem[dask]\" (Debian: apt install python3-distributed)")
#: Seconds to reach a scheduler.
CONNECT_TIMEOUT_S = 20.0
#: Seconds to wait for the first worker of a scheduler's cluster.
WORKER_TIMEOUT_S = 60.0
#: Runs of a task whose worker died while running it: the next start fails it instead.
MAX_ATTEMPTS = 2
#: Dask's own limit for a local cluster: tasks waiting on a worker that dies count as lost
#: too, so Dask's limit is higher than ours (which counts the runs that started).
_ALLOWED_FAILURES = 5
_ORDINAL = {1: "first", 2: "second", 3: "third"}
#: Seconds between two looks of a running task at the batch's cancel event.
_CANCEL_POLL_S = 0.3
#: Seconds between two progress messages of a running task (besides start and end).
_PROGRESS_EVERY_S = 0.25


def import_distributed() -> Any:
    """The ``distributed`` module, or an operator error saying how to install it."""
    return tiled_dask.import_distributed(f"Cannot run the batch: {INSTALL_HINT}.")


# -- the dependencies ----------------------------------------------------------------------------
def dependencies(tasks: Sequence[Task]) -> Dict[int, List[int]]:
    """``task index → indexes of the tasks it waits for`` (see the module docstring).

    Parameters
    ----------
    tasks : sequence of Task
        The plan's tasks in plan order (the steps in order).
    """
    steps: Dict[str, List[Task]] = {}
    for task in tasks:
        steps.setdefault(task.step, []).append(task)
    # per earlier step: its tasks by item, or None for a step without items
    by_item: List[Tuple[Optional[str], Optional[Dict[str, List[int]]], List[int]]] = []
    result: Dict[int, List[int]] = {}
    for step_tasks in steps.values():
        for task in step_tasks:
            deps: List[int] = []
            for kind, items, every in by_item:
                if task.item is None or items is None or kind != task.item_kind:
                    deps += every
                else:
                    deps += items.get(task.item, [])
            result[task.index] = sorted(deps)
        first = step_tasks[0]
        items: Optional[Dict[str, List[int]]] = None
        if first.item is not None:
            items = {}
            for task in step_tasks:
                items.setdefault(str(task.item), []).append(task.index)
        by_item.append((first.item_kind, items, [t.index for t in step_tasks]))
    return result


# -- in a worker ---------------------------------------------------------------------------------
def _blocked(spec: Dict[str, Any], deps: Sequence[Dict[str, Any]]) -> Optional[Dict[str, Any]]:
    """The record of a task that must not run: a dependency for its item failed (or was
    cancelled); ``None`` when it may run."""
    if any(d.get("status") == "cancelled" for d in deps):
        return no_result("cancelled", "not run: the batch was cancelled")
    if spec["item"] is None:
        return None
    for dep in sorted(deps, key=lambda d: d.get("index", 0)):
        if dep.get("status") == "failed" and dep.get("item_kind") == spec["item_kind"] \
                and dep.get("item") == spec["item"]:
            return no_result("failed", f"not run because step '{dep['step']}' failed for "
                                       f"{spec['item_kind']} '{spec['name']}'")
    return None


def _progress_emitter(topic: str, index: int) -> Callable[[float], None]:
    """Send ``{"i": index, "pct": …, "w": worker, "pid": …}`` to the batch (a Dask worker
    event); 0 % says the task started, further reports at most every 0.25 s or 1 %."""
    from distributed import get_worker  # lazy: runs in a Dask worker only

    worker = get_worker()
    last = [-1.0, 0.0]

    def emit(pct: float) -> None:
        now = time.monotonic()
        if pct <= 0.0 or pct >= 100.0 or (pct - last[0] >= 1.0
                                          and now - last[1] >= _PROGRESS_EVERY_S):
            last[0], last[1] = pct, now
            worker.log_event(topic, {"i": index, "pct": float(pct), "w": worker.address,
                                     "pid": os.getpid()})

    return emit


def _cancel_checker(name: str) -> Callable[[], bool]:
    """``is_canceled()`` of a task: the batch's Dask event, looked at every 0.3 s at most.

    Asked over the worker's own connection to the scheduler (no client in the worker).
    """
    from distributed import get_worker  # lazy: runs in a Dask worker only
    from distributed.utils import sync  # lazy: runs in a Dask worker only

    worker = get_worker()
    state = {"at": 0.0, "set": False}

    def is_canceled() -> bool:
        now = time.monotonic()
        if not state["set"] and now - state["at"] >= _CANCEL_POLL_S:
            state["at"] = now
            try:
                state["set"] = bool(sync(worker.loop, worker.scheduler.event_is_set,
                                         name=name, callback_timeout=10))
            except Exception:  # no scheduler: stop when this worker is closing (batch gone)
                state["set"] = _worker_closing()
        return state["set"]

    return is_canceled


def _attempt(spec: Dict[str, Any]) -> Tuple[int, List[str]]:
    """Count this run of the task in its log: ``(attempt number, workers of the earlier
    attempts)``. The log keeps one line per attempt of this batch (``spec["batch"]``), on
    the shared storage, so the count survives the workers that died running the task."""
    from distributed import get_worker  # lazy: runs in a Dask worker only

    log = Path(spec["log"])
    tag = f"attempt of batch {spec['batch']} on Dask worker "
    earlier: List[str] = []
    with contextlib.suppress(OSError):
        earlier = [line.split(tag, 1)[1].split(" ")[0]
                   for line in log.read_text(encoding="utf-8").splitlines() if tag in line]
    log.parent.mkdir(parents=True, exist_ok=True)
    with open(log, "a", encoding="utf-8") as fh:
        fh.write(f"{time.strftime('%H:%M:%S')} INFO    {tag}{get_worker().address} "
                 f"(pid {os.getpid()}, number {len(earlier) + 1})\n")
    return len(earlier) + 1, earlier


def _worker_closing() -> bool:
    """True when this Dask worker is closing (its cluster is being shut down)."""
    from distributed import get_worker  # lazy: runs in a Dask worker only

    try:
        status = get_worker().status
    except ValueError:  # not in a worker
        return False
    return getattr(status, "name", str(status)) not in ("running", "paused")


def run_task(spec: Dict[str, Any], deps: Sequence[Dict[str, Any]]) -> Dict[str, Any]:
    """The Dask task of one batch task: run it unless a dependency stops it.

    Parameters
    ----------
    spec : dict
        ``index``, ``step``, ``item``, ``item_kind``, ``name``, ``algorithm``, ``params``,
        ``log``, ``skip`` (the recorded outputs of a task complete from an earlier run, or
        ``None``), ``topic`` (progress), ``cancel`` (the event's name), ``modules``.
    deps : sequence of dict
        The records of the tasks it waits for (Dask passes them in).

    Returns
    -------
    dict
        The task's record (:func:`.batch.execute_task`) with ``index``, ``step``, ``item``
        and ``item_kind``; an operator error is a record with status ``failed``.
    """
    who = {k: spec[k] for k in ("index", "step", "item", "item_kind")}
    result = _blocked(spec, deps)
    if result is None and spec.get("skip") is not None:
        result = {"status": "skipped", "outputs": spec["skip"], "duration_s": 0.0,
                  "error": None}
    if result is None:
        registry.add_modules(spec["modules"])
        is_canceled = _cancel_checker(spec["cancel"])
        if is_canceled():
            result = no_result("cancelled", "not run: the batch was cancelled")
        elif (attempt := _attempt(spec))[0] > MAX_ATTEMPTS:
            result = no_result("failed", (
                f"the worker running it died (Dask worker {attempt[1][-1]}), the "
                f"{_ORDINAL.get(len(attempt[1]), str(len(attempt[1])) + 'th')} time for this "
                "task; if memory ran out, use fewer workers"))
        else:
            emit = _progress_emitter(spec["topic"], spec["index"])
            emit(0.0)  # started
            result = execute_task(spec["algorithm"], spec["params"], spec["log"], is_canceled,
                                  emit)
    result.update(who)
    return result


# -- the cluster ---------------------------------------------------------------------------------
@contextlib.contextmanager
def connect(n_workers: int, scheduler: Optional[str]) -> Iterator[Tuple[Any, Optional[Any]]]:
    """A Dask client: of ``scheduler`` (``tcp://host:8786``) or of a new ``LocalCluster``
    with ``n_workers`` processes of one thread each; closed (the cluster too) on exit.

    Yields
    ------
    (Client, LocalCluster or None)

    Raises
    ------
    InputError
        Dask is not installed, or the scheduler cannot be reached.
    """
    distributed = import_distributed()
    if scheduler:
        try:
            client = distributed.Client(scheduler, timeout=f"{CONNECT_TIMEOUT_S}s",
                                        set_as_default=False)
        except (OSError, TimeoutError) as exc:
            raise InputError(f"Cannot reach the Dask scheduler '{scheduler}': {exc}; start it "
                             "with 'dask scheduler' and check the address (tcp://host:8786)."
                             ) from None
        try:
            yield client, None
        finally:
            client.close()
        return
    with local_cluster(n_workers, allowed_failures=_ALLOWED_FAILURES) as cluster:
        client = distributed.Client(cluster, set_as_default=False)
        try:
            yield client, cluster
        finally:
            client.close()


def dashboard(client: Any, local: bool) -> Optional[str]:
    """The dashboard's address for the batch log, or ``None`` when the scheduler has none.

    A local cluster's dashboard is on a free port; it draws only with Bokeh installed.
    """
    link = None
    with contextlib.suppress(Exception):
        if client.scheduler_info().get("services", {}).get("dashboard"):
            link = str(client.dashboard_link)
    if link and local:
        try:
            import bokeh  # noqa: F401  # optional: the dashboard draws with it
        except ImportError:
            link += " (it needs the Python package bokeh)"
    return link


def check_shared_paths(client: Any, paths: Sequence[Tuple[str, Any]],
                       timeout: float = WORKER_TIMEOUT_S) -> int:
    """Check that every worker sees ``paths`` (``(what, folder)`` pairs) as folders.

    Returns
    -------
    int
        The number of workers.

    Raises
    ------
    InputError
        No worker within ``timeout`` seconds, or a worker that cannot see a folder (one
        line naming the worker and the folder).
    """
    try:
        client.wait_for_workers(1, timeout=timeout)
    except Exception:  # dask's TimeoutError (asyncio's or its own, by version)
        raise InputError(f"No Dask worker joined the scheduler within {timeout:.0f} s; start "
                         "workers with 'dask worker tcp://host:8786'.") from None
    for what, folder in paths:
        seen = client.run(os.path.isdir, str(folder))
        blind = sorted(w for w, ok in seen.items() if not ok)
        if blind:
            more = f" (and {len(blind) - 1} more workers)" if len(blind) > 1 else ""
            raise InputError(f"Dask worker {blind[0]}{more} cannot see {what} '{folder}': the "
                             "project and the run folder must be on storage every worker "
                             "sees, at the same path (a shared file system).")
    return len(client.scheduler_info().get("workers", {}))


# -- running the tasks ---------------------------------------------------------------------------
class DaskRun:
    """The batch's side of a Dask run: submits the tasks, follows them, records the results.

    Parameters
    ----------
    client : distributed.Client
        Connected (see :func:`connect`).
    hooks : object
        ``finish(task, result)``, ``progress.set(index, pct)``, ``log(message, warning=False,
        quiet=False)`` of :mod:`.batch` (all called in this thread).
    modules : sequence of str
        Extra algorithm modules the workers register.
    """

    def __init__(self, client: Any, hooks: Any, modules: Sequence[str]) -> None:
        self.client = client
        self.hooks = hooks
        self.modules = list(modules)
        uid = uuid.uuid4().hex[:12]
        self.prefix = f"photodem-{uid}"
        self.topic = f"{self.prefix}-progress"
        self.inbox: queue.Queue = queue.Queue()
        self.started: Dict[int, List[str]] = {}  # task index → the workers that started it
        self.erred: Set[int] = set()  # tasks Dask gave up (it errs the tasks waiting for them)
        self.cancelling = False

    def submit(self, tasks: Sequence[Task], skip: Dict[int, Dict[str, Any]],
               depends: Dict[int, List[int]]) -> Dict[int, Any]:
        """Submit ``tasks`` (plan order) with their dependencies; ``skip``: the recorded
        outputs of tasks complete from an earlier run (they return ``skipped`` unless a
        dependency failed)."""
        from distributed import Event  # lazy: a Dask batch only

        self.client.subscribe_topic(self.topic, lambda event: self.inbox.put(event[1]))
        self.cancel_event = Event(f"{self.prefix}-cancel", client=self.client)
        futures: Dict[int, Any] = {}
        for task in tasks:
            spec = {"index": task.index, "step": task.step, "item": task.item,
                    "item_kind": task.item_kind, "name": task.name, "algorithm": task.algorithm,
                    "params": task.params, "log": str(task.log), "skip": skip.get(task.index),
                    "topic": self.topic, "cancel": f"{self.prefix}-cancel",
                    "batch": self.prefix,
                    "modules": self.modules}
            deps = [futures[i] for i in depends.get(task.index, []) if i in futures]
            futures[task.index] = self.client.submit(
                run_task, spec, deps, key=f"{self.prefix}-{task.index}-{task.key}",
                retries=1, pure=False)
        self.depends = depends
        self.tasks = {t.index: t for t in tasks}
        return futures

    def follow(self, tasks: Sequence[Task], futures: Dict[int, Any], feedback: Feedback,
               grace: float, can_kill: bool) -> bool:
        """Record each task as it finishes; on a cancel, stop the tasks (``grace`` s).

        Returns
        -------
        bool
            True when tasks still ran after the grace time (a local cluster is then closed).
        """
        from distributed import as_completed  # lazy: a Dask batch only

        by_index = {t.index: t for t in tasks}
        pending = dict(futures)
        done_iter = as_completed(list(futures.values()), loop=self.client.loop)
        index_of = {f.key: i for i, f in futures.items()}
        deadline: Optional[float] = None
        while pending:
            self._messages(by_index, wait=0.05)
            if feedback.is_canceled() and deadline is None:
                deadline = time.monotonic() + grace
                self._cancel(pending)
            ready = done_iter.next_batch(block=False) if done_iter.has_ready() else []
            if deadline is not None:  # cancelled futures may not come out of as_completed
                ready += [f for f in pending.values() if f.cancelled() and f not in ready]
            for future in sorted(ready, key=lambda f: index_of[f.key]):
                index = index_of[future.key]
                if pending.pop(index, None) is not None:
                    self._record(by_index[index], future)
            if deadline is not None and time.monotonic() > deadline:
                return self._give_up(by_index, pending, can_kill)
        self._messages(by_index, wait=0.0)
        return False

    def _messages(self, by_index: Dict[int, Task], wait: float) -> None:
        """Progress and start messages of the workers (started: a line in batch.log)."""
        try:
            message = self.inbox.get(timeout=wait) if wait > 0 else self.inbox.get_nowait()
        except queue.Empty:
            return
        while True:
            index, pct = int(message["i"]), float(message["pct"])
            task = by_index.get(index)
            if task is not None and pct <= 0.0:
                self._started(task, str(message.get("w")), message.get("pid"))
            self.hooks.progress.set(index, min(pct, 99.0))
            try:
                message = self.inbox.get_nowait()
            except queue.Empty:
                return

    def _started(self, task: Task, worker: str, pid: Any) -> None:
        before = self.started.setdefault(task.index, [])
        if before:
            self.hooks.log(f"{task.key}: its worker {before[-1]} was lost; running the task "
                           f"once more, on worker {worker}", warning=True)
        before.append(worker)
        self.hooks.log(f"{task.key}: started on worker {worker} (pid {pid})", quiet=True)

    def _record(self, task: Task, future: Any) -> None:
        """Record a finished future: its record, or why it ended without one."""
        if future.cancelled() or (self.cancelling and future.status == "error"):
            return  # not started, or lost to the cancel: its record says "cancelled"
        if future.status == "finished":
            self.hooks.finish(task, future.result())
            return
        self.erred.add(task.index)
        self.hooks.finish(task, no_result("failed", self._error(task, future.exception())))

    def _error(self, task: Task, exc: BaseException) -> str:
        """Why a task erred: a dependency erred, its workers were lost, or an error of Dask."""
        failed = [self.tasks[i] for i in self.depends.get(task.index, []) if i in self.erred]
        if failed:  # Dask errs the tasks that wait for an erred one: this one did not run
            same = [d for d in failed if d.item_kind == task.item_kind and d.item == task.item]
            if task.item is not None and same:
                return (f"not run because step '{same[0].step}' failed for {task.item_kind} "
                        f"'{task.name}'")
            return f"not run because task '{failed[0].key}' failed"
        if type(exc).__name__ == "KilledWorker":
            workers = self.started.get(task.index, [])
            return (f"the workers running it died ({len(workers)} started it, the last "
                    f"{workers[-1] if workers else '?'}); Dask gave it up: {exc}")
        return f"{type(exc).__name__}: {exc}"

    def _cancel(self, pending: Dict[int, Any]) -> None:
        """Tell the running tasks to stop; cancel the ones not started."""
        self.cancelling = True
        self.hooks.log("cancel: telling the running tasks to stop", quiet=True)
        with contextlib.suppress(Exception):
            self.cancel_event.set()
        idle = [f for i, f in pending.items() if i not in self.started]
        if idle:
            self.client.cancel(idle)

    def _give_up(self, by_index: Dict[int, Task], pending: Dict[int, Any], can_kill: bool
                 ) -> bool:
        """Tasks that did not stop within the grace time after the cancel."""
        reason = ("worker killed: it did not stop within the grace time after the cancel"
                  if can_kill else "left running on its Dask worker: it did not stop within "
                                   "the grace time after the cancel")
        for index in sorted(pending):
            if index in self.started:
                self.hooks.finish(by_index[index], no_result("cancelled", reason))
        self.client.cancel(list(pending.values()))
        return True


__all__ = [
    "INSTALL_HINT",
    "DaskRun",
    "check_shared_paths",
    "connect",
    "dashboard",
    "dependencies",
    "import_distributed",
    "run_task",
]
