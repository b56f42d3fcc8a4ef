r"""Points → DSM grid: per-cell robust reduction, then gap interpolation that honours breaklines.

Grid
    Cells of side ``s`` (m), north up; cell (row, col) covers
    ``[x0 + col·s, x0 + (col+1)·s) × (y0 − (row+1)·s, y0 − row·s]``.

Reduction (groundels)
    The heights of all points in a cell are reduced to their **median** (weighted median with
    weights ``w = 1/σ²`` when σ is given: the smallest z with ``Σ_{z_i ≤ z} w_i ≥ ½ Σ w_i``);
    ``count`` is the number of points per cell. The median ignores up to half of the points
    as blunders.

Streaming
    :class:`GridAccumulator` sorts incoming points into output tiles (``tile`` cells square) and
    keeps only (cell index, z, w) per point; when the buffered points exceed ``memory_mb`` they
    are appended to one scratch file per tile. :meth:`GridAccumulator.reduce` then sorts one
    tile at a time (``lexsort`` by cell and z), so the peak memory is one tile's points plus
    the output grid, whatever the number of points.

Outlier rejection (optional, before the gap interpolation)
    With one or few points per cell the median cannot remove blunders, so measured cells are
    tested against their neighbourhood: with :math:`\tilde z` the median of the cells within
    a square window of side ``2·radius`` and :math:`\mathrm{MAD}` the median of
    :math:`|z - \tilde z|` in the same window, a cell is rejected (emptied) if
    :math:`|z - \tilde z| > \max(t,\ k \cdot 1.4826 \cdot \mathrm{MAD})`. ``t`` (m) is the
    smallest deviation that counts as a blunder; the MAD term keeps rough surfaces (steps at
    buildings, trees) whose neighbourhood spread is large. Empty cells of the window take the
    nearest measured height. Rejected cells are gaps like any other and may be re-filled by
    the interpolation below.

Gap interpolation
    Empty cells form gaps (4-connected). A gap is filled only if it is *small*: its inscribed
    diameter ``2·max_p dist(p, nearest measured cell)·s ≤ max_gap``; larger gaps stay NaN.
    The fill is the membrane (Laplace) interpolation :math:`\nabla^2 z = 0` inside the gap with
    the measured neighbours as fixed values — the discrete equation per gap cell
    :math:`\sum_{j \in N_4(i)} (z_i - z_j) = 0` over its 4-neighbours that are not barriers —
    solved as one sparse system. **Breaklines** are rasterised (every cell they touch) as
    barriers: no neighbour relation crosses them, so heights flow only around their ends and a
    step along a breakline is not smeared. Barrier cells that are empty get the breakline's own
    height (3-D lines) or else the nearest filled height. Exclusion areas and cells outside the
    boundary are NaN and are neither sources nor targets of the interpolation.
"""

from __future__ import annotations

import math
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, Iterable, List, Optional, Sequence, Tuple, Union

import numpy as np
from affine import Affine
from numpy.typing import ArrayLike, NDArray
from rasterio.features import rasterize

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from ..memory import check_allocation
from ..raster.io import write_raster

PathLike = Union[str, Path]
Array = NDArray[Any]


#: Bytes per cell a grid costs at least while it is worked on (a float32 result and one
#: float32 working copy); larger needs are checked where they arise.
GRID_BYTES_PER_CELL = 8


def check_grid_memory(width: int, height: int, spacing: float) -> None:
    """Refuse a grid that cannot be held in memory, before any work.

    Raises
    ------
    InputError
        Naming the grid size and the spacing to change.
    """
    check_allocation(float(width) * float(height) * GRID_BYTES_PER_CELL,
                     f"a grid of {width} × {height} cells at {spacing:g} m",
                     "the spacing (a coarser grid) or the extent")


