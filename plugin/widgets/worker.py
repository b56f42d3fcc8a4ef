"""Running an algorithm off the GUI thread: a QObject worker in a QThread.

The worker calls :func:`photodem.algorithms.processing.registry.run` — the same call as the CLI,
batch and QGIS — with a :class:`~photodem.algorithms.feedback.Feedback` whose
``on_progress``/``on_log`` emit Qt signals (queued across threads, so widgets are only touched in
the GUI thread). Cancel is :meth:`Feedback.cancel`; the algorithm stops at its next progress
check and discards its staged outputs.
"""

from __future__ import annotations

import traceback
from typing import Any, Callable, Dict, Optional

from ...algorithms.errors import Cancelled, PhotodemError
from ...algorithms.feedback import Feedback
from ...algorithms.processing import registry
from ..qt import QObject, Qt, QThread, pyqtSignal, pyqtSlot


class AlgorithmWorker(QObject):
    """Runs one algorithm; emits exactly one of finished/failed/cancelled, then ``done``.

    Signals
    -------
    progress(float)
        Percent 0–100.
    log(str, str)
        ``(level, message)``; level ``info``, ``warning`` or ``error``.
    finished(object)
        The JSON-ready output dict.
    failed(str, bool, object)
        The English message, whether it is an operator error (``False``: a bug, with
        traceback) and the error's :class:`~photodem.algorithms.errors.Message` (template and
        values, which the GUI translates with :func:`..i18n.error_text`) or ``None``.
    cancelled(str)
        The run was cancelled; no output was left behind.
    done()
        Last signal of every run.
    """

    progress = pyqtSignal(float)
    log = pyqtSignal(str, str)
    finished = pyqtSignal(object)
    failed = pyqtSignal(str, bool, object)
    cancelled = pyqtSignal(str)
    done = pyqtSignal()

    def __init__(self, algorithm_id: str, params: Dict[str, Any],
                 parent: Optional[QObject] = None) -> None:
        super().__init__(parent)
        self.algorithm_id = algorithm_id
        self.params = dict(params)
        self._last_pct = -1.0
        self.feedback = Feedback(on_progress=self._emit_progress, on_log=self.log.emit)

    def _emit_progress(self, pct: float) -> None:
        # A tenth of a percent is as fine as a progress bar shows; spare the event queue.
        if abs(pct - self._last_pct) >= 0.1 or pct >= 100.0:
            self._last_pct = pct
            self.progress.emit(pct)

    def cancel(self) -> None:
        """Ask the running algorithm to stop (thread-safe)."""
        self.feedback.cancel()

    def call(self) -> Any:
        """The work itself (in the worker's thread): the registry run of the algorithm."""
        return registry.run(self.algorithm_id, self.params, self.feedback)

    @pyqtSlot()
    def run(self) -> None:
        try:
            result = self.call()
        except Cancelled as exc:
            self.cancelled.emit(str(exc))
        except PhotodemError as exc:
            self.failed.emit(str(exc), True, exc.message)
        except Exception:  # a bug: show the traceback, keep the GUI alive
            self.failed.emit(traceback.format_exc(), False, None)
        else:
            self.finished.emit(result)
        finally:
            self.done.emit()


#: Threads started by :func:`start_in_thread` that have not been joined yet. None of them is
#: the child of a widget: a widget deleted while its run winds down would delete the QThread
#: with it, and ``~QThread`` then waits for the thread while holding the GIL that the thread
#: needs to delete its Python worker — a deadlock (it hung a CI run once). Each keeps its
#: worker referenced until it has ended: a worker nobody else holds (``Feedback`` makes it a
#: reference cycle) would otherwise be collected by Python's garbage collector, its QObject
#: deleted before ``run`` and the thread never told to quit (a test hung 1 run in 4).
#: The worker is deleted in the GUI thread, never in its own: deleting a Python-made QObject
#: takes Qt's connection locks and the GIL, and the GUI thread holds the GIL whenever it calls
#: into Qt from Python — a worker deleted in its thread while the GUI thread emitted a signal
#: deadlocked a test (its stack: the GUI thread in ``QTabWidget.setCurrentIndex``, the worker's
#: thread in C++ without a Python frame). So ``done`` moves the worker back to the GUI thread
#: and the GUI thread deletes it once the thread has been joined; after ``run`` the worker's
#: thread runs no Python and holds no lock the GUI thread waits for.
_LIVE: Dict[QThread, QObject] = {}


def start_in_thread(worker: QObject, on_finished: Optional[Callable[[], None]] = None
                    ) -> QThread:
    """Move ``worker`` to a new QThread, start it, and clean both up when the run is done.

    ``worker`` is a QObject with a ``run`` slot and a ``done`` signal emitted last
    (:class:`AlgorithmWorker`, the batch worker). After ``done`` it moves back to the GUI
    thread; the thread is joined there, then both are deleted there (see ``_LIVE``).
    ``on_finished`` is called in the GUI thread once the thread has ended — joined, so
    whatever the caller does next (delete its widget, start the next run) cannot meet a thread
    still winding down. It is connected before the thread starts: a run that fails at once can
    end its thread before a connection made after ``start()``.
    """
    thread = QThread()  # no parent: see _LIVE
    _LIVE[thread] = worker
    home = worker.thread()  # the GUI thread, where the worker is made and deleted

    def go_home() -> None:  # in the worker's thread, the last thing it does in Python
        worker.moveToThread(home)

    def ended() -> None:
        thread.wait()  # returns at once: the thread has ended
        _LIVE.pop(thread, None)
        worker.deleteLater()  # in the GUI thread (see _LIVE)
        thread.deleteLater()
        if on_finished is not None:
            on_finished()

    thread.finished.connect(ended)
    worker.moveToThread(thread)
    thread.started.connect(worker.run)
    worker.done.connect(go_home, Qt.DirectConnection)
    # Direct: quit() is thread-safe, and the thread then ends even while the GUI thread is
    # blocked in QThread.wait() (a queued quit would only run after that wait timed out).
    worker.done.connect(thread.quit, Qt.DirectConnection)
    thread.start()
    return thread
