"""What the standalone map view draws and how tools talk to it (the contract of issue 21).

The map view (:mod:`.map_view`) keeps an ordered list of :class:`MapLayer` objects and asks
each visible one to paint itself into the view's extent; rasters (:mod:`.raster_tiles`) and
vectors (:mod:`.map_vectors`) are subclasses. Editing and QC tools are :class:`MapTool`
objects: the view hands them its mouse and key events with the map coordinates already
computed, and lets them draw rubber bands on top of the layers.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Optional, Tuple

from ..qt import QtCore, QtGui, pyqtSignal

#: (xmin, ymin, xmax, ymax) in map units.
Bounds = Tuple[float, float, float, float]


@dataclass(frozen=True)
class ViewState:
    """One frame of the map view: what is shown and how big.

    Attributes
    ----------
    extent : Bounds
        The map extent of the whole widget (map units of ``crs``).
    width, height : int
        The widget size in device-independent pixels.
    crs : str
        The map CRS as WKT or ``EPSG:n``; empty for a view in pixel coordinates (rasters
        without a CRS).
    """

    extent: Bounds
    width: int
    height: int
    crs: str = ""

    @property
    def map_units_per_pixel(self) -> float:
        """Map units covered by one pixel (square pixels)."""
        return (self.extent[2] - self.extent[0]) / max(self.width, 1)

    def to_pixel(self, x: float, y: float) -> QtCore.QPointF:
        """Map coordinates → widget pixel (y grows downwards)."""
        xmin, ymin, xmax, ymax = self.extent
        return QtCore.QPointF((x - xmin) / (xmax - xmin) * self.width,
                              (ymax - y) / (ymax - ymin) * self.height)

    def to_map(self, px: float, py: float) -> Tuple[float, float]:
        """Widget pixel → map coordinates (the pixel's centre when ``px``/``py`` are ints + .5)."""
        xmin, ymin, xmax, ymax = self.extent
        return (xmin + px / self.width * (xmax - xmin),
                ymax - py / self.height * (ymax - ymin))


class MapLayer(QtCore.QObject):
    """A layer of the map view.

    Subclasses implement :meth:`paint` and :meth:`bounds`; they emit :attr:`changed` whenever
    they need to be drawn again (new tiles arrived, features edited, style changed).

    Attributes
    ----------
    name : str
        Shown in the layer list.
    kind : str
        What it is: ``dsm``, ``dtm``, ``difference``, ``ortho``, ``mosaic``, ``image``,
        ``edit:<layer>``, ``footprints``, ``stereo_models``, ``seamlines``, ``control_points``,
        ``vector``.
    path : Path or None
        The file behind it, when there is one.
    """

    changed = pyqtSignal()

    def __init__(self, name: str, kind: str, path: Optional[Path] = None,
                 parent: Optional[QtCore.QObject] = None) -> None:
        super().__init__(parent)
        self.name = name
        self.kind = kind
        self.path = Path(path) if path is not None else None
        self._visible = True
        self._opacity = 1.0

    @property
    def visible(self) -> bool:
        return self._visible

    @visible.setter
    def visible(self, value: bool) -> None:
        if bool(value) != self._visible:
            self._visible = bool(value)
            self.changed.emit()

    @property
    def opacity(self) -> float:
        """0 (transparent) … 1 (opaque)."""
        return self._opacity

    @opacity.setter
    def opacity(self, value: float) -> None:
        value = min(max(float(value), 0.0), 1.0)
        if value != self._opacity:
            self._opacity = value
            self.changed.emit()

    def bounds(self) -> Optional[Bounds]:
        """The layer's extent in map coordinates, or None when it is empty."""
        raise NotImplementedError

    def paint(self, painter: QtGui.QPainter, view: ViewState) -> None:
        """Draw the layer for ``view``; must return quickly (slow work goes to a thread and
        ends with :attr:`changed`)."""
        raise NotImplementedError

    def value_at(self, x: float, y: float) -> Optional[str]:
        """Text for the status bar at the map point (a raster value, a feature's name), or
        None."""
        return None

    def close(self) -> None:
        """Release files and threads (the layer was removed)."""


class MapTool(QtCore.QObject):
    """An interactive tool of the map view (pan, capture, vertex edit, QC area …).

    The view calls the handlers with the event and its map coordinates; a handler returns True
    when it used the event (else the view pans/zooms as usual). :meth:`paint` draws the
    tool's rubber band over the layers. Emit :attr:`changed` to be drawn again.
    """

    changed = pyqtSignal()

    def __init__(self, parent: Optional[QtCore.QObject] = None) -> None:
        super().__init__(parent)
        self.view: Any = None  # the MapView, set by MapView.set_tool

    def activate(self) -> None:
        """The tool became the view's tool."""

    def deactivate(self) -> None:
        """Another tool replaced this one: drop unfinished work."""

    def press(self, event: QtGui.QMouseEvent, x: float, y: float) -> bool:
        return False

    def move(self, event: QtGui.QMouseEvent, x: float, y: float) -> bool:
        return False

    def release(self, event: QtGui.QMouseEvent, x: float, y: float) -> bool:
        return False

    def double_click(self, event: QtGui.QMouseEvent, x: float, y: float) -> bool:
        return False

    def key_press(self, event: QtGui.QKeyEvent) -> bool:
        return False

    def paint(self, painter: QtGui.QPainter, view: ViewState) -> None:
        """Draw the rubber band (widget pixels: use ``view.to_pixel``)."""

    def cursor(self) -> QtGui.QCursor:
        return QtGui.QCursor(QtCore.Qt.CrossCursor)
