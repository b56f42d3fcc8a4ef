"""The "PhotoDEM editing" toolbar inside real QGIS: each tool driven by mouse events on the canvas
viewport, the features read back from ``edits.gpkg`` with fiona after *Save layer edits*.

The click table is ``tests/edit_clicks.py`` (shared with the standalone tool's tests). Heights
are checked against an analytic plane at the clicked pixel's map point (bilinear on a plane is
exact: 1e-6 m). The workspace is a stand-in with the contract's attributes (part W builds the
real one).
"""

from __future__ import annotations

import hashlib
import math
import shutil
import sys
from pathlib import Path
from typing import Any, Dict, List, Tuple

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests/: the shared click table
from _qgis_helpers import copy_block
from edit_clicks import (
    BOW_TIE,
    CLICKS,
    CROSSING_BREAKLINE,
    EXTENT,
    INTERPOLATED,
    ON_NODATA,
    OUTSIDE_MODELS,
    FakeAsk,
    check_written,
    surface_z,
    write_mosaic_seamlines,
    write_surface,
)

pytestmark = pytest.mark.qgis



# -- the block, the surface and the stand-in workspace ---------------------------------------------
@pytest.fixture(scope="module")
def block(tmp_path_factory, tiny_block, plugin) -> Path:
    """A tiny synthetic block, made once (each test edits a copy)."""
    return copy_block(tiny_block, tmp_path_factory.mktemp("edit-block"), "block")


class StandIn:
    """The contract's workspace: ``project``, ``root``, ``edit_layer``, ``surface_layers``."""

    def __init__(self, root: Path, layers: Dict[str, Any], surfaces: List[Any]) -> None:
        from photodem.algorithms.project.model import Project

        self.root = root
        self.project = Project.load(root)
        self.layers = layers
        self.surfaces = surfaces

    def edit_layer(self, name: str) -> Any:
        return self.layers.get(name)

    def surface_layers(self) -> List[Any]:
        return self.surfaces

    def add_products(self, paths: Any) -> List[Any]:
        return []


@pytest.fixture
def work(tmp_path, block, qgis_iface):
    """A fresh copy of the block, its edit layers and the surface on the map, the toolbar."""
    from qgis.core import (
        QgsCoordinateReferenceSystem,
        QgsProject,
        QgsRasterLayer,
        QgsRectangle,
        QgsVectorLayer,
    )

    from photodem.algorithms.project.edits import EDIT_LAYERS
    from photodem.plugin.qgis.editing_toolbar import EditingToolbar

    root = tmp_path / "block"
    shutil.copytree(block, root)
    gpkg = root / "edits.gpkg"
    layers = {}
    for name in EDIT_LAYERS:
        layer = QgsVectorLayer(f"{gpkg}|layername={name}", name, "ogr")
        assert layer.isValid(), name
        layer.setCustomProperty("photodem/kind", f"edit:{name}")
        layers[name] = layer
    surface = QgsRasterLayer(str(write_surface(tmp_path / "plane_dsm.tif")), "plane DSM")
    assert surface.isValid()
    QgsProject.instance().addMapLayer(surface)
    QgsProject.instance().addMapLayers(list(layers.values()))
    canvas = qgis_iface.mapCanvas()
    canvas.setDestinationCrs(QgsCoordinateReferenceSystem("EPSG:25832"))
    canvas.setExtent(QgsRectangle(*EXTENT))
    canvas.refresh()
    ask = FakeAsk()
    bar = EditingToolbar(qgis_iface, ask=ask)
    workspace = StandIn(root, layers, [surface])
    bar.set_workspace(workspace)
    state = {"root": root, "gpkg": gpkg, "layers": layers, "surface": surface, "bar": bar,
             "ask": ask, "canvas": canvas, "iface": qgis_iface, "workspace": workspace}
    yield state
    done = state.pop("bar")
    if done.toolbar in qgis_iface.toolbars:  # unload deletes it: not the iface's to delete
        qgis_iface.toolbars.remove(done.toolbar)
    done.unload()
    del bar, done
    for layer in layers.values():
        if layer.isEditable():
            layer.rollBack()
    _flush()


