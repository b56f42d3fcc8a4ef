"""The validation panel: the problems of the current edits, unsaved ones included.

The features are read from the QGIS layers (``getFeatures`` sees the edit buffer, so what the
operator has drawn but not saved is checked too) and checked one by one with the core's
``validate_edit`` — the same rules as when a tool writes an edit — and the breaklines pairwise
with ``check_new_breakline``. This is chosen over validating a temporary copy of ``edits.gpkg``:
no file is written, and each problem keeps its layer and feature id, so a click on it zooms to
the feature.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, List, Optional, Tuple

from qgis.core import QgsCoordinateTransform, QgsProject, QgsRectangle
from qgis.PyQt.QtCore import Qt
from qgis.PyQt.QtWidgets import (
    QAbstractItemView,
    QDockWidget,
    QHeaderView,
    QTableWidget,
    QTableWidgetItem,
)

from ...algorithms.project import edit_checks
from ...algorithms.project.edits import EDIT_LAYERS
from ...algorithms.project.stereo_models import block_footprints
from ..i18n import tr
from .edit_maptools import layer_crs, to_shapely

#: Half the size (m) of the view a click on a problem without a feature extent zooms to.
ZOOM_HALF_SIZE = 10.0


@dataclass
class Found:
    """One problem of one feature: layer, feature id, the core's problem and the feature's
    extent in the project CRS (``None`` when unknown)."""

    layer: str
    fid: Optional[int]
    problem: edit_checks.Problem
    extent: Optional[Tuple[float, float, float, float]] = None


def _features(workspace: Any, name: str, crs: Any) -> List[Tuple[int, Any, dict]]:
    """(fid, shapely geometry in the project CRS, edit fields) of a layer's current features."""
    layer = workspace.edit_layer(name)
    if layer is None:
        return []
    fields = list(EDIT_LAYERS[name][1])
    to_project = QgsCoordinateTransform(layer.crs(), crs, QgsProject.instance())
    out = []
    for feature in layer.getFeatures():
        geometry = feature.geometry()
        if geometry.isNull():
            shape = None
        else:
            geometry.transform(to_project)
            shape = to_shapely(geometry)
        names = feature.fields().names()
        attributes = {k: (feature[k] if k in names else None) for k in fields}
        # QGIS gives NULL as a QVariant; the core wants None
        attributes = {k: (None if v is None or str(v) == "NULL" else v)
                      for k, v in attributes.items()}
        out.append((feature.id(), shape, attributes))
    return out


def collect_problems(workspace: Any) -> List[Found]:
    """Every problem of the workspace's current edits (see the module notes)."""
    project = workspace.project
    crs = layer_crs(str(project.crs))
    footprints = block_footprints(project)
    found: List[Found] = []
    for name in EDIT_LAYERS:
        features = _features(workspace, name, crs)
        for fid, shape, attributes in features:
            extent = shape.bounds if shape is not None and not shape.is_empty else None
            for problem in edit_checks.validate_edit(name, shape, attributes, project,
                                                     footprints):
                found.append(Found(name, fid, problem, extent))
        if name == "breaklines":
            found += _crossings(features)
    return found


def _crossings(features: List[Tuple[int, Any, dict]]) -> List[Found]:
    """Breaklines crossing one another: each pair once, reported on the later feature."""
    found: List[Found] = []
    lines = [(fid, shape) for fid, shape, _ in features if shape is not None]
    for k, (fid, line) in enumerate(lines):
        others = [other for _, other in lines[:k]]
        for problem in edit_checks.check_new_breakline(line, others):
            text = problem.message.replace("The new breakline", tr("Breakline {0}").format(fid))
            found.append(Found("breaklines", fid,
                               edit_checks.Problem(text, problem.location, problem.severity),
                               line.bounds))
    return found


class ValidationDock(QDockWidget):
    """A dock listing problems (message, severity, layer, feature); a click zooms to one."""

    def __init__(self, iface: Any) -> None:
        super().__init__(tr("PhotoDEM validation"), iface.mainWindow())
        self.setObjectName("photodemValidationDock")
        self.iface = iface
        self.project_crs = ""
        self.table = QTableWidget(0, 4, self)
        self.table.setObjectName("photodemValidationList")
        self.table.setHorizontalHeaderLabels([tr("Problem"), tr("Severity"), tr("Layer"),
                                              tr("Feature")])
        self.table.setEditTriggers(QAbstractItemView.NoEditTriggers)
        self.table.setSelectionBehavior(QAbstractItemView.SelectRows)
        self.table.setWordWrap(True)  # long messages wrap in the stretched first column
        self.table.verticalHeader().setVisible(False)
        header = self.table.horizontalHeader()
        header.setSectionResizeMode(0, QHeaderView.Stretch)
        for column in (1, 2, 3):
            header.setSectionResizeMode(column, QHeaderView.ResizeToContents)
        self.table.itemClicked.connect(self.zoom_to)
        self.setWidget(self.table)
        self.setMinimumWidth(540)
        self.found: List[Found] = []

    def show_problems(self, found: List[Found], project_crs: str) -> None:
        """Fill the list (an "all fine" line when there is nothing)."""
        self.found = list(found)
        self.project_crs = project_crs
        severities = {"error": tr("error"), "warning": tr("warning")}
        self.table.clearContents()
        self.table.setRowCount(max(len(self.found), 1))
        for k, item in enumerate(self.found):
            fid = "" if item.fid is None else str(item.fid)
            if item.fid is not None and item.fid < 0:  # QGIS's id of a feature not yet saved
                fid = tr("unsaved")
            texts = [item.problem.message,
                     severities.get(item.problem.severity, item.problem.severity),
                     item.layer, fid]
            for column, text in enumerate(texts):
                cell = QTableWidgetItem(text)
                cell.setData(Qt.UserRole, k)
                cell.setToolTip(item.problem.message)
                self.table.setItem(k, column, cell)
        if not self.found:
            self.table.setItem(0, 0, QTableWidgetItem(tr("No problems found.")))
        self.table.resizeRowsToContents()
        self.show()
        self.raise_()

    def zoom_to(self, cell: QTableWidgetItem) -> None:
        """Zoom the canvas to the problem's feature, or centre on its location."""
        k = cell.data(Qt.UserRole)
        if k is None:
            return
        item = self.found[int(k)]
        box = item.extent
        if item.problem.location is not None:
            x, y = item.problem.location
            box = (x - ZOOM_HALF_SIZE, y - ZOOM_HALF_SIZE, x + ZOOM_HALF_SIZE, y + ZOOM_HALF_SIZE)
        if box is None:
            return
        canvas = self.iface.mapCanvas()
        rect = QgsRectangle(*box)
        if rect.width() == 0 or rect.height() == 0:
            rect = QgsRectangle(box[0] - ZOOM_HALF_SIZE, box[1] - ZOOM_HALF_SIZE,
                                box[2] + ZOOM_HALF_SIZE, box[3] + ZOOM_HALF_SIZE)
        to_canvas = QgsCoordinateTransform(layer_crs(self.project_crs),
                                           canvas.mapSettings().destinationCrs(),
                                           QgsProject.instance())
        rect = to_canvas.transformBoundingBox(rect)
        rect.scale(1.5)
        canvas.setExtent(rect)
        canvas.refresh()

    def resizeEvent(self, event: Any) -> None:
        """Re-wrap the messages to the new width."""
        super().resizeEvent(event)
        self.table.resizeRowsToContents()
