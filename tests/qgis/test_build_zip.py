"""make zip: one top folder photodem/, runtime files only, compiled .qm, loadable by QGIS."""

from __future__ import annotations

import configparser
import json
import sys
import zipfile
from pathlib import Path

import pytest
from _qgis_helpers import QGIS_PROCESS, qgis_process_env, run_qgis_process

pytestmark = pytest.mark.qgis

ROOT = Path(__file__).resolve().parents[2]
METADATA_KEYS = ("name", "qgisMinimumVersion", "description", "about", "version", "author",
                 "email", "repository", "tracker", "category", "tags", "hasProcessingProvider",
                 "license")


@pytest.fixture(scope="module")
def plugin_zip(tmp_path_factory) -> Path:
    sys.path.insert(0, str(ROOT / "tools"))
    from update_translations import find_lrelease

    if find_lrelease() is None:
        pytest.skip("lrelease not installed (Debian package qttools5-dev-tools)")
    import build_zip

    return build_zip.build(tmp_path_factory.mktemp("dist"))


def test_zip_layout(plugin_zip):
    assert plugin_zip.name == "photodem-0.1.0.zip" or plugin_zip.name.startswith("photodem-")
    with zipfile.ZipFile(plugin_zip) as archive:
        assert archive.testzip() is None
        names = archive.namelist()
        meta_text = archive.read("photodem/metadata.txt").decode("utf-8")
    assert {n.split("/")[0] for n in names} == {"photodem"}
    for required in ("photodem/__init__.py", "photodem/metadata.txt", "photodem/LICENSE",
                     "photodem/i18n/photodem_de.qm", "photodem/resources/icons/photodem.svg",
                     "photodem/plugin/qgis/plugin.py", "photodem/plugin/qgis/provider.py",
                     "photodem/plugin/qgis/algorithm.py", "photodem/plugin/qt.py",
                     "photodem/algorithms/processing/registry.py"):
        assert required in names, required
    for name in names:
        rel = name.split("/", 1)[1]
        assert not rel.startswith(("tests/", "bench/", "tools/", ".ci/", "docs/", ".git")), name
        assert rel not in ("pyproject.toml", "Makefile", ".gitignore"), name
        assert "__pycache__" not in name and not name.endswith((".pyc", ".ts")), name
    meta = configparser.ConfigParser(interpolation=None)
    meta.read_string(meta_text)
    for key in METADATA_KEYS:
        assert meta["general"].get(key), key
    assert meta["general"]["hasProcessingProvider"] == "yes"
    assert plugin_zip.name == f"photodem-{meta['general']['version']}.zip"


def test_zip_is_reproducible(plugin_zip, tmp_path):
    import build_zip

    again = build_zip.build(tmp_path)
    assert again.read_bytes() == plugin_zip.read_bytes()


def test_unzipped_plugin_loads_in_qgis_process(plugin_zip, tmp_path):
    """Install the zip like the plugin manager would and let qgis_process load it."""
    if not Path(QGIS_PROCESS).is_file():
        pytest.skip(f"{QGIS_PROCESS} not installed")
    plugins = tmp_path / "plugins"
    with zipfile.ZipFile(plugin_zip) as archive:
        archive.extractall(plugins)
    env = qgis_process_env(tmp_path / "qp", plugins / "photodem")
    env["QGIS_PLUGINPATH"] = str(plugins)  # the extracted copy, not the repository
    assert run_qgis_process(env, "plugins", "enable", "photodem").returncode == 0
    proc = run_qgis_process(env, "list", "--json")
    assert proc.returncode == 0, proc.stderr
    algorithms = json.loads(proc.stdout)["providers"]["photodem"]["algorithms"]
    from photodem.algorithms.processing import registry

    assert set(algorithms) == {f"photodem:{i}" for i in registry.algorithms()}
    assert "Traceback" not in proc.stderr, proc.stderr
