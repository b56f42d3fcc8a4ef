"""Fixtures for the processing tests: fake algorithms and a tiny project."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:  # workers (spawn) inherit sys.path and import _fake_algs
    sys.path.insert(0, str(HERE))

import _fake_algs  # noqa: E402


@pytest.fixture
def fake_algs(monkeypatch):
    """The fake algorithms in the registry (this process and spawned batch workers)."""
    _fake_algs.install(monkeypatch)
    monkeypatch.setenv("PHOTODEM_EXTRA_ALGORITHMS", "_fake_algs")
    return _fake_algs


@pytest.fixture
def project_dir(tmp_path):
    """A project with three stereo models and no images (enough for batch planning)."""
    from photodem.algorithms.project.model import Project, StereoModel

    root = tmp_path / "proj"
    Project(root=root, name="t", crs="EPSG:25832",
            models=[StereoModel("a_b", "a", "b"), StereoModel("b_c", "b", "c"),
                    StereoModel("c_d", "c", "d")]).save()
    return root
