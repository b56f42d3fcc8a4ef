"""Tier B: the DEM quality dock in real QGIS 3.22, driven by mouse and key events on the canvas:
a drawn polygon's statistics equal ``dem_compare`` restricted to it, profile heights equal the
surfaces at the stations (1e-6 m), a blunder becomes an exclusion area in ``edits.gpkg``
through the edit buffer (undo works)."""

from __future__ import annotations

from pathlib import Path
from typing import Tuple

import numpy as np
import pytest
from _qgis_helpers import copy_block

pytestmark = pytest.mark.qgis

#: Planted blunders of the DEM: (row, col) of the top-left cell in the DEM, (rows, cols), Δh.
PLANTED = [((100, 120), (6, 8), 4.0), ((300, 250), (4, 4), -3.0)]
CROP = (200, 200, 500, 500)  # row, col, rows, cols of the truth DSM the DEM covers


@pytest.fixture(scope="module")
def block(tmp_path_factory, tiny_block) -> Path:
    """The tiny block with a DEM = truth DSM (cropped) + noise + planted blunders as a DSM
    product, so that the workspace offers it."""
    import rasterio
    from rasterio.windows import Window

    root = copy_block(tiny_block, tmp_path_factory.mktemp("qc"), "block")
    r0, c0, h, w = CROP
    with rasterio.open(root / "truth" / "dsm.tif") as src:
        z = src.read(1, window=Window(c0, r0, w, h)).astype(np.float64)
        profile = src.profile | {"width": w, "height": h,
                                 "transform": src.window_transform(Window(c0, r0, w, h))}
    rng = np.random.default_rng(11)
    z += rng.normal(0.0, 0.05, z.shape).clip(-0.12, 0.12)
    for (r, c), (nr, nc), dz in PLANTED:
        z[r:r + nr, c:c + nc] += dz
    out = root / "products" / "dsm" / "0101_0102"
    out.mkdir(parents=True)
    with rasterio.open(out / "dsm.tif", "w", **profile) as dst:
        dst.write(z.astype(profile["dtype"]), 1)
    from photodem.algorithms.processing import registry

    registry.run("filter_lowpass", {"input": str(out / "dsm.tif"),
                                    "output": str(root / "products" / "dtm" / "0101_0102")})
    return root


@pytest.fixture
def dock(block, tmp_path, qgis_iface):
    """The dock on a fresh copy of the block, the truth DSM as the reference."""
    from qgis.core import QgsCoordinateReferenceSystem, QgsProject, QgsRasterLayer

    from photodem.plugin.qgis.qc_dock import QcDock
    from photodem.plugin.qgis.workspace import forget_workspace, open_workspace

    root = copy_block(block, tmp_path)
    ws = open_workspace(qgis_iface, root)
    truth = QgsRasterLayer(str(root / "truth" / "dsm.tif"), "truth DSM", "gdal")
    QgsProject.instance().addMapLayer(truth)
    dock = QcDock(qgis_iface)
    qgis_iface.addDockWidget(2, dock)
    dock.reference_combo.setLayer(truth)
    dsm = ws.surface_layers()[0]
    canvas = qgis_iface.mapCanvas()
    canvas.setDestinationCrs(QgsCoordinateReferenceSystem("EPSG:25832"))
    canvas.setExtent(dsm.extent())
    canvas.refresh()
    yield {"dock": dock, "ws": ws, "root": root, "dsm": dsm, "truth": truth, "canvas": canvas}
    dock.close()
    for layer in (ws.edit_layer(n) for n in ("exclusion_areas", "ground_points")):
        if layer is not None and layer.isEditable():
            layer.rollBack()
    forget_workspace()


def click(canvas, x: float, y: float, right: bool = False) -> Tuple[float, float]:
    """A mouse click at map (x, y); returns the map point of the clicked pixel's centre."""
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


def _paths(work):
    return work["dsm"].source(), work["truth"].source()


def test_defaults_come_from_the_workspace(dock):
    from qgis.core import QgsProject, QgsVectorLayer

    assert dock["dock"].dem_combo.currentLayer() is dock["dsm"]
    given = dock["dock"].inputs()
    assert given["dem"].endswith("products/dsm/0101_0102/dsm.tif")
    assert given["reference"].endswith("truth/dsm.tif")
    assert given["classes"] is None and not dock["dock"].class_field_combo.isEnabled()
    # class polygons with their attribute: per-class statistics by that attribute
    buildings = QgsVectorLayer(str(dock["root"] / "truth" / "buildings.gpkg"), "buildings",
                               "ogr")
    QgsProject.instance().addMapLayer(buildings)
    dock["dock"].classes_combo.setLayer(buildings)
    dock["dock"].class_field_combo.setField("roof")
    given = dock["dock"].inputs()
    assert given["classes"].endswith("buildings.gpkg") and given["class_field"] == "roof"
    dock["dock"].use_whole_model()
    assert dock["dock"].panel.wait()
    assert set(dock["dock"].panel.statistics["per_class"]) <= {"flat", "gabled"}
    assert dock["dock"].panel.statistics["per_class"]


