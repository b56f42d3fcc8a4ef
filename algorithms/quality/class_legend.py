"""Names of the codes of a class raster: from a legend file or the raster's QGIS style.

A class raster stores codes (1, 2, 3 …); reports should say "building", not "3". The names
come, in this order, from

1. a legend the operator gives: a CSV/TXT table ``value,name`` (a header line is optional;
   ``;`` or tab also separate) or a QGIS style (``.qml``);
2. the QGIS style beside the raster (``landcover.qml`` for ``landcover.tif``), which QGIS
   itself loads as the layer's default style: the labels of a paletted/unique-values renderer
   or of a pseudocolour ramp's items.

No legend found gives an empty mapping: the reports then show the codes.
"""

from __future__ import annotations

import csv
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Dict, Mapping, Optional, Tuple, Union
from xml.sax.saxutils import quoteattr

from ..errors import InputError
from ..raster.io import atomic_output

PathLike = Union[str, Path]


def code_key(value: Union[str, float, int]) -> str:
    """The key of a class code as the statistics use it (``3.0`` → ``"3"``)."""
    v = float(value)
    return str(int(v)) if v.is_integer() else f"{v:g}"


def _from_qml(path: Path) -> Dict[str, str]:
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as exc:
        raise InputError(f"Cannot read the class legend '{path}': {exc}") from exc
    names: Dict[str, str] = {}
    # paletted renderer: <paletteEntry value= label=>; pseudocolour: <item value= label=>
    for tag in ("paletteEntry", "item"):
        for node in root.iter(tag):
            value, label = node.get("value"), (node.get("label") or "").strip()
            if value is None or not label:
                continue
            try:
                names.setdefault(code_key(value), label)
            except ValueError:
                continue
    return names


def _from_table(path: Path) -> Dict[str, str]:
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"Cannot read the class legend '{path}': {exc}") from exc
    lines = text.splitlines()
    first = next((ln for ln in lines if ln.strip() and not ln.lstrip().startswith("#")), "")
    delimiter = next((d for d in ("\t", ";", ",") if d in first), ",")
    names: Dict[str, str] = {}
    for n, row in enumerate(csv.reader(lines, delimiter=delimiter), start=1):
        if len(row) < 2 or not row[0].strip() or row[0].lstrip().startswith("#"):
            continue
        try:
            key = code_key(row[0].strip())
        except ValueError:
            if n == 1:  # a header line
                continue
            raise InputError(f"Class legend '{path.name}', line {n}: '{row[0]}' is not a class "
                             "code; write one 'value,name' per line.") from None
        names[key] = row[1].strip()
    if not names:
        raise InputError(f"The class legend '{path.name}' holds no 'value,name' lines.")
    return names


def read_class_legend(classes: Optional[PathLike] = None,
                      legend: Optional[PathLike] = None) -> Dict[str, str]:
    """Names of the class codes.

    Parameters
    ----------
    classes : path, optional
        The class raster; its QGIS style beside it (same stem, ``.qml``) is read when no
        ``legend`` is given.
    legend : path, optional
        A ``value,name`` table (``.csv``/``.txt``) or a QGIS style (``.qml``).

    Returns
    -------
    dict
        Code key (as :func:`code_key`) → name; empty when nothing names the codes.

    Raises
    ------
    InputError
        A given legend that is missing or unreadable.
    """
    if legend is not None and str(legend) != "":
        path = Path(legend)
        if not path.is_file():
            raise InputError(f"The class legend '{path}' does not exist.")
        return _from_qml(path) if path.suffix.lower() == ".qml" else _from_table(path)
    if classes is None:
        return {}
    style = Path(classes).with_suffix(".qml")
    if not style.is_file():
        return {}
    try:
        return _from_qml(style)
    except InputError:
        return {}  # a broken default style only costs the names


def class_label(key: str, names: Dict[str, str]) -> str:
    """``"building (3)"`` when ``key`` has a name, else the key itself."""
    name = names.get(key)
    return f"{name} ({key})" if name else key


def class_style_qml(classes: Mapping[int, Tuple[str, str]]) -> str:
    """A QGIS paletted style: code → (name, colour ``#rrggbb``); the names are the legend."""
    entries = "\n".join(
        f'        <paletteEntry value="{int(code)}" color={quoteattr(colour)} alpha="255" '
        f"label={quoteattr(name)}/>" for code, (name, colour) in sorted(classes.items()))
    return ("<!DOCTYPE qgis PUBLIC 'http://mrcc.com/qgis.dtd' 'SYSTEM'>\n"
            '<qgis version="3.22.0" styleCategories="AllStyleCategories">\n  <pipe>\n'
            '    <rasterrenderer type="paletted" band="1" opacity="1" alphaBand="-1" '
            'nodataColor="">\n      <colorPalette>\n' + entries + "\n      </colorPalette>\n"
            "    </rasterrenderer>\n  </pipe>\n</qgis>\n")


def write_class_style(raster: PathLike, classes: Mapping[int, Tuple[str, str]]) -> Path:
    """Write :func:`class_style_qml` beside ``raster`` as ``<stem>.qml`` (QGIS loads it as the
    layer's default style; :func:`read_class_legend` reads the names from it)."""
    target = Path(raster).with_suffix(".qml")
    with atomic_output(target) as tmp:
        tmp.write_text(class_style_qml(classes), encoding="utf-8")
    return target


__all__ = ["class_label", "class_style_qml", "code_key", "read_class_legend",
           "write_class_style"]
