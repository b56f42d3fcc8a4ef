r"""Objects of a synthetic scene: embankment, ditch, road, fields, buildings, trees, check points.

All heights are written into the truth rasters on the fine grid; the vector truth (footprints,
3-D breaklines, check points) is kept alongside.

* **Embankment** — trapezoid on the terrain along a straight axis: crest height
  :math:`h_e` = 5.5–7.5 m, crest width 8–10 m, side slopes 1 : 1.5, so at signed distance
  :math:`d` from the axis :math:`\Delta z = h_e - \max(0, |d| - w_c/2)/1.5` (clipped at 0).
  Breaklines: both crest edges (``embankment_crest``) and both toes (``embankment_toe``).
* **Ditch** — trapezoid cut: depth 2–3 m, top width 6–10 m, bottom width 2 m; breaklines at
  both top edges (``ditch_edge``) and the bottom edges (``ditch_bottom``).
* **Road** — 6 m wide, at ground level, parallel to the embankment.
* **Buildings** — rectangles 8×10 … 12×16 m, gabled (ridge along the long side, pitch 30–45°,
  eaves 5–7 m) or flat (4–10 m). Each stands on a level platform: the DTM inside the footprint
  is set to the footprint's mean height and blended back over 4 m around it, so that
  DSM − DTM inside the footprint equals the roof height exactly outside the chimneys.
  Every block mixes roof looks (:data:`ROOF_STYLES`, see :mod:`.texture`); some gabled roofs
  carry chimneys (0.5–0.7 m square, flat top 1–1.5 m above the highest roof point under them),
  burned into the DSM as rendered.
* **Trees** — isolated crowns (height 5–15 m, radius 2–5 m, profile
  :math:`h\,(1 - (d/r)^2)^{0.6}`) and a closed forest patch (dense crowns 12–20 m). Crowns
  carry leaf clumps (relief ±0.2–0.4 m at λ ≈ 0.6 m, so the shading textures them) and about
  half of the isolated trees (a fifth in the forest) are sparse: gaps of λ ≈ 1.5 m covering
  15–35 % of the crown where the DSM is the ground and the land cover stays the ground's.
* **Land cover** codes: :data:`LANDCOVER`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Tuple

import numpy as np
from scipy import ndimage
from shapely.geometry import Point

from ..raster.sample import bilinear_grid
from .terrain import Grid, band_noise

#: Land-cover class codes of ``truth/landcover.tif``.
LANDCOVER: Dict[int, str] = {
    0: "nodata",
    1: "open (meadow, bare ground, rock)",
    2: "road",
    3: "building",
    4: "tree / forest",
    5: "water / ditch",
    6: "embankment",
    7: "field",
}
OPEN, ROAD, BUILDING, TREE, WATER, EMBANKMENT, FIELD = 1, 2, 3, 4, 5, 6, 7
#: The land-cover classes a DSM's object interior is judged on apart (roofs and crowns:
#: ``objects_run.object_metrics(cover_classes=…)``; one figure hides which of them is lost).
INTERIOR_CLASSES: Dict[str, Tuple[int, ...]] = {"buildings": (BUILDING,), "crowns": (TREE,)}
#: Map colours of the land-cover codes (the legend style written beside the raster).
LANDCOVER_COLOURS: Dict[int, str] = {1: "#c7dc8f", 2: "#8c8c8c", 3: "#d6604d", 4: "#1b7837",
                                     5: "#4393c3", 6: "#b08850", 7: "#f0d98a"}

#: Field (parcel) types used by the texture: meadow, furrowed, crop, bare soil.
PARCEL_TYPES = ("meadow", "furrowed", "crop", "bare")

#: Roof looks per roof type; the first of each is the plain look of earlier versions.
ROOF_STYLES: Dict[str, Tuple[str, ...]] = {
    "gabled": ("stripes", "tiles", "two_tone"),
    "flat": ("plain", "gravel", "fixtures"),
}


@dataclass
class Line:
    """A straight axis: point (x, y) and direction angle ``a`` (radians, from +X)."""

    x: float
    y: float
    a: float

    @property
    def e(self) -> np.ndarray:
        return np.array([np.cos(self.a), np.sin(self.a)])

    @property
    def n(self) -> np.ndarray:
        return np.array([-np.sin(self.a), np.cos(self.a)])

    def across(self, X: np.ndarray, Y: np.ndarray) -> np.ndarray:
        """Signed distance from the axis (left of the direction is positive)."""
        n = self.n
        return (X - self.x) * n[0] + (Y - self.y) * n[1]

    def along(self, X: np.ndarray, Y: np.ndarray) -> np.ndarray:
        e = self.e
        return (X - self.x) * e[0] + (Y - self.y) * e[1]

    def offset_polyline(self, offset: float, grid: Grid, spacing: float) -> Optional[np.ndarray]:
        """Vertices (N, 2) of the parallel at ``offset`` inside the grid (1 cell margin)."""
        xmin, ymin, xmax, ymax = grid.bounds
        m = 1.5 * grid.cell
        xmin, ymin, xmax, ymax = xmin + m, ymin + m, xmax - m, ymax - m
        p = np.array([self.x, self.y]) + offset * self.n
        e = self.e
        lo, hi = -np.inf, np.inf
        for k, (a, b) in enumerate(((xmin, xmax), (ymin, ymax))):
            if abs(e[k]) < 1e-12:
                if not a <= p[k] <= b:
                    return None
                continue
            s0, s1 = sorted(((a - p[k]) / e[k], (b - p[k]) / e[k]))
            lo, hi = max(lo, s0), min(hi, s1)
        if not hi - lo > spacing:
            return None
        n = int(np.ceil((hi - lo) / spacing)) + 1
        s = np.linspace(lo, hi, n)
        return p[None, :] + s[:, None] * e[None, :]


@dataclass
class Building:
    id: int
    x: float
    y: float
    angle: float  # long axis direction (radians)
    length: float
    width: float
    roof: str  # "gabled" | "flat"
    height: float  # eaves (flat: roof) height above the platform (m)
    ridge_height: float  # highest point above the platform (m)
    base_z: float = 0.0
    style: str = ""  # one of ROOF_STYLES[roof]; "" is the plain look
    texture_seed: int = 0  # seed of per-tile brightness and fixture layout
    chimneys: List[Tuple[float, float, float, float]] = field(default_factory=list)
    # chimneys: (u, v) centre in the building frame, side (m), top height above the platform

    def corners(self) -> np.ndarray:
        """Footprint corners (4, 2), counter-clockwise."""
        e = np.array([np.cos(self.angle), np.sin(self.angle)])
        n = np.array([-e[1], e[0]])
        hl, hw = self.length / 2.0, self.width / 2.0
        c = np.array([self.x, self.y])
        return np.array([c - hl * e - hw * n, c + hl * e - hw * n, c + hl * e + hw * n,
                         c - hl * e + hw * n])

    @property
    def radius(self) -> float:
        return 0.5 * float(np.hypot(self.length, self.width))

    def local(self, X: np.ndarray, Y: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
        """Coordinates along (u) and across (v) the long axis from the centre."""
        c, s = np.cos(self.angle), np.sin(self.angle)
        dx, dy = X - self.x, Y - self.y
        return dx * c + dy * s, -dx * s + dy * c

    def roof_height(self, v: np.ndarray) -> np.ndarray:
        """Roof height above the platform at across-axis coordinate v (inside the footprint)."""
        if self.roof == "flat":
            return np.full(np.shape(v), self.height)
        return self.height + (self.ridge_height - self.height) * (
            1.0 - np.abs(v) / (self.width / 2.0))


@dataclass
class SceneObjects:
    """Everything placed on the terrain, for texture and truth output."""

    embankment: Line
    embankment_height: float
    crest_width: float
    ditch: Line
    ditch_depth: float
    ditch_top: float
    ditch_bottom: float
    road: Line
    road_width: float
    parcel_angle: float
    parcel_size: Tuple[float, float]
    parcel_types: np.ndarray  # (nu, nv) type index into PARCEL_TYPES
    parcel_origin: Tuple[float, float]
    buildings: List[Building] = field(default_factory=list)
    trees: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))  # x, y, radius, height
    tree_sparse: np.ndarray = field(default_factory=lambda: np.zeros(0))  # gap share per tree
    breaklines: List[Tuple[str, np.ndarray]] = field(default_factory=list)  # kind, (N, 3)

    @property
    def toe_half_width(self) -> float:
        return self.crest_width / 2.0 + 1.5 * self.embankment_height


def _parcels(grid: Grid, obj: SceneObjects) -> Tuple[np.ndarray, np.ndarray]:
    """Parcel indices (iu, iv) of every cell."""
    c, s = np.cos(obj.parcel_angle), np.sin(obj.parcel_angle)
    dx = grid.xs - obj.parcel_origin[0]
    dy = grid.ys - obj.parcel_origin[1]
    iu = np.floor((dx * c + dy * s) / obj.parcel_size[0]).astype(np.int64)
    iv = np.floor((-dx * s + dy * c) / obj.parcel_size[1]).astype(np.int64)
    nu, nv = obj.parcel_types.shape
    return np.clip(iu, 0, nu - 1), np.clip(iv, 0, nv - 1)


def parcel_type_map(grid: Grid, obj: SceneObjects) -> np.ndarray:
    """Parcel type index (uint8) of every cell, see :data:`PARCEL_TYPES`."""
    iu, iv = _parcels(grid, obj)
    return obj.parcel_types[iu, iv].astype(np.uint8)


#: Distance (m) of placed objects from the edge of the grid.
_EDGE_MARGIN = 8.0


def _linear_features(grid: Grid, rng: np.random.Generator, extent_core: float) -> SceneObjects:
    """Draw the embankment, the ditch, the road and the parcels (no terrain change yet)."""
    xmin, ymin, xmax, ymax = grid.bounds
    cx, cy = (xmin + xmax) / 2.0, (ymin + ymax) / 2.0
    a_e = rng.uniform(np.radians(20), np.radians(70)) * rng.choice([-1.0, 1.0])
    n_e = np.array([-np.sin(a_e), np.cos(a_e)])
    off_e = rng.uniform(0.15, 0.25) * extent_core
    emb = Line(cx - off_e * n_e[0], cy - off_e * n_e[1], a_e)
    h_e, w_c = rng.uniform(5.5, 7.5), rng.uniform(8.0, 10.0)
    off_d = rng.uniform(0.2, 0.28) * extent_core
    ditch = Line(cx + off_d * n_e[0], cy + off_d * n_e[1], a_e + rng.uniform(-0.05, 0.05))
    depth, top_w, bot_w = rng.uniform(2.0, 3.0), rng.uniform(6.0, 10.0), 2.0
    toe = w_c / 2.0 + 1.5 * h_e
    road_w = 6.0
    road = Line(emb.x + (toe + 4.0 + road_w / 2.0) * n_e[0],
                emb.y + (toe + 4.0 + road_w / 2.0) * n_e[1], a_e)

    # parcels in a frame aligned with the road
    pu, pv = rng.uniform(30.0, 60.0), rng.uniform(18.0, 35.0)
    diag = float(np.hypot(xmax - xmin, ymax - ymin))
    porigin = (cx - diag * (np.cos(a_e) - np.sin(a_e)) / 2.0 * 1.0,
               cy - diag * (np.sin(a_e) + np.cos(a_e)) / 2.0 * 1.0)
    nu, nv = int(np.ceil(2 * diag / pu)) + 1, int(np.ceil(2 * diag / pv)) + 1
    ptypes = rng.choice(len(PARCEL_TYPES), size=(nu, nv), p=[0.35, 0.3, 0.2, 0.15])
    return SceneObjects(emb, h_e, w_c, ditch, depth, top_w, bot_w, road, road_w, a_e, (pu, pv),
                        ptypes, porigin)


def _shape_linear_features(grid: Grid, dtm: np.ndarray, obj: SceneObjects) -> np.ndarray:
    """Raise the embankment and cut the ditch into ``dtm`` (in place); return the land cover."""
    X, Y = grid.xs, grid.ys
    h_e, w_c, toe = obj.embankment_height, obj.crest_width, obj.toe_half_width
    top_w, bot_w, depth = obj.ditch_top, obj.ditch_bottom, obj.ditch_depth
    d_e = obj.embankment.across(X, Y)
    dtm += np.clip(h_e - np.maximum(np.abs(d_e) - w_c / 2.0, 0.0) / 1.5, 0.0, None)
    d_d = obj.ditch.across(X, Y)
    cut = np.clip((top_w / 2.0 - np.abs(d_d)) / ((top_w - bot_w) / 2.0), 0.0, 1.0) * depth
    dtm -= cut

    ptype = parcel_type_map(grid, obj)
    landcover = np.where(ptype == 0, OPEN, FIELD).astype(np.uint8)
    del ptype
    landcover[np.abs(obj.road.across(X, Y)) <= obj.road_width / 2.0] = ROAD
    landcover[np.abs(d_e) <= toe] = EMBANKMENT
    landcover[np.abs(d_d) <= top_w / 2.0] = WATER
    return landcover


def _clear_of_lines(obj: SceneObjects, px: float, py: float, r: float) -> bool:
    """Is a disc of radius ``r`` at (px, py) clear of the embankment, ditch and road?"""
    return (abs(float(obj.embankment.across(px, py))) > obj.toe_half_width + r + 3.0
            and abs(float(obj.ditch.across(px, py))) > obj.ditch_top / 2.0 + r + 3.0
            and abs(float(obj.road.across(px, py))) > obj.road_width / 2.0 + r + 2.0)


def _place_forest(grid: Grid, obj: SceneObjects, rng: np.random.Generator, extent_core: float,
                  taken: List[Tuple[float, float, float]]
                  ) -> List[Tuple[float, float, float, float]]:
    """Trees (x, y, radius, height) of one forest patch, placed first: it needs the most room."""
    xmin, ymin, xmax, ymax = grid.bounds
    margin = _EDGE_MARGIN
    trees: List[Tuple[float, float, float, float]] = []
    radius_f = float(np.clip(0.1 * extent_core, 10.0, 60.0))
    for _ in range(500):
        fx = rng.uniform(xmin + radius_f + margin, xmax - radius_f - margin)
        fy = rng.uniform(ymin + radius_f + margin, ymax - radius_f - margin)
        if _clear_of_lines(obj, fx, fy, radius_f) and all(
                np.hypot(fx - tx, fy - ty) > radius_f + tr for tx, ty, tr in taken):
            break
    else:
        return trees
    taken.append((fx, fy, radius_f + 4.0))
    spacing = 4.5
    g = np.arange(-radius_f, radius_f + 1e-9, spacing)
    gx, gy = np.meshgrid(g, g)
    gx = gx + rng.uniform(-1.2, 1.2, gx.shape)
    gy = gy + rng.uniform(-1.2, 1.2, gy.shape)
    ecc = rng.uniform(0.7, 1.0)
    keep = (gx / radius_f) ** 2 + (gy / (ecc * radius_f)) ** 2 <= 1.0
    for tx, ty in zip(gx[keep], gy[keep]):
        trees.append((fx + tx, fy + ty, rng.uniform(2.5, 4.0), rng.uniform(12.0, 20.0)))
    return trees


def _place_buildings(grid: Grid, obj: SceneObjects, rng: np.random.Generator, area: float,
                     taken: List[Tuple[float, float, float]]) -> None:
    """Append buildings to ``obj`` (one per 2500 m², 4 … 400) where there is room."""
    xmin, ymin, xmax, ymax = grid.bounds
    margin = _EDGE_MARGIN
    n_buildings = int(np.clip(area / 2500.0, 4, 400))
    for _ in range(40 * n_buildings):
        if len(obj.buildings) >= n_buildings:
            break
        length, width = rng.uniform(10.0, 16.0), rng.uniform(8.0, 12.0)
        if width > length:
            length, width = width, length
        px = rng.uniform(xmin + margin + length, xmax - margin - length)
        py = rng.uniform(ymin + margin + length, ymax - margin - length)
        r = 0.5 * float(np.hypot(length, width)) + 5.0
        if not _clear_of_lines(obj, px, py, r):
            continue
        if any(np.hypot(px - tx, py - ty) < r + tr for tx, ty, tr in taken):
            continue
        # both roof types always occur: the first two buildings are flat, then gabled
        gabled = rng.uniform() < 0.65 if len(obj.buildings) > 1 else len(obj.buildings) == 1
        if gabled:
            eaves = rng.uniform(5.0, 7.0)
            ridge = eaves + 0.5 * width * np.tan(np.radians(rng.uniform(30.0, 45.0)))
        else:
            eaves = ridge = rng.uniform(4.0, 10.0)
        angle = obj.parcel_angle + rng.choice([0.0, np.pi / 2]) + rng.normal(0.0, np.radians(3.0))
        b = Building(len(obj.buildings) + 1, px, py, float(angle), length, width,
                     "gabled" if gabled else "flat", float(eaves), float(ridge))
        taken.append((px, py, r))
        obj.buildings.append(b)


def _level_platforms(grid: Grid, dtm: np.ndarray, obj: SceneObjects) -> None:
    """Level the ground under every building (in place), blended over 4 m; sets ``base_z``."""
    X, Y = grid.xs, grid.ys
    for b in obj.buildings:
        rows, cols = grid.window(b.x - b.radius - 6, b.y - b.radius - 6, b.x + b.radius + 6,
                                 b.y + b.radius + 6)
        u, v = b.local(X[:, cols], Y[rows, :])
        inside = (np.abs(u) <= b.length / 2.0) & (np.abs(v) <= b.width / 2.0)
        sub = dtm[rows, cols]
        b.base_z = float(sub[inside].mean()) if inside.any() else float(sub.mean())
        dist = np.hypot(np.maximum(np.abs(u) - b.length / 2.0, 0.0),
                        np.maximum(np.abs(v) - b.width / 2.0, 0.0))
        w = np.clip(1.0 - (dist - 1.0) / 4.0, 0.0, 1.0)
        dtm[rows, cols] = w * b.base_z + (1.0 - w) * sub


def _decorate_buildings(obj: SceneObjects, rng: np.random.Generator) -> None:
    """Roof style, texture seed and chimneys of every building (from the detail stream).

    Styles cycle through :data:`ROOF_STYLES` from a random start, so every block with three or
    more roofs of a type has the plain look and the textured ones.
    """
    start = {k: int(rng.integers(len(v))) for k, v in ROOF_STYLES.items()}
    count = dict.fromkeys(ROOF_STYLES, 0)
    for b in obj.buildings:
        styles = ROOF_STYLES[b.roof]
        b.style = styles[(start[b.roof] + count[b.roof]) % len(styles)]
        count[b.roof] += 1
        b.texture_seed = int(rng.integers(2 ** 31))
        # two thirds of the gabled roofs carry chimneys, the first one always
        if b.roof != "gabled" or (rng.uniform() < 0.35 and any(o.chimneys for o in obj.buildings)):
            continue
        half = b.width / 2.0
        for _ in range(int(rng.integers(1, 3))):
            side = float(rng.uniform(0.5, 0.7))
            u = float(rng.uniform(-1.0, 1.0) * (b.length / 2.0 - 1.5))
            v = float(rng.choice([-1.0, 1.0]) * rng.uniform(0.0, half - 1.5))
            # flat top above the highest roof point under the square (nearest the ridge)
            top = float(b.roof_height(np.array(max(abs(v) - side / 2.0, 0.0))))
            b.chimneys.append((u, v, side, top + float(rng.uniform(1.0, 1.5))))


def _burn_buildings(grid: Grid, dsm: np.ndarray, landcover: np.ndarray,
                    obj: SceneObjects) -> None:
    """Roofs and chimneys into the DSM and BUILDING into the land cover (in place)."""
    X, Y = grid.xs, grid.ys
    for b in obj.buildings:
        rows, cols = grid.window(b.x - b.radius, b.y - b.radius, b.x + b.radius, b.y + b.radius)
        u, v = b.local(X[:, cols], Y[rows, :])
        inside = (np.abs(u) <= b.length / 2.0) & (np.abs(v) <= b.width / 2.0)
        roof = b.base_z + b.roof_height(v)
        for cu, cv, side, top in b.chimneys:
            box = (np.abs(u - cu) <= side / 2.0) & (np.abs(v - cv) <= side / 2.0)
            roof = np.where(box, b.base_z + top, roof)
        dsm[rows, cols] = np.where(inside, roof, dsm[rows, cols])
        lc = landcover[rows, cols]
        lc[inside] = BUILDING


def chimney_mask(b: Building, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Cells (building frame coordinates ``u``, ``v``) covered by a chimney of ``b``."""
    out = np.zeros(np.broadcast(u, v).shape, dtype=bool)
    for cu, cv, side, _top in b.chimneys:
        out |= (np.abs(u - cu) <= side / 2.0) & (np.abs(v - cv) <= side / 2.0)
    return out


