"""The stereo-model parameter in real Processing dialogs (standard, batch, modeler) of QGIS."""

from __future__ import annotations

from pathlib import Path

import pytest
from _qgis_helpers import copy_block

pytestmark = pytest.mark.qgis

MODELS = ["0101_0102", "0102_0103", "0201_0202", "0202_0203"]


@pytest.fixture(scope="module")
def tiny_project(tmp_path_factory, tiny_block) -> Path:
    root = copy_block(tiny_block, tmp_path_factory.mktemp("mw"), "block")
    return root


@pytest.fixture
def fresh_settings():
    """No remembered project/model before and after the test."""
    from qgis.core import QgsSettings

    from photodem.plugin.qgis.model_widget import SETTINGS_MODEL, SETTINGS_PROJECT

    for key in (SETTINGS_PROJECT, SETTINGS_MODEL):
        QgsSettings().remove(key)
    yield
    for key in (SETTINGS_PROJECT, SETTINGS_MODEL):
        QgsSettings().remove(key)


def _dialog(algorithm_id: str = "match_model"):
    from processing.gui.AlgorithmDialog import AlgorithmDialog
    from qgis.core import QgsApplication

    alg = QgsApplication.processingRegistry().createAlgorithmById(f"photodem:{algorithm_id}")
    return AlgorithmDialog(alg)


def _set_project(dialog, path) -> None:
    from qgis.core import QgsProcessingContext

    dialog.mainWidget().wrappers["project"].setParameterValue(str(path), QgsProcessingContext())


def test_the_model_parameter_is_a_drop_down_of_the_projects_models(
        qgis_iface, provider, tiny_project, fresh_settings):
    from qgis.PyQt.QtWidgets import QComboBox

    from photodem.plugin.qgis.model_widget import ModelWidgetWrapper

    dialog = _dialog()
    wrapper = dialog.mainWidget().wrappers["model"]
    assert isinstance(wrapper, ModelWidgetWrapper)
    assert isinstance(wrapper.combo, QComboBox) and wrapper.combo.isEditable()
    assert wrapper.models() == []  # no project yet
    _set_project(dialog, tiny_project)
    assert wrapper.models() == MODELS
    assert [wrapper.combo.itemText(i) for i in range(wrapper.combo.count())] == MODELS
    assert wrapper.value() == MODELS[0]  # a usable first choice
    wrapper.setValue("0201_0202")
    params = dialog.mainWidget().createProcessingParameters()
    assert params["model"] == "0201_0202"
    assert params["project"] == str(tiny_project)
    dialog.close()


def test_it_repopulates_when_the_project_changes_and_hints_at_an_unreadable_one(
        qgis_iface, provider, tiny_project, tmp_path, fresh_settings):
    dialog = _dialog("epipolar_pair")
    wrapper = dialog.mainWidget().wrappers["model"]
    _set_project(dialog, tiny_project)
    assert wrapper.models() == MODELS
    not_a_project = tmp_path / "empty"
    not_a_project.mkdir()
    _set_project(dialog, not_a_project)
    assert wrapper.models() == [] and wrapper.combo.count() == 0
    assert "project.toml" in wrapper.hint_text()
    assert wrapper.hint.isVisibleTo(dialog) and "project.toml" in wrapper.hint.text()
    broken = tmp_path / "broken"
    broken.mkdir()
    (broken / "project.toml").write_text("this is = = not toml", encoding="utf-8")
    _set_project(dialog, broken)
    assert wrapper.models() == [] and "cannot be read" in wrapper.hint_text()
    wrapper.setValue("0101_0102")  # still editable: a typed name is kept
    assert wrapper.value() == "0101_0102"
    _set_project(dialog, tiny_project)
    assert wrapper.models() == MODELS and wrapper.hint_text() == ""
    assert not wrapper.hint.isVisibleTo(dialog)
    assert wrapper.value() == "0101_0102"
    dialog.close()


