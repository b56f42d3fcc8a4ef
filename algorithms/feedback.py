"""Progress, cancellation and log lines for long work.

Core functions take a :class:`Feedback` (or ``None``) and call :meth:`Feedback.progress`,
:meth:`Feedback.check` (raises :class:`~photodem.algorithms.errors.Cancelled`) and
:meth:`Feedback.info`. Adapters subclass it: QGIS wraps ``QgsProcessingFeedback``, the standalone
tool a Qt signal, the CLI a progress line on stderr.
"""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Callable, List, Optional

from .errors import Cancelled


class Feedback:
    """Base feedback: records log lines, keeps the last progress, cancels by flag.

    Parameters
    ----------
    on_progress : callable, optional
        Called with the overall progress in percent (0–100).
    on_log : callable, optional
        Called with ``(level, message)``; level is ``"info"``, ``"warning"`` or ``"error"``.
    """

    def __init__(
        self,
        on_progress: Optional[Callable[[float], None]] = None,
        on_log: Optional[Callable[[str, str], None]] = None,
    ) -> None:
        self._on_progress = on_progress
        self._on_log = on_log
        self._cancel = threading.Event()
        self._committed = threading.Event()
        #: The outputs the run has renamed into place, in order (for the message after a stop).
        self.committed: List[Path] = []
        self.percent = 0.0
        self.lines: List[str] = []
        self.warnings: List[str] = []

    # -- cancellation -------------------------------------------------------------------------
    def cancel(self) -> None:
        """Ask the running work to stop at its next check."""
        self._cancel.set()

    def is_canceled(self) -> bool:
        """True once :meth:`cancel` was called."""
        return self._cancel.is_set()

    def mark_committed(self, path: Optional[Path] = None) -> None:
        """The run has renamed an output (``path``) into place: from now on it finishes,
        cancelled or not.

        Called by the run scope (:func:`..output_policy.commit`); a product set is never left
        half-replaced because an interrupt came late.
        """
        if path is not None:
            self.committed.append(Path(path))
        self._committed.set()

    def is_committed(self) -> bool:
        """True once the run has committed an output (see :meth:`mark_committed`)."""
        return self._committed.is_set()

    def check(self) -> None:
        """Raise :class:`Cancelled` if cancellation was requested and nothing is committed yet."""
        if self.is_canceled() and not self.is_committed():
            raise Cancelled()

    # -- progress and log ---------------------------------------------------------------------
    def progress(self, percent: float) -> None:
        """Report overall progress in percent and check for cancellation."""
        self.percent = float(min(max(percent, 0.0), 100.0))
        if self._on_progress is not None:
            self._on_progress(self.percent)
        self.check()

    def info(self, message: str) -> None:
        """A log line for the operator."""
        self.lines.append(message)
        if self._on_log is not None:
            self._on_log("info", message)

    def warning(self, message: str) -> None:
        """Something the operator should look at; the run goes on."""
        self.lines.append("WARNING: " + message)
        self.warnings.append(message)
        if self._on_log is not None:
            self._on_log("warning", message)

    def step(self, start: float, stop: float) -> StepFeedback:
        """A feedback whose 0–100 % maps onto ``start``–``stop`` % of this one."""
        return StepFeedback(self, start, stop)


class StepFeedback(Feedback):
    """Part of a longer run: maps its own 0–100 % onto a range of the parent's progress."""

    def __init__(self, parent: Feedback, start: float, stop: float) -> None:
        super().__init__()
        self.parent = parent
        self.start, self.stop = float(start), float(stop)

    def cancel(self) -> None:
        self.parent.cancel()

    def is_canceled(self) -> bool:
        return self.parent.is_canceled()

    def mark_committed(self, path: Optional[Path] = None) -> None:
        self.parent.mark_committed(path)

    def is_committed(self) -> bool:
        return self.parent.is_committed()

    def progress(self, percent: float) -> None:
        self.percent = float(min(max(percent, 0.0), 100.0))
        self.parent.progress(self.start + (self.stop - self.start) * self.percent / 100.0)

    def info(self, message: str) -> None:
        self.parent.info(message)

    def warning(self, message: str) -> None:
        self.parent.warning(message)


def ensure_feedback(feedback: Optional[Feedback]) -> Feedback:
    """The given feedback, or a silent one."""
    return feedback if feedback is not None else Feedback()
