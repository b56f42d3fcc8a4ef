r"""Dense DSM of one stereo model: epipolar resampling → SGM → triangulation → gridding.

1. The model's images are normalised (:class:`~..geometry.epipolar.EpipolarPair`, scale 1) and
   resampled to grey epipolar images block by block into scratch GeoTIFFs (bounded memory).
2. The disparity search range follows from the height range ``[z_min, z_max]``
   (:meth:`EpipolarPair.disparity_range`), widened by ``disparity_margin`` px and by 10 % for
   the variation of depth across the image. Default heights: the project's terrain height
   ``Z_t`` and the flying height above ground ``H`` as ``Z_t − 0.3·H … Z_t + 0.3·H``.
3. Tiled semi-global matching (:func:`.dense.iter_disparity_tiles`, with one
   :class:`~.dense.DenseOptions` built per model by :func:`dsm_dense_options`); every valid
   disparity of a tile is triangulated at once (:meth:`EpipolarPair.disparity_to_world`) and
   streamed into a :class:`~..surface.gridding.GridAccumulator` (median per cell).
   Disparities within 2 px of a mask or the image border (half windows), and within 2 px of a
   hole unless on the *upper* side of a height step of 1.5 m (``edge_jump`` in px of this
   model's parallax; a lower disparity within ``edge_reach`` px) in a segment of
   ≥ ``segment_px`` px, are dropped first (``edge_erosion``: foreground fattening at
   occlusions and depth steps); roof edges stay, hole borders on open terrain and blunder
   patches go.
   Holes with a step on their border get their upper (object) border's heights, by inverse
   distance, where that is nearer and alike in tone (``plane_fill``, :mod:`.dense_fill`); the
   ground part of holes is left to the gap interpolation (issue 19).
   Convergent models also give the cells that no pixel's point reached the points of the
   centres of 2 × 2 pixel quads on one surface (:func:`footprint_points`; a tilted frame's far
   side has fewer pixels than cells). Convergent and wide-base models (B/H ≥
   :data:`WIDE_BASE`: roof faces seen at clearly different scales) then give those cells the
   points of two *slant passes*: SGM against
   the right image stretched along its rows by :data:`SLANT_SCALES` (slopes that one camera
   sees foreshortened), in the ranges of the plain pass's disparities (:class:`_Guide`), each
   disparity refined by least-squares matching between the original images, whose affine
   x-scale fits the slope (:mod:`.slant_lsm`), and kept where they agree with the plain pass's
   heights around them (:data:`SLANT_GAP_CELLS`), the kept ones joining that reference for
   the next of up to :data:`SLANT_GROW_ROUNDS` rounds (:func:`slant_cells`) — ``slant_passes``,
   on by default (issue 22, parts N and X, issue 19, part Z in docs/decisions.md).
   Wide-base nadir models finally match the plain pass once more with a *refinement pass*
   (:data:`_REFINE_OPTIONS`): SGM ± 8 px around the first pass's smoothed disparities, the
   slant passes' disparities filling its holes, against the right image interpolated at them;
   every pixel the right image confirms takes the refined disparity, a hole only on an
   object (issue 19, part AA).
4. With about one point per cell the median cannot remove blunders: measured cells that deviate
   from their neighbourhood median by more than ``max(t, 3·1.4826·MAD)`` are emptied
   (:func:`~..surface.gridding.reject_outliers`; window ±``outlier_radius`` m, default 5
   cells; ``t = outlier_threshold``, default the height of 1 px of parallax ``GSD·H/B``,
   :attr:`~.model_setup.ModelSetup.parallax_per_metre`).
5. Exclusion areas (NaN) and boundaries (NaN outside) from ``edits.gpkg``; breaklines are
   barriers of the gap interpolation (gaps up to ``max_gap`` m), which also re-fills the
   rejected cells.
6. Convergent models are then matched once more along this first DSM (``guided``,
   :mod:`.dense_guided`): SGM ± 8 px around its disparities against the right image warped
   by them; a hole takes the new disparity where least-squares matching and a uniqueness
   test along the row confirm it, and only in the DSM's holes bordered by one surface
   (slopes across the base, issue 22, part AD). Steps 4 and 5 run again.

Outputs in a staged folder (nothing is left behind on error or cancel): ``dsm.tif`` (float32,
NaN, project CRS, overviews), ``count.tif`` (points per cell, uint16), ``report.json`` and
``report.html`` (:func:`.model_report.write_model_report`).
Coverage is the share of the cells of the stereo overlap (at the terrain height, inside the
boundary, outside exclusions) that hold a height.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any, Dict, Optional, Tuple, Union

import numpy as np
from rasterio.windows import Window
from scipy import ndimage

from ..feedback import Feedback, ensure_feedback
from ..geometry.epipolar import RESAMPLE_BLOCK_PIXELS, SIDES, EpipolarPair
from ..raster.io import gtiff_profile, open_image, scratch_folder, staged_folder
from ..surface.gridding import (
    Grid,
    GridAccumulator,
    deviates_from,
    fill_gaps,
    finish_grid,
    nearest_filled,
    polygon_mask,
    window_half,
    write_grid,
)
from .dense import DenseOptions, GreySource, array_source, iter_disparity_tiles
from .dense_guided import dsm_guide, terrain_holes
from .model_report import coverage_sentence, write_model_report
from .model_setup import ModelSetup, prepare_model
from .slant_lsm import SLANT_LSM_SHIFT, refine_slant

PathLike = Union[str, Path]

#: Matching options of the DSM path that differ from :func:`.dense.iter_disparity_tiles`:
#: disparities within 2 px of a hole, of a mask or of the image border are dropped (foreground
#: fattening at occlusions and depth steps) except on the upper side of a height step (a lower
#: disparity within 15 px) in a disparity segment of ≥ 300 px, so roof edges stay but hole
#: borders on open terrain and blunder patches go; the gridding fills the small gaps again.
#: A reach of 15 px keeps the ``aerial`` terrain RMS at its value without the exception
#: (20 px: +0.1 %; 10 px and less kept a blunder patch's raised edge on the first scenes:
#: 0.078 m against 0.046 m, issue 19). Where the left camera sees a wall wider than
#: ``wall_px`` = 20 px in an occlusion (``wall_view``, set per model by
#: :func:`dsm_dense_options`), roof edges near holes are eroded over a third of that width and
#: such holes get no roof fill: SGM spreads roofs over those walls (synthetic ``aerial`` block,
#: wide angle, base 4 px per metre of height: open cells within 0.5 m of an object > 1 m off
#: 42 % → 8 %; the ``small`` block's walls stay narrower and keep the rules above).
_DENSE_DEFAULTS: Dict[str, Any] = {"edge_erosion": 2, "plane_fill": 100.0, "segment_px": 300,
                                   "edge_reach": 15, "wall_px": 20.0}
#: The rule against roofs spilling over walls one camera sees (``wall_view``, part D4 in
#: docs/decisions.md) is off: on the aerial block it removes the spill (open cells with no
#: margin: RMS 0.54 → 0.12 m) but also half of the roofs (object interior 44 → 27 % on seed 1,
#: 44 → 16 % on held-out seed 11; walls 4.3 → 10.9 GSD), so by the issue's own measures it
#: does more harm than good. It stays an option (``wall_view`` of :class:`.dense.DenseOptions`).
_WALL_RULE = False
#: Height step (m) that separates an object from its ground for the one-sided erosion and the
#: plane fill (objects count from 2.5 m; ground slopes within a hole stay below it).
_JUMP_M = 1.5
#: Convergent models (axes more than :data:`~..geometry.epipolar.CONVERGENT_DEG` apart, drone
#: and oblique pairs) see the ground at different scales and slants, so the 9 px radiometric
#: normalisation and 5 px windows of the nadir defaults compare unlike patches: a 21 px
#: normalisation and 7 px windows (P1, P2 follow as 8·b², 32·b²) raise the valid disparities
#: of the synthetic drone pair 0101_0103 (47°, B/H 0.92) from 37.3 % to 48.7 % of the left
#: image and its measured share of the cells both cameras see from 60.0 % to 76.4 % (issue
#: 22; 9 → 15 px alone: 44.4 %, 31 px: 47.5 %; uniqueness 5, LR 2 px, other P1/P2: ±2 %).
#: Nadir models keep the defaults.
_CONVERGENT_OPTIONS: Dict[str, Any] = {"normalise_window": 21, "block_size": 7}
#: Wide-base models (B/H ≥ :data:`WIDE_BASE`, e.g. the synthetic ``aerial`` block's wide-angle
#: model, B/H 0.61) see slanted roofs at clearly different scales in the two images: the 9 px
#: normalisation then compares striped roof textures at different phases and SGM loses the
#: gabled roofs (aerial seed 1: 6–10 % of two gabled roofs right). A 21 px normalisation keeps
#: them (object interior 43.9 → 52.3 % on seed 1, 34.9 → 39.3 % on seed 2, held-out seed 11
#: 44.2 → 50.0 %); the left camera sees the walls there, so the plane fill takes the wall rule
#: (no roof in occlusions) but the erosion does not (with it the roofs go, part D4): without
#: the rule roofs filled over such walls put 11 m onto the terrain of seed 1 (0.076 ‰ H).
#: Issue 19, part A in docs/decisions.md.
#: Narrow-base models (the ``small`` block, B/H 0.36) keep the defaults: there the 21 px
#: window cost 3.6 points of interior on held-out seed 11.
WIDE_BASE = 0.5
_WIDE_BASE_OPTIONS: Dict[str, Any] = {"normalise_window": 21, "wall_erosion": False}
#: Wide-base *nadir* models also re-match every pixel in a refinement pass (``refine`` of
#: :class:`.dense.DenseOptions`, after the slant passes, whose disparities fill the guide's
#: holes): SGM ± 8 px around the smoothed first-pass disparities against the right image
#: interpolated (cubic) at them; a pixel takes the refined value where the right image's own
#: first pass confirms it, a hole only on an object. Aerial seeds 1 / 2 / 11: object interior
#: +3.0 / +2.2 / +2.5 points, terrain RMS −9 / −9 / −12 %, open cells within ±0.01 points, IoU
#: up, about 1.2 × the time. With the integer warp of part V only holes could take it (every
#: pixel: terrain NMAD 0.039 → 0.063 m). Narrow-base models (the ``small`` block: open cells
#: −0.02 / −0.04 points on seeds 11 / 2, walls of seed 1 1.1 → 1.4 GSD, 1.5–2 × the time) and
#: convergent ones (not measured) keep the first pass. Issue 19, part AA in docs/decisions.md.
_REFINE_OPTIONS: Dict[str, Any] = {"refine": 8, "refine_all": True}


def wide_base(setup: ModelSetup) -> bool:
    """Whether the model's base-to-height ratio is at least :data:`WIDE_BASE`."""
    return setup.pair.base / setup.flying_height >= WIDE_BASE


