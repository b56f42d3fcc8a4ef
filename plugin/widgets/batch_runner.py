"""Running a batch file off the GUI thread: the existing runner (:func:`run_batch`) in a QThread.

The worker plans the batch with :func:`~photodem.algorithms.processing.batch.load_batch` and runs
it with :func:`~photodem.algorithms.processing.batch.run_batch` — the same state folder, lock and
resume rules as ``photodem batch FILE``. Its feedback turns the runner's per-task hooks into Qt
signals (queued across threads: widgets are touched only in the GUI thread). QGIS runs the same
:meth:`BatchWorker.execute` inside a ``QgsTask`` (``plugin/qgis/batch_actions.py``); standalone,
:func:`~.worker.start_in_thread` runs it in a QThread.
"""

from __future__ import annotations

import traceback
from pathlib import Path
from typing import Any, Dict, Optional, Sequence

from ...algorithms.errors import PhotodemError
from ...algorithms.feedback import Feedback
from ...algorithms.processing import batch, batch_setup
from ..qt import QObject, pyqtSignal, pyqtSlot


class _BatchFeedback(Feedback):
    """A feedback whose per-task hooks (called by the runner) emit the worker's signals."""

    def __init__(self, worker: BatchWorker) -> None:
        super().__init__(on_progress=worker.progress.emit, on_log=worker.log.emit)
        self._worker = worker

    def task_progress(self, index: int, pct: float) -> None:
        self._worker.task_progress.emit(int(index), float(pct))

    def task_finished(self, index: int, record: Dict[str, Any]) -> None:
        self._worker.task_finished.emit(int(index), dict(record))


class BatchWorker(QObject):
    """Plans and runs one batch file; emits ``planned`` first and ``done`` last.

    Signals
    -------
    planned(object)
        The :class:`~photodem.algorithms.processing.batch.BatchPlan` (before the first task).
    progress(float)
        Overall percent.
    task_progress(int, float)
        A task (by index) started (0) or progressed (percent).
    task_finished(int, object)
        A task's record (status, outputs, duration_s, error, log).
    log(str, str)
        ``(level, message)`` lines of the batch.
    finished(object)
        The batch summary (also in ``<run>/summary.json``).
    failed(str)
        The batch could not start (a bad batch file, the lock held by another batch) or a bug.
    done()
        Last signal of every run.
    """

    planned = pyqtSignal(object)
    progress = pyqtSignal(float)
    task_progress = pyqtSignal(int, float)
    task_finished = pyqtSignal(int, object)
    log = pyqtSignal(str, str)
    finished = pyqtSignal(object)
    failed = pyqtSignal(str)
    done = pyqtSignal()

    def __init__(self, batch_file: Path, workers: Optional[int] = None, resume: bool = True,
                 only: Optional[Sequence[str]] = None, parent: Optional[QObject] = None,
                 scheduler: Optional[str] = None) -> None:
        super().__init__(parent)
        #: A Dask scheduler's address; "" runs on this machine, None as the batch file says.
        self.scheduler = scheduler
        self.batch_file = Path(batch_file)
        self.only = list(only) if only else None  # run these models/images/files alone
        self.workers = workers
        self.resume = resume
        self.feedback = _BatchFeedback(self)
        self.summary: Optional[Dict[str, Any]] = None
        self.error: Optional[str] = None

    def cancel(self) -> None:
        """Ask the batch to stop (thread-safe): running tasks discard their staged outputs."""
        self.feedback.cancel()

    def execute(self) -> Optional[Dict[str, Any]]:
        """Plan and run the batch in the calling thread; the summary, or ``None`` on failure
        (the message in :attr:`error` and the ``failed`` signal)."""
        try:
            plan = batch.load_batch(self.batch_file)
            if self.only:
                plan.tasks = batch_setup.only_items(plan.tasks, self.only)
            self.planned.emit(plan)
            self.summary = batch.run_batch(plan, self.feedback, workers=self.workers,
                                           resume=self.resume, scheduler=self.scheduler)
        except PhotodemError as exc:
            self.error = str(exc)
            self.failed.emit(self.error)
        except Exception:  # a bug: show the traceback, keep the GUI alive
            self.error = traceback.format_exc()
            self.failed.emit(self.error)
        else:
            self.finished.emit(self.summary)
        return self.summary

    @pyqtSlot()
    def run(self) -> None:
        try:
            self.execute()
        finally:
            self.done.emit()


__all__ = ["BatchWorker"]
