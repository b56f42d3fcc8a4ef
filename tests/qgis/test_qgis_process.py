"""qgis_process.bin (Debian 3.22): the plugin enables headless and gives Python's results.

Syntax verified on 3.22.16: ``qgis_process.bin run photodem:<id> --json -- name=value …``; a list
parameter is repeated (``rasters=a.tif rasters=b.tif``); enums take the option index; extents
``xmin,xmax,ymin,ymax``. Every subprocess gets its own temp profile (QGIS_CUSTOM_CONFIG_PATH).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from _qgis_helpers import (
    DIGITS,
    QGIS_PROCESS,
    normalise,
    qgis_process_env,
    qgis_process_results,
    run_qgis_process,
    to_cli_args,
    tree_digest,
)

pytestmark = pytest.mark.qgis

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def qp_env(tmp_path_factory):
    """A temp profile with the plugin enabled, the fixture algorithm registered via site hook."""
    if not Path(QGIS_PROCESS).is_file():
        pytest.skip(f"{QGIS_PROCESS} not installed (Debian package 'qgis')")
    env = qgis_process_env(tmp_path_factory.mktemp("qgis_process"), ROOT, with_fixture=True)
    proc = run_qgis_process(env, "plugins", "enable", "photodem")
    assert proc.returncode == 0, proc.stderr
    listing = run_qgis_process(env, "plugins")
    assert "* photodem" in listing.stdout, listing.stdout  # '*' = enabled
    return env


def test_provider_lists_algorithms(qp_env):
    from photodem.algorithms.processing import registry

    proc = run_qgis_process(qp_env, "list")
    assert proc.returncode == 0, proc.stderr
    for algorithm_id in [*registry.algorithms(), "fixture_all_kinds"]:
        assert f"photodem:{algorithm_id}" in proc.stdout
    helped = run_qgis_process(qp_env, "help", "photodem:fixture_all_kinds")
    assert helped.returncode == 0 and "choice" in helped.stdout


def test_run_equals_python(qp_env, tmp_path):
    """Every parameter kind through qgis_process gives registry.run's result."""
    from _fixture_algs import FixtureAllKinds
    from test_algorithm import _fixture_inputs, _outputs

    from photodem.algorithms.processing import registry

    spec = FixtureAllKinds()
    raw = _fixture_inputs(tmp_path)
    out_py, out_qp = tmp_path / "py", tmp_path / "qp"
    # The in-process run needs the fixture in this process's registry as well.
    registry.add(spec)
    try:
        expected = registry.run(spec.id, {**raw, **_outputs(out_py)})
    finally:
        registry.remove(spec.id)
    got = qgis_process_results(qp_env, spec.id, to_cli_args(spec, {**raw, **_outputs(out_qp)}))
    map_py, map_qp = {str(out_py): "<OUT>"}, {str(out_qp): "<OUT>"}
    assert normalise(got, map_qp, DIGITS) == normalise(expected, map_py, DIGITS)
    assert tree_digest(out_qp, map_qp, DIGITS) == tree_digest(out_py, map_py, DIGITS)


def test_operator_error_exit_code_and_message(qp_env, tmp_path):
    proc = run_qgis_process(qp_env, "run", "photodem:fixture_all_kinds", "--json", "--",
                            "fail=true", f"output_file={tmp_path / 'o.json'}")
    assert proc.returncode != 0
    assert "Fixture failure: the parameter 'fail' was set" in proc.stderr + proc.stdout
    assert not (tmp_path / "o.json").exists()


def test_plugin_without_fixture_loads_cleanly(tmp_path):
    """The shipped plugin alone (no test hook): enabled, listed, no Python errors on stderr."""
    if not Path(QGIS_PROCESS).is_file():
        pytest.skip(f"{QGIS_PROCESS} not installed")
    env = qgis_process_env(tmp_path, ROOT)
    assert run_qgis_process(env, "plugins", "enable", "photodem").returncode == 0
    proc = run_qgis_process(env, "list", "--json")
    assert proc.returncode == 0
    providers = json.loads(proc.stdout)["providers"]
    assert "photodem" in providers
    assert "Traceback" not in proc.stderr, proc.stderr

