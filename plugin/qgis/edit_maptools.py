"""The map tools of the "PhotoDEM editing" toolbar and what they do with a click or a drawing.

The tools only translate clicks and layers: what a new edit becomes (heights, repairs,
crossings, snapping, validation) is decided by the core's
:mod:`photodem.algorithms.project.edit_rules` through the steps shared with the standalone map
(:mod:`photodem.plugin.widgets.edit_flow`). Every edit is
written through the layer's edit buffer (``beginEditCommand`` / ``addFeature`` /
``endEditCommand``), so QGIS's undo/redo works and *Save layer edits* commits; nothing else is
ever written.

* :class:`EditController` — the shared state (workspace, surface, Z mode, the questions) and the
  steps of each kind of edit.
* :class:`PointTool` — a click (start, ground and check points).
* :class:`CaptureTool` — a line or polygon digitised with QGIS's capture machinery (snapping,
  tracing, the advanced digitizing panel): exclusion areas, boundaries, breaklines, seamlines.

All geometries handed to the core are in the project CRS (the CRS of ``edits.gpkg``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

from qgis.core import (
    Qgis,
    QgsCoordinateReferenceSystem,
    QgsCoordinateTransform,
    QgsFeature,
    QgsGeometry,
    QgsPointXY,
    QgsProject,
    QgsRasterLayer,
    QgsVectorLayer,
)
from qgis.gui import (
    QgsMapToolCapture,
    QgsMapToolDigitizeFeature,
    QgsMapToolEmitPoint,
    QgsVertexMarker,
)
from qgis.PyQt.QtCore import Qt
from qgis.PyQt.QtGui import QColor
from shapely import wkb

from ...algorithms.errors import PhotodemError
from ...algorithms.project import edit_rules, edit_tools
from ...algorithms.project.edits import EDIT_LAYERS, edits_access
from ...algorithms.project.stereo_models import block_footprints
from ..i18n import tr
from ..widgets import edit_flow
from ..widgets.edit_forms import DialogAsker

# The rules' constants, re-exported for the toolbar (one copy, in the core).
Z_MODES = edit_rules.Z_MODES
POINT_LAYERS = edit_rules.POINT_LAYERS
Z_LAYERS = edit_rules.Z_LAYERS
SNAP_PIXELS = edit_rules.SNAP_PIXELS
#: Message levels of the shared edit steps (:mod:`..widgets.edit_flow`) in QGIS's terms.
LEVELS = {"info": Qgis.Info, "warning": Qgis.Warning, "critical": Qgis.Critical}


def edits_problem(path: Path) -> Optional[str]:
    """Why ``edits.gpkg`` cannot take edits now (missing, read-only, locked), or ``None``
    (:func:`~photodem.algorithms.project.edits.edits_access`, in the operator's language)."""
    problem = edits_access(path)
    if problem is None:
        return None
    kind, detail = problem
    if kind == "missing":
        return tr("The edits file {0} does not exist.").format(path)
    if kind == "read-only":
        return tr("The edits file {0} is read-only; make it writable to edit.").format(path)
    return tr("The edits file {0} is locked or unreadable ({1}); close the program that "
              "holds it and try again.").format(path, detail)


def to_shapely(geometry: QgsGeometry) -> Any:
    """A QGIS geometry as a shapely one (Z kept)."""
    return wkb.loads(bytes(geometry.asWkb()))


def to_qgis(geometry: Any) -> QgsGeometry:
    """A shapely geometry as a QGIS one (Z kept)."""
    out = QgsGeometry()
    out.fromWkb(wkb.dumps(geometry))
    return out


def layer_crs(text: str) -> QgsCoordinateReferenceSystem:
    """The QGIS CRS of a project CRS text (``EPSG:…``, WKT or PROJ)."""
    crs = QgsCoordinateReferenceSystem(text)
    if not crs.isValid():
        crs = QgsCoordinateReferenceSystem.fromProj(text)
    return crs


class EditController:
    """What the editing tools share and what each kind of edit does.

    Parameters
    ----------
    iface : QgisInterface-like
        For the canvas, the message bar and the main window.
    ask : object, optional
        The questions (:class:`.edit_forms.DialogAsker` by default; tests pass a stand-in
        with the same methods).
    """

    def __init__(self, iface: Any, ask: Any = None) -> None:
        self.iface = iface
        self.canvas = iface.mapCanvas()
        self.ask = ask if ask is not None else DialogAsker(iface.mainWindow())
        self.workspace: Any = None
        self.surface_layer: Callable[[], Optional[QgsRasterLayer]] = lambda: None
        self.z_mode = "drape"
        self.markers: List[QgsVertexMarker] = []
        self._footprints: Any = None

    # -- messages ------------------------------------------------------------------------------
    def message(self, text: str, level: Any = Qgis.Warning) -> None:
        self.iface.messageBar().pushMessage("PhotoDEM", text, level, 8)

    # -- state ---------------------------------------------------------------------------------
    def set_workspace(self, workspace: Any) -> None:
        self.workspace = workspace
        self._footprints = None
        self.clear_marks()

    def footprints(self) -> Any:
        """The block's image footprints, computed once per workspace (they cost a projection
        of every image's border)."""
        if self._footprints is None:
            self._footprints = block_footprints(self.workspace.project)
        return self._footprints

    def project_crs(self) -> str:
        return str(self.workspace.project.crs)

    def edits_path(self) -> Path:
        return Path(self.workspace.root) / "edits.gpkg"

    def editable_layer(self, name: str) -> Optional[QgsVectorLayer]:
        """The edit layer ``name`` in edit mode, or ``None`` with a message (no project, a
        missing layer, a read-only or locked ``edits.gpkg``)."""
        if self.workspace is None:
            self.message(tr("Open a PhotoDEM project first (PhotoDEM → Open project…)."))
            return None
        layer = self.workspace.edit_layer(name)
        if layer is None or not layer.isValid():
            self.message(tr("The layer '{0}' of edits.gpkg is not loaded or missing; add it to "
                            "the project's edits first.").format(name), Qgis.Critical)
            return None
        if not layer.isEditable():
            problem = edits_problem(self.edits_path())
            if problem:
                self.message(problem, Qgis.Critical)
                return None
            if not layer.startEditing():
                self.message(tr("QGIS cannot edit the layer '{0}'.").format(name), Qgis.Critical)
                return None
        return layer

    def edit_layer_name(self, layer: Any) -> Optional[str]:
        """The edit layer name of a map layer of the workspace, else ``None``."""
        if self.workspace is None or layer is None:
            return None
        for name in EDIT_LAYERS:
            if self.workspace.edit_layer(name) is layer:
                return name
        return None

    # -- coordinates ---------------------------------------------------------------------------
    def canvas_to(self, crs: QgsCoordinateReferenceSystem) -> QgsCoordinateTransform:
        return QgsCoordinateTransform(self.canvas.mapSettings().destinationCrs(), crs,
                                      QgsProject.instance())

    def canvas_point(self, x: float, y: float) -> Tuple[float, float]:
        """A canvas point in the project CRS."""
        p = self.canvas_to(layer_crs(self.project_crs())).transform(QgsPointXY(x, y))
        return p.x(), p.y()

    def layer_geometry(self, layer: QgsVectorLayer, geometry: QgsGeometry) -> Any:
        """A geometry in ``layer``'s CRS (as the capture tool gives it) in the project CRS."""
        target = layer_crs(self.project_crs())
        g = QgsGeometry(geometry)
        if layer.crs() != target:
            g.transform(QgsCoordinateTransform(layer.crs(), target, QgsProject.instance()))
        return to_shapely(g)

    # -- the surface ---------------------------------------------------------------------------
    def surface_path(self, needed: bool = True) -> Optional[str]:
        """The file of the toolbar's surface, or ``None`` with a message (none chosen, no
        CRS, not a file)."""
        layer = self.surface_layer()
        if layer is None:
            if needed:
                self.message(tr("Choose a surface (DSM or DTM) in the editing toolbar."))
            return None
        if not layer.crs().isValid():
            self.message(tr("The surface '{0}' has no CRS; assign it its CRS (Layer "
                            "Properties → Source) first.").format(layer.name()), Qgis.Critical)
            return None
        path = layer.source().split("|")[0]
        if not Path(path).is_file():
            self.message(tr("The surface '{0}' is not a file ({1}).").format(layer.name(), path),
                         Qgis.Critical)
            return None
        return path

    def sample(self, x: float, y: float) -> Tuple[Optional[float], str]:
        """The surface height at a project point and, without one, why (for the form)."""
        return edit_flow.sample(self, x, y)

    # -- the host of the shared edit steps (:mod:`..widgets.edit_flow`) ---------------------------
    @property
    def project(self) -> Any:
        return self.workspace.project

    def say(self, text: str, level: str = "warning") -> None:
        self.message(text, LEVELS.get(level, Qgis.Warning))

    def checked(self, name: str, geometry: Any, attributes: Dict[str, Any]) -> bool:
        """``validate_edit``: errors refuse the edit (message), warnings are shown."""
        return edit_flow.checked(self, name, geometry, attributes)

    # -- writing -------------------------------------------------------------------------------
    def write(self, layer: QgsVectorLayer, geometries: Sequence[Any],
              attributes: Dict[str, Any], title: str) -> bool:
        """Add features (project CRS) through the edit buffer as one undoable command."""
        target = layer_crs(self.project_crs())
        features = []
        for geometry in geometries:
            g = to_qgis(geometry)
            if layer.crs() != target:
                g.transform(QgsCoordinateTransform(target, layer.crs(), QgsProject.instance()))
            feature = QgsFeature(layer.fields())
            feature.setGeometry(g)
            for key, value in attributes.items():
                feature[key] = value
            features.append(feature)
        layer.beginEditCommand(title)
        if not all(layer.addFeature(f) for f in features):
            layer.destroyEditCommand()
            self.message(tr("QGIS refused the new feature of '{0}'.").format(layer.name()),
                         Qgis.Critical)
            return False
        layer.endEditCommand()
        layer.triggerRepaint()
        return True

    # -- points, polygons, lines -----------------------------------------------------------
    def write_edit(self, layer: QgsVectorLayer, edit: Optional[edit_flow.Edit]) -> bool:
        """Write what the shared edit steps decided (None: refused or cancelled)."""
        if edit is None:
            return False
        return self.write(layer, [g for g, _ in edit.features], edit.features[0][1], edit.title)

    def add_point(self, name: str, cx: float, cy: float) -> bool:
        """A start, ground or check point at a canvas point: height from the surface (or
        typed), confirmed in the form, checked, written."""
        layer = self.editable_layer(name)
        if layer is None:
            return False
        x, y = self.canvas_point(cx, cy)
        return self.write_edit(layer, edit_flow.point_edit(self, name, x, y))

    def add_polygon(self, name: str, layer: QgsVectorLayer, geometry: QgsGeometry) -> bool:
        """An exclusion area or boundary: repaired with consent if self-intersecting, the
        action (or name) asked, checked, written."""
        polygon = self.layer_geometry(layer, geometry)
        return self.write_edit(layer, edit_flow.polygon_edit(self, name, polygon))

    def existing_lines(self, layer: QgsVectorLayer) -> List[Any]:
        """The layer's lines in the project CRS, unsaved ones of the edit buffer included."""
        return [self.layer_geometry(layer, f.geometry()) for f in layer.getFeatures()
                if f.hasGeometry()]

    def add_line(self, name: str, layer: QgsVectorLayer, geometry: QgsGeometry) -> bool:
        """A breakline (crossings refused at once, heights by the Z mode) or a seamline
        (snapped to the mosaic's seamlines)."""
        line = self.layer_geometry(layer, geometry)
        coords = [(c[0], c[1]) for c in line.coords]
        if name == "seamlines":
            edit = edit_flow.line_edit(self, name, coords, seam_lines=self.seamline_sources(),
                                       tolerance=SNAP_PIXELS * self.canvas.mapUnitsPerPixel())
        else:
            edit = edit_flow.line_edit(self, name, coords, self.existing_lines(layer))
        return self.write_edit(layer, edit)

    def seamline_sources(self) -> List[Any]:
        """The lines of every loaded mosaic seamline layer, in the project CRS."""
        lines: List[Any] = []
        for layer in QgsProject.instance().mapLayers().values():
            if not is_mosaic_seamlines(layer):
                continue
            try:
                lines += edit_tools.mosaic_seamlines(layer.source().split("|")[0],
                                                     self.project_crs())
            except PhotodemError as exc:
                self.message(str(exc))
        return lines

    def snapped(self, coords: List[Tuple[float, float]]) -> List[Tuple[float, float]]:
        """Seamline vertices snapped onto the mosaic's seamlines when close to one."""
        return edit_rules.snapped(coords, self.seamline_sources(),
                                  SNAP_PIXELS * self.canvas.mapUnitsPerPixel())

    # -- re-drape ------------------------------------------------------------------------------
    def redrape(self) -> int:
        """Re-sample the heights of the selected features of the active edit layer on the
        surface (one undoable edit command); returns how many were changed."""
        layer = self.iface.activeLayer()
        name = self.edit_layer_name(layer)
        if name not in Z_LAYERS + ("start_points",):
            self.message(tr("Select breaklines or points in an edit layer of the project "
                            "(breaklines, start, ground or check points) to re-drape them."))
            return 0
        selected = list(layer.getSelectedFeatures())
        if not selected:
            self.message(tr("Nothing selected in '{0}'.").format(layer.name()))
            return 0
        path = self.surface_path()
        if path is None or self.editable_layer(name) is None:
            return 0
        changes = self._redraped(layer, name, selected, path)
        if changes is None:
            return 0
        layer.beginEditCommand(tr("Re-drape"))
        for fid, geometry, height in changes:
            if geometry is not None:
                layer.changeGeometry(fid, geometry)
            if height is not None:
                layer.changeAttributeValue(fid, layer.fields().indexOf("height"), height)
        layer.endEditCommand()
        layer.triggerRepaint()
        self.message(tr("{0} features re-draped on the surface.").format(len(changes)),
                     Qgis.Info)
        return len(changes)

    def _redraped(self, layer: QgsVectorLayer, name: str, features: List[QgsFeature],
                  path: str) -> Optional[List[Tuple[int, Optional[QgsGeometry], Any]]]:
        """The new geometry or height of each feature; ``None`` (message) if any vertex has
        no height on the surface."""
        target = layer_crs(self.project_crs())
        back = QgsCoordinateTransform(target, layer.crs(), QgsProject.instance())
        changes = []
        for feature in features:
            shape = self.layer_geometry(layer, feature.geometry())
            try:  # the Qt-free part is the standalone tool's too
                answer = edit_tools.redrape_feature(path, name, shape, crs=self.project_crs())
            except PhotodemError as exc:
                self.message(str(exc), Qgis.Critical)
                return None
            if answer.reason:
                self.message(tr("Feature {0}: {1}").format(feature.id(), answer.reason),
                             Qgis.Critical)
                return None
            if answer.geometry is None:
                changes.append((feature.id(), None, answer.height))
                continue
            g = to_qgis(answer.geometry)
            if layer.crs() != target:
                g.transform(back)
            changes.append((feature.id(), g, None))
        return changes

    # -- marks ---------------------------------------------------------------------------------
    def mark(self, points: Sequence[Tuple[float, float]]) -> None:
        """Red crosses at project points (crossings, self-intersections) until the next edit."""
        self.clear_marks()
        to_canvas = self.canvas_to(layer_crs(self.project_crs()))
        for x, y in points:
            p = to_canvas.transform(QgsPointXY(x, y), QgsCoordinateTransform.ReverseTransform)
            marker = QgsVertexMarker(self.canvas)
            marker.setCenter(p)
            marker.setIconType(QgsVertexMarker.ICON_X)
            marker.setColor(QColor(220, 0, 0))
            marker.setIconSize(16)
            marker.setPenWidth(3)
            self.markers.append(marker)

    def clear_marks(self) -> None:
        for marker in self.markers:
            self.canvas.scene().removeItem(marker)
        self.markers = []


def is_mosaic_seamlines(layer: Any) -> bool:
    """A vector layer of a mosaic's ``<name>_seamlines.gpkg`` (not the operator's seamlines)."""
    if not isinstance(layer, QgsVectorLayer):
        return False
    kind = str(layer.customProperty("photodem/kind", "") or "")
    if kind.startswith("edit:"):
        return False
    source = layer.source()
    return kind == "mosaic_seamlines" or ("_seamlines.gpkg" in source
                                          and "layername=seamlines" in source)


class PointTool(QgsMapToolEmitPoint):
    """A click writes a point of ``layer_name`` (start, ground or check point)."""

    def __init__(self, canvas: Any, controller: EditController, layer_name: str) -> None:
        super().__init__(canvas)
        self.controller = controller
        self.layer_name = layer_name
        self.canvasClicked.connect(self._clicked)

    def _clicked(self, point: QgsPointXY, button: Any) -> None:
        x, y = point.x(), point.y()  # copy: the point is a temporary of the event
        if button == Qt.LeftButton:
            self.controller.add_point(self.layer_name, x, y)


class CaptureTool(QgsMapToolDigitizeFeature):
    """A line or polygon of ``layer_name`` digitised with QGIS's capture machinery (snapping,
    tracing and the advanced digitizing panel work); a right click finishes it."""

    def __init__(self, canvas: Any, cad_dock: Any, controller: EditController,
                 layer_name: str) -> None:
        polygon = "Polygon" in EDIT_LAYERS[layer_name][0]
        mode = QgsMapToolCapture.CapturePolygon if polygon else QgsMapToolCapture.CaptureLine
        super().__init__(canvas, cad_dock, mode)
        self.controller = controller
        self.layer_name = layer_name
        self.polygon = polygon
        self.digitizingCompleted.connect(self._completed)

    def _completed(self, feature: QgsFeature) -> None:
        geometry = QgsGeometry(feature.geometry())  # copy: the feature is a temporary
        layer = self.layer()
        if geometry.isNull() or layer is None:
            return
        if self.polygon:
            self.controller.add_polygon(self.layer_name, layer, geometry)
        else:
            self.controller.add_line(self.layer_name, layer, geometry)
