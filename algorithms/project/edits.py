"""The operator's edits: ``edits.gpkg`` beside ``project.toml``.

One GeoPackage layer per kind of edit, all in the project CRS, so that operators open and edit
the file directly in QGIS:

=================  ================  ===============================================================
layer              geometry          fields
=================  ================  ===============================================================
start_points       Point             ``height`` (float, m), ``note``
exclusion_areas    Polygon           ``action`` (``keep`` | ``remove`` | ``exclude``), ``note``
boundaries         Polygon           ``name``
breaklines         3D LineString     ``kind``, ``note``
ground_points      3D Point          ``note``
seamlines          LineString        ``note``
check_points       3D Point          ``id``
=================  ================  ===============================================================

Every feature is checked when it is read (:func:`check_feature`, for :func:`read_layer` and
:func:`read_geometries` alike):

* ``exclusion_areas.action`` must be empty (= ``remove``) or one of :data:`EXCLUSION_ACTIONS`
  (case and surrounding blanks do not matter); any other value is an error naming the feature;
* an invalid polygon (self-intersecting, a bow tie…) of any polygon layer is repaired
  (``make_valid``; ``buffer(0)`` where shapely lacks it) with a warning naming layer and fid;
  one that cannot be repaired is an error;
* a 2-D breakline (digitised without Z) is used as a barrier only — the surface may jump
  across it, but it gives no heights — with a warning naming it. 3-D breaklines also give their
  heights (matching, interpolation).
"""

from __future__ import annotations

import os
import sqlite3
import stat
from collections import OrderedDict
from pathlib import Path
from typing import Any, Dict, Iterable, List, Optional, Tuple, Union

import fiona
import pyproj
from rasterio.crs import CRS
from shapely.geometry import mapping, shape
from shapely.ops import unary_union
from shapely.validation import explain_validity

from ..errors import InputError, Message, msg
from ..input_errors import check_encodable, reading, warn_input
from ..raster.io import atomic_output
from .vector_io import read_features, to_crs

PathLike = Union[str, Path]

#: Layer name → (geometry type, fields) of ``edits.gpkg``.
EDIT_LAYERS: Dict[str, Tuple[str, OrderedDict[str, str]]] = {
    "start_points": ("Point", OrderedDict([("height", "float"), ("note", "str")])),
    "exclusion_areas": ("Polygon", OrderedDict([("action", "str"), ("note", "str")])),
    "boundaries": ("Polygon", OrderedDict([("name", "str")])),
    "breaklines": ("3D LineString", OrderedDict([("kind", "str"), ("note", "str")])),
    "ground_points": ("3D Point", OrderedDict([("note", "str")])),
    "seamlines": ("LineString", OrderedDict([("note", "str")])),
    "check_points": ("3D Point", OrderedDict([("id", "str")])),
}

#: Allowed values of ``exclusion_areas.action``.
EXCLUSION_ACTIONS = ("keep", "remove", "exclude")

#: The values the editing tools offer for ``breaklines.kind`` (seed-000 §2.10: breaklines and
#: structure lines). Other texts are kept (the kind steers no algorithm yet), with a warning.
BREAKLINE_KINDS = ("breakline", "structure_line")


def _where(path: PathLike, layer: str, fid: Any) -> Message:
    return msg("'{file}' layer {layer}, feature {fid}", file=Path(path).name, layer=layer,
               fid=fid)


def check_action(value: Any, where: Union[str, Message]) -> Optional[str]:
    """The normalised ``action`` of an exclusion area (``None`` when empty = ``remove``).

    Raises
    ------
    InputError
        For any other value, naming the feature and the allowed values.
    """
    if value is None or (isinstance(value, str) and not value.strip()):
        return None
    text = str(value).strip().lower()
    if text not in EXCLUSION_ACTIONS:
        raise InputError.of("{where}: action '{value}' is not one of {actions} (empty = remove); "
                            "fix it in edits.gpkg.", where=where, value=value,
                            actions=", ".join(EXCLUSION_ACTIONS))
    return text


