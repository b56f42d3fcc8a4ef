"""PhotoDEM algorithms as QGIS background tasks.

:func:`run_in_background` starts ``photodem:<id>`` as a ``QgsProcessingAlgRunnerTask`` in
QGIS's task manager (progress bar, cancel button), calls back in the main thread when it ends,
adds the run's raster and vector products to the open workspace and reports a failure in the
message bar. Tasks never touch widgets: everything visible happens in the callback.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable, Dict, List, Optional

from qgis.core import (
    Qgis,
    QgsApplication,
    QgsMapLayer,
    QgsProcessingAlgRunnerTask,
    QgsProcessingContext,
    QgsProcessingFeedback,
    QgsProject,
    QgsRasterLayer,
    QgsTask,
    QgsVectorLayer,
)
from qgis.PyQt.QtCore import QTimer

from ...algorithms.processing import registry
from ..i18n import tr
from .provider import PROVIDER_ID

#: Output kinds whose files are added to the map when a run ends.
MAP_OUTPUT_KINDS = ("raster", "vector")

#: Python references of the running tasks (task, context, feedback, algorithm, callback):
#: without them Python would collect the context or the feedback while the task still runs.
_RUNNING: Dict[int, Dict[str, Any]] = {}


class TaskFeedback(QgsProcessingFeedback):
    """Processing feedback that keeps the run's error messages for the message bar."""

    def __init__(self) -> None:
        super().__init__()
        self.errors: List[str] = []

    def reportError(self, error: str, fatalError: bool = False) -> None:  # noqa: N802
        self.errors.append(str(error))
        super().reportError(error, fatalError)


def current_workspace() -> Any:
    """The open PhotoDEM workspace, or None (also when the workspace module is missing)."""
    try:
        from .workspace import current_workspace as workspace_now  # optional: the workspace
    except ImportError:  # module of another part; absent in a build without it
        return None
    return workspace_now()


def product_paths(algorithm_id: str, results: Dict[str, Any]) -> List[str]:
    """The existing raster and vector files among the results, in the spec's output order."""
    spec = registry.algorithms().get(algorithm_id)
    if spec is None:
        return []
    paths = []
    for output in spec.outputs:
        value = results.get(output.name)
        if output.kind in MAP_OUTPUT_KINDS and isinstance(value, str) and Path(value).is_file():
            paths.append(value)
    return paths


def add_products(paths: List[str]) -> List[QgsMapLayer]:
    """Add files to the workspace's Products group; without a workspace, to the map's root."""
    workspace = current_workspace()
    if workspace is not None:
        return list(workspace.add_products(paths))
    layers: List[QgsMapLayer] = []
    for path in paths:
        name = f"{Path(path).parent.name}/{Path(path).stem}"
        layer: QgsMapLayer = QgsRasterLayer(path, name)
        if not layer.isValid():
            layer = QgsVectorLayer(path, name, "ogr")
        if layer.isValid():
            QgsProject.instance().addMapLayer(layer)
            layers.append(layer)
    return layers


def _message_bar(iface: Any) -> Any:
    """The message bar of ``iface`` or of the QGIS desktop (None under qgis_process)."""
    if iface is None:
        # lazy: qgis.utils.iface is set only inside the desktop application
        from qgis.utils import iface as desktop_iface

        iface = desktop_iface
    return iface.messageBar() if iface is not None else None


def task_description(algorithm: Any, parameters: Dict[str, Any]) -> str:
    """The task manager's line: algorithm name and the stereo model if there is one."""
    model = parameters.get("model")
    name = algorithm.displayName()
    # the model first: the task manager cuts long lines at the right
    return tr("PhotoDEM {1}: {0}").format(name, model) if model else tr(
        "PhotoDEM: {0}").format(name)


def run_in_background(
    algorithm_id: str,
    parameters: Dict[str, Any],
    on_finished: Callable[[bool, Dict[str, Any]], None],
    iface: Any = None,
) -> QgsTask:
    """Run ``photodem:<algorithm_id>`` as a task of QGIS's task manager.

    Parameters
    ----------
    algorithm_id : str
        A PhotoDEM algorithm id (``match_model``), without the provider prefix.
    parameters : dict
        Parameter values as for ``processing.run``.
    on_finished : callable
        ``on_finished(ok, results)``, called in the main thread when the task ends (``ok``
        False after an error or a cancel; ``results`` then ``{}``). Called after the products
        were added to the map.
    iface : QgisInterface, optional
        Whose message bar shows a failure; default the desktop's.

    Returns
    -------
    QgsTask
        The task, already handed to ``QgsApplication.taskManager()``.
    """
    algorithm = QgsApplication.processingRegistry().createAlgorithmById(
        f"{PROVIDER_ID}:{algorithm_id}")
    if algorithm is None:
        raise ValueError(f"unknown PhotoDEM algorithm {algorithm_id!r}")
    context = QgsProcessingContext()
    context.setProject(QgsProject.instance())
    feedback = TaskFeedback()
    task = QgsProcessingAlgRunnerTask(algorithm, parameters, context, feedback)
    task.setDescription(task_description(algorithm, parameters))
    key = id(task)
    _RUNNING[key] = {"task": task, "context": context, "feedback": feedback,
                     "algorithm": algorithm, "on_finished": on_finished}

    def executed(ok: bool, results: Dict[str, Any]) -> None:
        refs = _RUNNING.pop(key, {})
        _finish(algorithm_id, bool(ok), dict(results or {}), refs, iface)

    if task.isCanceled():  # preparing the algorithm failed: the task will never run
        QTimer.singleShot(0, lambda: executed(False, {}))
        return task
    task.executed.connect(executed)
    QgsApplication.taskManager().addTask(task)
    return task


def _finish(algorithm_id: str, ok: bool, results: Dict[str, Any], refs: Dict[str, Any],
            iface: Any) -> None:
    """Main thread, the task has ended: products to the map, failures to the message bar."""
    feedback: Optional[TaskFeedback] = refs.get("feedback")
    if ok:
        paths = product_paths(algorithm_id, results)
        if paths:
            add_products(paths)
    else:
        bar = _message_bar(iface)
        canceled = feedback is not None and feedback.isCanceled()
        if bar is not None:
            text = tr("{0} was cancelled.").format(algorithm_id) if canceled else (
                "; ".join(feedback.errors[-1:]) if feedback is not None and feedback.errors
                else tr("{0} failed; see the log messages.").format(algorithm_id))
            bar.pushMessage("PhotoDEM", text, Qgis.Warning if canceled else Qgis.Critical)
    callback = refs.get("on_finished")
    if callback is not None:
        callback(ok, results)


def running_tasks() -> List[QgsTask]:
    """The PhotoDEM tasks that have not ended yet."""
    return [refs["task"] for refs in _RUNNING.values()]
