"""Shared fixtures: real data in ../shared/data (skipped when absent)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHARED_DATA = Path(os.environ.get("PHOTODEM_SHARED_DATA", ROOT.parent / "shared" / "data"))


def shared_data(name: str) -> Path:
    """Folder of a real data set below ../shared/data, or skip the test with the reason."""
    path = SHARED_DATA / name
    if not path.is_dir():
        pytest.skip(f"real data '{name}' not found at {path} (../shared/data is absent)")
    return path


@pytest.fixture
def ngi_block() -> Path:
    """The NGI aerial block (4 frames, EO/IO, reference DEM)."""
    return shared_data("ngi_aerial_block")
