"""Checks of one edit while it is drawn, before it is written to ``edits.gpkg``.

The editing tools ask these functions; the rules are those applied when a run reads the edits
(:mod:`.edits`: the action values, the polygon repair, 2-D breaklines; the matcher's crossing
rule :func:`.breaklines.check_breaklines`), called here through the same functions, so an edit the
tools accept is not refused later, and the messages are the same.

* :func:`check_new_breakline` — crossings with the existing breaklines and with itself (touching
  end points of lines that continue one another are allowed), with the points to mark.
* :func:`check_new_polygon` — a self-intersecting polygon: the message and a repaired candidate
  the operator may accept.
* :func:`validate_edit` — one feature: layer, attribute values, geometry type, heights (finite
  and plausible for the block), inside the block area.
* :func:`models_at` — the stereo models whose overlap contains a map point.

Every check returns a list of :class:`Problem` (message, location, severity) instead of raising,
so the tool can list them and mark their places.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np
from shapely.geometry import Point
from shapely.ops import unary_union
from shapely.validation import explain_validity

from ..errors import InputError
from ..geometry.stereo import Footprints
from .breaklines import line_crossing, self_crossings
from .edits import (
    EDIT_LAYERS,
    check_fields,
    check_layer,
    flat_breakline_message,
    kind_message,
    repaired_polygon,
)
from .model import Project, StereoModel
from .stereo_models import block_footprints, overlap_polygon

XY = Tuple[float, float]

#: Heights further than this share of the flying height from the terrain are implausible.
HEIGHT_MARGIN_H = 0.5


@dataclass
class Problem:
    """One problem of an edit: a sentence for the operator and where it is.

    ``severity`` is ``"error"`` (the edit is refused) or ``"warning"`` (it may be written).
    """

    message: str
    location: Optional[XY] = None
    severity: str = "error"


@dataclass
class PolygonCheck:
    """The answer of :func:`check_new_polygon`: problems and, for an invalid polygon, the
    repaired candidate (``None`` when it is valid or nothing is left)."""

    problems: List[Problem] = field(default_factory=list)
    repaired: Any = None

    @property
    def ok(self) -> bool:
        return not self.problems


def errors(problems: Sequence[Problem]) -> List[Problem]:
    """The problems that refuse an edit."""
    return [p for p in problems if p.severity == "error"]


# -- crossings and polygon repair ------------------------------------------------------------------
def check_new_breakline(line: Any, existing: Sequence[Any]) -> List[Problem]:
    """Crossings of a new breakline with itself and with the existing ones.

    The matcher's rule (:func:`.breaklines.check_breaklines`): breaklines must not cross or touch,
    except at shared end points of lines that continue one another.

    Parameters
    ----------
    line : shapely LineString
        The new breakline (2-D or 3-D).
    existing : sequence of shapely lines
        The breaklines of the layer (1-based numbers in the messages follow this order).

    Returns
    -------
    list of Problem
        One per crossing, located at the crossing point; empty when the line may be written.
    """
    problems = [Problem("The new breakline crosses itself at "
                        f"({x:.2f}, {y:.2f}); breaklines must not cross or touch.", (x, y))
                for x, y in self_crossings(line)]
    for k, other in enumerate(existing, start=1):
        if other is None or other.is_empty:
            continue
        at = line_crossing(line, other)
        if at is not None:
            problems.append(Problem(f"The new breakline crosses breakline {k} at "
                                    f"({at[0]:.2f}, {at[1]:.2f}); breaklines must not cross or "
                                    "touch (only continue one another at end points).", at))
    return problems


def check_new_polygon(polygon: Any) -> PolygonCheck:
    """A new polygon (exclusion area, boundary): valid, or the reason and a repaired candidate.

    The repair is the run-time reader's (:func:`.edits.repaired_polygon`: ``make_valid``, else
    ``buffer(0)``), so what the operator accepts is what a run would use.
    """
    if polygon.is_valid and not polygon.is_empty:
        return PolygonCheck()
    if polygon.is_empty:
        return PolygonCheck([Problem("The polygon is empty; draw at least three corners.")])
    reason = explain_validity(polygon)
    fixed = repaired_polygon(polygon)
    where = _location_of(reason) or _first_xy(polygon)
    if fixed is None:
        return PolygonCheck([Problem(f"The polygon is invalid ({reason}) and nothing is left "
                                     "after repairing it; redraw it.", where)])
    return PolygonCheck([Problem(f"The polygon is invalid ({reason}); accept the repaired "
                                 f"polygon (area {polygon.area:.1f} → {fixed.area:.1f} m²) or "
                                 "redraw it.", where)], fixed)


def _location_of(reason: str) -> Optional[XY]:
    """The point of GEOS's validity reason (``"Self-intersection[5 5]"``), if it has one."""
    if "[" not in reason or "]" not in reason:
        return None
    try:
        x, y = reason[reason.index("[") + 1:reason.index("]")].split()[:2]
        return float(x), float(y)
    except ValueError:
        return None


