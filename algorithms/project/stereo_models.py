r"""Stereo models of a project: base, B/H, overlap, and their automatic detection.

Footprints come from :mod:`..geometry.stereo` (the image outline on the terrain).

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
       (radius = farthest footprint vertex from the projection centre, so a tilted frame that
       looks far to one side still finds its partners; k-d tree), with overlap *on the
       terrain* ≥ ``min_overlap``, B/H inside ``b_h_range`` and optical axes at most
       ``max_convergence`` apart (the convergence angle; drone and oblique pairs of 20–60° are
       models like vertical ones). Every model reports its convergence and B/H.
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
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Set, Tuple, Union

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree
from shapely.geometry import Polygon

from ..errors import GeometryError, InputError
from ..feedback import Feedback, ensure_feedback
from ..geometry.epipolar import convergence_deg
from ..geometry.stereo import (
    DemLike,
    Footprints,
    axial_diff,
    dominant_direction,
    footprint_and_height,
    load_dem,
)
from .model import Project, StereoModel

Pair = Tuple[int, int]


def image_labels(names: Sequence[str]) -> Dict[str, str]:
    """Short unique labels of image names, for model names.

    Names are split into tokens at ``_``, ``-`` and ``.``; the tokens that every name shares at
    its start and at its end are dropped. If the last remaining token alone is unique, it is the
    label (``0182`` for ``3324c_2015_1004_05_0182_RGB``); otherwise the remaining tokens joined
    by ``_``. Names that would lose uniqueness keep their full form.
    """
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


# -- footprints of a project -----------------------------------------------------------------------
def block_bounds(project: Project) -> Tuple[float, float, float, float]:
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


def _terrain_default(project: Project) -> float:
    th = getattr(project, "terrain_height", None)
    return 0.0 if th is None else float(th)


def block_footprints(project: Project, dem: DemLike = None, height: Optional[float] = None,
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


def _pair_footprints(project: Project, left: str, right: str, dem: DemLike,
                     footprints: Optional[Footprints]) -> Footprints:
    """``footprints`` when they hold both images, else the two footprints computed."""
    if footprints is not None and left in footprints and right in footprints:
        return footprints
    return block_footprints(project, dem=dem, names=[left, right])


# -- model geometry --------------------------------------------------------------------------------
def _order(project: Project, a: str, b: str) -> Tuple[str, str]:
    ra, rb = project.image(a), project.image(b)
    base = rb.eo.position - ra.eo.position
    x_axis = ra.eo.rotation[:, 0] + rb.eo.rotation[:, 0]
    y_axis = ra.eo.rotation[:, 1] + rb.eo.rotation[:, 1]
    nb = np.linalg.norm(base)
    s = float(base @ x_axis) / max(np.linalg.norm(x_axis) * nb, 1e-300)
    if abs(s) < 0.1:
        s = -float(base @ y_axis)  # b lies "below" a in the images → a is left
    return (a, b) if s >= 0 else (b, a)


#: Tilt (°) from which a model's GSD is taken at its overlap instead of below the camera.
TILTED_DEG = 5.0


def _image_gsd(project: Project, rec: Any, height: float, centre: Optional[NDArray]) -> float:
    r"""GSD (m) of one image of a model: :math:`H c/\delta` for a (near-)vertical image; for a
    tilted one (> :data:`TILTED_DEG`) at the model's overlap centre, the distance D along the
    ray scaled by the foreshortening of the ground, :math:`D/(f\sqrt{\cos i})` (i the ray's
    angle from the vertical; geometric mean of the two ground directions)."""
    cam = project.camera_of(rec)
    tilt = math.degrees(math.acos(float(np.clip(rec.eo.rotation[2, 2], -1.0, 1.0))))
    if tilt <= TILTED_DEG or centre is None:
        return float(cam.gsd(height))
    ray = centre - rec.eo.position
    dist = float(np.linalg.norm(ray))
    cos_i = abs(float(ray[2])) / dist
    return dist / cam.focal_length_px / math.sqrt(max(cos_i, 0.1))


def model_geometry(project: Project, left: str, right: str, dem: DemLike = None,
                   footprints: Optional[Footprints] = None, kind: str = "manual",
                   order: bool = True, labels: Optional[Dict[str, str]] = None) -> StereoModel:
    """A :class:`~.model.StereoModel` with base, B/H, overlap and GSD of two images.

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
    if left == right:
        raise InputError(f"A stereo model needs two different images, not '{left}' twice.")
    if order:
        left, right = _order(project, left, right)
    fp = _pair_footprints(project, left, right, dem, footprints)
    (fl, hl), (fr, hr) = fp[left], fp[right]
    rl, rr = project.image(left), project.image(right)
    base = float(np.linalg.norm(rr.eo.position - rl.eo.position))
    H_l, H_r = rl.eo.position[2] - hl, rr.eo.position[2] - hr
    H = 0.5 * (H_l + H_r)
    inter = fl.intersection(fr).area
    smaller = min(fl.area, fr.area)
    overlap = inter / smaller if smaller > 0 else 0.0
    centre = None
    if not fl.intersection(fr).is_empty:
        c = fl.intersection(fr).centroid
        centre = np.array([c.x, c.y, 0.5 * (hl + hr)])
    gsd = 0.5 * (_image_gsd(project, rl, H_l, centre) + _image_gsd(project, rr, H_r, centre))
    if labels is None:
        labels = image_labels([r.name for r in project.images])
    return StereoModel(name=f"{labels[left]}_{labels[right]}", left=left, right=right, kind=kind,
                       base=base, b_h=float(base / H) if H > 0 else float("nan"),
                       overlap=float(overlap), gsd=float(gsd), height_above_ground=float(H),
                       convergence=convergence_deg(rl.eo, rr.eo))


