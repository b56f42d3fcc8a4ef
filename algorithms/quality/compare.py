r"""Windowed comparison of a DEM with a reference DEM (the engine of ``dem_compare``).

The comparison grid is the **reference grid restricted to the common area**: the DEM is
interpolated onto the reference cells (bilinear, reprojected with GDAL through a ``WarpedVRT``
when the CRS or the grid differ — seed-000 §5.2 "one DEM is the reference; the other is
interpolated onto its grid"), and :math:`\Delta h = h_{DEM} - h_{ref}` at each cell. Nothing is
read whole: the grid is processed in windows of ``window_size`` cells (the reference with a
1-cell margin for its slope), and the statistics are accumulated by
:class:`~.stats.DifferenceAccumulator` within ``memory_budget``.

With ``coregister=True`` the shift of the DEM is estimated first (:func:`~.coregister.nuth_kaab`)
on the stable cells of a grid of at most ``coreg_max_cells`` cells (the reference grid averaged by
an integer factor when larger), and the comparison then samples the DEM at the shifted positions
(:math:`h'(\mathbf p) = h(\mathbf p - \mathbf d) + d_z`, the destination grid of the warp moved
by :math:`-\mathbf d`), so that the shift is applied exactly whatever the DEM's CRS.

Per-class statistics use class polygons (any vector format fiona reads, any CRS, attribute
``class_field``; rasterised per window, cell centres inside; later polygons win where they
overlap) or a class raster (nearest neighbour); per-slope statistics use the slope of the
reference (:data:`~.stats.SLOPE_CLASSES_DEG`).

With the reference's terrain model (``dtm``, when the reference is a DSM) every cell gets an
object class (:data:`~.objects.OBJECT_CLASSES`: object interior, object edge, open, other, from
the nDSM reference − DTM and ``object_height``, see :mod:`.objects`; the reference is read with
a margin of :func:`~.objects.mask_margin` cells so that the masks do not depend on the
windows), with statistics per object class (``per_object``). With classes or a DTM, the
**completeness** per class and per object class is counted too: of the cells with a valid
reference, the shares where the DEM is within ±0.5 m and ±1 m and the share it measures at all
(an empty DEM cell is a miss, unlike in the statistics, which only see cells both DEMs have).
"""

from __future__ import annotations

import contextlib
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Tuple, Union

import fiona
import numpy as np
import rasterio
import shapely
import shapely.geometry
import shapely.wkt
from affine import Affine
from numpy.typing import NDArray
from pyproj import CRS, Transformer
from rasterio.enums import Resampling
from rasterio.features import geometry_mask, rasterize
from rasterio.vrt import WarpedVRT
from rasterio.warp import transform_bounds
from rasterio.windows import Window, from_bounds
from shapely.geometry import shape
from shapely.ops import transform as shapely_transform

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from ..raster.io import atomic_output, gtiff_profile, open_image
from ..raster.tiled_dask import check_scheduler, map_tiles
from .class_legend import read_class_legend
from .coregister import nuth_kaab
from .objects import (
    OBJECT_CLASSES,
    OBJECT_HEIGHT,
    CompletenessAccumulator,
    mask_margin,
    object_classes,
    object_masks,
)
from .stats import SLOPE_LABELS, DifferenceAccumulator, _label_key, slope_class_index

PathLike = Union[str, Path]
Array = NDArray[np.float64]

VECTOR_SUFFIXES = {".gpkg", ".shp", ".geojson", ".json", ".kml", ".gml", ".fgb", ".sqlite"}
RASTER_SUFFIXES = {".tif", ".tiff", ".vrt", ".img", ".asc", ".nc", ".jp2", ".png"}

#: Called with (row, col, Δh) of every processing window of the comparison grid.
WindowHook = Callable[[int, int, Array], None]


# -- inputs ---------------------------------------------------------------------------------------


def _open_raster(stack: contextlib.ExitStack, path: PathLike, what: str) -> Any:
    p = Path(path)
    if not p.exists():
        raise InputError(f"The {what} '{p}' does not exist; give an existing raster file.")
    try:
        src = stack.enter_context(rasterio.open(p))
    except Exception as exc:  # rasterio raises RasterioIOError and others for unreadable files
        raise InputError(f"The {what} '{p}' cannot be read as a raster ({exc}).") from None
    if src.crs is None or not src.crs.to_wkt():
        raise InputError(f"The {what} '{p}' has no coordinate reference system; assign one "
                         "(e.g. in QGIS: Raster › Projections › Assign Projection) and retry.")
    if src.transform.b != 0 or src.transform.d != 0:
        raise InputError(f"The {what} '{p}' has a rotated geotransform; warp it to a north-up "
                         "grid first.")
    return src


