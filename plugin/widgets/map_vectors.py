"""Vector layers of the standalone map: files (GeoPackage, Shapefile…) or features in memory.

A :class:`VectorLayer` draws points, lines and polygons with a :class:`~.map_styles.Style`
read from our QML files, so edits, footprints, stereo models and seamlines look as in QGIS.
The features come from a file (read with the core reader :func:`read_features`, reprojected
to the map CRS) or from a callable — the edit session's features in memory — that is asked
again by :meth:`VectorLayer.reload`.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

from shapely.geometry import Point, shape
from shapely.geometry.base import BaseGeometry

from ...algorithms.errors import InputError
from ..qt import QtCore, QtGui
from .map_layer import Bounds, MapLayer, ViewState
from .map_styles import Style, Symbol, style_for_kind

LOG = logging.getLogger(__name__)

#: (fid, geometry, attributes): one feature as the layer keeps it.
Feature = Tuple[Any, BaseGeometry, Dict[str, Any]]
Source = Union[str, Path, Callable[[], Sequence[Tuple[Any, Any, Dict[str, Any]]]]]
#: Fields whose value names a feature (status bar, identify), in this order.
LABEL_FIELDS = ("name", "id", "image", "note", "kind", "action")
#: How near (pixels) the cursor must be to a feature for :meth:`VectorLayer.value_at`.
PICK_PIXELS = 5.0


def feature_label(fid: Any, attributes: Dict[str, Any]) -> str:
    """A feature's name for the status bar: the first non-empty :data:`LABEL_FIELDS` value,
    else ``#fid``."""
    for key in LABEL_FIELDS:
        value = attributes.get(key)
        if value not in (None, ""):
            return str(value)
    return f"#{fid}"


def read_file_features(path: Path, layer: Optional[str], map_crs: str) -> Tuple[List[Feature],
                                                                               bool]:
    """The features of ``layer`` of ``path`` in ``map_crs`` and whether the file has a CRS."""
    # lazy: rasterio's CRS and the core reader load with the first file layer
    from rasterio.crs import CRS

    from ...algorithms.project.vector_io import read_features, to_crs

    if not path.is_file():
        raise InputError(f"The vector file '{path}' does not exist.")
    found = read_features(path, [layer] if layer else None, what="vector file")
    target = CRS.from_user_input(map_crs) if map_crs else None
    features: List[Feature] = []
    has_crs = False
    for feat in found:
        has_crs = has_crs or feat.crs is not None
        geom = to_crs(feat.geometry, feat.crs, target)
        features.append((feat.fid, shape(geom), feat.properties))
    return features, has_crs or not found