def overlap_polygon(project: Project, left: str, right: str, dem: DemLike = None,
                    footprints: Optional[Footprints] = None) -> Polygon:
    """The object-space overlap of two images: intersection of their footprints."""
    fp = _pair_footprints(project, left, right, dem, footprints)
    return fp[left][0].intersection(fp[right][0])


def manual_model(project: Project, left: str, right: str, dem: DemLike = None) -> StereoModel:
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
@dataclass
class _Layout:
    """Where the images of a block lie: projection centres, footprint radii, the k-d tree of
    the centres, every image's nearest-neighbour direction, the strip direction and the axes
    along (``u``, pointing east or north) and across (``v``) the strips."""

    names: List[str]
    centres: NDArray[np.float64]
    radius: NDArray[np.float64]
    tree: cKDTree
    nn_dir: NDArray[np.float64]
    strip_dir: float
    u: NDArray[np.float64]
    v: NDArray[np.float64]

    @classmethod
    def of(cls, project: Project, names: List[str], fp: Footprints, tol: float) -> _Layout:
        """The layout of the images ``names`` with footprints ``fp``; ``tol`` in rad."""
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
        return cls(names, centres, radius, tree, nn_dir, strip_dir, u, v)

    def in_strip(self, i: int, j: int, tol: float) -> bool:
        """Whether the base i → j runs along the strips or along both images' own
        nearest-neighbour directions (module notes)."""
        d = self.centres[j] - self.centres[i]
        ang = math.atan2(d[1], d[0])
        return bool(axial_diff(ang, self.strip_dir) <= tol) or bool(
            axial_diff(ang, self.nn_dir[i]) <= tol and axial_diff(ang, self.nn_dir[j]) <= tol)


@dataclass
class _Criteria:
    """The acceptance rule of a candidate model (see :func:`detect_stereo_models`)."""

    min_overlap: float
    b_h_range: Tuple[float, float]
    tol: float
    in_strip_only: bool
    max_convergence: float = 60.0

    def accepts(self, m: StereoModel) -> bool:
        """Enough overlap on the terrain, a useful B/H, optical axes not too far apart."""
        return (m.overlap >= self.min_overlap
                and self.b_h_range[0] <= m.b_h <= self.b_h_range[1]
                and not m.convergence > self.max_convergence)


