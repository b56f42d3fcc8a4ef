"""Synthetic suburban scenes: building footprints and an aerial image of them (issue 23).

A town in EPSG:25832 holds 30–80 buildings (6–40 m; rectangles, L- and T-shapes, terraces of
3–6 attached units, each unit its own footprint) along a street network, trees and lawns. The
image is rendered through a known image → map affine (any rotation, scale 0.5–2 of a 0.5 m
pixel, shear, mirroring in half of the seeds): gabled roofs (ridge along the long axis) and
hipped roofs with a sun-facing and a shaded side, flat roofs with gravel texture, chimneys and
dormers as small bright or dark spots, walls, cast shadows (length ∝ height), tree crowns
partly over roofs, sensor noise. Roofs are displaced from their footprints as in a central
projection: radially from the image centre, 0–3 px, ∝ building height. Written as 8-bit, or as
11/12-bit data in uint16; the footprints as a GeoPackage of polygons.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple, Union

import fiona
import numpy as np
from affine import Affine
from numpy.typing import NDArray
from rasterio import features
from scipy import ndimage
from shapely.affinity import affine_transform
from shapely.geometry import LineString, Point, Polygon, box, mapping
from shapely.ops import unary_union
from shapely.prepared import prep

from .polygon_scene import random_affine, write_image

PathLike = Union[str, Path]
Array = NDArray[np.float64]

CRS = "EPSG:25832"
#: Map position of the town centre (Lower Saxony, UTM 32).
CENTRE = (560000.0, 5930000.0)
#: Nominal pixel size (m) at scale 1.
GSD = 0.5
#: Largest relief displacement of a roof (px, the tallest building in an image corner).
MAX_RELIEF_PX = 3.0


@dataclass
class RoofPart:
    """One rectangular roof part (map units): centre, unit vector along the ridge, half
    length along and half width across it, kind ("gabled", "hipped", "flat"), albedo."""

    centre: Array
    axis: Array
    half_length: float
    half_width: float
    kind: str
    albedo: float
    building: int

    def corners(self) -> Array:
        """The four corners (map units), counter-clockwise."""
        u = self.axis
        v = np.array([-u[1], u[0]])
        a, b = self.half_length, self.half_width
        return np.array([self.centre + s * a * u + t * b * v
                         for s, t in ((-1, -1), (1, -1), (1, 1), (-1, 1))])


@dataclass
class Town:
    """Footprints (one polygon each, ``building`` says which roof group they belong to),
    roof parts, heights per building, roads, trees (centre, radius) and the map extent."""

    footprints: List[Any]
    footprint_building: List[int]
    roofs: List[RoofPart]
    heights: List[float]
    roads: Any
    trees: List[Tuple[float, float, float]]
    extent: Tuple[float, float, float, float]
    kinds: List[str] = field(default_factory=list)  # per footprint: rectangle, l, t, terrace
    crs: str = CRS


def _rect(c: Array, u: Array, a: float, b: float) -> Polygon:
    v = np.array([-u[1], u[0]])
    return Polygon([c + s * a * u + t * b * v for s, t in ((-1, -1), (1, -1), (1, 1), (-1, 1))])


def _unit(angle: float) -> Array:
    return np.array([math.cos(angle), math.sin(angle)])


def _street_network(rng: np.random.Generator, extent: Tuple[float, float, float, float]
                    ) -> Tuple[Any, float]:
    """Two families of roughly parallel streets (a rotated grid with bends): the road area
    and the main grid angle."""
    x0, y0, x1, y1 = extent
    cx, cy = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
    size = max(x1 - x0, y1 - y0)
    angle = rng.uniform(0, math.pi)
    lines = []
    for fam in (0, 1):
        u = _unit(angle + fam * math.pi / 2 + rng.normal(0, 0.08))
        v = np.array([-u[1], u[0]])
        spacing = rng.uniform(70, 110)
        for off in np.arange(-size, size, spacing) + rng.uniform(0, spacing):
            p0 = np.array([cx, cy]) + off * v - size * u
            p1 = np.array([cx, cy]) + off * v + size * u
            mid = 0.5 * (p0 + p1) + v * rng.normal(0, 6)  # a slight bend
            lines.append(LineString([p0, mid, p1]).buffer(rng.uniform(3.0, 4.0)))
    return unary_union(lines).intersection(box(*extent)), angle


def _building(rng: np.random.Generator, c: Array, angle: float, bid: int
              ) -> Tuple[List[Polygon], List[RoofPart], str]:
    """One building (or terrace): its footprint polygon(s), roof parts and its kind."""
    kind = rng.choice(["rectangle", "rectangle", "l", "t", "terrace"])
    u = _unit(angle)
    v = np.array([-u[1], u[0]])
    roof_kind = rng.choice(["gabled", "gabled", "hipped", "flat"])
    alb = rng.uniform(0.25, 0.8)
    if kind == "terrace":
        n = int(rng.integers(3, 7))
        w, d = rng.uniform(5.5, 8.0), rng.uniform(8.0, 11.0)
        roof_kind = "gabled" if roof_kind == "flat" else roof_kind
        polys, parts = [], []
        for k in range(n):
            cc = c + (k - (n - 1) / 2) * w * u
            polys.append(_rect(cc, u, w / 2, d / 2))
            # one ridge along the row; each unit its own shade of the roof colour
            kk = "gabled" if roof_kind == "gabled" or 0 < k < n - 1 else "hipped"
            parts.append(RoofPart(cc, u, w / 2, d / 2, kk,
                                  float(np.clip(alb + rng.normal(0, 0.05), 0.15, 0.9)), bid))
        if roof_kind == "hipped":  # hipped ends: the end units' roofs slope outwards too
            parts[0].kind = parts[-1].kind = "gabled"
        return polys, parts, kind
    a, b = rng.uniform(4.0, 20.0), rng.uniform(3.0, 7.5)
    a = max(a, b * 1.15)
    parts = [RoofPart(c, u, a, b, roof_kind, alb, bid)]
    if kind in ("l", "t"):
        wb = rng.uniform(3.0, max(3.2, min(b, 6.0)))
        wl = rng.uniform(2 * wb, 2 * wb + 10.0)
        along = (a - wb) * (1 if rng.uniform() < 0.5 else -1) if kind == "l" else \
            rng.uniform(-0.3, 0.3) * a
        side = 1 if rng.uniform() < 0.5 else -1
        wc = c + along * u + side * (b + 0.5 * wl - 0.1) * v
        wkind = "flat" if roof_kind == "flat" else "gabled"
        parts.append(RoofPart(wc, v.copy(), 0.5 * wl + 0.1, wb, wkind, alb, bid))
    poly = unary_union([_rect(p.centre, p.axis, p.half_length, p.half_width) for p in parts])
    return [poly.simplify(0.01)], parts, kind


def make_town(seed: int = 0, extent: Optional[Tuple[float, float, float, float]] = None,
              n_buildings: Optional[int] = None, tree_share: float = 0.35) -> Town:
    """A random town in ``extent`` (default: 450 m × 450 m around :data:`CENTRE`).

    ``n_buildings`` (default 30–80) detached buildings and terraces (a terrace counts once)
    along the streets, facing them; trees between them, some over roof edges.
    """
    rng = np.random.default_rng(seed)
    if extent is None:
        extent = (CENTRE[0] - 225, CENTRE[1] - 225, CENTRE[0] + 225, CENTRE[1] + 225)
    roads, angle = _street_network(rng, extent)
    n = int(rng.integers(30, 81)) if n_buildings is None else int(n_buildings)
    x0, y0, x1, y1 = extent
    road_zone = prep(roads.buffer(2.0))
    taken: List[Any] = []  # buffered buildings placed so far
    fps, fpb, roofs, heights, kinds = [], [], [], [], []
    for _ in range(n):
        for _ in range(60):
            c = np.array([rng.uniform(x0 + 15, x1 - 15), rng.uniform(y0 + 15, y1 - 15)])
            ang = angle + rng.choice([0, math.pi / 2]) + rng.normal(0, 0.05) \
                if rng.uniform() < 0.75 else rng.uniform(0, math.pi)
            polys, parts, kind = _building(rng, c, ang, len(heights))
            zone = unary_union(polys).buffer(3.0)
            if road_zone.intersects(zone) or any(zone.intersects(t) for t in taken):
                continue
            taken.append(zone)
            h = rng.uniform(5.0, 9.0) if kind != "terrace" else rng.uniform(7.0, 10.0)
            heights.append(float(h + (rng.uniform(0, 6) if rng.uniform() < 0.15 else 0)))
            roofs += parts
            fps += polys
            fpb += [len(heights) - 1] * len(polys)
            kinds += [kind] * len(polys)
            break
    busy = prep(unary_union(taken)) if taken else None
    trees = []
    n_trees = int(tree_share * 3 * len(heights))
    for _ in range(n_trees * 4):
        if len(trees) >= n_trees:
            break
        c = (rng.uniform(x0, x1), rng.uniform(y0, y1))
        r = rng.uniform(2.0, 5.5)
        disc = Point(c).buffer(r)
        if disc.intersects(roads):
            continue
        # most stand on free ground; some overhang a roof edge
        if busy is not None and busy.intersects(disc) and not (
                rng.uniform() < 0.35 and not busy.intersects(Point(c).buffer(0.5 * r))):
            continue
        trees.append((c[0], c[1], r))
    return Town(fps, fpb, roofs, heights, roads, trees, extent, kinds)


def write_footprints(town: Town, path: PathLike) -> Path:
    """The footprints as a GeoPackage (layer ``buildings``; attributes ``id``, ``class``
    = "building", ``kind``, ``building`` = terrace group)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    schema = {"geometry": "Polygon", "properties": {"id": "int", "class": "str", "kind": "str",
                                                    "building": "int"}}
    with fiona.open(path, "w", driver="GPKG", layer="buildings", crs=town.crs,
                    schema=schema) as dst:
        dst.writerecords([{"geometry": mapping(p), "properties": {
            "id": k, "class": "building", "kind": kd, "building": b}}
            for k, (p, b, kd) in enumerate(zip(town.footprints, town.footprint_building,
                                               town.kinds))])
    return path