def kind_message(value: Any, where: str) -> Optional[str]:
    """A warning for a breakline ``kind`` that is not one of :data:`BREAKLINE_KINDS`, or
    ``None`` (empty = ``breakline``)."""
    if value is None or (isinstance(value, str) and not value.strip()):
        return None
    if str(value).strip().lower() in BREAKLINE_KINDS:
        return None
    return (f"{where}: kind '{value}' is not one of {', '.join(BREAKLINE_KINDS)}; the line is "
            "used as a breakline.")


def repaired_polygon(geom: Any) -> Optional[Any]:
    """The polygonal part of ``geom`` repaired, or ``None`` when nothing of it is left.

    ``shapely.validation.make_valid`` (shapely ≥ 1.8) keeps every part of a bow tie;
    ``buffer(0)`` is the fallback. Only the polygonal parts of the result are kept. A valid
    polygon is returned as it is. Shared by the run-time reader and the editing tools.
    """
    if geom.is_valid:
        return geom
    try:  # a version check, not a cycle: make_valid came with shapely 1.8
        from shapely.validation import make_valid

        fixed = make_valid(geom)
    except ImportError:  # pragma: no cover - shapely < 1.8
        fixed = geom.buffer(0)
    parts = [g for g in getattr(fixed, "geoms", [fixed])
             if g.geom_type in ("Polygon", "MultiPolygon") and not g.is_empty]
    fixed = unary_union(parts) if parts else None
    if fixed is None or fixed.is_empty or fixed.area <= 0:
        return None
    return fixed


def repair_polygon(geom: Any, where: Union[str, Message]) -> Any:
    """``geom`` if it is a valid polygon, else its repaired form (:func:`repaired_polygon`),
    with a warning.

    Raises
    ------
    InputError
        When nothing of the polygon is left after the repair.
    """
    if geom.is_valid:
        return geom
    reason = explain_validity(geom)
    fixed = repaired_polygon(geom)
    if fixed is None:
        raise InputError.of("{where}: the polygon is invalid ({reason}) and nothing is left "
                            "after repairing it; redraw it in edits.gpkg.", where=where,
                            reason=reason)  # GEOS's reason stays as it is
    warn_input(f"{where}: the polygon is invalid ({reason}); it is used repaired (area "
               f"{geom.area:.1f} → {fixed.area:.1f} m²). Check it and fix it in QGIS.")
    return fixed


def flat_breakline_message(layer: str, geom: Any, where: Union[str, Message]) -> Optional[str]:
    """The warning for a breakline without heights (2-D), or ``None``."""
    if layer == "breaklines" and "LineString" in geom.geom_type and not geom.has_z:
        return (f"{where}: the breakline has no heights (2-D); it only separates the surface "
                "and gives no heights. Digitise it with Z to use its heights.")
    return None


def check_feature(path: PathLike, layer: str, fid: Any, geom: Any,
                  props: Dict[str, Any]) -> Tuple[Any, Dict[str, Any]]:
    """One feature as read, checked and repaired (see the module notes).

    Returns
    -------
    (geometry, properties)
        The polygon repaired if it was invalid, ``action`` normalised.

    Raises
    ------
    InputError
        For an unknown exclusion action or a polygon that cannot be repaired.
    """
    where = _where(path, layer, fid)
    if layer == "exclusion_areas" and "action" in props:
        props = {**props, "action": check_action(props.get("action"), where)}
    if geom.geom_type in ("Polygon", "MultiPolygon"):
        geom = repair_polygon(geom, where)
    flat = flat_breakline_message(layer, geom, where)
    if flat:
        warn_input(flat)
    return geom, props


def _crs_wkt(crs: str) -> str:
    try:
        return pyproj.CRS.from_user_input(crs).to_wkt()
    except Exception as exc:  # pyproj.exceptions.CRSError
        raise InputError.of("Cannot use the CRS '{crs}' for edits.gpkg: {error}", crs=crs,
                            error=exc) from exc


