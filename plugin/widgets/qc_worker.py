"""A worker that runs a core function off the GUI thread (the QC panel's computations)."""

from __future__ import annotations

import traceback
from typing import Any, Callable, Dict, Optional

from ...algorithms.errors import Cancelled, PhotodemError
from ..qt import QtCore, pyqtSlot
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

    @pyqtSlot()
    def run(self) -> None:
        try:
            result = self.function(**self.kwargs, feedback=self.feedback)
        except Cancelled as exc:
            self.cancelled.emit(str(exc))
        except PhotodemError as exc:
            self.failed.emit(str(exc), True)
        except Exception:  # a bug: show the traceback, keep the GUI alive
            self.failed.emit(traceback.format_exc(), False)
        else:
            self.finished.emit(result)
        finally:
            self.done.emit()