def _place_isolated_trees(grid: Grid, obj: SceneObjects, rng: np.random.Generator,
                          area: float, taken: List[Tuple[float, float, float]],
                          trees: List[Tuple[float, float, float, float]]) -> None:
    """Append isolated trees (one per 1500 m², 5 … 400) to ``trees`` where there is room."""
    xmin, ymin, xmax, ymax = grid.bounds
    margin = _EDGE_MARGIN
    n_trees = int(np.clip(area / 1500.0, 5, 400))
    n_isolated = 0
    for _ in range(30 * n_trees):
        if n_isolated >= n_trees:
            break
        r, h = rng.uniform(2.0, 5.0), rng.uniform(5.0, 15.0)
        tx = rng.uniform(xmin + margin, xmax - margin)
        ty = rng.uniform(ymin + margin, ymax - margin)
        if not _clear_of_lines(obj, tx, ty, r - 2.0):
            continue
        if any(np.hypot(tx - bx, ty - by) < br + r - 3.0 for bx, by, br in taken):
            continue
        trees.append((tx, ty, r, h))
        taken.append((tx, ty, r + 1.0))
        n_isolated += 1


def _crown_details(sub: Grid, rng: np.random.Generator, sparse: float
                   ) -> Tuple[np.ndarray, np.ndarray]:
    """Leaf-clump relief (m) and gap mask of one crown window ``sub``.

    The clumps (λ ≈ 0.6 m, ±0.2–0.4 m) give the crown a texture through the shading; the gaps
    (λ ≈ 1.5 m) cover the lowest ``sparse`` share of a smooth field (none when 0).
    """
    relief = rng.uniform(0.2, 0.4) * band_noise(rng, sub, 0.6)
    if sparse <= 0.0:
        return relief, np.zeros(sub.shape, dtype=bool)
    field_ = band_noise(rng, sub, 1.5)
    return relief, field_ < np.quantile(field_, sparse)


