"""What a new edit becomes: the rules shared by the QGIS editing tools and the standalone map.

The map tools of both faces only collect clicks and answers; these functions decide the rest, so
that the same clicks give the same features in QGIS and in the standalone tool:

* points — :func:`point_start` (the surface height to pre-fill, the "outside every stereo
  model" case), :func:`point_feature` (geometry and attributes of each point layer);
* polygons — :func:`polygon_check` (a self-intersection refused, or its repair offered),
  :func:`polygon_parts`, :func:`polygon_attributes`;
* lines — :func:`breakline_crossings`, :func:`breakline_prefill` (draped, typed or
  interpolated heights), :func:`breakline_feature`, :func:`seamline_feature` (snapped onto a
  mosaic's seamlines);
* every edit — :func:`verdict` (``validate_edit`` split into refusals and warnings).

All coordinates are in the project CRS. Messages the operator reads are made by the faces (in
their language); the core hands them codes and the core's own reasons.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Sequence, Tuple

from shapely.geometry import LineString, Point

from ..errors import InputError
from . import edit_checks, edit_tools
from .model import Project

XY = Tuple[float, float]

#: Breakline height modes: each vertex draped on the surface, every height typed, or linear
#: between the typed heights of the two ends.
Z_MODES = ("drape", "typed", "interpolate")
#: Point layers and the attribute their text goes to.
POINT_LAYERS = {"start_points": "note", "ground_points": "note", "check_points": "id"}
#: Layers whose geometry carries the height in Z.
Z_LAYERS = ("breaklines", "ground_points", "check_points")
#: Seamline vertices within this many screen pixels of a mosaic seamline are snapped onto it.
SNAP_PIXELS = 12


@dataclass
class PointStart:
    """What the point form starts with.

    Attributes
    ----------
    z : float or None
        The surface height to pre-fill; None when the operator must type it.
    reason : str
        Why there is no surface height (the core's text: nodata, outside the surface …).
    outside_models : bool
        A start point outside every stereo model (no model would use it; typed height).
    """

    z: Optional[float]
    reason: str = ""
    outside_models: bool = False


def point_start(project: Project, layer: str, x: float, y: float, z: Optional[float],
                reason: str = "", footprints: Any = None) -> PointStart:
    """The pre-filled height of a new point of ``layer`` at (x, y).

    Parameters
    ----------
    z, reason
        The surface sample at the point (:func:`sample_surface`), or None and why not.
    footprints
        The block's image footprints (computed once per project by the caller).
    """
    if layer == "start_points" and not edit_checks.models_at(project, x, y, footprints):
        return PointStart(None, reason, outside_models=True)
    return PointStart(z, reason)


def sample_surface(surface: Optional[str], x: float, y: float,
                   crs: Any) -> Tuple[Optional[float], str]:
    """The surface height at a project point and, without one, the core's reason (empty when
    no surface is given: the caller says that in its language)."""
    if surface is None:
        return None, ""
    answer = edit_tools.sample_height(surface, x, y, crs=crs)
    return answer.z, answer.reason or ""


def point_feature(layer: str, x: float, y: float, height: float,
                  text: str = "") -> Tuple[Any, Dict[str, Any]]:
    """Geometry and attributes of a point: a start point keeps its height in ``height``, ground
    and check points in Z."""
    if layer == "start_points":
        return Point(x, y), {"height": height, "note": text or None}
    return Point(x, y, height), {POINT_LAYERS[layer]: text or None}


def verdict(layer: str, geometry: Any, attributes: Dict[str, Any], project: Project,
            footprints: Any = None) -> Tuple[List[Any], List[Any]]:
    """``validate_edit`` of a new edit as (refusals, warnings): any refusal stops the edit."""
    problems = edit_checks.validate_edit(layer, geometry, attributes, project, footprints)
    bad = edit_checks.errors(problems)
    return bad, [p for p in problems if p not in bad]


@dataclass
class PolygonVerdict:
    """A drawn polygon checked: ``problems`` (empty when fine), their ``locations``, the
    ``repaired`` geometry to offer (None: refuse) and the ``text`` of the problems."""

    polygon: Any
    problems: List[Any] = field(default_factory=list)
    locations: List[XY] = field(default_factory=list)
    repaired: Any = None

    @property
    def text(self) -> str:
        return " ".join(p.message for p in self.problems)


def polygon_check(polygon: Any) -> PolygonVerdict:
    """A new exclusion area or boundary checked (``check_new_polygon``)."""
    check = edit_checks.check_new_polygon(polygon)
    return PolygonVerdict(polygon, list(check.problems),
                          [p.location for p in check.problems if p.location], check.repaired)


def polygon_parts(polygon: Any) -> List[Any]:
    """The single polygons to write (a repaired bow tie becomes two features)."""
    return list(getattr(polygon, "geoms", [polygon]))


def polygon_attributes(layer: str, answer: Any) -> Dict[str, Any]:
    """The attributes of a polygon of ``layer`` from the form's answer: (action, note) for an
    exclusion area, the name for a boundary."""
    if layer == "exclusion_areas":
        action, note = answer
        return {"action": action, "note": note or None}
    return {"name": answer or None}


def breakline_crossings(coords: Sequence[XY], existing: Sequence[Any]) -> List[Any]:
    """The crossings of a new breakline with the layer's lines (any one refuses it)."""
    return edit_checks.check_new_breakline(LineString(coords), existing)


