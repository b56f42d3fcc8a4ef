"""Breaklines must not cross or touch (seed-000 §2.10): the one crossing rule.

The matcher refuses crossing breaklines before it matches (:func:`check_breaklines`, raising on
the first); the editing tools ask :func:`self_crossings` and :func:`line_crossing` while a line
is drawn, to mark the crossing points. Lines that continue one another (they meet only at end
points of both) do not cross.
"""

from __future__ import annotations

from typing import Any, Dict, List, Optional, Tuple

from shapely.geometry import MultiPoint, Point
from shapely.ops import unary_union

from ..errors import InputError

#: Two points closer than this (m) are one point (shared end points of continuing lines).
SAME_POINT_M = 1e-6


def _ends(line: Any) -> List[Any]:
    return [Point(line.coords[0]), Point(line.coords[-1])]


def self_crossings(line: Any) -> List[Tuple[float, float]]:
    """Points (x, y) where a line crosses or touches itself; empty for a simple line.

    The line is noded (split where it meets itself); a node shared by more than two pieces is
    a crossing. A closed line (first = last vertex) is not a crossing at its start.
    """
    if line.is_simple:
        return []
    noded = unary_union(line)
    count: Dict[Tuple[float, float], int] = {}
    for piece in getattr(noded, "geoms", [noded]):
        for x, y in (piece.coords[0][:2], piece.coords[-1][:2]):
            key = (round(x, 6), round(y, 6))
            count[key] = count.get(key, 0) + 1
    points = [p for p, n in count.items() if n > 2]
    if not points:  # an overlap along a segment, or a degenerate line: still not simple
        points = [line.representative_point().coords[0][:2]]
    return points


def line_crossing(a: Any, b: Any) -> Optional[Tuple[float, float]]:
    """Where two lines cross or touch, or ``None`` when they are apart or one continues the
    other (they meet only at end points of both)."""
    if not a.intersects(b):
        return None
    cut = a.intersection(b)
    points = list(getattr(cut, "geoms", [cut]))
    shared = [e for e in _ends(a) if any(e.distance(f) < SAME_POINT_M for f in _ends(b))]
    if all(isinstance(p, Point) and any(p.distance(e) < SAME_POINT_M for e in shared)
           for p in points):
        return None  # one line continues the other
    if isinstance(cut, (Point, MultiPoint)):  # a true crossing: mark a point of it not shared
        for p in points:
            if not any(p.distance(e) < SAME_POINT_M for e in shared):
                return p.x, p.y
    x, y = cut.representative_point().coords[0][:2]
    return x, y


def check_breaklines(lines: List[Any]) -> None:
    """Refuse breaklines that cross each other or themselves (seed-000 §2.10).

    Touching at end points is allowed (lines that continue one another). The matcher calls this
    before it matches; the editing tools use :func:`self_crossings` and :func:`line_crossing`.

    Raises
    ------
    InputError
        Naming the two lines (1-based, in the order of the layer) and the crossing point.
    """
    for i, a in enumerate(lines):
        if not a.is_simple:
            raise InputError.of("Breakline {number} crosses itself; fix it in edits.gpkg "
                                "(layer breaklines).", number=i + 1)
        for j in range(i + 1, len(lines)):
            b = lines[j]
            if not a.intersects(b):
                continue
            if line_crossing(a, b) is None:
                continue
            x, y = a.intersection(b).representative_point().coords[0][:2]
            raise InputError.of("Breaklines {first} and {second} cross at ({x:.2f}, {y:.2f}); "
                                "breaklines must not cross or touch — fix them in edits.gpkg.",
                                first=i + 1, second=j + 1, x=x, y=y)


__all__ = ["SAME_POINT_M", "check_breaklines", "line_crossing", "self_crossings"]
