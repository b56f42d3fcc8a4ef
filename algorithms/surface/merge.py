r"""Merge model DSMs into one DSM, window by window, with seam statistics in the overlaps.

Grid
    All inputs are brought onto one north-up grid in the CRS of the first input that has one:
    the union of the inputs' extents (transformed to that CRS) at the finest input cell size,
    or at ``spacing`` when given. Without ``spacing`` the grid is aligned to the finest input's
    cell corners, so inputs on that grid are copied without resampling; otherwise (other
    cell size, origin or CRS) an input is resampled bilinearly (GDAL warper, NaN ignored),
    except on cells that straddle a step of more than ``step`` (a wall), which take the
    nearest input cell (:func:`.merge_steps.step_aware`): bilinear weights would put them
    between roof and ground.

Merge per cell, over the inputs :math:`k` with a height :math:`z_k` there
    * ``median``: :math:`\mathrm{median}_k\, z_k` (mean of the two middle values for an even
      count) — robust against one blundering model where three or more overlap;
    * ``mean``: :math:`\frac{1}{n}\sum_k z_k`;
    * ``best_sigma``: the height of the input with the smallest :math:`\sigma_k` at that cell.
      σ comes from a second band of the input, or from a sibling raster ``<name>_sigma.tif``
      or ``sigma.tif`` in the input's folder. Cells where no input with σ has a height take the
      median of the inputs without σ (so without any σ at all this is the median).

Walls (issue 19)
    Where the heights of a cell spread over more than ``step`` (default 1 m), the inputs see
    different surfaces there (roof and ground at a wall placed differently, a blunder). The
    median of two and the mean of any number would put the cell between them; instead the
    candidates are split into populations at gaps > ``step`` and the largest population is
    combined (ties: the one closest to the pooled median of the 5 × 5 neighbourhood, then the
    upper one): :func:`.merge_steps.combine_keeping_steps`. Cells whose inputs agree within
    ``step`` are merged as above; ``step = 0`` turns this off (plain median / mean).

Seams
    For every pair of inputs :math:`(a, b)`, :math:`a < b` in input order, whose extents
    overlap: statistics of :math:`\Delta h = z_a - z_b` over the cells where both have a height
    (count, mean, median, std, RMS, NMAD, min, max: :func:`..quality.stats.difference_stats`,
    fed window by window through :class:`..quality.stats.DifferenceAccumulator`). Median and
    NMAD are exact up to 64 MB of differences in all (``exact: true``); beyond that they come
    from 0.5 mm histograms (within 0.25 mm, NMAD within 0.75 mm); moments are always exact.

Memory
    The output is processed in windows of ``tile`` × ``tile`` cells; a window holds one
    float32 layer per input that touches it (plus σ), so the peak memory is
    ``≈ 8 · tile² · (inputs per window)`` bytes plus the seam statistics (≤ 64 MB),
    independent of the mosaic size (3 inputs, 4000 × 4000 cells: +150 MB peak, 2.2 Mcells/s).
"""

from __future__ import annotations

import csv
import json
import math
import warnings
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, Iterable, Iterator, List, Optional, Sequence, Tuple, Union

import numpy as np
import rasterio
from affine import Affine
from numpy.typing import NDArray
from rasterio.enums import Resampling
from rasterio.warp import calculate_default_transform, reproject, transform_bounds
from rasterio.windows import Window

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from ..quality.stats import DifferenceAccumulator
from ..raster.io import atomic_output, cog_output, gtiff_profile, open_image, overview_factors
from ..raster.tiled_dask import check_scheduler, map_tiles
from .merge_steps import REF_RADIUS, STEP_M, combine_keeping_steps, step_aware

PathLike = Union[str, Path]
Array = NDArray[Any]

#: Merge modes.
MODES = ("median", "mean", "best_sigma")
#: Statistics of a seam copied into the report (all from difference_stats).
SEAM_KEYS = ("count", "mean", "median", "std", "rms", "nmad", "min", "max")