def test_project_and_model_are_remembered_for_the_next_dialog(
        qgis_iface, provider, tiny_project, fresh_settings):
    from qgis.core import QgsSettings

    from photodem.plugin.qgis.model_widget import SETTINGS_MODEL, SETTINGS_PROJECT

    first = _dialog()
    _set_project(first, tiny_project)
    first.mainWidget().wrappers["model"].setValue("0202_0203")
    first.close()
    assert QgsSettings().value(SETTINGS_PROJECT) == str(tiny_project)
    assert QgsSettings().value(SETTINGS_MODEL) == "0202_0203"
    second = _dialog("epipolar_pair")  # another algorithm with a model parameter
    panel = second.mainWidget()
    assert panel.wrappers["project"].parameterValue() == str(tiny_project)
    assert panel.wrappers["model"].value() == "0202_0203"
    # parameters given by the caller (a map action) win over the remembered ones
    second.setParameters({"project": str(tiny_project), "model": "0101_0102"})
    assert panel.wrappers["model"].value() == "0101_0102"
    second.close()


def test_the_batch_panel_gets_one_combo_per_row(qgis_iface, provider, tiny_project,
                                                fresh_settings):
    from processing.gui.BatchAlgorithmDialog import BatchAlgorithmDialog
    from qgis.core import QgsApplication, QgsProcessingContext

    from photodem.plugin.qgis.model_widget import ModelWidgetWrapper

    alg = QgsApplication.processingRegistry().createAlgorithmById("photodem:match_model")
    dialog = BatchAlgorithmDialog(alg)
    panel = dialog.mainWidget()
    row = panel.wrappers[0]
    names = [w.parameterDefinition().name() if w is not None else None for w in row]
    model = row[names.index("model")]
    project = row[names.index("project")]
    assert isinstance(model, ModelWidgetWrapper)
    assert model.widget is model.combo  # no hint label in a table cell
    project.setParameterValue(str(tiny_project), QgsProcessingContext())
    assert model.models() == MODELS
    assert model.value() is None  # batch rows are not pre-filled
    model.setValue("0102_0103")
    assert model.parameterValue() == "0102_0103"
    dialog.close()


def test_the_modeler_takes_a_static_name(qgis_iface, provider, fresh_settings):
    from processing.modeler.ModelerParametersDialog import ModelerParametersDialog
    from qgis.core import (
        QgsApplication,
        QgsProcessingModelAlgorithm,
        QgsProcessingModelChildParameterSource,
        QgsProcessingModelParameter,
        QgsProcessingParameterString,
    )

    from photodem.plugin.qgis.model_widget import ModelWidgetWrapper

    alg = QgsApplication.processingRegistry().createAlgorithmById("photodem:match_model")
    graph = QgsProcessingModelAlgorithm()
    name_input = QgsProcessingParameterString("which_model", "Which model")
    graph.addModelParameter(name_input, QgsProcessingModelParameter("which_model"))
    dialog = ModelerParametersDialog(alg, graph)
    wrappers = dialog.widget.widget.wrappers
    model = wrappers["model"]
    assert isinstance(model, ModelWidgetWrapper)
    model.setValue("0101_0102")  # a static name
    assert model.value() == "0101_0102"
    # or a string input of the model, bound at run time
    index = model.combo.findText("Which model")
    assert index >= 0
    model.combo.setCurrentIndex(index)
    source = model.value()
    assert source.source() == QgsProcessingModelChildParameterSource.ModelParameter
    assert source.parameterName() == "which_model"
    dialog.close()


def test_project_models_reads_the_core(tiny_project, tmp_path):
    from photodem.plugin.qgis.model_widget import project_models

    assert project_models(tiny_project) == (MODELS, "")
    assert project_models(tiny_project / "project.toml") == (MODELS, "")
    assert project_models("") == ([], "")
    names, problem = project_models(tmp_path)
    assert names == [] and problem
