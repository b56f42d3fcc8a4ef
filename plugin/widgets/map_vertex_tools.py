"""Vertex editing, feature deletion and re-drape on the standalone map (issue 21).

* :class:`VertexTool` — drag a vertex of an edit layer's feature to move it (one undo command
  on release); a right click or the Delete key on a vertex removes it. Heights of a moved
  vertex come from the chosen surface (:attr:`VertexTool.surface`) for the layers that carry
  heights, else they are kept. The edit must pass the checks the capture tools apply (crossing
  breaklines, valid polygons, :func:`~photodem.algorithms.project.edit_checks.validate_edit`);
  a refused edit changes nothing and says why (:attr:`VertexTool.message`).
* :class:`DeleteFeatureTool` — a click removes the feature under the cursor.
* :func:`redrape` — new heights of every feature from a surface, one undo command.

The geometry work (which vertex, moving and removing it) is Qt-free here; heights and checks
come from the core (:mod:`~photodem.algorithms.project.edit_tools`,
:mod:`~photodem.algorithms.project.edit_checks`), like in the QGIS tools. Edits go through the
:class:`.edit_session.EditSession`; the map coordinates are the project CRS (the edits' CRS).
"""

from __future__ import annotations

import math
from typing import Any, Dict, List, Optional, Sequence, Tuple

from shapely.geometry import (
    LineString,
    MultiLineString,
    MultiPoint,
    MultiPolygon,
    Point,
    Polygon,
)

from ...algorithms.errors import InputError, PhotodemError
from ...algorithms.project import edit_checks, edit_tools
from ...algorithms.project.edit_tools import REDRAPE_LAYERS
from ...algorithms.project.stereo_models import block_footprints
from ..i18n import tr
from ..qt import QtCore, QtGui, pyqtSignal
from .map_layer import MapTool, ViewState

#: A vertex: (part, ring, index) in :func:`vertex_rings`.
Key = Tuple[int, int, int]
Coord = Tuple[float, ...]
#: How close (widget pixels) a press must be to a vertex or a feature to take it.
PICK_PIXELS = 10.0
#: Layers whose geometry carries the height in Z; start points keep it in ``height``.
Z_LAYERS = ("breaklines", "ground_points", "check_points")


# -- vertices of a shapely geometry (Qt-free) ---------------------------------------------------
def vertex_rings(geometry: Any) -> List[List[List[Coord]]]:
    """The vertices of a geometry as parts → rings → coordinates (polygon rings without their
    closing vertex; a line or a point is one ring)."""
    parts = list(getattr(geometry, "geoms", [geometry]))
    out: List[List[List[Coord]]] = []
    for part in parts:
        if part.geom_type == "Polygon":
            rings = [part.exterior] + list(part.interiors)
            out.append([[tuple(c) for c in ring.coords][:-1] for ring in rings])
        else:
            out.append([[tuple(c) for c in part.coords]])
    return out


def rebuild(geom_type: str, parts: List[List[List[Coord]]]) -> Any:
    """A geometry of ``geom_type`` from :func:`vertex_rings`' structure."""
    def one(rings: List[List[Coord]], kind: str) -> Any:
        if kind == "Polygon":
            return Polygon(rings[0], rings[1:])
        if kind == "LineString":
            return LineString(rings[0])
        return Point(rings[0][0])

    if geom_type.startswith("Multi"):
        single = geom_type[len("Multi"):]
        cls = {"Polygon": MultiPolygon, "LineString": MultiLineString, "Point": MultiPoint}
        return cls[single]([one(rings, single) for rings in parts])
    return one(parts[0], geom_type)


def vertices(geometry: Any) -> List[Tuple[Key, Coord]]:
    """Every vertex with its key."""
    return [((p, r, i), c) for p, rings in enumerate(vertex_rings(geometry))
            for r, ring in enumerate(rings) for i, c in enumerate(ring)]


def moved(geometry: Any, key: Key, x: float, y: float, z: Optional[float] = None) -> Any:
    """``geometry`` with the vertex ``key`` at (x, y); its Z is ``z`` when given, else kept (a
    2-D geometry stays 2-D)."""
    parts = vertex_rings(geometry)
    p, r, i = key
    old = parts[p][r][i]
    if len(old) > 2:
        parts[p][r][i] = (x, y, old[2] if z is None else z)
    else:
        parts[p][r][i] = (x, y)
    return rebuild(geometry.geom_type, parts)