def _first_xy(geom: Any) -> Optional[XY]:
    if geom.is_empty:
        return None
    p = geom.centroid  # defined for invalid polygons too
    return p.x, p.y


# -- the block: area, plausible heights, models ---------------------------------------------------
def block_area(project: Project, footprints: Optional[Footprints] = None) -> Any:
    """The project's block area: the union of its image footprints (terrain height).

    ``footprints`` (:func:`.stereo_models.block_footprints`) may be passed to reuse them.
    """
    fp = block_footprints(project) if footprints is None else footprints
    return unary_union([poly for poly, _ in fp.values()])


def plausible_heights(project: Project) -> Tuple[float, float]:
    """The range (m) of plausible terrain heights of the block.

    The terrain height (``project.terrain_height``, else the cameras' mean height less the
    models' mean flying height above ground) ± :data:`HEIGHT_MARGIN_H` × the flying height,
    and always below the cameras. Without images or a flying height: (−∞, ∞).
    """
    cam_z = [float(r.eo.position[2]) for r in project.images
             if np.isfinite(r.eo.position[2])]
    if not cam_z:
        return -math.inf, math.inf
    z_cam = float(np.mean(cam_z))
    hag = [m.height_above_ground for m in project.models if np.isfinite(m.height_above_ground)]
    terrain = project.terrain_height
    if terrain is None and hag:
        terrain = z_cam - float(np.mean(hag))
    if terrain is None:
        return -math.inf, min(cam_z)
    flying = z_cam - float(terrain)
    if not flying > 0:
        return -math.inf, math.inf
    return (float(terrain) - HEIGHT_MARGIN_H * flying,
            min(float(terrain) + HEIGHT_MARGIN_H * flying, min(cam_z)))


def models_at(project: Project, x: float, y: float,
              footprints: Optional[Footprints] = None) -> List[StereoModel]:
    """The stereo models of the project whose overlap contains the map point (x, y).

    ``footprints`` (:func:`.stereo_models.block_footprints`) may be passed to reuse them
    between clicks. An empty list: the point lies outside every model (the start point tool
    warns).
    """
    if not project.models:
        return []
    fp = footprints if footprints is not None else block_footprints(project)
    p = Point(float(x), float(y))
    return [m for m in project.models
            if overlap_polygon(project, m.left, m.right, footprints=fp).covers(p)]


# -- one edit --------------------------------------------------------------------------------------
#: Layers whose features carry their heights in Z.
_Z_LAYERS = ("breaklines", "ground_points", "check_points")


def validate_edit(layer: str, geometry: Any, attributes: Optional[Dict[str, Any]],
                  project: Project, footprints: Optional[Footprints] = None) -> List[Problem]:
    """All problems of one edit before it is written to ``edits.gpkg``.

    Parameters
    ----------
    layer : str
        The edit layer (:data:`.edits.EDIT_LAYERS`).
    geometry : shapely geometry
        In the project CRS.
    attributes : dict
        The feature's fields.
    project : Project
        For the plausible heights, the block area and the stereo models.
    footprints : dict, optional
        :func:`.stereo_models.block_footprints` of the project, when the tool keeps them
        between edits (they cost a projection of every image's border).

    Returns
    -------
    list of Problem
        Errors refuse the edit, warnings do not; empty when it may be written as it is.
    """
    try:
        check_layer(layer)
    except InputError as exc:
        return [Problem(str(exc))]
    where = _first_xy(geometry) if geometry is not None else None
    problems = _attribute_problems(layer, attributes, where)
    if geometry is None or geometry.is_empty:
        return problems + [Problem(f"Layer '{layer}': the feature has no geometry.")]
    problems += _geometry_problems(layer, geometry)
    problems += _height_problems(layer, geometry, attributes or {}, plausible_heights(project))
    fp = block_footprints(project) if footprints is None else footprints
    problems += _area_problems(layer, geometry, block_area(project, fp))
    if layer == "start_points" and not errors(problems) and project.models \
            and not models_at(project, geometry.x, geometry.y, fp):
        problems.append(Problem(f"Layer '{layer}': the start point lies outside every stereo "
                                "model; no model will use it.", _first_xy(geometry), "warning"))
    return problems