class VectorLayer(MapLayer):
    """A vector layer drawn with our QML style of its kind.

    Parameters
    ----------
    source : path or callable
        A vector file (``layer``: its layer in a GeoPackage) or a callable returning
        ``[(fid, shapely geometry, attributes), …]`` in the map CRS.
    kind : str
        ``edit:<layer>``, ``footprints``, ``stereo_models``, ``seamlines``, ``vector`` …
    name : str
        Shown in the layer list (default: the layer or file name, or the kind).
    map_crs : str
        The view's CRS; file features are reprojected to it.
    style : Style, optional
        Default: :func:`~.map_styles.style_for_kind` of ``kind``.
    """

    def __init__(self, source: Source, kind: str, name: str = "", layer: Optional[str] = None,
                 map_crs: str = "", style: Optional[Style] = None,
                 parent: Optional[QtCore.QObject] = None) -> None:
        path = None if callable(source) else Path(source)
        default = layer or (path.stem if path is not None else kind.split(":")[-1])
        super().__init__(name or default, kind, path, parent)
        self.source = source
        self.layer_name = layer
        self.map_crs = map_crs
        self.style = style if style is not None else style_for_kind(kind)
        self.has_crs = True
        self._features: List[Feature] = []
        self._bounds: List[Tuple[float, float, float, float]] = []
        self._mupp = 1.0  # map units per pixel of the last drawing (for value_at)
        self._load()

    # -- features --------------------------------------------------------------------------------
    def _load(self) -> None:
        if callable(self.source):
            features = [(fid, geom if isinstance(geom, BaseGeometry) else shape(geom),
                         dict(attrs or {})) for fid, geom, attrs in self.source()]
        else:
            features, self.has_crs = read_file_features(Path(self.source), self.layer_name,
                                                        self.map_crs)
        self._features = [f for f in features if f[1] is not None and not f[1].is_empty]
        self._bounds = [f[1].bounds for f in self._features]

    def reload(self) -> None:
        """Read the source again (after edits) and draw again."""
        try:
            self._load()
        except Exception:  # a vanished file: keep what was shown, say why in the log
            LOG.exception("reloading %s", self.name)
        self.changed.emit()

    def features(self) -> List[Feature]:
        """The features as drawn: (fid, geometry in map CRS, attributes)."""
        return list(self._features)

    def bounds(self) -> Optional[Bounds]:
        if not self._bounds:
            return None
        return (min(b[0] for b in self._bounds), min(b[1] for b in self._bounds),
                max(b[2] for b in self._bounds), max(b[3] for b in self._bounds))

    def feature_at(self, x: float, y: float, tolerance: float) -> Optional[Feature]:
        """The feature at the map point, within ``tolerance`` map units (a polygon also when
        the point is inside); the one drawn last (on top) wins, then the nearest."""
        point = Point(x, y)
        best: Optional[Feature] = None
        best_distance = float("inf")
        for feature, (x0, y0, x1, y1) in zip(reversed(self._features), reversed(self._bounds)):
            if x < x0 - tolerance or x > x1 + tolerance or y < y0 - tolerance \
                    or y > y1 + tolerance:
                continue
            geom = feature[1]
            inside = geom.geom_type.endswith("Polygon") and geom.contains(point)
            distance = 0.0 if inside else geom.distance(point)
            if distance <= tolerance and distance < best_distance:
                best, best_distance = feature, distance
        return best

    def value_at(self, x: float, y: float) -> Optional[str]:
        """The label of the feature within 5 pixels of the point (at the last drawn scale)."""
        found = self.feature_at(x, y, PICK_PIXELS * self._mupp)
        return None if found is None else feature_label(found[0], found[2])

    # -- drawing ---------------------------------------------------------------------------------
    def paint(self, painter: QtGui.QPainter, view: ViewState) -> None:
        self._mupp = view.map_units_per_pixel
        xmin, ymin, xmax, ymax = view.extent
        if xmax <= xmin or ymax <= ymin:
            return
        sx = view.width / (xmax - xmin)
        sy = view.height / (ymax - ymin)
        to_px = QtGui.QTransform(sx, 0.0, 0.0, -sy, -xmin * sx, ymax * sy)
        labels: List[Tuple[QtCore.QPointF, str]] = []
        for (_fid, geom, attrs), (x0, y0, x1, y1) in zip(self._features, self._bounds):
            if x1 < xmin or x0 > xmax or y1 < ymin or y0 > ymax:
                continue
            symbol = self.style.symbol_for(attrs)
            self._draw_geometry(painter, geom, symbol, to_px)
            if self.style.label_field and attrs.get(self.style.label_field) not in (None, ""):
                anchor = geom.representative_point() if geom.geom_type.endswith("Polygon") \
                    else geom.centroid if geom.geom_type != "Point" else geom
                labels.append((to_px.map(QtCore.QPointF(anchor.x, anchor.y)),
                               _label_text(attrs.get(self.style.label_field))))
        self._draw_labels(painter, labels)

    def _draw_geometry(self, painter: QtGui.QPainter, geom: BaseGeometry, symbol: Symbol,
                       to_px: QtGui.QTransform) -> None:
        kind = geom.geom_type
        if kind.startswith("Multi") or kind == "GeometryCollection":
            for part in geom.geoms:
                self._draw_geometry(painter, part, symbol, to_px)
            return
        painter.setPen(symbol.qpen())
        if kind == "Point":
            draw_marker(painter, to_px.map(QtCore.QPointF(geom.x, geom.y)), symbol)
        elif kind in ("LineString", "LinearRing"):
            painter.setBrush(QtCore.Qt.NoBrush)
            painter.drawPolyline(to_px.map(_polygon_f(geom.coords)))
        elif kind == "Polygon":
            path = QtGui.QPainterPath()
            path.setFillRule(QtCore.Qt.OddEvenFill)
            for ring in (geom.exterior, *geom.interiors):
                path.addPolygon(_polygon_f(ring.coords))
                path.closeSubpath()
            painter.setBrush(symbol.qbrush())
            painter.drawPath(to_px.map(path))

    def _draw_labels(self, painter: QtGui.QPainter,
                     labels: List[Tuple[QtCore.QPointF, str]]) -> None:
        if not labels:
            return
        font = painter.font()
        font.setPointSizeF(self.style.label_size * 1.2)
        painter.setFont(font)
        painter.setPen(QtGui.QColor(*self.style.label_colour))
        metrics = QtGui.QFontMetricsF(font)
        for point, text in labels:
            width = metrics.horizontalAdvance(text)
            painter.drawText(QtCore.QPointF(point.x() - width / 2, point.y() - 6), text)


def _label_text(value: Any) -> str:
    return f"{value:.2f}" if isinstance(value, float) else str(value)


def _polygon_f(coords: Any) -> QtGui.QPolygonF:
    return QtGui.QPolygonF([QtCore.QPointF(c[0], c[1]) for c in coords])


def draw_marker(painter: QtGui.QPainter, at: QtCore.QPointF, symbol: Symbol) -> None:
    """A QGIS simple marker (circle, square, triangle, diamond, cross, cross2, star…) at the
    pixel ``at``."""
    half = symbol.marker_size / 2.0
    x, y = at.x(), at.y()
    painter.setBrush(QtGui.QColor(*symbol.marker_fill))
    name = symbol.marker
    if name in ("cross", "cross2", "x", "line"):
        pen = QtGui.QPen(QtGui.QColor(*symbol.marker_fill), max(symbol.pen_width, 1.5))
        pen.setCosmetic(True)
        painter.setPen(pen)
        if name in ("cross2", "x"):
            painter.drawLine(QtCore.QPointF(x - half, y - half), QtCore.QPointF(x + half, y + half))
            painter.drawLine(QtCore.QPointF(x - half, y + half), QtCore.QPointF(x + half, y - half))
        else:
            painter.drawLine(QtCore.QPointF(x - half, y), QtCore.QPointF(x + half, y))
            painter.drawLine(QtCore.QPointF(x, y - half), QtCore.QPointF(x, y + half))
        return
    shapes = {
        "square": [(-1, -1), (1, -1), (1, 1), (-1, 1)],
        "diamond": [(0, -1), (1, 0), (0, 1), (-1, 0)],
        "triangle": [(0, -1), (1, 0.8), (-1, 0.8)],
        "equilateral_triangle": [(0, -1), (0.87, 0.5), (-0.87, 0.5)],
    }
    if name in shapes:
        painter.drawPolygon(QtGui.QPolygonF([QtCore.QPointF(x + dx * half, y + dy * half)
                                             for dx, dy in shapes[name]]))
    else:  # circle and the rest
        painter.drawEllipse(at, half, half)


__all__ = ["LABEL_FIELDS", "VectorLayer", "draw_marker", "feature_label", "read_file_features"]