def _read_window(src: Any, row: int, col: int, h: int, w: int) -> Array:
    """Band 1 of ``src``, rows ``row…row+h``, cols ``col…col+w``: float64, NaN outside/nodata."""
    out = np.full((h, w), np.nan)
    r0, c0 = max(row, 0), max(col, 0)
    r1, c1 = min(row + h, src.height), min(col + w, src.width)
    if r1 > r0 and c1 > c0:
        a = src.read(1, window=Window(c0, r0, c1 - c0, r1 - r0), masked=True)
        out[r0 - row:r1 - row, c0 - col:c1 - col] = np.ma.filled(a.astype(np.float64), np.nan)
    return out


def _vrt(src: Any, crs: Any, transform: Affine, width: int, height: int,
         resampling: Resampling) -> WarpedVRT:
    kw: Dict[str, Any] = {}
    if src.nodata is not None:
        kw["src_nodata"] = src.nodata
    return WarpedVRT(src, crs=crs, transform=transform, width=width, height=height,
                     resampling=resampling, nodata=np.nan, dtype="float64", **kw)


class _GridReader:
    """Reads a raster on (a window of) the comparison grid: directly if aligned, else warped."""

    def __init__(self, stack: contextlib.ExitStack, src: Any, crs: Any, transform: Affine,
                 width: int, height: int, resampling: Resampling,
                 shift: Tuple[float, float] = (0.0, 0.0)) -> None:
        self.src = src
        self.offset: Optional[Tuple[int, int]] = None
        t = src.transform
        if shift == (0.0, 0.0) and src.crs == crs and math.isclose(t.a, transform.a) \
                and math.isclose(t.e, transform.e):
            col, row = ~t * (transform.c, transform.f)
            if abs(col - round(col)) < 1e-6 and abs(row - round(row)) < 1e-6:
                self.offset = (round(row), round(col))
        if self.offset is None:
            dst = Affine.translation(-shift[0], -shift[1]) * transform
            self.vrt = stack.enter_context(_vrt(src, crs, dst, width, height, resampling))

    def read(self, row: int, col: int, h: int, w: int) -> Array:
        if self.offset is not None:
            return _read_window(self.src, row + self.offset[0], col + self.offset[1], h, w)
        return _read_window(self.vrt, row, col, h, w)


def _common_grid(dem: Any, ref: Any) -> Tuple[Window, Affine]:
    """Window of the reference covering the common area (whole cells), and its transform."""
    try:
        b = transform_bounds(dem.crs, ref.crs, *dem.bounds, densify_pts=21)
    except Exception as exc:
        raise InputError(f"The DEM's CRS cannot be transformed to the reference CRS ({exc}).") \
            from None
    rb = ref.bounds
    left, bottom = max(b[0], rb.left), max(b[1], rb.bottom)
    right, top = min(b[2], rb.right), min(b[3], rb.top)
    if not (np.all(np.isfinite([left, bottom, right, top])) and right > left and top > bottom):
        raise InputError("The DEM and the reference DEM do not overlap; check that both cover "
                         "the same area and carry the right CRS.")
    win = from_bounds(left, bottom, right, top, transform=ref.transform)
    c0 = max(math.floor(win.col_off + 1e-6), 0)
    r0 = max(math.floor(win.row_off + 1e-6), 0)
    c1 = min(math.ceil(win.col_off + win.width - 1e-6), ref.width)
    r1 = min(math.ceil(win.row_off + win.height - 1e-6), ref.height)
    if c1 <= c0 or r1 <= r0:
        raise InputError("The DEM and the reference DEM overlap by less than one cell.")
    window = Window(c0, r0, c1 - c0, r1 - r0)
    return window, ref.window_transform(window)


def _vector_kind(path: PathLike) -> bool:
    """True if ``path`` is a vector layer, False if a raster."""
    suffix = Path(path).suffix.lower()
    if suffix in VECTOR_SUFFIXES:
        return True
    if suffix in RASTER_SUFFIXES:
        return False
    try:
        with rasterio.open(path):
            return False
    except Exception:
        return True