def _burn_trees(grid: Grid, dtm: np.ndarray, dsm: np.ndarray, landcover: np.ndarray,
                obj: SceneObjects, rng: np.random.Generator) -> None:
    """Tree crowns into the DSM (where higher) and TREE into the land cover (in place).

    ``obj.tree_sparse`` (share of gaps per tree) comes from :func:`_tree_density`; in a gap
    the DSM stays what it was (the ground or a lower crown) and so does the land cover.
    """
    X, Y = grid.xs, grid.ys
    for (tx, ty, r, h), sparse in zip(obj.trees, obj.tree_sparse):
        rows, cols = grid.window(tx - r, ty - r, tx + r, ty + r)
        d2 = ((X[:, cols] - tx) ** 2 + (Y[rows, :] - ty) ** 2) / (r * r)
        sub = Grid(grid.x0 + cols.start * grid.cell, grid.y1 - rows.start * grid.cell,
                   grid.cell, d2.shape[0], d2.shape[1])
        relief, gaps = _crown_details(sub, rng, float(sparse))
        shape_ = np.clip(1.0 - d2, 0.0, None) ** 0.6
        # clumps fade out towards the crown edge, so the outline stays the profile's; the
        # tree keeps its height h as the highest point
        crown = np.minimum(h * shape_ + relief * np.minimum(shape_ * 3.0, 1.0), h)
        sub_dtm = dtm[rows, cols]
        sub_dsm = dsm[rows, cols]
        top = sub_dtm + crown
        leaves = (h * shape_ > 0.05) & (crown > 0.05) & ~gaps
        higher = leaves & (top > sub_dsm)
        sub_dsm[higher] = top[higher]
        lc = landcover[rows, cols]
        lc[leaves & (lc != BUILDING)] = TREE


