r"""Profiles and point values of several surfaces for the QC panel (no files written).

:func:`surface_profile` samples up to :data:`MAX_SURFACES` surfaces along a line exactly as
``dem_profile`` does (:func:`~.profile.sample_line` stations, :func:`~.points.sample_dem`
bilinear heights) and adds what the operator checks beside the curves: where the project's
breaklines cross the line (distance along it, and the breakline's own height there when it is
3-D), the check points within ``near`` metres of it (distance along, offset, height), and, for a
LineString Z, the line's own vertex heights. :func:`identify` gives every surface's value at a
point and the pairwise differences. :func:`write_profile_csv` exports a profile.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Union

import numpy as np
import rasterio
from shapely.geometry import LineString, Point

from ..errors import InputError
from ..project.edits import read_layer
from ..raster.io import atomic_output
from .names import distinct_names
from .points import sample_dem
from .profile import MAX_SAMPLES, _cell_metres, sample_line

PathLike = Union[str, Path]

#: Most surfaces in one profile.
MAX_SURFACES = 5


def _line_z(line: LineString, dist: float) -> Optional[float]:
    """Height of a 3-D line at ``dist`` along it (linear between vertices), None if 2-D."""
    if not line.has_z:
        return None
    xyz = np.asarray(line.coords, dtype=float)
    cum = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xyz[:, :2], axis=0).T))])
    return float(np.interp(dist, cum, xyz[:, 2]))


def _crossing_points(line: LineString, other: Any) -> List[Point]:
    inter = line.intersection(other)
    if inter.is_empty:
        return []
    if inter.geom_type == "Point":
        return [inter]
    if inter.geom_type == "MultiPoint":
        return list(inter.geoms)
    return [Point(g.coords[0]) for g in getattr(inter, "geoms", [inter]) if not g.is_empty]


def breakline_crossings(line: LineString, edits: PathLike) -> List[Dict[str, Any]]:
    """Crossings of the profile line with the breaklines of ``edits.gpkg`` (project CRS).

    Returns ``{"distance", "x", "y", "z" (the breakline's height or None), "kind", "fid"}``
    sorted along the line.
    """
    out = []
    for fid, (geom, props) in enumerate(read_layer(edits, "breaklines"), start=1):
        for part in getattr(geom, "geoms", [geom]):
            for p in _crossing_points(line, part):
                out.append({"distance": float(line.project(p)), "x": p.x, "y": p.y,
                            "z": _line_z(part, part.project(p)), "kind": props.get("kind"),
                            "fid": fid})
    return sorted(out, key=lambda c: c["distance"])


def near_check_points(line: LineString, edits: PathLike, near: float) -> List[Dict[str, Any]]:
    """Check points of ``edits.gpkg`` within ``near`` metres of the line.

    Returns ``{"distance", "offset", "x", "y", "z", "id"}`` sorted along the line.
    """
    out = []
    for geom, props in read_layer(edits, "check_points"):
        if geom.is_empty or line.distance(geom) > near:
            continue
        out.append({"distance": float(line.project(geom)), "offset": float(line.distance(geom)),
                    "x": geom.x, "y": geom.y, "z": geom.z if geom.has_z else None,
                    "id": props.get("id")})
    return sorted(out, key=lambda c: c["distance"])


def surface_profile(surfaces: Sequence[PathLike], vertices: Any, *,
                    spacing: Optional[float] = None, edits: Optional[PathLike] = None,
                    near: float = 2.0, names: Optional[Sequence[str]] = None
                    ) -> Dict[str, Any]:
    """Heights of up to 5 surfaces along a line, with breakline crossings and check points.

    Parameters
    ----------
    surfaces : sequence of path
        Rasters, the first one's CRS is the line's (projected, metres).
    vertices : array_like, shape (n, 2) or (n, 3)
        The line; a third column is the line's own heights (LineString Z).
    spacing : float, optional
        Station spacing (m); default the finest cell.
    edits : path, optional
        The project's ``edits.gpkg`` (breaklines, check points), in the same CRS.
    near : float
        Check points up to this distance from the line (m) are returned.
    names : sequence of str, optional
        Curve names; default :func:`~.names.distinct_names` of the paths.

    Returns
    -------
    dict
        ``distance, x, y`` (arrays), ``heights`` {name: array (NaN outside)}, ``names``,
        ``length``, ``spacing``, ``vertices`` {``distance``, ``z``} (Z lines, else None),
        ``crossings``, ``check_points``.
    """
    paths = [Path(p) for p in surfaces]
    if not 1 <= len(paths) <= MAX_SURFACES:
        raise InputError(f"A profile shows 1 to {MAX_SURFACES} surfaces, not {len(paths)}.")
    for p in paths:
        if not p.is_file():
            raise InputError(f"The surface '{p}' does not exist.")
    v = np.asarray(vertices, dtype=float)
    if v.ndim != 2 or v.shape[0] < 2 or v.shape[1] not in (2, 3) or not np.isfinite(v).all():
        raise InputError("The profile line needs at least two vertices (x, y[, z]).")
    line = LineString(v.tolist())
    if line.length <= 0:
        raise InputError("The profile line has zero length; draw two distinct points.")
    if spacing is None:
        cells = []
        for p in paths:
            with rasterio.open(p) as src:
                cells.append(_cell_metres(src))
        spacing = min(cells)
    if line.length / spacing + 2 > MAX_SAMPLES:
        raise InputError(f"The line is {line.length:.0f} m long: a spacing of {spacing:g} m "
                         f"gives more than {MAX_SAMPLES} samples; choose a larger spacing.")
    dist, x, y = sample_line(v[:, :2], float(spacing))
    with rasterio.open(paths[0]) as first:
        crs = first.crs
    labels = list(names) if names else distinct_names(paths)
    heights = {n: sample_dem(p, x, y, crs=crs) for n, p in zip(labels, paths)}
    vert = None
    if v.shape[1] == 3:
        cum = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(v[:, :2], axis=0).T))])
        vert = {"distance": cum, "z": v[:, 2].copy()}
    return {
        "distance": dist, "x": x, "y": y, "heights": heights, "names": labels,
        "length": float(line.length), "spacing": float(spacing), "vertices": vert,
        "crossings": breakline_crossings(line, edits) if edits else [],
        "check_points": near_check_points(line, edits, near) if edits else [],
    }


def write_profile_csv(path: PathLike, profile: Dict[str, Any]) -> Path:
    """Write ``distance,x,y,<one column per surface>`` (empty = no height) atomically."""
    cols = [np.char.mod("%.3f", profile["distance"]), np.char.mod("%.3f", profile["x"]),
            np.char.mod("%.3f", profile["y"])]
    for name in profile["names"]:
        z = profile["heights"][name]
        cols.append(np.where(np.isfinite(z), np.char.mod("%.4f", np.nan_to_num(z)), ""))
    header = ",".join(["distance", "x", "y", *[n.replace(",", "_") for n in profile["names"]]])
    with atomic_output(path) as tmp:
        tmp.write_text("\n".join([header, *(",".join(r) for r in zip(*cols))]) + "\n",
                       encoding="utf-8")
    return Path(path)


def identify(surfaces: Sequence[PathLike], x: float, y: float, crs: Any = None,
             names: Optional[Sequence[str]] = None) -> Dict[str, Any]:
    """Every surface's height at (x, y) and their pairwise differences.

    Returns
    -------
    dict
        ``values`` {name: height or None}, ``differences`` [(a, b, h_a − h_b or None)] for each
        pair a before b in the order given.
    """
    paths = [Path(p) for p in surfaces]
    labels = list(names) if names else distinct_names(paths)
    values: Dict[str, Optional[float]] = {}
    for n, p in zip(labels, paths):
        z = float(sample_dem(p, [x], [y], crs=crs)[0])
        values[n] = z if np.isfinite(z) else None
    diffs = []
    for i, a in enumerate(labels):
        for b in labels[i + 1:]:
            va, vb = values[a], values[b]
            diffs.append((a, b, va - vb if va is not None and vb is not None else None))
    return {"x": float(x), "y": float(y), "values": values, "differences": diffs}


__all__ = ["MAX_SURFACES", "breakline_crossings", "identify", "near_check_points",
           "surface_profile", "write_profile_csv"]