@dataclass
class Grid:
    """A north-up grid: ``transform`` (cell corners), ``width``, ``height``, ``spacing``."""

    transform: Affine
    width: int
    height: int
    spacing: float

    @classmethod
    def from_bounds(cls, xmin: float, ymin: float, xmax: float, ymax: float,
                    spacing: float) -> Grid:
        """The grid covering the bounds, its corners snapped to multiples of ``spacing``."""
        if not spacing > 0:
            raise InputError(f"The grid spacing must be positive, got {spacing}.")
        if not (xmax > xmin and ymax > ymin):
            raise InputError("The grid area is empty.")
        x0 = math.floor(xmin / spacing) * spacing
        y0 = math.ceil(ymax / spacing) * spacing
        w = max(1, math.ceil((xmax - x0) / spacing))
        h = max(1, math.ceil((y0 - ymin) / spacing))
        check_grid_memory(w, h, spacing)
        return cls(Affine(spacing, 0.0, x0, 0.0, -spacing, y0), w, h, float(spacing))

    @property
    def shape(self) -> Tuple[int, int]:
        return self.height, self.width

    def cell_of(self, x: ArrayLike, y: ArrayLike) -> Tuple[Array, Array]:
        """(row, col) int64 of points; outside cells are returned as −1."""
        t = self.transform
        col = np.floor((np.asarray(x, float) - t.c) / t.a)
        row = np.floor((np.asarray(y, float) - t.f) / t.e)
        ok = (col >= 0) & (col < self.width) & (row >= 0) & (row < self.height)
        ok &= np.isfinite(col) & np.isfinite(row)
        return np.where(ok, row, -1).astype(np.int64), np.where(ok, col, -1).astype(np.int64)