def _flush() -> None:
    """Delete what ``deleteLater`` scheduled and collect the cycles now, while the application
    lives (not at interpreter exit)."""
    import gc

    from qgis.PyQt.QtCore import QCoreApplication, QEvent

    QCoreApplication.sendPostedEvents(None, QEvent.DeferredDelete)
    gc.collect()


# -- driving the canvas --------------------------------------------------------------------------
def click(canvas, x: float, y: float, right: bool = False) -> Tuple[float, float]:
    """A mouse click on the viewport at map (x, y); returns the map point of the clicked pixel."""
    from qgis.core import QgsPointXY
    from qgis.PyQt.QtCore import QPoint, Qt
    from qgis.PyQt.QtTest import QTest

    pixel = canvas.getCoordinateTransform().transform(QgsPointXY(x, y))
    point = QPoint(round(pixel.x()), round(pixel.y()))
    QTest.mouseMove(canvas.viewport(), point)
    QTest.mouseClick(canvas.viewport(), Qt.RightButton if right else Qt.LeftButton,
                     Qt.NoModifier, point)
    hit = canvas.getCoordinateTransform().toMapCoordinates(point.x(), point.y())
    return hit.x(), hit.y()


def draw(work, layer: str, clicks, finish: bool = True) -> List[Tuple[float, float]]:
    """Activate the tool of ``layer`` and click; lines and polygons end with a right click."""
    tool = work["bar"].activate(layer)
    assert tool is not None and work["canvas"].mapTool() is tool
    hits = [click(work["canvas"], x, y) for x, y in clicks]
    if finish and len(clicks) > 1:
        click(work["canvas"], *clicks[-1], right=True)
    return hits


def saved(work, layer: str) -> List[Tuple[Any, Dict[str, Any]]]:
    """Commit the layer (*Save layer edits*) and read it back from edits.gpkg with fiona."""
    import fiona
    from shapely.geometry import shape

    qlayer = work["layers"][layer]
    if qlayer.isEditable():
        assert qlayer.commitChanges(), qlayer.commitErrors()
    with fiona.open(work["gpkg"], layer=layer) as src:
        return [(shape(f["geometry"]), dict(f["properties"])) for f in src]


def digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def bar_text(iface) -> str:
    """All texts in the message bar."""
    return " ".join(item.text() for item in iface.messageBar().items())


# -- every tool of the click table ---------------------------------------------------------------
@pytest.mark.parametrize("case", CLICKS, ids=[c["layer"] for c in CLICKS])
def test_tool_writes_the_feature_and_undo_removes_it(work, case):
    layer_name = case["layer"]
    work["ask"].answer = dict(case["answer"])
    layer = work["layers"][layer_name]
    hits = draw(work, layer_name, case["clicks"])
    assert layer.featureCount() == 1, (bar_text(work["iface"]), work["ask"].calls, hits)
    layer.undoStack().undo()
    assert layer.featureCount() == 0  # QGIS's undo removes the edit
    layer.undoStack().redo()
    assert layer.featureCount() == 1
    check_written(case, hits, saved(work, layer_name))  # the standalone test expects the same