def without_vertex(geometry: Any, key: Key) -> Any:
    """``geometry`` without the vertex ``key``.

    Raises
    ------
    InputError
        When the geometry would become invalid: a point, a line with fewer than 2 vertices,
        a polygon ring with fewer than 3.
    """
    kind = geometry.geom_type.replace("Multi", "")
    parts = vertex_rings(geometry)
    p, r, i = key
    ring = parts[p][r]
    if kind == "Point":
        raise InputError(tr("A point has only this one vertex; delete the feature instead."))
    if kind == "LineString" and len(ring) <= 2:
        raise InputError(tr("A line needs at least 2 vertices; this one would keep only {0}. "
                            "Delete the feature instead.").format(len(ring) - 1))
    if kind == "Polygon" and len(ring) <= 3:
        raise InputError(tr("A polygon needs at least 3 vertices; this one would keep only "
                            "{0}. Delete the feature instead.").format(len(ring) - 1))
    del ring[i]
    return rebuild(geometry.geom_type, parts)


def nearest_vertex(features: Sequence[Tuple[int, Any, Dict[str, Any]]], view: ViewState,
                   px: float, py: float, tolerance: float = PICK_PIXELS
                   ) -> Optional[Tuple[int, Key, Coord]]:
    """The vertex nearest to the widget pixel (px, py) within ``tolerance`` pixels:
    ``(fid, key, coord)`` or None."""
    best: Optional[Tuple[int, Key, Coord]] = None
    best_d = tolerance
    for fid, geometry, _ in features:
        for key, c in vertices(geometry):
            at = view.to_pixel(c[0], c[1])
            d = math.hypot(at.x() - px, at.y() - py)
            if d <= best_d:
                best, best_d = (fid, key, c), d
    return best


# -- the checks of an edit ---------------------------------------------------------------------
def edit_problems(session: Any, layer: str, fid: Optional[int], geometry: Any,
                  attributes: Dict[str, Any], project: Any = None,
                  footprints: Any = None) -> List[edit_checks.Problem]:
    """The problems of a changed feature: crossings with the other breaklines, an invalid
    polygon, and (with a project) :func:`validate_edit`."""
    problems: List[edit_checks.Problem] = []
    if layer == "breaklines":
        others = [g for f, g, _ in session.features(layer) if f != fid]
        flat = [LineString([c[:2] for c in part.coords])
                for part in getattr(geometry, "geoms", [geometry])]
        for line in flat:
            problems += edit_checks.check_new_breakline(line, others)
    if "Polygon" in geometry.geom_type:
        problems += edit_checks.check_new_polygon(geometry).problems
    if project is not None and not problems:
        problems += edit_checks.validate_edit(layer, geometry, attributes, project, footprints)
    return problems


# -- the tools ------------------------------------------------------------------------------------
class _EditTool(MapTool):
    """What the vertex and delete tools share: the session, the layer, messages."""

    #: A sentence for the operator (the main window shows it in the status/message bar).
    message = pyqtSignal(str)

    def __init__(self, view: Any, session: Any, layer: str,
                 parent: Optional[QtCore.QObject] = None) -> None:
        super().__init__(parent)
        self.view = view
        self.session = session
        self.layer = layer
        self.last_message = ""

    def say(self, text: str) -> None:
        self.last_message = text
        self.message.emit(text)

    def state(self) -> Optional[ViewState]:
        return self.view.view_state() if self.view is not None else None

    def features(self) -> List[Tuple[int, Any, Dict[str, Any]]]:
        return self.session.features(self.layer)

    def refresh_layer(self) -> None:
        """Draw the edited layer again (a callable source is read again)."""
        if self.view is None:
            return
        drawn = self.view.layer_by_kind(f"edit:{self.layer}")
        if drawn is not None and hasattr(drawn, "reload"):
            drawn.reload()