class GridAccumulator:
    """Streaming per-cell median of points (see the module notes).

    Parameters
    ----------
    grid : Grid
    tile : int
        Side of the output tiles (cells) by which points are bucketed and reduced.
    memory_mb : float
        Buffered points beyond this go to scratch files (16 bytes per point).
    scratch_dir : path, optional
        Where scratch files go (default: the system temporary folder).
    """

    def __init__(self, grid: Grid, tile: int = 1024, memory_mb: float = 256.0,
                 scratch_dir: Optional[PathLike] = None) -> None:
        self.grid = grid
        self.tile = int(tile)
        self.tiles_x = math.ceil(grid.width / self.tile)
        self.tiles_y = math.ceil(grid.height / self.tile)
        self.limit = int(memory_mb * 2 ** 20 / 16)
        self._buffers: Dict[int, List[Array]] = {}
        self._buffered = 0
        self._scratch_parent = scratch_dir
        self._scratch: Optional[Path] = None
        self._weighted = False
        self.points = 0

    #: 16 bytes per point: cell index within its tile, height, weight
    _DTYPE = np.dtype([("cell", "<i4"), ("z", "<f4"), ("w", "<f8")])

    def add(self, x: ArrayLike, y: ArrayLike, z: ArrayLike,
            sigma: Optional[ArrayLike] = None) -> None:
        """Add points (any shapes, flattened); non-finite or outside points are ignored."""
        x = np.ravel(np.asarray(x, float))
        y = np.ravel(np.asarray(y, float))
        z = np.ravel(np.asarray(z, float))
        row, col = self.grid.cell_of(x, y)
        ok = (row >= 0) & np.isfinite(z)
        w = None
        if sigma is not None:
            s = np.ravel(np.broadcast_to(np.asarray(sigma, float), z.shape))
            ok &= np.isfinite(s) & (s > 0)
            w = 1.0 / np.square(s)
            self._weighted = True
        if not ok.any():
            return
        row, col, z = row[ok], col[ok], z[ok]
        ty, tx = row // self.tile, col // self.tile
        tid = ty * self.tiles_x + tx
        local = (row - ty * self.tile) * self.tile + (col - tx * self.tile)
        rec = np.empty(z.size, self._DTYPE)
        rec["cell"] = local
        rec["z"] = z
        rec["w"] = 1.0 if w is None else w[ok]
        order = np.argsort(tid, kind="stable")
        tid, rec = tid[order], rec[order]
        cuts = np.flatnonzero(np.diff(tid)) + 1
        for t, part in zip(tid[np.r_[0, cuts]], np.split(rec, cuts)):
            self._buffers.setdefault(int(t), []).append(part)
        self._buffered += z.size
        self.points += z.size
        if self._buffered > self.limit:
            self._spill()

    def _spill(self) -> None:
        if self._scratch is None:
            self._scratch = Path(tempfile.mkdtemp(prefix="photodem-grid-",
                                                  dir=self._scratch_parent))
        for t, parts in self._buffers.items():
            with open(self._scratch / f"{t}.bin", "ab") as fh:
                for p in parts:
                    fh.write(p.tobytes())
        self._buffers.clear()
        self._buffered = 0

    def _tile_points(self, t: int) -> Array:
        parts = list(self._buffers.pop(t, []))
        if self._scratch is not None and (self._scratch / f"{t}.bin").is_file():
            parts.insert(0, np.fromfile(self._scratch / f"{t}.bin", dtype=self._DTYPE))
        return np.concatenate(parts) if parts else np.empty(0, self._DTYPE)

    def covered(self) -> Array:
        """Boolean grid of the cells that hold at least one point so far (nothing consumed)."""
        g, n = self.grid, self.tile
        out = np.zeros(g.shape, bool)
        for t in range(self.tiles_x * self.tiles_y):
            parts = list(self._buffers.get(t, []))
            if self._scratch is not None and (self._scratch / f"{t}.bin").is_file():
                parts.append(np.fromfile(self._scratch / f"{t}.bin", dtype=self._DTYPE))
            if not parts:
                continue
            ty, tx = divmod(t, self.tiles_x)
            lr, lc = np.divmod(np.concatenate([p["cell"] for p in parts]), n)
            out[ty * n + lr, tx * n + lc] = True
        return out

    def reduce(self, feedback: Optional[Feedback] = None) -> Tuple[Array, Array]:
        """Per-cell (weighted) median (float32, NaN = empty) and count (uint32) of all points.

        Consumes the buffers and removes the scratch files.
        """
        feedback = ensure_feedback(feedback)
        g, n = self.grid, self.tile
        zgrid = np.full(g.shape, np.nan, np.float32)
        count = np.zeros(g.shape, np.uint32)
        try:
            n_tiles = self.tiles_x * self.tiles_y
            for t in range(n_tiles):
                feedback.progress(100.0 * t / n_tiles)
                pts = self._tile_points(t)
                if pts.size == 0:
                    continue
                ty, tx = divmod(t, self.tiles_x)
                r0, c0 = ty * n, tx * n
                th, tw = min(n, g.height - r0), min(n, g.width - c0)
                med, cnt = _median_per_cell(pts["cell"], pts["z"].astype(np.float64),
                                            pts["w"] if self._weighted else None, n * n)
                lr, lc = np.divmod(np.arange(n * n), n)
                inside = (lr < th) & (lc < tw)
                zgrid[r0:r0 + th, c0:c0 + tw] = med[inside].reshape(th, tw)
                count[r0:r0 + th, c0:c0 + tw] = cnt[inside].reshape(th, tw)
        finally:
            self.close()
        return zgrid, count

    def close(self) -> None:
        """Drop the buffers and the scratch files."""
        self._buffers.clear()
        if self._scratch is not None:
            shutil.rmtree(self._scratch, ignore_errors=True)
            self._scratch = None


def _median_per_cell(cell: Array, z: Array, w: Optional[Array], n_cells: int
                     ) -> Tuple[Array, Array]:
    """(Weighted) median and count per cell index in ``0..n_cells−1`` (NaN where empty)."""
    order = np.lexsort((z, cell))
    cell, z = cell[order], z[order]
    cnt = np.bincount(cell, minlength=n_cells)
    start = np.concatenate([[0], np.cumsum(cnt)[:-1]])
    med = np.full(n_cells, np.nan)
    has = cnt > 0
    if w is None:
        lo = start[has] + (cnt[has] - 1) // 2
        hi = start[has] + cnt[has] // 2
        med[has] = 0.5 * (z[lo] + z[hi])
    else:
        w = np.asarray(w, float)[order]
        cw = np.cumsum(w)
        total = np.bincount(cell, weights=w, minlength=n_cells)
        before = cw[start[has]] - w[start[has]]
        # first sorted point whose cumulative weight reaches half of the cell's total
        idx = np.searchsorted(cw, before + 0.5 * total[has] - 1e-12 * total[has], side="left")
        idx = np.minimum(idx, start[has] + cnt[has] - 1)
        med[has] = z[idx]
    return med.astype(np.float32), cnt.astype(np.uint32)