def test_start_point_in_the_real_form(work, qgis_app, shots_dir):
    """The real height form: pre-filled with the sampled height, edited, accepted."""
    from qgis.PyQt.QtCore import QTimer
    from qgis.PyQt.QtWidgets import QApplication, QDialogButtonBox, QDoubleSpinBox, QLineEdit

    from photodem.plugin.qgis.edit_forms import DialogAsker

    work["bar"].controller.ask = DialogAsker(work["iface"].mainWindow())
    seen: Dict[str, Any] = {}

    def fill() -> None:
        dialog = QApplication.activeModalWidget()
        if dialog is None:
            QTimer.singleShot(50, fill)
            return
        box = dialog.findChild(QDoubleSpinBox, "height")
        seen["prefilled"] = box.value()
        dialog.grab().save(str(shots_dir / "height_form.png"))
        box.setValue(box.value() + 1.5)
        dialog.findChild(QLineEdit, "text").setText("edited")
        dialog.findChild(QDialogButtonBox).button(QDialogButtonBox.Ok).click()

    QTimer.singleShot(0, fill)
    (hx, hy), = draw(work, "start_points", [CLICKS[0]["clicks"][0]])
    assert seen["prefilled"] == pytest.approx(surface_z(hx, hy), abs=1e-3)  # 3 decimals shown
    (_, props), = saved(work, "start_points")
    assert props["note"] == "edited"
    assert props["height"] == pytest.approx(round(surface_z(hx, hy), 3) + 1.5, abs=1e-6)


def test_real_action_form_offers_the_three_actions(work):
    from qgis.PyQt.QtWidgets import QComboBox

    from photodem.plugin.qgis.edit_forms import ActionDialog

    dialog = ActionDialog(work["iface"].mainWindow())
    box = dialog.findChild(QComboBox, "action")
    assert [box.itemData(i) for i in range(box.count())] == ["keep", "remove", "exclude"]


# -- refusals --------------------------------------------------------------------------------------
def test_crossing_breakline_is_refused_and_marked(work):
    first = next(c for c in CLICKS if c["layer"] == "breaklines")
    layer = work["layers"]["breaklines"]
    draw(work, "breaklines", first["clicks"])
    assert layer.featureCount() == 1  # unsaved, in the edit buffer
    before = digest(work["gpkg"])
    draw(work, "breaklines", CROSSING_BREAKLINE)
    assert layer.featureCount() == 1
    assert digest(work["gpkg"]) == before
    markers = work["bar"].controller.markers
    assert len(markers) == 1
    centre = markers[0].pos()  # scene position = canvas pixel
    crossing = work["canvas"].getCoordinateTransform().toMapCoordinates(round(centre.x()),
                                                                        round(centre.y()))
    assert abs(crossing.x() - 402285.0) < 1.0 and abs(crossing.y() - 5674707.5) < 1.0
    assert "refused" in bar_text(work["iface"])
    assert len(saved(work, "breaklines")) == 1


def test_self_intersecting_polygon_refused_or_repaired_with_consent(work):
    layer = work["layers"]["exclusion_areas"]
    work["ask"].answer = {"repair": False, "action": "exclude"}
    draw(work, "exclusion_areas", BOW_TIE)
    assert layer.featureCount() == 0
    assert "refused" in bar_text(work["iface"]) and "Self-intersection" in bar_text(work["iface"])
    assert saved(work, "exclusion_areas") == []
    work["ask"].answer = {"repair": True, "action": "exclude"}
    draw(work, "exclusion_areas", BOW_TIE)
    rows = saved(work, "exclusion_areas")
    assert len(rows) == 2  # the two triangles of the bow tie
    assert all(g.is_valid and p["action"] == "exclude" for g, p in rows)


def test_read_only_edits_are_refused(work):
    gpkg = work["gpkg"]
    gpkg.chmod(0o444)
    try:
        before = digest(gpkg)
        assert work["bar"].activate("start_points") is None
        assert "read-only" in bar_text(work["iface"])
        assert not work["bar"].actions["start_points"].isChecked()
        assert digest(gpkg) == before
    finally:
        gpkg.chmod(0o644)


def test_missing_layer_and_no_project(work):
    work["layers"].pop("seamlines")
    assert work["bar"].activate("seamlines") is None
    assert "missing" in bar_text(work["iface"])
    work["bar"].set_workspace(None)
    assert not work["bar"].actions["start_points"].isEnabled()
    assert work["bar"].activate("start_points") is None
    assert "Open a PhotoDEM project" in bar_text(work["iface"])


