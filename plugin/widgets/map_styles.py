"""Vector styles of the standalone map, read from OUR QGIS styles (``resources/styles/*.qml``).

QGIS draws the edit layers, footprints, stereo models and seamlines with these QML files; the
standalone map reads the same files with :mod:`xml.etree` so both show the same colours: the
first simple layer of each symbol (``SimpleFill``, ``SimpleLine``, ``SimpleMarker``; a
``LinePatternFill`` becomes a hatched brush), the categories of a categorized renderer (e.g.
exclusion areas by ``action``) and a simple label field. A style that can't be read falls back
to :data:`DEFAULT_STYLE` and the reason is logged.
"""

from __future__ import annotations

import logging
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field, replace
from functools import cache
from pathlib import Path
from typing import Any, Dict, Mapping, Optional, Tuple

from ..qt import QtCore, QtGui

LOG = logging.getLogger(__name__)

#: Folder of the QML styles (the package root's ``resources/styles``).
STYLES_DIR = Path(__file__).resolve().parents[2] / "resources" / "styles"
#: Pixels per millimetre at 96 dpi (QGIS widths and sizes are in mm).
PX_PER_MM = 96.0 / 25.4
#: Layer kind → QML file (``edit:<layer>`` → ``edit_<layer>.qml``).
KIND_FILES = {"footprints": "footprints.qml", "stereo_models": "stereo_models.qml",
              "seamlines": "seamlines.qml"}
RGBA = Tuple[int, int, int, int]


@dataclass(frozen=True)
class Symbol:
    """How one feature is drawn (pixels at 96 dpi; colours RGBA 0–255).

    ``brush_style`` is ``solid``, ``no`` or ``hatch``; ``marker`` a QGIS marker name
    (``circle``, ``square``, ``triangle``, ``cross``, ``cross2``, ``diamond`` …).
    """

    pen: RGBA = (60, 60, 60, 255)
    pen_width: float = 1.0
    pen_style: str = "solid"
    brush: RGBA = (0, 0, 0, 0)
    brush_style: str = "no"
    marker: str = "circle"
    marker_size: float = 8.0
    marker_fill: RGBA = (230, 230, 230, 255)

    def qpen(self) -> QtGui.QPen:
        """The outline / line pen (cosmetic: width in pixels)."""
        if self.pen_style == "no":
            return QtGui.QPen(QtCore.Qt.NoPen)
        pen = QtGui.QPen(QtGui.QColor(*self.pen), max(self.pen_width, 1.0))
        pen.setCosmetic(True)
        pen.setStyle({"dash": QtCore.Qt.DashLine, "dot": QtCore.Qt.DotLine,
                      "dash dot": QtCore.Qt.DashDotLine}.get(self.pen_style,
                                                             QtCore.Qt.SolidLine))
        pen.setJoinStyle(QtCore.Qt.RoundJoin)
        return pen

    def qbrush(self) -> QtGui.QBrush:
        """The polygon fill."""
        if self.brush_style == "no" or self.brush[3] == 0:
            return QtGui.QBrush(QtCore.Qt.NoBrush)
        style = QtCore.Qt.BDiagPattern if self.brush_style == "hatch" else QtCore.Qt.SolidPattern
        return QtGui.QBrush(QtGui.QColor(*self.brush), style)


@dataclass(frozen=True)
class Style:
    """A layer style: one symbol, or symbols by the value of ``attribute``; a label field."""

    symbol: Symbol = Symbol()
    attribute: str = ""
    categories: Dict[str, Symbol] = field(default_factory=dict)
    label_field: str = ""
    label_colour: RGBA = (40, 40, 40, 255)
    label_size: float = 7.0  # points
    source: str = ""  # the QML file it came from ("" = the default)

    def symbol_for(self, attributes: Optional[Mapping[str, Any]]) -> Symbol:
        """The symbol of a feature with ``attributes``."""
        if self.attribute and attributes is not None:
            value = attributes.get(self.attribute)
            key = "" if value is None else str(value)
            if key in self.categories:
                return self.categories[key]
        return self.symbol


DEFAULT_STYLE = Style(Symbol(pen=(200, 40, 120, 255), pen_width=1.5,
                             brush=(200, 40, 120, 40), brush_style="solid",
                             marker_fill=(200, 40, 120, 255)))


def _rgba(text: Optional[str], fallback: RGBA) -> RGBA:
    """A QGIS colour ``r,g,b,a`` (QGIS ≥ 3.28 may add ``,rgb:…``)."""
    if not text:
        return fallback
    parts = text.split(",")
    try:
        values = [int(float(p)) for p in parts[:4]]
    except ValueError:
        return fallback
    if len(values) == 3:
        values.append(255)
    return tuple(values) if len(values) == 4 else fallback  # type: ignore[return-value]


def _options(layer: ET.Element) -> Dict[str, str]:
    """A symbol layer's properties (``<Option>`` of 3.22, ``<prop>`` of older files)."""
    props = {p.get("k", ""): p.get("v", "") for p in layer.findall("prop")}
    mapping = layer.find("Option")
    if mapping is not None:
        for option in mapping.findall("Option"):
            if option.get("name"):
                props[option.get("name", "")] = option.get("value", "")
    return props


