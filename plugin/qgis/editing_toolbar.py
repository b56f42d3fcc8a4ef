"""The "PhotoDEM editing" toolbar: one checkable action per map tool, the surface, the breakline
height mode, *Re-drape* and *Validate*.

The toolbar works on the open PhotoDEM workspace (:meth:`EditingToolbar.set_workspace`; ``None``
= no project: the tools are disabled). It asks the workspace only for ``project``, ``root``,
``edit_layer(name)`` and ``surface_layers()`` (the shared contract), so tests pass a stand-in.
"""

from __future__ import annotations

import contextlib
from typing import Any, Dict, Optional, Tuple

from qgis.core import (
    Qgis,
    QgsApplication,
    QgsMapLayerProxyModel,
    QgsProject,
    QgsSnappingConfig,
    QgsTolerance,
)
from qgis.gui import QgsAdvancedDigitizingDockWidget, QgsMapLayerComboBox
from qgis.PyQt.QtCore import Qt
from qgis.PyQt.QtWidgets import QActionGroup, QComboBox, QLabel, QToolBar

from ..i18n import tr
from ..qt import QAction
from .edit_maptools import (
    SNAP_PIXELS,
    Z_MODES,
    CaptureTool,
    EditController,
    PointTool,
    is_mosaic_seamlines,
)
from .validation_dock import ValidationDock, collect_problems


def tool_labels() -> Dict[str, str]:
    """The edit layer of each tool and its translated label, in toolbar order."""
    return {"start_points": tr("Start point"), "exclusion_areas": tr("Exclusion area"),
            "breaklines": tr("Breakline (3-D)"), "ground_points": tr("Ground point (3-D)"),
            "check_points": tr("Check point (3-D)"), "boundaries": tr("Boundary"),
            "seamlines": tr("Seamline")}


def short_labels() -> Dict[str, str]:
    """The texts on the tool buttons (the full label is the tooltip)."""
    return {"breaklines": tr("Breakline"), "ground_points": tr("Ground point"),
            "check_points": tr("Check point")}


def z_mode_labels() -> Dict[str, Tuple[str, str]]:
    """Each breakline height mode: its short label and its explanation."""
    return {"drape": (tr("Z: drape"), tr("Each vertex gets the height of the surface")),
            "typed": (tr("Z: typed"), tr("Type the height of each vertex")),
            "interpolate": (tr("Z: interpolate"),
                            tr("Type the heights of the two ends; the vertices between are "
                               "interpolated along the line"))}


#: QGIS theme icon of each tool.
ICONS = {"start_points": "/mActionCapturePoint.svg",
         "exclusion_areas": "/mActionCapturePolygon.svg",
         "breaklines": "/mActionCaptureLine.svg", "ground_points": "/mActionCapturePoint.svg",
         "check_points": "/mActionCapturePoint.svg", "boundaries": "/mActionCapturePolygon.svg",
         "seamlines": "/mActionCaptureLine.svg"}


