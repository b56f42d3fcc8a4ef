"""Running an algorithm in a worker thread: the end of a run is always seen."""

from __future__ import annotations

import gc
import os
import threading

import pytest

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
pytest.importorskip("pytestqt")

from PyQt5 import sip

from photodem.plugin.qt import QtWidgets
from photodem.plugin.widgets.worker import AlgorithmWorker, start_in_thread


class _Instant(AlgorithmWorker):
    """A run that is over as soon as it starts."""

    def call(self) -> dict:
        return {}


def test_a_run_that_ends_at_once_is_seen_to_end(qtbot) -> None:
    # The thread has ended (wait) before the GUI thread looks again: a connection to its
    # end made after start() could come too late; on_finished is connected before it.
    ended: list = []
    for run in range(1, 21):
        thread = start_in_thread(_Instant("none", {}), on_finished=lambda: ended.append(1))
        assert thread.wait(10000)
        qtbot.waitUntil(lambda n=run: len(ended) == n, timeout=5000)


def test_the_end_comes_once_the_thread_is_gone(qtbot) -> None:
    # on_finished may delete the widget that started the run: by then the thread must have
    # ended entirely, else ~QThread waits for it while holding the GIL that the thread needs
    # to delete its Python worker (a deadlock).
    seen: list = []
    for run in range(1, 11):
        box: dict = {}
        box["thread"] = start_in_thread(
            _Instant("none", {}), on_finished=lambda b=box: seen.append(b["thread"].wait(0)))
        qtbot.waitUntil(lambda n=run: len(seen) == n, timeout=5000)
    assert seen == [True] * 10


def test_a_worker_nobody_holds_is_not_collected_before_it_ran(qtbot) -> None:
    # The worker is a reference cycle (its Feedback calls back into it): a garbage collection
    # right after the start used to delete it before run(), and the thread never ended.
    ended: list = []
    for run in range(1, 6):
        start_in_thread(_Instant("none", {}), on_finished=lambda: ended.append(1))
        gc.collect()
        qtbot.waitUntil(lambda n=run: len(ended) == n, timeout=5000)


def test_deleting_the_owner_while_the_run_goes_on(qtbot) -> None:
    release = threading.Event()

    class _Waiting(AlgorithmWorker):
        def call(self) -> dict:
            release.wait(10)
            return {}

    owner = QtWidgets.QWidget()
    ended: list = []
    worker = _Waiting("none", {})
    worker.finished.connect(owner.close)  # a connection to the widget that goes away
    start_in_thread(worker, on_finished=lambda: ended.append(1))
    sip.delete(owner)  # the window closes while its run goes on: the thread is not its child
    release.set()
    qtbot.waitUntil(lambda: ended == [1], timeout=10000)


def test_the_worker_is_deleted_in_the_gui_thread(qtbot) -> None:
    # Deleting a Python-made QObject takes Qt's connection locks and the GIL: deleted in its
    # own thread while the GUI thread emitted a signal, a worker deadlocked a test. It goes
    # back to the GUI thread with ``done`` and is deleted there once the thread has ended.
    gui = QtWidgets.QApplication.instance().thread()
    seen: list = []
    for run in range(1, 6):
        worker = _Instant("none", {})
        start_in_thread(worker, on_finished=lambda w=worker: seen.append(
            (w.thread() is gui or w.thread() == gui, sip.isdeleted(w))))
        qtbot.waitUntil(lambda n=run: len(seen) == n, timeout=5000)
        qtbot.waitUntil(lambda w=worker: sip.isdeleted(w), timeout=5000)
    assert seen == [(True, False)] * 5
