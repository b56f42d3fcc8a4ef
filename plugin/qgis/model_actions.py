"""Actions on a stereo model, offered where the operator sees the model on the map.

The stereo-models layer of a workspace (custom property ``photodem/kind`` = ``stereo_models``,
``photodem/project`` = the project folder; one polygon per model with the field ``name``) gets:

* *Match this model…* — the Processing dialog of ``match_model`` with project and model filled
  in (the dialog's own run goes into a background task);
* *Epipolar pair* — ``epipolar_pair`` of the model as a background task;
* *Filter its DSM…* — the dialog of ``filter_lowpass`` with the model's DSM filled in.

They are offered in three places: as ``QgsMapLayerAction`` (identify results, attribute table:
the feature is known), in the layer tree's context menu of the stereo-models layer (the model is
the selected feature, else picked from a list) and in the map canvas's context menu
(``QgsMapCanvas.contextMenuAboutToShow``, 3.16+) for the models under the click.
"""

from __future__ import annotations

import contextlib
from typing import Any, Callable, Dict, List, Optional, Tuple

from qgis.core import (
    Qgis,
    QgsApplication,
    QgsCoordinateTransform,
    QgsFeatureRequest,
    QgsGeometry,
    QgsMapLayer,
    QgsMapLayerType,
    QgsPointXY,
    QgsProject,
    QgsRectangle,
    QgsVectorLayer,
)
from qgis.gui import QgsGui, QgsMapLayerAction
from qgis.PyQt.QtCore import QObject, QTimer
from qgis.PyQt.QtWidgets import QAction, QInputDialog, QMenu

from ...algorithms.errors import PhotodemError
from ...algorithms.project.model_runs import (
    NoDsmYet,
    epipolar_pair_parameters,
    filter_dsm_parameters,
    match_model_parameters,
)
from ..i18n import tr
from .background import run_in_background
from .provider import PROVIDER_ID

KIND_PROPERTY = "photodem/kind"
PROJECT_PROPERTY = "photodem/project"
STEREO_MODELS_KIND = "stereo_models"
#: The layer-tree context-menu entry that holds the actions.
TREE_MENU = "PhotoDEM"

#: A handler of an action: (project folder, model name) → whatever it opened or started.
Handler = Callable[[str, str], Any]


def layer_property(layer: Optional[QgsMapLayer], key: str) -> str:
    """A PhotoDEM custom property of a layer: on the layer, else on its layer-tree node."""
    if layer is None:
        return ""
    value = layer.customProperty(key)
    if value in (None, ""):
        node = QgsProject.instance().layerTreeRoot().findLayer(layer.id())
        value = node.customProperty(key) if node is not None else None
    return "" if value is None else str(value)


def is_stereo_models_layer(layer: Optional[QgsMapLayer]) -> bool:
    """True for a vector layer the workspace marked as its stereo models."""
    return (isinstance(layer, QgsVectorLayer)
            and layer_property(layer, KIND_PROPERTY) == STEREO_MODELS_KIND)


def model_names(layer: QgsVectorLayer, selected_only: bool = False) -> List[str]:
    """The ``name`` values of a stereo-models layer (of its selected features)."""
    features = layer.getSelectedFeatures() if selected_only else layer.getFeatures()
    return [str(f["name"]) for f in features]


class StereoModelAction(QgsMapLayerAction):
    """A map-layer action on one feature of a stereo-models layer (and on no other layer)."""

    def __init__(self, text: str, parent: QObject, handler: Handler,
                 report: Callable[[str], None]) -> None:
        super().__init__(text, parent, QgsMapLayerAction.SingleFeature)
        self.handler = handler
        self.report = report
        self.triggeredForFeature.connect(self._triggered)

    def canRunUsingLayer(self, layer: QgsMapLayer) -> bool:  # noqa: N802 (QGIS API)
        return is_stereo_models_layer(layer)

    def _triggered(self, layer: QgsMapLayer, feature: Any) -> None:
        name = str(feature["name"])  # copy at once: QGIS passes a temporary feature
        project = layer_property(layer, PROJECT_PROPERTY)
        if not project:
            self.report(tr("The layer '{0}' names no PhotoDEM project.").format(layer.name()))
            return
        self.handler(project, name)


