"""Running an algorithm in a worker thread: the end of a run is always seen."""

from __future__ import annotations

import os

import pytest

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
pytest.importorskip("pytestqt")

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
        thread = start_in_thread(_Instant("none", {}), None, on_finished=lambda: ended.append(1))
        assert thread.wait(10000)
        qtbot.waitUntil(lambda n=run: len(ended) == n, timeout=5000)