@dataclass
class _Input:
    path: Path
    crs: Any
    transform: Affine
    width: int
    height: int
    bounds: Tuple[float, float, float, float]  # in the target CRS
    sigma_path: Optional[Path]
    sigma_band: bool
    aligned: Optional[Tuple[int, int]] = None  # (row, col) offset on the output grid


def _sigma_source(path: Path, bands: int) -> Tuple[Optional[Path], bool]:
    """Where the σ of a DSM is: its band 2, ``<stem>_sigma.tif`` or ``sigma.tif`` beside it."""
    if bands >= 2:
        return None, True
    for cand in (path.with_name(f"{path.stem}_sigma{path.suffix}"),
                 path.with_name("sigma.tif")):
        if cand.is_file() and cand.resolve() != path.resolve():
            return cand, False
    return None, False


def _open_inputs(paths: Sequence[PathLike]) -> Tuple[List[_Input], Any]:
    if not paths:
        raise InputError("No input DSMs given; give at least one raster.")
    infos = []
    for p in paths:
        p = Path(p)
        if not p.is_file():
            raise InputError(f"Input DSM '{p}' does not exist.")
        try:
            with rasterio.open(p) as src:
                infos.append((p, src.crs, src.transform, src.width, src.height, src.count,
                              tuple(src.bounds)))
        except rasterio.errors.RasterioIOError as exc:
            raise InputError(f"Cannot read the input DSM '{p.name}': {exc}") from exc
    crss = [i[1] for i in infos]
    known = [c for c in crss if c]
    if known and len(known) < len(crss):
        missing = [i[0].name for i in infos if not i[1]]
        raise InputError(f"{', '.join(missing)} has no CRS while other inputs have one, so it "
                         "cannot be reprojected; assign its CRS (e.g. gdal_edit.py -a_srs) "
                         "or merge only inputs without CRS.")
    target = known[0] if known else None
    out = []
    for p, crs, tr, w, h, bands, b in infos:
        if abs(tr.b) > 0 or abs(tr.d) > 0:
            raise InputError(f"'{p.name}' is a rotated raster; warp it north-up first.")
        if target is not None and crs != target:
            b = tuple(transform_bounds(crs, target, *b, densify_pts=21))
        sp, sb = _sigma_source(p, bands)
        out.append(_Input(p, crs, tr, w, h, b, sp, sb))  # type: ignore[arg-type]
    return out, target


def _grid(inputs: List[_Input], target: Any, spacing: Optional[float]
          ) -> Tuple[Affine, int, int, float]:
    """Transform, width, height, cell size of the output grid (see the module notes)."""
    res = []
    for i in inputs:
        if target is None or i.crs == target:
            res.append(min(abs(i.transform.a), abs(i.transform.e)))
        else:
            t, _, _ = calculate_default_transform(i.crs, target, i.width, i.height,
                                                  *_native_bounds(i))
            res.append(min(abs(t.a), abs(t.e)))
    xmin = min(i.bounds[0] for i in inputs)
    ymin = min(i.bounds[1] for i in inputs)
    xmax = max(i.bounds[2] for i in inputs)
    ymax = max(i.bounds[3] for i in inputs)
    if spacing is None:
        k = int(np.argmin(res))
        s = float(res[k])
        ref = inputs[k]
        if target is None or ref.crs == target:
            ox, oy = ref.transform.c, ref.transform.f  # align to the finest input's corners
        else:
            ox, oy = 0.0, 0.0
    else:
        if not spacing > 0:
            raise InputError(f"The spacing must be positive, got {spacing}.")
        s, ox, oy = float(spacing), 0.0, 0.0
    eps = 1e-6 * s
    x0 = ox + math.floor((xmin - ox) / s + 1e-9) * s
    y0 = oy + math.ceil((ymax - oy) / s - 1e-9) * s
    width = max(1, math.ceil((xmax - x0) / s - eps / s))
    height = max(1, math.ceil((y0 - ymin) / s - eps / s))
    if width * height > 2 ** 34:
        raise InputError(f"The merged grid would have {width} × {height} cells; give a larger "
                         "spacing.")
    return Affine(s, 0.0, x0, 0.0, -s, y0), width, height, s