def dsm_dense_options(setup: ModelSetup, **overrides: Any) -> DenseOptions:
    """The matching options of the DSM path for one model, built once.

    :data:`_DENSE_DEFAULTS` and the height step of 1.5 m in px of the model's parallax
    (:attr:`~.model_setup.ModelSetup.parallax_per_metre`) as ``edge_jump``; for wide-base
    models (B/H ≥ :data:`WIDE_BASE`) :data:`_WIDE_BASE_OPTIONS`, and if nadir also
    :data:`_REFINE_OPTIONS`; for convergent models :data:`_CONVERGENT_OPTIONS`; with
    :data:`_WALL_RULE` or a wide base also the epipolar principal points as ``wall_view``
    (where the left camera sees the walls of the objects in its occlusions). ``overrides``
    (fields of :class:`~.dense.DenseOptions`) win.

    Raises
    ------
    InputError
        For an override that is no dense matching option.
    """
    cx = setup.pair.cx
    wide = wide_base(setup)
    view = (float(cx[0]), float(cx[1])) if _WALL_RULE or wide else None
    values = dict(_DENSE_DEFAULTS, edge_jump=_JUMP_M * setup.parallax_per_metre, wall_view=view)
    if wide:
        values.update(_WIDE_BASE_OPTIONS)
        if not setup.convergent:
            values.update(_REFINE_OPTIONS)
    if setup.convergent:
        values.update(_CONVERGENT_OPTIONS)
    values.update(overrides)
    return DenseOptions.from_values(values)


#: Convergent models also triangulate sub-pixel points between adjacent valid disparities of
#: one surface (:func:`footprint_points`) and give them to the cells that no pixel's point
#: reached: the far side of a tilted frame has fewer left pixels than DSM cells (0.7 per cell
#: on the synthetic drone pair 0202_0203), so with one point per pixel a quarter to a half of
#: the cells there got no point although every pixel around them matched (issue 22, part F in
#: docs/decisions.md). Cells with a pixel's point keep its median; nadir models are unchanged.
#: A quad counts as one surface within ``FOOTPRINT_STEP`` px (1 px: +0.4–1.1 points more on
#: 0202_0203, but open RMSE up to +0.8 % on other models from a few more blunder cells).
FOOTPRINT_STEP = 0.5