def _tree_density(n_forest: int, n_all: int, rng: np.random.Generator) -> np.ndarray:
    """Gap share per tree: 0 (dense) or 0.15–0.35; half of the isolated trees are sparse,
    a fifth of the forest trees."""
    p = np.where(np.arange(n_all) < n_forest, 0.2, 0.5)
    sparse = rng.uniform(size=n_all) < p
    return np.where(sparse, rng.uniform(0.15, 0.35, n_all), 0.0)


def _add_breaklines(grid: Grid, dtm: np.ndarray, obj: SceneObjects) -> None:
    """3-D breaklines of the embankment and the ditch, heights from the final DTM."""
    emb, ditch, toe = obj.embankment, obj.ditch, obj.toe_half_width
    w_c, top_w, bot_w = obj.crest_width, obj.ditch_top, obj.ditch_bottom
    spacing = max(2.0, 4 * grid.cell)
    lines = [("embankment_crest", emb, -w_c / 2.0), ("embankment_crest", emb, w_c / 2.0),
             ("embankment_toe", emb, -toe), ("embankment_toe", emb, toe),
             ("ditch_edge", ditch, -top_w / 2.0), ("ditch_edge", ditch, top_w / 2.0),
             ("ditch_bottom", ditch, -bot_w / 2.0), ("ditch_bottom", ditch, bot_w / 2.0)]
    for kind, line, offset in lines:
        xy = line.offset_polyline(offset, grid, spacing)
        if xy is None:
            continue
        col, row = grid.index(xy[:, 0], xy[:, 1])
        z = bilinear_grid(dtm, col, row)
        ok = np.isfinite(z)
        if ok.sum() >= 2:
            obj.breaklines.append((kind, np.column_stack([xy[ok], z[ok]])))