def create_edits(path: PathLike, crs: str) -> Path:
    """Create an empty ``edits.gpkg`` with all edit layers (see module notes) in ``crs``.

    The file is written under a temporary name and renamed when complete. An existing file is
    never overwritten (it holds the operator's work).

    Parameters
    ----------
    path : path
        The GeoPackage to create (usually ``<project>/edits.gpkg``).
    crs : str
        Project CRS (WKT, ``EPSG:xxxx`` or PROJ string).

    Raises
    ------
    InputError
        When ``path`` exists or the CRS is not understood.
    """
    path = Path(path)
    if path.exists():
        raise InputError.of(
            "'{path}' exists already; PhotoDEM does not overwrite the operator's edits. "
            "Delete or rename it first if you really want an empty one.", path=path)
    wkt = _crs_wkt(crs)
    with atomic_output(path) as tmp:
        for layer, (geom_type, fields) in EDIT_LAYERS.items():
            schema = {"geometry": geom_type, "properties": OrderedDict(fields)}
            with fiona.open(str(tmp), "w", driver="GPKG", layer=layer, schema=schema,
                            crs_wkt=wkt):
                pass
    return path


def edits_access(path: PathLike) -> Optional[Tuple[str, str]]:
    """Why ``edits.gpkg`` cannot take edits now, or ``None`` when it can.

    Returns
    -------
    tuple (kind, detail) or None
        ``kind`` is ``"missing"``, ``"read-only"`` (the file or its folder, where SQLite
        writes its journal, is not writable) or ``"locked"`` (another program holds a write
        lock, or the file is not a database); ``detail`` says more in English.

    Notes
    -----
    The lock test opens a write transaction and rolls it back at once: nothing is written.
    The permission bits are checked as well as ``os.access``, which says yes to root for any
    file.
    """
    path = Path(path)
    if not path.is_file():
        return "missing", f"{path} does not exist"
    bits = stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH
    if not (os.access(path, os.W_OK) and path.stat().st_mode & bits):
        return "read-only", f"{path} is read-only"
    if not (os.access(path.parent, os.W_OK) and path.parent.stat().st_mode & bits):
        return "read-only", f"the folder {path.parent} is read-only"
    try:
        con = sqlite3.connect(f"file:{path}?mode=rw", uri=True, timeout=0.2)
        try:
            con.execute("BEGIN IMMEDIATE")
            con.rollback()
        finally:
            con.close()
    except sqlite3.Error as exc:
        return "locked", str(exc)
    return None


def missing_edit_layers(path: PathLike) -> List[str]:
    """The layers of :data:`EDIT_LAYERS` that ``edits.gpkg`` lacks (in their order)."""
    with reading(Path(path), "GeoPackage"):
        present = set(fiona.listlayers(str(path)))
    return [name for name in EDIT_LAYERS if name not in present]


def add_edit_layers(path: PathLike, crs: str, names: Iterable[str]) -> List[str]:
    """Add the empty edit layers ``names`` to an existing ``edits.gpkg``; the layers it holds
    (the operator's work) are not touched. Layers that exist are skipped.

    Returns the names of the layers added.

    Raises
    ------
    InputError
        For a name that is no edit layer or a CRS that is not understood.
    """
    wanted = [check_layer(name) for name in names]
    wkt = _crs_wkt(crs)
    added = []
    for name in wanted:
        if name not in missing_edit_layers(path):
            continue
        geom_type, fields = EDIT_LAYERS[name]
        schema = {"geometry": geom_type, "properties": OrderedDict(fields)}
        with fiona.open(str(path), "w", driver="GPKG", layer=name, schema=schema, crs_wkt=wkt):
            pass
        added.append(name)
    return added


def check_layer(layer: str) -> str:
    """``layer`` if it is a layer of ``edits.gpkg``.

    Raises
    ------
    InputError
        Naming the layer and the edit layers.
    """
    if layer not in EDIT_LAYERS:
        raise InputError.of("'{layer}' is not an edit layer; use one of {layers}.", layer=layer,
                            layers=", ".join(EDIT_LAYERS))
    return layer


def check_fields(layer: str, props: Optional[Dict[str, Any]]) -> Dict[str, Any]:
    """The attributes of one new feature of ``layer``, checked and normalised.

    Unknown fields are an error; ``action`` of an exclusion area is normalised by
    :func:`check_action`.

    Raises
    ------
    InputError
        Naming the layer and the offending field or value.
    """
    fields = EDIT_LAYERS[check_layer(layer)][1]
    props = dict(props or {})
    unknown = sorted(set(props) - set(fields))
    if unknown:
        raise InputError.of("Layer '{layer}' has no field(s) {fields}.", layer=layer,
                            fields=", ".join(unknown))
    if layer == "exclusion_areas":
        props["action"] = check_action(props.get("action"), msg("Layer '{layer}'", layer=layer))
    return props