class VertexTool(_EditTool):
    """Move (drag) and delete (right click, Delete key) vertices of one edit layer.

    Parameters
    ----------
    view : MapView
    session : EditSession
    layer : str
        The edit layer.
    surface : str, optional
        The DSM/DTM heights of moved vertices come from (layers with heights); None: kept.
    project : Project, optional
        For :func:`validate_edit` (block area, plausible heights); None: only the geometric
        checks.
    """

    def __init__(self, view: Any, session: Any, layer: str, surface: Optional[str] = None,
                 project: Any = None, parent: Optional[QtCore.QObject] = None) -> None:
        super().__init__(view, session, layer, parent)
        self.surface = surface
        self.project = project
        self._footprints: Any = None
        self._drag: Optional[Tuple[int, Key, Coord]] = None
        self._drag_to: Optional[Tuple[float, float]] = None
        self._hover: Optional[Tuple[int, Key, Coord]] = None

    def deactivate(self) -> None:
        self._drag = self._drag_to = self._hover = None
        self.changed.emit()

    def _pick(self, x: float, y: float) -> Optional[Tuple[int, Key, Coord]]:
        state = self.state()
        if state is None:
            return None
        at = state.to_pixel(x, y)
        return nearest_vertex(self.features(), state, at.x(), at.y())

    def press(self, event: QtGui.QMouseEvent, x: float, y: float) -> bool:
        hit = self._pick(x, y)
        if hit is None:
            return False
        if event.button() == QtCore.Qt.RightButton:
            self.delete_vertex(hit[0], hit[1])
            return True
        if event.button() == QtCore.Qt.LeftButton:
            self._drag, self._drag_to = hit, (x, y)
            self.changed.emit()
            return True
        return False

    def move(self, event: QtGui.QMouseEvent, x: float, y: float) -> bool:
        if self._drag is not None:
            self._drag_to = (x, y)
            self.changed.emit()
            return True
        hover = self._pick(x, y)
        if (hover and hover[:2]) != (self._hover and self._hover[:2]):
            self._hover = hover
            self.changed.emit()
        return False

    def release(self, event: QtGui.QMouseEvent, x: float, y: float) -> bool:
        if self._drag is None or event.button() != QtCore.Qt.LeftButton:
            return False
        fid, key, _ = self._drag
        self._drag = self._drag_to = None
        self.move_vertex(fid, key, x, y)
        self.changed.emit()
        return True

    def key_press(self, event: QtGui.QKeyEvent) -> bool:
        if event.key() == QtCore.Qt.Key_Escape and self._drag is not None:
            self._drag = self._drag_to = None
            self.changed.emit()
            return True
        if event.key() in (QtCore.Qt.Key_Delete, QtCore.Qt.Key_Backspace) and self._hover:
            self.delete_vertex(self._hover[0], self._hover[1])
            return True
        return False

    # -- the edits ---------------------------------------------------------------------------
    def _height_at(self, x: float, y: float) -> Tuple[Optional[float], str]:
        """The surface height at (x, y), or None and why (no surface: None, no reason)."""
        if not self.surface:
            return None, ""
        try:
            answer = edit_tools.sample_height(self.surface, x, y, crs=self.session.crs or None)
        except PhotodemError as exc:
            return None, str(exc)
        return answer.z, answer.reason or ""

    def move_vertex(self, fid: int, key: Key, x: float, y: float) -> bool:
        """Move one vertex to (x, y) as one undo command; False (with a message) if refused."""
        item = self.session.feature(self.layer, fid)
        if item is None:
            return False
        geometry, attrs = item
        z = None
        if self.layer in Z_LAYERS + ("start_points",) and self.surface:
            z, reason = self._height_at(x, y)
            if z is None:
                self.say(tr("The vertex was not moved: {0}").format(reason))
                return False
        new = moved(geometry, key, x, y, z if self.layer in Z_LAYERS else None)
        if self.layer == "start_points" and z is not None:
            attrs = {**attrs, "height": z}
        return self._commit(fid, new, attrs, tr("Move vertex"))

    def delete_vertex(self, fid: int, key: Key) -> bool:
        """Remove one vertex as one undo command; False (with a message) if refused."""
        item = self.session.feature(self.layer, fid)
        if item is None:
            return False
        try:
            new = without_vertex(item[0], key)
        except InputError as exc:
            self.say(tr("The vertex was not deleted: {0}").format(exc))
            return False
        self._hover = None
        return self._commit(fid, new, item[1], tr("Delete vertex"))

    def _commit(self, fid: int, geometry: Any, attrs: Dict[str, Any], text: str) -> bool:
        if self.project is not None and self._footprints is None:
            self._footprints = block_footprints(self.project)
        problems = edit_problems(self.session, self.layer, fid, geometry, attrs, self.project,
                                 self._footprints)
        bad = edit_checks.errors(problems)
        if bad:
            self.say(tr("Edit refused, nothing changed: {0}").format(
                " ".join(p.message for p in bad)))
            return False
        try:
            self.session.replace(self.layer, fid, geometry, attrs, text=text)
        except InputError as exc:
            self.say(str(exc))
            return False
        self.say(" ".join(p.message for p in problems))
        self.refresh_layer()
        return True

    # -- drawing -----------------------------------------------------------------------------
    def paint(self, painter: QtGui.QPainter, view: ViewState) -> None:
        """Vertex handles of the layer, the hovered one larger, the dragged edges dashed."""
        painter.save()
        painter.setRenderHint(QtGui.QPainter.Antialiasing)
        painter.setPen(QtGui.QPen(QtGui.QColor(120, 0, 0), 1))
        painter.setBrush(QtGui.QColor(255, 255, 255, 220))
        for _, geometry, _ in self.features():
            for _, c in vertices(geometry):
                at = view.to_pixel(c[0], c[1])
                painter.drawRect(QtCore.QRectF(at.x() - 3, at.y() - 3, 6, 6))
        if self._hover is not None:
            at = view.to_pixel(self._hover[2][0], self._hover[2][1])
            painter.setBrush(QtGui.QColor(255, 200, 0))
            painter.drawRect(QtCore.QRectF(at.x() - 5, at.y() - 5, 10, 10))
        if self._drag is not None and self._drag_to is not None:
            self._paint_drag(painter, view)
        painter.restore()

    def _paint_drag(self, painter: QtGui.QPainter, view: ViewState) -> None:
        fid, key, _ = self._drag
        item = self.session.feature(self.layer, fid)
        if item is None:
            return
        preview = moved(item[0], key, *self._drag_to)
        pen = QtGui.QPen(QtGui.QColor(220, 0, 0), 2, QtCore.Qt.DashLine)
        painter.setPen(pen)
        painter.setBrush(QtCore.Qt.NoBrush)
        p, r, _ = key
        ring = vertex_rings(preview)[p][r]
        closed = "Polygon" in preview.geom_type
        points = [view.to_pixel(c[0], c[1]) for c in ring + (ring[:1] if closed else [])]
        if len(points) > 1:
            painter.drawPolyline(QtGui.QPolygonF(points))
        at = view.to_pixel(*self._drag_to)
        painter.setBrush(QtGui.QColor(220, 0, 0))
        painter.drawEllipse(at, 4, 4)


