r"""Large DSMs in overlapping tiles, for both DSM → DTM filters.

A grid with more than ``max_cells`` cells is split into tiles of at most ``max_cells`` cells
(core plus an overlap of ``overlap`` cells on every inner side). Every tile is filtered on its
own — with its slice of the operator's edits — so the filter's temporaries are bounded by the
tile, not by the raster. The DTMs are joined with a linear feather across the overlap:

.. math:: z(c) = \frac{\sum_t w_t(c)\, z_t(c)}{\sum_t w_t(c)}, \qquad
          w_t(c) = \min\Bigl(1, \frac{\delta_t(c) + \tfrac12}{o + \tfrac12}\Bigr)

with :math:`\delta_t(c)` the distance (cells) of cell ``c`` from the tile's cut edges (edges at
the raster border do not count) and ``o`` the overlap, so a tile hands over to its neighbour
continuously where the neighbour's own edge effects have died away. Cell-wise products (the
ground mask, the weights) come from the tile whose core holds the cell. With an overlap of at
least the filter's reach — the largest window (low-pass) or the correlation reach of the finer
pyramid levels (linear prediction) — the joined DTM differs from the untiled one by less than
the DSM noise (tests: tiled vs untiled on a mid-size grid).

On a Dask cluster (:func:`tiling`, the filters' ``scheduler`` parameter) every tile is a task
(:func:`..raster.tiled_dask.map_tiles`); the tiles' DTMs are joined here in the order of the
tiles, so the result is bit-identical to the tiled run in one process. The filters' global
parameters (the blunder height range of the whole DSM) travel inside ``run_tile``.
"""

from __future__ import annotations

import math
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from typing import Any, Callable, Dict, Iterator, List, Optional, Tuple

import numpy as np
from affine import Affine
from numpy.typing import NDArray

from ..feedback import Feedback, ensure_feedback
from ..raster.tiled_dask import check_scheduler, map_tiles
from ..surface.gridding import Grid
from .surface_input import FilterConstraints, check_ground_points

Array = NDArray[Any]

#: Grids with more cells than this are filtered in tiles (4096² ≈ 16.8 M: the 4000 × 4000 DSM
#: of the speed target is still one piece; peak memory ≈ 150 bytes per cell of a tile).
MAX_CELLS = 4096 * 4096

#: Padded tiles start on multiples of this many cells (2⁷: pyramid blocks line up).
ALIGN = 128

Window = Tuple[int, int, int, int]  # r0, r1, c0, c1


@dataclass(frozen=True)
class Tiling:
    """Where and how large the filters' tiles are for the code inside :func:`tiling`."""

    scheduler: str = ""
    max_cells: Optional[int] = None


_TILING: ContextVar[Optional[Tiling]] = ContextVar("photodem_filter_tiling", default=None)


def _current() -> Tiling:
    """The tiling set by the innermost :func:`tiling` block (none: this process, MAX_CELLS)."""
    return _TILING.get() or Tiling()


@contextmanager
def tiling(scheduler: Optional[str] = "", tile: Optional[int] = None) -> Iterator[Tiling]:
    """Filter in tiles of at most ``tile``² cells (default :data:`MAX_CELLS`) on ``scheduler``
    (``""`` this process, ``"local"`` or ``"tcp://host:port"``: Dask) inside the block."""
    t = Tiling(check_scheduler(scheduler), None if not tile else int(tile) ** 2)
    token = _TILING.set(t)
    try:
        yield t
    finally:
        _TILING.reset(token)


def tile_limit(max_cells: Optional[int] = None) -> int:
    """Cells above which a grid is tiled: ``max_cells``, else :func:`tiling`'s, else
    :data:`MAX_CELLS`."""
    if max_cells is not None:
        return int(max_cells)
    return _current().max_cells or MAX_CELLS


def _splits(n: int, core: int) -> List[Tuple[int, int]]:
    """Equal core intervals of at most ``core`` cells covering 0…n."""
    k = max(1, math.ceil(n / max(core, 1)))
    edges = [round(i * n / k) for i in range(k + 1)]
    return [(edges[i], edges[i + 1]) for i in range(k)]