class _PlacementArea:
    """Only the ``bounds`` of a grid: where the forest, buildings and trees are placed."""

    def __init__(self, bounds: Tuple[float, float, float, float]) -> None:
        self.bounds = bounds


def place_objects(grid: Grid, dtm: np.ndarray, rng: np.random.Generator, extent_core: float,
                  detail_rng: Optional[np.random.Generator] = None,
                  placement: Optional[Tuple[float, float, float, float]] = None
                  ) -> Tuple[np.ndarray, np.ndarray, np.ndarray, SceneObjects]:
    """Modify the terrain, build the DSM and land cover, and return the object list.

    The random draws come in a fixed order (linear features and parcels, forest, buildings,
    isolated trees), so a seed gives the same scene. Roof styles, chimneys and crown details
    come from ``detail_rng`` (a stream of its own, so the layout does not depend on them;
    derived from ``rng`` after the layout when not given).

    Parameters
    ----------
    grid : Grid
    dtm : ndarray (float64)
        Natural terrain; a modified copy is returned.
    rng : numpy.random.Generator
    extent_core : float
        Size (m) of the area covered by the images; object counts scale with its square.
    detail_rng : numpy.random.Generator, optional
    placement : (xmin, ymin, xmax, ymax), optional
        Where the forest, buildings and isolated trees go (default the whole grid), e.g. the
        patch every image of a drone block sees.

    Returns
    -------
    dtm, dsm : ndarray float64
    landcover : ndarray uint8
    objects : SceneObjects
    """
    dtm = dtm.copy()
    obj = _linear_features(grid, rng, extent_core)
    landcover = _shape_linear_features(grid, dtm, obj)
    area = extent_core ** 2
    taken: List[Tuple[float, float, float]] = []  # x, y, keep-out radius
    where: Any = grid if placement is None else _PlacementArea(placement)
    trees = _place_forest(where, obj, rng, extent_core, taken)
    n_forest = len(trees)
    _place_buildings(where, obj, rng, area, taken)
    _level_platforms(grid, dtm, obj)  # platforms first (they change the DTM)
    dsm = dtm.copy()
    _place_isolated_trees(where, obj, rng, area, taken, trees)
    if detail_rng is None:
        detail_rng = np.random.default_rng(int(rng.integers(2 ** 63)))
    _decorate_buildings(obj, detail_rng)
    _burn_buildings(grid, dsm, landcover, obj)
    obj.trees = np.array(trees, dtype=float).reshape(-1, 4)
    obj.tree_sparse = _tree_density(n_forest, len(trees), detail_rng)
    _burn_trees(grid, dtm, dsm, landcover, obj, detail_rng)
    _add_breaklines(grid, dtm, obj)
    return dtm, dsm, landcover, obj


