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
"""

from __future__ import annotations

from collections import OrderedDict
from pathlib import Path
from typing import Any, Dict, Iterable, List, Optional, Tuple, Union

import fiona
from shapely.geometry import mapping, shape

from ..errors import InputError

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


def _crs_wkt(crs: str) -> str:
    import pyproj

    try:
        return pyproj.CRS.from_user_input(crs).to_wkt()
    except Exception as exc:  # pyproj.exceptions.CRSError
        raise InputError(f"Cannot use the CRS '{crs}' for edits.gpkg: {exc}") from exc


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
    from ..raster.io import atomic_output

    path = Path(path)
    if path.exists():
        raise InputError(
            f"'{path}' exists already; PhotoDEM does not overwrite the operator's edits. "
            "Delete or rename it first if you really want an empty one."
        )
    wkt = _crs_wkt(crs)
    with atomic_output(path) as tmp:
        for layer, (geom_type, fields) in EDIT_LAYERS.items():
            schema = {"geometry": geom_type, "properties": OrderedDict(fields)}
            with fiona.open(str(tmp), "w", driver="GPKG", layer=layer, schema=schema,
                            crs_wkt=wkt):
                pass
    return path


def add_features(path: PathLike, layer: str,
                 features: Iterable[Tuple[Any, Dict[str, Any]]]) -> int:
    """Append ``(shapely geometry, properties)`` pairs to a layer of ``edits.gpkg``.

    Missing properties are written as empty; unknown ones are an error. Returns the number of
    features written.
    """
    if layer not in EDIT_LAYERS:
        raise InputError(f"'{layer}' is not an edit layer; use one of {', '.join(EDIT_LAYERS)}.")
    fields = EDIT_LAYERS[layer][1]
    records = []
    for geom, props in features:
        props = dict(props or {})
        unknown = sorted(set(props) - set(fields))
        if unknown:
            raise InputError(f"Layer '{layer}' has no field(s) {', '.join(unknown)}.")
        if layer == "exclusion_areas" and props.get("action") not in (None, *EXCLUSION_ACTIONS):
            raise InputError(f"exclusion_areas.action must be one of {EXCLUSION_ACTIONS}.")
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
        raise InputError(f"Edits file '{path}' not found; create it with project_create.")
    if layer not in fiona.listlayers(str(path)):
        raise InputError(f"'{path}' has no layer '{layer}'.")
    out: List[Tuple[Any, Dict[str, Any]]] = []
    with fiona.open(str(path), layer=layer) as src:
        for feat in src:
            geom = feat["geometry"]
            if geom is None:
                continue
            # fiona ≥ 1.10 returns Geometry objects, 1.9 dicts; shape() takes both
            geom = geom if isinstance(geom, dict) else geom.__geo_interface__
            out.append((shape(geom), dict(feat["properties"])))
    return out


__all__ = ["EDIT_LAYERS", "EXCLUSION_ACTIONS", "add_features", "create_edits", "read_layer"]


def read_geometries(path: PathLike, kinds: Tuple[str, ...], crs: Any,
                    layers: Optional[Tuple[str, ...]] = None,
                    skip_keep: bool = False) -> List[Any]:
    """Shapely geometries of the given kinds (``"Polygon"``, ``"LineString"``) from a vector file.

    Every layer (or only ``layers``) is read; geometries are transformed to ``crs`` when the
    file has another CRS. ``skip_keep`` drops features whose ``action`` is ``keep`` (exclusion
    areas of edits.gpkg).
    """
    from rasterio.crs import CRS
    from rasterio.warp import transform_geom

    if crs is not None and not isinstance(crs, CRS):
        crs = CRS.from_user_input(crs)

    path = Path(path)
    if not path.is_file():
        raise InputError(f"Vector file '{path}' does not exist.")
    try:
        names = fiona.listlayers(str(path))
    except Exception as exc:  # driver-specific errors
        raise InputError(f"Cannot read the vector file '{path.name}': {exc}") from exc
    out: List[Any] = []
    for name in names:
        if layers is not None and name not in layers:
            continue
        with fiona.open(str(path), layer=name) as src:
            src_crs = CRS.from_wkt(src.crs_wkt) if src.crs_wkt else None
            for feat in src:
                geom = feat["geometry"]
                if geom is None:
                    continue
                geom = geom if isinstance(geom, dict) else geom.__geo_interface__
                if not any(k in geom["type"] for k in kinds):
                    continue
                if skip_keep and (dict(feat["properties"]).get("action") or "") == "keep":
                    continue
                if crs is not None and src_crs is not None and src_crs != crs:
                    geom = transform_geom(src_crs, crs, geom)
                out.append(shape(geom))
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
