"""The plugin loads like QGIS loads it: qgis_process path and desktop path; unload is complete."""

from __future__ import annotations

import configparser
import time
from pathlib import Path

import pytest

pytestmark = pytest.mark.qgis

ROOT = Path(__file__).resolve().parents[2]


class FakeIface:
    """Records what the plugin asks of QGIS's desktop interface (beside the real provider test)."""

    def __init__(self) -> None:
        from qgis.PyQt.QtWidgets import QMainWindow

        self.window = QMainWindow()
        self.calls: list = []

    def mainWindow(self):  # noqa: N802 (QGIS API)
        return self.window

    def addToolBarIcon(self, action):  # noqa: N802
        self.calls.append(("addToolBarIcon", action.objectName()))

    def removeToolBarIcon(self, action):  # noqa: N802
        self.calls.append(("removeToolBarIcon", action.objectName()))

    def addPluginToRasterMenu(self, menu, action):  # noqa: N802
        self.calls.append(("addPluginToRasterMenu", menu, action.objectName()))

    def removePluginRasterMenu(self, menu, action):  # noqa: N802
        self.calls.append(("removePluginRasterMenu", menu, action.objectName()))

    # the editing toolbar (issue 18 §2): a real canvas for its map tools, no CAD panel
    def mapCanvas(self):  # noqa: N802
        from qgis.gui import QgsMapCanvas

        if "canvas" not in self.__dict__:
            self.canvas = QgsMapCanvas(self.window)
        return self.canvas

    def cadDockWidget(self):  # noqa: N802
        return None

    def addToolBar(self, toolbar):  # noqa: N802
        self.calls.append(("addToolBar", toolbar.objectName()))
        self.window.addToolBar(toolbar)

    # -- actions on stereo models (model_actions): layer-tree entries, map context menu --
    def addCustomActionForLayerType(self, action, menu, layer_type, all_layers):  # noqa: N802
        self.calls.append(("addCustomActionForLayerType", menu, action.text()))

    def addCustomActionForLayer(self, action, layer):  # noqa: N802
        self.calls.append(("addCustomActionForLayer", action.text(), layer.id()))

    def removeCustomActionForLayerType(self, action):  # noqa: N802
        self.calls.append(("removeCustomActionForLayerType", action.text()))
        return True

    def __getattr__(self, name):  # anything else would be an unexpected use of iface
        raise AssertionError(f"the plugin used iface.{name}, which the fake does not provide")


def _registry():
    from qgis.core import QgsApplication

    return QgsApplication.processingRegistry()


def test_loaded_the_qgis_process_way(plugin, provider):
    """loadPlugin + startProcessingPlugin = classFactory(None) → initProcessing."""
    assert plugin.iface is None
    assert provider is not None and provider.id() == "photodem"
    assert _registry().providerById("photodem") is provider
    assert not plugin.actions  # no GUI without iface


def test_class_factory_none_then_init_processing_and_unload(qgis_app, plugin):
    """A second instance, driven by hand: registers its own provider, unload removes it."""
    import photodem

    registry = _registry()
    registry.removeProvider(plugin.provider)  # make room: provider ids are unique
    plugin.provider = None
    try:
        start = time.perf_counter()
        second = photodem.classFactory(None)
        second.initProcessing()
        elapsed = time.perf_counter() - start
        assert registry.providerById("photodem") is second.provider
        for algorithm_id in _ids():
            assert registry.algorithmById("photodem:" + algorithm_id) is not None
        second.initProcessing()  # idempotent
        assert len([p for p in registry.providers() if p.id() == "photodem"]) == 1
        second.unload()
        assert registry.providerById("photodem") is None
        assert second.provider is None
        print(f"classFactory(None) + initProcessing: {elapsed * 1000:.1f} ms")
    finally:
        plugin.initProcessing()  # restore the session's provider
    assert registry.providerById("photodem") is plugin.provider


def _ids() -> list:
    from photodem.algorithms.processing import registry

    return list(registry.algorithms())


