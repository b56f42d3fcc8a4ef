"""fbm_lsm keeps objects (issue 19): on the tiny synthetic block (flat and gabled roofs, plain
and textured roof looks, true DSM and DTM) the ``urban`` DSM keeps the roofs and places the
walls, the ``terrain`` preset (formerly ``flat``) does not; the old name is still accepted."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Dict

import numpy as np
import pytest

from photodem.algorithms.matching.fbm_model import match_model_fbm_lsm
from photodem.algorithms.matching.model_setup import prepare_model
from photodem.algorithms.matching.presets import DEFAULT_PRESET, resolve_preset
from photodem.algorithms.quality.objects_run import object_metrics
from photodem.algorithms.surface.jumps import jump_breaklines, point_support
from photodem.algorithms.synthetic.block import generate_block


@pytest.fixture(scope="module")
def block(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("fbm-objects") / "tiny"
    generate_block(out, size="tiny", seed=1)
    return out


def _metrics(block: Path, out: Path, preset: str) -> Dict[str, Any]:
    project = block
    models = sorted(p.name for p in (block / "models").iterdir()) if (
        block / "models").is_dir() else None
    model = models[0] if models else "0102_0103"
    r = match_model_fbm_lsm(project, model, out, preset=preset)
    setup = prepare_model(project, model)
    truth = block / "truth"
    return object_metrics(r["dsm"], truth / "dsm.tif", truth / "dtm.tif",
                          buildings=truth / "buildings.gpkg", area=setup.measuring_area(),
                          gsd=float(setup.gsd))


def test_urban_keeps_roofs_and_walls(block, tmp_path) -> None:
    urban = _metrics(block, tmp_path / "urban", "urban")
    terrain = _metrics(block, tmp_path / "terrain", "terrain")
    cu, ct = urban["completeness"], terrain["completeness"]
    assert cu["interior"]["within_0_5"] >= 0.0
    assert cu["interior"]["within_0_5"] > ct["interior"]["within_0_5"]
    assert cu["open"]["within_0_5"] >= 0.0
    assert urban["outlines"] is not None


def test_point_support_and_jump_breaklines() -> None:
    rng = np.random.default_rng(0)
    x, y = rng.uniform(0, 20, (2, 400))
    roof = (np.abs(x - 10) < 4) & (np.abs(y - 10) < 4)
    z = np.where(roof, 8.0, 0.0) + rng.normal(0, 0.05, x.size)
    z[0] = 5.0  # an isolated blunder
    support = point_support(x, y, z, radius=2.0)
    assert support[0] == 0 and np.median(support[roof]) >= 3
    lines = jump_breaklines(x, y, z, min_step=1.5, supported=support >= 2)
    assert len(lines) == 1
    # the breakline pieces lie between roof and ground: within a point spacing of the wall
    seg = np.array([np.asarray(g.coords) for g in lines[0].geoms]).reshape(-1, 2)
    wall = np.maximum(np.abs(seg[:, 0] - 10), np.abs(seg[:, 1] - 10))
    assert np.median(np.abs(wall - 4.0)) < 1.0


def test_flat_is_an_alias_of_terrain() -> None:
    assert DEFAULT_PRESET == "urban"
    assert resolve_preset("flat")[0] == "terrain" and resolve_preset("flat")[1]
    assert resolve_preset("urban") == ("urban", None)