def _reproject_geometry(geom: Any, transformer: Any) -> Any:
    """``geom`` with its coordinates transformed (shapely 2 and 1.8)."""
    if hasattr(shapely, "transform"):  # shapely ≥ 2: vectorised over all vertices
        return shapely.transform(geom, lambda xy: np.column_stack(
            transformer.transform(xy[:, 0], xy[:, 1])))
    return shapely_transform(transformer.transform, geom)


def _read_polygons(path: PathLike, crs: Any, field: Optional[str], what: str,
                   feedback: Feedback) -> Tuple[List[Any], List[Any]]:
    """Geometries (in ``crs``) and attribute values (or 1 when ``field`` is None)."""
    p = Path(path)
    if not p.exists():
        raise InputError(f"The {what} '{p}' does not exist; give an existing vector layer.")
    try:
        layer = fiona.open(p)
    except Exception as exc:
        raise InputError(f"The {what} '{p}' cannot be read as a vector layer ({exc}).") from None
    with layer:
        fields = list(layer.schema["properties"])
        if field is not None and field not in fields:
            raise InputError(f"The {what} '{p.name}' has no attribute '{field}'; available "
                             f"fields: {', '.join(fields) or '(none)'}.")
        wkt = layer.crs_wkt
        tr = None
        dst = CRS.from_wkt(crs.to_wkt())
        if wkt:
            srcc = CRS.from_wkt(wkt)
            if not srcc.equals(dst):
                tr = Transformer.from_crs(srcc, dst, always_xy=True)
        else:
            feedback.warning(f"The {what} '{p.name}' has no CRS; assuming the reference CRS.")
        geoms, values = [], []
        for feat in layer:
            if feat["geometry"] is None:
                continue
            g = shape(feat["geometry"])
            if g.is_empty or g.geom_type not in ("Polygon", "MultiPolygon"):
                continue
            if tr is not None:
                g = _reproject_geometry(g, tr)
            geoms.append(g)
            values.append(feat["properties"][field] if field is not None else 1)
    return geoms, values


class _PolygonRasteriser:
    """Rasterises polygons window by window (cell centres inside), values = polygon indices."""

    def __init__(self, geoms: List[Any], values: List[int]) -> None:
        self.geoms = geoms
        self.values = np.asarray(values, dtype=np.int64)
        self.bounds = np.array([g.bounds for g in geoms]).reshape(-1, 4)

    def labels(self, transform: Affine, h: int, w: int) -> Array:
        x0, y1 = transform * (0, 0)
        x1, y0 = transform * (w, h)
        b = self.bounds
        hit = np.nonzero((b[:, 0] <= max(x0, x1)) & (b[:, 2] >= min(x0, x1))
                         & (b[:, 1] <= max(y0, y1)) & (b[:, 3] >= min(y0, y1)))[0]
        out = np.full((h, w), np.nan)
        if hit.size:
            r = rasterize(((self.geoms[i], int(self.values[i])) for i in hit), out_shape=(h, w),
                          transform=transform, fill=-1, dtype="int32")
            out[r >= 0] = r[r >= 0]
        return out


# -- the engine -----------------------------------------------------------------------------------


def _slope_deg(ref_padded: Array, res_x: float, res_y: float) -> Array:
    gr, gc = np.gradient(ref_padded)
    s = np.degrees(np.arctan(np.hypot(gc / res_x, gr / res_y)))
    return s[1:-1, 1:-1]