def tile_windows(shape: Tuple[int, int], max_cells: int, overlap: int
                 ) -> List[Tuple[Window, Window]]:
    """Tiles of a grid: ``(padded window, core window)`` pairs, ``(r0, r1, c0, c1)`` each.

    The cores partition the grid; the padded windows add ``overlap`` cells on every side
    (clipped at the border) and hold at most about ``max_cells`` cells.
    """
    h, w = shape
    if h * w <= max_cells:
        return [((0, h, 0, w), (0, h, 0, w))]
    side = max(math.isqrt(int(max_cells)) - 2 * overlap - ALIGN, max(overlap, 64))
    out = []
    for r0, r1 in _splits(h, side):
        for c0, c1 in _splits(w, side):
            # padded starts on multiples of ALIGN: the filters' 2 × 2 pyramids (hole filling,
            # linear prediction levels) then see the same blocks as on the whole grid
            pad = (max(0, (r0 - overlap) // ALIGN * ALIGN), min(h, r1 + overlap),
                   max(0, (c0 - overlap) // ALIGN * ALIGN), min(w, c1 + overlap))
            out.append((pad, (r0, r1, c0, c1)))
    return out


def feather(pad: Window, shape: Tuple[int, int], overlap: int) -> Array:
    """Feather weight of a padded tile (see the module notes), float32 of the tile's shape."""
    r0, r1, c0, c1 = pad
    h, w = shape

    def ramp(n: int, cut_lo: bool, cut_hi: bool) -> Array:
        i = np.arange(n, dtype=np.float64)
        d = np.full(n, np.inf)
        if cut_lo:
            d = np.minimum(d, i)
        if cut_hi:
            d = np.minimum(d, n - 1 - i)
        return np.minimum(1.0, (d + 0.5) / (overlap + 0.5))

    wr = ramp(r1 - r0, r0 > 0, r1 < h)
    wc = ramp(c1 - c0, c0 > 0, c1 < w)
    return (wr[:, None] * wc[None, :]).astype(np.float32)


def sub_grid(grid: Grid, window: Window) -> Grid:
    """The grid of a window ``(r0, r1, c0, c1)``."""
    r0, r1, c0, c1 = window
    return Grid(grid.transform * Affine.translation(c0, r0), c1 - c0, r1 - r0, grid.spacing)


def sub_constraints(cons: Optional[FilterConstraints], window: Window
                    ) -> Optional[FilterConstraints]:
    """The edits of a window: masks sliced, ground points and breaklines kept whole (each
    filter places them on the tile's grid and ignores what lies outside)."""
    if cons is None:
        return None
    r0, r1, c0, c1 = window

    def cut(a: Optional[Array]) -> Optional[Array]:
        return None if a is None else np.asarray(a)[r0:r1, c0:c1]

    return FilterConstraints(cut(cons.keep), cut(cons.remove), cons.ground_points,
                             list(cons.breaklines or []), cut(cons.barrier), cut(cons.barrier_z))


def iter_tiles(shape: Tuple[int, int], max_cells: int, overlap: int
               ) -> Iterator[Tuple[int, Window, Window]]:
    """``(index, padded window, core window)`` of every tile."""
    for i, (pad, core) in enumerate(tile_windows(shape, max_cells, overlap)):
        yield i, pad, core


def _run_tile_task(run_tile: Callable[..., Dict[str, Any]],
                   job: Tuple[Array, Grid, Optional[FilterConstraints]]) -> Dict[str, Any]:
    """One tile as a Dask task (its messages stay on the worker)."""
    zt, gt, ct = job
    return run_tile(zt, gt, ct, Feedback())


@dataclass
class _Join:
    """The feathered sum of the tiles' DTMs and the cell-wise products of their cores."""

    acc: Array
    wsum: Array
    ground: Array
    disagree: List[Dict[str, Any]]
    first: Dict[str, Any]

    def add(self, i: int, tile: Tuple[Window, Window], res: Dict[str, Any], grid: Grid,
            shape: Tuple[int, int], overlap: int) -> None:
        """Add tile ``i`` (``(padded, core)`` windows) with the filter's result ``res``."""
        pad, core = tile
        r0, r1, c0, c1 = pad
        dtm = np.asarray(res["dtm"], np.float32)
        wt = feather(pad, shape, overlap)
        ok = np.isfinite(dtm)
        self.acc[r0:r1, c0:c1] += np.where(ok, wt * dtm, 0.0)
        self.wsum[r0:r1, c0:c1] += np.where(ok, wt, 0.0)
        q0, q1, p0, p1 = core
        self.ground[q0:q1, p0:p1] = np.asarray(res["ground"], bool)[q0 - r0:q1 - r0,
                                                                     p0 - c0:p1 - c0]
        cg = sub_grid(grid, core)
        for b in res.get("ground_points_disagreeing") or []:
            if b.get("status") == "outside":
                continue
            rr, _ = cg.cell_of(np.array([b["x"]]), np.array([b["y"]]))
            if rr[0] >= 0:
                self.disagree.append(b)
        if i == 0:
            self.first = {k: v for k, v in res.items() if k not in ("dtm", "ground")}


def filter_in_tiles(run_tile: Callable[[Array, Grid, Optional[FilterConstraints], Feedback],
                                       Dict[str, Any]],
                    z: Array, grid: Grid, constraints: Optional[FilterConstraints],
                    overlap: int, max_cells: int = MAX_CELLS,
                    feedback: Optional[Feedback] = None) -> Dict[str, Any]:
    """Run a filter tile by tile and join the results (see the module notes).

    Parameters
    ----------
    run_tile : callable ``(z, grid, constraints, feedback) -> dict``
        Filters one tile; returns ``dtm`` (float32 grid), ``ground`` (bool grid) and
        optionally ``ground_points_disagreeing`` (list of dicts with ``x``, ``y``) and
        anything else (kept from the first tile under ``first``).
    z : ndarray (h, w)
        The DSM (a numpy array or a read-only memory map; only tile windows are copied).
    overlap : int
        Overlap in cells (≥ the filter's reach).

    Returns
    -------
    dict
        ``dtm``, ``ground``, ``ground_points_disagreeing`` (points listed by the tile whose
        core holds them), ``tiles`` (count), ``first`` (the first tile's own result).
    """
    feedback = ensure_feedback(feedback)
    shape = tuple(z.shape)
    tiles = tile_windows(shape, max_cells, overlap)  # type: ignore[arg-type]
    join = _Join(np.zeros(shape, np.float32), np.zeros(shape, np.float32),
                 np.zeros(shape, bool), [], {})
    n = len(tiles)
    scheduler = _current().scheduler
    if scheduler:
        jobs = [(np.array(z[p[0]:p[1], p[2]:p[3]], np.float32), sub_grid(grid, p),
                 sub_constraints(constraints, p)) for p, _ in tiles]
        feedback.info(f"{n} tiles on the Dask scheduler {scheduler}.")
        for i, res in map_tiles(_run_tile_task, jobs, (run_tile,), scheduler, feedback):
            jobs[i] = None  # type: ignore[call-overload]
            join.add(i, tiles[i], res, grid, shape, overlap)
    else:
        for i, (pad, core) in enumerate(tiles):
            r0, r1, c0, c1 = pad
            feedback.info(f"Tile {i + 1} of {n}: rows {r0}–{r1}, columns {c0}–{c1}.")
            res = run_tile(np.array(z[r0:r1, c0:c1], np.float32), sub_grid(grid, pad),
                           sub_constraints(constraints, pad),
                           feedback.step(100.0 * i / n, 100.0 * (i + 1) / n))
            join.add(i, (pad, core), res, grid, shape, overlap)
            del res
    acc, wsum, ground, disagree, first = (join.acc, join.wsum, join.ground, join.disagree,
                                          join.first)
    with np.errstate(invalid="ignore", divide="ignore"):
        dtm_all = np.where(wsum > 0, acc / np.where(wsum > 0, wsum, 1.0), np.nan)
    dtm_all = dtm_all.astype(np.float32)
    del acc, wsum
    join.acc = join.wsum = np.empty(0, np.float32)
    if constraints is not None and len(constraints.ground_points):
        disagree += [b for b in check_ground_points(dtm_all, grid, constraints.ground_points,
                                                    float("inf"))
                     if b["status"] == "outside"]
    disagree.sort(key=lambda b: b["index"])
    return {"dtm": dtm_all, "ground": ground, "ground_points_disagreeing": disagree,
            "tiles": n, "first": first}


__all__ = ["MAX_CELLS", "Tiling", "feather", "filter_in_tiles", "iter_tiles", "sub_constraints",
           "sub_grid", "tile_limit", "tile_windows", "tiling"]