def _width(props: Mapping[str, str], key: str, fallback: float) -> float:
    try:
        value = float(props.get(key, ""))
    except ValueError:
        return fallback
    unit = props.get(key + "_unit", "MM")
    return value * PX_PER_MM if unit == "MM" else value


def symbol_from_xml(element: ET.Element) -> Symbol:
    """The :class:`Symbol` of a QML ``<symbol>``: its first drawable layer, hatching added."""
    symbol = Symbol()
    for layer in element.findall("layer"):
        if layer.get("enabled", "1") == "0":
            continue
        cls, props = layer.get("class", ""), _options(layer)
        if cls == "SimpleFill":
            symbol = replace(symbol, brush=_rgba(props.get("color"), symbol.brush),
                             brush_style=props.get("style", "solid"),
                             pen=_rgba(props.get("outline_color"), symbol.pen),
                             pen_style=props.get("outline_style", "solid"),
                             pen_width=_width(props, "outline_width", 1.0))
        elif cls == "LinePatternFill" and symbol.brush_style in ("no", "solid"):
            if symbol.brush_style == "no" or symbol.brush[3] < 80:
                symbol = replace(symbol, brush=_rgba(props.get("color"), symbol.pen),
                                 brush_style="hatch")
        elif cls == "SimpleLine":
            symbol = replace(symbol, pen=_rgba(props.get("line_color"), symbol.pen),
                             pen_style=props.get("line_style", "solid"),
                             pen_width=_width(props, "line_width", 1.0))
        elif cls == "SimpleMarker":
            symbol = replace(symbol, marker=props.get("name", "circle") or "circle",
                             marker_fill=_rgba(props.get("color"), symbol.marker_fill),
                             marker_size=_width(props, "size", 8.0),
                             pen=_rgba(props.get("outline_color"), symbol.pen),
                             pen_style=props.get("outline_style", "solid"),
                             pen_width=_width(props, "outline_width", 1.0))
        else:
            continue
        if cls != "SimpleFill":  # a fill is followed by its hatching; others are complete
            break
    return symbol


def _label(root: ET.Element) -> Tuple[str, RGBA, float]:
    """The first field of a simple labeling's expression, its colour and size."""
    if root.get("labelsEnabled", "0") != "1":
        return "", (40, 40, 40, 255), 7.0
    text = root.find("./labeling/settings/text-style")
    if text is None:
        return "", (40, 40, 40, 255), 7.0
    expression = text.get("fieldName", "")
    match = re.search(r'"([^"]+)"', expression)
    name = match.group(1) if match else expression.strip()
    try:
        size = float(text.get("fontSize", "7"))
    except ValueError:
        size = 7.0
    return name, _rgba(text.get("textColor"), (40, 40, 40, 255)), size


def parse_qml(path: Path) -> Style:
    """The :class:`Style` of a QML file; raises on a file that isn't one."""
    root = ET.parse(str(path)).getroot()
    renderer = root.find("renderer-v2")
    if renderer is None:
        raise ValueError("no vector renderer (renderer-v2)")
    symbols = {s.get("name", ""): symbol_from_xml(s)
               for s in renderer.findall("./symbols/symbol")}
    if not symbols:
        raise ValueError("no symbols")
    label_field, label_colour, label_size = _label(root)
    common: Dict[str, Any] = {"label_field": label_field, "label_colour": label_colour,
                              "label_size": label_size, "source": path.name}
    if renderer.get("type") == "categorizedSymbol":
        categories = {c.get("value", ""): symbols[c.get("symbol", "")]
                      for c in renderer.findall("./categories/category")
                      if c.get("symbol", "") in symbols and c.get("render", "true") == "true"}
        fallback = categories.get("", next(iter(symbols.values())))
        return Style(fallback, renderer.get("attr", ""), categories, **common)
    return Style(symbols.get("0", next(iter(symbols.values()))), **common)


def qml_for_kind(kind: str) -> Optional[Path]:
    """Our QML file for a layer kind, or None when there is none."""
    if kind.startswith("edit:"):
        return STYLES_DIR / f"edit_{kind.split(':', 1)[1]}.qml"
    name = KIND_FILES.get(kind)
    return STYLES_DIR / name if name else None


@cache
def style_for_kind(kind: str) -> Style:
    """The style of a layer kind from our QML, or :data:`DEFAULT_STYLE` (reason logged)."""
    path = qml_for_kind(kind)
    if path is None:
        return DEFAULT_STYLE
    try:
        return parse_qml(path)
    except Exception as exc:  # a broken or missing file: the map still draws
        LOG.warning("style %s unreadable (%s); default style used", path.name, exc)
        return DEFAULT_STYLE


__all__ = ["DEFAULT_STYLE", "STYLES_DIR", "Style", "Symbol", "parse_qml", "qml_for_kind",
           "style_for_kind", "symbol_from_xml"]
