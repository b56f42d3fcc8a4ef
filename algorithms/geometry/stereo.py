r"""Stereo models: footprints, base, B/H, overlap, and their automatic detection.

Footprint
    The image outline (corners plus points along the edges, so that distortion bends it) is
    intersected with a horizontal plane :math:`Z = h`. With a DEM, :math:`h` is iterated: start at
    the DEM height below the projection centre, intersect a 9 × 9 grid of image rays with
    :math:`Z = h`, set :math:`h` to the mean DEM height at those ground points, repeat until it
    changes by less than 1 cm (a few iterations; the mean height under the footprint).

Model geometry
    Base :math:`B = \lVert C_r - C_l \rVert`; flying height above ground
    :math:`H = \tfrac12[(Z_l - h_l) + (Z_r - h_r)]` with :math:`h_i` the terrain height under
    footprint *i*; overlap = area(F_l ∩ F_r) / min(area F_l, area F_r); GSD = mean of
    :math:`H_i\,p_x / c`. *Left* and *right* are ordered along the base: the right image lies in
    the +x direction of the image x axes (mean of both cameras' x axes), so x-parallaxes are
    positive as in the normal case; when the base is nearly perpendicular to the x axes
    (|cos| < 0.1) the image whose centre lies along the images' +y (up in the image) is left.

Detection (:func:`detect_stereo_models`)
    1. Candidate pairs: images whose centres are closer than the sum of their footprint radii
       (k-d tree), with overlap ≥ ``min_overlap`` and B/H inside ``b_h_range``.
    2. Strip direction: each image's *nearest-neighbour base* gives an axial direction (mod
       180°). The dominant direction is the mode of these directions (the direction with the
       most others within ``strip_angle_tolerance``), refined by the doubled-angle mean of its
       inliers. A pair is **in-strip** when its base lies within the tolerance of the dominant
       direction, or within the tolerance of *both* images' own nearest-neighbour directions
       (this keeps perpendicular cross flights in-strip too). Every other pair is
       **cross-strip**.
    3. Order: in-strip *neighbours* (no other image of the strip lies between the two along the
       base) first, strip by strip along the strip, then other in-strip pairs, then cross-strip
       pairs by decreasing overlap. Strips run north to south, models west to east (for
       north-south strips: south to north).

Model names are ``<left>_<right>`` with short image labels (:func:`image_labels`): the image
names without the parts all images share, e.g. ``0182_0184`` for the NGI frames
``3324c_2015_1004_05_0182_RGB`` and ``3324c_2015_1004_05_0184_RGB``; the model keeps the full
image names in ``left`` and ``right``.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
from numpy.typing import NDArray
from shapely.geometry import Polygon

from ..errors import GeometryError, InputError
from .camera import Camera
from .orientation import ExteriorOrientation
from .projection import ray_at_height

DemLike = Union[None, str, Path, Any]  # path or raster.sample.DemSampler
#: image name → (footprint polygon, terrain height under it in m)
Footprints = Dict[str, Tuple[Polygon, float]]


def image_labels(names: Sequence[str]) -> Dict[str, str]:
    """Short unique labels of image names, for model names.

    Names are split into tokens at ``_``, ``-`` and ``.``; the tokens that every name shares at
    its start and at its end are dropped. If the last remaining token alone is unique, it is the
    label (``0182`` for ``3324c_2015_1004_05_0182_RGB``); otherwise the remaining tokens joined
    by ``_``. Names that would lose uniqueness keep their full form.
    """
    import re

    tokens = [re.split(r"[_.\-]", n) for n in names]
    if len(names) < 2:
        return {n: n for n in names}
    shortest = min(len(t) for t in tokens)
    head = 0
    while head < shortest - 1 and len({t[head] for t in tokens}) == 1:
        head += 1
    tail = 0
    while tail < shortest - head - 1 and len({t[-1 - tail] for t in tokens}) == 1:
        tail += 1
    rest = [t[head:len(t) - tail] for t in tokens]
    last = [r[-1] for r in rest]
    if len(set(last)) == len(names):
        labels = last
    else:
        labels = ["_".join(r) for r in rest]
        if len(set(labels)) != len(names):
            labels = list(names)
    return dict(zip(names, labels))


# -- DEM -------------------------------------------------------------------------------------------
def load_dem(dem: DemLike, bounds: Optional[Sequence[float]] = None, crs: Any = None) -> Any:
    """A :class:`~..raster.sample.DemSampler` from a path (window ``bounds``), or ``dem`` as is.

    With ``crs`` (the project CRS) a DEM file in another CRS is refused, naming both
    (:func:`~..crs_check.check_surface_crs`): its heights would be sampled at wrong places.
    """
    if dem is None:
        return None
    if isinstance(dem, (str, Path)):
        from ..raster.sample import DemSampler

        if crs:
            import rasterio

            from ..crs_check import check_surface_crs
            from ..input_errors import check_encodable, reading

            check_encodable(dem, "DEM")
            if Path(dem).is_file():
                with reading(dem, "raster"), rasterio.open(dem) as src:
                    file_crs = src.crs
                check_surface_crs(dem, file_crs, crs, "DEM")

        return DemSampler.from_file(dem, bounds=None if bounds is None else tuple(bounds))
    return dem


def _dem_height(dem: Any, x: NDArray, y: NDArray) -> NDArray:
    return np.asarray(dem.height(x, y), dtype=float)


# -- footprints ------------------------------------------------------------------------------------
def outline_pixels(camera: Camera, per_edge: int = 8) -> NDArray[np.float64]:
    """Pixel (col, row) of the image outline, clockwise from top left: corners + edge points."""
    c = camera.corners()
    t = np.linspace(0.0, 1.0, per_edge + 1)[:-1, None]
    return np.concatenate([c[i] + t * (c[(i + 1) % 4] - c[i]) for i in range(4)])


def _polygon(points: NDArray) -> Polygon:
    ok = np.all(np.isfinite(points[:, :2]), axis=1)
    if ok.sum() < 3:
        raise GeometryError(
            "The image footprint cannot be computed: its rays do not reach the terrain "
            "(camera below the terrain or looking above the horizon?). Check the exterior "
            "orientation and the terrain height."
        )
    poly = Polygon(points[ok, :2])
    if not poly.is_valid:
        poly = poly.buffer(0)
    return poly


def footprint_and_height(camera: Camera, eo: ExteriorOrientation,
                         height: Optional[float] = None, dem: DemLike = None,
                         per_edge: int = 8, max_iter: int = 10) -> Tuple[Polygon, float]:
    """Footprint polygon and the terrain height it was computed at (see module notes).

    Parameters
    ----------
    height : float, optional
        Terrain height (m) of the horizontal plane; used when no DEM is given.
    dem : path or DemSampler, optional
        Terrain model; the footprint plane is iterated to the mean DEM height under it.
    """
    if dem is None and height is None:
        raise InputError("A footprint needs a terrain height or a DEM.")
    if dem is not None:
        sampler = load_dem(dem)
        h = float(_dem_height(sampler, eo.position[0:1], eo.position[1:2])[0])
        if not math.isfinite(h):
            h = float(np.nanmean(sampler.array))
        g = np.linspace(0.0, 1.0, 9)
        cols = -0.5 + g * camera.width
        rows = -0.5 + g * camera.height
        cc, rr = np.meshgrid(cols, rows)
        for _ in range(max_iter):
            pts = ray_at_height(cc.ravel(), rr.ravel(), h, camera, eo)
            z = _dem_height(sampler, pts[:, 0], pts[:, 1])
            if not np.isfinite(z).any():
                raise GeometryError(
                    "The image footprint lies outside the DEM (or over its nodata); use a DEM "
                    "that covers the images."
                )
            h_new = float(np.nanmean(z))
            done = abs(h_new - h) < 0.01
            h = h_new
            if done:
                break
    else:
        h = float(height)  # type: ignore[arg-type]
    col, row = outline_pixels(camera, per_edge).T
    return _polygon(ray_at_height(col, row, h, camera, eo)), h


def image_footprint(camera: Camera, eo: ExteriorOrientation, height: Optional[float] = None,
                    dem: DemLike = None) -> Polygon:
    """The image outline projected onto the terrain (plane at ``height`` or DEM mean height)."""
    return footprint_and_height(camera, eo, height=height, dem=dem)[0]


def block_bounds(project: Any) -> Tuple[float, float, float, float]:
    """Generous world bounds of all footprints (vertical images, terrain ≥ −500 m)."""
    xs, ys = [], []
    for rec in project.images:
        cam = project.cameras.get(rec.camera)
        if cam is None:
            continue
        half_diag = math.hypot(*cam.sensor_size) / 2.0
        r = 1.5 * max(rec.eo.position[2] + 500.0, 100.0) * half_diag / cam.focal_length
        xs += [rec.eo.position[0] - r, rec.eo.position[0] + r]
        ys += [rec.eo.position[1] - r, rec.eo.position[1] + r]
    if not xs:
        raise InputError("The project has no images with a known camera.")
    return min(xs), min(ys), max(xs), max(ys)


def _terrain_default(project: Any) -> float:
    th = getattr(project, "terrain_height", None)
    return 0.0 if th is None else float(th)


def block_footprints(project: Any, dem: DemLike = None, height: Optional[float] = None,
                     names: Optional[Sequence[str]] = None) -> Footprints:
    """Footprints and terrain heights of (some) images of a project.

    The terrain comes from ``dem`` (mean height under each footprint), else ``height``, else
    ``project.terrain_height``, else 0 m.
    """
    sampler = (load_dem(dem, block_bounds(project), crs=project.crs or None)
               if dem is not None else None)
    h = _terrain_default(project) if height is None else float(height)
    wanted = None if names is None else set(names)
    out: Footprints = {}
    for rec in project.images:
        if wanted is not None and rec.name not in wanted:
            continue
        cam = project.camera_of(rec)
        out[rec.name] = footprint_and_height(cam, rec.eo, height=h, dem=sampler)
    return out


def mean_terrain_height(footprints: Footprints) -> float:
    """Mean of the terrain heights under the footprints (m)."""
    return float(np.mean([h for _, h in footprints.values()]))


# -- model geometry --------------------------------------------------------------------------------
def _order(project: Any, a: str, b: str) -> Tuple[str, str]:
    ra, rb = project.image(a), project.image(b)
    base = rb.eo.position - ra.eo.position
    x_axis = ra.eo.rotation[:, 0] + rb.eo.rotation[:, 0]
    y_axis = ra.eo.rotation[:, 1] + rb.eo.rotation[:, 1]
    nb = np.linalg.norm(base)
    s = float(base @ x_axis) / max(np.linalg.norm(x_axis) * nb, 1e-300)
    if abs(s) < 0.1:
        s = -float(base @ y_axis)  # b lies "below" a in the images → a is left
    return (a, b) if s >= 0 else (b, a)


def model_geometry(project: Any, left: str, right: str, dem: DemLike = None,
                   footprints: Optional[Footprints] = None, kind: str = "manual",
                   order: bool = True, labels: Optional[Dict[str, str]] = None) -> Any:
    """A :class:`~..project.model.StereoModel` with base, B/H, overlap and GSD of two images.

    Parameters
    ----------
    project : Project
    left, right : str
        Image names; swapped when ``order`` and the base runs the other way (module notes).
    dem : path or DemSampler, optional
        Terrain; default ``project.terrain_height`` (else 0 m).
    footprints : dict, optional
        Precomputed :func:`block_footprints` (reused by detection).
    labels : dict, optional
        Precomputed :func:`image_labels` of the project's images (reused by detection).
    """
    from ..project.model import StereoModel

    if left == right:
        raise InputError(f"A stereo model needs two different images, not '{left}' twice.")
    if order:
        left, right = _order(project, left, right)
    fp = footprints if footprints is not None and left in footprints and right in footprints \
        else block_footprints(project, dem=dem, names=[left, right])
    (fl, hl), (fr, hr) = fp[left], fp[right]
    rl, rr = project.image(left), project.image(right)
    base = float(np.linalg.norm(rr.eo.position - rl.eo.position))
    H_l, H_r = rl.eo.position[2] - hl, rr.eo.position[2] - hr
    H = 0.5 * (H_l + H_r)
    inter = fl.intersection(fr).area
    smaller = min(fl.area, fr.area)
    overlap = inter / smaller if smaller > 0 else 0.0
    gsd = 0.5 * (float(project.camera_of(rl).gsd(H_l)) + float(project.camera_of(rr).gsd(H_r)))
    if labels is None:
        labels = image_labels([r.name for r in project.images])
    return StereoModel(name=f"{labels[left]}_{labels[right]}", left=left, right=right, kind=kind,
                       base=base, b_h=float(base / H) if H > 0 else float("nan"),
                       overlap=float(overlap), gsd=float(gsd), height_above_ground=float(H))


def overlap_polygon(project: Any, left: str, right: str, dem: DemLike = None,
                    footprints: Optional[Footprints] = None) -> Polygon:
    """The object-space overlap of two images: intersection of their footprints."""
    fp = footprints if footprints is not None and left in footprints and right in footprints \
        else block_footprints(project, dem=dem, names=[left, right])
    return fp[left][0].intersection(fp[right][0])


def manual_model(project: Any, left: str, right: str, dem: DemLike = None) -> Any:
    """A stereo model chosen by the operator (kind ``"manual"``); images must overlap.

    Raises
    ------
    GeometryError
        When the two footprints do not overlap.
    """
    m = model_geometry(project, left, right, dem=dem, kind="manual")
    if not m.overlap > 0:
        raise GeometryError(
            f"Images '{left}' and '{right}' do not overlap on the ground; choose two images "
            "that see the same area."
        )
    return m


# -- detection -------------------------------------------------------------------------------------
def _axial_diff(a: NDArray, b: NDArray) -> NDArray:
    """Smallest difference (rad) between axial directions (mod π)."""
    d = np.mod(np.asarray(a) - np.asarray(b), np.pi)
    return np.minimum(d, np.pi - d)


def dominant_direction(angles: NDArray, tolerance: float) -> float:
    """Mode of axial directions (rad, mod π): the direction with most others within
    ``tolerance`` (rad), refined by the doubled-angle mean of those inliers."""
    a = np.mod(np.asarray(angles, dtype=float), np.pi)
    counts = (_axial_diff(a[:, None], a[None, :]) <= tolerance).sum(axis=1)
    best = a[int(np.argmax(counts))]
    inl = a[_axial_diff(a, best) <= tolerance]
    return float(np.mod(0.5 * np.arctan2(np.sin(2 * inl).mean(), np.cos(2 * inl).mean()), np.pi))


def detect_stereo_models(
    project: Any,
    dem: DemLike = None,
    min_overlap: float = 0.25,
    b_h_range: Tuple[float, float] = (0.2, 1.2),
    strip_angle_tolerance: float = 20.0,
    in_strip_only: bool = False,
    footprints: Optional[Footprints] = None,
) -> List[Any]:
    """Find the stereo models of a block (rule and order in the module notes).

    Parameters
    ----------
    project : Project
    dem : path or DemSampler, optional
        Terrain for footprints; default ``project.terrain_height`` (else 0 m).
    min_overlap : float
        Minimum overlap (share of the smaller footprint, 0–1).
    b_h_range : (float, float)
        Accepted base-to-height ratios.
    strip_angle_tolerance : float
        Degrees between a base and the strip direction for an in-strip pair.
    in_strip_only : bool
        Return only in-strip pairs.

    Returns
    -------
    list of StereoModel
    """
    from scipy.spatial import cKDTree

    names = [r.name for r in project.images]
    if len(names) < 2:
        return []
    fp = footprints if footprints is not None else block_footprints(project, dem=dem)
    labels = image_labels(names)
    tol = math.radians(strip_angle_tolerance)
    centres = np.array([project.image(n).eo.position[:2] for n in names])
    radius = np.array([
        max(math.hypot(x - centres[i, 0], y - centres[i, 1])
            for x, y in fp[n][0].exterior.coords) if not fp[n][0].is_empty else 0.0
        for i, n in enumerate(names)
    ])
    tree = cKDTree(centres)
    _, nn = tree.query(centres, k=2)
    nn_vec = centres[nn[:, 1]] - centres
    nn_dir = np.arctan2(nn_vec[:, 1], nn_vec[:, 0])
    strip_dir = dominant_direction(nn_dir, tol)
    u = np.array([math.cos(strip_dir), math.sin(strip_dir)])
    if u[0] < -1e-12 or (abs(u[0]) <= 1e-12 and u[1] < 0):
        u = -u  # along-strip axis points east (or north): strips ordered north to south
    v = np.array([-u[1], u[0]])

    pairs = sorted(tree.query_pairs(2.0 * float(radius.max())))
    index = {n: i for i, n in enumerate(names)}
    strip_pairs: set = set()  # unordered pairs (i, j) with an in-strip base (any overlap)
    models = []
    for i, j in pairs:
        d = centres[j] - centres[i]
        if np.hypot(*d) > radius[i] + radius[j]:
            continue
        ang = math.atan2(d[1], d[0])
        in_strip = bool(_axial_diff(ang, strip_dir) <= tol) or bool(
            _axial_diff(ang, nn_dir[i]) <= tol and _axial_diff(ang, nn_dir[j]) <= tol)
        if in_strip:
            strip_pairs.add((i, j))
        if in_strip_only and not in_strip:
            continue
        if not fp[names[i]][0].intersects(fp[names[j]][0]):
            continue
        m = model_geometry(project, names[i], names[j], footprints=fp, labels=labels,
                           kind="in-strip" if in_strip else "cross-strip")
        if m.overlap >= min_overlap and b_h_range[0] <= m.b_h <= b_h_range[1]:
            models.append(m)

    # neighbours: no image k of the same strip between i and j along their base
    partners: Dict[int, List[int]] = {}
    for i, j in strip_pairs:
        partners.setdefault(i, []).append(j)
        partners.setdefault(j, []).append(i)

    def is_neighbour(i: int, j: int) -> bool:
        d = centres[j] - centres[i]
        dd = float(d @ d)
        for k in partners.get(i, []):
            if k != j and (min(i, k), max(i, k)) in strip_pairs and \
                    (min(j, k), max(j, k)) in strip_pairs:
                t = float((centres[k] - centres[i]) @ d) / dd
                if 0.0 < t < 1.0:
                    return False
        return True

    # strips: connected components of neighbouring in-strip pairs
    parent = list(range(len(names)))

    def find(a: int) -> int:
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    rank: Dict[str, int] = {}
    for m in models:
        if m.kind == "in-strip":
            i, j = index[m.left], index[m.right]
            rank[m.name] = 0 if is_neighbour(i, j) else 1
            if rank[m.name] == 0:
                parent[find(i)] = find(j)
    perp = centres @ v
    along = centres @ u
    strip_key: Dict[int, float] = {}
    for i in range(len(names)):
        r = find(i)
        strip_key[r] = min(strip_key.get(r, math.inf), -float(perp[i]))

    def key(m: Any) -> Tuple:
        i, j = index[m.left], index[m.right]
        if m.kind == "in-strip":
            return (rank[m.name], strip_key[find(i)], 0.5 * (along[i] + along[j]), 0.0)
        return (2, 0.0, 0.0, -m.overlap)

    models.sort(key=key)
    return models


__all__ = [
    "block_bounds",
    "block_footprints",
    "detect_stereo_models",
    "dominant_direction",
    "footprint_and_height",
    "image_footprint",
    "image_labels",
    "load_dem",
    "manual_model",
    "mean_terrain_height",
    "model_geometry",
    "outline_pixels",
    "overlap_polygon",
]
