"""Tier B: the difference style (resources/styles/dem_difference.qml) in real QGIS 3.22."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from affine import Affine

pytestmark = pytest.mark.qgis


def _colour(shader, value: float) -> str:
    ok, red, green, blue, _alpha = shader.shade(value)
    assert ok, value
    return f"#{red:02x}{green:02x}{blue:02x}"


def test_difference_style_loads_and_classes_as_specified(qgis_app, tmp_path: Path) -> None:
    from qgis.core import QgsRasterLayer

    from photodem.algorithms.quality.rasters import style_path, write_difference_style
    from photodem.algorithms.raster.io import write_raster

    values = np.linspace(-7.0, 7.0, 64 * 64).reshape(64, 64).astype(np.float32)
    raster = write_raster(tmp_path / "difference.tif", values,
                          Affine(1.0, 0, 400000.0, 0, -1.0, 5600000.0), "EPSG:25832")
    layer = QgsRasterLayer(str(raster), "difference")
    assert layer.isValid()
    message, ok = layer.loadNamedStyle(str(style_path()))
    assert ok, message
    renderer = layer.renderer()
    assert renderer.type() == "singlebandpseudocolor"
    shader = renderer.shader().rasterShaderFunction()
    assert _colour(shader, 0.0) == _colour(shader, 0.2) == _colour(shader, -0.2) == "#ffffbf"
    assert _colour(shader, -0.3) == "#e3eef8" and _colour(shader, 0.3) == "#fee0b6"
    assert _colour(shader, -6.0) == "#08306b" and _colour(shader, 6.0) == "#67001f"
    assert _colour(shader, -4.0) == "#2166ac" and _colour(shader, 4.0) == "#b2182b"
    # written beside the raster, QGIS applies it by itself when the layer is added
    write_difference_style(raster)
    again = QgsRasterLayer(str(raster), "difference")
    assert again.renderer().type() == "singlebandpseudocolor"
