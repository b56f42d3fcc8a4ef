r"""Height profiles of several DEMs along one line: CSV table and plot.

The line (a vector layer's first line feature in any CRS, or coordinates ``"x1,y1;x2,y2;…"`` in
the first DEM's CRS) is transformed to the first DEM's CRS and sampled at a constant spacing
:math:`s` along its length: with cumulative vertex distances :math:`d_k` the sample at distance
:math:`t_j = j\,s` (plus the end point :math:`t = L`) lies on the segment
:math:`d_k \le t_j \le d_{k+1}` at
:math:`P = P_k + (t_j - d_k)/(d_{k+1} - d_k)\,(P_{k+1} - P_k)`. Every DEM is sampled bilinearly
there (in its own CRS, block by block: :func:`.points.sample_dem`); cells outside a DEM stay
empty.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import fiona
import numpy as np
import rasterio
from numpy.typing import NDArray
from rasterio.crs import CRS
from rasterio.warp import transform as warp_transform

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from ..raster.io import atomic_output
from .names import distinct_names
from .points import sample_dem
from .report import new_figure, png_bytes

PathLike = Union[str, Path]

#: Most samples along one profile (a finer spacing is refused).
MAX_SAMPLES = 1_000_000


def parse_coordinates(text: str) -> NDArray[np.float64]:
    """``"x1,y1;x2,y2;…"`` (or ``"x1 y1, x2 y2"`` pairs separated by ``;``) → (n, 2) array.

    Raises
    ------
    InputError
        When a vertex is not two numbers or there are fewer than 2 vertices.
    """
    vertices = []
    for part in (p.strip() for p in str(text).split(";")):
        if not part:
            continue
        tokens = [t for t in part.replace(",", " ").split() if t]
        try:
            xy = [float(t) for t in tokens]
        except ValueError:
            xy = []
        if len(xy) != 2 or not all(math.isfinite(v) for v in xy):
            raise InputError(f"Profile vertex '{part}' is not 'x,y'; give the line as "
                             "'x1,y1;x2,y2;…'.")
        vertices.append(xy)
    arr = np.array(vertices, dtype=float).reshape(-1, 2)
    _check_vertices(arr, "The coordinates")
    return arr


def _check_vertices(xy: NDArray[Any], what: str) -> None:
    if len(xy) < 2:
        raise InputError(f"{what} give a line with {len(xy)} vertex; a profile needs at least "
                         "2 vertices.")
    if float(np.sum(np.hypot(*np.diff(xy, axis=0).T))) <= 0.0:
        raise InputError(f"{what} give a line of zero length; a profile needs two distinct "
                         "vertices.")


def read_line(path: PathLike) -> Tuple[NDArray[np.float64], Optional[str]]:
    """Vertices (x, y) and CRS (WKT) of the first line feature of a vector file.

    A MultiLineString contributes its first part.

    Raises
    ------
    InputError
        No line feature, or one with fewer than 2 vertices.
    """
    path = Path(path)
    if not path.exists():
        raise InputError(f"Line file '{path}' does not exist.")
    try:
        layers = fiona.listlayers(str(path))
    except Exception as exc:  # driver-specific errors
        raise InputError(f"Cannot read the line file '{path.name}': {exc}") from exc
    for layer in layers:
        with fiona.open(str(path), layer=layer) as src:
            crs = src.crs_wkt or None
            for feature in src:
                geom = feature["geometry"]
                if geom is None:
                    continue
                if geom["type"] == "LineString":
                    coords = geom["coordinates"]
                elif geom["type"] == "MultiLineString" and geom["coordinates"]:
                    coords = geom["coordinates"][0]
                else:
                    continue
                xy = np.array([c[:2] for c in coords], dtype=float).reshape(-1, 2)
                _check_vertices(xy, f"The first line of '{path.name}'")
                return xy, crs
    raise InputError(f"'{path.name}' holds no line feature; draw the profile line as a "
                     "LineString layer.")


def sample_line(vertices: NDArray[Any], spacing: float
                ) -> Tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Distances and positions every ``spacing`` along a polyline (the end point included).

    Returns
    -------
    distance, x, y : ndarray, shape (m,)
    """
    v = np.asarray(vertices, dtype=float)
    seg = np.hypot(*np.diff(v, axis=0).T)
    keep = np.concatenate([[True], seg > 0])  # repeated vertices would break np.interp
    v = v[keep]
    cum = np.concatenate([[0.0], np.cumsum(seg[seg > 0])])
    length = float(cum[-1])
    n = math.floor(length / spacing + 1e-9)
    t = np.arange(n + 1) * spacing
    if length - t[-1] > 1e-9 * max(length, 1.0):
        t = np.append(t, length)
    return t, np.interp(t, cum, v[:, 0]), np.interp(t, cum, v[:, 1])


def _cell_metres(src: Any) -> float:
    t = src.transform
    cell = min(math.hypot(t.a, t.d), math.hypot(t.b, t.e))
    if src.crs is not None and src.crs.is_geographic:
        lat = src.bounds.bottom + 0.5 * (src.bounds.top - src.bounds.bottom)
        cell *= 111_320.0 * max(math.cos(math.radians(lat)), 1e-3)
    return cell


