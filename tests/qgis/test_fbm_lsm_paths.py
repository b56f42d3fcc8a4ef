"""The same fbm_lsm DSM from QGIS and from the command line.

A model matched through ``qgis_process`` differed from the CLI's DSM by up to 15.7 m (2–5 % of
the cells). The Processing algorithm was not the cause: it hands fbm_lsm the same values as the
CLI (first test). Inside QGIS numpy's products run on another BLAS (GSL's, which QGIS links), so
the points differ by float noise (≤ 2 µm), and the triangulation of the wall breaklines followed
that noise (:func:`photodem.algorithms.surface.jumps.plan_triangulation`; second test).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any, Dict, List

import numpy as np
import pytest
from _qgis_helpers import (
    QGIS_PROCESS,
    copy_block,
    qgis_process_env,
    qgis_process_results,
    run_qgis_process,
    to_cli_args,
    to_qgis_params,
)

pytestmark = pytest.mark.qgis

ROOT = Path(__file__).resolve().parents[2]
#: The model of the tiny block (seed :data:`SEED`) where the old triangulation gave QGIS and
#: the CLI DSMs up to 4.3 m apart (1.0 % of the cells > 1 mm; seed 1: ≤ 0.4 mm, no test).
MODEL = "0101_0102"
SEED = 3
#: Parameter sets: the defaults, and every fbm_lsm option set away from its default.
CASES = {
    "defaults": {},
    "options": {"preset": "urban", "spacing": 0.45, "min_height": -10.0, "max_height": 60.5,
                "max_gap": 12.5, "fbm_window": 24, "rho_min": 0.65, "lsm": False,
                "groundel": 3.3, "reduction": "median", "points_format": "gpkg",
                "use_start_points": False},
}


class _Stop(Exception):
    """Raised by the recorder instead of matching."""


def _cli_argv(spec, raw: Dict[str, Any]) -> List[str]:
    """``photodem run match_model`` flags for raw values."""
    argv: List[str] = []
    for name, value in raw.items():
        text = str(value).lower() if isinstance(value, bool) else str(value)
        argv += [spec.parameter(name).flag, text]
    return argv


@pytest.mark.parametrize("case", sorted(CASES))
def test_processing_hands_fbm_lsm_the_cli_values(case, plugin, tiny_block, tmp_path,
                                                 monkeypatch):
    """processing.run and the CLI's parsing give match_model_fbm_lsm the same arguments."""
    import processing

    from photodem.algorithms import cli
    from photodem.algorithms.matching import fbm_model
    from photodem.algorithms.processing import registry

    calls: List[Dict[str, Any]] = []

    def record(project, model, output_dir, **kwargs):
        kwargs.pop("feedback", None)
        calls.append({"project": str(project.root), "model": model,
                      "output": str(output_dir), **kwargs})
        raise _Stop()

    monkeypatch.setattr(fbm_model, "match_model_fbm_lsm", record)
    spec = registry.get("match_model")
    raw = {"project": str(tiny_block), "model": MODEL, "output": str(tmp_path / "dsm"),
           **CASES[case]}
    parsed = cli.raw_parameters(spec, cli.parse_run_arguments(spec, _cli_argv(spec, raw)))
    with pytest.raises(_Stop):
        registry.run("match_model", parsed)
    with pytest.raises(Exception):  # noqa: B017 — QGIS wraps the recorder's stop
        processing.run("photodem:match_model", to_qgis_params(spec, raw))
    assert len(calls) == 2
    assert calls[1] == calls[0]
    assert all(type(calls[1][k]) is type(v) for k, v in calls[0].items())  # 3 stays no 3.0


@pytest.fixture(scope="module")
def tiny_seed(tmp_path_factory, plugin) -> Path:
    """The tiny synthetic block of seed :data:`SEED` (≈ 4 s)."""
    from photodem.algorithms.processing import registry

    root = tmp_path_factory.mktemp("tiny_seed") / "block"
    registry.run("synthetic_block", {"output": str(root), "size": "tiny", "seed": SEED})
    return root


@pytest.fixture(scope="module")
def qp_env(tmp_path_factory):
    if not Path(QGIS_PROCESS).is_file():
        pytest.skip(f"{QGIS_PROCESS} not installed (Debian package 'qgis')")
    env = qgis_process_env(tmp_path_factory.mktemp("qgis_process_fbm"), ROOT)
    proc = run_qgis_process(env, "plugins", "enable", "photodem")
    assert proc.returncode == 0, proc.stderr
    return env


def _dsm(folder: Path) -> np.ndarray:
    from photodem.algorithms.raster.io import open_image

    with open_image(folder / "dsm.tif") as src:
        return src.read(1).astype(float)


@pytest.mark.slow
def test_qgis_process_and_cli_give_the_same_dsm(plugin, tiny_seed, qp_env, tmp_path):
    """fbm_lsm of one model through qgis_process and through ``python -m …cli`` (another BLAS
    for numpy's products): the options agree to 12 digits, the DSMs to 2 mm. Measured: 0.01 mm
    (old triangulation: 1.0 % of the cells > 1 mm, up to 4.3 m). Why not 1 mm: where the FE
    plate's CG stops (‖r‖ ≤ 1e-7 ‖b‖) follows the float noise too; on seed 1's model the DSMs
    differed by 0.3 mm in one run and 1.1 mm in another."""
    from photodem.algorithms.processing import registry

    spec = registry.get("match_model")
    project = copy_block(tiny_seed, tmp_path)
    out_cli, out_qp = tmp_path / "cli", tmp_path / "qp"
    raw = {"project": str(project), "model": MODEL}
    cmd = [sys.executable, "-m", "photodem.algorithms.cli", "run", "match_model",
           *_cli_argv(spec, {**raw, "output": str(out_cli)}), "--quiet"]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600, check=False)
    assert proc.returncode == 0, proc.stderr[-3000:]
    qgis_process_results(qp_env, "match_model", to_cli_args(spec, {**raw, "output": str(out_qp)}))
    a, b = _dsm(out_cli), _dsm(out_qp)
    assert np.array_equal(np.isnan(a), np.isnan(b))
    assert np.nanmax(np.abs(a - b)) <= 2e-3
    options = [json.loads((o / "report.json").read_text())["options"] for o in (out_cli, out_qp)]
    assert options[0].keys() == options[1].keys()
    for key, value in options[0].items():
        if isinstance(value, float):
            assert value == pytest.approx(options[1][key], rel=1e-12), key
        else:
            assert value == options[1][key], key