def _coregister(stack: contextlib.ExitStack, dem: Any, ref: Any, grid: Affine, width: int,
                height: int, stable: Optional[PathLike], max_cells: int,
                feedback: Feedback) -> Dict[str, Any]:
    k = max(1, math.ceil(math.sqrt(width * height / max_cells)))
    t = grid * Affine.scale(k)
    w, h = math.ceil(width / k), math.ceil(height / k)
    res = Resampling.bilinear if k == 1 else Resampling.average
    ref_c = _GridReader(stack, ref, ref.crs, t, w, h,
                        Resampling.nearest if k == 1 else Resampling.average).read(0, 0, h, w)
    dem_c = _GridReader(stack, dem, ref.crs, t, w, h, res).read(0, 0, h, w)
    mask = None
    if stable is not None:
        if _vector_kind(stable):
            geoms, _ = _read_polygons(stable, ref.crs, None, "stable-area layer", feedback)
            if not geoms:
                raise InputError(f"The stable-area layer '{stable}' holds no polygons.")
            mask = geometry_mask(geoms, out_shape=(h, w), transform=t, invert=True)
        else:
            src = _open_raster(stack, stable, "stable-area mask")
            m = _GridReader(stack, src, ref.crs, t, w, h, Resampling.nearest).read(0, 0, h, w)
            mask = np.isfinite(m) & (m != 0)
        if not mask.any():
            raise InputError("The stable area does not overlap the common area of the DEMs.")
    if k > 1:
        feedback.info(f"Co-registration on a grid averaged {k}×{k} ({w} × {h} cells).")
    r = nuth_kaab(dem_c, ref_c, t, stable=mask)
    feedback.info(f"Co-registration (Nuth & Kääb): dx = {r.dx:.3f}, dy = {r.dy:.3f}, "
                  f"dz = {r.dz:.3f} after {r.iterations} iterations"
                  + ("" if r.converged else " (not converged)"))
    if not r.converged:
        feedback.warning("The co-registration did not converge; the shift may be unreliable.")
    return {"dx": r.dx, "dy": r.dy, "dz": r.dz, "iterations": r.iterations,
            "converged": r.converged, "residual_nmad": r.residual_nmad}


def class_names_of(classes: Optional[PathLike], legend: Optional[PathLike] = None
                   ) -> Dict[str, str]:
    """Names of the codes of a class *raster* (:func:`.class_legend.read_class_legend`);
    empty for class polygons, whose classes are names already, and without classes."""
    if classes is None or _vector_kind(classes):
        return {}
    return read_class_legend(classes, legend)


class _ClassSource:
    """Class labels window by window: from polygons (indices, with names) or a raster."""

    def __init__(self, stack: contextlib.ExitStack, classes: Optional[PathLike],
                 class_field: Optional[str], ref: Any, grid: Affine, width: int, height: int,
                 feedback: Feedback) -> None:
        self.names: Optional[Dict[str, str]] = None
        self.polys: Optional[_PolygonRasteriser] = None
        self.reader: Optional[_GridReader] = None
        if classes is None:
            return
        if _vector_kind(classes):
            geoms, values = _read_polygons(classes, ref.crs, class_field, "class layer",
                                           feedback)
            keys = sorted({_label_key(v) for v in values if v is not None})
            index = {k: i for i, k in enumerate(keys)}
            keep = [i for i, v in enumerate(values) if v is not None]
            self.polys = _PolygonRasteriser([geoms[i] for i in keep],
                                            [index[_label_key(values[i])] for i in keep])
            self.names = {str(i): k for k, i in index.items()}
        else:
            csrc = _open_raster(stack, classes, "class raster")
            self.reader = _GridReader(stack, csrc, ref.crs, grid, width, height,
                                      Resampling.nearest)

    def labels(self, wt: Affine, r: int, c: int, h: int, w: int) -> Optional[Array]:
        """Class of every cell of the window (NaN = none), or None without classes."""
        if self.polys is not None:
            return self.polys.labels(wt, h, w)
        if self.reader is not None:
            return self.reader.read(r, c, h, w)
        return None


class _ObjectSource:
    """Object classes of the reference cells, window by window (needs the reference's DTM)."""

    def __init__(self, stack: contextlib.ExitStack, dtm: Optional[PathLike], ref: Any,
                 grid: Affine, width: int, height: int, object_height: float) -> None:
        self.reader: Optional[_GridReader] = None
        self.object_height = float(object_height)
        self.cell = abs(grid.a)
        self.margin = mask_margin(self.cell)
        if dtm is None:
            return
        if not object_height > 0:
            raise InputError("The object height must be positive (metres above the DTM).")
        if ref.crs.is_geographic:
            raise InputError("Object classes need a reference in a projected CRS (cells in "
                             "metres); warp the reference DSM first (e.g. gdalwarp).")
        src = _open_raster(stack, dtm, "terrain model (DTM)")
        k = self.margin
        self.reader = _GridReader(stack, src, ref.crs, grid * Affine.translation(-k, -k),
                                  width + 2 * k, height + 2 * k, Resampling.bilinear)

    def labels(self, ref: Any, grid: _ComparisonGrid, r: int, c: int, h: int, w: int
               ) -> Optional[Array]:
        """Object class codes of the window (NaN where the reference or DTM is empty)."""
        if self.reader is None:
            return None
        k = self.margin
        z = _read_window(ref, grid.r_off + r - k, grid.c_off + c - k, h + 2 * k, w + 2 * k)
        t = self.reader.read(r, c, h + 2 * k, w + 2 * k)
        m = object_masks(z, t, self.cell, object_height=self.object_height)
        inner = (slice(k, k + h), slice(k, k + w))
        return object_classes(m, np.isfinite(z - t))[inner]