class EditingToolbar:
    """The "PhotoDEM editing" toolbar and its map tools.

    Parameters
    ----------
    iface : QgisInterface-like
        ``mapCanvas``, ``messageBar``, ``mainWindow``, ``addToolBar``, ``addDockWidget``,
        ``activeLayer``; ``cadDockWidget`` when there is one (QGIS desktop).
    ask : object, optional
        The questions of the tools (default: the real dialogs, :class:`.edit_forms.DialogAsker`).
    """

    def __init__(self, iface: Any, ask: Any = None) -> None:
        self.iface = iface
        self.canvas = iface.mapCanvas()
        self.controller = EditController(iface, ask)
        self.controller.surface_layer = self.surface_layer
        self.workspace: Any = None
        self.dock: Optional[ValidationDock] = None
        self.toolbar = QToolBar(tr("PhotoDEM editing"), iface.mainWindow())
        self.toolbar.setObjectName("photodemEditingToolbar")
        self.toolbar.setToolButtonStyle(Qt.ToolButtonTextBesideIcon)
        cad = getattr(iface, "cadDockWidget", None)
        self.cad_dock = cad() if callable(cad) else None
        if self.cad_dock is None:  # no desktop: the capture tools need a panel of their own
            self.cad_dock = QgsAdvancedDigitizingDockWidget(self.canvas, iface.mainWindow())
        self.actions: Dict[str, QAction] = {}
        self.tools: Dict[str, Any] = {}
        self._build_tools()
        self._build_options()
        iface.addToolBar(self.toolbar)
        QgsProject.instance().layersAdded.connect(self._layers_added)
        self.set_workspace(None)

    # -- building ------------------------------------------------------------------------------
    def _build_tools(self) -> None:
        group = QActionGroup(self.toolbar)
        for name, label in tool_labels().items():
            action = QAction(QgsApplication.getThemeIcon(ICONS[name]), label, self.toolbar)
            action.setObjectName(f"photodemEdit_{name}")
            action.setCheckable(True)
            action.setIconText(short_labels().get(name, label))
            action.setToolTip(label)
            action.triggered.connect(lambda _checked=False, n=name: self.activate(n))
            group.addAction(action)
            self.toolbar.addAction(action)
            if name in ("start_points", "ground_points", "check_points"):
                tool = PointTool(self.canvas, self.controller, name)
            else:
                tool = CaptureTool(self.canvas, self.cad_dock, self.controller, name)
            tool.setAction(action)  # QGIS unchecks the action when another tool takes over
            self.actions[name] = action
            self.tools[name] = tool
        group.setExclusive(False)  # all unchecked must be possible (no tool of ours active)

    def _build_options(self) -> None:
        self.toolbar.addSeparator()
        self.toolbar.addWidget(QLabel(tr("Surface") + " ", self.toolbar))
        self.surface_box = QgsMapLayerComboBox(self.toolbar)
        self.surface_box.setObjectName("photodemSurface")
        self.surface_box.setFilters(QgsMapLayerProxyModel.RasterLayer)
        self.surface_box.setAllowEmptyLayer(True)
        self.surface_box.setLayer(None)
        self.surface_box.setToolTip(tr("The DSM or DTM the heights are taken from"))
        self.surface_box.setMinimumContentsLength(14)
        self.toolbar.addWidget(self.surface_box)
        self.z_mode_box = QComboBox(self.toolbar)
        self.z_mode_box.setObjectName("photodemZMode")
        for k, (mode, (label, tip)) in enumerate(z_mode_labels().items()):
            self.z_mode_box.addItem(label, mode)
            self.z_mode_box.setItemData(k, tip, Qt.ToolTipRole)
        self.z_mode_box.setToolTip(tr("How the breakline tool gives its vertices their heights"))
        self.z_mode_box.currentIndexChanged.connect(self._z_mode_changed)
        self.toolbar.addWidget(self.z_mode_box)
        self.redrape_action = QAction(QgsApplication.getThemeIcon("/mActionReload.svg"),
                                      tr("Re-drape"), self.toolbar)
        self.redrape_action.setObjectName("photodemRedrape")
        self.redrape_action.setToolTip(tr("Re-sample the heights of the selected breaklines and "
                                          "points on the surface"))
        self.redrape_action.triggered.connect(lambda _checked=False: self.controller.redrape())
        self.toolbar.addAction(self.redrape_action)
        self.validate_action = QAction(QgsApplication.getThemeIcon("/mIconSuccess.svg"),
                                       tr("Validate"), self.toolbar)
        self.validate_action.setObjectName("photodemValidateEdits")
        self.validate_action.setToolTip(tr("Check the current edits, unsaved ones included"))
        self.validate_action.triggered.connect(lambda _checked=False: self.validate())
        self.toolbar.addAction(self.validate_action)

    # -- state ---------------------------------------------------------------------------------
    def set_workspace(self, workspace: Any) -> None:
        """Work on ``workspace`` (``None``: no project open, the tools are disabled)."""
        self.workspace = workspace
        self.controller.set_workspace(workspace)
        for name, action in self.actions.items():
            action.setEnabled(workspace is not None)
            if workspace is None and self.canvas.mapTool() is self.tools[name]:
                self.canvas.unsetMapTool(self.tools[name])
        self.redrape_action.setEnabled(workspace is not None)
        self.validate_action.setEnabled(workspace is not None)
        self.surface_box.setLayer(self.default_surface())

    def default_surface(self) -> Any:
        """The workspace's newest DSM (its first surface layer), or ``None``."""
        if self.workspace is None:
            return None
        layers = list(self.workspace.surface_layers() or [])
        return layers[0] if layers else None

    def _layers_added(self, _layers: Any) -> None:
        if self.surface_box.currentLayer() is None:
            self.surface_box.setLayer(self.default_surface())

    def surface_layer(self) -> Any:
        return self.surface_box.currentLayer()

    def _z_mode_changed(self, _index: int) -> None:
        self.controller.z_mode = self.z_mode_box.currentData() or Z_MODES[0]

    def set_z_mode(self, mode: str) -> None:
        self.z_mode_box.setCurrentIndex(self.z_mode_box.findData(mode))

    # -- actions -------------------------------------------------------------------------------
    def activate(self, name: str) -> Optional[Any]:
        """Make the tool of ``name`` the canvas's map tool; ``None`` (with a message, the
        action unchecked) when the layer cannot be edited."""
        layer = self.controller.editable_layer(name)
        tool = self.tools[name]
        if layer is None:
            self.actions[name].setChecked(False)
            if self.canvas.mapTool() is tool:
                self.canvas.unsetMapTool(tool)
            return None
        if isinstance(tool, CaptureTool):
            tool.setLayer(layer)
        if name == "seamlines":
            self._snap_to_mosaic_seamlines()
        self.canvas.setMapTool(tool)
        self.actions[name].setChecked(True)
        return tool

    def _snap_to_mosaic_seamlines(self) -> None:
        """Turn QGIS snapping on for the mosaic's seamline layers, when the operator has not
        configured snapping (a configured snapping is left as it is)."""
        project = QgsProject.instance()
        layers = [lyr for lyr in project.mapLayers().values() if is_mosaic_seamlines(lyr)]
        config = project.snappingConfig()
        if not layers or config.enabled():
            return
        config.setEnabled(True)
        config.setMode(QgsSnappingConfig.AdvancedConfiguration)
        for layer in layers:
            config.setIndividualLayerSettings(layer, QgsSnappingConfig.IndividualLayerSettings(
                True, QgsSnappingConfig.VertexFlag | QgsSnappingConfig.SegmentFlag,
                SNAP_PIXELS, QgsTolerance.Pixels, 0.0, 0.0))
        project.setSnappingConfig(config)

    def validate(self) -> Optional[ValidationDock]:
        """Check the current edits (unsaved ones included) and list the problems in the dock."""
        if self.workspace is None:
            self.controller.message(tr("Open a PhotoDEM project first (PhotoDEM → Open "
                                       "project…)."))
            return None
        found = collect_problems(self.workspace)
        if self.dock is None:
            self.dock = ValidationDock(self.iface)
            self.iface.addDockWidget(Qt.RightDockWidgetArea, self.dock)
        self.dock.show_problems(found, str(self.workspace.project.crs))
        level = Qgis.Info if not found else Qgis.Warning
        self.controller.message(tr("Validation: {0} problems.").format(len(found)), level)
        return self.dock

    def unload(self) -> None:
        """Remove the tools, the dock and the toolbar."""
        with contextlib.suppress(TypeError):  # already disconnected
            QgsProject.instance().layersAdded.disconnect(self._layers_added)
        for tool in self.tools.values():
            if self.canvas.mapTool() is tool:
                self.canvas.unsetMapTool(tool)
        self.controller.clear_marks()
        if self.dock is not None:
            self.iface.removeDockWidget(self.dock)
            self.dock.deleteLater()
            self.dock = None
        self.iface.mainWindow().removeToolBar(self.toolbar)
        self.toolbar.deleteLater()
        self.tools = {}
        self.actions = {}