# -- rendering --------------------------------------------------------------------------------
@dataclass
class _Canvas:
    """The supersampled image grid: map coordinates of every sample, the map → sample
    affine (shapely order) and the relief displacement per building (samples)."""

    X: Array
    Y: Array
    to_sample: List[float]
    ss: int
    shape: Tuple[int, int]
    shift: Array  # (buildings, 2) roof displacement in samples (x, y)


def _canvas(T: Array, width: int, height: int, ss: int, town: Town,
            relief_px: float = MAX_RELIEF_PX) -> _Canvas:
    Tinv = np.linalg.inv(T)
    a, b, c, d = Tinv[0, 0], Tinv[0, 1], Tinv[1, 0], Tinv[1, 1]
    e, f = Tinv[0, 2] + 0.5, Tinv[1, 2] + 0.5  # pixel centres at integers
    to_sample = [a * ss, b * ss, c * ss, d * ss, e * ss, f * ss]
    cols = (np.arange(width * ss) + 0.5) / ss - 0.5
    rows = (np.arange(height * ss) + 0.5) / ss - 0.5
    cc, rr = np.meshgrid(cols, rows)
    X = T[0, 0] * cc + T[0, 1] * rr + T[0, 2]
    Y = T[1, 0] * cc + T[1, 1] * rr + T[1, 2]
    # relief displacement: radial from the image centre, ∝ height, 3 px at the corner
    centre = np.array([(width - 1) / 2, (height - 1) / 2])
    rmax = float(np.hypot(*centre))
    hmax = max(town.heights) if town.heights else 1.0
    shift = np.zeros((len(town.heights), 2))
    for k in range(len(town.heights)):
        parts = [p.centre for p in town.roofs if p.building == k]
        if not parts:
            continue
        m = np.mean(parts, axis=0)
        pix = (Tinv @ np.array([m[0], m[1], 1.0]))[:2]
        shift[k] = (pix - centre) / rmax * relief_px * town.heights[k] / hmax * ss
    return _Canvas(X, Y, to_sample, ss, (height * ss, width * ss), shift)