class _ComparisonGrid:
    """The reference window both DEMs cover: its transform, size and offset in the reference."""

    def __init__(self, src: Any, ref: Any) -> None:
        gwin, self.transform = _common_grid(src, ref)
        self.width, self.height = int(gwin.width), int(gwin.height)
        self.r_off, self.c_off = int(gwin.row_off), int(gwin.col_off)

    def windows(self, window_size: int, within: Optional[Window] = None
                ) -> List[Tuple[int, int, int, int]]:
        """(row, col, h, w) of the processing windows (only those of ``within`` when given)."""
        step = max(16, int(window_size))
        r0, c0, r1, c1 = 0, 0, self.height, self.width
        if within is not None:
            r0, c0 = int(within.row_off), int(within.col_off)
            r1, c1 = r0 + int(within.height), c0 + int(within.width)
        return [(r, c, min(step, r1 - r), min(step, c1 - c))
                for r in range(r0, r1, step) for c in range(c0, c1, step)]


class _Area:
    """The cells of the comparison grid whose centres lie in an area (polygon or extent).

    Only the area's bounding window of the grid is processed, so an area statistic reads no
    more than the area; cells outside the polygon are masked out window by window.
    """

    def __init__(self, area: Any, grid: _ComparisonGrid) -> None:
        if isinstance(area, str):
            area = shapely.wkt.loads(area)
        elif isinstance(area, (tuple, list)) and len(area) == 4:
            area = shapely.geometry.box(*[float(v) for v in area])
        if area is None or area.is_empty or area.geom_type not in ("Polygon", "MultiPolygon"):
            raise InputError("The area must be a polygon or an extent (xmin, ymin, xmax, ymax) "
                             "in the reference CRS.")
        self.geom = area if area.is_valid else area.buffer(0)
        t = grid.transform
        win = from_bounds(*self.geom.bounds, transform=t)
        c0 = max(math.floor(win.col_off), 0)
        r0 = max(math.floor(win.row_off), 0)
        c1 = min(math.ceil(win.col_off + win.width), grid.width)
        r1 = min(math.ceil(win.row_off + win.height), grid.height)
        if c1 <= c0 or r1 <= r0:
            raise InputError("The area lies outside the common area of the DEM and the "
                             "reference; draw it where both have heights.")
        self.window = Window(c0, r0, c1 - c0, r1 - r0)
        self.transform = t

    def result(self) -> Dict[str, Any]:
        """``{"area": {"row", "col", "height", "width"}}``: the area's window of the grid."""
        w = self.window
        return {"area": {"row": int(w.row_off), "col": int(w.col_off), "height": int(w.height),
                         "width": int(w.width)}}

    def inside(self, r: int, c: int, h: int, w: int) -> NDArray[np.bool_]:
        """True for the cells of the window whose centres lie in the area."""
        return geometry_mask([self.geom], out_shape=(h, w), invert=True,
                             transform=self.transform * Affine.translation(c, r))


def _difference_output(stack: contextlib.ExitStack, path: Optional[PathLike], ref: Any,
                       grid: _ComparisonGrid) -> Any:
    """The open (staged) Δh raster, or None when no path is given."""
    if path is None:
        return None
    tmp = stack.enter_context(atomic_output(path))
    profile = gtiff_profile(grid.width, grid.height, 1, "float32", ref.crs, nodata=float("nan"),
                            transform=grid.transform, predictor=3)
    return stack.enter_context(open_image(tmp, "w", **profile))


