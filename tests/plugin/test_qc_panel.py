"""The DEM quality panel (pytest-qt): area statistics, compare, blunders → edits, profile."""

from __future__ import annotations

import os

import numpy as np
import pytest
import rasterio
from affine import Affine
from shapely.geometry import Polygon, box

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
pytest.importorskip("pytestqt")

from photodem.algorithms.project.edits import create_edits, read_layer
from photodem.algorithms.quality.compare import compare_dems
from photodem.algorithms.quality.points import sample_dem
from photodem.plugin.widgets.qc_panel import QcPanel

X0, Y0, RES, N = 400000.0, 5600000.0, 0.5, 100
T = Affine(RES, 0, X0, 0, -RES, Y0)
CRS = "EPSG:25832"
PLANTED = [((10, 10), (4, 5), 3.0), ((60, 70), (3, 3), -2.0)]


def _write(path, z):
    with rasterio.open(path, "w", driver="GTiff", width=N, height=N, count=1, dtype="float32",
                       crs=CRS, transform=T) as dst:
        dst.write(z.astype(np.float32), 1)
    return str(path)


@pytest.fixture
def project(tmp_path):
    """A folder with edits.gpkg, a reference and a DEM with two planted blunders."""
    _, cols = np.mgrid[0:N, 0:N]
    ref = 50.0 + 0.03 * cols
    dem = ref + np.random.default_rng(3).normal(0, 0.1, ref.shape).clip(-0.25, 0.25)
    for (r, c), (h, w), dz in PLANTED:
        dem[r:r + h, c:c + w] += dz
    (tmp_path / "project.toml").write_text("")
    create_edits(tmp_path / "edits.gpkg", CRS)
    return tmp_path, _write(tmp_path / "dem.tif", dem), _write(tmp_path / "ref.tif", ref)


@pytest.fixture
def panel(qtbot, project):
    root, dem, ref = project
    w = QcPanel()
    qtbot.addWidget(w)
    w.set_project(root)
    w.set_inputs(dem=dem, reference=ref)
    w.resize(900, 700)
    w.show()
    return w


def test_area_statistics_equal_dem_compare_on_the_area(panel, project):
    _, dem, ref = project
    poly = Polygon([(X0 + 3.1, Y0 - 2.2), (X0 + 30.4, Y0 - 4.0), (X0 + 24.0, Y0 - 35.3)])
    panel.set_area(poly.wkt)
    assert panel.wait()
    expected = compare_dems(dem, ref, area=poly)["stats"]
    assert panel.statistics["stats"] == expected
    assert panel.stats_table.item(0, 1).text().replace("\u202f", "") == str(expected["count"])
    assert panel.group_table.rowCount() >= 1


def test_compare_writes_into_products_and_offers_the_difference(panel, project, qtbot):
    root = project[0]
    with qtbot.waitSignal(panel.difference_ready, timeout=60000) as sig:
        assert panel.compare()
    assert panel.wait()
    path = sig.args[0]
    assert path.startswith(str(root / "products" / "quality"))
    assert os.path.isfile(path) and os.path.isfile(path[:-4] + ".qml")
    assert panel.statistics["stats"]["count"] == N * N


def test_compare_co_registers_on_stable_terrain(panel, project, qtbot):
    root, _, ref = project
    with rasterio.open(ref) as src:
        z = src.read(1)
    _write(root / "dem_up.tif", z + 0.4)  # a vertical bias the co-registration removes
    panel.set_inputs(dem=str(root / "dem_up.tif"))
    panel.coregister_check.setChecked(True)
    panel.stable_edit.setText(_write(root / "stable.tif", np.ones((N, N))))
    with qtbot.waitSignal(panel.difference_ready, timeout=60000):
        assert panel.compare()
    assert panel.wait()
    assert panel.statistics["shift"]["dz"] == pytest.approx(-0.4, abs=0.01)
    assert abs(panel.statistics["stats"]["mean"]) < 0.01


