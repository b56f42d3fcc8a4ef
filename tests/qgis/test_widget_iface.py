"""The real-widget interface of the GUI tests: a click on the canvas viewport reaches a map tool
at the map coordinates it was aimed at (the basis of every map-tool test)."""

from __future__ import annotations

import pytest

pytestmark = pytest.mark.qgis


def test_click_on_canvas_reaches_a_map_tool(qgis_iface):
    from qgis.core import QgsCoordinateReferenceSystem, QgsPointXY, QgsRectangle
    from qgis.gui import QgsMapToolEmitPoint
    from qgis.PyQt.QtCore import QPoint, Qt
    from qgis.PyQt.QtTest import QTest

    canvas = qgis_iface.mapCanvas()
    canvas.setDestinationCrs(QgsCoordinateReferenceSystem("EPSG:25832"))
    canvas.setExtent(QgsRectangle(0, 0, 1000, 1000))
    clicked = []
    tool = QgsMapToolEmitPoint(canvas)
    # copy: the signal's point is a temporary that dies with the event
    tool.canvasClicked.connect(lambda point, _button: clicked.append((point.x(), point.y())))
    canvas.setMapTool(tool)
    pixel = canvas.getCoordinateTransform().transform(QgsPointXY(500, 300))
    QTest.mouseClick(canvas.viewport(), Qt.LeftButton, Qt.NoModifier,
                     QPoint(round(pixel.x()), round(pixel.y())))
    assert len(clicked) == 1
    # one pixel of the canvas is the precision of a click
    assert abs(clicked[0][0] - 500) <= canvas.mapUnitsPerPixel()
    assert abs(clicked[0][1] - 300) <= canvas.mapUnitsPerPixel()
