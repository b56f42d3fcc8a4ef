r"""DSM of one stereo model by hierarchical feature-based matching + LSM (seed-000 §3.3).

1. :func:`.model_setup.prepare_model`: epipolar geometry, height and disparity range,
   measuring area (stereo overlap ∩ boundaries), exclusion areas, breaklines, DSM grid
   (default spacing 2 × GSD).
2. Grey epipolar images of both images; the operator's constraints are carried into the left
   epipolar image: exclusion areas and the outside of the boundaries become the ``mask`` (not
   matched), breaklines become ``barriers`` (approximations do not propagate across them), the
   start points of ``edits.gpkg`` (with heights) become ``seeds``. Without start points the
   coarsest level searches the whole height range.
3. :func:`.hierarchy.match_epipolar_fbm_lsm`: image pyramids coarse → fine, Förstner points,
   candidate matching with robust consistency and a bidirectional check, LSM at the finest
   level; failed windows are marked, matching goes on around them.
4. Every raw point is intersected (:meth:`EpipolarPair.disparity_to_world`) with
   :math:`\sigma_Z = |Z(d + \sigma_d) - Z(d)|`; points outside the measuring area or inside
   an exclusion area are dropped.
5. Groundel reduction (:func:`..surface.groundel.reduce_groundels`, cell ``groundel`` m,
   default 40 GSD ≈ √2 × the FBM window on the ground): robust L1 plane / median / lower
   envelope per cell, σ1 (raw points), σ2 = F·σ1/√n̄ (reduced points), outlier flags.
6. The DSM grid from the inlier points (weights 1/σ_Z²) by the finite-element interpolation
   with curvature regularisation (:func:`..surface.fe_grid.fe_interpolate`), which honours
   breaklines, exclusion areas (NaN) and boundaries, or by the median per cell + membrane
   gap filling (``interpolation="membrane"``).

Outputs (staged folder: nothing is left behind on error or cancel): ``dsm.tif``,
``sigma.tif`` (σ2 of the groundel each cell lies in, m), ``count.tif`` (raw points per cell),
``points.gpkg`` / ``points.las`` (raw points: σ_Z, σ_d, ρ, flags, level, outlier),
``reduced.gpkg`` / ``.las`` (one point per groundel), ``report.json`` and ``report.html``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple, Union

import numpy as np
from affine import Affine
from matplotlib.path import Path as MplPath
from rasterio.features import rasterize
from scipy import ndimage
from shapely.geometry import LineString, Point, Polygon

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from ..geometry.epipolar import SIDES
from ..project.edits import read_layer
from ..raster.io import staged_folder
from ..surface.fe_grid import fe_interpolate
from ..surface.gridding import GridAccumulator, finish_grid, polygon_mask, write_grid
from ..surface.groundel import reduce_groundels
from ..surface.jumps import jump_breaklines, point_support
from ..surface.point_output import write_points
from .hierarchy import EpipolarMatches, FbmLsmOptions, match_epipolar_fbm_lsm
from .model_report import coverage_sentence, write_model_report
from .model_setup import ModelSetup, footprint, prepare_model
from .presets import (
    DEFAULT_PRESET,
    POINT_FORMATS,
    PRESET_NAMES,
    PRESETS,
    SPACING_GSD,
    resolve_preset,
)

PathLike = Union[str, Path]



def _grey(image: np.ndarray, pair: Any, side: str) -> np.ndarray:
    """Grey (band mean) epipolar image, float32, NaN outside the original image."""
    img, valid = pair.resample(image, side)
    grey = img.astype(np.float32)
    if grey.ndim == 3:
        grey = grey.mean(axis=0)
    grey[~valid] = np.nan
    return grey


def _to_epipolar(setup: ModelSetup, coords: np.ndarray, z: float) -> np.ndarray:
    """Object (x, y[, z]) vertices → left epipolar (col, row); missing z → ``z``."""
    c = np.asarray(coords, dtype=float)
    zz = c[:, 2] if c.shape[1] > 2 else np.full(len(c), z)
    zz = np.where(np.isfinite(zz), zz, z)
    col, row = setup.pair.world_to_epipolar(np.column_stack([c[:, 0], c[:, 1], zz]), "left")
    return np.column_stack([col, row])


def _epipolar_shapes(setup: ModelSetup, geoms: List[Any], z: float) -> List[Any]:
    out = []
    for g in geoms:
        for part in getattr(g, "geoms", [g]):
            if part.geom_type == "Polygon":
                ext = _to_epipolar(setup, np.asarray(part.exterior.coords), z)
                holes = [_to_epipolar(setup, np.asarray(h.coords), z) for h in part.interiors]
                poly = Polygon(ext, holes)
                if np.isfinite(ext).all():
                    out.append(poly.buffer(0))
            elif part.geom_type == "LineString":
                xy = _to_epipolar(setup, np.asarray(part.coords), z)
                if np.isfinite(xy).all() and len(xy) > 1:
                    out.append(LineString(xy))
    return out


def epipolar_constraints(setup: ModelSetup, shape: Tuple[int, int]
                         ) -> Tuple[Optional[np.ndarray], Optional[np.ndarray]]:
    """Mask (exclusions, outside the boundaries) and barriers (breaklines) in the left image.

    Polygons are projected at the model's mid height (the exact test is made in object space
    after the intersection); breaklines at their own heights.
    """
    centre = Affine.translation(-0.5, -0.5)  # pixel centres at integer coordinates
    mask = None
    excl = _epipolar_shapes(setup, setup.exclusions, setup.z_mid)
    if excl:
        mask = rasterize([(g, 1) for g in excl], out_shape=shape, transform=centre,
                         dtype="uint8").astype(bool)
    if setup.boundaries:
        inside = _epipolar_shapes(setup, setup.boundaries, setup.z_mid)
        keep = rasterize([(g, 1) for g in inside], out_shape=shape, transform=centre,
                         dtype="uint8").astype(bool) if inside else np.zeros(shape, bool)
        mask = ~keep if mask is None else (mask | ~keep)
    barriers = None
    lines = _epipolar_shapes(setup, setup.breaklines, setup.z_mid)
    if lines:
        barriers = rasterize([(g, 1) for g in lines], out_shape=shape, transform=centre,
                             all_touched=True, dtype="uint8").astype(bool)
    return mask, barriers


def start_point_seeds(setup: ModelSetup) -> Optional[np.ndarray]:
    """The operator's start points as seeds ``(col, row, disparity)`` of the left image.

    Raises
    ------
    InputError
        A start point without a height, outside the model or inside an exclusion area.
    """
    path = Path(setup.project.edits_path)
    if not path.is_file():
        return None
    try:
        feats = read_layer(path, "start_points")
    except InputError:
        return None
    if not feats:
        return None
    seeds = []
    for k, (geom, props) in enumerate(feats, start=1):
        h = props.get("height")
        if h is None and geom.has_z:
            h = geom.z
        if h is None or not np.isfinite(float(h)):
            raise InputError(f"Start point {k} has no height; enter its terrain height (m) in "
                             "edits.gpkg (layer start_points, field height).")
        h = float(h)
        p = Point(geom.x, geom.y)
        inside = all(footprint(c, r.eo, h).contains(p)
                     for c, r in zip(setup.cameras, setup.records))
        if setup.boundaries:
            inside = inside and any(b.contains(p) for b in setup.boundaries)
        if not inside:
            raise InputError(f"Start point {k} at ({geom.x:.2f}, {geom.y:.2f}) lies outside "
                             f"model '{setup.model.name}'; move it into the stereo overlap.")
        if any(e.contains(p) for e in setup.exclusions):
            raise InputError(f"Start point {k} at ({geom.x:.2f}, {geom.y:.2f}) lies in an "
                             "exclusion area; move it out or delete it.")
        world = np.array([[geom.x, geom.y, h]])
        cl, row = setup.pair.world_to_epipolar(world, "left")
        cr, _ = setup.pair.world_to_epipolar(world, "right")
        seeds.append([float(cl[0]), float(row[0]), float(cl[0] - cr[0])])
    return np.asarray(seeds, dtype=float)


#: Convergent models (axes more than :data:`~..geometry.epipolar.CONVERGENT_DEG` apart, drone
#: and oblique pairs): matching windows 1.5 × the preset's, a bidirectional tolerance of at
#: least 1 px and Förstner points down to roundness 0.4. Why: on the synthetic drone block
#: (issue 22, 10 cm GSD, B/H 0.44–0.92) a metre of height is 4–8 px of parallax, so half of the
#: 32 px windows hold trees or buildings whose disparity differs by > 8 px from their ground
#: (0101_0103: 244 of 475 windows); 83 % of the failed windows are such windows (55 % of them
#: fail, 11 % of those with < 4 px): the window plane from the coarser level is off by 12 px
#: (median), few candidates reach ρ ≥ 0.55 on the obliquely seen crowns and walls, and the
#: right→left search of the others lands up to a pixel away (the views see a slanted patch at
#: different scales). Larger windows hold a ground majority, their objects become outliers of
#: the plane and are measured point by point by the grid densification; corners foreshortened
#: in one view are less round. Failed windows at the finest level, models 0101_0102 /
#: 0202_0203 / 0201_0203 / 0101_0103 (seed 1): 22 / 22 / 36 / 32 % → 16 / 10 / 20 / 17 %
#: (48 px and 1 px alone: 16 / 13 / 22 / 17 %; 40 px: 21 / – / – / 24 %; 9 or 11 px NCC,
#: ρ ≥ 0.45, a 40 px object pull-in: ≥ 27 % on 0101_0103); seed 2 (more and taller objects):
#: 39 / 32 / 46 / 50 % → 29 / 16 / 28 / 33 %; open-terrain NMAD unchanged on both.
#: Explicit options win; nadir models keep the preset.
_CONVERGENT_WINDOW_FACTOR = 1.5
_CONVERGENT_BIDIR_TOL = 1.0
_CONVERGENT_Q_MIN = 0.4


def _convergent_values(values: Dict[str, Any]) -> Dict[str, Any]:
    """The preset's values with the convergent-model changes (:data:`_CONVERGENT_WINDOW_FACTOR`,
    :data:`_CONVERGENT_BIDIR_TOL`, :data:`_CONVERGENT_Q_MIN`)."""
    window = int(values.get("fbm_window", FbmLsmOptions.fbm_window))
    bidir = float(values.get("bidir_tol", FbmLsmOptions.bidir_tol))
    q_min = float(values.get("q_min", FbmLsmOptions.q_min))
    return dict(values, fbm_window=round(_CONVERGENT_WINDOW_FACTOR * window),
                bidir_tol=max(bidir, _CONVERGENT_BIDIR_TOL), q_min=min(q_min, _CONVERGENT_Q_MIN))


def _options(preset: str, overrides: Dict[str, Any], convergent: bool = False
             ) -> Tuple[Any, Dict[str, Any]]:
    """Hierarchy options and surface options from a preset, the convergent-model changes
    (``convergent``) and explicit values (which win)."""
    if preset not in PRESETS:
        raise InputError(f"Unknown preset '{preset}'; use one of {', '.join(PRESET_NAMES)}.")
    values = dict(PRESETS[preset])
    if convergent:
        values = _convergent_values(values)
    values.update({k: v for k, v in overrides.items() if v is not None})
    names = {f.name for f in fields(FbmLsmOptions)}
    surface_keys = ("groundel_gsd", "reduction", "smoothing", "objects", "object_height_m",
                    "wall_offset_gsd", "jump_weak_slope")
    unknown = set(values) - names - set(surface_keys)
    if unknown:
        raise InputError(f"Unknown matching option(s): {', '.join(sorted(unknown))}.")
    options = replace(FbmLsmOptions(), **{k: v for k, v in values.items() if k in names})
    surface = {k: values[k] for k in surface_keys if k in values}
    return options, surface


def _object_search(opts: FbmLsmOptions, surface: Dict[str, Any], setup: ModelSetup
                   ) -> FbmLsmOptions:
    """The grid densification's upward band from the preset's object height (m), in px of
    this model's parallax (explicit ``object_search`` wins).

    Why per model: the same 8 m roof is ≈ 15 px of parallax on the ``small`` block (B/H 0.36,
    GSD 0.2 m) but ≈ 33 px on the wide-angle ``aerial`` block (B/H 0.6, GSD 0.15 m), beyond
    the 20 px pull-in there (issue 19).
    """
    height = surface.get("object_height_m")
    if opts.object_search is not None or not height:
        return opts
    return replace(opts, object_search=float(height) * setup.parallax_per_metre)


def _model_options(preset: str, overrides: Dict[str, Any], setup: ModelSetup
                   ) -> Tuple[FbmLsmOptions, Dict[str, Any]]:
    """:func:`_options` for a prepared model: its convergence, and the object search in px
    of its parallax (:func:`_object_search`)."""
    opts, surface = _options(preset, overrides, convergent=setup.convergent)
    return _object_search(opts, surface, setup), surface


def _on_surface(pair: Any, col: np.ndarray, row: np.ndarray, min_d: float, max_d: float,
                z_grid: np.ndarray, grid: Any, steps: int = 128) -> np.ndarray:
    """Ground position (n, 2) of left epipolar pixels: where their ray meets the DSM.

    Failed windows have no disparity; their rays are sampled over the disparity range and
    the first crossing of the DSM (nearest cell) is taken, so the report's failure map shows
    them where they are, not where the middle of a range of hundreds of metres would put them.
    Rays that do not meet the DSM keep the middle of the range.
    """
    d = np.linspace(min_d, max_d, steps)
    w = pair.disparity_to_world(np.broadcast_to(d, (col.size, steps)),
                                np.repeat(col[:, None], steps, 1),
                                np.repeat(row[:, None], steps, 1))
    r, c = grid.cell_of(w[..., 0], w[..., 1])
    inside = r >= 0
    surf = np.full(r.shape, np.nan)
    surf[inside] = z_grid[r[inside], c[inside]]
    above = w[..., 2] - surf  # grows with the disparity (the ray point rises)
    cross = (above[:, :-1] < 0) & (above[:, 1:] >= 0)
    k = np.where(cross.any(1), cross.argmax(1), -1)
    out = w[:, steps // 2, :2].copy()
    hit = k >= 0
    if hit.any():
        i = np.flatnonzero(hit)
        a0, a1 = above[i, k[hit]], above[i, k[hit] + 1]
        t = (-a0 / (a1 - a0))[:, None]
        out[hit] = (1 - t) * w[i, k[hit], :2] + t * w[i, k[hit] + 1, :2]
    return out


def _inside_any(polygons: List[Any], x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Points strictly inside any of the (multi)polygons (holes honoured), vectorised."""
    out = np.zeros(len(x), bool)
    xy = np.column_stack([x, y])
    for g in polygons:
        for part in getattr(g, "geoms", [g]):
            if part.geom_type != "Polygon" or part.is_empty:
                continue
            x0, y0, x1, y1 = part.bounds
            cand = np.flatnonzero((x >= x0) & (x <= x1) & (y >= y0) & (y <= y1) & ~out)
            if cand.size == 0:
                continue
            inside = MplPath(np.asarray(part.exterior.coords)[:, :2]).contains_points(xy[cand])
            for hole in part.interiors:
                inside &= ~MplPath(np.asarray(hole.coords)[:, :2]).contains_points(xy[cand])
            out[cand[inside]] = True
    return out