def _native_bounds(i: _Input) -> Tuple[float, float, float, float]:
    t = i.transform
    xs = (t.c, t.c + t.a * i.width)
    ys = (t.f, t.f + t.e * i.height)
    return min(xs), min(ys), max(xs), max(ys)


def _aligned_offset(i: _Input, target: Any, transform: Affine) -> Optional[Tuple[int, int]]:
    """(row, col) of the input's first cell on the output grid if no resampling is needed."""
    t = i.transform
    if (target is not None and i.crs != target) or t.e > 0:
        return None
    s = transform.a
    if abs(t.a - s) > 1e-9 * s or abs(-t.e - s) > 1e-9 * s:
        return None
    col = (t.c - transform.c) / s
    row = (transform.f - t.f) / s
    if abs(col - round(col)) > 1e-6 or abs(row - round(row)) > 1e-6:
        return None
    return round(row), round(col)


def _read_window(src: Any, band: int, info: _Input, target: Any, win_transform: Affine,
                 shape: Tuple[int, int], r0: int, c0: int, step: float = 0.0) -> Array:
    """Heights of one input on one output window (float32, NaN where it has none).

    A resampled input takes the nearest cell where bilinear weights straddle a step of more
    than ``step`` (:func:`.merge_steps.step_aware`; 0 = bilinear everywhere).
    """
    h, w = shape
    out = np.full(shape, np.nan, np.float32)
    if info.aligned is not None:
        ar, ac = info.aligned
        rr0, rr1 = max(r0, ar), min(r0 + h, ar + info.height)
        cc0, cc1 = max(c0, ac), min(c0 + w, ac + info.width)
        if rr1 <= rr0 or cc1 <= cc0:
            return out
        win = Window(cc0 - ac, rr0 - ar, cc1 - cc0, rr1 - rr0)
        data = src.read(band, window=win, masked=True)
        vals = np.ma.filled(data.astype(np.float32), np.nan)
        out[rr0 - r0:rr1 - r0, cc0 - c0:cc1 - c0] = vals
    else:
        out = _resampled(src, band, target, win_transform, shape, Resampling.bilinear)
        if step > 0:
            near = _resampled(src, band, target, win_transform, shape, Resampling.nearest)
            out = step_aware(out, near, step)
    out[~np.isfinite(out)] = np.nan
    return out


def _resampled(src: Any, band: int, target: Any, win_transform: Affine,
               shape: Tuple[int, int], how: Any) -> Array:
    """One band of ``src`` warped onto a window of the output grid (float32, NaN = none)."""
    out = np.full(shape, np.nan, np.float32)
    nodata = src.nodatavals[band - 1]
    reproject(
        source=rasterio.band(src, band), destination=out,
        src_transform=src.transform, src_crs=src.crs or target,
        src_nodata=nodata if nodata is not None else np.nan,
        dst_transform=win_transform, dst_crs=target or src.crs, dst_nodata=np.nan,
        resampling=how, init_dest_nodata=True)
    return out


def _combine(stack: Array, mode: str, sigma: Optional[Array], step: float = 0.0,
             halo: int = 0) -> Array:
    """Merged heights of a (k, h, w) stack (NaN = no height); see the module notes.

    ``stack`` and ``sigma`` cover the window plus ``halo`` cells on every side (context of
    the step rule); the result is the window's core.
    """
    h, w = stack.shape[1] - 2 * halo, stack.shape[2] - 2 * halo
    core = (slice(None), slice(halo, halo + h), slice(halo, halo + w))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN cells stay NaN
        if mode == "mean":
            plain = np.nanmean(stack[core], axis=0).astype(np.float32)
            return combine_keeping_steps(stack, "mean", plain, step, halo)
        med = np.nanmedian(stack[core], axis=0).astype(np.float32)
        if mode == "median" or sigma is None:
            return combine_keeping_steps(stack, "median", med, step, halo)
        st, sg = stack[core], sigma[core]
        has_sigma = np.isfinite(sg) & np.isfinite(st)
        s = np.where(has_sigma, sg, np.inf)
        best = np.argmin(s, axis=0)
        zbest = np.take_along_axis(st, best[None], axis=0)[0]
        any_sigma = has_sigma.any(axis=0)
        # inputs without σ: median of those (walls kept as for the median)
        rest = np.where(np.isfinite(sigma), np.nan, stack)
        med_rest = np.nanmedian(rest[core], axis=0).astype(np.float32)
        med_rest = combine_keeping_steps(rest, "median", med_rest, step, halo)
        return np.where(any_sigma, zbest, med_rest).astype(np.float32)