def test_blunders_list_zoom_and_edits(panel, project, qtbot):
    root, _, ref = project
    assert panel.find_blunders()
    assert panel.wait()
    assert panel.blunder_table.rowCount() == len(PLANTED)
    with qtbot.waitSignal(panel.zoomTo) as sig:
        panel._blunder_clicked(1)
    (r, c), (h, w), _ = PLANTED[1]
    assert sig.args[0] == pytest.approx((*(T * (c, r + h)), *(T * (c + w, r))))
    assert panel.blunder_to_exclusion(0, "remove")
    assert panel.blunder_to_ground_point(1)
    (poly, props), = read_layer(root / "edits.gpkg", "exclusion_areas")
    (r, c), (h, w), _ = PLANTED[0]
    assert poly.is_valid and poly.equals(box(*(T * (c, r + h)), *(T * (c + w, r))))
    assert props["action"] == "remove"
    (pt, _), = read_layer(root / "edits.gpkg", "ground_points")
    assert pt.z == pytest.approx(sample_dem(ref, [pt.x], [pt.y])[0])


def test_profile_and_identify(panel, project, tmp_path):
    _, dem, ref = project
    line = [(X0 + 2.3, Y0 - 5.4), (X0 + 40.1, Y0 - 31.7)]
    prof = panel.set_line(line)
    for name, path in zip(prof["names"], (dem, ref)):
        assert np.allclose(prof["heights"][name], sample_dem(path, prof["x"], prof["y"]),
                           atol=1e-6, equal_nan=True)
    assert panel.export_profile_csv(tmp_path / "p.csv").is_file()
    assert panel.export_profile_png(tmp_path / "p.png").stat().st_size > 1000
    res = panel.show_identify(X0 + 10.25, Y0 - 10.25)
    assert set(res["values"]) == {"dem", "ref"}
    assert panel.identify_table.rowCount() == 3


def test_missing_inputs_are_reported(qtbot):
    w = QcPanel()
    qtbot.addWidget(w)
    with qtbot.waitSignal(w.message) as sig:
        assert not w.compute_statistics()
    assert sig.args[0] == "warning" and "DEM" in sig.args[1]


def test_typed_extent_and_line_and_the_standalone_entry(qtbot, project):
    from photodem.plugin.app.main_window import ToolboxWindow

    root, dem, ref = project
    window = ToolboxWindow(message_boxes=False)
    qtbot.addWidget(window)
    panel = window.open_quality_panel()
    assert window.open_quality_panel() is panel  # one dock, shown again
    panel.project_edit.setText(str(root))
    panel.project_edit.editingFinished.emit()
    assert panel.project_root == root
    panel.set_inputs(dem=dem, reference=ref)
    panel.extent_edit.setText(f"{X0 + 5}, {Y0 - 15}, {X0 + 15}, {Y0 - 5}")
    panel._typed_extent()
    assert panel.wait()
    assert panel.statistics["stats"]["count"] == 400
    panel.line_edit.setText(f"{X0 + 1},{Y0 - 1};{X0 + 20},{Y0 - 20}")
    panel._typed_line()
    assert panel.profile is not None and panel.profile["length"] > 26
    panel.set_project(root / "images")  # no project.toml: refused
    assert panel.project_root is None and "no PhotoDEM project" in panel.status.text()


def test_filter_review_writes_only_on_accept(qtbot, tmp_path):
    import hashlib
    from pathlib import Path

    from photodem.algorithms.processing import registry

    _, cols = np.mgrid[0:N, 0:N]
    z = 100.0 + 0.02 * cols
    z[40:56, 40:60] += 8.0  # a house
    dsm = _write(tmp_path / "dsm.tif", z)
    out = registry.run("filter_lowpass", {"input": dsm, "output": str(tmp_path / "dtm")})
    w = QcPanel()
    qtbot.addWidget(w)
    w.set_inputs(dem=dsm)
    w.filter_tab.dtm_edit.setText(out["dtm"])
    assert not w.filter_tab.run()  # no area yet
    w.set_area(box(X0 + 15, Y0 - 35, X0 + 35, Y0 - 15).wkt, run=False)
    w.filter_tab.preset_combo.setCurrentIndex(w.filter_tab.preset_combo.findData("urban"))
    digest = hashlib.sha256(Path(out["dtm"]).read_bytes()).hexdigest()
    assert w.filter_tab.run()
    assert w.wait()
    review = w.filter_tab.review
    assert review is not None and review["preset"] == "urban"
    assert review["inside"].sum() == 40 * 40 and "urban" in w.filter_tab.summary.text()
    assert hashlib.sha256(Path(out["dtm"]).read_bytes()).hexdigest() == digest
    with qtbot.waitSignal(w.filter_tab.dtm_changed):
        assert w.filter_tab.accept(confirm=False)
    assert hashlib.sha256(Path(out["dtm"]).read_bytes()).hexdigest() != digest or \
        np.allclose(review["new"], review["old"], equal_nan=True)
