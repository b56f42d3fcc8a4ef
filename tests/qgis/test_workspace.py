"""Tier B: a PhotoDEM project opened as the operator's workspace in real QGIS 3.22 (issue 18 §1):
groups, styled layers with guarded forms, products in step, a .qgz round trip, bad input."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Iterator

import pytest
from _qgis_helpers import copy_block

pytestmark = pytest.mark.qgis

EDIT_NAMES = ["start_points", "exclusion_areas", "boundaries", "breaklines", "ground_points",
              "seamlines", "check_points"]
#: What the layer tree shows for them (English UI).
EDIT_TITLES = ["Start points", "Exclusion areas", "Boundaries", "Breaklines", "Ground points",
               "Seamlines", "Check points"]


@pytest.fixture(scope="module")
def demo(tmp_path_factory, tiny_block) -> Path:
    """The tiny synthetic project with a matched model and its filtered DTM (made once)."""
    from photodem.algorithms.processing import registry

    root = copy_block(tiny_block, tmp_path_factory.mktemp("ws"), "demo")
    registry.run("match_model", {"project": str(root), "model": "0101_0102"})
    registry.run("filter_lowpass", {"input": str(root / "products/dsm/0101_0102/dsm.tif"),
                                    "project": str(root),
                                    "output": str(root / "products/dtm/0101_0102")})
    dtm = str(root / "truth" / "dtm.tif")
    registry.run("orthorectify", {"project": str(root), "image": "0101", "dem": dtm})
    registry.run("mosaic", {"project": str(root), "dem": dtm})
    registry.run("dem_compare", {"dem": str(root / "products/dsm/0101_0102/dsm.tif"),
                                 "reference": str(root / "truth" / "dsm.tif"),
                                 "output": str(root / "products/compare/0101_0102")})
    return root


@pytest.fixture
def project(demo, tmp_path) -> Path:
    """A fresh copy of the demo project for one test."""
    copy = tmp_path / "demo"
    shutil.copytree(demo, copy)
    return copy


@pytest.fixture
def ws_iface(qgis_iface) -> Iterator:
    """The widget iface; the current workspace is forgotten after the test."""
    from photodem.plugin.qgis.workspace import forget_workspace

    yield qgis_iface
    forget_workspace()


def _names(group) -> list:
    return [child.name() for child in group.children()]


def _messages(iface) -> list:
    return [item.text() for item in iface.messageBar().items()]


def test_open_gives_groups_and_styled_layers(project, ws_iface) -> None:
    from qgis.core import QgsProject

    from photodem.plugin.qgis.workspace import (
        BLOCK,
        EDITS,
        PRODUCTS,
        current_workspace,
        open_workspace,
    )

    ws = open_workspace(ws_iface, project)
    assert current_workspace() is ws and ws.root == project.resolve()
    root = QgsProject.instance().layerTreeRoot()
    assert [g.name() for g in root.children()] == [f"PhotoDEM – {ws.project.name}"]
    assert _names(ws.group) == ["Edits", "Block", "Products"]
    edits = ws.subgroup(EDITS)
    assert _names(edits) == EDIT_TITLES
    for name, node in zip(EDIT_NAMES, edits.findLayers()):
        layer = node.layer()
        assert layer.providerType() == "ogr" and not layer.readOnly()
        assert layer.customProperty("photodem/kind") == f"edit:{name}"
        assert layer.source().endswith(f"|layername={name}")
        assert layer.customProperty("photodem/project") == str(project.resolve())
    areas = ws.edit_layer("exclusion_areas")
    assert areas.renderer().type() == "categorizedSymbol"
    assert [c.value() for c in areas.renderer().categories()] == ["keep", "remove", "exclude"]
    widget = {name: ws.edit_layer(layer).fields().field(name).editorWidgetSetup()
              for layer, name in (("exclusion_areas", "action"), ("breaklines", "kind"),
                                  ("start_points", "height"))}
    assert {k: w.type() for k, w in widget.items()} == {"action": "ValueMap",
                                                        "kind": "ValueMap", "height": "Range"}
    assert widget["height"].config()["Suffix"] == " m"
    values = [v for entry in widget["action"].config()["map"] for v in entry.values()]
    assert values == ["keep", "remove", "exclude"]
    block = ws.subgroup(BLOCK)
    assert _names(block) == ["Stereo models", "Image footprints"]
    models = block.findLayers()[0].layer()
    assert models.customProperty("photodem/kind") == "stereo_models"
    assert models.featureCount() == len(ws.project.models) and models.labelsEnabled()
    assert block.findLayers()[1].layer().featureCount() == len(ws.project.images)
    ws.load_block()  # again: replaced, not doubled
    assert _names(ws.subgroup(BLOCK)) == ["Stereo models", "Image footprints"]
    products = [n.layer() for n in ws.subgroup(PRODUCTS).findLayers()]
    assert [p.name() for p in products] == ["DSM 0101_0102", "DSM 0101_0102 (hillshade)",
                                            "DTM 0101_0102", "DTM 0101_0102 (hillshade)",
                                            "Difference 0101_0102", "Ortho 0101",
                                            "Mosaic mosaic", "Seamlines mosaic"]
    assert [p.providerType() for p in products] == ["gdal"] * 7 + ["ogr"]
    assert [p.renderer().type() for p in products[:7]] == (
        ["singlebandpseudocolor", "hillshade"] * 2 + ["singlebandpseudocolor"]
        + ["multibandcolor"] * 2)
    assert products[0].renderer().opacity() == pytest.approx(0.5)
    shader = products[4].renderer().shader().rasterShaderFunction()  # dem_difference.qml
    assert (shader.minimumValue(), shader.maximumValue()) == (-5.0, 5.0)
    assert [p.renderer().alphaBand() for p in products[5:7]] == [4, 4]  # RGB with alpha
    assert products[7].geometryType() == 1 and "layername=seamlines" in products[7].source()
    assert [p.name() for p in ws.surface_layers()] == ["DSM 0101_0102", "DTM 0101_0102"]


def test_constraints_refuse_bad_values(project, ws_iface) -> None:
    from qgis.core import QgsFeature, QgsFieldConstraints, QgsVectorLayerUtils

    from photodem.plugin.qgis.workspace import open_workspace

    ws = open_workspace(ws_iface, project)

    def valid(layer_name: str, field: str, value) -> bool:
        layer = ws.edit_layer(layer_name)
        feature = QgsFeature(layer.fields())
        feature.setAttribute(field, value)
        index = layer.fields().indexOf(field)
        ok, _errors = QgsVectorLayerUtils.validateAttribute(
            layer, feature, index, QgsFieldConstraints.ConstraintStrengthHard)
        return ok

    assert all(valid("exclusion_areas", "action", v) for v in ("keep", "remove", "exclude"))
    assert not valid("exclusion_areas", "action", "kep")
    assert not valid("exclusion_areas", "action", None)
    assert valid("breaklines", "kind", "structure_line") and valid("breaklines", "kind", None)
    assert not valid("breaklines", "kind", "wall")
    assert valid("start_points", "height", 312.5)
    assert not valid("start_points", "height", 20000.0)
    assert not valid("start_points", "height", None)


def test_translated_labels_keep_english_values(project, ws_iface, monkeypatch) -> None:
    from photodem.plugin.qgis import styles
    from photodem.plugin.qgis.workspace import open_workspace

    german = {"keep": "behalten", "remove": "entfernen", "exclude": "ausschließen"}
    monkeypatch.setattr(styles, "tr", lambda text: german.get(text, text))
    ws = open_workspace(ws_iface, project)
    layer = ws.edit_layer("exclusion_areas")
    setup = layer.fields().field("action").editorWidgetSetup()
    pairs = [next(iter(e.items())) for e in setup.config()["map"]]
    assert pairs == [("behalten", "keep"), ("entfernen", "remove"), ("ausschließen", "exclude")]
    assert [c.label() for c in layer.renderer().categories()] == list(german.values())


def test_changed_signals(project, ws_iface) -> None:
    from photodem.plugin.qgis.workspace import (
        current_workspace,
        open_workspace,
        workspace_notifier,
    )

    seen = []
    workspace_notifier().changed.connect(seen.append)
    try:
        ws = open_workspace(ws_iface, project)
        closed = []
        ws.changed.connect(lambda: closed.append(current_workspace()))
        ws.close()
    finally:
        workspace_notifier().changed.disconnect(seen.append)
    assert seen == [ws, None] and closed == [None]
    assert ws.group is None and current_workspace() is None


def test_open_again_replaces_the_group(project, ws_iface) -> None:
    from qgis.core import QgsProject

    from photodem.plugin.qgis.workspace import open_workspace, workspace_groups

    open_workspace(ws_iface, project)
    count = len(QgsProject.instance().mapLayers())
    ws = open_workspace(ws_iface, project / "project.toml")
    assert len(workspace_groups()) == 1 and workspace_groups()[0] is ws.group
    assert len(QgsProject.instance().mapLayers()) == count


def test_add_products_replaces_older_layer_of_the_same_file(project, ws_iface, tmp_path) -> None:
    from qgis.core import QgsProject

    from photodem.plugin.qgis.workspace import PRODUCTS, open_workspace

    ws = open_workspace(ws_iface, project)
    dsm = project / "products/dsm/0101_0102/dsm.tif"
    old_ids = {layer.id() for layer in ws.layers("dsm")}
    added = ws.add_products([str(dsm)])
    assert [layer.name() for layer in added] == ["DSM 0101_0102", "DSM 0101_0102 (hillshade)"]
    assert len(ws.layers("dsm")) == 1 and ws.layers("dsm")[0].id() not in old_ids
    assert ws.subgroup(PRODUCTS).findLayers()[0].layer() is added[0]  # newest on top
    outside = tmp_path / "elsewhere" / "dsm.tif"
    outside.parent.mkdir()
    shutil.copy(dsm, outside)
    (layer, _shade) = ws.add_products([str(outside)])
    root = QgsProject.instance().layerTreeRoot()
    assert root.findLayer(layer.id()).parent() is root
    assert layer.renderer().type() == "singlebandpseudocolor"
    assert layer.customProperty("photodem/kind") == "dsm"
    assert layer.customProperty("photodem/project") == ""


def test_qgz_round_trip_rebinds_the_group(project, ws_iface, tmp_path) -> None:
    from qgis.core import QgsProject

    from photodem.plugin.qgis.project_menu import ProjectMenu
    from photodem.plugin.qgis.workspace import current_workspace

    menu = ProjectMenu(ws_iface, "&PhotoDEM")
    menu.register()
    try:
        ws = menu.open_project(str(project))
        names = [n.name() for n in ws.group.findLayers()]
        qgz = tmp_path / "session.qgz"
        assert QgsProject.instance().write(str(qgz))
        QgsProject.instance().clear()
        assert current_workspace() is None
        assert QgsProject.instance().read(str(qgz))
        again = current_workspace()
        assert again is not None and again is not ws and again.root == ws.root
        assert [n.name() for n in again.group.findLayers()] == names
        assert again.edit_layer("breaklines").isValid()
        assert again.surface_layers()[0].name() == "DSM 0101_0102"
    finally:
        menu.unregister()


def test_not_a_project_adds_nothing(tmp_path, ws_iface) -> None:
    from qgis.core import QgsProject

    from photodem.plugin.qgis.project_menu import ProjectMenu

    menu = ProjectMenu(ws_iface, "&PhotoDEM")
    menu.register()
    try:
        assert menu.open_project(str(tmp_path)) is None
        bad = tmp_path / "bad"
        bad.mkdir()
        (bad / "project.toml").write_text("[project\nname = ", encoding="utf-8")
        assert menu.open_project(str(bad)) is None
    finally:
        menu.unregister()
    assert QgsProject.instance().layerTreeRoot().children() == []
    text = " ".join(_messages(ws_iface))
    assert "is not a PhotoDEM project" in text and "not valid TOML" in text


def test_recent_projects_drop_missing_ones(project, ws_iface, tmp_path) -> None:
    from qgis.core import QgsSettings

    from photodem.plugin.qgis.project_menu import (
        RECENT_KEY,
        ProjectMenu,
        recent_projects,
        remember_project,
    )

    QgsSettings().remove(RECENT_KEY)
    gone = tmp_path / "gone"
    remember_project(gone)
    menu = ProjectMenu(ws_iface, "&PhotoDEM")
    menu.register()
    try:
        menu.open_project(str(project))
        assert recent_projects() == [str(project.resolve()), str(gone.resolve())]
        assert [a.text() for a in menu.recent_menu.actions()] == recent_projects()
        assert menu.open_recent(str(gone.resolve())) is None
        assert recent_projects() == [str(project.resolve())]
        assert any("no longer there" in m for m in _messages(ws_iface))
        for i in range(7):
            remember_project(tmp_path / f"p{i}")
        assert len(recent_projects()) == 5
    finally:
        menu.unregister()
        QgsSettings().remove(RECENT_KEY)


def _click_offer(iface) -> None:
    from qgis.PyQt.QtWidgets import QPushButton

    buttons = iface.messageBar().findChildren(QPushButton, "photodemOffer")
    assert buttons, _messages(iface)
    buttons[-1].click()


def test_missing_layer_is_offered_and_others_untouched(project, ws_iface) -> None:
    import fiona
    from shapely.geometry import Point

    from photodem.algorithms.project.edits import add_features, missing_edit_layers, read_layer
    from photodem.plugin.qgis.workspace import EDITS, open_workspace

    edits = project / "edits.gpkg"
    add_features(edits, "start_points", [(Point(0, 0), {"height": 12.0})])
    keep = [n for n in EDIT_NAMES if n != "breaklines"]
    saved = project / "saved.gpkg"
    for name in keep:  # rebuild the file without breaklines, keeping the features
        with fiona.open(str(edits), layer=name) as src, \
                fiona.open(str(saved), "w", layer=name, **src.meta) as dst:
            dst.writerecords(src)
    saved.replace(edits)
    ws = open_workspace(ws_iface, project)
    assert _names(ws.subgroup(EDITS)) == [t for t in EDIT_TITLES if t != "Breaklines"]
    assert any("breaklines" in m for m in _messages(ws_iface))
    points = ws.edit_layer("start_points")
    points.startEditing()  # while a layer is edited the file is not written
    _click_offer(ws_iface)
    assert missing_edit_layers(edits) == ["breaklines"]
    assert any("Save or discard the edits of Start points" in m for m in _messages(ws_iface))
    points.rollBack()
    _click_offer(ws_iface)  # offered again
    assert _names(ws.subgroup(EDITS)) == EDIT_TITLES  # in its place
    assert ws.edit_layer("breaklines").isValid() and ws.edit_layer("start_points") is points
    assert [ws.edit_layer(n).featureCount() for n in EDIT_NAMES] == [1, 0, 0, 0, 0, 0, 0]
    assert [p["height"] for _g, p in read_layer(edits, "start_points")] == [12.0]


def test_missing_edits_file_is_offered(project, ws_iface) -> None:
    from photodem.plugin.qgis.workspace import EDITS, open_workspace

    (project / "edits.gpkg").unlink()
    ws = open_workspace(ws_iface, project)
    assert _names(ws.subgroup(EDITS)) == []
    assert any("edits.gpkg" in m for m in _messages(ws_iface))
    _click_offer(ws_iface)
    assert (project / "edits.gpkg").is_file()
    assert _names(ws.subgroup(EDITS)) == EDIT_TITLES


def test_read_only_edits_load_read_only(project, ws_iface, monkeypatch) -> None:
    import os

    from photodem.plugin.qgis import workspace

    edits = str(project / "edits.gpkg")
    real = os.access
    monkeypatch.setattr(workspace.os, "access",
                        lambda p, mode: False if str(p) == edits else real(p, mode))
    ws = workspace.open_workspace(ws_iface, project)
    assert ws.read_only
    assert all(ws.edit_layer(n).readOnly() for n in EDIT_NAMES)
    assert any("read-only" in m for m in _messages(ws_iface))


class _StandInToolbar:
    """What the plugin calls of the editing toolbar."""

    workspace = None

    def set_workspace(self, workspace) -> None:
        self.workspace = workspace

    def unload(self) -> None:
        pass


def test_plugin_menu_opens_projects(project, ws_iface, monkeypatch) -> None:
    from photodem.plugin.qgis.plugin import MENU_TITLE, PhotodemPlugin
    from photodem.plugin.qgis.project_menu import ProjectMenu
    from photodem.plugin.qgis.workspace import current_workspace

    monkeypatch.setattr(PhotodemPlugin, "initProcessing", lambda self: None)  # session's stays
    plugin = PhotodemPlugin(ws_iface)
    plugin.initGui()
    try:
        names = [a.objectName() for a in ws_iface.menus[MENU_TITLE]]
        assert names[:1] == ["photodemOpenProject"]
        assert plugin.project_menu.recent_menu.menuAction() in ws_iface.menus[MENU_TITLE]
        monkeypatch.setattr(ProjectMenu, "ask_project", lambda self: str(project / "project.toml"))
        toolbar = getattr(plugin, "editing_toolbar", None)
        if toolbar is None:  # the editing toolbar (section 2) lives in another branch
            toolbar = plugin.editing_toolbar = _StandInToolbar()
        plugin.project_menu.open_action.trigger()
        assert current_workspace() is not None and current_workspace().root == project.resolve()
        assert toolbar.workspace is current_workspace()  # the toolbar works on the new project
    finally:
        plugin.unload()
    assert not any(a.objectName() == "photodemOpenProject"
                   for a in ws_iface.menus.get(MENU_TITLE, []))
