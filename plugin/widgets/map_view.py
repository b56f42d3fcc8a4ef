"""The standalone tool's map: a widget that draws :class:`~.map_layer.MapLayer` objects.

The view keeps a centre and a size of one pixel in map units, so pixels stay square whatever the
widget's shape. Layers paint into a cached pixmap that is redrawn only when a layer changes or
the extent moves; the active :class:`~.map_layer.MapTool` draws its rubber band over that pixmap
on every repaint, so a rubber band following the mouse costs no layer drawing.

A view either has a CRS (map units, usually metres) or is in pixel coordinates (``crs ""``) for
a raster without georeferencing; the two never mix (:meth:`MapView.add_layer` refuses).
"""

from __future__ import annotations

import contextlib
import logging
import math
from pathlib import Path
from typing import Callable, List, Optional, Tuple, Union

from ...algorithms.errors import InputError
from ..i18n import tr
from ..qt import QtCore, QtGui, QtWidgets, pyqtSignal
from .map_layer import Bounds, MapLayer, MapTool, ViewState

LOG = logging.getLogger(__name__)

#: Zoom factor of one wheel notch (120 eighths of a degree) and of the + / − keys.
WHEEL_STEP = 1.25
#: Screen resolution assumed for the scale 1:n (QGIS's default too).
SCREEN_DPI = 96.0
#: Length the scale bar aims at, in pixels.
SCALE_BAR_PX = 110


class MixedCoordinatesError(InputError):
    """A layer in pixel coordinates and one in map coordinates cannot share the view."""


def nice_length(length: float) -> float:
    """The largest of 1, 2, 5 × 10ⁿ not above ``length`` (> 0) — a scale bar's length."""
    if length <= 0 or not math.isfinite(length):
        return 0.0
    power = 10.0 ** math.floor(math.log10(length))
    for step in (5.0, 2.0, 1.0):
        if step * power <= length:
            return step * power
    return power


def length_text(length: float, pixel_units: bool = False) -> str:
    """``length`` in map units as the scale bar writes it (m below 1 km, else km; px)."""
    if pixel_units:
        return f"{length:g} px"
    if length >= 1000:
        return f"{length / 1000:g} km"
    return f"{length:g} m"


def union_bounds(bounds: List[Bounds]) -> Optional[Bounds]:
    """The box around all ``bounds`` (None for none)."""
    if not bounds:
        return None
    return (min(b[0] for b in bounds), min(b[1] for b in bounds),
            max(b[2] for b in bounds), max(b[3] for b in bounds))


def _layer_has_crs(layer: MapLayer) -> bool:
    """Whether the layer is georeferenced (rasters and files say so; callables are)."""
    return bool(getattr(layer, "has_crs", True))


def _layer_crs(layer: MapLayer) -> str:
    """The CRS a georeferenced layer is drawn in when the view has none yet (a vector file's
    ``crs``, a raster's ``info.crs``), or ``""``."""
    crs = getattr(layer, "crs", "") or getattr(getattr(layer, "info", None), "crs", "")
    return str(crs or "")


