"""The batch dialog in QGIS: a Raster → PhotoDEM menu entry and the batch as a ``QgsTask``.

:func:`open_batch_dialog` opens :class:`~photodem.plugin.widgets.batch_dialog.BatchDialog` on
the open workspace's project (else the project used last), with ``QgsSettings`` for what it
remembers. The batch runs as a :class:`BatchTask` in QGIS's task manager (its progress bar and
cancel button work too), so closing the dialog can keep it running in the background. When it
ends, its raster and vector products are added to the workspace (``add_products``) and the
message bar says how it went.
"""

from __future__ import annotations

import multiprocessing
import shutil
import sys
from pathlib import Path
from typing import Any, Dict, List, Optional

from qgis.core import Qgis, QgsApplication, QgsSettings, QgsTask
from qgis.PyQt.QtCore import Qt

from ..i18n import tr
from ..qt import QAction, QIcon
from ..widgets.batch_dialog import BatchDialog
from ..widgets.batch_runner import BatchWorker
from .workspace import current_workspace

#: Python references of running batch tasks (task id → task): the task manager holds only the
#: C++ object, and a collected Python wrapper would lose ``run``.
_RUNNING: Dict[int, BatchTask] = {}


class BatchTask(QgsTask):
    """Runs a :class:`BatchWorker` in a task-manager thread; cancel reaches the batch.

    The worker's signals are emitted from the task's thread and reach the dialog queued; its
    ``done`` signal is emitted in :meth:`finished` (main thread), after the run's others.
    """

    def __init__(self, worker: BatchWorker) -> None:
        super().__init__(tr("PhotoDEM batch: {0}").format(worker.batch_file.name),
                         QgsTask.CanCancel)
        self.worker = worker
        self.started_run = False

    def run(self) -> bool:
        self.started_run = True
        self.worker.progress.connect(self.setProgress, Qt.DirectConnection)
        return self.worker.execute() is not None

    def cancel(self) -> None:
        self.worker.cancel()
        super().cancel()

    def finished(self, result: bool) -> None:
        """In the main thread, after :meth:`run` (or instead of it: cancelled before it
        began); ``result`` is not needed, the worker holds the summary."""
        _RUNNING.pop(id(self), None)
        if not self.started_run:  # cancelled in the task manager before it began
            self.worker.log.emit("warning", tr("The batch was cancelled before it started."))
        self.worker.done.emit()

    def wait(self, msecs: int = 60000) -> bool:
        """Block until :meth:`run` returned (tests, unloading the plugin)."""
        return bool(self.waitForFinished(msecs))


def start_batch_task(worker: BatchWorker) -> BatchTask:
    """Start ``worker`` as a task in QGIS's task manager; returns the task."""
    _python_for_workers()
    task = BatchTask(worker)
    _RUNNING[id(task)] = task
    QgsApplication.taskManager().addTask(task)
    return task


def _python_for_workers() -> None:
    """Batch workers are spawned processes: inside the QGIS application ``sys.executable``
    is QGIS itself, so point multiprocessing at a Python interpreter (best effort)."""
    if Path(sys.executable).name.lower().startswith("python"):
        return
    python = shutil.which("python3") or shutil.which("python")
    if python:
        multiprocessing.set_executable(python)


def open_batch_dialog(iface: Any, project: Optional[str] = None) -> BatchDialog:
    """Open the batch dialog (on the workspace's project unless ``project`` is given)."""
    workspace = current_workspace()
    if project is None and workspace is not None:
        project = str(workspace.root)
    parent = iface.mainWindow() if iface is not None else None

    def add_products(paths: List[str]) -> None:
        ws = current_workspace()
        if ws is not None:
            ws.add_products(paths)

    dialog = BatchDialog(project, parent, settings=QgsSettings(),
                         start_worker=start_batch_task, on_products=add_products)
    dialog.setAttribute(Qt.WA_DeleteOnClose, False)  # hidden while a batch runs on
    if iface is not None:
        dialog.report = lambda text: iface.messageBar().pushWarning("PhotoDEM", text)
        dialog.batch_finished.connect(lambda summary: _tell(iface, summary))
    dialog.show()
    return dialog


def _tell(iface: Any, summary: Optional[Dict[str, Any]]) -> None:
    """One message-bar line when a batch ends (also when its dialog is hidden)."""
    if summary is None:
        return
    counts = ", ".join(f"{v} {k}" for k, v in summary["counts"].items() if v)
    level = {"done": Qgis.Success, "failed": Qgis.Warning}.get(summary["status"], Qgis.Info)
    iface.messageBar().pushMessage(
        "PhotoDEM", tr("Batch {0}: {1}; summary in {2}").format(
            summary["status"], counts, summary["summary"]), level, 10)


class BatchMenu:
    """The *Batch over stereo models…* entry of the Raster → PhotoDEM menu."""

    def __init__(self, iface: Any, menu_title: str, icon: QIcon) -> None:
        self.iface = iface
        self.menu_title = menu_title
        self.dialog: Optional[BatchDialog] = None
        self.action = QAction(icon, tr("Batch over stereo models…"), iface.mainWindow())
        self.action.setObjectName("photodemBatchDialog")
        self.action.setToolTip(tr("Run steps over many stereo models, resumable"))
        self.action.triggered.connect(lambda _checked=False: self.open())

    def register(self) -> None:
        self.iface.addPluginToRasterMenu(self.menu_title, self.action)

    def open(self, project: Optional[str] = None) -> BatchDialog:
        """Show the running batch's dialog again, or open a new one."""
        if self.dialog is not None and self.dialog.is_running():
            self.dialog.show()
            self.dialog.raise_()
            return self.dialog
        if self.dialog is not None:
            self.dialog.deleteLater()
        self.dialog = open_batch_dialog(self.iface, project)
        return self.dialog

    def unregister(self) -> None:
        self.iface.removePluginRasterMenu(self.menu_title, self.action)
        if self.dialog is not None:
            self.dialog.cancel()
            self.dialog.wait(30000)
            self.dialog.deleteLater()
            self.dialog = None
        self.action.deleteLater()


__all__ = ["BatchMenu", "BatchTask", "open_batch_dialog", "start_batch_task"]