def _attribute_problems(layer: str, attributes: Optional[Dict[str, Any]],
                        where: Optional[XY]) -> List[Problem]:
    """The field names and values, checked by the writer's own :func:`.edits.check_fields`."""
    try:
        check_fields(layer, attributes)
    except InputError as exc:
        return [Problem(str(exc), where)]
    kind = kind_message((attributes or {}).get("kind"), f"Layer '{layer}'")
    if layer == "breaklines" and kind:
        return [Problem(kind, where, "warning")]
    return []


def _geometry_problems(layer: str, geometry: Any) -> List[Problem]:
    """Geometry type, Z where the layer needs it, polygon validity."""
    expected = EDIT_LAYERS[layer][0].replace("3D ", "")
    if expected not in geometry.geom_type:
        return [Problem(f"Layer '{layer}' takes {expected} features, not "
                        f"{geometry.geom_type}.", _first_xy(geometry))]
    where = _first_xy(geometry)
    problems: List[Problem] = []
    flat = flat_breakline_message(layer, geometry, f"Layer '{layer}'")
    if flat:
        problems.append(Problem(flat, where, "warning"))
    elif layer in _Z_LAYERS and not geometry.has_z:
        problems.append(Problem(f"Layer '{layer}' needs 3-D points; give the point its height "
                                "(Z).", where))
    if "Polygon" in geometry.geom_type:
        problems += check_new_polygon(geometry).problems
    return problems


def _heights_of(layer: str, geometry: Any, attributes: Dict[str, Any]) -> List[Tuple[Any, str]]:
    """The heights an edit carries, each with its name for the message."""
    out: List[Tuple[Any, str]] = []
    if layer == "start_points" and attributes.get("height") is not None:
        out.append((attributes["height"], "height"))
    if geometry.has_z and layer in _Z_LAYERS + ("start_points",):
        parts = getattr(geometry, "geoms", [geometry])
        out += [(c[2], "Z") for part in parts for c in part.coords]
    return out


def _height_problems(layer: str, geometry: Any, attributes: Dict[str, Any],
                     plausible: Tuple[float, float]) -> List[Problem]:
    """Heights that are not finite numbers, or outside the plausible range of the block."""
    lo, hi = plausible
    for value, name in _heights_of(layer, geometry, attributes):
        try:
            z = float(value)
        except (TypeError, ValueError):
            z = math.nan
        if not math.isfinite(z):
            return [Problem(f"Layer '{layer}': {name} '{value}' is not a height in metres.",
                            _first_xy(geometry))]
        if not lo <= z <= hi:
            return [Problem(f"Layer '{layer}': {name} {z:.2f} m lies outside the plausible "
                            f"heights of the block ({lo:.1f} to {hi:.1f} m); check the height "
                            "and its datum.", _first_xy(geometry))]
    return []


def _area_problems(layer: str, geometry: Any, area: Any) -> List[Problem]:
    """Outside the block area: an error; partly outside: a warning."""
    if "Polygon" in geometry.geom_type and not geometry.is_valid:
        geometry = repaired_polygon(geometry)  # GEOS predicates want valid polygons
        if geometry is None:
            return []  # refused by the polygon check already
    if area is None or area.is_empty or area.covers(geometry):
        return []
    where = _first_xy(geometry)
    if not area.intersects(geometry):
        return [Problem(f"Layer '{layer}': the edit lies outside the project's block (the "
                        "images' footprints); draw it where the images are.", where)]
    return [Problem(f"Layer '{layer}': the edit lies partly outside the project's block; only "
                    "the part inside is used.", where, "warning")]


__all__ = ["HEIGHT_MARGIN_H", "PolygonCheck", "Problem", "block_area", "check_new_breakline",
           "check_new_polygon", "errors", "models_at", "plausible_heights", "validate_edit"]