def test_edit_outside_the_block_is_refused(work):
    work["ask"].answer = {"height": 50.0}
    draw(work, "ground_points", [(402232.0, 5674785.0)])  # canvas corner, outside the block
    assert work["layers"]["ground_points"].featureCount() == 0
    assert "outside the project's block" in bar_text(work["iface"])


# -- heights without a surface value -------------------------------------------------------------
def test_outside_models_asks_for_a_typed_height(work):
    work["ask"].answer = {"height": 48.0, "text": ""}
    draw(work, "start_points", [OUTSIDE_MODELS])
    kind, prefilled, message = work["ask"].calls[-1]
    assert kind == "height" and prefilled is None and "outside every stereo model" in message
    assert "outside every stereo model" in bar_text(work["iface"])
    (_, props), = saved(work, "start_points")
    assert props["height"] == 48.0


def test_nodata_asks_for_a_typed_height(work):
    work["ask"].answer = {"height": 47.0}
    draw(work, "ground_points", [ON_NODATA])
    _, prefilled, message = work["ask"].calls[-1]
    assert prefilled is None and "nodata" in message
    (geometry, _), = saved(work, "ground_points")
    assert geometry.z == 47.0


def test_surface_in_another_crs_is_reprojected(work, tmp_path):
    """The same plane warped to EPSG:4326 still gives the plane's height (to its resampling)."""
    from osgeo import gdal
    from qgis.core import QgsProject, QgsRasterLayer

    path = str(tmp_path / "plane_4326.tif")
    gdal.Warp(path, work["surface"].source(), dstSRS="EPSG:4326", resampleAlg="bilinear")
    layer = QgsRasterLayer(path, "plane 4326")
    QgsProject.instance().addMapLayer(layer)
    work["bar"].surface_box.setLayer(layer)
    work["ask"].answer = {}
    (hx, hy), = draw(work, "ground_points", [(402300.0, 5674700.0)])
    (geometry, _), = saved(work, "ground_points")
    assert geometry.z == pytest.approx(surface_z(hx, hy), abs=0.01)


def test_surface_without_crs_is_named(work, tmp_path):
    from qgis.core import QgsCoordinateReferenceSystem, QgsProject, QgsRasterLayer

    layer = QgsRasterLayer(str(write_surface(tmp_path / "no_crs.tif", crs=None)), "no crs")
    layer.setCrs(QgsCoordinateReferenceSystem())
    QgsProject.instance().addMapLayer(layer)
    work["bar"].surface_box.setLayer(layer)
    work["ask"].answer = {"height": None}  # the operator cancels the form
    draw(work, "ground_points", [(402300.0, 5674700.0)])
    assert "no CRS" in bar_text(work["iface"]) + str(work["ask"].calls)
    assert work["layers"]["ground_points"].featureCount() == 0


# -- breakline modes, seamline snapping, re-drape, validation ------------------------------------
def test_interpolated_breakline(work):
    work["bar"].set_z_mode("interpolate")
    work["ask"].answer = {"heights": [INTERPOLATED["ends"][0], None, INTERPOLATED["ends"][1]]}
    hits = draw(work, "breaklines", INTERPOLATED["clicks"])
    _, _, editable, _ = work["ask"].calls[-1]
    assert editable == [True, False, True]
    (line, _), = saved(work, "breaklines")
    z = [c[2] for c in line.coords]
    lengths = [0.0, math.dist(hits[0], hits[1])]
    lengths.append(lengths[1] + math.dist(hits[1], hits[2]))
    z0, z1 = INTERPOLATED["ends"]
    assert z == pytest.approx([z0 + (z1 - z0) * s / lengths[-1] for s in lengths], abs=1e-6)


def test_seamline_snaps_to_the_mosaic_seamlines(work, tmp_path):
    from qgis.core import QgsProject, QgsVectorLayer

    path = write_mosaic_seamlines(tmp_path / "mosaic_seamlines.gpkg")
    QgsProject.instance().addMapLayer(
        QgsVectorLayer(f"{path}|layername=seamlines", "mosaic seamlines", "ogr"))
    case = next(c for c in CLICKS if c["layer"] == "seamlines")
    draw(work, "seamlines", case["clicks"])
    (line, _), = saved(work, "seamlines")
    assert [c[0] for c in line.coords] == pytest.approx([402301.0, 402301.0], abs=1e-6)


