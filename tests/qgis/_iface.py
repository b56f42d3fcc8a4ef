"""A QGIS desktop interface made of real QGIS widgets, for the tier-B GUI tests.

QGIS's own ``QgisInterface`` exists only inside the desktop application. This one gives the
plugin the parts it uses — a real :class:`QgsMapCanvas` bound to ``QgsProject.instance()``, a real
message bar, a real layer-tree view, a main window for toolbars and docks — so map tools are
driven by real mouse events on the canvas viewport (pytest-qgis' ``qgis_iface`` does the same).
"""

from __future__ import annotations

from typing import Any, Dict, List


class WidgetIface:
    """The subset of ``QgisInterface`` the plugin uses, backed by real widgets."""

    def __init__(self) -> None:
        from qgis.core import QgsLayerTreeModel, QgsProject
        from qgis.gui import (
            QgsLayerTreeMapCanvasBridge,
            QgsLayerTreeView,
            QgsMapCanvas,
            QgsMessageBar,
        )
        from qgis.PyQt.QtWidgets import QMainWindow

        self.window = QMainWindow()
        self.canvas = QgsMapCanvas(self.window)
        self.canvas.resize(600, 600)
        self.window.setCentralWidget(self.canvas)
        self.window.resize(800, 650)
        self.bar = QgsMessageBar(self.window)
        root = QgsProject.instance().layerTreeRoot()
        self.bridge = QgsLayerTreeMapCanvasBridge(root, self.canvas)
        self.tree_model = QgsLayerTreeModel(root)
        self.tree_model.setFlag(QgsLayerTreeModel.AllowNodeReorder)
        self.tree_model.setFlag(QgsLayerTreeModel.AllowNodeChangeVisibility)
        self.tree_view = QgsLayerTreeView()
        self.tree_view.setModel(self.tree_model)
        self.toolbars: List[Any] = []
        self.docks: List[Any] = []
        self.menus: Dict[str, List[Any]] = {}
        self.toolbar_icons: List[Any] = []
        self.layer_actions: List[Any] = []
        self.layer_action_layers: List[Any] = []  # (action, layer id) of addCustomActionForLayer
        self.window.show()

    # -- widgets ------------------------------------------------------------------------------
    def mainWindow(self):  # noqa: N802 (QGIS API)
        return self.window

    def mapCanvas(self):  # noqa: N802
        return self.canvas

    def messageBar(self):  # noqa: N802
        return self.bar

    def layerTreeView(self):  # noqa: N802
        return self.tree_view

    def layerTreeCanvasBridge(self):  # noqa: N802
        return self.bridge

    def activeLayer(self):  # noqa: N802
        return self.tree_view.currentLayer()

    def setActiveLayer(self, layer):  # noqa: N802
        self.tree_view.setCurrentLayer(layer)
        return True

    # -- toolbars, docks, menus ---------------------------------------------------------------
    def addToolBar(self, toolbar_or_name):  # noqa: N802
        from qgis.PyQt.QtWidgets import QToolBar

        if isinstance(toolbar_or_name, QToolBar):
            self.window.addToolBar(toolbar_or_name)
            toolbar = toolbar_or_name
        else:
            toolbar = self.window.addToolBar(toolbar_or_name)
        self.toolbars.append(toolbar)
        return toolbar

    def addDockWidget(self, area, dock):  # noqa: N802
        self.window.addDockWidget(area, dock)
        self.docks.append(dock)

    def removeDockWidget(self, dock):  # noqa: N802
        self.window.removeDockWidget(dock)
        if dock in self.docks:
            self.docks.remove(dock)

    def addToolBarIcon(self, action):  # noqa: N802
        self.toolbar_icons.append(action)

    def removeToolBarIcon(self, action):  # noqa: N802
        if action in self.toolbar_icons:
            self.toolbar_icons.remove(action)

    def addPluginToRasterMenu(self, menu, action):  # noqa: N802
        self.menus.setdefault(menu, []).append(action)

    def removePluginRasterMenu(self, menu, action):  # noqa: N802
        if action in self.menus.get(menu, []):
            self.menus[menu].remove(action)

    def addPluginToMenu(self, menu, action):  # noqa: N802
        self.addPluginToRasterMenu(menu, action)

    def removePluginMenu(self, menu, action):  # noqa: N802
        self.removePluginRasterMenu(menu, action)

    def addCustomActionForLayerType(self, action, menu, layer_type, all_layers):  # noqa: N802
        self.layer_actions.append(action)

    def addCustomActionForLayer(self, action, layer):  # noqa: N802
        self.layer_action_layers.append((action, layer.id()))

    def removeCustomActionForLayerType(self, action):  # noqa: N802
        if action in self.layer_actions:
            self.layer_actions.remove(action)
            return True
        return False

    def close(self) -> None:
        for toolbar in self.toolbars:
            toolbar.deleteLater()
        self.window.close()