def test_drawn_polygon_statistics_equal_dem_compare(dock):
    from shapely.geometry import Polygon

    from photodem.algorithms.quality.compare import compare_dems

    work, canvas = dock["dock"], dock["canvas"]
    e = dock["dsm"].extent()
    x0, y0, w, h = e.xMinimum(), e.yMinimum(), e.width(), e.height()
    clicks = [(x0 + 0.2 * w, y0 + 0.3 * h), (x0 + 0.7 * w, y0 + 0.25 * h),
              (x0 + 0.6 * w, y0 + 0.8 * h), (x0 + 0.3 * w, y0 + 0.7 * h)]
    tool = work.activate("area")
    assert canvas.mapTool() is tool
    hits = [click(canvas, x, y) for x, y in clicks]
    click(canvas, *clicks[-1], right=True)
    assert work.panel.wait()
    dem, ref = _paths(dock)
    expected = compare_dems(dem, ref, area=Polygon(hits))["stats"]
    assert work.panel.statistics["stats"] == expected
    assert expected["count"] > 1000
    assert work.area_band.numberOfVertices() >= 4
    # visible extent and whole model use the same code
    work.use_whole_model()
    assert work.panel.wait()
    assert work.panel.statistics["stats"] == compare_dems(dem, ref)["stats"]


def test_profile_of_a_drawn_line_and_the_arrow_keys(dock):
    from qgis.PyQt.QtCore import Qt
    from qgis.PyQt.QtTest import QTest

    from photodem.algorithms.quality.points import sample_dem

    work, canvas = dock["dock"], dock["canvas"]
    e = dock["dsm"].extent()
    a = (e.xMinimum() + 0.1 * e.width(), e.yMinimum() + 0.5 * e.height())
    b = (e.xMinimum() + 0.9 * e.width(), e.yMinimum() + 0.6 * e.height())
    work.activate("line")
    hits = [click(canvas, *a), click(canvas, *b)]
    click(canvas, *b, right=True)
    prof = work.panel.profile
    assert prof is not None and np.allclose(work.panel.line[:, :2], hits)
    dem, ref = _paths(dock)
    for name, path in zip(prof["names"], (dem, ref)):
        assert np.allclose(prof["heights"][name], sample_dem(path, prof["x"], prof["y"]),
                           atol=1e-6, equal_nan=True)
    before = work.panel.line.copy()
    canvas.setFocus()
    QTest.keyClick(canvas, Qt.Key_Left)
    moved = work.panel.line
    cell = dock["dsm"].rasterUnitsPerPixelX()
    assert np.allclose(np.hypot(*(moved - before)[:, :2].T), cell)
    assert work.panel.profile is not prof


def test_identify_click(dock):
    work, canvas = dock["dock"], dock["canvas"]
    e = dock["dsm"].extent()
    work.activate("identify")
    x, y = click(canvas, e.center().x(), e.center().y())
    values = work.panel.identify_table
    assert values.rowCount() == 6  # DEM, reference, the workspace DTM, three differences
    assert work.panel.identify_text.text() == f"At x = {x:.2f}, y = {y:.2f}"


def test_blunder_to_exclusion_area_through_the_edit_buffer(dock):
    import fiona
    from qgis.core import QgsPointXY
    from shapely.geometry import shape

    work = dock["dock"]
    assert work.panel.find_blunders()
    assert work.panel.wait()
    spots = work.panel.blunders["spots"]
    assert len(spots) == len(PLANTED)
    layer = dock["ws"].edit_layer("exclusion_areas")
    n0 = layer.featureCount()
    work.panel.blunder_table.selectRow(0)
    work.panel.exclusion_button.click()
    assert layer.isEditable() and layer.featureCount() == n0 + 1
    layer.undoStack().undo()
    assert layer.featureCount() == n0
    layer.undoStack().redo()
    assert layer.commitChanges(), layer.commitErrors()
    with fiona.open(dock["root"] / "edits.gpkg", layer="exclusion_areas") as src:
        feats = [(shape(f["geometry"]), dict(f["properties"])) for f in src]
    (poly, props), = feats
    assert poly.is_valid and props["action"] == "remove"
    (r, c), (nr, nc), _ = PLANTED[0]
    t = dock["dsm"].extent()
    res = dock["dsm"].rasterUnitsPerPixelX()
    expected = (t.xMinimum() + c * res, t.yMaximum() - (r + nr) * res,
                t.xMinimum() + (c + nc) * res, t.yMaximum() - r * res)
    assert poly.bounds == pytest.approx(expected, abs=1e-6)
    # a row click zooms to the spot
    work.panel._blunder_clicked(1)
    assert dock["canvas"].extent().contains(QgsPointXY(*spots[1]["centroid"]))


