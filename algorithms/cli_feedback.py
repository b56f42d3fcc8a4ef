"""Feedback for the command line: progress and log lines on stderr, never on stdout.

stdout belongs to the result (``photodem run … --json`` prints exactly one JSON object there), so
everything the operator watches while a run goes on is written to stderr:

- on a terminal, one progress line ``[ 42%] last message`` that is redrawn in place
  (``\\r`` + erase to end of line), at most ten times a second;
- otherwise (a log file, a pipe, CI) plain lines: ``photodem: 40%`` at every 10 % step and log
  lines as ``photodem: message``;
- with ``quiet``, only warnings.
"""

from __future__ import annotations

import sys
import time
from typing import Callable, Optional, TextIO

from .feedback import Feedback


class CliFeedback(Feedback):
    """A :class:`Feedback` that writes progress and log lines to a text stream (stderr).

    Parameters
    ----------
    stream : text stream, optional
        Where to write; default ``sys.stderr`` at the time of each write.
    quiet : bool
        Suppress progress and info lines; warnings are still written.
    tty : bool, optional
        Force the terminal (single redrawn line) or the plain mode; default: ``stream.isatty()``.
    clock : callable, optional
        Monotonic clock in seconds (tests replace it).
    """

    #: Minimum time between two redraws of the terminal progress line (s).
    REDRAW_INTERVAL = 0.1
    #: Plain mode: a progress line at every multiple of this many percent.
    PLAIN_STEP = 10.0

    def __init__(
        self,
        stream: Optional[TextIO] = None,
        quiet: bool = False,
        tty: Optional[bool] = None,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        super().__init__()
        self._stream = stream
        self.quiet = quiet
        self._tty = tty
        self._clock = clock
        self._last_draw = -1e9
        self._last_plain = -1.0
        self._message = ""
        self._line_open = False  # a progress line without newline is on the terminal

    # -- stream helpers -----------------------------------------------------------------------
    @property
    def stream(self) -> TextIO:
        return self._stream if self._stream is not None else sys.stderr

    @property
    def tty(self) -> bool:
        if self._tty is None:
            try:
                self._tty = bool(self.stream.isatty())
            except (AttributeError, ValueError):
                self._tty = False
        return self._tty

    def _write(self, text: str) -> None:
        try:
            self.stream.write(text)
            self.stream.flush()
        except (OSError, ValueError):  # closed pipe: the run must not die of its log
            pass

    def _draw(self, force: bool = False) -> None:
        now = self._clock()
        if not force and now - self._last_draw < self.REDRAW_INTERVAL:
            return
        self._last_draw = now
        message = self._message[:70]
        self._write(f"\r[{self.percent:3.0f}%] {message}\x1b[K")
        self._line_open = True

    def _end_line(self) -> None:
        if self._line_open:
            self._write("\r\x1b[K")
            self._line_open = False

    # -- Feedback interface -------------------------------------------------------------------
    def progress(self, percent: float) -> None:
        previous = self.percent
        self.percent = float(min(max(percent, 0.0), 100.0))
        if not self.quiet:
            if self.tty:
                self._draw(force=self.percent >= 100.0 and previous < 100.0)
            else:
                step = self.PLAIN_STEP * int(self.percent // self.PLAIN_STEP)
                if step > self._last_plain:
                    self._last_plain = step
                    self._write(f"photodem: {step:.0f}%\n")
        self.check()

    def info(self, message: str) -> None:
        self.lines.append(message)
        if self.quiet:
            return
        if self.tty:
            self._end_line()
            self._write(message + "\n")
            self._message = message
            self._draw(force=True)
        else:
            self._write(f"photodem: {message}\n")

    def warning(self, message: str) -> None:
        self.lines.append("WARNING: " + message)
        self.warnings.append(message)
        self._end_line()
        self._write(f"photodem: warning: {message}\n")
        if self.tty and not self.quiet:
            self._draw(force=True)

    def close(self) -> None:
        """Clear the terminal progress line (call once when the run ends)."""
        self._end_line()
