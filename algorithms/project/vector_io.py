"""One reader of vector layers (edits.gpkg, constraint layers, operator seamlines).

It opens every layer (or the chosen ones) of a GeoPackage / Shapefile / GeoJSON, skips
attribute-only rows and yields each feature's GeoJSON-like geometry in the layer's own CRS with
that CRS; :func:`to_crs` brings a geometry into another CRS. What a caller checks or keeps (the
edit rules, the seamline attributes) stays with the caller.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, Iterator, List, Optional, Sequence, Union

import fiona
from rasterio.crs import CRS
from rasterio.warp import transform_geom

from ..errors import InputError
from ..input_errors import role

PathLike = Union[str, Path]


@dataclass
class VectorFeature:
    """One feature of a vector layer."""

    layer: str  #: name of its layer
    fid: Any  #: feature id in the layer
    geometry: Dict[str, Any]  #: GeoJSON-like mapping, in :attr:`crs`
    properties: Dict[str, Any]  #: attribute values
    crs: Optional[CRS]  #: CRS of the layer (``None``: the file names none)


def read_features(path: PathLike, layers: Optional[Sequence[str]] = None,
                  what: str = "vector file") -> List[VectorFeature]:
    """The features with a geometry of every layer of ``path`` (or only of ``layers``).

    Read completely before they are returned, so that every layer is closed again when a
    caller stops at a feature it refuses.

    Parameters
    ----------
    path : path
        An existing vector file (the caller names a missing one in its own words).
    layers : sequence of str, optional
        Layers to read (others are skipped); default: all.
    what : str
        The file's role in the message of an unreadable file ("seamline file").

    Raises
    ------
    InputError
        When the file's layers cannot be listed.
    """
    path = Path(path)
    try:
        names = fiona.listlayers(str(path))
    except Exception as exc:  # driver-specific errors
        raise InputError.of("Cannot read the {what} '{name}': {error}", what=role(what),
                            name=path.name, error=exc) from exc
    return list(_features(path, names, layers))


def _features(path: Path, names: Sequence[str],
              layers: Optional[Sequence[str]]) -> Iterator[VectorFeature]:
    """The features of the layers ``names`` of ``path`` that are in ``layers`` (if given)."""
    for name in names:
        if layers is not None and name not in layers:
            continue
        with fiona.open(str(path), layer=name) as src:
            src_crs = CRS.from_wkt(src.crs_wkt) if src.crs_wkt else None
            for feat in src:
                geom = feat["geometry"]
                if geom is None:  # QGIS allows attribute-only rows
                    continue
                # fiona ≥ 1.10 returns Geometry objects, 1.9 dicts; shape() takes both
                geom = geom if isinstance(geom, dict) else geom.__geo_interface__
                yield VectorFeature(name, feat["id"], geom, dict(feat["properties"]), src_crs)


def to_crs(geometry: Dict[str, Any], source: Optional[CRS],
           target: Optional[CRS]) -> Dict[str, Any]:
    """``geometry`` (GeoJSON-like) transformed from ``source`` to ``target``; unchanged when
    either is unknown or both are the same."""
    if target is not None and source is not None and source != target:
        return transform_geom(source, target, geometry)
    return geometry


__all__ = ["VectorFeature", "read_features", "to_crs"]