def choose_checkpoints(grid: Grid, dtm: np.ndarray, dsm: np.ndarray, landcover: np.ndarray,
                       region, n: int, pad_radius: float, rng: np.random.Generator,
                       clearance: float = 14.0, spacing: float = 12.0) -> np.ndarray:
    """Sites (N, 3) for bright check-point discs on open, flat ground, away from tall objects.

    A site needs: its dark pad (radius ``pad_radius``) plus 1 m entirely on open ground or
    fields, no object higher than 0.5 m within ``clearance`` (relaxed step by step when the
    scene is too crowded), a slope below 15°, a place inside ``region`` (a shapely polygon:
    the area seen by stereo models) and ``spacing`` to the other sites. Heights are the
    bilinear DTM (= DSM) at the site.
    """
    f = max(1, round(1.0 / grid.cell))  # work on ~1 m blocks
    nr, nc = grid.nrows // f, grid.ncols // f

    def blocks(a: np.ndarray) -> np.ndarray:
        return a[:nr * f, :nc * f].reshape(nr, f, nc, f)

    tall = blocks(dsm - dtm > 0.5).any(axis=(1, 3))
    bad = blocks((landcover != OPEN) & (landcover != FIELD)).any(axis=(1, 3)) | tall
    cell = grid.cell * f
    far = np.full(tall.shape, 1e9)
    d_tall = ndimage.distance_transform_edt(~tall) * cell if tall.any() else far
    d_bad = ndimage.distance_transform_edt(~bad) * cell if bad.any() else far
    zb = blocks(dtm).mean(axis=(1, 3))
    gy, gx = np.gradient(zb, cell)
    slope = np.degrees(np.arctan(np.hypot(gx, gy)))
    base_ok = (d_bad > pad_radius + 3.5 + cell) & (slope < 15.0)  # + flattening blend
    sites: List[Tuple[float, float]] = []
    c = clearance
    while len(sites) < n and c >= pad_radius:
        ok = base_ok & (d_tall > c)
        rr, cc = np.nonzero(ok)
        order = rng.permutation(len(rr))
        for k in order:
            x = grid.x0 + (cc[k] + 0.5) * cell + rng.uniform(-0.3, 0.3) * cell
            y = grid.y1 - (rr[k] + 0.5) * cell + rng.uniform(-0.3, 0.3) * cell
            if any(np.hypot(x - sx, y - sy) < spacing for sx, sy in sites):
                continue
            if region is not None and not region.contains(Point(x, y)):
                continue
            sites.append((x, y))
            if len(sites) >= n:
                break
        c *= 0.7
    if not sites:
        return np.zeros((0, 3))
    xy = np.array(sites)
    col, row = grid.index(xy[:, 0], xy[:, 1])
    z = bilinear_grid(dtm, col, row)
    return np.column_stack([xy, z])