# -- masks -------------------------------------------------------------------------------------
def polygon_mask(geoms: Iterable[Any], grid: Grid) -> Array:
    """Boolean mask of the cells whose centre lies in any of the (shapely) polygons."""
    shapes = [(g, 1) for g in geoms if g is not None and not g.is_empty]
    if not shapes:
        return np.zeros(grid.shape, bool)
    return rasterize(shapes, out_shape=grid.shape, transform=grid.transform, fill=0,
                     dtype="uint8").astype(bool)


def line_barrier(lines: Iterable[Any], grid: Grid) -> Tuple[Array, Array]:
    """Cells touched by the lines (barrier mask) and the lines' height there (NaN if 2-D).

    Heights come from sampling each line every ¼ cell and taking the mean z per touched cell.
    """
    lines = [g for g in lines if g is not None and not g.is_empty]
    barrier = np.zeros(grid.shape, bool)
    zline = np.full(grid.shape, np.nan, np.float32)
    if not lines:
        return barrier, zline
    barrier = rasterize([(g, 1) for g in lines], out_shape=grid.shape, transform=grid.transform,
                        fill=0, all_touched=True, dtype="uint8").astype(bool)
    xs, ys, zs = [], [], []
    for g in lines:
        if not g.has_z:
            continue
        for part in getattr(g, "geoms", [g]):
            c = np.asarray(part.coords, float)
            if len(c) < 2:
                continue
            seg = np.linalg.norm(np.diff(c[:, :2], axis=0), axis=1)
            s = np.concatenate([[0.0], np.cumsum(seg)])
            t = np.arange(0.0, s[-1] + 1e-9, grid.spacing / 4.0)
            xs.append(np.interp(t, s, c[:, 0]))
            ys.append(np.interp(t, s, c[:, 1]))
            zs.append(np.interp(t, s, c[:, 2]))
    if xs:
        r, cidx = grid.cell_of(np.concatenate(xs), np.concatenate(ys))
        z = np.concatenate(zs)
        ok = (r >= 0) & np.isfinite(z)
        flat = r[ok] * grid.width + cidx[ok]
        n = grid.width * grid.height
        s = np.bincount(flat, weights=z[ok], minlength=n)
        k = np.bincount(flat, minlength=n)
        with np.errstate(invalid="ignore", divide="ignore"):
            zline = np.where(k > 0, s / np.maximum(k, 1), np.nan).reshape(grid.shape)
        zline = zline.astype(np.float32)
    return barrier, zline


# -- outliers ----------------------------------------------------------------------------------
def reject_outliers(z: Array, spacing: float, radius: float, threshold: float,
                    k: float = 3.0) -> Array:
    """Mask of the measured cells that deviate from their neighbourhood (see the module notes).

    Parameters
    ----------
    z : ndarray (h, w)
        Heights, NaN = empty.
    spacing : float
        Cell size (m).
    radius : float
        Half side of the square neighbourhood (m); at least one cell.
    threshold : float
        Smallest rejected deviation ``t`` (m) from the neighbourhood median.
    k : float
        Multiple of the robust local spread (1.4826·MAD) that a deviation must also exceed.

    Returns
    -------
    ndarray of bool
        True where a measured cell is an outlier.
    """
    return deviates_from(z, z, spacing, radius, threshold, k)


