r"""Seamlines of an orthophoto mosaic: nadir partition, least-cost seam routing, operator seams.

All of this works on the *seam grid*: the mosaic grid reduced by an integer factor so that it
has at most ``seam_cells`` cells along its longer side (see :mod:`.mosaic`); its size, and so the
memory used here, is bounded by that parameter and not by the mosaic size.

Nadir partition
    Every seam-grid cell goes to the image whose projection centre is nearest in XY among the
    images that cover the cell completely (valid fraction 1); cells covered only partly go to
    the image with the largest valid fraction. This is the Voronoi diagram of the nadir points
    clipped to the footprints: every cell is seen as steeply as possible, so relief displacement
    :math:`\Delta r = h\,r/H` (and the lean of buildings in a classical ortho) is smallest.

Seam routing (``auto``)
    Each boundary between two images :math:`i, j` of the partition is replaced by a least-cost
    path. The path may use the cells of a corridor of half-width ``corridor`` cells around the
    boundary that belong to :math:`i` or :math:`j` and are valid in both; it runs between the two
    ends of the corridor (where it meets a third image, the mosaic edge or nodata) and minimises
    :math:`\sum c` (diagonal steps :math:`\sqrt 2\,c`, :class:`skimage.graph.MCP_Geometric`) with
    the cost per cell

    .. math::  c = 1 + \min\!\left(\frac{|g_i - g_j|}{\overline{|g_i - g_j|}}, 20\right)
               + \begin{cases} P & \Delta h \ge h_{\min} \\
                               2\,\Delta h / h_{\min} & \text{else} \end{cases}

    where :math:`g` is the grey value (mean of the balanced bands), the bar the mean over the
    corridor, :math:`\Delta h` = DSM − DTM (maximum in the cell, dilated by the feather
    half-width so that the blend zone stays off objects) and :math:`P = 1000`: a seam crosses a
    building or tree only where the corridor offers no way around. Corridor cells are then given
    to the side of the path they are connected to. Boundaries are routed one after the other on
    the current partition, twice, so a boundary moved by one seam is routed again.

    What routing cannot avoid (a corridor without a way around, ends that are not two clear
    pieces) is settled object by object (:func:`keep_objects_whole`): every connected object
    (DSM − DTM ≥ :math:`h_{\min}`, dilated by the feather margin) that a seam still splits
    goes entirely to one image — one whose footprint holds all of it, with the fewest
    occluded cells — so the seam runs along the object's dilated outline. Seams therefore
    cross buildings and trees only where no single image covers the object.

Operator seamlines
    A vector file (GeoPackage, Shapefile, GeoJSON; every layer is read) or the ``seamlines``
    layer of the project's ``edits.gpkg``:

    * **polygons with an ``image`` attribute** (the image name, or the ortho's file name) take
      their area from that image — the footprint GeoPackage a mosaic writes is such a file, so
      an operator can edit it and mosaic again;
    * **lines** (and polygons without ``image``) cut the mosaic area into regions; each region
      takes the image that the nadir partition gives most of its area.

    Assigned polygons win over cut regions; cells outside both follow the nadir partition.
    Operator seams are honoured exactly (rasterised at full resolution), not routed.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import fiona
import numpy as np
from affine import Affine
from numpy.typing import NDArray
from rasterio.crs import CRS
from rasterio.features import rasterize, shapes
from scipy import ndimage
from shapely.geometry import MultiLineString, MultiPolygon, box, mapping, shape
from shapely.ops import linemerge, polygonize, unary_union
from skimage.graph import MCP_Geometric

from ..errors import InputError
from ..project.vector_io import read_features, to_crs
from ..raster.io import atomic_output

PathLike = Union[str, Path]
Array = NDArray[Any]

#: Cost added to seam-grid cells on elevated objects (DSM − DTM ≥ min_height).
OBJECT_PENALTY = 1000.0
#: Cap of the normalised image-difference cost.
DIFF_CAP = 20.0

_EIGHT = np.ones((3, 3), bool)
_FOUR = ndimage.generate_binary_structure(2, 1)


@dataclass
class SeamImage:
    """One ortho on the seam grid: a window of it and what seams need there.

    Attributes
    ----------
    name : str
        Image name.
    centre : (float, float)
        Projection centre X, Y (project CRS).
    row, col : int
        Offset of the window on the seam grid.
    frac : ndarray (h, w) float32
        Valid fraction of each cell (1 = every pixel valid and visible).
    grey : ndarray (h, w) float32
        Mean of the (balanced) colour bands.
    cover : ndarray (h, w) float32, optional
        Geometric coverage (1 = inside the image, visible or occluded), from the ortho's
        visibility raster; default ``frac``. The partition is built on it, so that occlusions
        do not break it into islands before the seams are routed.
    """

    name: str
    centre: Tuple[float, float]
    row: int
    col: int
    frac: Array
    grey: Array
    cover: Optional[Array] = None

    @property
    def shape(self) -> Tuple[int, int]:
        return self.frac.shape  # type: ignore[return-value]

    def crop(self, array: Array, r0: int, r1: int, c0: int, c1: int, fill: float) -> Array:
        """``array`` (one of this image's window layers) on seam-grid rows/cols ``[r0, r1)``."""
        out = np.full((r1 - r0, c1 - c0), fill, dtype=array.dtype)
        h, w = array.shape
        a0, a1 = max(r0, self.row), min(r1, self.row + h)
        b0, b1 = max(c0, self.col), min(c1, self.col + w)
        if a1 > a0 and b1 > b0:
            out[a0 - r0:a1 - r0, b0 - c0:b1 - c0] = array[a0 - self.row:a1 - self.row,
                                                          b0 - self.col:b1 - self.col]
        return out


def cell_centres(transform: Affine, rows: Array, cols: Array) -> Tuple[Array, Array]:
    """World X (1, w) and Y (h, 1) of cell centres for row/col index vectors (broadcastable)."""
    x = transform.c + (np.asarray(cols, np.float64) + 0.5) * transform.a
    y = transform.f + (np.asarray(rows, np.float64) + 0.5) * transform.e
    return x[None, :], y[:, None]


def nadir_labels(shape: Tuple[int, int], transform: Affine,
                 images: Sequence[SeamImage], geometric: bool = False) -> Array:
    r"""Nadir (Voronoi) partition of the seam grid: index of the image per cell, −1 = none.

    Score per image and cell: :math:`(1 - f)\cdot 10^{12} + d^2` with :math:`f` the valid
    fraction and :math:`d` the XY distance to the projection centre; the smallest score wins,
    so a completely covered cell always goes to a complete image, nearest nadir first.
    ``geometric`` uses the coverage ``cover`` (occluded cells count as covered) instead of
    the valid fraction.
    """
    best = np.full(shape, np.inf)
    labels = np.full(shape, -1, np.int32)
    for k, im in enumerate(images):
        h, w = im.shape
        x, y = cell_centres(transform, np.arange(im.row, im.row + h),
                            np.arange(im.col, im.col + w))
        d2 = (x - im.centre[0]) ** 2 + (y - im.centre[1]) ** 2
        frac = im.cover if geometric and im.cover is not None else im.frac
        score = np.where(frac > 0, (1.0 - frac) * 1e12 + d2, np.inf)
        view = best[im.row:im.row + h, im.col:im.col + w]
        lab = labels[im.row:im.row + h, im.col:im.col + w]
        better = score < view
        view[better] = score[better]
        lab[better] = k
    return labels


def fill_invalid(labels: Array, images: Sequence[SeamImage], fallback: Array) -> Array:
    """``labels`` where its image is completely valid, else ``fallback`` (next best image)."""
    out = labels.copy()
    for k, im in enumerate(images):
        h, w = im.shape
        view = out[im.row:im.row + h, im.col:im.col + w]
        src = labels[im.row:im.row + h, im.col:im.col + w]
        bad = (src == k) & (im.frac < 1.0)
        view[bad] = fallback[im.row:im.row + h, im.col:im.col + w][bad]
    outside = (labels >= 0) & (labels < len(images))
    for k, im in enumerate(images):  # cells of an image outside its window
        inside = np.zeros(labels.shape, bool)
        inside[im.row:im.row + im.shape[0], im.col:im.col + im.shape[1]] = True
        stray = outside & (labels == k) & ~inside
        out[stray] = fallback[stray]
    return out


def adjacent_pairs(labels: Array) -> List[Tuple[int, int]]:
    """Pairs ``(i, j)``, ``i < j``, of labels ≥ 0 that touch (4-neighbourhood), sorted."""
    pairs = set()
    for a, b in ((labels[:, :-1], labels[:, 1:]), (labels[:-1, :], labels[1:, :])):
        m = (a != b) & (a >= 0) & (b >= 0)
        if m.any():
            lo = np.minimum(a[m], b[m]).astype(np.int64)
            hi = np.maximum(a[m], b[m]).astype(np.int64)
            for code in np.unique(lo * 1_000_003 + hi):
                pairs.add((int(code // 1_000_003), int(code % 1_000_003)))
    return sorted(pairs)


def boundary_cells(labels: Array) -> Array:
    """Cells with a 4-neighbour of another label (both ≥ 0): the seams of a partition."""
    out = np.zeros(labels.shape, bool)
    for axis in (0, 1):
        a = labels.take(np.arange(labels.shape[axis] - 1), axis=axis)
        b = labels.take(np.arange(1, labels.shape[axis]), axis=axis)
        m = (a != b) & (a >= 0) & (b >= 0)
        if axis == 0:
            out[:-1, :] |= m
            out[1:, :] |= m
        else:
            out[:, :-1] |= m
            out[:, 1:] |= m
    return out


def object_height(dsm: Array, dtm: Array, margin: int = 0) -> Array:
    """Height above the terrain (DSM − DTM, NaN → 0), dilated by ``margin`` cells (max filter)."""
    hag = np.nan_to_num(dsm.astype(np.float32) - dtm.astype(np.float32), nan=0.0)
    hag = np.maximum(hag, 0.0)
    if margin > 0:
        hag = ndimage.maximum_filter(hag, size=2 * margin + 1, mode="nearest")
    return hag


def _pair_cost(gi: Array, gj: Array, hag: Optional[Array], passable: Array,
               min_height: float, offset: Array) -> Array:
    """Cost of the seam cells of one corridor (see the module notes); ∞ where impassable."""
    diff = np.abs(gi - gj)
    mean = float(diff[passable].mean()) if passable.any() else 0.0
    cost = 1.0 + offset + np.minimum(diff / (mean + 1e-6), DIFF_CAP)
    if hag is not None:
        cost = cost + np.where(hag >= min_height, OBJECT_PENALTY,
                               2.0 * hag / max(min_height, 1e-6))
    return np.where(passable, cost, np.inf)


def _route_pair(labels: Array, i: int, j: int, images: Sequence[SeamImage],
                hag: Optional[Array], corridor: int, min_height: float) -> Tuple[int, int]:
    """Route the seam between ``i`` and ``j`` in place; returns (routed, kept) component counts."""
    H, W = labels.shape
    seam = boundary_cells(np.where((labels == i) | (labels == j), labels, -1))
    rows, cols = np.nonzero(seam)
    if rows.size == 0:
        return 0, 0
    pad = corridor + 2
    r0, r1 = max(rows.min() - pad, 0), min(rows.max() + pad + 1, H)
    c0, c1 = max(cols.min() - pad, 0), min(cols.max() + pad + 1, W)
    lab = labels[r0:r1, c0:c1]
    b = seam[r0:r1, c0:c1]
    dist = ndimage.distance_transform_edt(~b)
    zone = (dist <= corridor) & ((lab == i) | (lab == j))
    fi = images[i].crop(images[i].frac, r0, r1, c0, c1, 0.0)
    fj = images[j].crop(images[j].frac, r0, r1, c0, c1, 0.0)
    passable = zone & (fi >= 1.0) & (fj >= 1.0)
    core_i = (lab == i) & ~zone
    core_j = (lab == j) & ~zone
    # "other": third images, nodata and (by padding) everything beyond the grid edge
    other = np.pad(~zone & ~core_i & ~core_j, 1, constant_values=True)
    near_other = ndimage.binary_dilation(other, _EIGHT)[1:-1, 1:-1]
    ends = passable & near_other
    gi = images[i].crop(images[i].grey, r0, r1, c0, c1, 0.0)
    gj = images[j].crop(images[j].grey, r0, r1, c0, c1, 0.0)
    h = None if hag is None else hag[r0:r1, c0:c1]
    # the offset term (0 … 1) keeps the seam near the nadir boundary where costs are flat
    cost = _pair_cost(gi, gj, h, passable, min_height, dist / max(corridor, 1))
    comps, n = ndimage.label(passable, _EIGHT)
    routed = kept = 0
    for comp in range(1, n + 1):
        member = comps == comp
        if not (member & b).any():
            continue
        end_lab, n_end = ndimage.label(ends & member, _EIGHT)
        if n_end != 2:  # a closed ring or a broken corridor: keep the nadir boundary
            kept += 1
            continue
        starts = np.argwhere(end_lab == 1)
        goals = np.argwhere(end_lab == 2)
        mcp = MCP_Geometric(np.where(member, cost, np.inf), fully_connected=True)
        cum, _ = mcp.find_costs([tuple(p) for p in starts], [tuple(p) for p in goals])
        gcost = cum[goals[:, 0], goals[:, 1]]
        if not np.isfinite(gcost).any():
            kept += 1
            continue
        goal = goals[int(np.argmin(gcost))]
        path = np.zeros(member.shape, bool)
        pr, pc = np.asarray(mcp.traceback(tuple(goal))).T
        path[pr, pc] = True
        sides, m = ndimage.label(member & ~path, _FOUR)
        if m == 0:
            kept += 1
            continue
        # each side goes to the image it borders most (outside the corridor component)
        idx = np.arange(1, m + 1)
        ti = ndimage.sum(ndimage.binary_dilation((lab == i) & ~member, _FOUR), sides, idx)
        tj = ndimage.sum(ndimage.binary_dilation((lab == j) & ~member, _FOUR), sides, idx)
        new = np.full(m + 1, -1, np.int32)
        new[1:][ti > tj] = i
        new[1:][tj > ti] = j
        assign = new[sides]
        change = (sides > 0) & (assign >= 0)
        lab[change] = assign[change]
        lab[path] = i  # the seam runs along the path's j-side edge
        routed += 1
    return routed, kept


def keep_objects_whole(labels: Array, images: Sequence[SeamImage], objects: Array
                       ) -> Tuple[Array, Dict[str, int]]:
    """Give every object that the partition splits to one image, so no seam crosses it.

    ``objects`` marks the cells to keep whole (DSM − DTM ≥ min_height, dilated by the
    feather margin). Each 8-connected object that holds cells of more than one image goes
    entirely to one image: among the images whose footprint holds *all* its cells the one
    with the most valid (visible) cells, then the one that already holds most of it. The
    new seam then
    runs along the object's dilated outline, off the object. Cells without an image (−1)
    stay so.

    Returns
    -------
    labels : ndarray (H, W) int32
        The partition with whole objects (a new array).
    stats : dict
        ``objects`` (all), ``objects_moved`` (split ones given to one image),
        ``objects_not_covered`` (split ones that no image's footprint covers completely:
        cells outside the chosen image are filled from another one).
    """
    labels = labels.copy()
    comp, n = ndimage.label(objects, _EIGHT)
    stats = {"objects": int(n), "objects_moved": 0, "objects_not_covered": 0}
    if n == 0:
        return labels, stats
    K = len(images)
    held = (comp > 0) & (labels >= 0)
    counts = np.bincount(comp[held].astype(np.int64) * K + labels[held],
                         minlength=(n + 1) * K).reshape(n + 1, K)
    split = (counts > 0).sum(axis=1) > 1
    if not split.any():
        return labels, stats
    size = np.bincount(comp[held], minlength=n + 1)
    valid = np.zeros((n + 1, K), np.int64)
    inside = np.zeros((n + 1, K), np.int64)
    for k, im in enumerate(images):
        h, w = im.shape
        c = comp[im.row:im.row + h, im.col:im.col + w]
        valid[:, k] = np.bincount(c[(c > 0) & (im.frac >= 1.0)], minlength=n + 1)
        cover = im.frac if im.cover is None else im.cover
        inside[:, k] = np.bincount(c[(c > 0) & (cover >= 1.0)], minlength=n + 1)
    full = inside >= size[:, None]
    # inside the image completely first, then the fewest occluded cells to fill from other
    # images, then the image that already holds most of the object
    big = size.max() + 1
    score = full * (4 * big * big) + valid * big + counts
    choice = np.argmax(score, axis=1).astype(np.int32)
    move = split[comp] & held
    labels[move] = choice[comp[move]]
    stats["objects_moved"] = int(split.sum())
    stats["objects_not_covered"] = int((split & ~full[np.arange(n + 1), choice]).sum())
    return labels, stats


def route_seams(labels: Array, images: Sequence[SeamImage], hag: Optional[Array] = None,
                corridor: int = 20, min_height: float = 2.0, margin: int = 1,
                passes: int = 2, feedback: Any = None) -> Tuple[Array, Dict[str, Any]]:
    """Replace the boundaries of a partition by least-cost seams (see the module notes).

    Parameters
    ----------
    labels : ndarray (H, W) int32
        Partition of the seam grid (image index, −1 none), e.g. :func:`nadir_labels`.
    images : sequence of SeamImage
        The images in label order.
    hag : ndarray (H, W), optional
        Height above the terrain per cell (:func:`object_height`), m.
    corridor : int
        Half-width of the search corridor around each boundary, seam-grid cells.
    min_height : float
        Objects at least this high (m) get the penalty :data:`OBJECT_PENALTY`.
    margin : int
        The penalty extends this many cells around objects (feather half-width + 1).
    passes : int
        Rounds over all boundaries.

    Returns
    -------
    labels : ndarray (H, W) int32
        The routed partition (a new array).
    stats : dict
        ``pairs`` (boundaries), ``routed`` / ``kept`` (corridor components routed / left at
        the nadir boundary), ``seam_cells_on_objects_before`` / ``_after`` (seam-grid cells
        on a boundary with DSM − DTM ≥ min_height, only with ``hag``).
    """
    labels = labels.copy()
    cost_height = None
    if hag is not None:
        cost_height = ndimage.maximum_filter(hag, size=2 * margin + 1, mode="nearest") \
            if margin > 0 else hag
    stats: Dict[str, Any] = {"pairs": 0, "routed": 0, "kept": 0}
    if hag is not None:
        stats["seam_cells_on_objects_before"] = int((boundary_cells(labels)
                                                     & (hag >= min_height)).sum())
    for p in range(passes):
        pairs = adjacent_pairs(labels)
        stats["pairs"] = max(stats["pairs"], len(pairs))
        for k, (i, j) in enumerate(pairs):
            if feedback is not None:
                feedback.progress(100.0 * (p + k / max(len(pairs), 1)) / passes)
            routed, kept = _route_pair(labels, i, j, images, cost_height, corridor,
                                       min_height)
            if p == passes - 1:
                stats["routed"] += routed
                stats["kept"] += kept
    if hag is not None:
        stats["seam_cells_on_objects_routed"] = int((boundary_cells(labels)
                                                     & (hag >= min_height)).sum())
        # what routing could not avoid: objects split by a seam go whole to one image
        labels, snap = keep_objects_whole(labels, images, cost_height >= min_height)
        stats.update(snap)
        stats["seam_cells_on_objects_after"] = int((boundary_cells(labels)
                                                    & (hag >= min_height)).sum())
    return labels, stats


# -- operator seamlines -----------------------------------------------------------------------

def read_operator_seamlines(source: PathLike, crs: Any, names: Sequence[str],
                            layers: Optional[Tuple[str, ...]] = None
                            ) -> Tuple[List[Tuple[Any, int]], List[Any]]:
    """Operator seamlines from a vector file (see the module notes).

    Parameters
    ----------
    source : path
        GeoPackage / Shapefile / GeoJSON; every layer is read, or only ``layers``.
    crs : CRS-like
        Mosaic CRS; geometries in another CRS are transformed.
    names : sequence of str
        Image names of the mosaic inputs (index = label); an ``image`` attribute may also be
        the ortho's file name or stem.

    Returns
    -------
    assigned : list of (polygon, image index)
    cuts : list of line geometries

    Raises
    ------
    InputError
        Unreadable file, an ``image`` that is not a mosaic input, or no usable geometry.
    """
    path = Path(source)
    if not path.is_file():
        raise InputError(f"Seamline file '{path}' does not exist; give a vector file, 'auto' "
                         "or 'edits'.")
    target = None if crs is None else CRS.from_user_input(crs)
    lookup = {n.lower(): k for k, n in enumerate(names)}
    assigned: List[Tuple[Any, int]] = []
    cuts: List[Any] = []
    for feat in read_features(path, layers, "seamline file"):
        layer = feat.layer
        g = shape(to_crs(feat.geometry, feat.crs, target))
        if g.is_empty:
            continue
        image = (feat.properties.get("image") or "").strip()
        if "Polygon" in g.geom_type and image:
            key = image.lower()
            k = lookup.get(key, lookup.get(Path(key).stem))
            if k is None:
                raise InputError(
                    f"Seamline polygon of layer '{layer}' names the image '{image}', "
                    f"which is not in the mosaic ({', '.join(names)}); correct its "
                    "'image' attribute.")
            assigned.append((g.buffer(0), k))
        elif "Polygon" in g.geom_type:
            cuts.append(g.boundary)
        elif "LineString" in g.geom_type:
            cuts.append(g)
    if not assigned and not cuts:
        raise InputError(f"'{path.name}' holds no seamlines (lines, or polygons with an "
                         "'image' attribute); digitise some or use seamlines=auto.")
    return assigned, cuts


def cut_regions(cuts: Sequence[Any], bounds: Tuple[float, float, float, float],
                labels: Array, transform: Affine, n_images: int) -> List[Tuple[Any, int]]:
    """Regions of the mosaic area cut by lines, each with the image the partition favours.

    Each region takes the label that ``labels`` (the nadir partition on the seam grid with
    ``transform``) gives most of its cells; regions without a labelled cell are dropped.
    """
    area = box(*bounds)
    lines = unary_union([*cuts, area.boundary])
    regions = [p for p in polygonize(lines) if p.representative_point().within(area)]
    if not regions:
        return []
    ids = rasterize(((r, k + 1) for k, r in enumerate(regions)), out_shape=labels.shape,
                    transform=transform, fill=0, dtype="int32")
    ok = (ids > 0) & (labels >= 0)
    votes = np.zeros((len(regions) + 1, n_images), np.int64)
    np.add.at(votes, (ids[ok], labels[ok]), 1)
    out = []
    for k, region in enumerate(regions):
        if votes[k + 1].sum() > 0:
            out.append((region, int(np.argmax(votes[k + 1]))))
    return out


def rasterize_regions(regions: Sequence[Tuple[Any, int]], shape: Tuple[int, int],
                      transform: Affine) -> Array:
    """Image index per cell from ``(polygon, index)`` pairs (later pairs win), −1 elsewhere."""
    if not regions:
        return np.full(shape, -1, np.int32)
    out = rasterize(((g, k + 1) for g, k in regions), out_shape=shape, transform=transform,
                    fill=0, dtype="int32")
    return out - 1


# -- footprint polygons and seam lines ------------------------------------------------------

def partition_polygons(labels: Array, transform: Affine, n_images: int) -> List[Any]:
    """One (multi)polygon per image index (``None`` if it has no cell) from a label raster."""
    parts: List[List[Any]] = [[] for _ in range(n_images)]
    lab = labels.astype(np.int32)
    for geom, value in shapes(lab, mask=lab >= 0, transform=transform, connectivity=4):
        parts[int(value)].append(shape(geom))
    return [unary_union(p) if p else None for p in parts]


def seam_lines(polygons: Sequence[Any]) -> List[Tuple[int, int, Any]]:
    """Shared boundaries ``(i, j, line)`` of neighbouring footprint polygons, ``i < j``."""
    out = []
    for i in range(len(polygons)):
        for j in range(i + 1, len(polygons)):
            a, b = polygons[i], polygons[j]
            if a is None or b is None or not a.intersects(b):
                continue
            shared = a.boundary.intersection(b.boundary)
            lines = [g for g in getattr(shared, "geoms", [shared])
                     if g.geom_type in ("LineString", "MultiLineString") and g.length > 0]
            if lines:
                merged = linemerge(lines) if len(lines) > 1 else lines[0]
                out.append((i, j, merged))
    return out


def write_seamlines(path: PathLike, polygons: Sequence[Any], names: Sequence[str],
                    orthos: Sequence[str], lines: Sequence[Tuple[int, int, Any]],
                    crs: Any) -> Path:
    """Write layers ``footprints`` (polygon per image: image, ortho, area_m2) and ``seamlines``.

    The ``footprints`` layer can be edited and given back to a mosaic as operator seamlines.
    """
    wkt = None
    if crs is not None:
        wkt = CRS.from_user_input(crs).to_wkt()
    poly_schema = {"geometry": "MultiPolygon",
                   "properties": OrderedDict([("image", "str"), ("ortho", "str"),
                                              ("area_m2", "float")])}
    line_schema = {"geometry": "MultiLineString",
                   "properties": OrderedDict([("image_a", "str"), ("image_b", "str"),
                                              ("length_m", "float")])}
    with atomic_output(path) as tmp:
        with fiona.open(str(tmp), "w", driver="GPKG", layer="footprints", schema=poly_schema,
                        crs_wkt=wkt) as dst:
            for poly, name, ortho in zip(polygons, names, orthos):
                if poly is None or poly.is_empty:
                    continue
                mp = poly if poly.geom_type == "MultiPolygon" else MultiPolygon([poly])
                dst.write({"geometry": mapping(mp),
                           "properties": OrderedDict([("image", name), ("ortho", ortho),
                                                      ("area_m2", float(poly.area))])})
        with fiona.open(str(tmp), "w", driver="GPKG", layer="seamlines", schema=line_schema,
                        crs_wkt=wkt) as dst:
            for i, j, line in lines:
                parts = list(getattr(line, "geoms", [line]))
                dst.write({"geometry": mapping(MultiLineString(parts)),
                           "properties": OrderedDict([("image_a", names[i]),
                                                      ("image_b", names[j]),
                                                      ("length_m", float(line.length))])})
    return Path(path)


def default_corridor(centres: Sequence[Tuple[float, float]]) -> float:
    """A quarter of the median distance between neighbouring projection centres (m).

    With 60 % forward overlap the nadir boundary lies ≈ 0.75 bases from the end of the
    overlap, so a quarter base keeps the corridor well inside it.
    """
    pts = np.asarray(centres, np.float64)
    if len(pts) < 2:
        return 0.0
    d = np.sqrt(((pts[:, None, :] - pts[None, :, :]) ** 2).sum(-1))
    d[np.arange(len(pts)), np.arange(len(pts))] = np.inf
    return 0.25 * float(np.median(d.min(axis=1)))


__all__ = [
    "DIFF_CAP",
    "OBJECT_PENALTY",
    "SeamImage",
    "adjacent_pairs",
    "boundary_cells",
    "cut_regions",
    "default_corridor",
    "fill_invalid",
    "keep_objects_whole",
    "nadir_labels",
    "object_height",
    "partition_polygons",
    "rasterize_regions",
    "read_operator_seamlines",
    "route_seams",
    "seam_lines",
    "write_seamlines",
]
