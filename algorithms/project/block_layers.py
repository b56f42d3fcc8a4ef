"""The block as map layers: image footprints and stereo models in ``.photodem/block.gpkg``.

The faces show where the images and the stereo models of a project lie. Both are derived from
``project.toml`` (cameras, exterior orientations, the stereo models), so they are written to
the project's own scratch folder ``<project>/.photodem/block.gpkg`` (never into the operator's
files) and rewritten only when ``project.toml`` is newer than the file:

=============  ========  =======================================================================
layer          geometry  fields
=============  ========  =======================================================================
footprints     Polygon   ``image`` — the image outline projected onto the terrain
stereo_models  Polygon   ``name``, ``left``, ``right``, ``b_h``, ``overlap_pct`` — the overlap of
                         the two footprints
=============  ========  =======================================================================

Footprints lie on the plane at the project's terrain height (0 m without one), like the
stereo-model detection uses them. The file is written under a staging name and renamed when
complete, so a reader never sees half a file.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from pathlib import Path
from typing import Any, Dict, List, Tuple

import fiona
import pyproj
from shapely.geometry import mapping

from ..errors import InputError
from ..raster.io import atomic_output
from .model import Project, StereoModel
from .stereo_models import block_footprints, model_geometry

#: The project's scratch folder and the block file in it.
SCRATCH_DIR = ".photodem"
BLOCK_FILE = "block.gpkg"
#: Layer name → (geometry type, fields) of ``block.gpkg``.
BLOCK_LAYERS: Dict[str, Tuple[str, OrderedDict[str, str]]] = {
    "footprints": ("Polygon", OrderedDict([("image", "str")])),
    "stereo_models": ("Polygon", OrderedDict([("name", "str"), ("left", "str"),
                                              ("right", "str"), ("b_h", "float"),
                                              ("overlap_pct", "float")])),
}


def block_path(project: Project) -> Path:
    """``<project>/.photodem/block.gpkg``."""
    return Path(project.root) / SCRATCH_DIR / BLOCK_FILE


def is_current(project: Project) -> bool:
    """True when ``block.gpkg`` exists and is not older than ``project.toml``."""
    path = block_path(project)
    try:
        return path.stat().st_mtime >= project.project_file.stat().st_mtime
    except OSError:
        return False


def _polygon(geom: Any) -> Any:
    """The largest polygon of ``geom`` (an intersection may give a collection)."""
    if geom.geom_type == "Polygon":
        return geom
    parts = [g for g in getattr(geom, "geoms", []) if g.geom_type == "Polygon"]
    return max(parts, key=lambda g: g.area) if parts else None


def _measured(project: Project, model: StereoModel, footprints: Dict[str, Any]) -> StereoModel:
    """``model`` itself when it carries B/H and overlap, else both computed from the
    footprints (a manual model written without them)."""
    if math.isfinite(model.b_h) and math.isfinite(model.overlap):
        return model
    return model_geometry(project, model.left, model.right, footprints=footprints, order=False)


def footprint_records(project: Project, footprints: Dict[str, Any]) -> List[Dict[str, Any]]:
    """One record per image with a footprint."""
    return [{"geometry": mapping(poly), "properties": OrderedDict([("image", name)])}
            for name, (poly, _height) in footprints.items()]


def model_records(project: Project, footprints: Dict[str, Any]) -> List[Dict[str, Any]]:
    """One record per stereo model: the overlap polygon with name, images, B/H, overlap %."""
    records = []
    for model in project.models:
        if model.left not in footprints or model.right not in footprints:
            continue
        overlap = _polygon(footprints[model.left][0].intersection(footprints[model.right][0]))
        if overlap is None or overlap.is_empty:
            continue
        m = _measured(project, model, footprints)
        props = OrderedDict([("name", model.name), ("left", model.left), ("right", model.right),
                             ("b_h", round(float(m.b_h), 4)),
                             ("overlap_pct", round(100.0 * float(m.overlap), 1))])
        records.append({"geometry": mapping(overlap), "properties": props})
    return records


def _crs_wkt(project: Project) -> str:
    if not project.crs:
        raise InputError(f"'{project.project_file}' names no CRS; the block layers need one.")
    try:
        return pyproj.CRS.from_user_input(project.crs).to_wkt()
    except Exception as exc:  # pyproj.exceptions.CRSError
        raise InputError(f"The project CRS '{project.crs}' is not understood: {exc}") from exc


def write_block_layers(project: Project, force: bool = False) -> Path:
    """Write (or keep) ``<project>/.photodem/block.gpkg`` and return its path.

    The file is rewritten only when ``project.toml`` is newer (or ``force``); it is written
    under a staging name and renamed when complete.

    Raises
    ------
    InputError
        When the project has no usable CRS or no images with a camera.
    """
    path = block_path(project)
    if not force and is_current(project):
        return path
    wkt = _crs_wkt(project)
    footprints = block_footprints(project)
    records = {"footprints": footprint_records(project, footprints),
               "stereo_models": model_records(project, footprints)}
    with atomic_output(path, tag=False) as tmp:
        for layer, (geom_type, fields) in BLOCK_LAYERS.items():
            schema = {"geometry": geom_type, "properties": OrderedDict(fields)}
            with fiona.open(str(tmp), "w", driver="GPKG", layer=layer, schema=schema,
                            crs_wkt=wkt) as dst:
                dst.writerecords(records[layer])
    return path


__all__ = ["BLOCK_FILE", "BLOCK_LAYERS", "SCRATCH_DIR", "block_path", "footprint_records",
           "is_current", "model_records", "write_block_layers"]
