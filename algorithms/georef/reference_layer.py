"""Reference objects: polygons of a vector layer, or regions of a georeferenced raster.

Vector data split one visible object (a forest) into many parts along lines nobody sees in an
image (parcel borders, paths), so the polygons of the selected class are **dissolved** where
they touch (a snap tolerance closes digitising gaps), exploded into single polygons and reduced
to their outer rings (seed-001 §2.5). Matching runs in a projected CRS: the layer's own when it
is projected, else the UTM zone of the layer's centre — never in degrees.

A raster reference (an orthophoto) is segmented like the image (seed-001 §2.17) and its regions'
outlines are taken to map coordinates with the raster's geotransform.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import fiona
import numpy as np
import pyproj
import rasterio
from shapely.geometry import MultiPolygon, Polygon, shape
from shapely.ops import unary_union

from ..errors import InputError
from ..feedback import Feedback
from .correspondence import apply
from .fit import centre_matrix
from .objects import REFERENCE, PolygonObject, orient_ring
from .regions import image_objects, load_image

PathLike = Union[str, Path]

RASTER_SUFFIXES = (".tif", ".tiff", ".vrt", ".img", ".jp2", ".png", ".jpg")


def is_raster(path: PathLike) -> bool:
    """True when ``path`` is a raster (by suffix, else by trying to open it)."""
    p = Path(path)
    if p.suffix.lower() in RASTER_SUFFIXES:
        return True
    if p.suffix.lower() in (".gpkg", ".shp", ".geojson", ".json", ".gml", ".kml", ".fgb"):
        return False
    try:
        with rasterio.open(p):
            return True
    except Exception:
        return False


def matching_crs(crs: Any, lon: float, lat: float) -> Any:
    """The projected CRS to match in: ``crs`` when projected, else the UTM zone at lon/lat."""
    c = pyproj.CRS.from_user_input(crs)
    if c.is_projected:
        return c
    zone = int((lon + 180.0) // 6.0) + 1
    return pyproj.CRS.from_epsg((32600 if lat >= 0 else 32700) + min(max(zone, 1), 60))


def _match_value(value: Any, wanted: str) -> bool:
    if value is None:
        return False
    if str(value).strip() == wanted:
        return True
    try:
        return float(value) == float(wanted)
    except (TypeError, ValueError):
        return False


def _transform_polygon(g: Any, tr: Any) -> Any:
    """A (multi)polygon through a pyproj transformer (rings rebuilt; shapely 1.8 and 2)."""
    def ring(coords: Any) -> np.ndarray:
        c = np.asarray(coords, float)
        x, y = tr.transform(c[:, 0], c[:, 1])
        return np.column_stack([x, y])

    parts = [Polygon(ring(p.exterior.coords), [ring(h.coords) for h in p.interiors])
             for p in getattr(g, "geoms", [g])]
    return parts[0] if len(parts) == 1 else MultiPolygon(parts)


def reference_objects_from_vector(path: PathLike, class_field: Optional[str] = None,
                                  class_value: Optional[str] = None, crs: Any = None,
                                  snap: Optional[float] = None, layer: Optional[str] = None,
                                  feedback: Optional[Feedback] = None
                                  ) -> Tuple[List[PolygonObject], Any, Dict[str, Any]]:
    """Reference objects of a polygon layer.

    Parameters
    ----------
    path : path
        GeoPackage, Shapefile, GeoJSON … (anything fiona reads), any CRS.
    class_field, class_value : str, optional
        Select the features whose ``class_field`` equals ``class_value`` (compared as text,
        or as numbers). Without a field all polygons are used.
    crs : CRS, optional
        CRS to match in (default: :func:`matching_crs`).
    snap : float, optional
        Snap tolerance (map units) for dissolving touching polygons; default 0.05 % of the
        layer extent.

    Returns
    -------
    objects : list of PolygonObject
        Outer rings in the matching CRS, ids in a stable order (by source feature id);
        ``attributes["features"]``: the source features dissolved into it,
        ``attributes["outlines"]``: their rings (outer and holes) before the dissolve.
    crs : pyproj.CRS
    info : dict
        Feature counts (read, selected, after dissolve).

    Raises
    ------
    InputError
        Unreadable layer, a class field it does not have, no polygon after the selection.
    """
    path = Path(path)
    if not path.exists():
        raise InputError.of("Reference layer '{path}' not found.", path=path)
    try:
        src = fiona.open(path, layer=layer) if layer else fiona.open(path)
    except Exception as exc:
        raise InputError.of("Cannot read the reference layer '{path}': {error}", path=path,
                            error=exc) from exc
    with src:
        fields = list(src.schema.get("properties", {}))
        if class_field and class_field not in fields:
            raise InputError.of("The reference layer '{name}' has no attribute '{field}'; its "
                                "attributes are: {fields}.", name=path.name, field=class_field,
                                fields=", ".join(fields) or "—")
        layer_crs = src.crs_wkt or None
        geoms, ids = [], []
        n_read = 0
        for feat in src:
            n_read += 1
            if feat["geometry"] is None:
                continue
            if class_field and class_value is not None and not _match_value(
                    feat["properties"][class_field], str(class_value).strip()):
                continue
            g = shape(feat["geometry"])
            if g.geom_type not in ("Polygon", "MultiPolygon") or g.is_empty:
                continue
            if not g.is_valid:
                g = g.buffer(0)
            geoms.append(g)
            ids.append(feat.get("id", n_read - 1))
    if not geoms:
        if class_field:
            raise InputError.of("No polygons with {field} = {value} in the reference layer "
                                "'{name}' ({count} features read); check the class field and "
                                "value.", field=class_field, value=class_value, name=path.name,
                                count=n_read)
        raise InputError.of("No polygons in the reference layer '{name}' ({count} features "
                            "read); check the class field and value.", name=path.name,
                            count=n_read)
    if layer_crs is None:
        raise InputError.of("The reference layer '{name}' has no CRS; assign one in QGIS "
                            "first.", name=path.name)
    merged = unary_union(geoms)
    cen = merged.centroid
    to_ll = pyproj.Transformer.from_crs(layer_crs, "EPSG:4326", always_xy=True)
    lon, lat = to_ll.transform(cen.x, cen.y)
    target = pyproj.CRS.from_user_input(crs) if crs else matching_crs(layer_crs, lon, lat)
    if not pyproj.CRS.from_user_input(layer_crs).equals(target):
        tr = pyproj.Transformer.from_crs(layer_crs, target, always_xy=True)
        geoms = [_transform_polygon(g, tr) for g in geoms]
    x0, y0, x1, y1 = unary_union(geoms).bounds
    eps = snap if snap is not None else 0.0005 * max(x1 - x0, y1 - y0)
    # dissolve touching polygons of the class: grow by eps, union, shrink back
    dissolved = unary_union([g.buffer(eps, join_style=2) for g in geoms]).buffer(-eps,
                                                                                   join_style=2)
    parts = [p for p in getattr(dissolved, "geoms", [dissolved])
             if p.geom_type == "Polygon" and not p.is_empty]
    parts.sort(key=lambda p: (round(p.bounds[0], 3), round(p.bounds[1], 3)))
    objects = []
    for k, p in enumerate(parts):
        ring = orient_ring(np.asarray(p.exterior.coords)[:, :2])
        inside = [i for i, g in enumerate(geoms) if g.intersects(p)]
        objects.append(PolygonObject(id=k, ring=ring, source=REFERENCE,
                                     attributes={"features": [ids[i] for i in inside],
                                                 "outlines": _outlines(geoms[i]
                                                                       for i in inside)}))
    info = {"features_read": n_read, "selected": len(geoms), "objects": len(objects),
            "snap": eps, "crs": target.to_string()}
    if feedback:
        feedback.info(f"Reference: {len(geoms)} of {n_read} polygons selected, {len(objects)} "
                      f"objects after dissolving touching ones (matching CRS {target.name}).")
    return objects, target, info


def _outlines(geoms: Any) -> List[np.ndarray]:
    """All rings (outer and holes) of the individual polygons before the dissolve: the
    boundaries between touching polygons, which the dissolved objects no longer have."""
    out = []
    for g in geoms:
        for p in getattr(g, "geoms", [g]):
            if p.geom_type != "Polygon" or p.is_empty:
                continue
            out.append(np.asarray(p.exterior.coords)[:, :2])
            out += [np.asarray(r.coords)[:, :2] for r in p.interiors]
    return out


def load_reference(path: PathLike, band: Optional[int] = None
                   ) -> Tuple[np.ndarray, np.ndarray, Any, Dict[str, Any]]:
    """A georeferenced reference raster: grey level 0, reference pixel → map (3 × 3; pixel
    centres at integers), the CRS (pyproj) and what the report says about it.

    Raises
    ------
    InputError
        The raster has no georeference or a geographic CRS.
    """
    with rasterio.open(path) as src:
        if src.crs is None or src.transform.is_identity:
            raise InputError.of("The reference raster '{name}' has no georeference; a raster "
                                "reference must be georeferenced (an orthophoto).",
                                name=Path(path).name)
        transform, crs = src.transform, pyproj.CRS.from_user_input(src.crs.to_wkt())
    if not crs.is_projected:
        raise InputError.of("The reference raster '{name}' is in a geographic CRS; reproject "
                            "it to a projected CRS first.", name=Path(path).name)
    grey, info = load_image(path, band)
    return grey, centre_matrix(transform), crs, {**info, "crs": crs.to_string()}


def reference_objects_from_raster(path: PathLike, thresholds: Sequence[float],
                                  min_area: float = 0.0003, max_area: float = 0.05,
                                  pyramid_level: Union[int, str] = "auto",
                                  band: Optional[int] = None, smooth: float = 0.0,
                                  merge: bool = False,
                                  feedback: Optional[Feedback] = None
                                  ) -> Tuple[List[PolygonObject], Any, Dict[str, Any]]:
    """Reference objects of a georeferenced raster, segmented like the image.

    Regions are outlined in the raster's pixel frame and taken to map coordinates with its
    geotransform (pixel centres at integers: map = transform · (x + 0.5, y + 0.5)).
    """
    grey, to_map, crs, _ = load_reference(path, band)
    objs, info = image_objects(grey, thresholds, min_area, max_area, pyramid_level,
                               smooth=smooth, merge=merge, feedback=feedback)
    out = []
    for o in objs:
        ring = apply(to_map, o.ring)
        out.append(PolygonObject(id=o.id, ring=orient_ring(ring), source=REFERENCE, run=o.run,
                                 threshold=o.threshold, touches_border=o.touches_border,
                                 attributes=o.attributes))
    return out, crs, info
