"""The steps of a new edit — ask, check, warn — shared by the QGIS editing toolbar and the
standalone map's capture tools.

The decisions are the core's (:mod:`photodem.algorithms.project.edit_rules`); this module adds
what the operator sees: the questions (an *asker* with the methods of
:class:`.edit_forms.DialogAsker`) and the messages in the operator's language. Each face passes
a *host* with:

* ``ask`` — the asker; ``say(text, level)`` — a message, level ``info``/``warning``/``critical``;
* ``project`` and ``project_crs()``; ``footprints()`` — the block's footprints (cached);
* ``surface_path(needed)`` — the chosen surface file or None (with a message when ``needed``);
* ``z_mode`` — the breakline height mode; ``mark(points)`` / ``clear_marks()`` — red crosses.

Every function returns an :class:`Edit` to write (project CRS) or None (refused or cancelled,
the operator was told). Nothing here writes.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Dict, List, Optional, Sequence, Tuple

from ...algorithms.errors import PhotodemError
from ...algorithms.project import edit_rules
from ..i18n import tr

XY = Tuple[float, float]


@dataclass
class Edit:
    """Features of one edit layer to add as one undoable step."""

    layer: str
    features: List[Tuple[Any, Dict[str, Any]]]
    title: str


def point_titles() -> Dict[str, str]:
    return {"start_points": tr("Start point"), "ground_points": tr("Ground point"),
            "check_points": tr("Check point")}


def sample(host: Any, x: float, y: float) -> Tuple[Optional[float], str]:
    """The surface height at a project point and, without one, why (for the form)."""
    path = host.surface_path(False)
    if path is None:
        return None, tr("No surface chosen; type the height.")
    try:
        return edit_rules.sample_surface(path, x, y, host.project_crs())
    except PhotodemError as exc:
        return None, str(exc)


def checked(host: Any, layer: str, geometry: Any, attributes: Dict[str, Any]) -> bool:
    """``validate_edit``: refusals stop the edit (message), warnings are shown."""
    bad, warnings = edit_rules.verdict(layer, geometry, attributes, host.project,
                                       host.footprints())
    if bad:
        host.say(" ".join(p.message for p in bad), "critical")
        return False
    if warnings:
        host.say(" ".join(p.message for p in warnings), "warning")
    return True


def point_edit(host: Any, layer: str, x: float, y: float) -> Optional[Edit]:
    """A start, ground or check point at a project point: the height from the surface (or
    typed), confirmed in the form, checked."""
    z, reason = sample(host, x, y)
    start = edit_rules.point_start(host.project, layer, x, y, z, reason, host.footprints())
    notes = [reason] if reason else []
    if start.outside_models:
        notes.insert(0, tr("The point lies outside every stereo model; no model will use it."))
    if notes:
        host.say(" ".join(notes), "warning")
    title = point_titles()[layer]
    label = tr("Id") if edit_rules.POINT_LAYERS[layer] == "id" else tr("Note")
    answer = host.ask.height(title, start.z, " ".join(notes), label)
    if answer is None:
        return None
    geometry, attributes = edit_rules.point_feature(layer, x, y, answer[0], answer[1])
    if not checked(host, layer, geometry, attributes):
        return None
    return Edit(layer, [(geometry, attributes)], title)


def polygon_edit(host: Any, layer: str, polygon: Any) -> Optional[Edit]:
    """An exclusion area or boundary: repaired with consent if self-intersecting, the action
    (or name) asked, checked."""
    check = edit_rules.polygon_check(polygon)
    if check.problems:
        host.mark(check.locations)
        if check.repaired is None or not host.ask.repair(check.text):
            host.say(tr("Polygon refused, nothing written: {0}").format(check.text), "critical")
            return None
        polygon = check.repaired
    if layer == "exclusion_areas":
        answer = host.ask.action()
        title = tr("Exclusion area")
    else:
        answer = host.ask.text(tr("Boundary"), tr("Name"))
        title = tr("Boundary")
    if answer is None:
        return None
    attributes = edit_rules.polygon_attributes(layer, answer)
    parts = edit_rules.polygon_parts(polygon)
    if not all(checked(host, layer, part, attributes) for part in parts):
        return None
    host.clear_marks()
    return Edit(layer, [(part, attributes) for part in parts], title)


def line_edit(host: Any, layer: str, coords: Sequence[XY], existing: Sequence[Any] = (),
              seam_lines: Sequence[Any] = (), tolerance: float = 0.0) -> Optional[Edit]:
    """A breakline (crossings of ``existing`` refused, heights by the Z mode) or a seamline
    (snapped onto ``seam_lines`` within ``tolerance`` map units)."""
    coords = [(float(c[0]), float(c[1])) for c in coords]
    if layer == "seamlines":
        line, attributes = edit_rules.seamline_feature(coords, seam_lines, tolerance)
        if not checked(host, layer, line, attributes):
            return None
        return Edit(layer, [(line, attributes)], tr("Seamline"))
    crossings = edit_rules.breakline_crossings(coords, existing)
    if crossings:
        host.mark([p.location for p in crossings if p.location])
        host.say(tr("Breakline refused, nothing written: {0}").format(
            " ".join(p.message for p in crossings)), "critical")
        return None
    host.clear_marks()
    feature = breakline(host, coords)
    if feature is None or not checked(host, layer, *feature):
        return None
    return Edit(layer, [feature], tr("Breakline"))


def breakline(host: Any, coords: List[XY]) -> Optional[Tuple[Any, Dict[str, Any]]]:
    """The 3-D breakline: heights by the Z mode, confirmed (and completed) in the form."""
    mode = host.z_mode
    path = None
    if mode in ("drape", "typed"):
        path = host.surface_path(mode == "drape")
        if path is None and mode == "drape":
            return None
    try:
        prefill = edit_rules.breakline_prefill(path, coords, mode, host.project_crs())
    except PhotodemError as exc:
        host.say(str(exc), "critical")
        return None
    message = prefill.reason
    if mode == "interpolate":
        message = tr("Type the heights of the two ends; the others are interpolated.")
    if message:
        host.say(message, "warning")
    answer = host.ask.breakline(prefill.heights, prefill.editable, message)
    if answer is None:
        return None
    try:
        return edit_rules.breakline_feature(coords, answer[0], mode, answer[1])
    except PhotodemError as exc:
        host.say(tr("Every vertex of a breakline needs a height.")
                 if "needs a height" in str(exc) else str(exc), "critical")
        return None