def dem_profile(dems: Sequence[PathLike], *, csv_path: PathLike, png_path: PathLike,
                line: Optional[PathLike] = None, coordinates: Optional[str] = None,
                spacing: Optional[float] = None,
                feedback: Optional[Feedback] = None) -> Dict[str, Any]:
    """Sample DEMs along a line and write the table and a plot.

    Parameters
    ----------
    dems : sequence of path
        DEM rasters; the first one's CRS is the profile's CRS (must be projected, metres).
    csv_path, png_path : path
        Outputs: ``distance,x,y,<one column per DEM>`` (empty = outside/nodata; columns
        named by :func:`.names.distinct_names`, ``m1/dtm`` and ``m2/dtm`` for two ``dtm.tif``)
        and the plot.
    line : path, optional
        Vector file whose first line feature is the profile (any CRS; transformed).
    coordinates : str, optional
        ``"x1,y1;x2,y2;…"`` in the first DEM's CRS (when no ``line`` is given).
    spacing : float, optional
        Sample spacing in metres; default the finest DEM cell.

    Returns
    -------
    dict
        ``csv``, ``png`` (paths), ``length`` (m), ``samples``, ``coverage`` (share of samples
        with a height, per DEM column name) and ``columns``.

    Raises
    ------
    InputError
        No DEM, neither or a bad line, a line with < 2 vertices, a geographic first DEM, too
        many samples, or a DEM that does not cover the line at all.
    """
    feedback = ensure_feedback(feedback)
    dems = [Path(d) for d in dems]
    if not dems:
        raise InputError("Give at least one DEM for the profile.")
    for d in dems:
        if not d.is_file():
            raise InputError(f"DEM '{d}' does not exist.")
    if line is None and not (coordinates and str(coordinates).strip()):
        raise InputError("Give the profile line: a line layer ('line') or coordinates "
                         "'x1,y1;x2,y2;…' ('coordinates').")
    with rasterio.open(dems[0]) as first:
        work_crs = first.crs
        cells = []
    if work_crs is not None and work_crs.is_geographic:
        raise InputError(f"The first DEM '{dems[0].name}' has a geographic CRS; the profile "
                         "needs distances in metres: list a DEM in a projected CRS first.")
    for d in dems:
        with rasterio.open(d) as src:
            cells.append(_cell_metres(src))
    if line is not None:
        vertices, line_crs = read_line(line)
        if line_crs is not None and work_crs is not None and \
                CRS.from_user_input(line_crs) != work_crs:
            xs, ys = warp_transform(CRS.from_user_input(line_crs), work_crs,
                               vertices[:, 0].tolist(), vertices[:, 1].tolist())
            vertices = np.column_stack([xs, ys])
    else:
        vertices = parse_coordinates(str(coordinates))
    step = float(spacing) if spacing else min(cells)
    if not (math.isfinite(step) and step > 0):
        raise InputError(f"The profile spacing must be a positive number of metres, not {step}.")
    length = float(np.sum(np.hypot(*np.diff(vertices, axis=0).T)))
    if length / step + 2 > MAX_SAMPLES:
        raise InputError(f"The line is {length:.0f} m long: a spacing of {step:g} m gives more "
                         f"than {MAX_SAMPLES} samples; choose a larger spacing.")
    dist, x, y = sample_line(vertices, step)
    names = distinct_names(dems)
    heights: List[NDArray[np.float64]] = []
    for k, d in enumerate(dems):
        z = sample_dem(d, x, y, crs=work_crs)
        if not np.isfinite(z).any():
            raise InputError(f"The DEM '{d.name}' does not cover the profile line (or only "
                             "nodata there); check the line and the DEM's CRS.")
        share = float(np.isfinite(z).mean())
        if share < 1.0:
            feedback.warning(f"'{d.name}' has heights for {100 * share:.1f} % of the profile.")
        heights.append(z)
        feedback.progress(80.0 * (k + 1) / len(dems))
    _write_csv(csv_path, dist, x, y, names, heights)
    _write_plot(png_path, dist, names, heights, step)
    return {
        "csv": str(csv_path),
        "png": str(png_path),
        "length": length,
        "samples": len(dist),
        "spacing": step,
        "columns": names,
        "coverage": {n: float(np.isfinite(z).mean()) for n, z in zip(names, heights)},
    }


def _write_csv(path: PathLike, dist: NDArray[Any], x: NDArray[Any], y: NDArray[Any],
               names: Sequence[str], heights: Sequence[NDArray[Any]]) -> None:
    cols = [np.char.mod("%.3f", dist), np.char.mod("%.3f", x), np.char.mod("%.3f", y)]
    for z in heights:
        text = np.char.mod("%.4f", np.nan_to_num(z))
        cols.append(np.where(np.isfinite(z), text, ""))
    body = [",".join(row) for row in zip(*cols)]
    header = ",".join(["distance", "x", "y", *[n.replace(",", "_") for n in names]])
    with atomic_output(path) as tmp:
        tmp.write_text("\n".join([header, *body]) + "\n", encoding="utf-8")


def _write_plot(path: PathLike, dist: NDArray[Any], names: Sequence[str],
                heights: Sequence[NDArray[Any]], spacing: float) -> None:
    fig = new_figure(10.0, 4.5)
    ax = fig.add_subplot(1, 1, 1)
    for name, z in zip(names, heights):
        ax.plot(dist, z, linewidth=1.2, label=name)
    ax.set_xlabel("Distance along the line [m]")
    ax.set_ylabel("Height [m]")
    ax.set_title(f"Height profile: {len(names)} DEM(s), {dist[-1]:.1f} m, "
                 f"sample spacing {spacing:g} m")
    ax.grid(True, alpha=0.3)
    ax.set_xlim(0.0, float(dist[-1]))
    ax.legend(loc="best", fontsize=9)
    fig.tight_layout()
    with atomic_output(path) as tmp:
        tmp.write_bytes(png_bytes(fig))


__all__ = ["MAX_SAMPLES", "dem_profile", "parse_coordinates", "read_line", "sample_line"]
