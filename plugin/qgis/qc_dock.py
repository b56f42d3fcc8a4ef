"""The DEM quality dock of QGIS: the :class:`~photodem.plugin.widgets.qc_panel.QcPanel` with
layer pickers and the map tools that feed it.

* *Area*: a polygon drawn with QGIS's capture machinery (snapping works; a right click ends
  it), the visible extent or the whole model → area statistics; a rubber band shows the area.
* *Profile*: a line drawn (or a line feature of the active layer picked) → the profile of the
  surfaces; the arrow keys move the line sideways by one DEM cell and redraw the profile.
* *Identify*: a click → every surface's height there and their differences.

Geometries are taken from the canvas CRS into the reference's CRS (areas) or the DEM's CRS
(lines, points) with ``QgsCoordinateTransform``. The difference model of *Compare* is added to
the workspace's Products group (its ``.qml`` diverging style applies), and the blunder buttons
write through the workspace's edit layers' edit buffer (one undoable command each), so the
operator can undo them and saves them with QGIS's *Save layer edits*.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple

import numpy as np
from qgis.core import (
    Qgis,
    QgsCoordinateReferenceSystem,
    QgsCoordinateTransform,
    QgsFeature,
    QgsGeometry,
    QgsMapLayer,
    QgsMapLayerProxyModel,
    QgsPalettedRasterRenderer,
    QgsPointXY,
    QgsProject,
    QgsRasterLayer,
    QgsRectangle,
    QgsVectorLayer,
    QgsWkbTypes,
)
from qgis.gui import (
    QgsAdvancedDigitizingDockWidget,
    QgsFieldComboBox,
    QgsMapLayerComboBox,
    QgsMapToolCapture,
    QgsMapToolDigitizeFeature,
    QgsMapToolEmitPoint,
    QgsMapToolIdentifyFeature,
    QgsRubberBand,
)
from qgis.PyQt.QtCore import Qt
from qgis.PyQt.QtGui import QColor
from qgis.PyQt.QtWidgets import (
    QDockWidget,
    QFormLayout,
    QGridLayout,
    QPushButton,
    QVBoxLayout,
    QWidget,
)
from shapely.geometry import LineString

from ...algorithms.errors import InputError
from ..i18n import tr
from ..widgets.map_qc_tools import area_label
from ..widgets.qc_panel import QcPanel
from .edit_maptools import to_qgis, to_shapely
from .workspace import _source_path, current_workspace, workspace_notifier

#: Share of the spot's size added around it when a blunder row zooms (and at least 5 m).
ZOOM_MARGIN = 1.0
#: Arrow keys and the sideways direction they move the profile line (+1 = left of it).
NUDGE_KEYS = {Qt.Key_Left: 1, Qt.Key_Up: 1, Qt.Key_Right: -1, Qt.Key_Down: -1}


def layer_path(layer: Optional[QgsMapLayer]) -> Optional[str]:
    """The file behind a layer (an OGR layer name dropped), or None."""
    if layer is None:
        return None
    path = _source_path(layer)
    return path if path and Path(path).is_file() else None


def offset_line(coords: np.ndarray, distance: float) -> np.ndarray:
    """The polyline moved sideways by ``distance`` (positive: to its left), vertex by vertex
    along the mean normal of the adjacent segments; Z (if any) is kept."""
    xy = coords[:, :2]
    seg = np.diff(xy, axis=0)
    normals = np.column_stack([-seg[:, 1], seg[:, 0]]) / np.hypot(*seg.T)[:, None]
    per_vertex = np.vstack([normals[:1], normals[:-1] + normals[1:], normals[-1:]])
    per_vertex /= np.hypot(*per_vertex.T)[:, None]
    out = coords.copy()
    out[:, :2] = xy + distance * per_vertex
    return out


class AreaTool(QgsMapToolDigitizeFeature):
    """Draw a polygon (right click ends it) → :meth:`QcDock.area_drawn`."""

    def __init__(self, dock: QcDock) -> None:
        super().__init__(dock.canvas, dock.cad, QgsMapToolCapture.CapturePolygon)
        self.dock = dock
        self.digitizingCompleted.connect(self._completed)

    def _completed(self, feature: QgsFeature) -> None:
        geometry = QgsGeometry(feature.geometry())  # copy: the feature is a temporary
        if not geometry.isNull():
            self.dock.area_drawn(geometry)


class LineTool(QgsMapToolDigitizeFeature):
    """Draw a profile line (right click ends it) → :meth:`QcDock.line_drawn`; the arrow keys
    move the last line sideways."""

    def __init__(self, dock: QcDock) -> None:
        super().__init__(dock.canvas, dock.cad, QgsMapToolCapture.CaptureLine)
        self.dock = dock
        self.digitizingCompleted.connect(self._completed)

    def _completed(self, feature: QgsFeature) -> None:
        geometry = QgsGeometry(feature.geometry())
        if not geometry.isNull():
            self.dock.line_drawn(geometry)

    def keyPressEvent(self, event: Any) -> None:
        if event.key() in NUDGE_KEYS and self.size() == 0 and self.dock.panel.line is not None:
            self.dock.nudge(NUDGE_KEYS[event.key()])
            event.accept()
            return
        super().keyPressEvent(event)


class IdentifyTool(QgsMapToolEmitPoint):
    """A click → :meth:`QcDock.identify_at`."""

    def __init__(self, dock: QcDock) -> None:
        super().__init__(dock.canvas)
        self.dock = dock
        self.canvasClicked.connect(self._clicked)

    def _clicked(self, point: QgsPointXY, button: Any) -> None:
        x, y = point.x(), point.y()  # copy: the point is a temporary of the event
        if button == Qt.LeftButton:
            self.dock.identify_at(x, y)


class QcDock(QDockWidget):
    """The QC panel in a dock, with layer pickers, area/line/point tools and rubber bands.

    Parameters
    ----------
    iface : QgisInterface-like
        For the canvas, the message bar and the active layer.
    """

    def __init__(self, iface: Any, parent: Optional[QWidget] = None) -> None:
        super().__init__(tr("PhotoDEM – DEM quality"), parent)
        self.setObjectName("photodemQcDock")
        self.iface = iface
        self.canvas = iface.mapCanvas()
        self.workspace: Any = None
        self.panel = QcPanel(self)
        self.panel.inputs_box.hide()
        self.panel.input_provider = self.inputs
        self.panel.edit_writer = self.write_edit
        self.panel.zoomTo.connect(self.zoom_to)
        self.panel.difference_ready.connect(self.add_difference)
        self.panel.message.connect(self._message)
        self.panel.filter_tab.dtm_changed.connect(self.reload_layers_of)
        self._build()
        self.area_band = self._band(QgsWkbTypes.PolygonGeometry, QColor(255, 0, 160, 50))
        self.line_band = self._band(QgsWkbTypes.LineGeometry, QColor(255, 0, 160, 220))
        # the capture tools keep a raw pointer to it: it must live as long as they do
        self.cad = QgsAdvancedDigitizingDockWidget(self.canvas, self)
        self.cad.hide()
        self._scratch_layers: Dict[str, QgsVectorLayer] = {}
        self.tools = {"area": AreaTool(self), "line": LineTool(self),
                      "identify": IdentifyTool(self)}
        self.set_workspace(current_workspace())
        workspace_notifier().changed.connect(self.set_workspace)

    # -- layout ----------------------------------------------------------------------------------
    def _build(self) -> None:
        body = QWidget(self)
        lay = QVBoxLayout(body)
        form = QFormLayout()
        self.dem_combo = self._raster_combo(body, False)
        self.reference_combo = self._raster_combo(body, False)
        self.classes_combo = self._raster_combo(body, True)
        self.classes_combo.setFilters(QgsMapLayerProxyModel.RasterLayer
                                      | QgsMapLayerProxyModel.PolygonLayer)
        self.class_field_combo = QgsFieldComboBox(body)
        self.classes_combo.layerChanged.connect(self._classes_changed)
        form.addRow(tr("DEM"), self.dem_combo)
        form.addRow(tr("Reference"), self.reference_combo)
        form.addRow(tr("Classes (optional)"), self.classes_combo)
        form.addRow(tr("Class attribute"), self.class_field_combo)
        self._classes_changed(None)
        lay.addLayout(form)
        grid = QGridLayout()
        self.buttons: Dict[str, QPushButton] = {}
        rows = ((("area", tr("Draw area"), lambda: self.activate("area")),
                 ("extent", tr("Visible extent"), self.use_visible_extent),
                 ("whole", tr("Whole model"), self.use_whole_model),
                 ("mask", tr("Show eliminated cells"), self.show_mask)),
                (("line", tr("Draw profile"), lambda: self.activate("line")),
                 ("pick", tr("Profile of feature"), self.pick_line),
                 ("identify", tr("Identify"), lambda: self.activate("identify"))))
        for r, buttons in enumerate(rows):
            for c, (key, text, slot) in enumerate(buttons):
                button = QPushButton(text, body)
                button.clicked.connect(slot)
                grid.addWidget(button, r, c)
                self.buttons[key] = button
        lay.addLayout(grid)
        lay.addWidget(self.panel, 1)
        self.setWidget(body)

    def _raster_combo(self, parent: QWidget, optional: bool) -> QgsMapLayerComboBox:
        combo = QgsMapLayerComboBox(parent)
        combo.setFilters(QgsMapLayerProxyModel.RasterLayer)
        combo.setAllowEmptyLayer(optional)
        if optional:
            combo.setLayer(None)
        return combo

    def _classes_changed(self, layer: Any) -> None:
        """Class polygons need their class attribute; a class raster does not."""
        vector = layer is not None and layer.type() == QgsMapLayer.VectorLayer
        self.class_field_combo.setLayer(layer if vector else None)
        self.class_field_combo.setEnabled(vector)

    def _band(self, kind: Any, colour: QColor) -> QgsRubberBand:
        band = QgsRubberBand(self.canvas, kind)
        band.setColor(colour)
        band.setStrokeColor(QColor(255, 0, 160))
        band.setWidth(2)
        return band

    # -- workspace and inputs --------------------------------------------------------------------
    def set_workspace(self, workspace: Any) -> None:
        """Work on a project: its edits, its products; defaults: the newest DSM and the next
        surface as the reference."""
        self.workspace = workspace
        self.panel.set_project(workspace.root if workspace is not None else None)
        if workspace is None:
            return
        surfaces = workspace.surface_layers()
        if surfaces:
            self.dem_combo.setLayer(surfaces[0])
        if len(surfaces) > 1:
            self.reference_combo.setLayer(surfaces[1])
        dtms = [p for p in (layer_path(x) for x in workspace.layers("dtm")) if p]
        if dtms and not self.panel.filter_tab.dtm_edit.text():
            self.panel.filter_tab.dtm_edit.setText(dtms[0])

    def inputs(self) -> Dict[str, Any]:
        """The panel's inputs from the layer pickers (+ the workspace's other surfaces)."""
        dem, ref = layer_path(self.dem_combo.currentLayer()), \
            layer_path(self.reference_combo.currentLayer())
        others: List[str] = []
        if self.workspace is not None:
            others = [p for p in (layer_path(x) for x in self.workspace.surface_layers())
                      if p and p not in (dem, ref)]
        classes = self.classes_combo.currentLayer()
        field = self.class_field_combo.currentField() if self.class_field_combo.isEnabled() \
            else None
        return {"dem": dem, "reference": ref, "classes": layer_path(classes),
                "class_field": field or None, "surfaces": others}

    def _crs_of(self, combo: QgsMapLayerComboBox) -> Optional[QgsCoordinateReferenceSystem]:
        layer = combo.currentLayer()
        return layer.crs() if layer is not None else None

    def _to_layer(self, geometry: QgsGeometry, combo: QgsMapLayerComboBox) -> QgsGeometry:
        """A canvas geometry in the CRS of the combo's layer."""
        out = QgsGeometry(geometry)
        crs = self._crs_of(combo)
        source = self.canvas.mapSettings().destinationCrs()
        if crs is not None and crs.isValid() and crs != source:
            out.transform(QgsCoordinateTransform(source, crs, QgsProject.instance()))
        return out

    def _message(self, level: str, text: str) -> None:
        levels = {"info": Qgis.Info, "warning": Qgis.Warning, "error": Qgis.Critical}
        self.iface.messageBar().pushMessage("PhotoDEM", text, levels.get(level, Qgis.Info),
                                            5 if level == "info" else 0)

    # -- tools -----------------------------------------------------------------------------------
    def activate(self, name: str) -> Any:
        """Make one of the dock's map tools (``area``, ``line``, ``identify``) current."""
        tool = self.tools[name]
        if name in ("area", "line"):
            tool.setLayer(self._scratch(name))
        self.canvas.setMapTool(tool)
        return tool

    def _scratch(self, name: str) -> QgsVectorLayer:
        """An editable memory layer in the canvas CRS for a capture tool (never on the map):
        QGIS's capture tools digitise only into an editable layer; nothing is added to it."""
        kind = "Polygon" if name == "area" else "LineString"
        crs = self.canvas.mapSettings().destinationCrs().authid() or "EPSG:4326"
        layer = QgsVectorLayer(f"{kind}?crs={crs}", f"photodem qc {name}", "memory")
        layer.startEditing()
        self._scratch_layers[name] = layer  # keep it alive while the tool uses it
        return layer

    def area_drawn(self, geometry: QgsGeometry) -> None:
        """A polygon was drawn (canvas CRS): show it and compute its statistics."""
        self.area_band.setToGeometry(geometry, None)
        shape = to_shapely(self._to_layer(geometry, self.reference_combo))
        self.panel.set_area(shape.wkt, area_label(shape))

    def use_visible_extent(self) -> None:
        rect = QgsGeometry.fromRect(self.canvas.extent())
        self.area_band.setToGeometry(rect, None)
        shape = to_shapely(self._to_layer(rect, self.reference_combo))
        self.panel.set_area(shape.wkt, tr("visible extent"))

    def use_whole_model(self) -> None:
        self.area_band.reset(QgsWkbTypes.PolygonGeometry)
        self.panel.set_area(None, tr("whole model"))

    def line_drawn(self, geometry: QgsGeometry) -> None:
        """A line was drawn or picked (canvas CRS): show it and draw the profile."""
        self.line_band.setToGeometry(geometry, None)
        shape = to_shapely(self._to_layer(geometry, self.dem_combo))
        if shape.geom_type == "MultiLineString":
            shape = shape.geoms[0]
        self.panel.set_line(np.asarray(shape.coords, dtype=float))

    def pick_line(self) -> Any:
        """Pick a line feature of the active layer (e.g. a breakline) as the profile line."""
        layer = self.iface.activeLayer()
        if layer is None or layer.type() != QgsMapLayer.VectorLayer or \
                layer.geometryType() != QgsWkbTypes.LineGeometry:
            self._message("warning", tr("Select a line layer in the layer tree first."))
            return None
        tool = QgsMapToolIdentifyFeature(self.canvas, layer)
        tool.featureIdentified.connect(lambda f, lyr=layer: self.feature_picked(lyr, f))
        self.tools["pick"] = tool
        self.canvas.setMapTool(tool)
        return tool

    def feature_picked(self, layer: Any, feature: QgsFeature) -> None:
        """A line feature: its geometry (with Z: the vertex heights are plotted too)."""
        geometry = QgsGeometry(feature.geometry())
        source = layer.crs()
        target = self.canvas.mapSettings().destinationCrs()
        if source != target:
            geometry.transform(QgsCoordinateTransform(source, target, QgsProject.instance()))
        self.line_drawn(geometry)

    def nudge(self, direction: int) -> None:
        """Move the profile line sideways by one DEM cell (+1: to its left) and redraw."""
        line = self.panel.line
        layer = self.dem_combo.currentLayer()
        if line is None or layer is None:
            return
        cell = layer.rasterUnitsPerPixelX()
        moved = offset_line(line, direction * cell)
        geom = to_qgis(LineString(moved.tolist()))
        crs = layer.crs()
        target = self.canvas.mapSettings().destinationCrs()
        shown = QgsGeometry(geom)
        if crs != target:
            shown.transform(QgsCoordinateTransform(crs, target, QgsProject.instance()))
        self.line_band.setToGeometry(shown, None)
        self.panel.set_line(moved)

    def identify_at(self, x: float, y: float) -> Any:
        """Heights of every surface at a canvas point."""
        point = self._to_layer(QgsGeometry.fromPointXY(QgsPointXY(x, y)), self.dem_combo)
        p = point.asPoint()
        return self.panel.show_identify(p.x(), p.y())

    def zoom_to(self, bounds: Tuple[float, float, float, float]) -> None:
        """Zoom the canvas to a blunder spot (reference CRS), with a margin."""
        xmin, ymin, xmax, ymax = bounds
        pad = max(ZOOM_MARGIN * max(xmax - xmin, ymax - ymin), 5.0)
        rect = QgsGeometry.fromRect(QgsRectangle(xmin - pad, ymin - pad, xmax + pad, ymax + pad))
        crs = self._crs_of(self.reference_combo)
        target = self.canvas.mapSettings().destinationCrs()
        if crs is not None and crs != target:
            rect.transform(QgsCoordinateTransform(crs, target, QgsProject.instance()))
        self.canvas.setExtent(rect.boundingBox())
        self.canvas.refresh()

    # -- filter review ---------------------------------------------------------------------------
    def show_mask(self) -> Optional[QgsRasterLayer]:
        """The eliminated cells of the review's DTM (its ``mask.tif``) on top of the map:
        objects red, half transparent; ground and no data clear."""
        dtm = self.panel.filter_tab.dtm_edit.text().strip()
        mask = Path(dtm).with_name("mask.tif") if dtm else None
        if mask is None or not mask.is_file():
            self._message("warning", tr("Choose a DTM of a PhotoDEM filter run (with its "
                                        "mask.tif) in the Filter review tab."))
            return None
        layer = QgsRasterLayer(str(mask), tr("eliminated cells ({0})")
                               .format(Path(dtm).parent.name), "gdal")
        if not layer.isValid():
            return None
        classes = [QgsPalettedRasterRenderer.Class(1, QColor(215, 48, 31), tr("eliminated"))]
        renderer = QgsPalettedRasterRenderer(layer.dataProvider(), 1, classes)
        renderer.setOpacity(0.5)
        layer.setRenderer(renderer)
        QgsProject.instance().addMapLayer(layer)
        return layer

    def reload_layers_of(self, path: str) -> int:
        """Redraw the layers of a file an *Accept* changed (and its mask); returns how many."""
        wanted = {str(Path(path).resolve()), str(Path(path).with_name("mask.tif").resolve())}
        count = 0
        for layer in QgsProject.instance().mapLayers().values():
            if _source_path(layer) in wanted:
                layer.dataProvider().reloadData()
                layer.triggerRepaint()
                count += 1
        return count

    # -- products and edits ----------------------------------------------------------------------
    def add_difference(self, path: str) -> List[QgsMapLayer]:
        """The difference model on the map (and the DEM's hillshade the comparison wrote below
        it): in the Products group (styled) with a workspace, else on top with its ``.qml``
        style."""
        if self.workspace is not None:
            shade = Path(path).with_name("hillshade.tif")
            return self.workspace.add_products([str(shade), path] if shade.is_file() else [path])
        layer = QgsRasterLayer(path, Path(path).parent.name + " Δh", "gdal")
        if not layer.isValid():
            return []
        style = Path(path).with_suffix(".qml")
        if style.is_file():
            layer.loadNamedStyle(str(style))
        QgsProject.instance().addMapLayer(layer)
        return [layer]

    def write_edit(self, name: str, geometry: Any, attributes: Dict[str, Any]) -> None:
        """Add an edit through the workspace layer's edit buffer (undoable), project CRS."""
        layer = self.workspace.edit_layer(name) if self.workspace is not None else None
        if layer is None:
            raise InputError(tr("Open a PhotoDEM project first: the edit goes into its "
                                "layer '{0}'.").format(name))
        if not layer.isEditable():
            layer.startEditing()
        g = to_qgis(geometry)
        crs = self._crs_of(self.reference_combo)
        if crs is not None and crs.isValid() and crs != layer.crs():
            g.transform(QgsCoordinateTransform(crs, layer.crs(), QgsProject.instance()))
        feature = QgsFeature(layer.fields())
        feature.setGeometry(g)
        for key, value in attributes.items():
            feature[key] = value
        layer.beginEditCommand(tr("Blunder to {0}").format(name))
        if not layer.addFeature(feature):
            layer.destroyEditCommand()
            raise InputError(tr("QGIS refused the new feature of '{0}'.").format(layer.name()))
        layer.endEditCommand()
        layer.triggerRepaint()

    def closeEvent(self, event: Any) -> None:
        """Remove the rubber bands and give the canvas its tool back."""
        self.area_band.reset(QgsWkbTypes.PolygonGeometry)
        self.line_band.reset(QgsWkbTypes.LineGeometry)
        for tool in self.tools.values():
            if self.canvas.mapTool() is tool:
                self.canvas.unsetMapTool(tool)
        super().closeEvent(event)