@dataclass
class _CompareJob:
    """What a window task on a Dask worker opens itself (paths and options, picklable)."""

    dem: str
    reference: str
    classes: Optional[str]
    class_field: Optional[str]
    dtm: Optional[str]
    object_height: float
    shift: Tuple[float, float]
    dz0: float
    grid: _ComparisonGrid
    area: Optional[_Area]

    @classmethod
    def of(cls, paths: Tuple[Any, Any, Any, Any], class_field: Optional[str],
           object_height: float, shift: Optional[Dict[str, Any]], grid: _ComparisonGrid,
           area: Optional[_Area]) -> _CompareJob:
        """From ``(dem, reference, classes, dtm)`` (None where not given) and the shift."""
        dem, ref, classes, dtm = (None if p is None else str(p) for p in paths)
        return cls(str(dem), str(ref), classes, class_field, dtm, float(object_height),
                   (shift["dx"], shift["dy"]) if shift else (0.0, 0.0),
                   shift["dz"] if shift else 0.0, grid, area)

    def sources(self, stack: contextlib.ExitStack, ref: Any, src: Any, fb: Feedback
                ) -> Tuple[_GridReader, _ClassSource, _ObjectSource]:
        """The DEM on the comparison grid, the classes and the object classes (open)."""
        g = self.grid
        return (_GridReader(stack, src, ref.crs, g.transform, g.width, g.height,
                            Resampling.bilinear, self.shift),
                _ClassSource(stack, self.classes, self.class_field, ref, g.transform, g.width,
                             g.height, fb),
                _ObjectSource(stack, self.dtm, ref, g.transform, g.width, g.height,
                              self.object_height))


def _window_task(job: _CompareJob, win: Tuple[int, int, int, int]) -> Tuple[Any, ...]:
    """:func:`_window_values` of one window with the rasters opened here (a Dask task)."""
    with contextlib.ExitStack() as stack:
        ref = _open_raster(stack, job.reference, "reference DEM")
        src = _open_raster(stack, job.dem, "DEM")
        reader, classes, objects = job.sources(stack, ref, src, Feedback())
        return _window_values(ref, reader, job.dz0, job.grid, (classes, objects), job.area,
                              win)


def _window_values(ref: Any, dem_reader: _GridReader, dz0: float, grid: _ComparisonGrid,
                   sources: Tuple[_ClassSource, _ObjectSource], area: Optional[_Area],
                   win: Tuple[int, int, int, int]) -> Tuple[Any, ...]:
    """Δh of one window ``(row, col, h, w)``, its groups, the valid reference cells and the
    numbers of valid reference and DEM heights (cell-wise: no statistics here)."""
    classes, objects = sources
    t = grid.transform
    r, c, h, w = win
    refp = _read_window(ref, grid.r_off + r - 1, grid.c_off + c - 1, h + 2, w + 2)
    z_ref = refp[1:-1, 1:-1]
    z_dem = dem_reader.read(r, c, h, w) + dz0
    if area is not None:  # outside the area: as if neither DEM had a height there
        outside = ~area.inside(r, c, h, w)
        z_ref = np.where(outside, np.nan, z_ref)
        z_dem[outside] = np.nan
    groups = {"slope": slope_class_index(_slope_deg(refp, t.a, t.e))}
    labels = classes.labels(t * Affine.translation(c, r), r, c, h, w)
    if labels is not None:
        groups["class"] = labels
    obj = objects.labels(ref, grid, r, c, h, w)
    if obj is not None:
        groups["object"] = obj
    ref_valid = np.isfinite(z_ref)
    return (z_dem - z_ref, groups, ref_valid, int(np.count_nonzero(ref_valid)),
            int(np.count_nonzero(np.isfinite(z_dem))))


