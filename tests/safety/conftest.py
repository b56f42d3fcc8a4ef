"""Fixtures of the safety tests (issue 16): a tiny project made once, a folder of bad files,
and a fresh workspace per case. The helpers live in ``_safety.py``."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest
from _safety import PHOTODEM, Workspace, make_bad_files


@pytest.fixture(scope="session")
def tiny_project(tmp_path_factory) -> Path:
    """A tiny synthetic project (6 images, 4 models, truth/), made once and never written to."""
    root = tmp_path_factory.mktemp("tiny") / "p"
    code = subprocess.run([str(PHOTODEM), "run", "synthetic_block", "--output", str(root),
                           "--size", "tiny", "--quiet"], capture_output=True, text=True)
    assert code.returncode == 0, code.stderr
    return root


@pytest.fixture(scope="session")
def bad_files(tmp_path_factory, tiny_project) -> Path:
    """A folder of broken, odd and valid-but-hostile input files (see :func:`make_bad_files`)."""
    folder = tmp_path_factory.mktemp("bad")
    make_bad_files(folder, tiny_project)
    return folder


@pytest.fixture
def workspace(tmp_path, tiny_project, bad_files, monkeypatch) -> Workspace:
    """A fresh copy of the tiny project and an empty work folder that is the current folder."""
    p = tmp_path / "p"
    shutil.copytree(tiny_project, p)
    w = tmp_path / "w"
    w.mkdir()
    monkeypatch.chdir(w)
    return Workspace(p=p, w=w, bad=bad_files)


