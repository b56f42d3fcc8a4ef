"""The match_model algorithm hands its parameters to the matcher it runs."""

from __future__ import annotations

import pytest

from photodem.algorithms.feedback import Feedback
from photodem.algorithms.matching import dense_model
from photodem.algorithms.processing import registry


@pytest.mark.parametrize("given, key, expected", [
    ({}, "slant_passes", True), ({"slant_passes": False}, "slant_passes", False),
    ({}, "guided", True), ({"guided_pass": False}, "guided", False)])
def test_dense_gets_the_slant_and_guided_passes(chain_project, tmp_path, monkeypatch, given,
                                                key, expected):
    seen: dict = {}

    def fake(project, model, out, **kwargs):
        seen.update(kwargs, model=model)
        return {}

    monkeypatch.setattr(dense_model, "match_model_dense", fake)
    root = chain_project("abc")
    registry.run("match_model", {"project": str(root), "model": "a_b", "method": "dense",
                                 "output": str(tmp_path / "dsm"), **given}, Feedback())
    assert seen["model"] == "a_b" and seen[key] is expected