@dataclass
class BreaklinePrefill:
    """What the breakline form shows: a height per vertex (None = to type), which ones the
    operator may edit, and the core's reason for missing heights."""

    heights: List[Optional[float]]
    editable: List[bool]
    reason: str = ""


def breakline_prefill(surface: Optional[str], coords: Sequence[XY], z_mode: str,
                      crs: Any = None) -> BreaklinePrefill:
    """The heights of a new breakline before the form, by the Z mode.

    ``drape``: each vertex on the surface (only vertices without a surface height editable);
    ``typed``: every vertex editable, pre-filled from the surface when there is one;
    ``interpolate``: the two ends typed, the inner vertices follow.
    """
    n = len(coords)
    if z_mode == "interpolate":
        return BreaklinePrefill([None] * n, [i in (0, n - 1) for i in range(n)])
    heights: List[Optional[float]] = [None] * n
    reason = ""
    if surface is not None:
        draped = edit_tools.drape_line(surface, list(coords), crs=crs)
        heights = [None if i in draped.missing else c[2] for i, c in enumerate(draped.coords)]
        reason = draped.reason or ""
    editable = [z is None for z in heights] if z_mode == "drape" else [True] * n
    return BreaklinePrefill(heights, editable, reason)


def breakline_feature(coords: Sequence[XY], heights: Sequence[Optional[float]], z_mode: str,
                      kind: str) -> Tuple[Any, Dict[str, Any]]:
    """The 3-D breakline from the form's heights (the inner ones interpolated in the
    ``interpolate`` mode); :class:`InputError` when a vertex has no height."""
    if z_mode == "interpolate":
        line = edit_tools.drape_line(None, list(coords), mode="interpolate",
                                     end_heights=(heights[0], heights[-1]))
        heights = [c[2] for c in line.coords]
    if any(z is None for z in heights):
        raise InputError.of("Every vertex of a breakline needs a height.")
    line = LineString([(x, y, float(z)) for (x, y), z in zip(coords, heights)])
    return line, {"kind": kind}


def snapped(coords: Sequence[XY], lines: Sequence[Any], tolerance: float) -> List[XY]:
    """Vertices snapped onto the mosaic's seamlines when within ``tolerance`` of one."""
    out = []
    for xy in coords:
        snap = edit_tools.snap_to_lines(xy, lines, tolerance) if lines else None
        out.append(tuple(snap.point) if snap is not None else tuple(xy))
    return out


def seamline_feature(coords: Sequence[XY], lines: Sequence[Any],
                     tolerance: float) -> Tuple[Any, Dict[str, Any]]:
    """An operator's seamline, its vertices snapped onto the mosaic's seamlines."""
    return LineString(snapped(coords, lines, tolerance)), {}
