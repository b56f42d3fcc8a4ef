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
    """A project with three stereo models over four images without files (enough for batch
    planning)."""
    from photodem.algorithms.geometry.camera import Camera
    from photodem.algorithms.geometry.orientation import ExteriorOrientation
    from photodem.algorithms.project.model import ImageRecord, Project, StereoModel

    root = tmp_path / "proj"
    eo = ExteriorOrientation.from_opk([0.0, 0.0, 1000.0], 0.0, 0.0, 0.0)
    images = [ImageRecord(n, f"{n}.tif", "c", eo) for n in "abcd"]  # no files
    Project(root=root, name="t", crs="EPSG:25832",
            cameras={"c": Camera("c", 100, 80, 1.0, (0.01, 0.01))}, images=images,
            models=[StereoModel("a_b", "a", "b"), StereoModel("b_c", "b", "c"),
                    StereoModel("c_d", "c", "d")]).save()
    return root
