"""Tier B: outputs loaded on completion (issue 18 §3): ``processing.runAndLoadResults`` adds the
styled DTM of a real ``filter_lowpass`` run (into the open workspace's Products group when it
lies in the project), and HTML reports are ``QgsProcessingOutputHtml``."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Iterator

import pytest
from _qgis_helpers import copy_block

pytestmark = pytest.mark.qgis


@pytest.fixture(scope="module")
def tiny(tmp_path_factory, tiny_block) -> Path:
    root = copy_block(tiny_block, tmp_path_factory.mktemp("load"), "tiny")
    return root


@pytest.fixture
def project(tiny, tmp_path) -> Path:
    copy = tmp_path / "tiny"
    shutil.copytree(tiny, copy)
    return copy


@pytest.fixture
def ws_iface(qgis_iface, provider) -> Iterator:
    from photodem.plugin.qgis.workspace import forget_workspace

    yield qgis_iface
    forget_workspace()


def _layers_of(path: Path) -> list:
    from qgis.core import QgsProject

    wanted = str(path.resolve())
    return [layer for layer in QgsProject.instance().mapLayers().values()
            if str(Path(layer.source().split("|")[0]).resolve()) == wanted]


def test_run_and_load_results_adds_the_dtm_into_the_workspace(project, ws_iface) -> None:
    import processing

    from photodem.plugin.qgis.workspace import PRODUCTS, open_workspace

    ws = open_workspace(ws_iface, project)
    out = project / "products" / "dtm" / "truth"
    result = processing.runAndLoadResults("photodem:filter_lowpass", {
        "input": str(project / "truth" / "dsm.tif"), "project": str(project),
        "output": str(out)})
    dtm = out / "dtm.tif"
    assert Path(result["dtm"]) == dtm and dtm.is_file()
    layers = _layers_of(dtm)
    assert sorted(layer.customProperty("photodem/kind") for layer in layers) == ["dtm",
                                                                                 "hillshade"]
    names = [n.layer().name() for n in ws.subgroup(PRODUCTS).findLayers()]
    assert names[:2] == ["DTM truth", "DTM truth (hillshade)"]
    ramp = ws.layers("dtm")[0]
    assert ramp.providerType() == "gdal" and ramp.renderer().type() == "singlebandpseudocolor"
    assert ws.surface_layers()[0] is ramp
    # a run that writes the file again replaces its layers, it does not add more (PhotoDEM
    # refuses a non-empty output folder, so the operator removed the old one first)
    shutil.rmtree(out)
    processing.runAndLoadResults("photodem:filter_lowpass", {
        "input": str(project / "truth" / "dsm.tif"), "project": str(project),
        "output": str(out)})
    assert len(_layers_of(dtm)) == 2
    assert [n.layer().name() for n in ws.subgroup(PRODUCTS).findLayers()][:2] == names[:2]


def test_mosaic_and_its_seamlines_are_loaded(project, ws_iface) -> None:
    import processing

    from photodem.plugin.qgis.workspace import PRODUCTS, open_workspace

    ws = open_workspace(ws_iface, project)
    processing.runAndLoadResults("photodem:mosaic", {
        "project": str(project), "dem": str(project / "truth" / "dtm.tif")})
    layers = {n.layer().name(): n.layer() for n in ws.subgroup(PRODUCTS).findLayers()}
    assert set(layers) == {"Mosaic mosaic", "Seamlines mosaic"}
    mosaic, seams = layers["Mosaic mosaic"], layers["Seamlines mosaic"]
    assert mosaic.renderer().type() == "multibandcolor" and mosaic.renderer().alphaBand() == 4
    assert seams.geometryType() == 1 and seams.source().endswith("|layername=seamlines")
    assert seams.customProperty("photodem/kind") == "seamlines"


def test_without_a_workspace_the_dtm_lands_at_the_root_styled(project, ws_iface,
                                                              tmp_path) -> None:
    import processing
    from qgis.core import QgsProject

    out = tmp_path / "elsewhere"
    processing.runAndLoadResults("photodem:filter_lowpass", {
        "input": str(project / "truth" / "dsm.tif"), "output": str(out)})
    (layer,) = _layers_of(out / "dtm.tif")
    assert layer.renderer().type() == "singlebandpseudocolor"
    assert layer.customProperty("photodem/kind") == "dtm"
    root = QgsProject.instance().layerTreeRoot()
    assert root.findLayer(layer.id()).parent() is root


def test_processing_run_loads_nothing(project, ws_iface, tmp_path) -> None:
    import processing
    from qgis.core import QgsProject

    processing.run("photodem:filter_lowpass", {
        "input": str(project / "truth" / "dsm.tif"), "output": str(tmp_path / "quiet")})
    assert QgsProject.instance().mapLayers() == {}


def test_html_reports_are_html_outputs(provider) -> None:
    from qgis.core import QgsApplication

    registry = QgsApplication.processingRegistry()
    for alg_id, name in (("match_model", "report_html"), ("dem_compare", "report")):
        output = registry.algorithmById(f"photodem:{alg_id}").outputDefinition(name)
        assert output.type() == "outputHtml", (alg_id, output.type())
