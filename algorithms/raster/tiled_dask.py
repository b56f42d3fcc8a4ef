"""Tiles of a block product as Dask tasks: one code path for one process and for a cluster.

A tiled product (mosaic, filter) lists its tiles as jobs and hands them with one task function
to :func:`map_tiles`. The parts every tile needs (seamlines, balancing, a filter's global
parameters) are computed once by the caller and passed as ``shared``: on a cluster they are
scattered to every worker once, not pickled into every task. The results come back in the
order of the jobs, so a product that sums overlapping tiles (a filter's feather) adds them in
the same order as the single-process run and stays bit-identical to it.

Schedulers (the ``scheduler`` parameter of the tiled algorithms):

``""``
    No Dask: the tiles run one after the other in this process (as before Dask).
``"local"``
    A ``distributed.LocalCluster`` on this machine (one single-threaded worker process per
    core, at most :data:`LOCAL_WORKERS`), shut down afterwards.
``"tcp://host:port"``
    The running Dask scheduler at that address; its workers must see the inputs and the
    output folder under the same paths (a shared file system).

Memory per task: one tile and its overlap — about ``(tile + 2·overlap)² ×`` the product's
bytes per cell (:func:`task_bytes`); nothing else grows with the block. The client keeps the
output open and writes each tile as its turn comes; finished tiles wait on their workers.
"""

from __future__ import annotations

import logging
import os
import re
from contextlib import ExitStack, contextmanager
from typing import Any, Callable, Dict, Iterator, Optional, Sequence, Tuple

from ..errors import InputError, PhotodemError
from ..feedback import Feedback, ensure_feedback

#: Workers of ``scheduler="local"`` (at most; never more than the cores).
LOCAL_WORKERS = 4

#: What an operator installs to use a scheduler.
INSTALL_HINT = 'pip install "photodem[dask]"'


#: A scheduler's address: ``[scheme://]host:port`` (an IPv6 host in brackets).
_ADDRESS = re.compile(r"(?:[a-z][a-z0-9+]*://)?(?:[^\s/:\[\]]+|\[[0-9a-fA-F:]+\]):\d+")


def check_scheduler(scheduler: Optional[str]) -> str:
    """The scheduler text stripped: ``""`` (this process), ``"local"`` (a cluster on this
    machine) or an address (``tcp://host:8786``, ``host:8786``) — the one check of every
    ``--scheduler``, the batch's included.

    Raises
    ------
    InputError
        Anything else, e.g. an address without a port or with spaces.
    """
    text = (scheduler or "").strip()
    if text.lower() in ("", "local"):
        return text.lower()
    if not _ADDRESS.fullmatch(text):
        raise InputError(f"Dask scheduler '{text}': give its address as tcp://host:port (e.g. "
                         "tcp://host:8786), 'local' for a cluster on this machine, or nothing.")
    return text


def import_distributed(refusal: Optional[str] = None) -> Any:
    """The ``distributed`` module, or an InputError saying how to install it — the one
    import of Dask distributed of the tiled products and the batch.

    ``refusal``: the whole message without Dask (default: the tiled products' message).
    """
    try:
        import distributed  # optional: Dask is an extra, the plugin works without it
    except ImportError as exc:
        raise InputError(refusal or "Running tiles on a Dask scheduler needs Dask "
                         f"distributed: {INSTALL_HINT}") from exc
    return distributed


@contextmanager
def local_cluster(n_workers: int, allowed_failures: Optional[int] = None) -> Iterator[Any]:
    """A ``LocalCluster`` of ``n_workers`` single-threaded worker processes on 127.0.0.1,
    closed on exit — the one local cluster of the batch and of the tiled products.

    ``allowed_failures`` sets the scheduler's ``distributed.scheduler.allowed-failures``.
    """
    dist = import_distributed()
    import dask  # lazy: comes with distributed, only for a local cluster

    with _worker_environ(n_workers) as environ:
        settings: Dict[str, Any] = {"distributed.nanny.pre-spawn-environ": environ}
        if allowed_failures is not None:
            settings["distributed.scheduler.allowed-failures"] = int(allowed_failures)
        with dask.config.set(settings):
            cluster = dist.LocalCluster(
                n_workers=n_workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                scheduler_port=0, dashboard_address="127.0.0.1:0", memory_limit=0,
                silence_logs=logging.ERROR)
        try:
            yield cluster
        finally:
            cluster.close()


#: Variables that set the threads of the numeric libraries (OpenCV, OpenMP, BLAS).
_THREAD_VARIABLES = ("OPENCV_FOR_THREADS_NUM", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                     "MKL_NUM_THREADS")


