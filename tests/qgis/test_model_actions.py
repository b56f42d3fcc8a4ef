"""Actions on a stereo model (identify/attribute table, layer tree, map canvas) in real QGIS."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any, List

import pytest
from _qgis_helpers import copy_block

pytestmark = pytest.mark.qgis

MODELS = ["0101_0102", "0102_0103", "0201_0202", "0202_0203"]


@pytest.fixture(scope="module")
def tiny_project(tmp_path_factory, tiny_block) -> Path:
    """The tiny project with its block layers per the contract (``.photodem/block.gpkg``)."""
    root = copy_block(tiny_block, tmp_path_factory.mktemp("ma"), "block")
    _write_block_gpkg(root)
    return root


def _write_block_gpkg(root: Path) -> None:
    """footprints (image) and stereo_models (name, left, right, b_h, overlap_pct)."""
    from qgis.core import QgsCoordinateTransformContext, QgsVectorFileWriter, QgsVectorLayer

    from photodem.algorithms.project.model import Project
    from photodem.algorithms.project.stereo_models import block_footprints

    project = Project.load(root)
    prints = {name: poly for name, (poly, _h) in block_footprints(project).items()}
    rows = {
        "footprints": ("field=image:string", [([n], p) for n, p in prints.items()]),
        "stereo_models": (
            "field=name:string&field=left:string&field=right:string&field=b_h:double"
            "&field=overlap_pct:double",
            [([m.name, m.left, m.right, 0.36, 60.0],
              prints[m.left].intersection(prints[m.right])) for m in project.models]),
    }
    target = root / ".photodem" / "block.gpkg"
    target.parent.mkdir(exist_ok=True)
    for layer_name, (fields, features) in rows.items():
        memory = QgsVectorLayer(f"Polygon?crs=EPSG:25832&{fields}", layer_name, "memory")
        _add_features(memory, features)
        options = QgsVectorFileWriter.SaveVectorOptions()
        options.driverName = "GPKG"
        options.layerName = layer_name
        if target.exists():
            options.actionOnExistingFile = QgsVectorFileWriter.CreateOrOverwriteLayer
        error = QgsVectorFileWriter.writeAsVectorFormatV3(
            memory, str(target), QgsCoordinateTransformContext(), options)
        assert error[0] == QgsVectorFileWriter.NoError, error


def _add_features(layer, features) -> None:
    from qgis.core import QgsFeature, QgsGeometry

    out = []
    for attributes, polygon in features:
        feature = QgsFeature(layer.fields())
        feature.setAttributes(attributes)
        feature.setGeometry(QgsGeometry.fromWkt(polygon.wkt))
        out.append(feature)
    assert layer.dataProvider().addFeatures(out)[0]


def _block_layer(root: Path, name: str, kind: str, on_node: bool = False):
    """A layer of block.gpkg added to the project and marked like the workspace marks it."""
    from qgis.core import QgsProject, QgsVectorLayer

    layer = QgsVectorLayer(f"{root / '.photodem' / 'block.gpkg'}|layername={name}", name, "ogr")
    assert layer.isValid()
    QgsProject.instance().addMapLayer(layer)
    target = QgsProject.instance().layerTreeRoot().findLayer(layer.id()) if on_node else layer
    target.setCustomProperty("photodem/kind", kind)
    target.setCustomProperty("photodem/project", str(root))
    return layer


def _feature(layer, model: str):
    return next(f for f in layer.getFeatures() if f["name"] == model)


@pytest.fixture
def actions(qgis_iface, provider):
    from photodem.plugin.qgis.model_actions import ModelActions

    model_actions = ModelActions(qgis_iface)
    model_actions.register()
    yield model_actions
    model_actions.unregister()
    for dialog in model_actions.dialogs:
        dialog.close()


@pytest.fixture
def workspace(monkeypatch):
    from photodem.plugin.qgis import background

    added: List[List[str]] = []

    class StandIn:
        def add_products(self, paths):
            added.append(list(paths))
            return []

    monkeypatch.setattr(background, "current_workspace", StandIn)
    return added


def _parameters(dialog) -> dict:
    return dialog.mainWidget().createProcessingParameters()


def _static(value) -> str:
    """A destination value of the dialog as a plain path."""
    sink = getattr(value, "sink", None)
    return str(sink.staticValue() if sink is not None else value)


def test_map_layer_actions_only_on_stereo_model_layers(actions, tiny_project):
    from qgis.gui import QgsGui

    models = _block_layer(tiny_project, "stereo_models", "stereo_models")
    prints = _block_layer(tiny_project, "footprints", "footprints")
    registry = QgsGui.mapLayerActionRegistry()
    texts = [a.text() for a in registry.mapLayerActions(models)]
    assert texts[-3:] == ["Match this model…", "Epipolar pair", "Filter its DSM…"]
    assert not [a for a in registry.mapLayerActions(prints) if a in actions.layer_actions]
    actions.unregister()
    assert not [a for a in registry.mapLayerActions(models) if a.text() == "Epipolar pair"]
    actions.register()  # for the fixture's teardown


def test_match_this_model_opens_the_dialog_with_project_and_model(actions, tiny_project):
    from processing.gui.AlgorithmDialog import AlgorithmDialog

    layer = _block_layer(tiny_project, "stereo_models", "stereo_models")
    match = actions.layer_actions[0]
    match.triggerForFeature(layer, _feature(layer, "0201_0202"))
    dialog = actions.dialogs[-1]
    assert isinstance(dialog, AlgorithmDialog) and dialog.isVisible()
    assert dialog.algorithm().id() == "photodem:match_model"
    params = _parameters(dialog)
    assert params["project"] == str(tiny_project) and params["model"] == "0201_0202"
    assert _static(params["output"]) == str(tiny_project / "products" / "dsm" / "0201_0202")
    assert dialog.mainWidget().wrappers["model"].models() == MODELS


def test_epipolar_pair_runs_in_the_background(actions, tiny_project, workspace, qtbot,
                                              qgis_iface):
    layer = _block_layer(tiny_project, "stereo_models", "stereo_models", on_node=True)
    actions.layer_actions[1].triggerForFeature(layer, _feature(layer, "0102_0103"))
    assert actions.tasks and "0102_0103" in actions.tasks[-1].description()
    qtbot.waitUntil(lambda: bool(workspace), timeout=120000)
    folder = tiny_project / "products" / "epipolar" / "0102_0103"
    assert str(folder / "left.tif") in workspace[0]
    qtbot.waitUntil(lambda: any("0102_0103" in w.text()
                                for w in qgis_iface.messageBar().items()), timeout=5000)


def test_filter_its_dsm_needs_a_dsm_then_fills_it_in(actions, tiny_project, qgis_iface):
    layer = _block_layer(tiny_project, "stereo_models", "stereo_models")
    model = "0202_0203"
    filter_dsm = actions.layer_actions[2]
    filter_dsm.triggerForFeature(layer, _feature(layer, model))
    assert actions.dialogs == []
    texts = [w.text() for w in qgis_iface.messageBar().items()]
    assert any("no DSM yet" in t and model in t for t in texts), texts
    dsm = tiny_project / "products" / "dsm" / model / "dsm.tif"
    dsm.parent.mkdir(parents=True)
    shutil.copy(tiny_project / "truth" / "dsm.tif", dsm)
    try:
        filter_dsm.triggerForFeature(layer, _feature(layer, model))
        dialog = actions.dialogs[-1]
        assert dialog.algorithm().id() == "photodem:filter_lowpass"
        params = _parameters(dialog)
        assert params["input"] == str(dsm)
        assert params["project"] == str(tiny_project)
        assert _static(params["output"]) == str(tiny_project / "products" / "dtm" / model)
    finally:
        shutil.rmtree(dsm.parent)


def test_layer_tree_actions_on_the_stereo_models_layer(actions, tiny_project, qgis_iface,
                                                       qtbot):
    layer = _block_layer(tiny_project, "stereo_models", "stereo_models")
    other = _block_layer(tiny_project, "footprints", "footprints")
    qtbot.waitUntil(lambda: bool(qgis_iface.layer_action_layers), timeout=2000)
    attached = {(a.text(), lid) for a, lid in qgis_iface.layer_action_layers}
    assert ("Match this model…", layer.id()) in attached
    assert not [lid for _a, lid in qgis_iface.layer_action_layers if lid == other.id()]
    assert set(qgis_iface.layer_actions) == set(actions.tree_actions)
    qgis_iface.setActiveLayer(layer)
    layer.selectByIds([_feature(layer, "0101_0102").id()])
    actions.tree_actions[0].trigger()
    assert _parameters(actions.dialogs[-1])["model"] == "0101_0102"
    # several selected: the picker is asked (the real one is a list dialog)
    layer.selectAll()
    asked: List[Any] = []
    actions.pick_model = lambda lyr: asked.append(lyr) or "0202_0203"
    actions.tree_actions[0].trigger()
    assert asked == [layer] and _parameters(actions.dialogs[-1])["model"] == "0202_0203"
    qgis_iface.setActiveLayer(other)
    count = len(actions.dialogs)
    actions.tree_actions[0].trigger()
    assert len(actions.dialogs) == count
    assert any("stereo-models layer" in w.text() for w in qgis_iface.messageBar().items())


def test_right_click_on_the_map_offers_the_models_under_it(actions, tiny_project, qgis_iface):
    from qgis.core import QgsCoordinateReferenceSystem, QgsPointXY
    from qgis.gui import QgsMapMouseEvent
    from qgis.PyQt.QtCore import QEvent, QPoint, Qt
    from qgis.PyQt.QtWidgets import QMenu

    layer = _block_layer(tiny_project, "stereo_models", "stereo_models")
    canvas = qgis_iface.mapCanvas()
    canvas.setDestinationCrs(QgsCoordinateReferenceSystem("EPSG:25832"))
    canvas.setLayers([layer])
    canvas.setExtent(layer.extent())
    # a point inside exactly one model: the centre of 0101_0102 minus the other models
    geometry = _feature(layer, "0101_0102").geometry()
    for f in layer.getFeatures():
        if f["name"] != "0101_0102":
            geometry = geometry.difference(f.geometry())
    centre = geometry.pointOnSurface().asPoint()
    pixel = canvas.getCoordinateTransform().transform(QgsPointXY(centre))
    event = QgsMapMouseEvent(canvas, QEvent.MouseButtonPress,
                             QPoint(round(pixel.x()), round(pixel.y())), Qt.RightButton)
    menu = QMenu()
    canvas.contextMenuAboutToShow.emit(menu, event)
    subs = [a.menu() for a in menu.actions() if a.menu() is not None]
    assert [m.title() for m in subs] == ["Stereo model 0101_0102"]
    entries = subs[0].actions()
    assert [a.text() for a in entries] == ["Match this model…", "Epipolar pair",
                                           "Filter its DSM…"]
    entries[0].trigger()
    assert _parameters(actions.dialogs[-1])["model"] == "0101_0102"
    outside = QgsMapMouseEvent(canvas, QEvent.MouseButtonPress, QPoint(1, 1), Qt.RightButton)
    empty = QMenu()
    canvas.contextMenuAboutToShow.emit(empty, outside)
    assert empty.actions() == []


def test_a_real_right_click_with_the_pan_tool_shows_the_model_menu(actions, tiny_project,
                                                                    qgis_iface):
    from qgis.core import QgsCoordinateReferenceSystem, QgsPointXY
    from qgis.gui import QgsMapToolPan
    from qgis.PyQt.QtCore import QPoint, Qt, QTimer
    from qgis.PyQt.QtTest import QTest
    from qgis.PyQt.QtWidgets import QApplication

    layer = _block_layer(tiny_project, "stereo_models", "stereo_models")
    canvas = qgis_iface.mapCanvas()
    canvas.setDestinationCrs(QgsCoordinateReferenceSystem("EPSG:25832"))
    canvas.setLayers([layer])
    canvas.setExtent(layer.extent())
    pan = QgsMapToolPan(canvas)
    canvas.setMapTool(pan)
    centre = _feature(layer, "0202_0203").geometry()
    for f in layer.getFeatures():
        if f["name"] != "0202_0203":
            centre = centre.difference(f.geometry())
    pixel = canvas.getCoordinateTransform().transform(
        QgsPointXY(centre.pointOnSurface().asPoint()))
    seen: List[str] = []

    def read_and_close() -> None:  # the menu is modal: read it, then close it
        popup = QApplication.activePopupWidget()
        if popup is not None:
            seen.extend(a.text() for a in popup.actions())
            popup.close()

    QTimer.singleShot(300, read_and_close)
    QTest.mouseClick(canvas.viewport(), Qt.RightButton, Qt.NoModifier,
                     QPoint(round(pixel.x()), round(pixel.y())))
    QTest.qWait(400)
    assert "Stereo model 0202_0203" in seen, seen


def test_the_dialog_opened_by_the_action_runs_match_model_as_a_task(actions, tiny_project,
                                                                    qtbot):
    from qgis.core import QgsApplication

    layer = _block_layer(tiny_project, "stereo_models", "stereo_models")
    model = "0202_0203"
    actions.layer_actions[0].triggerForFeature(layer, _feature(layer, model))
    dialog = actions.dialogs[-1]
    before = len(QgsApplication.taskManager().tasks())
    dialog.runAlgorithm()  # what the Run button does
    assert len(QgsApplication.taskManager().tasks()) >= before  # 3.22: a background task
    qtbot.waitUntil(lambda: bool(dialog.results()), timeout=120000)
    dsm = tiny_project / "products" / "dsm" / model / "dsm.tif"
    assert dialog.results()["dsm"] == str(dsm) and dsm.is_file()