def _cell_lookup(grid: Any, x: np.ndarray, y: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """Flat cell index of points (−1 outside the grid)."""
    r, c = grid.cell_of(x, y)
    r = np.asarray(r)
    c = np.asarray(c)
    ok = (r >= 0) & (r < grid.height) & (c >= 0) & (c < grid.width)
    return np.where(ok, r * grid.width + c, -1), ok


def _sigma2_on(red: Any, grid: Any) -> np.ndarray:
    """σ2 = F·σ1_cell/√n of the groundel each DSM cell centre lies in (NaN: no σ)."""
    g, layers = red.grid()
    with np.errstate(invalid="ignore", divide="ignore"):
        s2 = red.F * layers["sigma1"] / np.sqrt(layers["n"].astype(np.float32))
    t = grid.transform
    xs = t.c + (np.arange(grid.width) + 0.5) * t.a
    ys = t.f + (np.arange(grid.height) + 0.5) * t.e
    r, _ = g.cell_of(np.zeros_like(ys) + g.transform.c, ys)
    _, c = g.cell_of(xs, np.zeros_like(xs) + g.transform.f - 0.5 * g.spacing)
    out = np.full(grid.shape, np.nan, np.float32)
    rr, cc = np.meshgrid(r, c, indexing="ij")
    ok = (rr >= 0) & (cc >= 0)
    out[ok] = s2[rr[ok], cc[ok]]
    return out


@dataclass
class _ModelPoints:
    """Raw points in object space that pass the object-space constraints.

    Attributes
    ----------
    xyz : (n, 3) float64
    sigma_z : (n,) float64
        σ_Z = |Z(d + σ_d) − Z(d)|, m.
    cell : (n,) int64
        Flat DSM cell index of each point.
    keep : (n,) int64
        Index of each point in the matcher's arrays.
    allowed : bool grid
        DSM cells inside the measuring area and outside exclusions.
    n_matched : int
        Points of the matcher before the constraints.
    """

    xyz: np.ndarray
    sigma_z: np.ndarray
    cell: np.ndarray
    keep: np.ndarray
    allowed: np.ndarray
    n_matched: int


def _grey_epipolar(setup: ModelSetup, feedback: Feedback
                   ) -> Tuple[Dict[str, np.ndarray], Optional[np.ndarray], Optional[np.ndarray]]:
    """Grey epipolar images of both sides, and the constraints' mask and barriers."""
    grey = {}
    for side, rec in zip(SIDES, setup.records):
        grey[side] = _grey(setup.project.read_image(rec, colour_only=True), setup.pair, side)
        feedback.check()
    mask, barriers = epipolar_constraints(setup, grey["left"].shape)
    return grey, mask, barriers


def _intersect(setup: ModelSetup, matches: EpipolarMatches) -> _ModelPoints:
    """Object points of the matches, kept inside the measuring area and outside exclusions.

    Raises
    ------
    InputError
        Fewer than 3 points remain.
    """
    pair, grid = setup.pair, setup.grid
    col, row, d = matches.col, matches.row, matches.disparity
    pts = pair.disparity_to_world(d, col, row)
    pts_s = pair.disparity_to_world(d + np.maximum(matches.sigma_px, 1e-3), col, row)
    sigma_z = np.abs(pts_s[:, 2] - pts[:, 2])
    ok = np.isfinite(pts).all(axis=1)
    # object-space constraints, exactly: inside the measuring area, outside exclusions
    allowed = polygon_mask([setup.measuring_area()], grid) & ~polygon_mask(setup.exclusions,
                                                                              grid)
    idx, on_grid = _cell_lookup(grid, pts[:, 0], pts[:, 1])
    ok &= on_grid
    ok[ok] = allowed.ravel()[idx[ok]]
    # exactly: a point inside an exclusion area is dropped even where the cell centre is not
    ok[ok] = ~_inside_any(setup.exclusions, pts[ok, 0], pts[ok, 1])
    keep = np.nonzero(ok)[0]
    if len(keep) < 3:
        raise InputError(f"Model '{setup.model.name}': matching found {len(keep)} points; "
                         "check the height range, the start points and the image texture.")
    return _ModelPoints(pts[keep], sigma_z[keep], idx[keep], keep, allowed, len(d))


#: Objects in the surface step (issue 19): neighbourhood of a point's support (groundels),
#: agreeing neighbours that make a groundel outlier part of an upper or lower surface, and
#: the smallest height jump (m) and jump slope between neighbouring points that become an
#: automatic breakline.
OBJECT_SUPPORT_GROUNDELS = 1.5
OBJECT_MIN_SUPPORT = 2
OBJECT_MIN_STEP = 1.5
OBJECT_MIN_SLOPE = 1.0
#: Agreeing neighbours every point needs to be used at all (0: groundel inliers stay in).
OBJECT_LONE = 1
#: Agreeing neighbours the upper point of an edge needs to become a jump by hysteresis: more
#: than the least supported roof points (a roof of a few barely supported points is not
#: closed off; issue 19, part M).
OBJECT_WEAK_SUPPORT = OBJECT_MIN_SUPPORT + 1


def object_surfaces(pts: np.ndarray, red: Any, wall_offset: Optional[float] = None,
                    weak_slope: Optional[float] = None, object_height: Optional[float] = None
                    ) -> Tuple[np.ndarray, List[Any]]:
    """Inliers that keep consistent upper surfaces, and breaklines at the height jumps.

    A groundel outlier with :data:`OBJECT_MIN_SUPPORT` agreeing neighbours (a roof in a
    groundel that is mostly ground) stays in; isolated outliers stay out. Jumps between
    supported neighbouring inliers become 2-D breaklines (:mod:`..surface.jumps`), so that the
    FE surface does not bridge a wall.

    Parameters
    ----------
    pts : (n, 3) float
        Raw points (x, y, z in m; any consistent units, e.g. disparity as z).
    red : GroundelResult
        Their groundel reduction (:func:`..surface.groundel.reduce_groundels`).
    wall_offset : float, optional
        Breaklines this far (m) from the upper point of each jump instead of halfway
        (``upper_offset`` of :func:`..surface.jumps.jump_breaklines`).
    weak_slope : float, optional
        Jump edges grow by hysteresis along edges this steep (``weak_slope`` of
        :func:`..surface.jumps.jump_breaklines`), so the line closes where the ground behind a
        wall lies far from the roof points; only from upper points with
        :data:`OBJECT_WEAK_SUPPORT` agreeing neighbours.
    object_height : float, optional
        Hysteresis only along edges no higher than this (m; ``weak_max_step``): higher steps
        are relief, not the objects looked for.

    Returns
    -------
    inlier : (n,) bool
        Points the surface uses.
    lines : list of shapely geometries
        Automatic 2-D breaklines.
    """
    support = point_support(pts[:, 0], pts[:, 1], pts[:, 2],
                            OBJECT_SUPPORT_GROUNDELS * red.cell_size)
    supported = support >= OBJECT_MIN_SUPPORT
    # a point no neighbour agrees with is a blunder even where its groundel does not flag it
    # (small groundels of few points follow their blunders)
    inlier = (~red.outlier & (support >= OBJECT_LONE)) | supported
    idx = np.flatnonzero(inlier)
    lines = jump_breaklines(pts[idx, 0], pts[idx, 1], pts[idx, 2], OBJECT_MIN_STEP,
                            OBJECT_MIN_SLOPE, supported=supported[idx], upper_offset=wall_offset,
                            weak_slope=weak_slope, weak_max_step=object_height,
                            weak_upper=support[idx] >= OBJECT_WEAK_SUPPORT)
    return inlier, lines


def _surface(setup: ModelSetup, mp: _ModelPoints, red: Any, surface: Dict[str, Any],
             interpolation: str, max_gap: Optional[float], feedback: Feedback) -> np.ndarray:
    """DSM heights (float32, NaN outside the allowed cells) from the inlier points."""
    grid, inlier, pts = setup.grid, ~red.outlier, mp.xyz
    breaklines = list(setup.breaklines)
    if surface.get("objects"):
        offset = surface.get("wall_offset_gsd")
        inlier, auto = object_surfaces(mp.xyz, red,
                                       None if offset is None else float(offset) * setup.gsd,
                                       surface.get("jump_weak_slope"),
                                       surface.get("object_height_m"))
        breaklines += auto
    if interpolation == "fe":
        # a point's weight: its matching σ_Z and the scatter of the points about the local
        # surface (σ1 of the groundels: texture, roughness, objects), which σ_Z of LSM
        # (often a few cm) does not contain — else a few over-confident points bend the plate
        # into ripples between them
        s1 = red.summary().get("sigma1_m")
        s1 = float(s1) if s1 is not None and math.isfinite(s1) else 0.0
        w = 1.0 / (np.maximum(mp.sigma_z[inlier], 1e-3) ** 2 + s1 * s1)
        z_grid, _ = fe_interpolate(pts[inlier, 0], pts[inlier, 1], pts[inlier, 2], grid,
                                   weights=w, smoothing=float(surface.get("smoothing", 1.0)),
                                   reference_spacing=SPACING_GSD * setup.gsd,
                                   breaklines=breaklines, exclusions=setup.exclusions,
                                   boundaries=setup.boundaries, max_gap=max_gap,
                                   feedback=feedback.step(78, 92))
    else:
        acc = GridAccumulator(grid)
        acc.add(pts[inlier, 0], pts[inlier, 1], pts[inlier, 2])
        zg, n_cell = acc.reduce()
        z_grid = finish_grid(zg, n_cell, grid, math.inf if max_gap is None else max_gap,
                             setup.exclusions, setup.boundaries,
                             breaklines).z
    z_grid = np.asarray(z_grid, dtype=np.float32)
    z_grid[~mp.allowed] = np.nan
    return z_grid


def _metrics(setup: ModelSetup, mp: _ModelPoints, red: Any, z_grid: np.ndarray,
             count: np.ndarray, cell: float, seeds: Optional[np.ndarray],
             matches: EpipolarMatches, max_gap: Optional[float]) -> Dict[str, Any]:
    """Headline figures of the model: counts, σ1/σ2, geometry and the shares of the model area
    (``allowed``) that are measured (a height within ½ groundel of a matched point),
    interpolated (a height filled between points) and empty; they add up to 100 %, and
    ``coverage_pct`` = measured + interpolated. ``failed_windows_finest_pct``: the share of
    the matching windows that failed at the finest pyramid level."""
    grid, pair, allowed = setup.grid, setup.pair, mp.allowed
    n_area = int(allowed.sum())
    n_have = int((np.isfinite(z_grid) & allowed).sum())
    coverage = 100.0 * n_have / n_area if n_area else 0.0
    # measured: a height within half a groundel of a matched point (the rest is interpolated)
    near = ndimage.distance_transform_edt(count == 0) * grid.spacing <= 0.5 * cell
    n_measured = int((near & np.isfinite(z_grid) & allowed).sum())
    measured = 100.0 * n_measured / n_area if n_area else 0.0
    summary = red.summary()
    H = setup.flying_height
    return {
        "points_matched": mp.n_matched,
        "points_raw": len(mp.xyz),
        "points_reduced": red.cells,
        "outliers": red.n_outliers,
        "coverage_pct": coverage,
        "measured_pct": measured,
        "interpolated_pct": 100.0 * (n_have - n_measured) / n_area if n_area else 0.0,
        "empty_pct": 100.0 - coverage if n_area else 0.0,
        "sigma1_m": summary.get("sigma1_m"),
        "sigma2_m": summary.get("sigma2_m"),
        "sigma2_permille": (1000.0 * summary["sigma2_m"] / H
                            if summary.get("sigma2_m") is not None else None),
        "spacing_m": setup.spacing,
        "groundel_m": cell,
        "cells": [grid.width, grid.height],
        "disparity_range_px": [setup.min_d, setup.max_d],
        "height_range_m": [setup.z_min, setup.z_max],
        "start_points": 0 if seeds is None else len(seeds),
        "failed_windows": len(matches.failures),
        "failed_windows_finest_pct": matches.stats.get("total", {}).get("failure_pct_level0"),
        "max_gap_m": max_gap,
        "base_px": float(pair.base * pair.focal_px / H) if H > 0 else None,
        "epipolar_mpx": pair.sizes[0][0] * pair.sizes[0][1] / 1e6,
    }


def _write_points(tmp: Path, suffix: str, crs: Any, mp: _ModelPoints, red: Any,
                  matches: EpipolarMatches) -> None:
    """Raw points (σ_Z, σ_d, ρ, flags, level, outlier) and reduced points (one per groundel)."""
    pts, keep = mp.xyz, mp.keep
    write_points(tmp / f"points{suffix}", pts[:, 0], pts[:, 1], pts[:, 2], {
        "sigma_z": mp.sigma_z.astype(np.float32),
        "sigma_px": matches.sigma_px[keep].astype(np.float32),
        "rho": matches.rho[keep].astype(np.float32),
        "flags": matches.flags[keep].astype(np.int32),
        "level": matches.level[keep].astype(np.int32),
        "outlier": red.outlier.astype(np.int32),
    }, crs=crs)
    write_points(tmp / f"reduced{suffix}", red.x, red.y, red.z, {
        "n": red.n.astype(np.int32), "sigma1": red.sigma1.astype(np.float32),
        "sigma2": (red.F * red.sigma1 / np.sqrt(np.maximum(red.n, 1))).astype(np.float32),
        "plane": red.plane.astype(np.int32)}, crs=crs)


def _write_grids(tmp: Path, crs: Any, grid: Any, z_grid: np.ndarray, count: np.ndarray,
                 sigma_grid: Optional[np.ndarray]) -> None:
    """dsm.tif, count.tif (raw points per cell) and sigma.tif (σ2 per cell)."""
    write_grid(tmp / "dsm.tif", z_grid, grid, crs=crs)
    write_grid(tmp / "count.tif", np.minimum(count, 65535).astype(np.uint16), grid,
               crs=crs, overviews=False)
    if sigma_grid is not None:
        write_grid(tmp / "sigma.tif", np.asarray(sigma_grid, np.float32), grid,
                   crs=crs, overviews=False)


def _check_choices(points_format: str, interpolation: str) -> None:
    """Raise InputError for an unknown point format or interpolation."""
    if points_format not in POINT_FORMATS:
        raise InputError(f"Unknown point format '{points_format}'; use gpkg or las.")
    if interpolation not in ("fe", "membrane"):
        raise InputError(f"Unknown interpolation '{interpolation}'; use fe or membrane.")


def _groundel_size(groundel: Optional[float], surface: Dict[str, Any],
                   setup: ModelSetup) -> float:
    """Groundel side (m): explicit, else the preset's multiple of the GSD."""
    cell = float(groundel) if groundel else float(surface["groundel_gsd"]) * setup.gsd
    if not cell > 0:
        raise InputError(f"The groundel size must be positive, got {cell}.")
    return cell


def _timed(timings: Dict[str, float], key: str, t0: float) -> None:
    """Record the seconds since ``t0`` under ``key``."""
    timings[key] = time.perf_counter() - t0


def _announce(setup: ModelSetup, seeds: Optional[np.ndarray], cell: float,
              opts: FbmLsmOptions, feedback: Feedback) -> None:
    """Tell the operator the ranges, start points, DSM grid and groundel size, and the window
    and tolerance of a convergent model."""
    grid = setup.grid
    feedback.info(f"Model {setup.model.name}: heights {setup.z_min:.1f}…{setup.z_max:.1f} m → "
                  f"disparities {setup.min_d}…{setup.max_d} px; "
                  f"{0 if seeds is None else len(seeds)} start point(s); DSM "
                  f"{grid.width}×{grid.height} cells at {setup.spacing:.3f} m; groundels "
                  f"{cell:.2f} m.")
    if setup.convergent:
        feedback.info(f"Model {setup.model.name} is convergent (optical axes "
                      f"{setup.convergence:.0f}° apart): matching windows "
                      f"{opts.fbm_window} px, bidirectional tolerance {opts.bidir_tol:g} px, "
                      f"Förstner roundness ≥ {opts.q_min:g}.")


def _report(setup: ModelSetup, preset: str, metrics: Dict[str, Any],
            matches: EpipolarMatches, red: Any, opts: FbmLsmOptions,
            timings: Dict[str, float]) -> Dict[str, Any]:
    """The content of report.json (keys in the order of the report)."""
    return {"model": setup.model.name, "method": "fbm_lsm", "images": setup.names,
            "crs": setup.project.crs, "flying_height_m": setup.flying_height,
            "preset": preset, "convergent": setup.convergent, "metrics": metrics,
            "levels": matches.stats.get("levels", []), "reduction": red.summary(),
            "matching": {k: v for k, v in matches.stats.items() if k != "levels"},
            "options": {f.name: getattr(opts, f.name) for f in fields(opts)},
            "seconds": timings}


def match_model_fbm_lsm(project: Any, model: str, output_dir: PathLike,
                        spacing: Optional[float] = None, feedback: Optional[Feedback] = None,
                        min_height: Optional[float] = None, max_height: Optional[float] = None,
                        max_gap: Optional[float] = None, preset: str = DEFAULT_PRESET,
                        groundel: Optional[float] = None, reduction: Optional[str] = None,
                        smoothing: Optional[float] = None, interpolation: str = "fe",
                        points_format: str = "gpkg", use_start_points: bool = True,
                        **options: Any) -> Dict[str, Any]:
    """DSM of a stereo model by hierarchical FBM + LSM (see the module notes).

    Parameters
    ----------
    project : Project or path
    model : str
        Stereo model name.
    output_dir : path
        Output folder (created, or replaced if PhotoDEM wrote it).
    spacing : float, optional
        DSM cell size (m); default 2 × the model's GSD.
    min_height, max_height : float, optional
        Height range (m) searched without start points; default terrain height ∓/± 0.3 H.
    max_gap : float, optional
        Cells farther than ``max_gap / 2`` (m) from every matched point stay NaN; default
        (or 0): every cell of the measuring area gets a height, and the report tells the
        measured share (cells within half a groundel of a point) from the interpolated one.
    preset : {"general", "urban", "terrain", "hilly", "forest"}
        Strategy preset (:data:`PRESETS`; convergent models get larger windows,
        :data:`_CONVERGENT_WINDOW_FACTOR`); explicit options win. ``general`` (default) and
        ``urban`` (built-up areas) keep buildings and trees; ``terrain`` (old name ``flat``,
        still accepted with a note in the log) smooths them away.
    groundel : float, optional
        Groundel (reduction cell) side (m); default the preset's ``groundel_gsd`` × GSD.
    reduction : {"l1", "median", "lower"}, optional
        Groundel reduction mode; default the preset's.
    smoothing : float, optional
        Curvature weight of the FE interpolation for cells of :data:`SPACING_GSD` GSD (scaled
        to the DSM spacing, so the surface does not depend on it); default the preset's.
    interpolation : {"fe", "membrane"}
        Finite elements with curvature regularisation, or median per cell + membrane filling.
    points_format : {"gpkg", "las"}
        Format of the point outputs (LAS needs laspy).
    use_start_points : bool
        Use the start points of ``edits.gpkg`` as seeds.
    **options
        Fields of :class:`.hierarchy.FbmLsmOptions` (fbm_window, rho_min, lsm, …).

    Returns
    -------
    dict
        ``{"dsm", "sigma", "count", "points", "reduced", "report", "report_html", "metrics"}``.
    """
    feedback = ensure_feedback(feedback)
    t_start = time.perf_counter()
    _check_choices(points_format, interpolation)
    preset, note = resolve_preset(preset)
    if note:
        feedback.warning(note)
    overrides = dict(options, groundel_gsd=None, reduction=reduction, smoothing=smoothing)
    _options(preset, overrides)  # bad presets and options fail before the model is set up
    setup = prepare_model(project, model, spacing=spacing, spacing_gsd=SPACING_GSD,
                          min_height=min_height, max_height=max_height)
    opts, surface = _model_options(preset, overrides, setup)
    project, m, grid = setup.project, setup.model, setup.grid
    cell = _groundel_size(groundel, surface, setup)
    max_gap = None if max_gap is None or max_gap <= 0 else float(max_gap)
    seeds = start_point_seeds(setup) if use_start_points else None
    _announce(setup, seeds, cell, opts, feedback)
    timings: Dict[str, float] = {}
    t0 = time.perf_counter()
    grey, mask, barriers = _grey_epipolar(setup, feedback)
    _timed(timings, "epipolar", t0)
    feedback.progress(5.0)
    t0 = time.perf_counter()
    matches = match_epipolar_fbm_lsm(grey["left"], grey["right"], setup.min_d, setup.max_d,
                                     seeds=seeds, mask=mask, barriers=barriers, options=opts,
                                     feedback=feedback.step(5, 70))
    del grey
    _timed(timings, "matching", t0)
    t0 = time.perf_counter()
    mp = _intersect(setup, matches)
    _timed(timings, "intersection", t0)
    feedback.progress(72.0)
    t0 = time.perf_counter()
    red = reduce_groundels(mp.xyz[:, 0], mp.xyz[:, 1], mp.xyz[:, 2], cell,
                           origin=(grid.transform.c, grid.transform.f),
                           mode=surface.get("reduction", "l1"))
    _timed(timings, "reduction", t0)
    feedback.progress(78.0)
    t0 = time.perf_counter()
    z_grid = _surface(setup, mp, red, surface, interpolation, max_gap, feedback)
    count = np.bincount(mp.cell, minlength=grid.width * grid.height).reshape(grid.shape)
    sigma_grid = _sigma2_on(red, grid)
    _timed(timings, "gridding", t0)
    feedback.check()
    metrics = _metrics(setup, mp, red, z_grid, count, cell, seeds, matches, max_gap)
    out = Path(output_dir)
    suffix = "." + points_format
    with staged_folder(out, replace=True, product="match_model") as tmp:
        _write_grids(tmp, project.crs, grid, z_grid, count, sigma_grid)
        feedback.progress(94.0)
        _write_points(tmp, suffix, project.crs, mp, red, matches)
        feedback.progress(97.0)
        fails = matches.failures
        fail_xy = None
        if len(fails):
            fail_xy = _on_surface(setup.pair, fails[:, 0], fails[:, 1], setup.min_d,
                                  setup.max_d, z_grid, grid)
        _timed(timings, "total", t_start)
        report = _report(setup, preset, metrics, matches, red, opts, timings)
        write_model_report(tmp, report, dsm=tmp / "dsm.tif",
                           sigma=tmp / "sigma.tif" if sigma_grid is not None else None,
                           count=tmp / "count.tif", failures=fail_xy)
        feedback.progress(100.0)
    feedback.info(f"Model {m.name}: {metrics['points_raw']} points, "
                  f"{metrics['points_reduced']} groundels; {coverage_sentence(metrics)}")
    return {"dsm": str(out / "dsm.tif"),
            "sigma": str(out / "sigma.tif") if sigma_grid is not None else None,
            "count": str(out / "count.tif"), "points": str(out / f"points{suffix}"),
            "reduced": str(out / f"reduced{suffix}"), "report": str(out / "report.json"),
            "report_html": str(out / "report.html"), "metrics": metrics}


__all__ = ["DEFAULT_PRESET", "POINT_FORMATS", "PRESETS", "PRESET_NAMES", "SPACING_GSD",
           "epipolar_constraints", "match_model_fbm_lsm", "object_surfaces", "start_point_seeds"]