def deviates_from(z: Array, reference: Array, spacing: float, radius: float,
                  threshold: float, k: float = 3.0, where: Optional[Array] = None) -> Array:
    """Mask of the cells of ``z`` that deviate from the neighbourhood of ``reference``.

    The test of :func:`reject_outliers` (deviation from the median of the neighbourhood
    larger than ``max(threshold, k·1.4826·MAD)``) with the median and MAD taken from another
    grid, e.g. candidate heights checked against the heights one trusts more.

    Parameters
    ----------
    z : ndarray (h, w)
        Heights to test, NaN = empty (never rejected).
    reference : ndarray (h, w)
        Heights of the neighbourhood, NaN = empty; empty cells take the nearest height.
    spacing, radius, threshold, k : float
        As :func:`reject_outliers`.
    where : ndarray of bool (h, w), optional
        Test only these cells (the others are returned False). A few scattered cells are
        tested from their own windows, with the same result as over the whole grid.

    Returns
    -------
    ndarray of bool
        True where a cell of ``z`` is an outlier; all False without reference heights.
    """
    from scipy import ndimage  # lazy: keeps photodem list fast

    z = np.asarray(z, np.float32)
    valid = np.isfinite(z) if where is None else np.isfinite(z) & where
    rf = nearest_filled(reference)
    if radius <= 0 or not valid.any() or rf is None:
        return np.zeros(z.shape, bool)
    half = window_half(radius, spacing)
    size = 2 * half + 1
    # the medians the tested cells' MADs read: within ``half`` of them
    need = (ndimage.maximum_filter(valid.view(np.uint8), size=size, mode="constant") > 0
            if where is not None else None)
    if need is not None and need.mean() < _SPARSE_SHARE:
        med = np.full(z.shape, np.nan, np.float32)
        med[need] = _window_medians(rf, *np.nonzero(need), half)
        rows, cols = np.nonzero(valid)
        mad = np.zeros(z.shape, np.float32)
        mad[valid] = _window_medians(np.abs(rf - med), rows, cols, half)
    else:
        med = ndimage.median_filter(rf, size=size, mode="nearest")
        mad = ndimage.median_filter(np.abs(rf - med), size=size, mode="nearest")
    with np.errstate(invalid="ignore"):
        return valid & (np.abs(z - med) > np.maximum(float(threshold), k * 1.4826 * mad))


#: Below this share of the grid in reach of the tested cells :func:`deviates_from` takes the
#: medians window by window (2.4 µs a cell against 1.5 µs for ``median_filter``'s whole grid,
#: 11 × 11 windows).
_SPARSE_SHARE = 0.5
#: Window values gathered at a time by :func:`_window_medians` (4 bytes each).
_MEDIAN_VALUES = 2_500_000


def window_half(radius: float, spacing: float) -> int:
    """Half side (cells, at least one) of the square neighbourhood of :func:`deviates_from`."""
    return max(1, int(radius / spacing + 0.5))


def nearest_filled(reference: Array) -> Optional[Array]:
    """``reference`` (float32) with each empty cell at the nearest finite height; None with
    fewer than three finite heights."""
    from scipy import ndimage  # lazy: keeps photodem list fast

    ref = np.asarray(reference, np.float32)
    have = np.isfinite(ref)
    if have.sum() < 3:
        return None
    if have.all():
        return ref
    _, (nr, nc) = ndimage.distance_transform_edt(~have, return_indices=True)
    return ref[nr, nc]