def test_redrape_selected_points_is_one_undoable_command(work):
    layer = work["layers"]["ground_points"]
    work["ask"].answer = {"height": 30.0}
    (hx, hy), = draw(work, "ground_points", [(402300.0, 5674700.0)])
    feature = next(layer.getFeatures())
    assert feature.geometry().constGet().z() == 30.0
    layer.selectByIds([feature.id()])
    work["iface"].setActiveLayer(layer)
    assert work["bar"].controller.redrape() == 1
    z = next(layer.getFeatures()).geometry().constGet().z()
    assert z == pytest.approx(surface_z(hx, hy), abs=1e-6)
    layer.undoStack().undo()
    assert next(layer.getFeatures()).geometry().constGet().z() == 30.0


def test_validate_lists_unsaved_problems_and_zooms(work):
    from qgis.core import QgsFeature, QgsGeometry, QgsPointXY

    layer = work["layers"]["start_points"]
    layer.startEditing()
    feature = QgsFeature(layer.fields())
    feature.setGeometry(QgsGeometry.fromPointXY(QgsPointXY(402290.0, 5674660.0)))
    feature["height"] = 900.0  # implausible: QGIS's own digitizing let it in
    layer.addFeature(feature)
    dock = work["bar"].validate()
    assert dock is not None and dock.table.rowCount() >= 1
    found = dock.found
    assert any(f.layer == "start_points" and "plausible" in f.problem.message for f in found)
    work["canvas"].setExtent(work["canvas"].fullExtent().buffered(5000))
    row = next(k for k, f in enumerate(found) if "plausible" in f.problem.message)
    dock.table.itemClicked.emit(dock.table.item(row, 0))
    centre = work["canvas"].center()
    assert abs(centre.x() - 402290.0) < 5 and abs(centre.y() - 5674660.0) < 5
    assert work["canvas"].extent().width() < 100


# -- screenshots -----------------------------------------------------------------------------------
def _draw_everything(work) -> None:
    for case in CLICKS:
        if case["layer"] == "seamlines":
            continue
        work["ask"].answer = dict(case["answer"])
        draw(work, case["layer"], case["clicks"])
    work["ask"].answer = {"action": "remove"}
    draw(work, "exclusion_areas", [(402305.0, 5674720.0), (402325.0, 5674720.0),
                                   (402325.0, 5674735.0), (402305.0, 5674735.0)])
    work["ask"].answer = {"action": "exclude"}
    draw(work, "exclusion_areas", [(402275.0, 5674725.0), (402295.0, 5674725.0),
                                   (402290.0, 5674745.0)])
    draw(work, "breaklines", CROSSING_BREAKLINE)  # refused: its crossing stays marked


def _preview_styles(work) -> None:
    """Plain see-through styles for the screenshot (part W's QML styles replace them): the
    exclusion actions in three colours with a light fill, outlines for boundaries."""
    from qgis.core import (
        QgsCategorizedSymbolRenderer,
        QgsFillSymbol,
        QgsLineSymbol,
        QgsMarkerSymbol,
        QgsRendererCategory,
        QgsSingleSymbolRenderer,
    )

    def fill(colour: str) -> Any:
        return QgsFillSymbol.createSimple({"color": colour + ",60", "outline_color": colour,
                                           "outline_width": "0.8"})

    layers = work["layers"]
    layers["exclusion_areas"].setRenderer(QgsCategorizedSymbolRenderer("action", [
        QgsRendererCategory(value, fill(colour), value)
        for value, colour in (("keep", "40,160,60"), ("remove", "230,140,0"),
                              ("exclude", "210,30,30"))]))
    layers["boundaries"].setRenderer(QgsSingleSymbolRenderer(QgsFillSymbol.createSimple(
        {"style": "no", "outline_color": "30,60,200", "outline_width": "0.8",
         "outline_style": "dash"})))
    layers["breaklines"].setRenderer(QgsSingleSymbolRenderer(QgsLineSymbol.createSimple(
        {"line_color": "120,0,160", "line_width": "0.9"})))
    for name, colour, shape in (("start_points", "0,120,255", "circle"),
                                ("ground_points", "140,90,40", "triangle"),
                                ("check_points", "0,0,0", "cross2")):
        layers[name].setRenderer(QgsSingleSymbolRenderer(QgsMarkerSymbol.createSimple(
            {"name": shape, "color": colour, "outline_color": "white", "size": "4"})))