def test_filter_review_mask_refilter_and_accept(dock):
    import hashlib

    from qgis.core import QgsProject

    work, canvas = dock["dock"], dock["canvas"]
    tab = work.panel.filter_tab
    dtm = dock["root"] / "products" / "dtm" / "0101_0102" / "dtm.tif"
    assert Path(tab.dtm_edit.text()) == dtm.resolve()
    mask = work.show_mask()
    assert mask is not None and mask.renderer().type() == "paletted"
    assert mask in QgsProject.instance().mapLayers().values()
    e = dock["dsm"].extent()
    x0, y0, w, h = e.xMinimum(), e.yMinimum(), e.width(), e.height()
    work.activate("area")
    for x, y in ((x0 + 0.3 * w, y0 + 0.3 * h), (x0 + 0.6 * w, y0 + 0.3 * h),
                 (x0 + 0.5 * w, y0 + 0.6 * h)):
        click(canvas, x, y)
    click(canvas, x0 + 0.5 * w, y0 + 0.6 * h, right=True)
    assert work.panel.wait()
    before = hashlib.sha256(dtm.read_bytes()).hexdigest()
    tab.preset_combo.setCurrentIndex(tab.preset_combo.findData("urban"))
    assert tab.run() and work.panel.wait()
    assert tab.review is not None and tab.review["inside"].sum() > 100
    assert hashlib.sha256(dtm.read_bytes()).hexdigest() == before  # nothing written yet
    assert tab.accept(confirm=False)
    assert work.reload_layers_of(str(dtm)) >= 2  # the DTM layer and the mask layer


def test_profile_of_a_picked_line_z_feature(dock, qgis_iface):
    from qgis.core import QgsFeature, QgsGeometry, QgsProject, QgsVectorLayer

    work, canvas = dock["dock"], dock["canvas"]
    e = dock["dsm"].extent()
    y = e.center().y()
    x0, x1 = e.xMinimum() + 0.2 * e.width(), e.xMinimum() + 0.8 * e.width()
    lines = QgsVectorLayer("LineStringZ?crs=EPSG:25832", "lines", "memory")
    feature = QgsFeature()
    feature.setGeometry(QgsGeometry.fromWkt(f"LineStringZ({x0} {y} 50, {x1} {y} 55)"))
    lines.dataProvider().addFeatures([feature])
    QgsProject.instance().addMapLayer(lines)
    qgis_iface.setActiveLayer(lines)
    assert work.pick_line() is canvas.mapTool()
    click(canvas, 0.5 * (x0 + x1), y)
    prof = work.panel.profile
    assert prof is not None and prof["vertices"]["z"].tolist() == [50.0, 55.0]
    assert prof["length"] == pytest.approx(x1 - x0)


def test_compare_adds_the_styled_difference_to_products(dock):
    from photodem.plugin.qgis.workspace import PRODUCTS

    work = dock["dock"]
    assert work.panel.compare()
    assert work.panel.wait()
    products = dock["ws"].layers_in(PRODUCTS)
    diff = [p for p in products if p.source().endswith("difference.tif")]
    assert len(diff) == 1 and diff[0].renderer().type() == "singlebandpseudocolor"
    assert "products/quality/" in diff[0].source()
    shade = [p for p in products if p.source().endswith("hillshade.tif")]
    assert shade and products.index(diff[0]) < products.index(shade[0])  # above its hillshade
    assert work.panel.statistics["stats"]["count"] > 1000


def test_raster_menu_entry_shows_the_dock(qgis_iface, monkeypatch):
    from photodem.plugin.qgis.plugin import MENU_TITLE, PhotodemPlugin
    from photodem.plugin.qgis.qc_dock import QcDock

    monkeypatch.setattr(PhotodemPlugin, "initProcessing", lambda self: None)  # session's stays
    plugin = PhotodemPlugin(qgis_iface)
    plugin.initGui()
    try:
        entry = [a for a in qgis_iface.menus[MENU_TITLE]
                 if a.objectName() == "photodemQualityDock"]
        assert len(entry) == 1
        entry[0].trigger()
        dock = plugin.qc_dock
        assert isinstance(dock, QcDock) and dock in qgis_iface.docks and dock.isVisible()
        entry[0].trigger()
        assert plugin.qc_dock is dock  # shown again, not made twice
    finally:
        plugin.unload()
    assert plugin.qc_dock is None and dock not in qgis_iface.docks