def add_features(path: PathLike, layer: str,
                 features: Iterable[Tuple[Any, Dict[str, Any]]]) -> int:
    """Append ``(shapely geometry, properties)`` pairs to a layer of ``edits.gpkg``.

    Missing properties are written as empty; unknown ones are an error. Returns the number of
    features written.
    """
    fields = EDIT_LAYERS[check_layer(layer)][1]
    records = []
    for geom, props in features:
        props = check_fields(layer, props)
        records.append({"geometry": mapping(geom),
                        "properties": OrderedDict((k, props.get(k)) for k in fields)})
    with fiona.open(str(path), "a", driver="GPKG", layer=layer) as dst:
        dst.writerecords(records)
    return len(records)


def read_layer(path: PathLike, layer: str) -> List[Tuple[Any, Dict[str, Any]]]:
    """All features of one layer as ``(shapely geometry, properties dict)``.

    Features without geometry are skipped (QGIS allows attribute-only rows).

    Raises
    ------
    InputError
        When the file or the layer does not exist.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError.of("Edits file '{path}' not found; create it with project_create.",
                            path=path)
    out: List[Tuple[Any, Dict[str, Any]]] = []
    with reading(path, "GeoPackage"):
        if layer not in fiona.listlayers(str(path)):
            raise InputError.of("'{path}' has no layer '{layer}'.", path=path, layer=layer)
        for feat in read_features(path, (layer,), "GeoPackage"):
            out.append(check_feature(path, layer, feat.fid, shape(feat.geometry),
                                     feat.properties))
    return out


def read_geometries(path: PathLike, kinds: Tuple[str, ...], crs: Any,
                    layers: Optional[Tuple[str, ...]] = None,
                    skip_keep: bool = False) -> List[Any]:
    """Shapely geometries of the given kinds (``"Polygon"``, ``"LineString"``) from a vector file.

    Every layer (or only ``layers``) is read; geometries are transformed to ``crs`` when the
    file has another CRS. ``skip_keep`` drops features whose ``action`` is ``keep`` (exclusion
    areas of edits.gpkg).
    """
    if crs is not None and not isinstance(crs, CRS):
        crs = CRS.from_user_input(crs)
    path = Path(path)
    if not path.is_file():
        raise InputError.of("Vector file '{path}' does not exist.", path=path)
    check_encodable(path, "vector file")
    out: List[Any] = []
    with reading(path, "vector file"):
        for feat in read_features(path, layers):
            if not any(k in feat.geometry["type"] for k in kinds):
                continue
            checked, props = check_feature(path, feat.layer, feat.fid, shape(feat.geometry),
                                           feat.properties)
            if skip_keep and props.get("action") == "keep":
                continue
            if crs is not None and feat.crs is not None and feat.crs != crs:
                checked = shape(to_crs(mapping(checked), feat.crs, crs))
            out.append(checked)
    return out


def read_constraints(path: PathLike, crs: Any = None) -> Tuple[List[Any], List[Any], List[Any]]:
    """The operator's matching/interpolation constraints from ``edits.gpkg``.

    Returns exclusion polygons (without those whose ``action`` is ``keep``: there the surface
    stays as measured), boundary polygons and breaklines (3-D where digitised), transformed to
    ``crs`` when given. A missing layer gives an empty list.
    """
    return (read_geometries(path, ("Polygon",), crs, ("exclusion_areas",), skip_keep=True),
            read_geometries(path, ("Polygon",), crs, ("boundaries",)),
            read_geometries(path, ("LineString",), crs, ("breaklines",)))


__all__ = [
    "BREAKLINE_KINDS",
    "EDIT_LAYERS",
    "EXCLUSION_ACTIONS",
    "add_edit_layers",
    "add_features",
    "check_action",
    "check_feature",
    "check_fields",
    "check_layer",
    "create_edits",
    "edits_access",
    "flat_breakline_message",
    "kind_message",
    "missing_edit_layers",
    "read_constraints",
    "read_geometries",
    "read_layer",
    "repair_polygon",
    "repaired_polygon",
]