def _accumulate(ref: Any, dem_reader: _GridReader, dz0: float, grid: _ComparisonGrid,
                sources: Tuple[_ClassSource, _ObjectSource], out_ds: Any,
                accs: Tuple[DifferenceAccumulator, Dict[str, CompletenessAccumulator]],
                window_size: int, progress: Tuple[float, Feedback],
                area: Optional[_Area] = None,
                on_window: Optional[WindowHook] = None,
                job: Optional[Tuple[str, _CompareJob]] = None) -> Tuple[int, int]:
    """Feed Δh of every window (with slope, class and object groups) to the accumulators.

    Writes Δh. Returns the numbers of valid reference and DEM heights. ``sources`` are the
    class and object-class sources; ``accs`` the statistics and the completeness per grouping
    (``"class"``, ``"object"``); ``progress`` is (the share already done in %, the feedback).
    With ``area`` only its windows are read and cells outside it are empty; ``on_window``
    receives ``(row, col, dz)`` of every window (grid rows/columns). With ``job`` =
    (scheduler, what to open) the windows are Dask tasks (:mod:`..raster.tiled_dask`); the
    statistics are still added here, window by window in the same order: the same result.
    """
    acc, comp = accs
    base, fb = progress
    wins = grid.windows(window_size, area.window if area is not None else None)
    if job is not None and job[0]:
        results = map_tiles(_window_task, wins, (job[1],), job[0], fb.step(base, 100.0))
    else:
        results = ((i, _window_values(ref, dem_reader, dz0, grid, sources, area, win))
                   for i, win in enumerate(wins))
    n_ref = n_dem = 0
    for i, (dz, groups, ref_valid, nr, nd) in results:
        r, c, h, w = wins[i]
        n_ref += nr
        n_dem += nd
        for name in ("class", "object"):
            if name in groups:
                comp[name].add_labels(dz, groups[name], truth_valid=ref_valid)
        acc.add(dz, groups)
        if on_window is not None:
            on_window(r, c, dz)
        if out_ds is not None:
            out_ds.write(dz.astype(np.float32), 1, window=Window(c, r, w, h))
        fb.progress(base + (100.0 - base) * (i + 1) / len(wins))
    return n_ref, n_dem


def _check_overlap_heights(n_ref: int, n_dem: int, acc: DifferenceAccumulator,
                           dem: PathLike, reference: PathLike) -> None:
    """One-line errors when a DEM or both together have no valid heights in common."""
    if n_ref == 0:
        raise InputError(f"The reference DEM '{reference}' has no valid heights in the area "
                         "it shares with the DEM (all nodata).")
    if n_dem == 0:
        raise InputError(f"The DEM '{dem}' has no valid heights in the area it shares with "
                         "the reference (all nodata).")
    if acc.total.n == 0:
        raise InputError("The DEM and the reference have no valid heights at the same "
                         "cells; nothing to compare.")


