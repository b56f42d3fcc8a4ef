"""Tier B: the plugin inside real QGIS 3.22 (Debian), no GUI.

One ``QgsApplication`` for the whole session, Processing initialised, and the plugin loaded the
way ``qgis_process`` loads it (``qgis.utils.loadPlugin`` + ``startProcessingPlugin``, i.e.
``classFactory(None)`` → ``initProcessing``). Without an importable ``qgis.core`` (tier A) this
folder is not collected at all; ``tools/run_tier_b.sh`` decides whether that is a failure.
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, Dict, Iterator

import pytest

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

try:
    import qgis.core  # noqa: F401
except ImportError:  # tier A: nothing here can run, and nothing here may change the process
    # This folder itself is importable as a namespace package "qgis"; do not leave it behind.
    for _name in [m for m in sys.modules if m == "qgis" or m.startswith("qgis.")]:
        del sys.modules[_name]
    collect_ignore_glob = ["test_*.py"]
    HAVE_QGIS = False
else:
    HAVE_QGIS = True
    # In a venv sys.prefix is the venv, so Debian's pyproj cannot find /usr/share/proj by itself
    # ("UserWarning: Valid PROJ data directory not found"); QGIS finds it, pyproj does not.
    # Only here: PyPI wheels (tier A) bring their own, newer proj.db.
    if "PROJ_DATA" not in os.environ and Path("/usr/share/proj").is_dir():
        os.environ["PROJ_DATA"] = "/usr/share/proj"
    # Never touch the user's QGIS profile (QgsApplication writes qgis.db, auth db, styles…).
    os.environ.setdefault("QGIS_CUSTOM_CONFIG_PATH", tempfile.mkdtemp(prefix="photodem-qgis-"))

ROOT = Path(__file__).resolve().parents[2]
PLUGIN_NAME = "photodem"
TIMINGS: Dict[str, float] = {}


def pytest_collection_modifyitems(config, items) -> None:
    here = Path(__file__).parent
    for item in items:
        if here in Path(str(item.fspath)).parents:
            item.add_marker(pytest.mark.qgis)


def pytest_report_header(config) -> list:
    if not HAVE_QGIS:
        return ["tier B: qgis.core not importable"]
    import numpy
    from osgeo import gdal
    from qgis.core import Qgis
    from qgis.PyQt.QtCore import QT_VERSION_STR

    try:
        import shapely

        shapely_version = shapely.__version__
    except ImportError:  # pragma: no cover
        shapely_version = "-"
    return [
        f"QGIS {Qgis.QGIS_VERSION}, Qt {QT_VERSION_STR}, GDAL {gdal.__version__}, "
        f"numpy {numpy.__version__}, shapely {shapely_version}, Python {sys.version.split()[0]}"
    ]


def pytest_terminal_summary(terminalreporter) -> None:
    for key, seconds in TIMINGS.items():
        terminalreporter.write_line(f"photodem tier-B timing: {key}: {seconds:.3f} s")


@pytest.fixture(scope="session")
def qgis_app():
    """The one QgsApplication with Processing initialised.

    GUI-enabled (offscreen): the workspace tests need real widgets — a ``QgsMapCanvas``, map
    tools, docks — in the same process as the Processing tests.
    """
    from qgis.core import QgsApplication

    start = time.perf_counter()
    QgsApplication.setPrefixPath(os.environ.get("QGIS_PREFIX_PATH", "/usr"), True)
    app = QgsApplication([], True)
    app.initQgis()
    plugins_dir = str(Path(QgsApplication.pkgDataPath()) / "python" / "plugins")
    if plugins_dir not in sys.path:
        sys.path.append(plugins_dir)  # Debian: /usr/share/qgis/python/plugins ('processing')
    from processing.core.Processing import Processing

    Processing.initialize()
    TIMINGS["QgsApplication + Processing.initialize"] = time.perf_counter() - start
    yield app
    # No app.exitQgis(): tearing QGIS down inside pytest crashes on some builds, and the
    # process ends right after anyway.


@pytest.fixture(scope="session")
def plugin(qgis_app):
    """The plugin, loaded exactly as qgis_process does: classFactory(None) → initProcessing."""
    import qgis.utils

    start = time.perf_counter()
    assert qgis.utils.loadPlugin(PLUGIN_NAME)
    assert qgis.utils.startProcessingPlugin(PLUGIN_NAME)
    TIMINGS["plugin load (classFactory + initProcessing + provider)"] = (
        time.perf_counter() - start
    )
    instance = qgis.utils.plugins[PLUGIN_NAME]
    yield instance  # qgis.utils keeps the reference too


@pytest.fixture
def provider(plugin):
    """The session plugin's current provider (tests may unload and re-register it)."""
    return plugin.provider


@pytest.fixture
def fixture_alg(provider) -> Iterator[Any]:
    """Register the test-only algorithm ``fixture_all_kinds`` for one test."""
    from _fixture_algs import FIXTURE_ID, FixtureAllKinds

    from photodem.algorithms.processing import registry

    spec = registry.add(FixtureAllKinds())
    provider.refreshAlgorithms()
    try:
        yield spec
    finally:
        registry.remove(FIXTURE_ID)
        provider.refreshAlgorithms()


@pytest.fixture
def qgis_iface(qgis_app, plugin):
    """A desktop interface of real widgets (canvas, message bar, layer tree) for one test.

    The project is cleared before and after, so each test starts from an empty map.
    """
    from _iface import WidgetIface
    from qgis.core import QgsProject

    QgsProject.instance().clear()
    iface = WidgetIface()
    yield iface
    QgsProject.instance().clear()
    iface.close()


@pytest.fixture(scope="session")
def tiny_block(tmp_path_factory, plugin) -> Path:
    """One tiny synthetic block (``synthetic_block --size tiny``) for the session. Read only:
    a module or test that writes into a project takes a copy (``_qgis_helpers.copy_block``)."""
    from photodem.algorithms.processing import registry

    root = tmp_path_factory.mktemp("tiny") / "block"
    registry.run("synthetic_block", {"output": str(root), "size": "tiny"})
    return root

