"""The map tools of the "PhotoDEM editing" toolbar and what they do with a click or a drawing.

The tools only translate clicks and layers: heights come from
:mod:`photodem.algorithms.project.edit_tools` (``sample_height``, ``drape_line``,
``snap_to_lines``), the checks from :mod:`~photodem.algorithms.project.edit_checks`
(``models_at``, ``check_new_breakline``, ``check_new_polygon``, ``validate_edit``). Every edit is
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
from shapely.geometry import LineString, Point

from ...algorithms.errors import PhotodemError
from ...algorithms.project import edit_checks, edit_tools
from ...algorithms.project.edits import EDIT_LAYERS, edits_access
from ...algorithms.project.stereo_models import block_footprints
from ..i18n import tr
from .edit_forms import DialogAsker

#: Breakline height modes of the toolbar: each vertex draped on the surface, every height typed,
#: or linear between the typed heights of the two ends.
Z_MODES = ("drape", "typed", "interpolate")
#: Point layers and the label of their text field in the height form.
POINT_LAYERS = {"start_points": "note", "ground_points": "note", "check_points": "id"}
#: Layers whose geometry carries the height in Z.
Z_LAYERS = ("breaklines", "ground_points", "check_points")
#: Seamline vertices within this many screen pixels of a mosaic seamline are snapped onto it.
SNAP_PIXELS = 12


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
        path = self.surface_path(needed=False)
        if path is None:
            return None, tr("No surface chosen; type the height.")
        try:
            answer = edit_tools.sample_height(path, x, y, crs=self.project_crs())
        except PhotodemError as exc:
            return None, str(exc)
        return answer.z, answer.reason or ""

    # -- writing -------------------------------------------------------------------------------
    def checked(self, name: str, geometry: Any, attributes: Dict[str, Any]) -> bool:
        """``validate_edit``: errors refuse the edit (message), warnings are shown."""
        problems = edit_checks.validate_edit(name, geometry, attributes, self.workspace.project,
                                             self.footprints())
        bad = edit_checks.errors(problems)
        if bad:
            self.message(" ".join(p.message for p in bad), Qgis.Critical)
            return False
        if problems:
            self.message(" ".join(p.message for p in problems))
        return True

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

    # -- points --------------------------------------------------------------------------------
    def add_point(self, name: str, cx: float, cy: float) -> bool:
        """A start, ground or check point at a canvas point: height from the surface (or
        typed), confirmed in the form, checked, written."""
        layer = self.editable_layer(name)
        if layer is None:
            return False
        x, y = self.canvas_point(cx, cy)
        z, reason = self.sample(x, y)
        notes = [reason] if reason else []
        if name == "start_points" and not edit_checks.models_at(self.workspace.project, x, y,
                                                                self.footprints()):
            notes.insert(0, tr("The point lies outside every stereo model; no model will use "
                               "it."))
            z = None  # the operator types the height there
        if notes:
            self.message(" ".join(notes))
        titles = {"start_points": tr("Start point"), "ground_points": tr("Ground point"),
                  "check_points": tr("Check point")}
        label = tr("Id") if POINT_LAYERS[name] == "id" else tr("Note")
        answer = self.ask.height(titles[name], z, " ".join(notes), label)
        if answer is None:
            return False
        height, text = answer
        if name == "start_points":
            geometry, attributes = Point(x, y), {"height": height, "note": text or None}
        else:
            geometry, attributes = Point(x, y, height), {POINT_LAYERS[name]: text or None}
        if not self.checked(name, geometry, attributes):
            return False
        return self.write(layer, [geometry], attributes, titles[name])

    # -- polygons ------------------------------------------------------------------------------
    def add_polygon(self, name: str, layer: QgsVectorLayer, geometry: QgsGeometry) -> bool:
        """An exclusion area or boundary: repaired with consent if self-intersecting, the
        action (or name) asked, checked, written."""
        polygon = self.layer_geometry(layer, geometry)
        check = edit_checks.check_new_polygon(polygon)
        if check.problems:
            text = " ".join(p.message for p in check.problems)
            self.mark([p.location for p in check.problems if p.location])
            if check.repaired is None or not self.ask.repair(text):
                self.message(tr("Polygon refused, nothing written: {0}").format(text),
                             Qgis.Critical)
                return False
            polygon = check.repaired
        if name == "exclusion_areas":
            answer = self.ask.action()
            if answer is None:
                return False
            attributes = {"action": answer[0], "note": answer[1] or None}
            title = tr("Exclusion area")
        else:
            text = self.ask.text(tr("Boundary"), tr("Name"))
            if text is None:
                return False
            attributes, title = {"name": text or None}, tr("Boundary")
        parts = list(getattr(polygon, "geoms", [polygon]))
        if not all(self.checked(name, part, attributes) for part in parts):
            return False
        self.clear_marks()
        return self.write(layer, parts, attributes, title)

    # -- lines ---------------------------------------------------------------------------------
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
            line = LineString(self.snapped(coords))
            if not self.checked(name, line, {}):
                return False
            return self.write(layer, [line], {}, tr("Seamline"))
        flat = LineString(coords)
        crossings = edit_checks.check_new_breakline(flat, self.existing_lines(layer))
        if crossings:
            self.mark([p.location for p in crossings if p.location])
            self.message(tr("Breakline refused, nothing written: {0}").format(
                " ".join(p.message for p in crossings)), Qgis.Critical)
            return False
        self.clear_marks()
        answer = self.breakline_heights(coords)
        if answer is None:
            return False
        heights, kind = answer
        line = LineString([(x, y, z) for (x, y), z in zip(coords, heights)])
        attributes = {"kind": kind}
        if not self.checked(name, line, attributes):
            return False
        return self.write(layer, [line], attributes, tr("Breakline"))

    def breakline_heights(self, coords: List[Tuple[float, float]]
                          ) -> Optional[Tuple[List[float], str]]:
        """Vertex heights by the Z mode, confirmed (and completed) in the breakline form."""
        n = len(coords)
        heights: List[Optional[float]] = [None] * n
        editable = [True] * n
        message = ""
        if self.z_mode in ("drape", "typed"):
            path = self.surface_path(needed=self.z_mode == "drape")
            if path is None and self.z_mode == "drape":
                return None
            if path is not None:
                try:
                    draped = edit_tools.drape_line(path, coords, crs=self.project_crs())
                except PhotodemError as exc:
                    self.message(str(exc), Qgis.Critical)
                    return None
                heights = [None if i in draped.missing else c[2]
                           for i, c in enumerate(draped.coords)]
                message = draped.reason or ""
            if self.z_mode == "drape":
                editable = [z is None for z in heights]
        if self.z_mode == "interpolate":
            editable = [i in (0, n - 1) for i in range(n)]
            message = tr("Type the heights of the two ends; the others are interpolated.")
        if message:
            self.message(message)
        answer = self.ask.breakline(heights, editable, message)
        if answer is None:
            return None
        typed, kind = answer
        if self.z_mode == "interpolate":
            try:
                line = edit_tools.drape_line(None, coords, mode="interpolate",
                                             end_heights=(typed[0], typed[-1]))
            except PhotodemError as exc:
                self.message(str(exc), Qgis.Critical)
                return None
            typed = [c[2] for c in line.coords]
        if any(z is None for z in typed):  # a form that let a vertex without height through
            self.message(tr("Every vertex of a breakline needs a height."), Qgis.Warning)
            return None
        return [float(z) for z in typed], kind

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
        lines = self.seamline_sources()
        if not lines:
            return coords
        tolerance = SNAP_PIXELS * self.canvas.mapUnitsPerPixel()
        out = []
        for xy in coords:
            snap = edit_tools.snap_to_lines(xy, lines, tolerance)
            out.append(tuple(snap.point) if snap is not None else xy)
        return out

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