def _window_medians(a: Array, rows: Array, cols: Array, half: int) -> Array:
    """Medians of the ``(2·half + 1)²`` windows of ``a`` centred on the cells ``rows, cols``,
    the edge cells repeated beyond the border (as ``ndimage.median_filter``'s ``nearest``)."""
    h, w = a.shape
    off = np.arange(-half, half + 1)
    out = np.empty(rows.size, a.dtype)
    chunk = max(1, _MEDIAN_VALUES // off.size ** 2)
    for s in range(0, rows.size, chunk):
        r = np.clip(rows[s:s + chunk, None, None] + off[None, :, None], 0, h - 1)
        c = np.clip(cols[s:s + chunk, None, None] + off[None, None, :], 0, w - 1)
        out[s:s + chunk] = np.median(a[r, c].reshape(r.shape[0], -1), axis=1)
    return out


# -- gap filling -------------------------------------------------------------------------------
def fill_gaps(z: Array, spacing: float, max_gap: float, domain: Optional[Array] = None,
              barrier: Optional[Array] = None, barrier_z: Optional[Array] = None
              ) -> Tuple[Array, Array]:
    """Fill small gaps of a grid by membrane interpolation that does not cross barriers.

    Parameters
    ----------
    z : ndarray (h, w)
        Heights, NaN = empty.
    spacing : float
        Cell size (m).
    max_gap : float
        Largest inscribed gap diameter (m) that is filled; 0 = no filling.
    domain : ndarray of bool, optional
        Cells that may hold heights (False: excluded / outside the boundary → NaN).
    barrier : ndarray of bool, optional
        Breakline cells: no interpolation across them.
    barrier_z : ndarray, optional
        Breakline heights for empty barrier cells (NaN = use the nearest filled height).

    Returns
    -------
    (filled z float32, mask of the cells that were filled)
    """
    from scipy import ndimage, sparse  # lazy: keeps photodem list fast
    from scipy.sparse.linalg import spsolve  # lazy: keeps photodem list fast

    z = np.array(z, dtype=np.float64)
    h, w = z.shape
    domain = np.ones((h, w), bool) if domain is None else np.asarray(domain, bool)
    barrier = np.zeros((h, w), bool) if barrier is None else np.asarray(barrier, bool) & domain
    z[~domain] = np.nan
    valid = np.isfinite(z)
    filled = np.zeros((h, w), bool)
    if max_gap <= 0 or valid.all() or not valid.any():
        return z.astype(np.float32), filled
    hole = ~valid & domain
    # gap size: distance of each empty cell to the nearest measured cell (barriers ignored)
    dist = ndimage.distance_transform_edt(~valid)
    labels, n = ndimage.label(hole)
    if n == 0:
        return z.astype(np.float32), filled
    radius = np.asarray(ndimage.maximum(dist, labels, index=np.arange(1, n + 1)))
    small = np.concatenate([[False], 2.0 * radius * spacing <= max_gap + 1e-9])
    target = small[labels] & ~barrier
    # keep only target cells connected to a measured cell without crossing a barrier
    tl, tn = ndimage.label(target)
    if tn:
        near = ndimage.binary_dilation(valid & ~barrier) & target
        reach = np.concatenate([[False], np.asarray(ndimage.maximum(
            near, tl, index=np.arange(1, tn + 1))) > 0])
        target &= reach[tl]
    idx = np.full((h, w), -1, np.int64)
    ii = np.flatnonzero(target)
    idx.flat[ii] = np.arange(ii.size)
    if ii.size:
        rows, cols = np.divmod(ii, w)
        diag = np.zeros(ii.size)
        rhs = np.zeros(ii.size)
        ai, aj = [], []
        for dr, dc in ((-1, 0), (1, 0), (0, -1), (0, 1)):
            nr, nc = rows + dr, cols + dc
            ok = (nr >= 0) & (nr < h) & (nc >= 0) & (nc < w)
            nr_c, nc_c = np.clip(nr, 0, h - 1), np.clip(nc, 0, w - 1)
            ok &= ~barrier[nr_c, nc_c] & domain[nr_c, nc_c]
            nb_valid = ok & valid[nr_c, nc_c]
            nb_unknown = ok & (idx[nr_c, nc_c] >= 0)
            diag += nb_valid | nb_unknown
            rhs += np.where(nb_valid, z[nr_c, nc_c], 0.0)
            ai.append(np.flatnonzero(nb_unknown))
            aj.append(idx[nr_c, nc_c][nb_unknown])
        ai_c, aj_c = np.concatenate(ai), np.concatenate(aj)
        A = sparse.csr_matrix((np.concatenate([diag, -np.ones(ai_c.size)]),
                               (np.concatenate([np.arange(ii.size), ai_c]),
                                np.concatenate([np.arange(ii.size), aj_c]))),
                              shape=(ii.size, ii.size))
        sol = spsolve(A.tocsc(), rhs)
        z.flat[ii] = sol
        filled.flat[ii] = True
    # empty barrier cells inside small gaps: the breakline's height, else the nearest height
    bcells = barrier & small[labels] & ~valid
    if bcells.any():
        if barrier_z is not None:
            bz = np.asarray(barrier_z, float)
            use = bcells & np.isfinite(bz)
            z[use] = bz[use]
            filled |= use
            bcells &= ~use
        if bcells.any():
            have = np.isfinite(z) & ~bcells
            if have.any():
                _, (nr, nc) = ndimage.distance_transform_edt(~have, return_indices=True)
                z[bcells] = z[nr[bcells], nc[bcells]]
                filled |= bcells & np.isfinite(z)
    return z.astype(np.float32), filled


# -- one call ----------------------------------------------------------------------------------
@dataclass
class GridResult:
    """A gridded DSM: heights (float32, NaN), point count per cell, filled-cell mask, grid."""

    z: Array
    count: Array
    filled: Array
    grid: Grid

    @property
    def transform(self) -> Affine:
        return self.grid.transform


def finish_grid(z: Array, count: Array, grid: Grid, max_gap: float = 0.0,
                exclusions: Sequence[Any] = (), boundary: Sequence[Any] = (),
                breaklines: Sequence[Any] = (), outlier_radius: float = 0.0,
                outlier_threshold: float = 0.0, outlier_k: float = 3.0) -> GridResult:
    """Masks (exclusions → NaN, outside the boundary polygons → NaN), outliers, gap filling.

    ``outlier_radius`` (m, 0 = off), ``outlier_threshold`` (m) and ``outlier_k``: see
    :func:`reject_outliers`; rejected cells get count 0 and are gaps.
    """
    domain = ~polygon_mask(exclusions, grid)
    if len(boundary):
        domain &= polygon_mask(boundary, grid)
    barrier, bz = line_barrier(breaklines, grid)
    z = np.where(domain, z, np.nan).astype(np.float32)
    count = np.where(domain, count, 0).astype(np.uint32)
    if outlier_radius > 0:
        bad = reject_outliers(z, grid.spacing, outlier_radius, outlier_threshold, outlier_k)
        z[bad] = np.nan
        count[bad] = 0
    zf, filled = fill_gaps(z, grid.spacing, max_gap, domain, barrier, bz)
    return GridResult(zf, count, filled, grid)


def grid_points(x: ArrayLike, y: ArrayLike, z: ArrayLike, spacing: float,
                bounds: Optional[Tuple[float, float, float, float]] = None,
                sigma: Optional[ArrayLike] = None, max_gap: float = 0.0,
                exclusions: Sequence[Any] = (), boundary: Sequence[Any] = (),
                breaklines: Sequence[Any] = ()) -> GridResult:
    """In-memory points → DSM grid (median per cell, small gaps filled; see the module notes).

    Parameters
    ----------
    x, y, z : array_like
        Point coordinates (m, project CRS).
    spacing : float
        Cell size (m).
    bounds : (xmin, ymin, xmax, ymax), optional
        Grid extent; default the points' extent.
    sigma : array_like, optional
        σ per point (m): weighted median with ``w = 1/σ²``.
    max_gap : float
        Largest gap (inscribed diameter, m) that is interpolated.
    exclusions, boundary, breaklines : sequences of shapely geometries
        Excluded polygons (NaN), measuring-area polygons (NaN outside; none = everywhere),
        breaklines (barriers of the interpolation).
    """
    x = np.ravel(np.asarray(x, float))
    y = np.ravel(np.asarray(y, float))
    if bounds is None:
        ok = np.isfinite(x) & np.isfinite(y)
        if not ok.any():
            raise InputError("No points to grid.")
        bounds = (x[ok].min(), y[ok].min(), x[ok].max() + 1e-9, y[ok].max() + 1e-9)
    grid = Grid.from_bounds(*bounds, spacing=spacing)
    acc = GridAccumulator(grid)
    acc.add(x, y, z, sigma)
    zg, count = acc.reduce()
    return finish_grid(zg, count, grid, max_gap, exclusions, boundary, breaklines)


def write_grid(path: PathLike, z: Array, grid: Grid, crs: Any = None,
               overviews: bool = True) -> Path:
    """Write a grid as a tiled, compressed GeoTIFF with overviews (float → NaN nodata)."""
    return write_raster(path, z, transform=grid.transform, crs=crs, overviews=overviews)


__all__ = ["Grid", "GridAccumulator", "GridResult", "deviates_from", "fill_gaps", "finish_grid",
           "grid_points", "line_barrier", "nearest_filled", "polygon_mask", "reject_outliers",
           "window_half", "write_grid"]