def _candidate_models(project: Project, lay: _Layout, fp: Footprints, crit: _Criteria
                      ) -> Tuple[List[StereoModel], Set[Pair]]:
    """The accepted models (in k-d tree pair order) and all in-strip pairs (i, j), i < j,
    of images close enough to overlap, whether their models were accepted or not."""
    labels = image_labels(lay.names)
    names, centres, radius = lay.names, lay.centres, lay.radius
    strip_pairs: Set[Pair] = set()
    models = []
    for i, j in sorted(lay.tree.query_pairs(2.0 * float(radius.max()))):
        d = centres[j] - centres[i]
        if np.hypot(*d) > radius[i] + radius[j]:
            continue
        in_strip = lay.in_strip(i, j, crit.tol)
        if in_strip:
            strip_pairs.add((i, j))
        if crit.in_strip_only and not in_strip:
            continue
        if not fp[names[i]][0].intersects(fp[names[j]][0]):
            continue
        m = model_geometry(project, names[i], names[j], footprints=fp, labels=labels,
                           kind="in-strip" if in_strip else "cross-strip")
        if crit.accepts(m):
            models.append(m)
    return models, strip_pairs


class _StripOrder:
    """The order of detected models (module notes, step 3).

    In-strip pairs with no image of the strip between them are *neighbours* (rank 0, other
    in-strip pairs rank 1, cross-strip pairs rank 2); strips are the connected components of
    neighbouring pairs (union–find), ordered by their northernmost image across the strips.
    """

    def __init__(self, lay: _Layout, strip_pairs: Set[Pair], models: List[StereoModel]) -> None:
        self.lay = lay
        self.index = {n: i for i, n in enumerate(lay.names)}
        self.strip_pairs = strip_pairs
        self.partners: Dict[int, List[int]] = {}
        for i, j in strip_pairs:
            self.partners.setdefault(i, []).append(j)
            self.partners.setdefault(j, []).append(i)
        self.parent = list(range(len(lay.names)))
        self.rank: Dict[str, int] = {}
        for m in models:
            if m.kind == "in-strip":
                i, j = self.index[m.left], self.index[m.right]
                self.rank[m.name] = 0 if self.is_neighbour(i, j) else 1
                if self.rank[m.name] == 0:
                    self.parent[self.find(i)] = self.find(j)
        perp = lay.centres @ lay.v
        self.along = lay.centres @ lay.u
        self.strip_key: Dict[int, float] = {}
        for i in range(len(lay.names)):
            r = self.find(i)
            self.strip_key[r] = min(self.strip_key.get(r, math.inf), -float(perp[i]))

    def is_neighbour(self, i: int, j: int) -> bool:
        """No image k of the same strip lies between i and j along their base."""
        centres, pairs = self.lay.centres, self.strip_pairs
        d = centres[j] - centres[i]
        dd = float(d @ d)
        for k in self.partners.get(i, []):
            if k != j and (min(i, k), max(i, k)) in pairs and (min(j, k), max(j, k)) in pairs:
                t = float((centres[k] - centres[i]) @ d) / dd
                if 0.0 < t < 1.0:
                    return False
        return True

    def find(self, a: int) -> int:
        """The root of image ``a``'s strip (with path halving)."""
        parent = self.parent
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    def key(self, m: StereoModel) -> Tuple:
        """Sort key: rank, strip, position along the strip; cross-strip by overlap."""
        i, j = self.index[m.left], self.index[m.right]
        if m.kind == "in-strip":
            return (self.rank[m.name], self.strip_key[self.find(i)],
                    0.5 * (self.along[i] + self.along[j]), 0.0)
        return (2, 0.0, 0.0, -m.overlap)


