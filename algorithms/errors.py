"""Errors an operator can cause, and cancellation.

Every error an operator can fix (a missing file, no overlap, a wrong CRS, a bad parameter) is a
:class:`PhotodemError` whose message says what is wrong and what to do. The CLI prints it without
a traceback and exits 2; QGIS and the standalone tool show it in their log.
"""

from __future__ import annotations

from typing import Any, Dict, Optional


class PhotodemError(Exception):
    """An error the operator can fix; the message is shown as it is.

    ``counts``: the figures behind the message as data (e.g. a failed georeferencing's pair
    and score counts); empty where there are none.
    """

    def __init__(self, message: str = "", counts: Optional[Dict[str, Any]] = None) -> None:
        super().__init__(message)
        self.counts: Dict[str, Any] = dict(counts or {})


class InputError(PhotodemError):
    """An input file, layer or parameter is missing or unusable."""


class GeometryError(PhotodemError):
    """The photogrammetric geometry does not allow the operation (no overlap, ray misses DEM…)."""


class Cancelled(PhotodemError):
    """The operator cancelled the run; no output was left behind."""

    def __init__(self, message: str = "Cancelled by the operator; no output was written.") -> None:
        super().__init__(message)