class ModelActions(QObject):
    """The stereo-model actions of the plugin: register them with QGIS, run them.

    Parameters
    ----------
    iface : QgisInterface
        The desktop interface (message bar, main window, layer tree, map canvas).
    """

    def __init__(self, iface: Any) -> None:
        super().__init__()
        self.iface = iface
        self.layer_actions: List[StereoModelAction] = []
        self.tree_actions: List[QAction] = []
        self.dialogs: List[Any] = []  # references: open dialogs must outlive this call
        self.tasks: List[Any] = []
        #: Picks a model of a layer for the layer-tree actions (tests replace it).
        self.pick_model: Callable[[QgsVectorLayer], Optional[str]] = self._ask_model

    # -- what each action does ------------------------------------------------------------------
    def entries(self) -> List[Tuple[str, Handler]]:
        """The actions as (label, handler), in menu order."""
        return [(tr("Match this model…"), self.match_model),
                (tr("Epipolar pair"), self.epipolar_pair),
                (tr("Filter its DSM…"), self.filter_dsm)]

    def match_model(self, project: str, model: str) -> Any:
        """Open the ``match_model`` dialog with project, model and output folder filled in.

        The output is the spec's default folder ``products/dsm/<model>/``, written out so the
        operator sees where the DSM goes.
        """
        try:
            params = match_model_parameters(project, model)
        except PhotodemError:  # unreadable: the dialog itself says so
            params = {"project": project, "model": model}
        return self.open_dialog("match_model", params)

    def epipolar_pair(self, project: str, model: str) -> Any:
        """Start ``epipolar_pair`` of the model as a background task."""

        def done(ok: bool, results: Dict[str, Any]) -> None:
            if ok:
                self.message(tr("Epipolar pair of {0} written to {1}.").format(
                    model, results.get("folder", "")), Qgis.Success)

        try:
            params = epipolar_pair_parameters(project, model)
        except PhotodemError as exc:
            self._warn(str(exc))
            return None
        task = run_in_background("epipolar_pair", params, done, iface=self.iface)
        self.tasks = [t for t in self.tasks if _alive(t)] + [task]
        return task

    def filter_dsm(self, project: str, model: str) -> Any:
        """Open the ``filter_lowpass`` dialog for the model's DSM (a message if it has none)."""
        try:
            params = filter_dsm_parameters(project, model)
        except NoDsmYet as exc:
            self.message(tr("Stereo model {0} has no DSM yet ({1}); match it first.").format(
                exc.model, exc.dsm), Qgis.Warning)
            return None
        except PhotodemError as exc:
            self.message(str(exc), Qgis.Warning)
            return None
        return self.open_dialog("filter_lowpass", params)

    def open_dialog(self, algorithm_id: str, parameters: Dict[str, Any]) -> Any:
        """Show the Processing dialog of ``photodem:<algorithm_id>`` filled with ``parameters``.

        Like ``processing.createAlgorithmDialog`` (which needs ``qgis.utils.iface``), but with
        this plugin's interface as parent; shown modeless so the map stays usable.
        """
        # lazy: QGIS's processing plugin exists only in the desktop application
        from processing.gui.AlgorithmDialog import AlgorithmDialog

        algorithm = QgsApplication.processingRegistry().createAlgorithmById(
            f"{PROVIDER_ID}:{algorithm_id}")
        dialog = AlgorithmDialog(algorithm, parent=self.iface.mainWindow())
        dialog.setParameters(parameters)
        dialog.show()
        self.dialogs = [d for d in self.dialogs if d.isVisible()] + [dialog]
        return dialog

    def message(self, text: str, level: Any = Qgis.Info) -> None:
        """A line in the message bar."""
        self.iface.messageBar().pushMessage("PhotoDEM", text, level)

    # -- registration ---------------------------------------------------------------------------
    def register(self) -> None:
        """Offer the actions in identify results, attribute table, layer tree and canvas menu."""
        registry = QgsGui.mapLayerActionRegistry()
        for text, handler in self.entries():
            action = StereoModelAction(text, self, handler, self._warn)
            registry.addMapLayerAction(action)
            self.layer_actions.append(action)
            tree_action = QAction(text, self.iface.mainWindow())
            tree_action.triggered.connect(lambda _=False, h=handler: self.run_on_current_layer(h))
            self.iface.addCustomActionForLayerType(
                tree_action, TREE_MENU, QgsMapLayerType.VectorLayer, False)
            self.tree_actions.append(tree_action)
        QgsProject.instance().layersAdded.connect(self._layers_added)
        self._attach([layer.id() for layer in QgsProject.instance().mapLayers().values()])
        self.iface.mapCanvas().contextMenuAboutToShow.connect(self.populate_canvas_menu)

    def unregister(self) -> None:
        """Withdraw every action registered by :meth:`register`."""
        registry = QgsGui.mapLayerActionRegistry()
        for action in self.layer_actions:
            registry.removeMapLayerAction(action)
            action.deleteLater()
        for action in self.tree_actions:
            self.iface.removeCustomActionForLayerType(action)
            action.deleteLater()
        self.layer_actions, self.tree_actions = [], []
        _disconnect(QgsProject.instance().layersAdded, self._layers_added)
        _disconnect(self.iface.mapCanvas().contextMenuAboutToShow, self.populate_canvas_menu)

    def _layers_added(self, layers: List[QgsMapLayer]) -> None:
        # The workspace marks a layer right after adding it: look once control is back.
        ids = [layer.id() for layer in layers]
        QTimer.singleShot(0, lambda: self._attach(ids))

    def _attach(self, layer_ids: List[str]) -> None:
        """Show the layer-tree actions on the stereo-models layers among ``layer_ids``."""
        for layer_id in layer_ids:
            layer = QgsProject.instance().mapLayer(layer_id)
            if is_stereo_models_layer(layer):
                for action in self.tree_actions:
                    self.iface.addCustomActionForLayer(action, layer)

    # -- layer tree -----------------------------------------------------------------------------
    def run_on_current_layer(self, handler: Handler) -> Any:
        """Run ``handler`` for the model picked in the current stereo-models layer."""
        layer = self.iface.layerTreeView().currentLayer()
        if not is_stereo_models_layer(layer):
            self._warn(tr("Select the stereo-models layer of a PhotoDEM project first."))
            return None
        project = layer_property(layer, PROJECT_PROPERTY)
        model = self.pick_model(layer)
        if not project or not model:
            return None
        return handler(project, model)

    def _ask_model(self, layer: QgsVectorLayer) -> Optional[str]:
        """The selected model; else the only one; else the operator picks one from a list."""
        selected = model_names(layer, selected_only=True)
        if len(selected) == 1:
            return selected[0]
        names = sorted(model_names(layer))
        if len(names) <= 1:
            return names[0] if names else None
        name, ok = QInputDialog.getItem(self.iface.mainWindow(), tr("Stereo model"),
                                        tr("Stereo model:"), names, 0, False)
        return str(name) if ok else None

    # -- map canvas -----------------------------------------------------------------------------
    def models_at(self, point: QgsPointXY) -> List[Tuple[str, str]]:
        """(project, model) of every stereo model under a canvas point (canvas CRS)."""
        canvas = self.iface.mapCanvas()
        found: List[Tuple[str, str]] = []
        for layer in canvas.layers():
            if not is_stereo_models_layer(layer):
                continue
            to_layer = QgsCoordinateTransform(canvas.mapSettings().destinationCrs(),
                                              layer.crs(), QgsProject.instance())
            here = QgsGeometry.fromPointXY(to_layer.transform(QgsPointXY(point)))
            project = layer_property(layer, PROJECT_PROPERTY)
            request = QgsFeatureRequest().setFilterRect(QgsRectangle(here.boundingBox()))
            for feature in layer.getFeatures(request):
                if feature.geometry().contains(here):
                    found.append((project, str(feature["name"])))
        return found

    def populate_canvas_menu(self, menu: QMenu, event: Any) -> None:
        """Add a sub-menu per stereo model under a right click on the map."""
        point = QgsPointXY(event.mapPoint())  # copy: the event dies with the click
        for project, model in self.models_at(point):
            sub = menu.addMenu(tr("Stereo model {0}").format(model))
            for text, handler in self.entries():
                action = sub.addAction(text)
                action.triggered.connect(
                    lambda _=False, h=handler, p=project, m=model: h(p, m))

    def _warn(self, text: str) -> None:
        self.message(text, Qgis.Warning)


def _alive(task: Any) -> bool:
    """False once QGIS has deleted a finished task."""
    try:
        task.status()
    except RuntimeError:
        return False
    return True


def _disconnect(signal: Any, slot: Any) -> None:
    # TypeError: never connected; RuntimeError: the emitter is gone already
    with contextlib.suppress(TypeError, RuntimeError):
        signal.disconnect(slot)