def _burn(cv: _Canvas, shapes: List[Tuple[Any, float]], fill: float = 0.0,
          dtype: str = "float32") -> NDArray[Any]:
    """Rasterise map-coordinate geometries into the sample grid (later ones on top)."""
    if not shapes:
        return np.full(cv.shape, fill, dtype=dtype)
    sh = [(affine_transform(g, cv.to_sample), v) for g, v in shapes]
    return features.rasterize(sh, out_shape=cv.shape, fill=fill, transform=Affine.identity(),
                              dtype=dtype, all_touched=False)


def _roof_shading(cv: _Canvas, town: Town, sun: Array, labels: NDArray[Any],
                  rng: np.random.Generator) -> Array:
    """Brightness of every roof sample (0 elsewhere): the plane of its roof part (gabled: by
    the side of the ridge; hipped: by the nearest eave) lit by the sun; flat: gravel."""
    out = np.zeros(cv.shape)
    m = labels > 0
    k = labels[m] - 1
    cen = np.array([p.centre for p in town.roofs])
    ax = np.array([p.axis for p in town.roofs])
    hl = np.array([p.half_length for p in town.roofs])
    hw = np.array([p.half_width for p in town.roofs])
    alb = np.array([p.albedo for p in town.roofs])
    kind = np.array([{"gabled": 0, "hipped": 1, "flat": 2}[p.kind] for p in town.roofs])
    bld = np.array([p.building for p in town.roofs])
    # the sample's map position before the roof's displacement
    Ainv = np.linalg.inv(np.array(cv.to_sample[:4]).reshape(2, 2))
    dxy = cv.shift[bld[k]] @ Ainv.T
    dx, dy = cv.X[m] - dxy[:, 0] - cen[k, 0], cv.Y[m] - dxy[:, 1] - cen[k, 1]
    u = dx * ax[k, 0] + dy * ax[k, 1]
    v = -dx * ax[k, 1] + dy * ax[k, 0]
    vx, vy = -ax[k, 1], ax[k, 0]
    # outward direction of the roof plane's eave (map), slope 35°
    by_side = np.where(v >= 0, 1.0, -1.0)
    ex, ey = by_side * vx, by_side * vy
    hip = (kind[k] == 1) & (hl[k] - np.abs(u) < hw[k] - np.abs(v))
    ex = np.where(hip, np.sign(u) * ax[k, 0], ex)
    ey = np.where(hip, np.sign(u) * ax[k, 1], ey)
    s, c = math.sin(math.radians(35)), math.cos(math.radians(35))
    lit = np.clip(s * (ex * sun[0] + ey * sun[1]) + c * sun[2], 0.05, None)
    flat = kind[k] == 2
    lit = np.where(flat, sun[2], lit)
    gravel = ndimage.gaussian_filter(rng.normal(0, 1, cv.shape), 0.7 * cv.ss)[m]
    val = alb[k] * lit * (1 + np.where(flat, 0.12, 0.03) * gravel / max(gravel.std(), 1e-9))
    out[m] = val
    return out