class DeleteFeatureTool(_EditTool):
    """A left click removes the feature of the layer under the cursor (one undo command)."""

    def press(self, event: QtGui.QMouseEvent, x: float, y: float) -> bool:
        if event.button() != QtCore.Qt.LeftButton:
            return False
        fid = self.feature_at(x, y)
        if fid is None:
            return False
        try:
            self.session.remove(self.layer, fid)
        except InputError as exc:
            self.say(str(exc))
            return True
        self.refresh_layer()
        return True

    def feature_at(self, x: float, y: float) -> Optional[int]:
        """The fid of the feature at the map point (inside a polygon, or within
        :data:`PICK_PIXELS` of a point or line; the nearest wins), or None."""
        state = self.state()
        if state is None:
            return None
        tolerance = PICK_PIXELS * state.map_units_per_pixel
        point = Point(x, y)
        best, best_d = None, tolerance
        for fid, geometry, _ in self.features():
            inside = "Polygon" in geometry.geom_type and geometry.covers(point)
            d = 0.0 if inside else geometry.distance(point)
            if d <= best_d:
                best, best_d = fid, d
        return best

    def cursor(self) -> QtGui.QCursor:
        return QtGui.QCursor(QtCore.Qt.PointingHandCursor)


# -- re-drape ---------------------------------------------------------------------------------
#: Heights closer than this (m) are the same (a re-drape does not count rounding noise).
SAME_HEIGHT = 1e-6


def _same_height(old: Any, new: Optional[float]) -> bool:
    try:
        return abs(float(old) - float(new)) <= SAME_HEIGHT
    except (TypeError, ValueError):
        return False


def redrape(session: Any, surface_path: str,
            layers: Sequence[str] = REDRAPE_LAYERS) -> int:
    """New heights of every feature of ``layers`` from the surface, as ONE undo command.

    Breaklines, ground and check points get new Z, start points a new ``height``
    (:func:`~photodem.algorithms.project.edit_tools.redrape_feature`, as in QGIS). Features
    whose heights are unchanged are left out of the command.

    Returns
    -------
    int
        The number of features changed (0: nothing pushed).

    Raises
    ------
    InputError
        A read-only session, a layer without heights, a surface that cannot be read, or a
        vertex without a height on it (naming the feature); nothing is changed then.
    """
    if session.read_only:
        raise InputError(session.problem)
    changes = []
    for layer in layers:
        for fid, geometry, attrs in session.features(layer):
            answer = edit_tools.redrape_feature(surface_path, layer, geometry,
                                                crs=session.crs or None)
            if answer.reason:
                raise InputError(tr("Nothing re-draped: {0} {1}: {2}").format(
                    layer, fid, answer.reason))
            if answer.geometry is None:
                if not _same_height(attrs.get("height"), answer.height):
                    changes.append((layer, fid, geometry, {**attrs, "height": answer.height}))
            elif not all(_same_height(a[2] if len(a) > 2 else None, b[2])
                         for (_, a), (_, b) in zip(vertices(geometry),
                                                   vertices(answer.geometry))):
                changes.append((layer, fid, answer.geometry, attrs))
    if not changes:
        return 0
    session.undo_stack.beginMacro(tr("Re-drape {0} features").format(len(changes)))
    try:
        for layer, fid, geometry, attrs in changes:
            session.replace(layer, fid, geometry, attrs, text=tr("Re-drape"))
    finally:
        session.undo_stack.endMacro()
    return len(changes)


__all__ = ["PICK_PIXELS", "DeleteFeatureTool", "VertexTool", "edit_problems", "moved",
           "nearest_vertex", "rebuild", "redrape", "vertex_rings", "vertices", "without_vertex"]