class MapView(QtWidgets.QWidget):
    """The map widget: ordered layers, navigation, tools, scale bar.

    Signals
    -------
    cursor_moved(float, float)
        The map point under the mouse.
    extent_changed()
        The shown extent changed (pan, zoom, resize, CRS).
    layers_changed()
        A layer was added or removed, or the order changed.
    context_menu_requested(float, float, QPoint)
        A right press no tool used: the map point of the pixel and the global position where
        a context menu opens.
    """

    cursor_moved = pyqtSignal(float, float)
    extent_changed = pyqtSignal()
    layers_changed = pyqtSignal()
    context_menu_requested = pyqtSignal(float, float, QtCore.QPoint)

    def __init__(self, parent: Optional[QtWidgets.QWidget] = None) -> None:
        super().__init__(parent)
        self._layers: List[MapLayer] = []
        self._crs = ""
        self._center: Tuple[float, float] = (0.0, 0.0)
        self._mupp = 1.0  # map units per pixel
        self._tool: Optional[MapTool] = None
        self._cache: Optional[QtGui.QPixmap] = None  # the layers, drawn for _cache_state
        self._cache_state: Optional[ViewState] = None
        self._generation = 0  # counts invalidations
        self._drag: Optional[QtCore.QPoint] = None  # last mouse position of a pan drag
        self.setFocusPolicy(QtCore.Qt.StrongFocus)
        self.setMouseTracking(True)
        self.setMinimumSize(120, 90)
        self.setAttribute(QtCore.Qt.WA_OpaquePaintEvent)
        self.setCursor(QtGui.QCursor(QtCore.Qt.OpenHandCursor))

    # -- CRS -------------------------------------------------------------------------------------
    def set_crs(self, crs: str) -> None:
        """Set the map CRS (WKT or ``EPSG:n``; ``""`` = pixel coordinates)."""
        crs = crs or ""
        if crs != self._crs:
            self._crs = crs
            self._invalidate()
            self.extent_changed.emit()

    def crs(self) -> str:
        """The map CRS (``""``: pixel coordinates)."""
        return self._crs

    def is_georeferenced(self) -> bool:
        """True unless the view is in pixel coordinates."""
        return bool(self._crs)

    # -- layers ----------------------------------------------------------------------------------
    def layers(self) -> List[MapLayer]:
        """The layers, top first."""
        return list(self._layers)

    def layer_by_kind(self, kind: str) -> Optional[MapLayer]:
        """The topmost layer of ``kind``, or None."""
        return next((layer for layer in self._layers if layer.kind == kind), None)

    def layer_by_path(self, path: Union[str, Path]) -> Optional[MapLayer]:
        """The layer showing the file ``path`` (compared resolved), or None."""
        wanted = Path(path).resolve()
        for layer in self._layers:
            if layer.path is not None and Path(layer.path).resolve() == wanted:
                return layer
        return None

    def check_layer(self, layer: MapLayer) -> None:
        """Raise :class:`MixedCoordinatesError` when ``layer`` cannot join the view: a raster
        without CRS in a georeferenced view, or a georeferenced layer in a pixel-coordinate
        view."""
        if not self._layers:
            return
        georef = _layer_has_crs(layer)
        if self.is_georeferenced() and not georef:
            raise MixedCoordinatesError(
                tr("'{0}' has no coordinate reference system: it can only be shown alone, in "
                   "pixel coordinates.").format(layer.name))
        if not self.is_georeferenced() and georef:
            raise MixedCoordinatesError(
                tr("The map shows a raster in pixel coordinates; '{0}' is georeferenced and "
                   "cannot be shown with it.").format(layer.name))

    def add_layer(self, layer: MapLayer, index: int = 0) -> MapLayer:
        """Add ``layer`` at ``index`` (0 = on top); raises :class:`InputError` when it would
        mix pixel coordinates with map coordinates (see :meth:`check_layer`)."""
        self.check_layer(layer)
        if not self._layers:  # the first layer decides pixel or map coordinates
            if not _layer_has_crs(layer):
                self.set_crs("")
            elif not self._crs and _layer_crs(layer):
                self.set_crs(_layer_crs(layer))
        index = min(max(int(index), 0), len(self._layers))
        self._layers.insert(index, layer)
        layer.changed.connect(self._on_layer_changed)
        self._invalidate()
        self.layers_changed.emit()
        return layer

    def remove_layer(self, layer: MapLayer) -> None:
        """Take ``layer`` off the map and release it (:meth:`MapLayer.close`)."""
        if layer not in self._layers:
            return
        self._layers.remove(layer)
        with contextlib.suppress(TypeError):  # never connected
            layer.changed.disconnect(self._on_layer_changed)
        layer.close()
        self._invalidate()
        self.layers_changed.emit()

    def move_layer(self, layer: MapLayer, index: int) -> None:
        """Put ``layer`` at ``index`` of :meth:`layers` (0 = top)."""
        if layer not in self._layers:
            return
        self._layers.remove(layer)
        self._layers.insert(min(max(int(index), 0), len(self._layers)), layer)
        self._invalidate()
        self.layers_changed.emit()

    def clear_layers(self) -> None:
        """Remove every layer."""
        for layer in list(self._layers):
            self.remove_layer(layer)

    def add_raster(self, path: Union[str, Path], kind: str = "auto", name: str = "") -> MapLayer:
        """Add the raster ``path`` above the other rasters but under the vectors drawn over
        them (edits stay visible); raises :class:`InputError` for a file GDAL can't open or a
        raster that can't join this view. Without ``name`` the layer names itself ("DSM
        0101_0102" for a product, else the file's stem)."""
        from .raster_tiles import RasterLayer  # lazy: loads GDAL/rasterio and the tile pool

        layer = RasterLayer(path, kind=kind, name=name, map_crs=self._crs, parent=self)
        layers = self.layers()
        index = next((i for i, other in enumerate(layers) if isinstance(other, RasterLayer)),
                     len(layers))
        try:
            return self.add_layer(layer, index)
        except InputError:
            layer.close()
            raise

    def add_vector(self, source: Union[str, Path, Callable[[], list]], kind: str,
                   name: str = "", layer: Optional[str] = None) -> MapLayer:
        """Add a vector layer on top: a file (``layer`` of a GeoPackage) reprojected to the
        map CRS, or a callable returning ``[(fid, shapely geometry, attributes), …]``."""
        from .map_vectors import VectorLayer  # lazy: fiona/shapely load with the first vector

        vector = VectorLayer(source, kind, name=name, layer=layer, map_crs=self._crs,
                             parent=self)
        try:
            return self.add_layer(vector)
        except InputError:
            vector.close()
            raise

    def _on_layer_changed(self) -> None:
        self._invalidate()

    # -- extent ----------------------------------------------------------------------------------
    def view_state(self) -> ViewState:
        """The current frame: extent, size in pixels, CRS."""
        width, height = max(self.width(), 1), max(self.height(), 1)
        cx, cy = self._center
        half_w, half_h = width * self._mupp / 2.0, height * self._mupp / 2.0
        return ViewState((cx - half_w, cy - half_h, cx + half_w, cy + half_h),
                         width, height, self._crs)

    def extent(self) -> Bounds:
        """The map extent of the whole widget."""
        return self.view_state().extent

    def map_units_per_pixel(self) -> float:
        """Size of one (square) pixel in map units."""
        return self._mupp

    def scale(self) -> float:
        """The scale denominator n of 1:n at :data:`SCREEN_DPI` (map units in metres)."""
        return self._mupp * SCREEN_DPI / 0.0254

    def set_extent(self, bounds: Bounds) -> None:
        """Show at least ``bounds`` (xmin, ymin, xmax, ymax), centred, square pixels."""
        xmin, ymin, xmax, ymax = (float(v) for v in bounds)
        if not all(math.isfinite(v) for v in (xmin, ymin, xmax, ymax)):
            return
        width, height = max(self.width(), 1), max(self.height(), 1)
        span = max((xmax - xmin) / width, (ymax - ymin) / height)
        self._set_view(((xmin + xmax) / 2.0, (ymin + ymax) / 2.0),
                       span if span > 0 else self._mupp)

    def _set_view(self, center: Tuple[float, float], mupp: float) -> None:
        if not (mupp > 0 and math.isfinite(mupp)):
            return
        if center == self._center and mupp == self._mupp:
            return
        self._center, self._mupp = center, mupp
        self._invalidate()
        self.extent_changed.emit()

    def full_extent(self) -> Optional[Bounds]:
        """The box around every layer, or None when no layer has an extent."""
        found = []
        for layer in self._layers:
            try:
                bounds = layer.bounds()
            except Exception:  # a layer that can't say must not block zooming
                LOG.exception("bounds of %s", layer.name)
                bounds = None
            if bounds is not None:
                found.append(bounds)
        return union_bounds(found)

    def zoom_full(self) -> None:
        """Show every layer."""
        bounds = self.full_extent()
        if bounds is not None:
            self.set_extent(_padded(bounds))

    def zoom_to_layer(self, layer: MapLayer) -> None:
        """Show the whole of ``layer`` (with a small margin)."""
        bounds = layer.bounds()
        if bounds is not None:
            self.set_extent(_padded(bounds))

    def zoom_by(self, factor: float, anchor_xy: Optional[Tuple[float, float]] = None) -> None:
        """Zoom in by ``factor`` (> 1 in, < 1 out) keeping the map point ``anchor_xy`` (default
        the centre) at the same pixel."""
        if factor <= 0:
            return
        cx, cy = self._center
        ax, ay = anchor_xy if anchor_xy is not None else (cx, cy)
        self._set_view((ax + (cx - ax) / factor, ay + (cy - ay) / factor), self._mupp / factor)

    def pan_by(self, dx_px: float, dy_px: float) -> None:
        """Move the map content by (dx, dy) pixels (right and down positive)."""
        cx, cy = self._center
        self._set_view((cx - dx_px * self._mupp, cy + dy_px * self._mupp), self._mupp)

    # -- tools -----------------------------------------------------------------------------------
    def set_tool(self, tool: Optional[MapTool]) -> None:
        """Make ``tool`` the active tool (None: navigation only); the old one is deactivated."""
        old = self._tool
        if old is tool:
            return
        if old is not None:
            with contextlib.suppress(TypeError):
                old.changed.disconnect(self.update)
            old.deactivate()
            old.view = None
        self._tool = tool
        if tool is not None:
            tool.view = self
            tool.changed.connect(self.update)
            tool.activate()
            self.setCursor(tool.cursor())
        else:
            self.setCursor(QtGui.QCursor(QtCore.Qt.OpenHandCursor))
        self.update()

    def tool(self) -> Optional[MapTool]:
        """The active tool, or None."""
        return self._tool

    # -- drawing ---------------------------------------------------------------------------------
    def refresh(self) -> None:
        """Draw every layer again."""
        self._invalidate()

    def _invalidate(self) -> None:
        self._cache_state = None
        self._generation += 1  # a change during a drawing keeps the cache stale
        self.update()

    def render_layers(self, state: Optional[ViewState] = None) -> QtGui.QImage:
        """The layers drawn for ``state`` (default the current view) into an image."""
        state = state or self.view_state()
        image = QtGui.QImage(state.width, state.height, QtGui.QImage.Format_ARGB32_Premultiplied)
        image.fill(QtGui.QColor("white"))
        painter = QtGui.QPainter(image)
        self._paint_layers(painter, state)
        painter.end()
        return image

    def _paint_layers(self, painter: QtGui.QPainter, state: ViewState) -> None:
        painter.setRenderHint(QtGui.QPainter.Antialiasing, True)
        painter.setRenderHint(QtGui.QPainter.SmoothPixmapTransform, True)
        for layer in reversed(self._layers):  # bottom first
            if not layer.visible or layer.opacity <= 0:
                continue
            painter.save()
            painter.setOpacity(layer.opacity)
            try:
                layer.paint(painter, state)
            except Exception:  # one broken layer must not blank the map
                LOG.exception("painting layer %s", layer.name)
            painter.restore()

    def _render_cache(self) -> None:
        state = self.view_state()
        ratio = self.devicePixelRatioF()
        pixmap = QtGui.QPixmap(int(state.width * ratio), int(state.height * ratio))
        pixmap.setDevicePixelRatio(ratio)
        pixmap.fill(QtGui.QColor("white"))
        generation = self._generation
        painter = QtGui.QPainter(pixmap)
        self._paint_layers(painter, state)
        painter.end()
        self._cache = pixmap
        # a layer that changed while it drew (a file re-read) is drawn again at the next paint
        self._cache_state = state if generation == self._generation else None

    def paintEvent(self, event: QtGui.QPaintEvent) -> None:
        state = self.view_state()
        if self._cache is None or self._cache_state != state:
            self._render_cache()
        painter = QtGui.QPainter(self)
        painter.drawPixmap(0, 0, self._cache)
        if self._tool is not None:
            painter.save()
            painter.setRenderHint(QtGui.QPainter.Antialiasing, True)
            try:
                self._tool.paint(painter, state)
            except Exception:  # a tool's bug must not stop the map from drawing
                LOG.exception("painting tool")
            painter.restore()
        self._paint_decorations(painter, state)
        painter.end()

    def _paint_decorations(self, painter: QtGui.QPainter, state: ViewState) -> None:
        """The scale bar (bottom left), the north arrow and the frame."""
        painter.setRenderHint(QtGui.QPainter.Antialiasing, True)
        length = nice_length(SCALE_BAR_PX * state.map_units_per_pixel)
        if length > 0:  # a half-filled bar and its length to the right of it
            bar_px = length / state.map_units_per_pixel
            x0, y0 = 12.0, state.height - 16.0
            text = length_text(length, pixel_units=not state.crs)
            metrics = painter.fontMetrics()
            width = metrics.horizontalAdvance(text)
            box = QtCore.QRectF(x0 - 6, y0 - metrics.height() / 2 - 4,
                                bar_px + width + 20, metrics.height() + 8)
            painter.fillRect(box, QtGui.QColor(255, 255, 255, 200))
            painter.setPen(QtGui.QPen(QtGui.QColor(30, 30, 30), 1.0))
            painter.setBrush(QtCore.Qt.NoBrush)
            painter.fillRect(QtCore.QRectF(x0, y0 - 2, bar_px / 2.0, 5), QtGui.QColor(30, 30, 30))
            painter.drawRect(QtCore.QRectF(x0, y0 - 2, bar_px, 5))
            painter.drawText(QtCore.QPointF(x0 + bar_px + 6, y0 + metrics.ascent() / 2 - 1), text)
        self._paint_north(painter, state)
        painter.setPen(QtGui.QPen(QtGui.QColor(120, 120, 120), 1.0))
        painter.setBrush(QtCore.Qt.NoBrush)
        painter.drawRect(QtCore.QRectF(0.5, 0.5, state.width - 1, state.height - 1))

    @staticmethod
    def _paint_north(painter: QtGui.QPainter, state: ViewState) -> None:
        """A small arrow: the map is always drawn north up."""
        x, y = state.width - 22.0, 12.0
        arrow = QtGui.QPolygonF([QtCore.QPointF(x, y), QtCore.QPointF(x + 7, y + 20),
                                 QtCore.QPointF(x, y + 15), QtCore.QPointF(x - 7, y + 20)])
        painter.setPen(QtGui.QPen(QtGui.QColor(30, 30, 30), 1.0))
        painter.setBrush(QtGui.QColor(255, 255, 255, 200))
        painter.drawPolygon(arrow)
        painter.drawText(QtCore.QRectF(x - 8, y + 20, 16, 16), QtCore.Qt.AlignCenter, "N")

    def wait_rendered(self, timeout_ms: int = 5000) -> bool:
        """Block (processing events) until every layer has drawn all it needs for the current
        view — raster tiles included; False on timeout. For tests and screenshots."""
        timer = QtCore.QElapsedTimer()
        timer.start()
        app = QtWidgets.QApplication.instance()
        while True:
            self._render_cache()  # asks the layers for the tiles of this view
            left = max(timeout_ms - timer.elapsed(), 0)
            done = all(layer.wait(int(left)) for layer in self._layers
                       if layer.visible and hasattr(layer, "wait"))
            if app is not None:
                app.processEvents()  # deliver the layers' queued `changed`
            if done and self._cache_state is not None:
                self._render_cache()
                self.update()
                return True
            if timer.elapsed() >= timeout_ms:
                return False

    # -- events ----------------------------------------------------------------------------------
    def _map_point(self, pos: QtCore.QPoint) -> Tuple[float, float]:
        """The map point of the pixel centre under ``pos``."""
        return self.view_state().to_map(pos.x() + 0.5, pos.y() + 0.5)

    def mousePressEvent(self, event: QtGui.QMouseEvent) -> None:
        self.setFocus(QtCore.Qt.MouseFocusReason)
        x, y = self._map_point(event.pos())
        if event.button() == QtCore.Qt.MiddleButton:
            self._start_drag(event.pos())
            return
        if self._tool is not None and self._tool.press(event, x, y):
            return
        if event.button() == QtCore.Qt.LeftButton:
            self._start_drag(event.pos())
        elif event.button() == QtCore.Qt.RightButton:  # the tool has no use for it: a menu
            self.context_menu_requested.emit(x, y, self.mapToGlobal(event.pos()))

    def _start_drag(self, pos: QtCore.QPoint) -> None:
        self._drag = QtCore.QPoint(pos)
        self.setCursor(QtGui.QCursor(QtCore.Qt.ClosedHandCursor))

    def mouseMoveEvent(self, event: QtGui.QMouseEvent) -> None:
        x, y = self._map_point(event.pos())
        self.cursor_moved.emit(x, y)
        if self._drag is not None:
            delta = event.pos() - self._drag
            self._drag = QtCore.QPoint(event.pos())
            self.pan_by(delta.x(), delta.y())
            return
        if self._tool is not None:
            self._tool.move(event, x, y)

    def mouseReleaseEvent(self, event: QtGui.QMouseEvent) -> None:
        if self._drag is not None:
            self._drag = None
            tool = self._tool
            self.setCursor(tool.cursor() if tool is not None
                           else QtGui.QCursor(QtCore.Qt.OpenHandCursor))
            return
        if self._tool is not None:
            x, y = self._map_point(event.pos())
            self._tool.release(event, x, y)

    def mouseDoubleClickEvent(self, event: QtGui.QMouseEvent) -> None:
        if self._tool is not None:
            x, y = self._map_point(event.pos())
            if self._tool.double_click(event, x, y):
                return
        super().mouseDoubleClickEvent(event)

    def wheelEvent(self, event: QtGui.QWheelEvent) -> None:
        steps = event.angleDelta().y() / 120.0
        if steps == 0:
            return
        pos = event.position() if hasattr(event, "position") else QtCore.QPointF(event.pos())
        anchor = self.view_state().to_map(pos.x(), pos.y())
        self.zoom_by(WHEEL_STEP ** steps, anchor)
        event.accept()

    def keyPressEvent(self, event: QtGui.QKeyEvent) -> None:
        if self._tool is not None and self._tool.key_press(event):
            return
        key = event.key()
        width, height = self.width() / 4.0, self.height() / 4.0
        pans = {QtCore.Qt.Key_Left: (width, 0), QtCore.Qt.Key_Right: (-width, 0),
                QtCore.Qt.Key_Up: (0, height), QtCore.Qt.Key_Down: (0, -height)}
        if key in pans:
            self.pan_by(*pans[key])
        elif key in (QtCore.Qt.Key_Plus, QtCore.Qt.Key_Equal):
            self.zoom_by(WHEEL_STEP)
        elif key in (QtCore.Qt.Key_Minus, QtCore.Qt.Key_Underscore):
            self.zoom_by(1.0 / WHEEL_STEP)
        else:
            super().keyPressEvent(event)

    def resizeEvent(self, event: QtGui.QResizeEvent) -> None:
        # the centre and the pixel size stay: square pixels, the map does not stretch
        super().resizeEvent(event)
        self._invalidate()
        self.extent_changed.emit()

    def sizeHint(self) -> QtCore.QSize:  # noqa: N802
        return QtCore.QSize(800, 600)


def _padded(bounds: Bounds, margin: float = 0.03) -> Bounds:
    """``bounds`` grown by ``margin`` of its size on each side (a point gets 1 unit)."""
    xmin, ymin, xmax, ymax = bounds
    dx = (xmax - xmin) * margin or 1.0
    dy = (ymax - ymin) * margin or 1.0
    return (xmin - dx, ymin - dy, xmax + dx, ymax + dy)


__all__ = ["MapView", "MixedCoordinatesError", "length_text", "nice_length", "union_bounds"]
