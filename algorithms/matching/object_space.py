r"""Object-space multi-image least-squares matching on a DSM grid (2.5D "facets stereo vision").

Refines a DSM with every image that sees it (2 … N), after Wrobel's FAST Vision as described by
Schlüter (1999) — see ``methods/seed-004.md`` §5 (the minimal 2.5D algorithm, variant I).

Model (per computation window)
    Sample points :math:`p` on a grid of one ground pixel :math:`\Delta s_\ell = GSD\cdot2^\ell`;
    object grey values :math:`G` on a grid of ``grey_px`` pixels, bilinear; heights as the input
    DSM plus a bilinear correction on geometry nodes of ``facet_px`` pixels (aligned with the
    output cells):

    .. math::

       Z_p = Z^{in}_p + \sum_m a_{pm}\,\Delta Z_m, \qquad G_p = \sum_k b_{pk}\,G_k

    With :math:`(c, r)_{pi} = \mathrm{world\_to\_pixel}_i(X_p, Y_p, Z_p)` and the grey value
    :math:`g_{pi}` of image *i* there (bilinear), the radiometric correspondence
    :math:`h_{1i}\,g_{pi} + h_{0i} = G_p` is linearised (Gauss–Newton, unit weights):

    .. math::

       \sum_k b_{pk}\,dG_k - k_{pi}\sum_m a_{pm}\,dZ_m - g_{pi}\,dh_{1i} - dh_{0i}
       = h_{1i}g_{pi} + h_{0i} - G_p + v_{pi},
       \qquad k_{pi} = h_{1i}\,\nabla g_{pi}\cdot\frac{\partial(c, r)_{pi}}{\partial Z}

    (gradients from central differences of the pyramid level, ∂(c, r)/∂Z by central differences
    of the collinearity, in the camera frame; a window of a larger frame is just a camera
    with its principal point far from the window centre). The radiometric datum is fixed on a
    reference image (:math:`h_0 = 0, h_1 = 1`); only samples seen by at least two images give
    equations.

Visibility and gross errors (seed §5.3 step 4, §7.3/7.12)
    A DSM to be refined has buildings and trees, and a DSM from matching has walls smeared
    over several cells. Once per level, on the level's start surface, every image drops the
    samples it cannot see (ray marching against the window's cells) or sees at a grazing
    angle (cos ∠(normal, ray) < :data:`.object_space_window.MIN_COS`: walls, steep back
    slopes), plus a margin of :data:`.object_space_window.VIS_MARGIN` samples around them
    (mixed pixels at occluding edges). After every Gauss–Newton step a sample whose images
    still disagree by more than :data:`.object_space_window.REJECT_K` robust σ is left out
    for the rest of the level (:func:`.object_space_window._screen`): a surface the 2.5D
    facets cannot represent or a single-image disturbance. Without both, such samples pull
    the heights of the open ground around them and the per-window radiometry (measured on the
    synthetic aerial block: refined RMS 0.30 → 0.63 m instead of → 0.18 m).

Regularisation (curvature minimisation, seed (7.2-5/6))
    For every interior geometry node, with node spacing normalised to 1 and heights in metres,
    pseudo-observations of weight λ:
    :math:`dZ_{i-1} - 2dZ_i + dZ_{i+1} = -(Z^\circ_{i-1} - 2Z^\circ_i + Z^\circ_{i+1})` along
    both axes. ``regularisation_mode="correction"`` (default) uses only :math:`\Delta Z`: it
    keeps the shape of the input DSM (buildings, embankments, ditches), which a refinement
    must not flatten; ``"curvature"`` uses the surface :math:`Z^\circ = Z^{in} + \Delta Z`
    (the thesis's curvature minimisation, λ = 1e4 for 8-bit grey values, for a start from a
    plane) and bends open ground next to every building and breakline.

Solution
    Normal equations :math:`N = A^TA + \lambda R^TR` (+ a ridge of
    :data:`.object_space_window.GREY_RIDGE` of the typical grey diagonal on the grey values:
    a grey node that only the corner of one sample's bilinear weights touches is not
    determinable), solved by conjugate gradients with the Jacobi (diagonal) preconditioner
    (seed Tab. 7-3: as fast as SSOR, no fill-in; :func:`..linalg.pcg`).
    Increments are clipped to 0.2 geometry spacings and 1 px of parallax. Stop when
    :math:`\max|dZ| < 0.01\,GSD_\ell H/B` over the nodes with image data or σ0 changes by
    less than 0.5 %, at most ``max_iter`` iterations per level (0: the input with its σ).
    Coarse → fine over ``levels`` image-pyramid levels (:func:`.pyramid.build_pyramid` of the
    image windows, their origins on the lattice of the top level), the correction of level
    ℓ+1 prolongated bilinearly as the start of level ℓ.

Precision (seed §2.13, 7.3-11)
    After the finest level the system is rebuilt **without** regularisation (radiometry kept),
    factorised once (sparse LU in symmetric mode, :func:`scipy.sparse.linalg.splu`);
    :math:`\sigma_0^2 =
    (l^Tl - l^TA\hat x)/(n - u)` in grey values and :math:`\sigma_{Z,m} = \sigma_0\sqrt{Q_{mm}}`.
    :math:`Q_{mm}` is estimated by **probing** (Tang & Saad 2012): the geometry nodes are split
    into :math:`d \times d` colour classes (nodes ``d`` apart, d = 5); one solve with the sum of
    the unit vectors of a class gives :math:`Q_{mm} + \sum_j Q_{mj}` over the other class
    members, which are ≥ 5 nodes away, where the correlations have decayed (seed: 0.2–0.35 for
    direct neighbours). So 25 solves instead of one per node; the bias is a small
    overestimate. Output cells get σ interpolated bilinearly from the nodes (the thesis's
    pragmatic, slightly pessimistic choice).

Windows
    The output grid is processed in tiles of ``tile`` cells plus ``overlap`` cells on every side
    (only the tile's core is written). Each window reads only the image windows it needs
    (:func:`..raster.io.open_image` windows) and uses the images whose footprint covers at least
    ``min_cover`` of it. Exclusion areas and cells outside the boundaries of ``edits.gpkg`` are
    NaN. A window whose adjustment diverges is written as NaN and counted as a failure; the run
    goes on.

Walls (issue 19)
    Discontinuities come from the input DSM. Curvature rows whose input second difference
    exceeds :data:`.object_space_window.BREAK_M` (1 m: a wall, not a slope) are left out and
    their centre nodes held at the input height (``2·ΔZ = 0``, weight λ) instead; samples,
    the prolongation between levels and the output cells take their correction only from
    nodes on the same side (:func:`.object_space_window.same_side_weights`: a node more than
    1 m + 0.5 × distance off in input height is across a wall). A cell without a node on its
    side (the wall itself), or whose observed nodes are all across a wall, keeps its input
    height without σ. So a roof's correction does not leak onto the ground beside it, and the
    walls stay where the input has them (measured in ``docs/decisions.md``).

Not modelled: robust reweighting (off in the thesis as well; the screening above only removes
gross errors), moving walls (the 2.5D limit: their samples are dropped, the input's wall
position is kept).

The adjustment of one window is in :mod:`.object_space_window`; the conjugate gradients are
:func:`..linalg.pcg`.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
from numpy.typing import NDArray
from rasterio.enums import ColorInterp
from rasterio.windows import Window

from ..crs_check import check_surface_crs
from ..errors import GeometryError, InputError
from ..feedback import Feedback, ensure_feedback
from ..geometry.projection import world_to_pixel
from ..project.edits import read_constraints
from ..project.model import Project
from ..raster.io import gtiff_profile, open_image, staged_folder
from ..raster.sample import bilinear_grid, world_to_grid
from ..surface.gridding import Grid, polygon_mask
from .object_space_window import (
    MODES,
    PROBE_DISTANCE,
    ImageWindow,
    WindowResult,
    _bilinear_weights,
    _fill_nearest,
    adjust_window,
    noblas,
    same_side_weights,
)
from .pyramid import build_pyramid

PathLike = Union[str, Path]
Array = NDArray[np.float64]


# -- image windows -----------------------------------------------------------------------------
def _read_grey(path: Path, col0: int, row0: int, width: int, height: int) -> NDArray:
    """Grey (mean of the colour bands) of an image window, float32."""
    with open_image(path) as src:
        bands = [i + 1 for i, c in enumerate(src.colorinterp) if c != ColorInterp.alpha]
        bands = (bands or [1])[:3]
        data = src.read(bands, window=Window(col0, row0, width, height)).astype(np.float32)
    return data.mean(axis=0)


def _stack(level_image: NDArray) -> NDArray:
    img = np.asarray(level_image, dtype=np.float32)
    gr, gc = np.gradient(img)
    return np.stack([img, gc, gr]).astype(np.float32)


# -- the driver ------------------------------------------------------------------------------
def _footprint_cover(cam: Any, eo: Any, X: Array, Y: Array, Z: Array) -> float:
    """Share of the points (X, Y, Z) that project inside the image."""
    c, r = world_to_pixel(np.stack([X, Y, Z], axis=-1), cam, eo)
    ok = (c >= 0) & (c <= cam.width - 1) & (r >= 0) & (r <= cam.height - 1)
    return float(np.mean(ok)) if ok.size else 0.0


def _image_window(cam: Any, eo: Any, X: Array, Y: Array, zlo: float, zhi: float, pad: int,
                  align: int = 1) -> Optional[Tuple[int, int, int, int]]:
    """Level-0 pixel window (col0, row0, width, height) that holds the points, clipped.

    The origin is a multiple of ``align`` (2^(levels−1)), so every pyramid level samples the
    image on the same lattice whichever window a tile reads: neighbouring tiles and windows
    cut from a larger frame at even offsets see identical pyramid pixels.
    """
    cs, rs = [], []
    for z in (zlo, zhi):
        c, r = world_to_pixel(np.stack([X, Y, np.full_like(X, z)], axis=-1), cam, eo)
        cs.append(c)
        rs.append(r)
    c = np.concatenate(cs)
    r = np.concatenate(rs)
    if not (np.isfinite(c).any() and np.isfinite(r).any()):
        return None
    c0 = max((math.floor(np.nanmin(c)) - pad) // align * align, 0)
    c1 = min(math.ceil(np.nanmax(c)) + pad + 1, cam.width)
    r0 = max((math.floor(np.nanmin(r)) - pad) // align * align, 0)
    r1 = min(math.ceil(np.nanmax(r)) + pad + 1, cam.height)
    if c1 - c0 < 8 or r1 - r0 < 8:
        return None
    return c0, r0, c1 - c0, r1 - r0


def refine_object_space(project: Any, dsm: PathLike, output_dir: PathLike, *,
                        spacing: Optional[float] = None, levels: Optional[int] = None,
                        max_iter: int = 8, regularisation: float = 1.0,
                        regularisation_weight: Optional[float] = None,
                        regularisation_mode: str = "correction",
                        images: Optional[Sequence[str]] = None, tile: int = 192,
                        overlap: Optional[int] = None, facet_px: float = 8.0,
                        grey_px: float = 2.0, min_cover: float = 0.1,
                        feedback: Optional[Feedback] = None) -> Dict[str, Any]:
    r"""Refine a DSM by object-space multi-image least-squares matching (module notes).

    Parameters
    ----------
    project : Project or path
        The project (cameras, oriented images, edits.gpkg).
    dsm : path
        The DSM to refine (float, NaN/nodata = no height), in the project CRS.
    output_dir : path
        Output folder (created, or replaced if PhotoDEM wrote it); nothing is left on error.
    spacing : float, optional
        Cell size of the refined DSM (m); default the DSM's. Geometry nodes lie on every
        ``stride``-th cell, ``stride = max(1, round(facet_px·GSD / spacing))``.
    levels : int, optional
        Image-pyramid levels (coarse → fine); default 2 (the input DSM must be within
        ≈ 2 px of parallax on the top level, i.e. ≈ 4 px on level 0). More levels only help
        where the texture survives the reduction.
    max_iter : int
        Gauss–Newton iterations per level at most; 0 returns the input heights (with σ) on
        the refinable cells.
    regularisation : float
        Share of the curvature regularisation on the height diagonal of the normal equations,
        mean diag(λRᵀR) / mean diag(AᵀA) (seed-004 §5.5): λ is set from it on the first
        iteration of every level and window, so it does not depend on the grey-value range,
        texture or image count. 0 = no regularisation.
    regularisation_weight : float, optional
        A fixed λ instead (grey values² per m², node spacing normalised to 1; the thesis used
        1e4 with 8-bit images).
    regularisation_mode : {"correction", "curvature"}
        Penalise only the curvature of the correction to the DSM (default; keeps buildings and
        breaklines of the input) or of the surface itself (thesis, start from a plane).
    images : sequence of str, optional
        Image names to use; default every image whose footprint covers ≥ ``min_cover`` of a
        tile.
    tile : int
        Tile side in output cells (plus ``overlap`` on every side).
    overlap : int, optional
        Overlap in cells on every side; default 3 geometry facets.
    facet_px, grey_px : float
        Geometry and grey facet sizes in image pixels (thesis: 8 and 2).
    min_cover : float
        Share of a tile an image must see to be used there.
    feedback : Feedback, optional
        Progress and cancellation.

    Returns
    -------
    dict
        ``{"dsm", "sigma", "report", "metrics"}``.
    """
    feedback = ensure_feedback(feedback)
    t_start = time.perf_counter()
    _check_options(regularisation_mode, regularisation, regularisation_weight, max_iter)
    if not isinstance(project, Project):
        project = Project.load(project)
    plan = _plan(project, Path(dsm), images, spacing, levels, tile, overlap, facet_px)
    settings = _TileSettings(min_cover, max_iter, regularisation, regularisation_weight,
                             regularisation_mode, grey_px)
    W, H = plan.out_grid.width, plan.out_grid.height
    feedback.info(f"Object-space matching: {len(plan.recs)} images, GSD {plan.gsd:.3f} m, DSM "
                  f"{W}×{H} cells at {plan.spacing:.3f} m, geometry nodes every {plan.stride} "
                  f"cells, {plan.levels} levels, {len(plan.tiles)} tiles.")
    out = Path(output_dir)
    totals = _Totals()
    with staged_folder(out, replace=True, product="refine_object_space") as tmp:
        _write_tiles(plan, settings, tmp, totals, feedback)
        feedback.check()
        seconds = time.perf_counter() - t_start
        metrics = _metrics(plan, totals)
        report = {"dsm": str(plan.dsm), "crs": project.crs, "metrics": metrics,
                  "options": {"max_iter": int(max_iter), "regularisation": regularisation,
                              "regularisation_weight": regularisation_weight,
                              "regularisation_mode": regularisation_mode,
                              "facet_px": facet_px, "grey_px": grey_px, "tile": plan.tile,
                              "overlap": plan.overlap, "min_cover": min_cover,
                              "sigma": "probing of diag(N⁻¹), colour distance "
                                       f"{PROBE_DISTANCE} nodes, without regularisation"},
                  "tiles": totals.tile_reports, "seconds": {"total": seconds}}
        (tmp / "report.json").write_text(json.dumps(report, indent=1), encoding="utf-8")
        feedback.progress(100.0)
    feedback.info(f"Refined {totals.n_refined} cells ({totals.n_nodes} geometry nodes), median "
                  f"σ_Z {metrics['sigma_z_median_m'] or float('nan'):.3f} m, "
                  f"{totals.failures} failed tiles.")
    return {"dsm": str(out / "dsm.tif"), "sigma": str(out / "sigma.tif"),
            "report": str(out / "report.json"), "metrics": metrics}


def _check_options(mode: str, regularisation: float, weight: Optional[float],
                   max_iter: int) -> None:
    """Reject a mode, regularisation or iteration count that cannot be used."""
    if mode not in MODES:
        raise InputError(f"Unknown regularisation mode '{mode}'; use one of "
                         f"{', '.join(MODES)}.")
    if not regularisation >= 0 or (weight is not None and not weight >= 0):
        raise InputError("The regularisation must not be negative.")
    if int(max_iter) < 0:
        raise InputError("max_iter must not be negative (0 = no adjustment, only σ).")


@dataclass(frozen=True)
class _TileSettings:
    """Options of the adjustment of every tile (see :func:`refine_object_space`)."""

    min_cover: float
    max_iter: int
    regularisation: float
    weight: Optional[float]
    mode: str
    grey_px: float


@dataclass
class _Plan:
    """The frame of a refinement: images, grids, lattice and tiles."""

    project: Any
    dsm: Path
    recs: Sequence[Any]
    cams: Dict[str, Any]
    in_grid: Grid
    out_grid: Grid
    nodata: Optional[float]
    spacing: float
    gsd: float
    levels: int
    stride: int  # output cells per geometry node on level 0
    unit: int  # node lattice of the top level, in cells
    tile: int
    overlap: int
    excl: List[Any]
    bounds: List[Any]
    tiles: List[Tuple[int, int]]


@dataclass
class _Totals:
    """What the tiles add up to: their reports, σ of the refined cells, counts."""

    tile_reports: List[Dict[str, Any]] = field(default_factory=list)
    sig_all: List[Array] = field(default_factory=list)
    n_refined: int = 0
    n_nodes: int = 0
    failures: int = 0


def _records(project: Any, dsm: Path, images: Optional[Sequence[str]]) -> List[Any]:
    """The image records to use, after checking that the DSM and the image files exist."""
    if not dsm.is_file():
        raise InputError(f"The DSM '{dsm}' does not exist.")
    recs = project.images if images is None else [project.image(n) for n in images]
    if len(recs) < 2:
        raise InputError("Object-space matching needs at least two images; the project or "
                         "the 'images' list has fewer.")
    for rec in recs:
        p = project.image_path(rec)
        if not p.is_file():
            raise InputError(f"Image file '{p}' of image '{rec.name}' does not exist; fix its "
                             "path in project.toml.")
    return recs


def _dsm_frame(dsm: Path, project: Any) -> Tuple[Grid, Optional[float], Any, Array]:
    """Grid, nodata, bounds and a coarse overview of the heights (≤ 256 cells a side)."""
    with open_image(dsm) as src:
        check_surface_crs(dsm, src.crs, project.crs, "DSM")
        t = src.transform
        if t.b != 0 or t.d != 0 or abs(abs(t.a) - abs(t.e)) > 1e-9 * abs(t.a):
            raise InputError(f"The DSM '{dsm.name}' must be north-up with square cells.")
        in_grid = Grid(t, src.width, src.height, float(abs(t.a)))
        step = max(1, max(src.width, src.height) // 256)
        ov = src.read(1, out_shape=(max(1, src.height // step), max(1, src.width // step)),
                      masked=True).astype(float).filled(np.nan)
        frame = (in_grid, src.nodata, src.bounds, ov)
    if not np.isfinite(ov).any():
        raise InputError(f"The DSM '{dsm.name}' has no heights.")
    return frame


def _plan(project: Any, dsm: Path, images: Optional[Sequence[str]], spacing: Optional[float],
          levels: Optional[int], tile: int, overlap: Optional[int], facet_px: float) -> _Plan:
    """Check the inputs and fix grids, GSD, geometry stride, overlap and tiles."""
    recs = _records(project, dsm, images)
    in_grid, nodata, b, ov = _dsm_frame(dsm, project)
    dsm_spacing = in_grid.spacing
    spacing = dsm_spacing if not spacing else float(spacing)
    if not spacing > 0:
        raise InputError(f"The spacing must be positive, got {spacing}.")
    out_grid = in_grid if spacing == dsm_spacing else Grid.from_bounds(
        b.left, b.bottom, b.right, b.top, spacing)
    z_mean = float(np.nanmean(ov))
    cams = {rec.name: project.camera_of(rec) for rec in recs}
    heights = np.array([rec.eo.position[2] - z_mean for rec in recs])
    if not (heights > 0).all():
        raise GeometryError("Some images are not above the DSM; check the DSM heights and the "
                            "orientations.")
    gsd = float(np.median([cams[r.name].gsd(h) for r, h in zip(recs, heights)]))
    levels = 2 if levels is None else int(levels)
    if levels < 1:
        raise InputError("levels must be at least 1.")
    stride = max(1, round(facet_px * gsd / spacing))
    unit = stride * 2 ** (levels - 1)
    overlap = int(overlap) if overlap is not None else 3 * stride
    tile = max(int(tile), unit)
    excl, bounds = [], []
    if Path(project.edits_path).is_file():
        excl, bounds, _lines = read_constraints(project.edits_path, project.crs or None)
    W, H = out_grid.width, out_grid.height
    tiles = [(r0, c0) for r0 in range(0, H, tile) for c0 in range(0, W, tile)]
    return _Plan(project, dsm, recs, cams, in_grid, out_grid, nodata, spacing, gsd, levels,
                 stride, unit, tile, overlap, excl, bounds, tiles)


def _write_tiles(plan: _Plan, settings: _TileSettings, tmp: Path, totals: _Totals,
                 feedback: Feedback) -> None:
    """Refine tile by tile and write the cores into dsm.tif and sigma.tif of ``tmp``."""
    W, H = plan.out_grid.width, plan.out_grid.height
    profile = gtiff_profile(W, H, 1, "float32", plan.project.crs, nodata=float("nan"),
                            predictor=3, transform=plan.out_grid.transform)
    with open_image(tmp / "dsm.tif", "w", **profile) as dst_z, \
            open_image(tmp / "sigma.tif", "w", **profile) as dst_s, \
            open_image(plan.dsm) as src:
        for t_i, (r0, c0) in enumerate(plan.tiles):
            feedback.progress(100.0 * t_i / len(plan.tiles))
            z_out, s_out, rep = _refine_tile(plan, settings, src, r0, c0, totals, feedback)
            totals.tile_reports.append(rep)
            th, tw = z_out.shape
            dst_z.write(z_out[None], window=Window(c0, r0, tw, th))
            dst_s.write(s_out[None], window=Window(c0, r0, tw, th))


def _window_heights(plan: _Plan, src: Any, wr0: int, wc0: int, nr: int, nc: int,
                    x_first: float, y_first: float) -> Array:
    """Input heights (NaN = none) at the cell centres of a window of the output grid."""
    spacing = plan.spacing
    if plan.out_grid is plan.in_grid:
        z_in = src.read(1, window=Window(wc0, wr0, nc, nr), boundless=True,
                        fill_value=np.nan, masked=True)
        z_in = z_in.astype(float).filled(np.nan)
    else:
        xs = x_first + spacing * np.arange(nc)
        ys = y_first - spacing * np.arange(nr)
        XX, YY = np.meshgrid(xs, ys)
        cc, rr = world_to_grid(src.transform, XX, YY)
        ic0 = max(int(np.floor(cc.min())) - 1, 0)
        ir0 = max(int(np.floor(rr.min())) - 1, 0)
        ic1 = min(int(np.ceil(cc.max())) + 2, src.width)
        ir1 = min(int(np.ceil(rr.max())) + 2, src.height)
        if ic1 > ic0 and ir1 > ir0:
            a = src.read(1, window=Window(ic0, ir0, ic1 - ic0, ir1 - ir0),
                         masked=True).astype(float).filled(np.nan)
            z_in = bilinear_grid(a, cc - ic0, rr - ir0)
        else:
            z_in = np.full((nr, nc), np.nan)
    if plan.nodata is not None and np.isfinite(plan.nodata):
        z_in[z_in == plan.nodata] = np.nan
    return z_in


def _refine_tile(plan: _Plan, settings: _TileSettings, src: Any, r0: int, c0: int,
                 totals: _Totals, feedback: Feedback) -> Tuple[Array, Array, Dict[str, Any]]:
    """Heights and σ of the core of the tile at (r0, c0) (NaN where not refined), and its
    report; adds to ``totals``."""
    W, H = plan.out_grid.width, plan.out_grid.height
    overlap, unit, spacing = plan.overlap, plan.unit, plan.spacing
    th, tw = min(plan.tile, H - r0), min(plan.tile, W - c0)
    # window: core ± overlap, extended so that nodes of every level fit exactly
    wr0, wc0 = r0 - overlap, c0 - overlap
    nr = ((th + 2 * overlap - 1 + unit - 1) // unit) * unit + 1
    nc = ((tw + 2 * overlap - 1 + unit - 1) // unit) * unit + 1
    wgrid = Grid(plan.out_grid.transform * plan.out_grid.transform.translation(wc0, wr0),
                 nc, nr, spacing)
    x_first, y_first = wgrid.transform * (0.5, 0.5)
    z_in = _window_heights(plan, src, wr0, wc0, nr, nc, x_first, y_first)
    valid = np.isfinite(z_in)
    if plan.excl:
        valid &= ~polygon_mask(plan.excl, wgrid)
    if plan.bounds:
        valid &= polygon_mask(plan.bounds, wgrid)
    core = (slice(overlap, overlap + th), slice(overlap, overlap + tw))
    z_out = np.full((th, tw), np.nan, np.float32)
    s_out = np.full((th, tw), np.nan, np.float32)
    rep: Dict[str, Any] = {"tile": [int(r0), int(c0)], "images": [], "iterations": [],
                           "sigma0": None, "failed": False}
    if not valid[core].any():
        return z_out, s_out, rep
    res = _run_tile(plan, z_in, valid, x_first, y_first, settings, feedback)
    rep["images"] = res.images
    rep["iterations"] = res.iterations
    rep["cg_iterations"] = res.cg_iterations
    rep["regularisation_share"] = (round(res.reg_share, 4)
                                   if np.isfinite(res.reg_share) else None)
    rep["rejected_share"] = (round(res.rejected_share, 4)
                             if np.isfinite(res.rejected_share) else None)
    if not res.ok:
        totals.failures += 1
        rep["failed"] = True
        rep["message"] = res.message
        feedback.warning(f"Tile at row {r0}, col {c0}: {res.message}; left empty (NaN).")
        return z_out, s_out, rep
    z_out, s_out = _tile_products(res, z_in, valid, core, plan.stride, plan.spacing)
    rep["sigma0"] = round(res.sigma0, 4) if np.isfinite(res.sigma0) else None
    k = np.isfinite(s_out)
    totals.n_refined += int(k.sum())
    totals.sig_all.append(s_out[k].astype(float))
    st = plan.stride
    nodes_core = res.observed[overlap // st:(overlap + th) // st,
                              overlap // st:(overlap + tw) // st]
    totals.n_nodes += int(nodes_core.sum())
    return z_out, s_out, rep


def _tile_products(res: WindowResult, z_in: Array, valid: NDArray[np.bool_],
                   core: Tuple[slice, slice], stride: int, spacing: float
                   ) -> Tuple[Array, Array]:
    """Refined heights and σ (float32) of a tile's core from the node results.

    Bilinear from the nodes on the same side of a wall as the cell
    (:func:`.object_space_window.same_side_weights`): a roof's correction does not leak to
    the ground beside it. A cell with no node on its side (on the wall itself) keeps its
    input height, without σ, and so does a cell whose observed nodes are all across a wall.
    Cells without observed nodes around them are NaN (as without the walls rule).
    """
    nr, nc = z_in.shape
    rr_, cc_ = np.mgrid[0:nr, 0:nc]
    ny, nx = res.dz.shape
    idx, w_all = _bilinear_weights(cc_.ravel() / stride, rr_.ravel() / stride, nx, ny)
    zf = _fill_nearest(np.asarray(z_in, dtype=float))
    w = same_side_weights(idx, w_all, zf[::stride, ::stride][:ny, :nx].ravel(), zf.ravel(),
                          stride * spacing)
    wall = (w.sum(axis=1) == 0).reshape(nr, nc)

    def interp(nodes: Array, weights: Array = w) -> Array:
        return (nodes.ravel()[idx] * weights).sum(axis=1).reshape(nr, nc)

    dz = interp(res.dz)
    sg = interp(np.nan_to_num(res.sigma, nan=1e9))
    # refined where the nodes around the cell are observed, on its side and in all; where
    # only those across a wall are, or on the wall itself, the input height is kept (the
    # cells the refinement leaves empty stay what they were without the walls rule)
    obs_all = interp(res.observed.astype(float), w_all)
    good = valid & (obs_all > 0.5) & (interp(res.observed.astype(float)) > 0.5) & (sg < 1e8)
    keep = valid & ~good & (wall | (obs_all > 0.5))
    zr = np.where(good, z_in + dz, np.where(keep, z_in, np.nan))
    sr = np.where(good, sg, np.nan)
    # σ to 0.1 mm: the sparse LU may differ in the last bits between processes (BLAS
    # builds), which must not show in the product
    return zr[core].astype(np.float32), np.round(sr[core], 4).astype(np.float32)


def _metrics(plan: _Plan, totals: _Totals) -> Dict[str, Any]:
    """The figures of the report (σ0 per tile, σ_Z of the refined cells, counts)."""
    sig = np.concatenate(totals.sig_all) if totals.sig_all else np.zeros(0)
    s0s = [r["sigma0"] for r in totals.tile_reports if r.get("sigma0") is not None]
    return {
        "cells": [plan.out_grid.width, plan.out_grid.height],
        "spacing_m": plan.spacing,
        "gsd_m": plan.gsd,
        "geometry_stride_cells": plan.stride,
        "levels": plan.levels,
        "tiles": len(plan.tiles),
        "refined_cells": totals.n_refined,
        "geometry_nodes": totals.n_nodes,
        "failures": totals.failures,
        "sigma0_grey_mean": float(np.mean(s0s)) if s0s else None,
        "sigma0_grey_median": float(np.median(s0s)) if s0s else None,
        # no mean: nodes on texture-free ground have σ of kilometres (no regularisation
        # in the σ), which would swamp it; the share of such nodes is reported instead
        "sigma_z_median_m": float(np.median(sig)) if sig.size else None,
        "sigma_z_p95_m": float(np.percentile(sig, 95)) if sig.size else None,
        "nodes_sigma_over_1m_pct": (round(100.0 * float(np.mean(sig > 1.0)), 3)
                                    if sig.size else None),
    }


def _run_tile(plan: _Plan, z_in: Array, valid: NDArray[np.bool_], x_first: float,
              y_first: float, settings: _TileSettings, feedback: Feedback) -> WindowResult:
    """Choose the images of a window, read their windows and pyramids, adjust."""
    spacing, gsd, levels = plan.spacing, plan.gsd, plan.levels
    nr, nc = z_in.shape
    zf = z_in[valid]
    zlo, zhi = float(zf.min()), float(zf.max())
    zm = float(np.median(zf))
    # footprint test on a coarse lattice of the window's valid cells
    rr, cc = np.nonzero(valid)
    sel = np.linspace(0, rr.size - 1, min(rr.size, 400)).astype(int)
    X = x_first + cc[sel] * spacing
    Y = y_first - rr[sel] * spacing
    Z = z_in[rr[sel], cc[sel]]
    border = np.array([[0, 0], [0, nc - 1], [nr - 1, 0], [nr - 1, nc - 1]], float)
    BX = x_first + border[:, 1] * spacing
    BY = y_first - border[:, 0] * spacing
    lim = 2.0 ** levels * 8.0
    wins: List[ImageWindow] = []
    for rec in plan.recs:
        cam = plan.cams[rec.name]
        if _footprint_cover(cam, rec.eo, X, Y, Z) < settings.min_cover:
            continue
        box = _image_window(cam, rec.eo, np.concatenate([BX, X]), np.concatenate([BY, Y]),
                            zlo - 1.0, zhi + 1.0, int(lim), 2 ** (levels - 1))
        if box is None:
            continue
        grey = _read_grey(plan.project.image_path(rec), *box)
        pyr = build_pyramid(grey, levels)
        if len(pyr) < levels:
            continue
        wins.append(ImageWindow(rec.name, cam, noblas(rec.eo), box[0], box[1],
                                 [_stack(p) for p in pyr]))
    if len(wins) < 2:
        return WindowResult(np.zeros((1, 1)), np.full((1, 1), np.nan), np.zeros((1, 1), bool),
                            float("nan"), [], [], [w.name for w in wins], False,
                            "fewer than two images see it")
    # widest base over the used images → parallax per metre of height
    P = np.array([w.eo.position for w in wins])
    base = max(float(np.linalg.norm(P[i, :2] - P[j, :2]))
               for i in range(len(wins)) for j in range(i + 1, len(wins)))
    h = float(np.mean(P[:, 2]) - zm)
    parallax_per_m = max(base / h / gsd, 1e-6)
    return adjust_window(z_in, valid, x_first, y_first, spacing, plan.stride, wins, gsd,
                         parallax_per_m, levels, max_iter=settings.max_iter,
                         regularisation=settings.regularisation, weight=settings.weight,
                         mode=settings.mode, grey_px=settings.grey_px, feedback=feedback)


__all__ = ["MODES", "WindowResult", "adjust_window", "refine_object_space"]