def footprint_points(block: np.ndarray, max_step: float = FOOTPRINT_STEP
                     ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Disparities at the centres of the 2 × 2 pixel quads of one surface in a disparity block.

    A quad whose four disparities are valid and differ by at most ``max_step`` px (height
    steps at objects are not bridged) gives its mean disparity at its centre: a point inside
    the ground footprint of four matched pixels, for the cells where a pixel covers more than
    one DSM cell. (Midpoints of pixel pairs as well, without the quad's four-way agreement,
    added a few blunder cells beside objects: open RMSE up to +2 % on the drone models.)

    Parameters
    ----------
    block : ndarray
        Disparities (h, w), NaN invalid.
    max_step : float
        Largest disparity difference (px) within a quad.

    Returns
    -------
    d, col, row : ndarray
        Disparities and their (half-pixel) columns and rows in the block.
    """
    quad = np.stack([block[:-1, :-1], block[:-1, 1:], block[1:, :-1], block[1:, 1:]])
    with np.errstate(invalid="ignore"):
        ok = np.all(np.isfinite(quad), axis=0)
        ok &= (quad.max(axis=0) - quad.min(axis=0)) <= max_step
    rr, cc = np.nonzero(ok)
    return quad[:, rr, cc].mean(axis=0), cc + 0.5, rr + 0.5


#: Horizontal scales of the right epipolar image for the slant passes of convergent and
#: wide-base models (:func:`stretched_source`, :func:`slant_scales`): a slope seen at a
#: grazing angle by one camera and facing the other has ``∂x_r/∂x_l`` of 0.2–1.9 on the
#: synthetic drone pairs (issue 22, part N), so square windows compare unlike patches there;
#: a pass with the right image stretched by ``s`` matches slopes with ``∂x_r/∂x_l ≈ 1/s``.
#: The wide-base aerial model's roof faces (0.67 and 1.9, issue 19, part V) gain as much
#: from these scales as from 0.6 / 1.6 or 0.5 / 1.5 (object interior within 1 point, terrain
#: and open cells slightly better, 0.6 / 1.6 takes 1.35 × the time; issue 19, part Z).
SLANT_SCALES: Tuple[float, ...] = (0.7, 1.4)
#: Slant passes of convergent models that also shear the right image along its rows
#: (stretch, shear in px per row; :func:`slant_passes`): a slope across the epipolar lines
#: changes the disparity from row to row — 0.71 px per row on the embankment of the drone
#: pair 0202_0203, seed 1 — which neither a square window nor a stretch follows; there SGM put
#: 84 % of the pixels more than 1 px off even when searched within 8 px of the truth, and a
#: pass stretched and sheared like the slope matched 67 % right. The shears lean the way the
#: model's ground leans (the sign of the plain pass's disparity change per row). Measured on
#: the four drone models of seeds 1 and 2 (docs/decisions.md, 2026-11-28).
SLANT_SHEARS: Tuple[Tuple[float, float], ...] = ((0.7, 0.35), (0.7, 0.7), (1.0, 0.35))
#: Largest disparity step (px) within a 2 × 2 quad of the slant passes' disparities that gives
#: a footprint point (:func:`footprint_points`) on convergent models: a slope stretched 1.55 ×
#: changes the disparity by 0.55 px per column, so the plain pass's 0.5 px would split it.
SLANT_FOOTPRINT_STEP = 1.0
#: A cell that only a slant pass measured is kept where it passes the DSM outlier test
#: against the plain pass's heights around it (within 1 px of parallax of their median, or
#: 3 × their spread), interpolated over enclosed gaps up to ``SLANT_GAP_CELLS`` cells wide
#: (:func:`~..surface.gridding.fill_gaps`). Without the test (and with the object fill in
#: the slant passes) their blunders on periodic field textures raised the open RMSE by 20 %
#: (drone seed 1, 0201_0203: 0.69 → 0.85 m); 3 px instead of 1 px kept a few more cells and
#: more blunders (0202_0203: open RMSE 0.4765 against 0.4728 m).
SLANT_GAP_CELLS = 100
#: With the LSM refinement of the slant disparities (issue 22, part X) the test allows
#: ``SLANT_TOLERANCE`` × the DSM outlier threshold (2 px of parallax by default): on drone
#: seeds 1–2 +0.04 to +1.3 points of the visible cells against 1 px with open NMAD and RMSE
#: as before (±0.2 %, RMSE up to −0.7 %); without the test open RMSE rose by 1.2 / 1.7 %
#: (seed 2 0101_0102, 0202_0203).
SLANT_TOLERANCE = 2.0
#: The test of the slant cells runs in rounds, each against the plain pass's heights and the
#: slant cells kept so far, until no more are kept or this many rounds have run: a slope the
#: plain pass left empty (an embankment) is filled in from its foot in the first round, metres
#: off its upper part, so one round refused it. Eight rounds against one on the drone models
#: of seeds 1–3: +0.03 to +2.9 points of the visible cells, open NMAD within 0.0005 m, open
#: RMSE −0.7 to +1.3 % (+1.3 %: a roof spread over 18 occluded ground cells), object RMSE −5
#: to 0 %, 13–17 % more time (docs/decisions.md, 2026-11-28, slant cells kept in rounds) —
#: since the rounds retest only the cells near a change, 2.2 instead of 9.4 s a grid.
SLANT_GROW_ROUNDS = 8
#: Side (left pixels) of the blocks of :class:`_Guide`.
GUIDE_FACTOR = 8
#: Half width (px) of the guided pass's search around the first DSM's disparities
#: (:func:`guided_pass`; as the refinement of wide-base nadir models).
GUIDED_REFINE = 8


def slant_scales(setup: ModelSetup, slant_passes: bool = True) -> Tuple[float, ...]:
    """The stretches of the model's slant passes: :data:`SLANT_SCALES` for convergent and
    wide-base models (:func:`wide_base`), none for narrow-base nadir models or without
    ``slant_passes``."""
    if slant_passes and (setup.convergent or wide_base(setup)):
        return SLANT_SCALES
    return ()


def slant_passes(setup: ModelSetup, scales: Tuple[float, ...], row_slope: float
                 ) -> Tuple[Tuple[float, float], ...]:
    """The (stretch, shear) of each slant pass: the ``scales`` unsheared, and for convergent
    models also :data:`SLANT_SHEARS`, leaning the way ``row_slope`` (the plain pass's
    disparity change per row, :meth:`_Guide.row_slope`) does."""
    passes = tuple((s, 0.0) for s in scales)
    if scales and setup.convergent:
        sign = 1.0 if row_slope >= 0 else -1.0
        passes += tuple((s, sign * k) for s, k in SLANT_SHEARS)
    return passes


def stretched_source(source: GreySource, scale: float, shear: float = 0.0) -> GreySource:
    """A grey source of the right epipolar image stretched along its rows by ``scale`` (and
    sheared by ``shear`` px per row).

    Column ``x'`` of row ``y`` of the stretched image is column ``x' / scale − shear·y`` of the
    original (linear interpolation, NaN where either neighbour is masked or outside); rows
    stay, so the pair stays epipolar and a disparity ``d'`` against it is
    ``d = x_l − (x_l − d') / scale + shear·y`` (:func:`unstretch`).
    """
    def read(r0: int, r1: int, c0: int, c1: int) -> np.ndarray:
        x = (np.arange(c0, c1, dtype=np.float64)[None, :] / scale
             - shear * np.arange(r0, r1, dtype=np.float64)[:, None])
        a0 = int(np.floor(x.min()))
        base = np.floor(x).astype(np.int64)
        block = source(r0, r1, a0, int(base.max()) + 2)
        i, f = base - a0, (x - base).astype(np.float32)
        rows = np.arange(r1 - r0)[:, None]
        return block[rows, i] * (1.0 - f) + block[rows, i + 1] * f

    return read


def unstretch(d: np.ndarray, col: np.ndarray, scale: float, row: Any = 0.0,
              shear: float = 0.0) -> np.ndarray:
    """Disparities against the image stretched by ``scale`` and sheared by ``shear``
    (:func:`stretched_source`) at left pixels (``col``, ``row``) → disparities of the pair."""
    return col - (col - d) / scale + shear * np.asarray(row)


def _stretched_range(setup: ModelSetup, scale: float, shear: float = 0.0) -> Tuple[int, int]:
    """Search range against the right image stretched by ``scale`` and sheared by ``shear``:
    ``d' = (1 − s)·x_l + s·d − s·k·y`` over the left image's columns and rows and the
    model's range."""
    w, h = setup.pair.sizes[0][0], setup.pair.height
    ends = [(1.0 - scale) * x + scale * d - scale * shear * y for x in (0.0, w - 1.0)
            for d in (setup.min_d, setup.max_d) for y in (0.0, h - 1.0)]
    return int(np.floor(min(ends))), int(np.ceil(max(ends)))


def _write_grey(pair: EpipolarPair, side: str, image: np.ndarray, path: Path,
                feedback: Feedback) -> None:
    """Grey (band mean) epipolar image as float32, NaN outside the original image."""
    w, h = pair.sizes[SIDES.index(side)]
    profile = gtiff_profile(w, h, 1, "float32", nodata=float("nan"), compress="none")
    chunk = max(1, RESAMPLE_BLOCK_PIXELS // max(w, 1))
    with open_image(path, "w", **profile) as dst:
        for r0, block, valid, _, _ in pair.iter_resample(image, side, chunk):
            grey = block.astype(np.float32).mean(axis=0)
            grey[~valid] = np.nan
            dst.write(grey[None], window=Window(0, r0, w, grey.shape[0]))
            feedback.check()


def _window_source(src: Any) -> Tuple[GreySource, Tuple[int, int]]:
    """Window reader of band 1 of a float32 scratch image (NaN beyond the image)."""
    h, w = src.height, src.width

    def read(r0: int, r1: int, c0: int, c1: int) -> np.ndarray:
        out = np.full((r1 - r0, c1 - c0), np.nan, np.float32)
        rr0, rr1, cc0, cc1 = max(r0, 0), min(r1, h), max(c0, 0), min(c1, w)
        if rr1 > rr0 and cc1 > cc0:
            out[rr0 - r0:rr1 - r0, cc0 - c0:cc1 - c0] = src.read(
                1, window=Window(cc0, rr0, cc1 - cc0, rr1 - rr0))
        return out

    return read, (h, w)


class _Guide:
    """Block means of the plain pass's disparities over ``GUIDE_FACTOR``² left pixels: the
    search ranges of the slant passes (the stretch widens the model's range by ``|1 − s|``
    × the image width, which a coarse pass of its own could not narrow again)."""

    def __init__(self, shape: Tuple[int, int]) -> None:
        cells = (-(-shape[0] // GUIDE_FACTOR), -(-shape[1] // GUIDE_FACTOR))
        self.total = np.zeros(cells, np.float64)
        self.count = np.zeros(cells, np.int64)

    def add(self, d: np.ndarray, col: np.ndarray, row: np.ndarray) -> None:
        """Valid disparities ``d`` at left pixels (``col``, ``row``)."""
        at = (row // GUIDE_FACTOR, col // GUIDE_FACTOR)
        np.add.at(self.total, at, d)
        np.add.at(self.count, at, 1)

    def _means(self) -> np.ndarray:
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(self.count > 0, self.total / self.count, np.nan)

    def stretched(self, scale: float, shear: float = 0.0) -> np.ndarray:
        """The block means as disparities against the right image stretched by ``scale``
        and sheared by ``shear`` (:func:`stretched_source`)."""
        d = self._means()
        col = (np.arange(d.shape[1]) + 0.5) * GUIDE_FACTOR - 0.5
        row = (np.arange(d.shape[0]) + 0.5) * GUIDE_FACTOR - 0.5
        return ((1.0 - scale) * col[None, :] + scale * d
                - scale * shear * row[:, None]).astype(np.float32)

    def row_slope(self) -> float:
        """The disparity change per left row of a plane fitted to the block means (px per
        row; 0 with fewer than three blocks)."""
        d = self._means()
        rr, cc = np.nonzero(np.isfinite(d))
        if rr.size < 3:
            return 0.0
        A = np.column_stack([cc, rr, np.ones(rr.size)]).astype(np.float64)
        coef = np.linalg.lstsq(A, d[rr, cc], rcond=None)[0]
        return float(coef[1]) / GUIDE_FACTOR


def _settled_cells(acc: GridAccumulator, footprints: Optional[GridAccumulator]) -> np.ndarray:
    """Cells the plain pass measured whose eight neighbours it measured too.

    The gridding drops every slant point in a measured cell (:func:`_grid`), so a
    slant disparity whose every possible refined position lies in measured cells need not be
    refined at all (:func:`_may_reach_open_cells`)."""
    covered = acc.covered()
    if footprints is not None:
        covered |= footprints.covered()
    return ndimage.binary_erosion(covered, np.ones((3, 3), bool), border_value=1)


def _may_reach_open_cells(pair: EpipolarPair, grid: Grid, settled: np.ndarray, d: np.ndarray,
                          cols: np.ndarray, rows: np.ndarray, shift: float) -> np.ndarray:
    """True for the disparities whose point, moved by up to ± ``shift`` px (the LSM bound),
    may fall in a cell outside ``settled``.

    Over d ± shift the point runs along a straight piece of the left ray; sampled at no more
    than one cell apart, every cell the piece crosses is a neighbour of a sampled cell, and a
    sample in a settled cell has only measured neighbours."""
    ends = [pair.disparity_to_world(d + s, cols, rows) for s in (-shift, shift)]
    length = np.hypot(*(ends[1][:, :2] - ends[0][:, :2]).T)
    finite = np.isfinite(length)
    n = 2 + int(np.ceil(np.max(length[finite], initial=0.0) / grid.spacing))
    reach = ~finite  # a point without a position is left to the refinement
    for t in np.linspace(0.0, 1.0, n):
        xy = (1.0 - t) * ends[0][:, :2] + t * ends[1][:, :2]
        r, c = grid.cell_of(xy[:, 0], xy[:, 1])
        inside = r >= 0  # points outside the grid are dropped by the accumulator
        reach[inside] |= ~settled[r[inside], c[inside]]
    return reach


class _SlantImage:
    """Scratch image (left epipolar geometry, float32, NaN = none) of the slant passes'
    kept disparities, read back tile by tile as the refinement pass's guide
    (``refine_guide`` of :func:`.dense.iter_disparity_tiles`); the first scale that gives a
    pixel a disparity keeps it."""

    def __init__(self, path: Path, shape: Tuple[int, int]) -> None:
        h, w = shape
        profile = gtiff_profile(w, h, 1, "float32", nodata=float("nan"), compress="none")
        self._ctx = open_image(path, "w+", **profile)
        self.src = self._ctx.__enter__()
        rows = max(1, RESAMPLE_BLOCK_PIXELS // max(w, 1))
        for r0 in range(0, h, rows):
            n = min(rows, h - r0)
            self.src.write(np.full((1, n, w), np.nan, np.float32), window=Window(0, r0, w, n))

    def add(self, d: np.ndarray, cols: np.ndarray, rows: np.ndarray) -> None:
        """Disparities ``d`` at left pixels (``cols``, ``rows``) where there is none yet."""
        if not d.size:
            return
        r0, c0 = int(rows.min()), int(cols.min())
        win = Window(c0, r0, int(cols.max()) - c0 + 1, int(rows.max()) - r0 + 1)
        block = self.src.read(1, window=win)
        rr, cc = rows - r0, cols - c0
        empty = ~np.isfinite(block[rr, cc])
        block[rr[empty], cc[empty]] = d[empty]
        self.src.write(block[None], window=win)

    def source(self) -> GreySource:
        """A window reader of the image."""
        return _window_source(self.src)[0]

    def close(self) -> None:
        """Close the scratch image."""
        self._ctx.__exit__(None, None, None)


def _slant_disparities(block: np.ndarray, r0: int, c0: int, scale: float, shear: float,
                       left: GreySource, right: GreySource, pair: EpipolarPair, grid: Grid,
                       settled: Optional[np.ndarray]
                       ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The disparities of the pair from one slant tile (with ``settled``: those that may reach
    a cell outside it), refined by LSM between the original images
    (:func:`.slant_lsm.refine_slant`, started with the pass's stretch and shear), those it
    keeps. Returns ``d``, columns and rows."""
    ok = np.isfinite(block)
    rr, cc = np.nonzero(ok)
    cols, rows = cc + c0, rr + r0
    d = unstretch(block[ok], cols, scale, rows, shear)
    if settled is not None:
        useful = _may_reach_open_cells(pair, grid, settled, d, cols, rows, SLANT_LSM_SHIFT)
        d, cols, rows = d[useful], cols[useful], rows[useful]
    # the right image's rows move by −shear px per row against the left's (∂x_r/∂y)
    d, keep = refine_slant(left, right, d, cols, rows, scale, shear=-shear)
    return d[keep], cols[keep], rows[keep]


def _slant_footprints(d: np.ndarray, cols: np.ndarray, rows: np.ndarray, shape: Tuple[int, int],
                      r0: int, c0: int) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`footprint_points` of the kept slant disparities of a tile (``shape`` at
    ``r0``, ``c0``) with :data:`SLANT_FOOTPRINT_STEP`: disparities, columns and rows."""
    block = np.full(shape, np.nan)
    block[rows - r0, cols - c0] = d
    fd, fc, fr = footprint_points(block, SLANT_FOOTPRINT_STEP)
    return fd, fc + c0, fr + r0


def _slant_into(setup: ModelSetup, grey: Dict[str, Path], acc: GridAccumulator,
                memory_mb: float, options: DenseOptions, guide: _Guide,
                scales: Tuple[float, ...], feedback: Feedback,
                settled: Optional[np.ndarray] = None,
                image: Optional[_SlantImage] = None) -> float:
    """The slant passes (stretches ``scales``, :func:`slant_scales`, and on convergent models
    the sheared ones of :func:`slant_passes`): tiled SGM against the stretched right image in
    the ranges of ``guide``; the valid disparities, refined by LSM
    (:func:`_slant_disparities`; if ``settled`` is given, only those that may reach a cell
    outside it), give their points into ``acc`` (convergent models: with their footprint
    points, :func:`_slant_footprints`) and, if given, into ``image``; returns the matching
    time (s)."""
    pair = setup.pair
    seconds = triangulation = 0.0  # the caller counts the triangulation apart
    # slopes, not objects: every hole border eroded and no object fill (with the plain pass's
    # upper-side rule and fill, roofs ran onto the ground beside buildings: 13 % of the new
    # field cells of 0202_0203 > 2 m off)
    options = replace(options, edge_jump=0.0, plane_fill=0.0, refine=0)
    with open_image(grey["left"]) as src_l, open_image(grey["right"]) as src_r:
        left, shape_l = _window_source(src_l)
        right, (h_r, w_r) = _window_source(src_r)
        passes = slant_passes(setup, scales, guide.row_slope())
        share = 100.0 / len(passes)
        for k, (scale, shear) in enumerate(passes):
            lo, hi = _stretched_range(setup, scale, shear)
            shape_r = (h_r, int(np.ceil(scale * (w_r - 1 + max(shear, 0.0) * (h_r - 1)))) + 1)
            t0 = time.perf_counter()
            for r0, c0, block in iter_disparity_tiles(
                    left, stretched_source(right, scale, shear), shape_l, shape_r, lo, hi,
                    options, max_memory_mb=memory_mb,
                    feedback=feedback.step(k * share, (k + 1) * share),
                    guide=(guide.stretched(scale, shear), GUIDE_FACTOR)):
                # the LSM refinement counts as matching
                d, cols, rows = _slant_disparities(block, r0, c0, scale, shear, left, right,
                                                   pair, setup.grid, settled)
                if image is not None:
                    image.add(d, cols, rows)
                t1 = time.perf_counter()
                if d.size:
                    if setup.convergent:  # with the points between four matched pixels
                        fd, fc, fr = _slant_footprints(d, cols, rows, block.shape, r0, c0)
                        d, cols, rows = (np.concatenate(p) for p in ((d, fd), (cols, fc),
                                                                     (rows, fr)))
                    pts = pair.disparity_to_world(d, cols, rows)
                    acc.add(pts[:, 0], pts[:, 1], pts[:, 2])
                triangulation += time.perf_counter() - t1
            seconds += time.perf_counter() - t0
    return seconds - triangulation


@dataclass
class _MatchCounts:
    """Left pixels with data, valid disparities and the matching time over all tiles."""

    n_left: int = 0
    n_valid: int = 0
    seconds: float = 0.0


def _match_into(setup: ModelSetup, grey: Dict[str, Path], acc: Optional[GridAccumulator],
                memory_mb: float, options: DenseOptions, feedback: Feedback,
                footprints: Optional[GridAccumulator] = None,
                guide: Optional[_Guide] = None,
                refine_guide: Optional[GreySource] = None) -> _MatchCounts:
    """Tiled SGM of the scratch epipolar images; every tile's points into ``acc``, the
    sub-pixel points of :func:`footprint_points` into ``footprints`` and the disparities
    into ``guide`` if given (``refine_guide`` as :func:`.dense.iter_disparity_tiles`).
    ``feedback`` covers the matching alone.

    The time of the matching (the tile generator) is told apart from the triangulation.
    """
    pair = setup.pair
    counts = _MatchCounts()
    with open_image(grey["left"]) as src_l, open_image(grey["right"]) as src_r:
        left, shape_l = _window_source(src_l)
        right, shape_r = _window_source(src_r)
        tiles = iter_disparity_tiles(left, right, shape_l, shape_r, setup.min_d, setup.max_d,
                                     options, max_memory_mb=memory_mb,
                                     feedback=feedback, refine_guide=refine_guide)
        while True:
            t1 = time.perf_counter()
            try:
                r0, c0, block = next(tiles)
            except StopIteration:
                break
            counts.seconds += time.perf_counter() - t1
            counts.n_left += int(np.isfinite(left(r0, r0 + block.shape[0], c0,
                                                  c0 + block.shape[1])).sum())
            ok = np.isfinite(block)
            counts.n_valid += int(ok.sum())
            if not ok.any():
                continue
            rr, cc = np.nonzero(ok)
            if acc is not None:
                pts = pair.disparity_to_world(block[ok], cc + c0, rr + r0)
                acc.add(pts[:, 0], pts[:, 1], pts[:, 2])
            if guide is not None:
                guide.add(block[ok], cc + c0, rr + r0)
            if footprints is not None:
                d, fc, fr = footprint_points(block)
                pts = pair.disparity_to_world(d, fc + c0, fr + r0)
                footprints.add(pts[:, 0], pts[:, 1], pts[:, 2])
    return counts


def _all_passes(setup: ModelSetup, grey: Dict[str, Path], acc: GridAccumulator,
                memory_mb: float, options: DenseOptions, feedback: Feedback, work: Path,
                footprints: Optional[GridAccumulator], guide: Optional[_Guide],
                scales: Tuple[float, ...]) -> Tuple[_MatchCounts, Optional[GridAccumulator]]:
    """The plain pass into ``acc`` (and ``footprints``), then the slant passes (with
    ``guide``) into an accumulator of their own, which is returned with the counts.

    With the refinement (``options.refine``) and slant passes, the plain pass only gives the
    slant passes their ranges; the plain pass is then matched once more, refined with the
    slant disparities in its guide (:class:`_SlantImage`), and that gives ``acc`` its
    points — so the refinement sees what the slant passes found.
    """
    if guide is None:
        return _match_into(setup, grey, acc, memory_mb, options, feedback.step(20, 85),
                           footprints), None
    refine = options.ours and options.refine > 0
    # the slant passes take most of the matching time when they run
    slant = GridAccumulator(setup.grid, memory_mb=memory_mb, scratch_dir=work)
    if not refine:
        counts = _match_into(setup, grey, acc, memory_mb, options, feedback.step(20, 45),
                             footprints, guide)
        settled = _settled_cells(acc, footprints)
        counts.seconds += _slant_into(setup, grey, slant, memory_mb, options, guide, scales,
                                      feedback.step(45, 85), settled)
        return counts, slant
    # the refined pass's cells are not known yet, and the refinement's guide takes the slant
    # disparities of every hole: each of them is refined (no ``settled`` cells)
    first = _match_into(setup, grey, None, memory_mb, replace(options, refine=0),
                        feedback.step(20, 35), None, guide)
    image = _SlantImage(work / "slant_disparity.tif", (setup.pair.height,
                                                       setup.pair.sizes[0][0]))
    try:
        seconds = _slant_into(setup, grey, slant, memory_mb, options, guide, scales,
                              feedback.step(35, 75), image=image)
        counts = _match_into(setup, grey, acc, memory_mb, options, feedback.step(75, 85),
                             footprints, refine_guide=image.source())
    finally:
        image.close()
    counts.seconds += first.seconds + seconds
    return counts, slant


@dataclass
class _Outliers:
    """The DSM outlier test (:func:`~..surface.gridding.reject_outliers`)."""

    radius: float
    threshold: float
    k: float


def _pct(part: int, whole: int) -> float:
    """``100 · part / whole`` (0 for an empty whole)."""
    return 100.0 * part / whole if whole else 0.0


def _metrics(setup: ModelSetup, acc: GridAccumulator, res: Any, counts: _MatchCounts,
             max_gap: float, outliers: _Outliers, slant_cells: Optional[np.ndarray] = None,
             guided_cells: Optional[np.ndarray] = None) -> Dict[str, Any]:
    """Headline figures: points, the valid share of the disparities, and the shares of the
    measuring area that are measured (a cell with a triangulated point), interpolated (a gap
    filled) and empty; they add up to 100 %, ``coverage_pct`` = measured + interpolated. With
    slant passes also the share measured by them alone, with the guided pass the share it
    added to the first DSM (both part of ``measured_pct``)."""
    grid = setup.grid
    area = polygon_mask([setup.measuring_area()], grid) & ~polygon_mask(setup.exclusions, grid)
    n_area = int(area.sum())
    have = np.isfinite(res.z) & area
    n_have = int(have.sum())
    n_filled = int((have & res.filled).sum())
    n_left, n_valid = counts.n_left, counts.n_valid
    metrics = {
        "points": int(acc.points),
        "coverage_pct": _pct(n_have, n_area),
        "measured_pct": _pct(n_have - n_filled, n_area),
        "interpolated_pct": _pct(n_filled, n_area),
        "empty_pct": _pct(n_area - n_have, n_area),
        "valid_disparity_pct": _pct(n_valid, n_left),
        "spacing_m": setup.spacing,
        "cells": [grid.width, grid.height],
        "disparity_range_px": [setup.min_d, setup.max_d],
        "height_range_m": [setup.z_min, setup.z_max],
        "max_gap_m": max_gap,
        "outlier_radius_m": outliers.radius,
        "outlier_threshold_m": outliers.threshold,
        "epipolar_mpx": setup.pair.sizes[0][0] * setup.pair.sizes[0][1] / 1e6,
    }
    if slant_cells is not None:
        metrics["slant_measured_pct"] = _pct(int((slant_cells & have & ~res.filled).sum()),
                                             n_area)
    if guided_cells is not None:
        metrics["guided_measured_pct"] = _pct(int((guided_cells & have).sum()), n_area)
    return metrics


def _reduced(acc: Optional[GridAccumulator]) -> Optional[Tuple[np.ndarray, np.ndarray]]:
    """Median and count per cell of an accumulator (consumed), None without one."""
    return None if acc is None else acc.reduce()


def slant_cells(z: np.ndarray, z_slant: np.ndarray, spacing: float, radius: float,
                threshold: float, k: float, rounds: int = SLANT_GROW_ROUNDS) -> np.ndarray:
    """Cells whose slant-pass height agrees with the heights around them.

    Each round fills the gaps of ``z`` (up to :data:`SLANT_GAP_CELLS` cells) and keeps the
    slant cells that pass :func:`~..surface.gridding.deviates_from` against it; the kept cells
    join ``z`` for the next round, so a slope grows from the cells that hold it.

    Parameters
    ----------
    z : ndarray (h, w)
        The trusted heights (the plain pass's cells), NaN = empty.
    z_slant : ndarray (h, w)
        Candidate heights, NaN = none (give none where ``z`` has one).
    spacing, radius, threshold, k : float
        As :func:`~..surface.gridding.deviates_from`.
    rounds : int
        Largest number of rounds; 1 = the test against ``z`` alone.

    Returns
    -------
    ndarray of bool
        True where a candidate is kept.
    """
    z = np.array(z, np.float32)
    candidate = np.isfinite(z_slant)
    take = np.zeros(z.shape, bool)
    # a verdict reads the reference within two half windows (the median of each neighbour's
    # window): where the reference did not change that far, last round's verdict stands
    reach = 2 * window_half(radius, spacing)
    before = None
    for _round in range(rounds):
        ref = fill_gaps(z, spacing, SLANT_GAP_CELLS * spacing)[0]
        filled = nearest_filled(ref)
        todo = candidate & ~take
        if before is not None and filled is not None:
            changed = (filled != before).view(np.uint8)
            todo &= ndimage.maximum_filter(changed, size=2 * reach + 1) > 0
        new = todo & ~deviates_from(z_slant, ref if filled is None else filled, spacing,
                                    radius, threshold, k, where=todo)
        if not new.any():
            break
        take |= new
        z[new] = z_slant[new]
        before = filled
    return take


def _grid(setup: ModelSetup, plain: Tuple[np.ndarray, np.ndarray], max_gap: float,
          outliers: _Outliers, feedback: Feedback,
          footprints: Optional[Tuple[np.ndarray, np.ndarray]] = None,
          slant: Optional[Tuple[np.ndarray, np.ndarray]] = None
          ) -> Tuple[Any, Optional[np.ndarray]]:
    """The DSM of the reduced accumulators (median and count per cell): the ``plain`` pass's
    cells, cells without a pixel's point from ``footprints``, then from ``slant`` where that
    agrees with its neighbourhood; outlier test and gap filling. Returns the grid result and
    the cells the slant passes gave (None without them)."""
    grid = setup.grid
    zg, count = plain[0].copy(), plain[1].copy()
    if footprints is not None:
        zf, count_f = footprints
        take = (count == 0) & (count_f > 0)
        zg[take], count[take] = zf[take], count_f[take]
    if slant is not None:
        zs = np.where(count > 0, np.nan, slant[0])
        take = slant_cells(zg, zs, grid.spacing, outliers.radius,
                           SLANT_TOLERANCE * outliers.threshold, outliers.k)
        zg[take], count[take] = zs[take], slant[1][take]
    else:
        take = None
    res = finish_grid(zg, count, grid, max_gap, setup.exclusions, setup.boundaries,
                      setup.breaklines, outlier_radius=outliers.radius,
                      outlier_threshold=outliers.threshold, outlier_k=outliers.k)
    feedback.check()
    return res, take


def _write(setup: ModelSetup, res: Any, tmp: Path) -> None:
    """dsm.tif and count.tif of a grid result into ``tmp``."""
    grid, crs = setup.grid, setup.project.crs
    write_grid(tmp / "dsm.tif", res.z, grid, crs=crs)
    write_grid(tmp / "count.tif", np.minimum(res.count, 65535).astype(np.uint16), grid,
               crs=crs, overviews=False)


def guided_pass(setup: ModelSetup, guided: bool = True) -> bool:
    """Whether the model gets the DSM-guided pass (:mod:`.dense_guided`): convergent models
    with ``guided``."""
    return bool(guided and setup.convergent)


def _guided_into(setup: ModelSetup, grey: Dict[str, Path], acc: GridAccumulator, res: Any,
                 memory_mb: float, options: DenseOptions, feedback: Feedback
                 ) -> Tuple[_MatchCounts, np.ndarray]:
    """The DSM-guided pass: the plain pass once more, refined within ± :data:`GUIDED_REFINE`
    px of the first DSM's disparities (:func:`.dense_guided.dsm_guide`), its holes filled
    where least-squares matching and uniqueness confirm them; every point into ``acc``.
    Returns the counts and the cells the pass may add: the first DSM's
    :func:`.dense_guided.terrain_holes` (a left pixel whose guide is the ground in front of
    an unmeasured roof may see the roof)."""
    measured = (res.count > 0) & ~res.filled
    area = polygon_mask([setup.measuring_area()], setup.grid)
    holes = terrain_holes(res.z, measured, area, _JUMP_M)
    guide = dsm_guide(setup.pair, res.z, measured, setup.grid, measured | holes)
    source, _ = array_source(guide)
    opts = replace(options, refine=GUIDED_REFINE, refine_all=False, refine_holes="verified")
    counts = _match_into(setup, grey, acc, memory_mb, opts, feedback, refine_guide=source)
    return counts, holes


def _regrid(setup: ModelSetup, acc: GridAccumulator, first: Any,
            plain: Tuple[np.ndarray, np.ndarray], holes: np.ndarray, max_gap: float,
            outliers: _Outliers, feedback: Feedback,
            footprints: Optional[Tuple[np.ndarray, np.ndarray]],
            slant: Optional[Tuple[np.ndarray, np.ndarray]]
            ) -> Tuple[Any, Optional[np.ndarray], np.ndarray]:
    """The DSM of the guided pass's points (``acc``, consumed) as :func:`_grid`, new cells
    only in the first DSM's terrain ``holes`` (``plain``: the first pass's median and count).
    Returns the grid result, the slant passes' cells and the cells the pass added to the
    ``first`` grid result."""
    z, count = acc.reduce()
    off = (plain[1] == 0) & ~holes
    z[off], count[off] = np.nan, 0
    res, slant_cells = _grid(setup, (z, count), max_gap, outliers, feedback, footprints, slant)
    added = (res.count > 0) & ~res.filled & ~((first.count > 0) & ~first.filled)
    return res, slant_cells, added


def _report(setup: ModelSetup, metrics: Dict[str, Any], options: DenseOptions,
            timings: Dict[str, float]) -> Dict[str, Any]:
    """The content of report.json (keys in the order of the report)."""
    recs = setup.records
    report = {"model": setup.model.name, "images": [recs[0].name, recs[1].name],
              "method": "dense", "crs": setup.project.crs, "metrics": metrics,
              "options": {k: v for k, v in asdict(options).items() if v is not None},
              "seconds": timings}
    report["flying_height_m"] = setup.flying_height
    return report


def match_model_dense(project: Any, model: str, output_dir: PathLike,
                      spacing: Optional[float] = None, feedback: Optional[Feedback] = None,
                      min_height: Optional[float] = None, max_height: Optional[float] = None,
                      max_gap: Optional[float] = None, disparity_margin: int = 4,
                      memory_mb: float = 256.0, outlier_radius: Optional[float] = None,
                      outlier_threshold: Optional[float] = None, outlier_k: float = 3.0,
                      slant_passes: bool = True, guided: bool = True,
                      **dense_options: Any) -> Dict[str, Any]:
    """Dense DSM of a stereo model (see the module notes).

    Parameters
    ----------
    project : Project or path
        The project (or its folder / project.toml).
    model : str
        Stereo model name.
    output_dir : path
        Output folder (created or replaced if PhotoDEM wrote it).
    spacing : float, optional
        DSM cell size (m); default 1 × the model's GSD.
    min_height, max_height : float, optional
        Height range of the terrain and objects (m); default terrain height ∓/± 0.3 H.
    max_gap : float, optional
        Largest gap (m, inscribed diameter) that is interpolated; default 10 × spacing.
    disparity_margin : int
        Extra disparities (px) searched on either side of the range.
    memory_mb : float
        Memory per matching tile and for buffered points.
    outlier_radius : float, optional
        Half side (m) of the neighbourhood of the DSM outlier test
        (:func:`~..surface.gridding.reject_outliers`); default 5 × spacing; 0 = off.
    outlier_threshold : float, optional
        Smallest height deviation (m) from the neighbourhood median that is rejected; default
        the height of 1 px of parallax, ``GSD · H / B``.
    outlier_k : float
        Multiple of the local robust spread (1.4826 · MAD) a rejected deviation must exceed.
    slant_passes : bool
        Convergent and wide-base models (:func:`slant_scales`): also match against the right
        image stretched by :data:`SLANT_SCALES` and give the cells no plain point reached the
        heights that agree with the plain ones (module notes). On by default: 0.9–5.4 points
        more of the drone models' visible cells, open accuracy as before, about 5–8 × the
        time (issue 22, parts N and X; issue 19, part Z in docs/decisions.md).
    guided : bool
        Convergent models: match once more along the first DSM (:func:`guided_pass`, module
        notes, step 6). On by default (issue 22, part AD).
    **dense_options
        Fields of :class:`~.dense.DenseOptions` (method, block_size, p1, p2, …) that replace
        the DSM path's values for this model (:func:`dsm_dense_options`).

    Returns
    -------
    dict
        ``{"dsm", "count", "report", "points", "metrics"}``.
    """
    feedback = ensure_feedback(feedback)
    t_start = time.perf_counter()
    setup = prepare_model(project, model, spacing=spacing, spacing_gsd=1.0,
                          min_height=min_height, max_height=max_height,
                          disparity_margin=disparity_margin)
    m, pair, grid, spacing = setup.model, setup.pair, setup.grid, setup.spacing
    max_gap = 10.0 * spacing if max_gap is None else float(max_gap)
    outliers = _Outliers(5.0 * spacing if outlier_radius is None else float(outlier_radius),
                         # 1 px of parallax in height
                         1.0 / setup.parallax_per_metre
                         if outlier_threshold is None else outlier_threshold, outlier_k)
    options = dsm_dense_options(setup, **dense_options)
    feedback.info(f"Model {m.name}: heights {setup.z_min:.1f}…{setup.z_max:.1f} m → "
                  f"disparities {setup.min_d}…{setup.max_d} px; DSM {grid.width}×{grid.height} "
                  f"cells at {spacing:.3f} m.")
    images = [setup.project.read_image(rec, colour_only=True) for rec in setup.records]
    out = Path(output_dir)
    timings: Dict[str, float] = {}
    with staged_folder(out, replace=True, product="match_model") as tmp, \
            scratch_folder(tmp.parent, f"{out.name}.dense") as work:
        t0 = time.perf_counter()
        grey = {}
        for i, side in enumerate(SIDES):
            grey[side] = work / f"{side}.tif"
            _write_grey(pair, side, images[i], grey[side], feedback.step(10 * i, 10 * i + 10))
        del images
        timings["epipolar"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        acc = GridAccumulator(grid, memory_mb=memory_mb, scratch_dir=work)
        extra = (GridAccumulator(grid, memory_mb=memory_mb, scratch_dir=work)
                 if setup.convergent else None)
        scales = slant_scales(setup, slant_passes)
        guide = _Guide((pair.height, pair.sizes[0][0])) if scales else None
        second = guided_pass(setup, guided)
        counts, slant = _all_passes(setup, grey, acc, memory_mb, options,
                                    feedback.step(0, 76 if second else 100), work,
                                    extra, guide, scales)
        timings["matching"] = counts.seconds
        timings["triangulation"] = time.perf_counter() - t0 - counts.seconds
        t0 = time.perf_counter()
        plain = acc.reduce(feedback.step(85, 92))
        footprints, slanted = _reduced(extra), _reduced(slant)
        res, slant_cells = _grid(setup, plain, max_gap, outliers, feedback, footprints,
                                 slanted)
        guided_cells = None
        if second:
            t1 = time.perf_counter()
            acc = GridAccumulator(setup.grid, memory_mb=memory_mb, scratch_dir=work)
            counts, holes = _guided_into(setup, grey, acc, res, memory_mb, options,
                                         feedback.step(76, 85))
            timings["guided"] = time.perf_counter() - t1
            res, slant_cells, guided_cells = _regrid(setup, acc, res, plain, holes, max_gap,
                                                     outliers, feedback, footprints, slanted)
        _write(setup, res, tmp)
        metrics = _metrics(setup, acc, res, counts, max_gap, outliers, slant_cells,
                           guided_cells)
        timings["gridding"] = time.perf_counter() - t0 - timings.get("guided", 0.0)
        timings["total"] = time.perf_counter() - t_start
        write_model_report(tmp, _report(setup, metrics, options, timings),
                           dsm=tmp / "dsm.tif", count=tmp / "count.tif",
                           exclusions=setup.exclusions)
        feedback.progress(100.0)
    feedback.info(f"Model {m.name}: {metrics['points']} points; {coverage_sentence(metrics)}")
    return {"dsm": str(out / "dsm.tif"), "count": str(out / "count.tif"), "sigma": None,
            "report": str(out / "report.json"), "report_html": str(out / "report.html"),
            "points": None, "reduced": None, "metrics": metrics}


__all__ = ["dsm_dense_options", "match_model_dense"]
