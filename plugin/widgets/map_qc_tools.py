"""The quality panel's tools on the standalone map: a drawn polygon → the panel's area
statistics, a drawn line → its profile, a click → identify.

They hand the panel (:class:`~.qc_panel.QcPanel`) exactly what the QGIS dock hands it
(:mod:`photodem.plugin.qgis.qc_dock`): ``set_area(wkt, label)``, ``set_line(coords)``,
``show_identify(x, y)``; the map CRS is the project's (the panel's rasters are read in it).
The drawn shape stays on the map until the next one.
"""

from __future__ import annotations

from typing import Any, List, Optional

import numpy as np
from shapely.geometry import Polygon

from ..i18n import tr
from ..qt import QtCore, QtGui
from .map_edit_tools import XY, CaptureTool, _pen
from .map_layer import MapTool, ViewState

#: Colour of the drawn QC shapes (as the QGIS dock's rubber bands).
QC_COLOUR = QtGui.QColor(0, 160, 255)


def area_label(polygon: Any) -> str:
    """The panel's label of a drawn polygon (the QGIS dock's)."""
    return tr("drawn polygon ({0:.0f} m²)").format(polygon.area)


class _QcCapture(CaptureTool):
    """A capture tool that keeps its last shape on the map."""

    def __init__(self, view: Any, panel: Any, shape: str) -> None:
        super().__init__(view, shape)
        self.panel = panel
        self.last: List[XY] = []

    def paint(self, painter: QtGui.QPainter, view: ViewState) -> None:
        if self.last and not self.vertices:
            points = QtGui.QPolygonF([view.to_pixel(x, y) for x, y in self.last])
            painter.setPen(_pen(QC_COLOUR, 2))
            painter.setBrush(QtCore.Qt.NoBrush)
            (painter.drawPolygon if self.shape == "polygon" else painter.drawPolyline)(points)
        super().paint(painter, view)


class QcAreaTool(_QcCapture):
    """Draw a polygon (right click or Enter ends it) → the panel's area statistics."""

    def __init__(self, view: Any, panel: Any) -> None:
        super().__init__(view, panel, "polygon")

    def finished(self, coords: List[XY]) -> None:
        polygon = Polygon(coords)
        if not polygon.is_valid:
            polygon = polygon.buffer(0)
        self.last = list(coords)
        self.panel.set_area(polygon.wkt, area_label(polygon))


class QcLineTool(_QcCapture):
    """Draw a profile line (right click or Enter ends it) → the panel's profile."""

    def __init__(self, view: Any, panel: Any) -> None:
        super().__init__(view, panel, "line")

    def finished(self, coords: List[XY]) -> None:
        self.last = list(coords)
        self.panel.set_line(np.asarray(coords, dtype=float))


class QcIdentifyTool(MapTool):
    """A left click → the panel's identify (every surface's height there)."""

    def __init__(self, view: Any, panel: Any) -> None:
        super().__init__(view)
        self.panel = panel
        self.point: Optional[XY] = None

    def press(self, event: QtGui.QMouseEvent, x: float, y: float) -> bool:
        return event.button() == QtCore.Qt.LeftButton

    def release(self, event: QtGui.QMouseEvent, x: float, y: float) -> bool:
        if event.button() != QtCore.Qt.LeftButton:
            return False
        self.point = (x, y)
        self.changed.emit()
        self.panel.show_identify(x, y)
        return True

    def paint(self, painter: QtGui.QPainter, view: ViewState) -> None:
        if self.point is not None:
            p = view.to_pixel(*self.point)
            painter.setPen(_pen(QC_COLOUR, 2))
            painter.drawEllipse(p, 5.0, 5.0)