def _profile(width: int, height: int, dtype: str, transform: Affine, crs: Any,
             nodata: Optional[float]) -> Dict[str, Any]:
    extra = {"predictor": 3} if dtype.startswith("float") else {}
    return gtiff_profile(width, height, 1, dtype, crs, nodata=nodata, transform=transform,
                         **extra)


def _overviews(dst: Any, width: int, height: int, resampling: Any) -> None:
    factors = overview_factors(width, height)
    if factors:
        dst.build_overviews(factors, resampling)


def sibling_paths(output: PathLike) -> Dict[str, Path]:
    """Files written beside a merged DSM ``output``: count raster, seam JSON and CSV."""
    output = Path(output)
    stem = output.stem
    return {"dsm": output, "count": output.with_name(f"{stem}_count.tif"),
            "report": output.with_name(f"{stem}_seams.json"),
            "csv": output.with_name(f"{stem}_seams.csv")}


def _overlap(a: Tuple[float, ...], b: Tuple[float, ...]) -> bool:
    """Do two (xmin, ymin, xmax, ymax) extents overlap (with a positive area)?"""
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def _checked_inputs(inputs: Sequence[PathLike], output: PathLike, mode: str,
                    feedback: Feedback) -> Tuple[List[_Input], Any, Dict[str, Path]]:
    """The opened inputs, the target CRS and the output files, after the up-front checks."""
    if mode not in MODES:
        raise InputError(f"Unknown merge mode '{mode}'; use one of {', '.join(MODES)}.")
    out_paths = sibling_paths(output)
    if out_paths["dsm"].suffix.lower() not in (".tif", ".tiff"):
        raise InputError(f"The output '{output}' must be a GeoTIFF (.tif).")
    infos, target = _open_inputs(inputs)
    if len({i.path.resolve() for i in infos}) < len(infos):
        feedback.warning("The same DSM is given more than once; it counts once per mention.")
    if out_paths["dsm"].resolve() in {i.path.resolve() for i in infos}:
        raise InputError("The output would overwrite an input; choose another output name.")
    return infos, target, out_paths


def _count_sigma(infos: List[_Input], mode: str, feedback: Feedback) -> int:
    """Inputs with σ; warns when ``best_sigma`` lacks σ for some or all inputs."""
    n_sigma = sum(1 for i in infos if i.sigma_band or i.sigma_path is not None)
    if mode == "best_sigma" and n_sigma == 0:
        feedback.warning("best_sigma: no input has σ (band 2 or a sibling sigma.tif); the "
                         "median is used.")
    elif mode == "best_sigma" and n_sigma < len(infos):
        feedback.warning(f"best_sigma: {len(infos) - n_sigma} input(s) have no σ; they are used "
                         "(as their median) only where no input with σ has a height.")
    return n_sigma