def test_desktop_init_gui_and_unload(qgis_app, plugin):
    """initGui → initProcessing + one menu entry per algorithm + a toolbar button; unload undoes."""
    import photodem
    from photodem.algorithms.processing import registry as core_registry

    registry = _registry()
    registry.removeProvider(plugin.provider)
    plugin.provider = None
    iface = FakeIface()
    try:
        desktop = photodem.classFactory(iface)
        assert not iface.calls  # the constructor does not touch iface
        desktop.initGui()
        assert registry.providerById("photodem") is desktop.provider
        added = [c for c in iface.calls if c[0] == "addPluginToRasterMenu"]
        names = {c[2] for c in added}
        assert {f"photodem_{i}" for i in core_registry.algorithms()} <= names
        assert "photodemGeorefReview" in names
        assert "photodemBatchDialog" in names  # Batch over stereo models…
        assert ("addToolBarIcon", "photodemShowToolbox") in iface.calls
        assert ("addToolBar", "photodemEditingToolbar") in iface.calls
        assert all(c[1] == "&PhotoDEM" for c in added)
        iface.calls.clear()
        desktop.unload()
        removed = [c for c in iface.calls if c[0] == "removePluginRasterMenu"]
        assert {c[2] for c in removed} == names
        assert ("removeToolBarIcon", "photodemShowToolbox") in iface.calls
        assert registry.providerById("photodem") is None
        assert desktop.actions == []
        tree = {c[1] for c in iface.calls if c[0] == "removeCustomActionForLayerType"}
        assert tree == {"Match this model…", "Epipolar pair", "Filter its DSM…"}
        assert desktop.model_actions is None
    finally:
        plugin.initProcessing()
    assert registry.providerById("photodem") is plugin.provider


def test_provider_lists_every_registry_algorithm(provider, fixture_alg):
    from photodem.algorithms.processing import registry

    listed = {a.id() for a in provider.algorithms()}
    expected = {f"photodem:{i}" for i in registry.algorithms()}
    assert expected == listed
    assert "photodem:fixture_all_kinds" in listed
    for alg in provider.algorithms():
        assert _registry().algorithmById(alg.id()) is not None


def test_provider_identity_and_icon(provider):
    from photodem.plugin.qgis.provider import ICON_PATH

    assert provider.name() == "PhotoDEM"
    assert ICON_PATH.is_file()
    assert not provider.icon().isNull()
    assert provider.defaultRasterFileExtension() == "tif"


def test_metadata_is_complete():
    meta = configparser.ConfigParser()
    meta.read(ROOT / "metadata.txt", encoding="utf-8")
    general = meta["general"]
    for key in ("name", "qgisMinimumVersion", "description", "about", "version", "author",
                "email", "repository", "tracker", "category", "tags", "hasProcessingProvider",
                "license", "icon"):
        assert general.get(key), key
    assert general["qgisMinimumVersion"] == "3.22"
    assert general["hasProcessingProvider"] == "yes"
    assert (ROOT / general["icon"]).is_file()
    assert (ROOT / "LICENSE").is_file()
    import photodem.algorithms as core

    assert general["version"] == core.__version__


def test_missing_dependencies_give_one_clear_message(qgis_app, plugin, monkeypatch):
    """No provider and one message naming the packages when the core cannot import."""
    import photodem
    from photodem.plugin.qgis import plugin as plugin_module

    monkeypatch.setattr(plugin_module, "missing_dependencies", lambda: ["rasterio", "skimage"])
    messages = []

    class Bar:
        def pushCritical(self, title, text):  # noqa: N802 (QGIS API)
            messages.append(text)

    iface = FakeIface()
    iface.messageBar = lambda: Bar()
    broken = photodem.classFactory(iface)
    broken.initGui()
    assert broken.provider is None and not broken.actions
    assert len(messages) == 1
    assert "rasterio, skimage" in messages[0] and "python3-rasterio python3-skimage" in messages[0]
    broken.unload()
    assert _registry().providerById("photodem") is plugin.provider  # the session's is untouched


def test_georef_review_opens_inside_qgis(qgis_app, plugin, tmp_path):
    """The review dialog on a real result, with QGIS's Qt (desktop plugin, fake iface)."""
    import photodem
    from photodem.algorithms.processing import registry as core_registry
    from photodem.algorithms.synthetic.polygon_scene import georef_case

    case = georef_case(tmp_path / "case", seed=5)
    out = tmp_path / "georef"
    core_registry.run("georeference_polygons", {
        "image": case["image"], "reference": case["reference"], "output": str(out)})
    desktop = photodem.classFactory(FakeIface())
    dialog = desktop.open_georef_review(str(out))
    assert dialog is not None and dialog.point_table.rowCount() >= 50
    dialog.set_point_enabled(0, False)
    assert dialog.rows[0]["role"] == "check"
    assert dialog.save() and (out / "report_auto.json").is_file()
    dialog.message_boxes = False
    dialog.close()
