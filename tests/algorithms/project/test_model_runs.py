"""The parameters of the stereo-model runs both faces offer on the map (model_runs)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from photodem.algorithms.errors import InputError
from photodem.algorithms.processing import registry
from photodem.algorithms.project.model import Project
from photodem.algorithms.project.model_runs import (
    NoDsmYet,
    epipolar_pair_parameters,
    filter_dsm_parameters,
    match_model_parameters,
    model_dsm,
)


@pytest.fixture(scope="module")
def tiny(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("tiny") / "project"
    registry.run("synthetic_block", {"output": str(out), "size": "tiny"})
    return out


def test_match_model_parameters_name_the_default_output(tiny):
    params = match_model_parameters(tiny, "0201_0202")
    assert params == {"project": str(tiny), "model": "0201_0202",
                      "output": str(tiny / "products" / "dsm" / "0201_0202")}
    # the project file works too; the project is passed on as given
    params = match_model_parameters(str(tiny / "project.toml"), "0201_0202")
    assert params["project"] == str(tiny / "project.toml")
    assert params["output"] == str(tiny / "products" / "dsm" / "0201_0202")


def test_epipolar_pair_parameters(tiny):
    assert epipolar_pair_parameters(tiny, "0101_0102") == {"project": str(tiny),
                                                           "model": "0101_0102"}


def test_unknown_model_and_no_project_are_input_errors(tiny, tmp_path):
    for build in (match_model_parameters, epipolar_pair_parameters, filter_dsm_parameters):
        with pytest.raises(InputError, match="0909_0910"):
            build(tiny, "0909_0910")
        with pytest.raises(InputError):
            build(tmp_path, "0101_0102")


def test_filter_dsm_needs_the_models_dsm(tiny):
    model = "0202_0203"
    with pytest.raises(NoDsmYet, match="no DSM yet") as caught:
        filter_dsm_parameters(tiny, model)
    assert caught.value.model == model
    assert caught.value.dsm == f"products/dsm/{model}/dsm.tif"
    assert isinstance(caught.value, InputError)
    dsm = model_dsm(Project.load(tiny), model)
    dsm.parent.mkdir(parents=True)
    shutil.copy(tiny / "truth" / "dsm.tif", dsm)
    try:
        params = filter_dsm_parameters(tiny, model)
        assert params == {"input": str(dsm), "project": str(tiny),
                          "output": str(tiny / "products" / "dtm" / model)}
        assert registry.get("filter_lowpass").parameters  # the names exist in the spec
        names = {p.name for p in registry.get("filter_lowpass").parameters}
        assert set(params) <= names
    finally:
        shutil.rmtree(dsm.parent)


def test_the_parameters_are_those_of_the_algorithms(tiny):
    for alg, params in (("match_model", match_model_parameters(tiny, "0101_0102")),
                        ("epipolar_pair", epipolar_pair_parameters(tiny, "0101_0102"))):
        assert set(params) <= {p.name for p in registry.get(alg).parameters}