@dataclass
class _MergeSources:
    """The open inputs (and σ rasters) of a merge, with what the windows need of them."""

    infos: List[_Input]
    srcs: List[Any]
    sig_srcs: List[Any]
    target: Any
    mode: str
    n_sigma: int
    pairs: List[Tuple[int, int]]
    step: float = STEP_M

    def window(self, transform: Affine, s: float, r0: int, c0: int, h: int, w: int
               ) -> Tuple[Array, Array, Dict[Tuple[int, int], Array]]:
        """Merged heights, input count and Δh of every overlapping pair on one window.

        The inputs are read with a halo of :data:`.merge_steps.REF_RADIUS` cells (context
        of the step rule at the window's border), so windows join without seams.
        """
        g = REF_RADIUS if self.step > 0 else 0
        rh, ch, hh, wh = r0 - g, c0 - g, h + 2 * g, w + 2 * g
        wt = transform * Affine.translation(ch, rh)
        wb = (wt.c, wt.f - hh * s, wt.c + wh * s, wt.f)
        idx = [j for j, i in enumerate(self.infos) if _overlap(i.bounds, wb)]
        if not idx:
            return np.full((h, w), np.nan, np.float32), np.zeros((h, w), np.uint16), {}
        layers = np.stack([_read_window(self.srcs[j], 1, self.infos[j], self.target, wt,
                                        (hh, wh), rh, ch, self.step) for j in idx])
        sig = None
        if self.mode == "best_sigma" and self.n_sigma:
            sig = np.stack([self._sigma(j, wt, (hh, wh), rh, ch) for j in idx])
        zc = _combine(layers, self.mode, sig, self.step, g)
        layers = layers[:, g:g + h, g:g + w]
        cnt = np.isfinite(layers).sum(axis=0).astype(np.uint16)
        pos = {j: n for n, j in enumerate(idx)}
        diffs = {(a, b): layers[pos[a]] - layers[pos[b]] for a, b in self.pairs
                 if a in pos and b in pos}
        return zc, cnt, diffs

    def _sigma(self, j: int, wt: Affine, shape: Tuple[int, int], r0: int, c0: int) -> Array:
        """σ of input ``j`` on the window (NaN when it has none)."""
        info = self.infos[j]
        if info.sigma_band:
            return _read_window(self.srcs[j], 2, info, self.target, wt, shape, r0, c0)
        if self.sig_srcs[j] is not None:
            return _read_window(self.sig_srcs[j], 1, info, self.target, wt, shape, r0, c0)
        return np.full(shape, np.nan, np.float32)


def _open_sources(stack: ExitStack, infos: List[_Input], target: Any, mode: str,
                  n_sigma: int, pairs: List[Tuple[int, int]], step: float) -> _MergeSources:
    """Open every input and, for ``best_sigma``, its sibling σ raster (checked grid)."""
    use_sigma = mode == "best_sigma"
    srcs = [stack.enter_context(rasterio.open(i.path)) for i in infos]
    sig_srcs = [stack.enter_context(rasterio.open(i.sigma_path))
                if (use_sigma and i.sigma_path is not None) else None for i in infos]
    for i, ss in zip(infos, sig_srcs):  # a sibling σ must be on its DSM's grid
        if ss is not None and (ss.transform != i.transform or ss.width != i.width
                               or ss.height != i.height):
            raise InputError(f"The σ raster '{i.sigma_path}' does not have the grid of "
                             f"'{i.path.name}'; give σ on the DSM's grid.")
    return _MergeSources(infos, srcs, sig_srcs, target, mode, n_sigma, pairs, step)


@dataclass
class _MergeJob:
    """What a window task on a Dask worker opens itself (picklable): inputs and the grid."""

    infos: List[_Input]
    target: Any
    mode: str
    n_sigma: int
    pairs: List[Tuple[int, int]]
    step: float
    transform: Affine
    spacing: float


def _merge_window_task(job: _MergeJob, win: Tuple[int, int, int, int]
                       ) -> Tuple[Array, Array, Dict[Tuple[int, int], Array]]:
    """:meth:`_MergeSources.window` of ``win`` = (row, col, h, w), inputs opened here."""
    with ExitStack() as stack:
        sources = _open_sources(stack, job.infos, job.target, job.mode, job.n_sigma, job.pairs,
                                job.step)
        return sources.window(job.transform, job.spacing, *win)


