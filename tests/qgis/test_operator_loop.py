"""The operator's loop in real QGIS, with the real workspace, toolbar and model actions: open the
project → match a model from its action → start point, exclusion area and breakline drawn with
the mouse on the DSM → match again → the new DSM replaces the old one in the Products group and
is empty inside the exclusion area. The README's "In QGIS" walkthrough follows these steps."""

from __future__ import annotations

import shutil
import sys
from pathlib import Path
from typing import Any, List

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))  # tests/qgis: the click helpers
from _qgis_helpers import copy_block
from test_edit_tools import FakeAsk, draw

pytestmark = pytest.mark.qgis

MODEL = "0101_0102"
#: Inside model 0101_0102 of the tiny block (EPSG:25832).
START = (402290.0, 5674700.0)
REMOVE = [(402275.0, 5674670.0), (402300.0, 5674670.0), (402300.0, 5674690.0),
          (402275.0, 5674690.0)]
BREAKLINE = [(402270.0, 5674720.0), (402290.0, 5674725.0), (402310.0, 5674722.0)]


@pytest.fixture(scope="module")
def block(tmp_path_factory, tiny_block, plugin) -> Path:
    root = copy_block(tiny_block, tmp_path_factory.mktemp("loop"), "block")
    return root


@pytest.fixture
def desk(block, tmp_path, qgis_iface, provider):
    """The project copy opened as workspace, the editing toolbar and the model actions."""
    from photodem.plugin.qgis.editing_toolbar import EditingToolbar
    from photodem.plugin.qgis.model_actions import ModelActions
    from photodem.plugin.qgis.workspace import forget_workspace, open_workspace

    root = tmp_path / "block"
    shutil.copytree(block, root)
    workspace = open_workspace(qgis_iface, root)
    ask = FakeAsk()
    toolbar = EditingToolbar(qgis_iface, ask=ask)
    toolbar.set_workspace(workspace)
    actions = ModelActions(qgis_iface)
    actions.register()
    yield {"root": root, "ws": workspace, "bar": toolbar, "ask": ask, "actions": actions,
           "iface": qgis_iface, "canvas": qgis_iface.mapCanvas()}
    actions.unregister()
    for dialog in actions.dialogs:
        dialog.close()
    if toolbar.toolbar in qgis_iface.toolbars:
        qgis_iface.toolbars.remove(toolbar.toolbar)
    toolbar.unload()
    forget_workspace()


def _match_from_the_model_action(desk: Any, qtbot) -> Path:
    """Right-click action *Match this model…* on the model's feature, then Run in its dialog."""
    from photodem.plugin.qgis.workspace import BLOCK

    (models,) = desk["ws"].layers("stereo_models", subgroup=BLOCK)
    feature = next(f for f in models.getFeatures() if f["name"] == MODEL)
    match = next(a for a in desk["actions"].layer_actions if a.text().startswith("Match"))
    match.triggerForFeature(models, feature)
    dialog = desk["actions"].dialogs[-1]
    dialog.runAlgorithm()  # the dialog's Run button: a background task
    qtbot.waitUntil(lambda: bool(dialog.results()), timeout=180000)
    return Path(dialog.results()["dsm"])


def _bilinear(path: Path, x: float, y: float) -> float:
    """The raster's bilinear height at (x, y), computed here by hand (independent of the tool)."""
    import numpy as np
    import rasterio

    with rasterio.open(path) as src:
        col, row = ~src.transform * (x, y)
        c0, r0 = int(np.floor(col - 0.5)), int(np.floor(row - 0.5))
        z = src.read(1, window=((r0, r0 + 2), (c0, c0 + 2))).astype(float)
    fc, fr = col - 0.5 - c0, row - 0.5 - r0
    return float(z[0, 0] * (1 - fc) * (1 - fr) + z[0, 1] * fc * (1 - fr)
                 + z[1, 0] * (1 - fc) * fr + z[1, 1] * fc * fr)


def _product_names(desk: Any) -> List[str]:
    from photodem.plugin.qgis.workspace import PRODUCTS

    return [node.layer().name() for node in desk["ws"].subgroup(PRODUCTS).findLayers()]


def test_open_match_edit_rematch(desk, qtbot) -> None:
    import fiona
    import numpy as np
    import rasterio
    from qgis.core import QgsRectangle
    from shapely.geometry import Point, Polygon, shape

    root, ws, canvas = desk["root"], desk["ws"], desk["canvas"]
    # 1. match the model from its action: the DSM arrives in the Products group
    dsm = _match_from_the_model_action(desk, qtbot)
    assert dsm == root / "products" / "dsm" / MODEL / "dsm.tif"
    assert f"DSM {MODEL}" in _product_names(desk)
    surface = desk["bar"].surface_layer()
    assert surface is not None and Path(surface.source()) == dsm  # the newest DSM by default
    canvas.setExtent(QgsRectangle(402230.0, 5674615.0, 402370.0, 5674790.0))
    canvas.refresh()
    # 2. a start point: its height is the DSM's bilinear value at the clicked pixel
    desk["ask"].answer = {"text": "loop"}
    (hit,) = draw(desk, "start_points", [START])
    expected = _bilinear(dsm, *hit)
    # 3. a remove area and 4. a breakline draped on the DSM
    desk["ask"].answer = {"action": "remove", "text": "trees"}
    area = draw(desk, "exclusion_areas", REMOVE)
    # heights from the DSM; typed (50 m) only where it has a hole (the form asks for them)
    desk["ask"].answer = {"kind": "breakline", "heights": [50.0] * len(BREAKLINE)}
    draw(desk, "breaklines", BREAKLINE)
    inner = Polygon(area).buffer(-3.0)
    assert np.isfinite(_bilinear(dsm, *inner.centroid.coords[0]))  # matched before the edit
    for name in ("start_points", "exclusion_areas", "breaklines"):  # Save layer edits
        layer = ws.edit_layer(name)
        assert layer.commitChanges(), layer.commitErrors()
    with fiona.open(root / "edits.gpkg", layer="start_points") as src:
        (point,) = [f for f in src if f["properties"]["note"] == "loop"]
    assert point["properties"]["height"] == pytest.approx(expected, abs=1e-6)
    with fiona.open(root / "edits.gpkg", layer="exclusion_areas") as src:
        assert [f["properties"]["action"] for f in src if f["properties"]["note"] == "trees"] \
            == ["remove"]
    with fiona.open(root / "edits.gpkg", layer="breaklines") as src:
        lines = [shape(f["geometry"]) for f in src]
    assert any(line.has_z and len(line.coords) == 3 for line in lines)
    # 5. match again: the DSM is replaced in the group (no second layer) and honours the area
    _match_from_the_model_action(desk, qtbot)
    assert _product_names(desk).count(f"DSM {MODEL}") == 1
    with rasterio.open(dsm) as src:
        values = [v[0] for v in src.sample([inner.centroid.coords[0]])]
        outside = [v[0] for v in src.sample([Point(START).coords[0]])]
    assert np.isnan(values[0]) or values[0] == src.nodata  # not matched inside "remove"
    assert np.isfinite(outside[0])