@contextmanager
def _worker_environ(n_workers: int) -> Iterator[Dict[str, str]]:
    """The environment of a local cluster's workers: each gets its share of the cores for
    the threads of OpenCV and BLAS (variables the operator set are kept).

    Without it, every worker's OpenCV used every core: two workers on two cores matched a
    model in 14 s instead of 5 s. Dask's own defaults are not used either: they pin BLAS to
    one thread but not OpenCV, and set ``MALLOC_TRIM_THRESHOLD_``, which turns off glibc's
    adaptive mmap threshold (every large numpy temporary is mapped and zeroed anew). The
    nannies set these variables in this process before they spawn a worker; they are
    restored when the cluster is closed.
    """
    share = str(max(1, (os.cpu_count() or 1) // max(1, n_workers)))
    saved = {k: os.environ.get(k) for k in _THREAD_VARIABLES}
    try:
        yield {k: v if v is not None else share for k, v in saved.items()}
    finally:
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value


@contextmanager
def dask_client(scheduler: str, feedback: Optional[Feedback] = None) -> Iterator[Any]:
    """A ``distributed.Client`` for ``scheduler`` (``"local"`` or an address), closed after.

    A LocalCluster made here (:func:`local_cluster`) is shut down on leaving; a remote
    scheduler is left running. The dashboard link is reported.
    """
    fb = ensure_feedback(feedback)
    dist = import_distributed()
    with ExitStack() as stack:
        if scheduler == "local":
            n = max(1, min(LOCAL_WORKERS, os.cpu_count() or 1))
            client = dist.Client(stack.enter_context(local_cluster(n)))
        else:
            try:
                client = dist.Client(scheduler, timeout="20s")
            except OSError as exc:
                raise InputError(f"No Dask scheduler answers at {scheduler}: {exc}") from exc
        stack.callback(client.close)
        fb.info(f"Dask scheduler {client.scheduler.address}, dashboard "
                f"{client.dashboard_link}.")
        yield client


def map_tiles(task: Callable[..., Any], jobs: Sequence[Any], shared: Tuple[Any, ...] = (),
              scheduler: str = "", feedback: Optional[Feedback] = None
              ) -> Iterator[Tuple[int, Any]]:
    """``(index, task(*shared, job))`` for every job, in the order of the jobs.

    Parameters
    ----------
    task : callable
        A module-level function (picklable); it must not write the product itself.
    jobs : sequence
        One small, picklable description per tile (e.g. its window).
    shared : tuple
        Arguments every task needs, computed once (scattered once to every worker).
    scheduler : str
        See the module notes; ``""`` runs the tasks here, one after the other.
    feedback : Feedback, optional
        Progress counts finished tiles; cancelling stops submitting and cancels the rest.
    """
    fb = ensure_feedback(feedback)
    scheduler = check_scheduler(scheduler)
    n = max(len(jobs), 1)
    if not scheduler:
        for i, job in enumerate(jobs):
            fb.check()
            yield i, task(*shared, job)
            fb.progress(100.0 * (i + 1) / n)
        return
    with dask_client(scheduler, fb) as client:
        yield from _on_cluster(client, task, jobs, shared, fb)


def _on_cluster(client: Any, task: Callable[..., Any], jobs: Sequence[Any],
                shared: Tuple[Any, ...], fb: Feedback) -> Iterator[Tuple[int, Any]]:
    """:func:`map_tiles` on a client: a sliding window of tasks, results handed back in order.

    At most :func:`_in_flight` tasks are submitted or waiting to be taken at a time, so
    finished tiles never pile up on the workers or here beyond that window.
    """
    dist = import_distributed()
    scattered = [client.scatter(s, broadcast=True) for s in shared]
    done = dist.as_completed(with_results=True)
    index: Dict[Any, int] = {}
    live: Dict[Any, Any] = {}  # key → future of the tiles not taken yet
    ready: Dict[int, Any] = {}
    n, limit = len(jobs), _in_flight(client)
    submitted = taken = 0

    def submit() -> None:
        nonlocal submitted
        # pure=False: a re-run of the product recomputes its tiles (inputs may have changed);
        # retries: a lost worker's tile runs again elsewhere (operator errors come back as
        # results, so they are not retried)
        fut = client.submit(_guarded, task, *scattered, jobs[submitted], pure=False, retries=2)
        index[fut.key] = submitted
        live[fut.key] = fut
        done.add(fut)
        submitted += 1

    fb.info(f"{n} tiles for the Dask cluster, at most {limit} at a time.")
    try:
        while submitted < min(n, limit):
            submit()
        for fut, result in done:
            fb.check()
            if isinstance(result, _OperatorError):
                raise result.error
            ready[index.pop(fut.key)] = result
            live.pop(fut.key, None)  # the worker may drop the tile: we hold it now
            while taken in ready:
                yield taken, ready.pop(taken)
                taken += 1
                fb.progress(100.0 * taken / max(n, 1))
                if submitted < n:
                    submit()
    finally:  # cancelled or failed: the tiles not taken are not computed further
        done.clear()
        if live:
            client.cancel(list(live.values()))


class _OperatorError:
    """A tile's operator error, handed back as a result: Dask retries only exceptions."""

    def __init__(self, error: PhotodemError) -> None:
        self.error = error


def _guarded(task: Callable[..., Any], *args: Any) -> Any:
    """``task(*args)``, with an operator error returned instead of raised (no retry).

    A bad input fails the same way on every worker; only a lost worker is worth a retry.
    """
    try:
        return task(*args)
    except PhotodemError as exc:
        return _OperatorError(exc)


def _in_flight(client: Any) -> int:
    """Tiles submitted at a time: 4 per worker thread (at least 8)."""
    try:
        threads = sum(client.nthreads().values())
    except (OSError, AttributeError, TypeError):
        threads = 2
    return max(8, 4 * int(threads))


def task_bytes(tile: int, overlap: int, bytes_per_cell: float) -> int:
    """Memory bound of one tile task: ``(tile + 2·overlap)² × bytes_per_cell`` (bytes)."""
    side = int(tile) + 2 * int(overlap)
    return int(side * side * float(bytes_per_cell))


__all__ = ["INSTALL_HINT", "LOCAL_WORKERS", "check_scheduler", "dask_client",
           "import_distributed", "map_tiles", "task_bytes"]