def _merged_windows(sources: _MergeSources, job: _MergeJob, shape: Tuple[int, int], tile: int,
                    scheduler: str, feedback: Feedback) -> Iterator[Tuple[Any, ...]]:
    """``(window, heights, count, pair differences)`` of every output window, in order:
    here, or as Dask tasks on ``scheduler`` (:mod:`..raster.tiled_dask`; memory per task ≈
    8 · (tile + 2·halo)² · inputs bytes plus tile² · 4 bytes per overlapping pair)."""
    height, width = shape
    wins = [(r, c, min(tile, height - r), min(tile, width - c))
            for r in range(0, height, tile) for c in range(0, width, tile)]
    if scheduler:
        results: Iterable[Tuple[int, Any]] = map_tiles(_merge_window_task, wins, (job,),
                                                       scheduler, feedback.step(0.0, 95.0))
    else:
        results = ((i, sources.window(job.transform, job.spacing, *win))
                   for i, win in enumerate(wins))
    for i, (zc, cnt, diffs) in results:
        feedback.progress(95.0 * i / len(wins))
        yield (wins[i], zc, cnt, diffs)


def _seam_records(accs: Dict[Tuple[int, int], Any], infos: List[_Input]) -> List[Dict[str, Any]]:
    """One dict per pair of inputs with common heights: names, indices, Δh statistics."""
    seams = []
    for (a, b), acc in accs.items():
        full = acc.result()
        st = full["stats"]
        if not st["count"]:
            continue  # extents overlap but no common heights
        seams.append({"a": infos[a].path.name, "b": infos[b].path.name,
                      "a_index": a, "b_index": b,
                      **{key: st[key] for key in SEAM_KEYS},
                      "exact": bool(full["precision"]["exact"])})
    return seams


def _write_seam_report(tmp_json: PathLike, tmp_csv: PathLike, result: Dict[str, Any],
                       infos: List[_Input], crs_out: Any, transform: Affine,
                       out_paths: Dict[str, Path]) -> None:
    """``<stem>_seams.json`` (the result without paths, plus the grid) and the seam CSV."""
    report = {**{k: v for k, v in result.items()
                 if k not in ("dsm", "count", "report", "csv")},
              "inputs": [i.path.name for i in infos],
              "crs": crs_out.to_wkt() if crs_out is not None else None,
              "transform": list(transform)[:6],
              "files": {k: p.name for k, p in out_paths.items()},
              "difference": "a − b (heights of input a minus input b)"}
    Path(tmp_json).write_text(json.dumps(report, indent=2, allow_nan=False) + "\n",
                              encoding="utf-8")
    with open(tmp_csv, "w", newline="", encoding="utf-8") as fh:
        wr = csv.writer(fh)
        wr.writerow(["a", "b", *SEAM_KEYS])
        for sm in result["seams"]:
            wr.writerow([sm["a"], sm["b"], *("" if sm[key] is None else
                                             (f"{sm[key]:.6f}" if key != "count"
                                              else sm[key]) for key in SEAM_KEYS)])