def detect_stereo_models(
    project: Project,
    dem: DemLike = None,
    min_overlap: float = 0.25,
    b_h_range: Tuple[float, float] = (0.2, 1.2),
    strip_angle_tolerance: float = 20.0,
    in_strip_only: bool = False,
    footprints: Optional[Footprints] = None,
    max_convergence: float = 60.0,
) -> List[StereoModel]:
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
    footprints : dict, optional
        Precomputed :func:`block_footprints` of all images.
    max_convergence : float
        Largest angle (°) between the two optical axes: convergent drone or oblique pairs up to
        it are models when their overlap on the terrain and B/H are useful; beyond it the two
        views of a surface differ too much to match.

    Returns
    -------
    list of StereoModel
        Each with its ``convergence`` (°) and B/H.
    """
    names = [r.name for r in project.images]
    if len(names) < 2:
        return []
    fp = footprints if footprints is not None else block_footprints(project, dem=dem)
    tol = math.radians(strip_angle_tolerance)
    lay = _Layout.of(project, names, fp, tol)
    crit = _Criteria(min_overlap, b_h_range, tol, in_strip_only, max_convergence)
    models, strip_pairs = _candidate_models(project, lay, fp, crit)
    models.sort(key=_StripOrder(lay, strip_pairs, models).key)
    return models


__all__ = [
    "block_bounds",
    "block_footprints",
    "detect_stereo_models",
    "image_labels",
    "manual_model",
    "model_geometry",
    "overlap_polygon",
]


def _manual_pairs(text: Optional[str]) -> List[Tuple[str, str]]:
    """Pairs ``'left,right; left,right'`` (newlines also separate pairs)."""
    pairs = []
    for pair in (text or "").replace("\n", ";").split(";"):
        if not pair.strip():
            continue
        parts = [p.strip() for p in pair.split(",")]
        if len(parts) != 2:
            raise InputError(f"Manual pair '{pair.strip()}': give two image names "
                             "separated by a comma, pairs separated by ';'.")
        pairs.append((parts[0], parts[1]))
    return pairs


def run_stereo_models(project_path: Union[str, Path], *, detect: bool = True,
                      min_overlap: float = 0.25, b_h_range: Tuple[float, float] = (0.2, 1.2),
                      strip_angle_tolerance: float = 20.0, in_strip_only: bool = False,
                      manual: Optional[str] = None, dem: Optional[Union[str, Path]] = None,
                      feedback: Optional[Feedback] = None,
                      max_convergence: float = 60.0) -> Dict[str, Any]:
    """Set a project's stereo models (detected and/or manual) and save ``project.toml``.

    Parameters
    ----------
    project_path : str or Path
        Project folder or ``project.toml``.
    detect : bool
        Detect models from the footprints (:func:`detect_stereo_models`).
    min_overlap : float
        Minimum overlap as a share (0–1) of the smaller footprint.
    b_h_range : (float, float)
        Accepted base-to-height ratios.
    strip_angle_tolerance : float
        Degrees between a base and the strip direction for an in-strip pair.
    in_strip_only : bool
        Keep in-strip models only.
    manual : str, optional
        Pairs ``'left,right; left,right'`` by image name or short label, added as ``manual``.
    dem : path, optional
        DEM for terrain heights and footprints; default the project's terrain height.
    feedback : Feedback, optional
        Progress and messages.
    max_convergence : float
        Largest angle (°) between the optical axes of a detected model.

    Returns
    -------
    dict
        ``models`` (as in ``project.toml``), ``count`` and ``unpaired`` image names.
    """
    feedback = ensure_feedback(feedback)
    project = Project.load(project_path)
    if b_h_range[0] >= b_h_range[1]:
        raise InputError(f"Minimum B/H ({b_h_range[0]:g}) must be below the maximum "
                         f"({b_h_range[1]:g}).")
    surface = load_dem(dem, block_bounds(project), crs=project.crs) if dem else None
    models: List[StereoModel] = []
    if detect:
        models = detect_stereo_models(
            project, dem=surface, min_overlap=min_overlap, b_h_range=b_h_range,
            strip_angle_tolerance=strip_angle_tolerance, in_strip_only=in_strip_only,
            max_convergence=max_convergence)
    feedback.progress(60)
    by_label = {label: name for name, label in
                image_labels([r.name for r in project.images]).items()}
    seen = {frozenset((m.left, m.right)) for m in models}
    for left, right in _manual_pairs(manual):
        left, right = by_label.get(left, left), by_label.get(right, right)
        m = manual_model(project, project.image(left).name, project.image(right).name,
                         dem=surface)
        if frozenset((m.left, m.right)) not in seen:
            seen.add(frozenset((m.left, m.right)))
            models.append(m)
    project.models = models
    project.save()  # atomic: the old project.toml stays until the new one is complete
    paired = {m.left for m in models} | {m.right for m in models}
    unpaired = [r.name for r in project.images if r.name not in paired]
    for name in unpaired:
        feedback.warning(f"Image '{name}' has no stereo partner.")
    feedback.info(f"{len(models)} stereo models written to {project.project_file}.")
    return {"models": [m.to_dict() for m in models], "count": len(models),
            "unpaired": unpaired}
