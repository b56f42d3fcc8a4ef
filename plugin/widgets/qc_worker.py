"""A worker that runs a core function off the GUI thread (the QC panel's computations)."""

from __future__ import annotations

from typing import Any, Callable, Dict, Optional

from ..qt import QtCore
from .worker import AlgorithmWorker


class FunctionWorker(AlgorithmWorker):
    """An :class:`~.worker.AlgorithmWorker` that calls a core function instead of the registry.

    ``function(**kwargs, feedback=…)``; the same signals, cancel and thread handling.
    """

    def __init__(self, function: Callable[..., Any], kwargs: Dict[str, Any],
                 parent: Optional[QtCore.QObject] = None) -> None:
        super().__init__(getattr(function, "__name__", "qc"), {}, parent)
        self.function = function
        self.kwargs = dict(kwargs)

    def call(self) -> Any:
        """The core function with the worker's feedback."""
        return self.function(**self.kwargs, feedback=self.feedback)
