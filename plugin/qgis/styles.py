"""The PhotoDEM styles in QGIS: one QML file per edit layer and product kind.

The QML files in ``resources/styles/`` carry symbology, labels **and** the editor widgets and
constraints of the edit layers (value maps for ``action`` and ``kind``, a range with unit for
``height``, NOT NULL and expression constraints), so QGIS's own digitizing and attribute forms
refuse a bad value. Three things depend on the layer or the language and are set after loading:

* the labels of value maps are translated (the stored value stays the English key);
* the elevation ramp of a DSM/DTM is spread over the layer's own 2–98 % range;
* orthophotos and mosaics use their alpha band when they have one.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Dict, List, Optional

from qgis.core import (
    QgsColorRampShader,
    QgsEditorWidgetSetup,
    QgsMapLayer,
    QgsRasterBandStats,
    QgsRasterLayer,
    QgsVectorLayer,
)

from ...algorithms.project.edits import EDIT_LAYERS
from ..i18n import tr

STYLES_DIR = Path(__file__).resolve().parents[2] / "resources" / "styles"
#: Layer kind (``photodem/kind`` without the ``edit:`` prefix for edit layers) → QML file.
KIND_STYLES: Dict[str, str] = {
    **{f"edit:{name}": f"edit_{name}.qml" for name in EDIT_LAYERS},
    "footprints": "footprints.qml",
    "stereo_models": "stereo_models.qml",
    "dsm": "dem_elevation.qml",
    "dtm": "dem_elevation.qml",
    "hillshade": "dem_hillshade.qml",
    "difference": "dem_difference.qml",
    "ortho": "ortho.qml",
    "mosaic": "ortho.qml",
    "seamlines": "seamlines.qml",
}
#: Share of the cells below/above the ends of the elevation ramp.
RAMP_CUT = (0.02, 0.98)


def value_labels() -> Dict[str, str]:
    """Translated labels of the stored values of the value maps (English key → label)."""
    labels = {"keep": tr("keep"), "remove": tr("remove"), "exclude": tr("exclude"),
              "breakline": tr("breakline"), "structure_line": tr("structure line"),
              "": tr("other values")}  # the renderers' catch-all category
    return labels


def constraint_descriptions() -> Dict[str, str]:
    """Translated descriptions of the expression constraints in the QML files (shown when
    a form refuses a value), by their English text."""
    return {"keep, remove or exclude": tr("keep, remove or exclude"),
            "breakline or structure_line": tr("breakline or structure_line"),
            "height between -500 m and 9000 m": tr("height between -500 m and 9000 m"),
            "a non-empty id": tr("a non-empty id")}


def style_path(kind: str) -> Optional[Path]:
    """The QML file of a layer kind, or ``None`` when the kind has none."""
    name = KIND_STYLES.get(kind)
    return STYLES_DIR / name if name else None


def apply_style(layer: QgsMapLayer, kind: str) -> bool:
    """Load the style of ``kind`` into ``layer`` and adapt it (module notes).

    Returns
    -------
    bool
        False when the kind has no style or QGIS could not load it (the layer keeps its
        default style).
    """
    path = style_path(kind)
    if path is None or not path.is_file():
        return False
    _message, ok = layer.loadNamedStyle(str(path))
    if not ok:
        return False
    if isinstance(layer, QgsVectorLayer):
        translate_value_maps(layer)
    elif isinstance(layer, QgsRasterLayer):
        if kind in ("dsm", "dtm"):
            stretch_ramp(layer)
        elif kind in ("ortho", "mosaic"):
            use_alpha_band(layer)
    layer.triggerRepaint()
    return True


def translate_value_maps(layer: QgsVectorLayer) -> None:
    """Replace the labels of every value map of ``layer`` by their translation (the stored
    values stay), the category labels of a categorised renderer and the descriptions of the
    expression constraints (shown when the form refuses a value) alike."""
    labels, descriptions = value_labels(), constraint_descriptions()
    for index, field in enumerate(layer.fields()):
        expression = field.constraints().constraintExpression()
        if expression:
            text = field.constraints().constraintDescription()
            layer.setConstraintExpression(index, expression, descriptions.get(text, text))
        setup = field.editorWidgetSetup()
        if setup.type() != "ValueMap":
            continue
        entries: List[Dict[str, Any]] = []
        for entry in setup.config().get("map", []):
            for label, value in entry.items():
                entries.append({labels.get(str(value), label): value})
        layer.setEditorWidgetSetup(index, QgsEditorWidgetSetup("ValueMap", {"map": entries}))
    renderer = layer.renderer()
    if renderer is not None and renderer.type() == "categorizedSymbol":
        for i, category in enumerate(renderer.categories()):
            label = labels.get(str(category.value()))
            if label:
                renderer.updateCategoryLabel(i, label)


def stretch_ramp(layer: QgsRasterLayer) -> None:
    """Spread the ramp of a pseudocolour renderer (items given on 0…1) over the layer's
    2–98 % range (estimated from a sample of the cells)."""
    renderer = layer.renderer()
    if renderer is None or renderer.type() != "singlebandpseudocolor":
        return
    low, high = _cut_range(layer)
    if high <= low:
        high = low + 1.0
    shader_fn = renderer.shader().rasterShaderFunction()
    items = [QgsColorRampShader.ColorRampItem(low + item.value * (high - low), item.color,
                                              _height_label(low + item.value * (high - low)))
             for item in shader_fn.colorRampItemList()]
    shader_fn.setColorRampItemList(items)
    if hasattr(shader_fn, "legendSettings"):  # version: QGIS ≥ 3.18; the legend lists "52.4 m"…
        legend = shader_fn.legendSettings()
        legend.setUseContinuousLegend(False)
        shader_fn.setLegendSettings(legend)
    shader_fn.setMinimumValue(low)
    shader_fn.setMaximumValue(high)
    renderer.setClassificationMin(low)
    renderer.setClassificationMax(high)


def _height_label(value: float) -> str:
    return f"{value:.1f} m"


def _cut_range(layer: QgsRasterLayer) -> tuple:
    """The 2 % and 98 % quantiles of band 1 (from QGIS's histogram), else min and max."""
    provider = layer.dataProvider()
    try:
        low, high = provider.cumulativeCut(1, RAMP_CUT[0], RAMP_CUT[1], layer.extent(), 250000)
    except TypeError:  # pragma: no cover - binding variants return a tuple of three
        low, high = float("nan"), float("nan")
    if low == low and high == high and high > low:  # not NaN
        return float(low), float(high)
    stats = provider.bandStatistics(1, QgsRasterBandStats.Min | QgsRasterBandStats.Max)
    return float(stats.minimumValue), float(stats.maximumValue)


def use_alpha_band(layer: QgsRasterLayer) -> None:
    """Use band 4 as alpha of an RGB renderer when the raster has four bands or more."""
    renderer = layer.renderer()
    if renderer is not None and layer.bandCount() >= 4 and hasattr(renderer, "setAlphaBand"):
        renderer.setAlphaBand(4)


__all__ = ["KIND_STYLES", "STYLES_DIR", "apply_style", "stretch_ramp", "style_path",
           "translate_value_maps", "use_alpha_band", "value_labels"]