def _hillshade_under(work) -> None:
    """The block's DSM as a hillshade at the bottom; the analytic plane (the toolbar's surface)
    hidden."""
    from qgis.core import QgsHillshadeRenderer, QgsProject, QgsRasterLayer

    dsm = QgsRasterLayer(str(work["root"] / "truth" / "dsm.tif"), "DSM (hillshade)")
    dsm.setRenderer(QgsHillshadeRenderer(dsm.dataProvider(), 1, 315, 45))
    project = QgsProject.instance()
    project.addMapLayer(dsm, False)
    root = project.layerTreeRoot()
    root.insertLayer(len(root.children()), dsm)
    root.findLayer(work["surface"].id()).setItemVisibilityChecked(False)


def _unsaved_problem(work) -> None:
    """A start point with an implausible height, as QGIS's own digitizing could add it."""
    from qgis.core import QgsFeature, QgsGeometry, QgsPointXY

    layer = work["layers"]["start_points"]
    feature = QgsFeature(layer.fields())
    feature.setGeometry(QgsGeometry.fromPointXY(QgsPointXY(402320.0, 5674650.0)))
    feature["height"] = 900.0
    layer.addFeature(feature)


@pytest.mark.parametrize("lang", ["en", "de"])
def test_screenshot_toolbar_and_canvas(work, lang, qgis_app, shots_dir, german):
    from qgis.PyQt.QtWidgets import QApplication

    from photodem.plugin.i18n import install_translator

    if lang == "de":
        german()
        if work["bar"].toolbar in work["iface"].toolbars:
            work["iface"].toolbars.remove(work["bar"].toolbar)
        work["bar"].unload()
        from photodem.plugin.qgis.editing_toolbar import EditingToolbar

        work["bar"] = EditingToolbar(work["iface"], ask=work["ask"])
        work["bar"].set_workspace(work["workspace"])
    try:
        _preview_styles(work)
        _hillshade_under(work)
        _draw_everything(work)
        _unsaved_problem(work)
        work["bar"].validate()
        window = work["iface"].mainWindow()
        window.resize(1900, 900)
        canvas = work["canvas"]
        for _ in range(3):
            QApplication.processEvents()
            canvas.refreshAllLayers()
            canvas.waitWhileRendering()
        assert window.grab().save(str(shots_dir / f"editing_{lang}.png"))
    finally:
        install_translator("en")


# -- more bad input and modes --------------------------------------------------------------------
def test_locked_edits_are_refused(work):
    """Another program holds a write lock on edits.gpkg: the tool says so, nothing is written."""
    import sqlite3

    holder = sqlite3.connect(str(work["gpkg"]))
    holder.execute("BEGIN IMMEDIATE")
    try:
        before = digest(work["gpkg"])
        assert work["bar"].activate("breaklines") is None
        assert "locked" in bar_text(work["iface"])
        assert digest(work["gpkg"]) == before
    finally:
        holder.rollback()
        holder.close()