def compare_dems(
    dem: PathLike,
    reference: PathLike,
    *,
    coregister: bool = False,
    stable: Optional[PathLike] = None,
    classes: Optional[PathLike] = None,
    class_field: Optional[str] = None,
    flying_height: Optional[float] = None,
    difference_path: Optional[PathLike] = None,
    window_size: int = 1024,
    memory_budget: int = 512 * 2**20,
    coreg_max_cells: int = 4_000_000,
    dtm: Optional[PathLike] = None,
    object_height: float = OBJECT_HEIGHT,
    area: Any = None,
    on_window: Optional[WindowHook] = None,
    scheduler: str = "",
    feedback: Optional[Feedback] = None,
) -> Dict[str, Any]:
    """Compare a DEM with a reference DEM on the reference grid, window by window.

    Parameters
    ----------
    dem, reference : path
        Rasters (band 1 = heights in metres); any CRS, grid and extent; nodata → ignored.
    coregister : bool
        Estimate and remove the DEM's horizontal and vertical shift first (Nuth & Kääb).
    stable : path, optional
        Stable terrain for the co-registration: a mask raster (non-zero = stable) or polygons.
    classes : path, optional
        Class polygons (with ``class_field``) or a class raster.
    class_field : str, optional
        Attribute of the class polygons that holds the class.
    flying_height : float, optional
        Flying height above ground (m): statistics also in ‰ of it.
    difference_path : path, optional
        Write Δh (float32, NaN = no data, tiled GeoTIFF, atomically) on the comparison grid.
    window_size : int
        Window edge (cells) of the processing; memory per window ≈ 60 bytes × window_size².
    memory_budget : int
        Bytes of differences kept for exact quantiles (beyond: 0.5 mm histograms).
    coreg_max_cells : int
        Cells of the (averaged) grid the co-registration sees.
    dtm : path, optional
        Terrain model of the reference (when the reference is a DSM): object classes from the
        nDSM, statistics and completeness per object class.
    object_height : float
        Height above the DTM (m) from which a cell is an object.
    area : shapely polygon, WKT or (xmin, ymin, xmax, ymax), optional
        Only the cells whose centres lie in it (reference CRS); only its window is read.
    on_window : callable, optional
        ``on_window(row, col, dz)`` per window (grid rows/cols; NaN outside ``area``).
    scheduler : str
        ``""`` (here), ``"local"`` or ``"tcp://host:port"``: where the windows run (same result).
    feedback : Feedback, optional
        Progress per window; cancelling raises Cancelled and leaves no difference raster.

    Returns
    -------
    dict
        ``{"stats", "shift" (dx, dy, dz, iterations, converged, residual_nmad) or None,
        "per_class", "per_slope", "grid" {"crs", "transform", "width", "height",
        "resolution"}, "difference", "precision"}``; statistics as
        :func:`~.stats.difference_stats`. With ``dtm`` also ``"per_object"`` (statistics per
        object class); with classes or ``dtm`` also ``"completeness"`` ``{"per_class",
        "per_object"}`` (:meth:`~.objects.CompletenessAccumulator.result` per class).

    Raises
    ------
    InputError
        Unreadable files, missing CRS, no overlap, no valid heights, missing class attribute.
    """
    fb = ensure_feedback(feedback)
    if classes is not None and _vector_kind(classes) and not class_field:
        raise InputError("Class polygons need the attribute that holds the class "
                         "(class_field); give its name.")
    with contextlib.ExitStack() as stack:
        ref = _open_raster(stack, reference, "reference DEM")
        src = _open_raster(stack, dem, "DEM")
        cg = _ComparisonGrid(src, ref)
        grid, width, height = cg.transform, cg.width, cg.height
        fb.info(f"Comparison grid: {width} × {height} cells of the reference "
                f"({abs(grid.a):g} × {abs(grid.e):g}), {ref.crs.to_string()}.")
        shift = (_coregister(stack, src, ref, grid, width, height, stable, coreg_max_cells,
                             fb.step(0, 10)) if coregister else None)
        zone = _Area(area, cg) if area is not None else None
        job = _CompareJob.of((dem, reference, classes, dtm), class_field, object_height, shift,
                             cg, zone)
        dem_reader, class_src, obj_src = job.sources(stack, ref, src, fb)
        acc = DifferenceAccumulator(memory_budget=memory_budget)
        comp = {"class": CompletenessAccumulator(), "object": CompletenessAccumulator()}
        out_ds = _difference_output(stack, difference_path, ref, cg)
        n_ref, n_dem = _accumulate(ref, dem_reader, job.dz0, cg, (class_src, obj_src), out_ds,
                                   (acc, comp), window_size, (10.0 if coregister else 0.0, fb),
                                   zone, on_window, (check_scheduler(scheduler), job))
        _check_overlap_heights(n_ref, n_dem, acc, dem, reference)
        res = acc.result(flying_height)

    per_slope = {SLOPE_LABELS[int(k)]: v for k, v in res.get("per_slope", {}).items()}
    per_class = res.get("per_class", {})
    comp_class = comp["class"].result()
    if class_src.names is not None:
        per_class = {class_src.names[k]: v for k, v in per_class.items()}
        comp_class = {class_src.names.get(k, k): v for k, v in comp_class.items()}
    extra = _object_results(res, comp_class, comp["object"].result(), classes is not None,
                            dtm is not None)
    return {
        "stats": res["stats"],
        "shift": shift,
        "per_class": per_class,
        "per_slope": per_slope,
        "grid": {"crs": ref.crs.to_string(), "transform": list(grid)[:6], "width": width,
                 "height": height, "resolution": [abs(grid.a), abs(grid.e)]},
        "difference": str(difference_path) if difference_path is not None else None,
        "precision": res["precision"],
        **(zone.result() if zone is not None else {}),
        **extra,
    }


def _object_results(res: Dict[str, Any], comp_class: Dict[str, Any], comp_object: Dict[str, Any],
                    with_classes: bool, with_objects: bool) -> Dict[str, Any]:
    """``per_object`` and ``completeness`` of the result (only what was asked for)."""
    names = {str(code): name for code, name in OBJECT_CLASSES}
    order = [name for _, name in OBJECT_CLASSES]
    out: Dict[str, Any] = {}
    if with_objects:
        per = {names.get(k, k): v for k, v in res.get("per_object", {}).items()}
        out["per_object"] = {k: per[k] for k in order if k in per}
    if with_classes or with_objects:
        comp_o = {names.get(k, k): v for k, v in comp_object.items()}
        out["completeness"] = {"per_class": comp_class if with_classes else None,
                               "per_object": ({k: comp_o[k] for k in order if k in comp_o}
                                              if with_objects else None)}
    return out