def merge_dsms(inputs: Sequence[PathLike], output: PathLike, mode: str = "median",
               spacing: Optional[float] = None, tile: int = 512,
               feedback: Optional[Feedback] = None, step: float = STEP_M,
               scheduler: str = "") -> Dict[str, Any]:
    """Merge DSMs onto a common grid (see the module notes).

    Parameters
    ----------
    inputs : sequence of paths
        Model DSMs (float heights, nodata/NaN = no height); any extents, grids and CRSs.
    output : path
        Merged DSM GeoTIFF; ``<stem>_count.tif``, ``<stem>_seams.json`` and
        ``<stem>_seams.csv`` are written beside it.
    mode : {"median", "mean", "best_sigma"}
    spacing : float, optional
        Output cell size (units of the output CRS, m); default the finest input cell size.
    tile : int
        Side (cells) of the processing windows; bounds the memory.
    feedback : Feedback, optional
    step : float
        Height spread (m) of a cell's inputs above which they are treated as different
        surfaces (a wall) and not averaged (module notes "Walls"); 0 = plain median / mean.
    scheduler : str
        ``""`` (windows here), ``"local"`` or ``"tcp://host:port"``: the windows as Dask tasks;
        the seam statistics are still added here in window order (the same result).

    Returns
    -------
    dict
        ``dsm, count, report, csv`` (paths), ``seams`` (one dict per overlapping pair:
        ``a, b`` input names, ``a_index, b_index`` and the statistics of ``Δh = z_a − z_b``),
        ``cells, covered, coverage, spacing, width, height, mode, sigma_inputs``.
    """
    feedback = ensure_feedback(feedback)
    scheduler = check_scheduler(scheduler)
    infos, target, out_paths = _checked_inputs(inputs, output, mode, feedback)
    if not step >= 0:
        raise InputError(f"The step threshold must not be negative, got {step}.")
    transform, width, height, s = _grid(infos, target, spacing)
    gx0, gy0 = transform.c, transform.f
    gbounds = (gx0, gy0 - height * s, gx0 + width * s, gy0)
    for i in infos:
        i.aligned = _aligned_offset(i, target, transform)
    n_sigma = _count_sigma(infos, mode, feedback)
    if not any(_overlap(i.bounds, gbounds) for i in infos):
        raise InputError("No input DSM overlaps the output grid; check the inputs' extents "
                         "and CRSs.")
    pairs = [(a, b) for a in range(len(infos)) for b in range(a + 1, len(infos))
             if _overlap(infos[a].bounds, infos[b].bounds)]
    # exact order statistics up to 64 MB of differences in all, then 0.5 mm histograms
    budget = max(2 ** 20, (64 * 2 ** 20) // max(len(pairs), 1))
    accs = {p: DifferenceAccumulator(memory_budget=budget) for p in pairs}
    tile = max(16, int(tile) // 16 * 16)
    job = _MergeJob(infos, target, mode, n_sigma, pairs, step, transform, s)
    covered = 0
    crs_out = target
    with ExitStack() as stack:
        sources = _open_sources(stack, infos, target, mode, n_sigma, pairs, step)
        tmp_dsm, dsm_profile = stack.enter_context(cog_output(
            out_paths["dsm"], _profile(width, height, "float32", transform, crs_out,
                                       float("nan"))))
        tmp_cnt, cnt_profile = stack.enter_context(cog_output(
            out_paths["count"], _profile(width, height, "uint16", transform, crs_out, None)))
        tmp_json = stack.enter_context(atomic_output(out_paths["report"]))
        tmp_csv = stack.enter_context(atomic_output(out_paths["csv"]))
        with open_image(tmp_dsm, "w", **dsm_profile) as dst, \
                open_image(tmp_cnt, "w", **cnt_profile) as cnt_dst:
            for (r0, c0, h, w), zc, cnt, diffs in _merged_windows(
                    sources, job, (height, width), tile, scheduler, feedback):
                for pair, d in diffs.items():
                    accs[pair].add(d)
                covered += int(np.isfinite(zc).sum())
                win = Window(c0, r0, w, h)
                dst.write(zc[None], window=win)
                cnt_dst.write(cnt[None], window=win)
            feedback.progress(96.0)
            _overviews(dst, width, height, Resampling.average)
            _overviews(cnt_dst, width, height, Resampling.nearest)
        if covered == 0:
            raise InputError("None of the input DSMs has a height (all cells are nodata); "
                             "check the inputs.")
        seams = _seam_records(accs, infos)
        cells = width * height
        result: Dict[str, Any] = {
            "dsm": str(out_paths["dsm"]), "count": str(out_paths["count"]),
            "report": str(out_paths["report"]), "csv": str(out_paths["csv"]),
            "seams": seams, "mode": mode, "spacing": s, "width": width, "height": height,
            "cells": cells, "covered": covered, "coverage": covered / float(cells),
            "sigma_inputs": n_sigma, "step": float(step),
        }
        _write_seam_report(tmp_json, tmp_csv, result, infos, crs_out, transform, out_paths)
        feedback.progress(100.0)
    feedback.info(f"Merged {len(infos)} DSMs ({mode}): {width} × {height} cells of {s:g}, "
                  f"{100.0 * result['coverage']:.1f} % with a height, {len(seams)} seam(s).")
    for sm in seams:
        feedback.info(f"Seam {sm['a']} − {sm['b']}: {sm['count']} cells, mean "
                      f"{sm['mean']:+.3f}, NMAD {sm['nmad']:.3f}, RMS {sm['rms']:.3f}.")
    return result


__all__ = ["MODES", "merge_dsms", "sibling_paths"]