def test_typed_breakline_heights(work):
    """Typed mode: every vertex is editable (pre-filled with the surface), the typed Z written."""
    work["bar"].set_z_mode("typed")
    case = next(c for c in CLICKS if c["layer"] == "breaklines")
    work["ask"].answer = {"heights": [41.0, 42.0, 43.0], "kind": "structure_line"}
    hits = draw(work, "breaklines", case["clicks"])
    _, prefilled, editable, _ = work["ask"].calls[-1]
    assert editable == [True, True, True]
    assert prefilled == pytest.approx([surface_z(*h) for h in hits], abs=1e-6)
    (line, props), = saved(work, "breaklines")
    assert [c[2] for c in line.coords] == [41.0, 42.0, 43.0]
    assert props["kind"] == "structure_line"


def test_canvas_in_another_crs(work):
    """Canvas in EPSG:3857: points and polygons land in the project CRS, heights at the point."""
    from qgis.core import (
        QgsCoordinateReferenceSystem,
        QgsCoordinateTransform,
        QgsPointXY,
        QgsProject,
        QgsRectangle,
    )

    canvas = work["canvas"]
    web = QgsCoordinateReferenceSystem("EPSG:3857")
    utm = QgsCoordinateReferenceSystem("EPSG:25832")
    to_web = QgsCoordinateTransform(utm, web, QgsProject.instance())
    canvas.setDestinationCrs(web)
    canvas.setExtent(to_web.transformBoundingBox(QgsRectangle(*EXTENT)))
    back = QgsCoordinateTransform(web, utm, QgsProject.instance())

    def web_point(x: float, y: float) -> Tuple[float, float]:
        p = to_web.transform(QgsPointXY(x, y))
        return p.x(), p.y()

    def utm_point(x: float, y: float) -> Tuple[float, float]:
        p = back.transform(QgsPointXY(x, y))
        return p.x(), p.y()

    work["ask"].answer = {"text": "web"}
    (hit,) = draw(work, "start_points", [web_point(402290.0, 5674660.0)])
    (point, props), = saved(work, "start_points")
    assert (point.x, point.y) == pytest.approx(utm_point(*hit), abs=1e-3)
    assert props["height"] == pytest.approx(surface_z(point.x, point.y), abs=1e-6)
    case = next(c for c in CLICKS if c["layer"] == "exclusion_areas")
    work["ask"].answer = dict(case["answer"])
    hits = draw(work, "exclusion_areas", [web_point(*xy) for xy in case["clicks"]])
    (polygon, _), = saved(work, "exclusion_areas")
    corners = list(polygon.exterior.coords)[:-1]
    for (x, y), h in zip(corners, hits):
        assert (x, y) == pytest.approx(utm_point(*h), abs=1e-3)


def test_redrape_selected_breakline(work):
    layer = work["layers"]["breaklines"]
    work["bar"].set_z_mode("typed")
    case = next(c for c in CLICKS if c["layer"] == "breaklines")
    work["ask"].answer = {"heights": [30.0, 30.0, 30.0]}
    draw(work, "breaklines", case["clicks"])
    layer.selectAll()
    work["iface"].setActiveLayer(layer)
    assert work["bar"].controller.redrape() == 1
    (line, _), = saved(work, "breaklines")
    for x, y, z in line.coords:
        assert z == pytest.approx(surface_z(x, y), abs=1e-6)


def test_breakline_form_needs_the_free_heights(work):
    """The real breakline form: OK only when every editable height is typed."""
    from qgis.PyQt.QtWidgets import QDialogButtonBox

    from photodem.plugin.qgis.edit_forms import BreaklineDialog

    dialog = BreaklineDialog(work["iface"].mainWindow(), [None, 45.0, None],
                             [True, False, True])
    ok = dialog.buttons.button(QDialogButtonBox.Ok)
    assert not ok.isEnabled()
    dialog.boxes[0].setValue(40.0)
    assert not ok.isEnabled()
    dialog.boxes[2].setValue(44.0)
    assert ok.isEnabled()
    assert dialog.heights() == [40.0, 45.0, 44.0]
    assert not dialog.boxes[1].isEnabled()
    dialog.deleteLater()