def _fixtures(town: Town, rng: np.random.Generator) -> List[Tuple[Any, float]]:
    """Chimneys and dormers: small squares on the roofs, bright or dark (reflectance)."""
    out = []
    for p in town.roofs:
        for _ in range(int(rng.integers(0, 3))):
            s = rng.uniform(0.6, 1.6)
            c = p.centre + rng.uniform(-0.7, 0.7) * p.half_length * p.axis \
                + rng.uniform(-0.6, 0.6) * p.half_width * np.array([-p.axis[1], p.axis[0]])
            out.append((_rect(c, p.axis, s, s), rng.choice([0.08, 0.9]), p.building))
    return out


def render_town(town: Town, T: Array, width: int, height: int, seed: int = 0,
                sun_azimuth: float = 150.0, sun_elevation: float = 40.0, noise: float = 0.008,
                supersample: int = 2, relief_px: float = MAX_RELIEF_PX) -> Array:
    """Render the town into an image whose pixels map by ``T`` (image → map, pixel centres
    at integers). Returns reflectance-like values (about 0–1), noise included. ``relief_px``:
    the roof displacement of the tallest building at an image corner."""
    rng = np.random.default_rng(seed + 2000)
    ss = supersample
    cv = _canvas(T, width, height, ss, town, relief_px)
    az, el = math.radians(sun_azimuth), math.radians(sun_elevation)
    sun = np.array([math.sin(az), math.cos(az), 0.0]) * math.cos(el)
    sun[2] = math.sin(el)
    # ground: lawns of varying green, roads
    coarse = ndimage.gaussian_filter(rng.normal(0, 1, (cv.shape[0] // 16 + 2,
                                                       cv.shape[1] // 16 + 2)), 25 * ss / 16)
    low = ndimage.zoom(coarse, 16, order=1)[:cv.shape[0], :cv.shape[1]]
    img = 0.32 + 0.05 * low / max(low.std(), 1e-9) \
        + 0.02 * ndimage.gaussian_filter(rng.normal(0, 1, cv.shape), 1.5 * ss) * 3
    road = _burn(cv, [(town.roads, 1.0)]) > 0
    img[road] = 0.2 + 0.01 * rng.normal(0, 1, int(road.sum()))
    # cast shadows: each roof part swept away from the sun by h / tan(elevation)
    back = -np.array([sun[0], sun[1]]) / math.hypot(sun[0], sun[1]) / math.tan(el)
    shadows = []
    for p in town.roofs:
        corners = p.corners()
        sweep = np.vstack([corners, corners + back * town.heights[p.building]])
        shadows.append((Polygon(sweep).convex_hull, 1.0))
    for x, y, r in town.trees:
        shadows.append((Point(x + back[0] * 1.5 * r, y + back[1] * 1.5 * r).buffer(r), 1.0))
    img[_burn(cv, shadows) > 0] *= 0.42
    # walls (footprint area not covered by the displaced roof), then the roofs
    img[_burn(cv, [(f, 1.0) for f in town.footprints]) > 0] = 0.28
    labels = _roof_labels(cv, town, T)
    shade = _roof_shading(cv, town, sun, labels, rng)
    img = np.where(labels > 0, shade, img)
    fx = [(Polygon(np.asarray(g.exterior.coords) + _map_offset(T, cv.shift[b] / ss)), v)
          for g, v, b in _fixtures(town, rng)]
    spots = _burn(cv, fx, fill=-1.0)
    img = np.where((spots >= 0) & (labels > 0), spots, img)
    img = _trees(cv, town, sun, img, rng)
    out = img.reshape(height, ss, width, ss).mean(axis=(1, 3))
    return out + rng.normal(0, noise, out.shape)


def _roof_labels(cv: _Canvas, town: Town, T: Array) -> NDArray[np.int32]:
    """Roof part number + 1 of every sample (0: no roof), roofs displaced by relief."""
    shapes = [(_rect(p.centre + _map_offset(T, cv.shift[p.building] / cv.ss), p.axis,
                     p.half_length, p.half_width), k + 1) for k, p in enumerate(town.roofs)]
    return _burn(cv, shapes, dtype="int32")


def roof_mask(town: Town, T: Array, width: int, height: int,
              relief_px: float = MAX_RELIEF_PX) -> NDArray[np.bool_]:
    """Pixels whose centre lies on a roof (as rendered, with the relief displacement)."""
    return _roof_labels(_canvas(T, width, height, 1, town, relief_px), town, T) > 0


def _map_offset(T: Array, d_px: Array) -> Array:
    """Map vector of an image displacement ``d_px`` (px)."""
    return T[:2, :2] @ np.asarray(d_px, float)


def _trees(cv: _Canvas, town: Town, sun: Array, img: Array, rng: np.random.Generator
           ) -> Array:
    """Tree crowns on top: dark, lit on the sun side, leafy texture."""
    if not town.trees:
        return img
    crowns = _burn(cv, [(Point(x, y).buffer(r), k + 1) for k, (x, y, r)
                        in enumerate(town.trees)], dtype="int32")
    m = crowns > 0
    t = np.array(town.trees)[crowns[m] - 1]
    dx, dy = (cv.X[m] - t[:, 0]) / t[:, 2], (cv.Y[m] - t[:, 1]) / t[:, 2]
    leaf = ndimage.gaussian_filter(rng.normal(0, 1, cv.shape), 0.8 * cv.ss)[m]
    val = 0.16 + 0.07 * np.clip(dx * sun[0] + dy * sun[1], -1, 1) \
        + 0.03 * leaf / max(leaf.std(), 1e-9)
    img = img.copy()
    img[m] = val
    return img


def to_dtype(img: Array, bits: int = 8) -> NDArray[Any]:
    """Reflectance-like values → 8-bit (``bits`` = 8) or ``bits``-bit data in uint16 (with a
    dark offset as sensors have)."""
    if bits == 8:
        return np.clip(np.round(img * 255.0), 0, 255).astype(np.uint8)
    if not 9 <= bits <= 16:
        raise ValueError(f"bits must be 8 or 9–16, not {bits}")
    top = 2**bits - 1
    return np.clip(np.round(0.02 * top + img * 0.9 * top), 0, top).astype(np.uint16)


def _image_extent(T: Array, width: int, height: int, margin: float
                  ) -> Tuple[float, float, float, float]:
    corners = np.array([[-0.5, -0.5, 1], [width - 0.5, -0.5, 1], [width - 0.5, height - 0.5, 1],
                        [-0.5, height - 0.5, 1]]) @ T.T
    x0, y0 = corners[:, :2].min(axis=0) - margin
    x1, y1 = corners[:, :2].max(axis=0) + margin
    return float(x0), float(y0), float(x1), float(y1)


def suburban_case(folder: PathLike, seed: int = 0, width: int = 900, height: int = 900,
                  bits: int = 8, town_seed: Optional[int] = None,
                  scale_range: Tuple[float, float] = (0.5, 2.0), shear: float = 0.15,
                  mirror: Optional[bool] = None, n_buildings: Optional[int] = None,
                  noise: float = 0.008, relief_px: float = MAX_RELIEF_PX) -> Dict[str, Any]:
    """One synthetic suburban case: footprints GeoPackage, image, truth (image → map, 3 × 3).

    The town covers the image footprint (plus 20 m): 30–80 buildings (``n_buildings``) per
    image whatever the scale. ``town_seed``: the footprints of a *different* town (the image
    still shows the town of ``seed``; the case must fail). ``mirror``: None = half of the
    seeds. ``relief_px``: roof displacement of the tallest building at an image corner
    (0: roofs exactly over their footprints). Returns the keys of
    :func:`.polygon_scene.georef_case` plus ``bits``, ``town`` (the rendered town),
    ``mirrored`` and ``relief_corner_px`` (the mean roof displacement at an image corner).
    """
    folder = Path(folder)
    rng = np.random.default_rng(seed)
    box450 = (CENTRE[0] - 225, CENTRE[1] - 225, CENTRE[0] + 225, CENTRE[1] + 225)
    gsd = GSD * 900.0 / max(width, height)  # scale 1: a 450 m square
    T = random_affine(rng, gsd, width, height, box450, scale_range=scale_range, shear=shear,
                      mirror=mirror)
    extent = _image_extent(T, width, height, 20.0)
    # buildings per image area: the image covers only part of its bounding box
    share = width * height * abs(np.linalg.det(T[:2, :2])) / (
        (extent[2] - extent[0]) * (extent[3] - extent[1]))
    n_img = int(rng.integers(30, 81)) if n_buildings is None else int(n_buildings)
    n_town = round(n_img / max(share, 0.2))
    town = make_town(seed, extent, n_buildings=n_town)
    img = render_town(town, T, width, height, seed=seed, noise=noise, relief_px=relief_px)
    ref_town = town if town_seed is None else make_town(town_seed, extent, n_buildings=n_town)
    ref = write_footprints(ref_town, folder / "buildings.gpkg")
    image = write_image(folder / "image.tif", to_dtype(img, bits))
    return {"reference": str(ref), "image": str(image), "truth": T, "width": width,
            "height": height, "crs": CRS, "bits": bits, "town": town,
            "mirrored": bool(np.linalg.det(T[:2, :2]) > 0),
            # the mean roof displacement at an image corner: a fit to roofs is biased by it
            "relief_corner_px": relief_px * float(np.mean(town.heights)) / max(town.heights)}