def flatten_sites(grid: Grid, dtm: np.ndarray, dsm: np.ndarray, sites: np.ndarray,
                  radius: float, blend: float = 2.0) -> np.ndarray:
    r"""Level the ground under check-point targets (in place) and return their 3-D centres.

    Targets are laid on flat ground: within ``radius`` of a site the terrain becomes its
    least-squares plane :math:`z = a + b\,\Delta x + c\,\Delta y` (fitted over radius + blend),
    blended back to the natural terrain over ``blend`` metres. On a rough surface the image of a
    disc would be bent by relief displacement; on a plane its centroid is the projection of its
    centre. The sites lie on open ground, so the DSM follows the DTM there.
    """
    out = np.asarray(sites, dtype=float).reshape(-1, 3).copy()
    X, Y = grid.xs, grid.ys
    outer = radius + blend
    for x, y, _z in out:
        rows, cols = grid.window(x - outer, y - outer, x + outer, y + outer)
        dx = X[:, cols] - x
        dy = Y[rows, :] - y
        dx, dy = np.broadcast_arrays(dx, dy)
        d = np.hypot(dx, dy)
        sub = dtm[rows, cols]
        fit = d <= outer
        A = np.column_stack([np.ones(fit.sum()), dx[fit], dy[fit]])
        coef = np.linalg.lstsq(A, sub[fit], rcond=None)[0]
        plane = coef[0] + coef[1] * dx + coef[2] * dy
        w = np.clip((outer - d) / blend, 0.0, 1.0)
        ground = dsm[rows, cols] == sub
        new = w * plane + (1.0 - w) * sub
        sub[...] = new
        dsm_sub = dsm[rows, cols]
        dsm_sub[ground] = new[ground]
    col, row = grid.index(out[:, 0], out[:, 1])
    out[:, 2] = bilinear_grid(dtm, col, row)
    return out
