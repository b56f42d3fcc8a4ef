"""Synthetic polygon maps and images of them with a known georeference (georeferencing truth).

A map in a projected CRS holds forests (irregular smooth blobs, some split into touching parts
along straight lines as vector data are), fields (rounded quadrilaterals) and lakes (round-ish
blobs), written as a GeoPackage with a ``class`` attribute. An image is rendered from the map
through a known image → map affine (rotation, scale, shear, mirroring): each class a grey level,
fields each their own, anti-aliased edges (4 × 4 supersampling), texture and noise; saved
without georeference. Also: a georeferenced synthetic orthophoto and an image of it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple, Union

import fiona
import numpy as np
from affine import Affine
from numpy.typing import NDArray
from rasterio import features
from scipy import ndimage
from shapely.affinity import affine_transform
from shapely.geometry import LineString, Polygon, mapping
from shapely.ops import split

from ..raster.io import write_raster

PathLike = Union[str, Path]

#: Grey values of the classes (background = meadow).
GREY = {"background": 110.0, "forest": 55.0, "lake": 25.0}
CRS = "EPSG:32632"
ORIGIN = (500000.0, 5400000.0)


@dataclass
class PolygonScene:
    """Map polygons with their class (map coordinates, metres)."""

    polygons: List[Any]  # shapely Polygons
    classes: List[str]
    extent: Tuple[float, float, float, float]
    crs: str = CRS
    groups: Optional[List[int]] = None  # parts of one object (a split forest) share a group


def _blob(rng: np.random.Generator, centre: Tuple[float, float], radius: float,
          roughness: float = 0.3, n: int = 96) -> NDArray[np.float64]:
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    r = np.ones(n)
    for k in range(2, 7):
        r += rng.normal(0, roughness / k) * np.cos(k * t + rng.uniform(0, 2 * np.pi))
    r = np.clip(r, 0.35, None) * radius
    return np.column_stack([centre[0] + r * np.cos(t), centre[1] + r * np.sin(t)])


def make_scene(seed: int = 0, size: float = 3000.0, n_forest: int = 14, n_field: int = 10,
               n_lake: int = 5, split_share: float = 0.3, object_scale: float = 1.0
               ) -> PolygonScene:
    """Random non-overlapping polygons in a ``size`` × ``size`` m square (``object_scale``
    scales their radii, e.g. to fit more of them)."""
    rng = np.random.default_rng(seed)
    x0, y0 = ORIGIN
    polys: List[Any] = []
    classes: List[str] = []
    groups: List[int] = []
    occupied: List[Any] = []
    plan = ["forest"] * n_forest + ["field"] * n_field + ["lake"] * n_lake
    for cls in plan:
        for _ in range(200):
            radius = object_scale * size * (rng.uniform(0.04, 0.11) if cls != "lake"
                                            else rng.uniform(0.03, 0.06))
            c = (x0 + rng.uniform(radius, size - radius), y0 + rng.uniform(radius, size - radius))
            if cls == "field":
                a, b = radius * rng.uniform(0.8, 1.3), radius * rng.uniform(0.4, 0.8)
                ang = rng.uniform(0, np.pi)
                corners = np.array([[-a, -b], [a, -b * rng.uniform(0.6, 1.0)], [a, b],
                                    [-a * rng.uniform(0.6, 1.0), b]])
                R = np.array([[math.cos(ang), -math.sin(ang)], [math.sin(ang), math.cos(ang)]])
                p = Polygon(corners @ R.T + c).buffer(radius * 0.05).buffer(-radius * 0.05)
            else:
                p = Polygon(_blob(rng, c, radius, 0.35 if cls == "forest" else 0.15))
            if not p.is_valid:
                p = p.buffer(0)
            if p.geom_type != "Polygon":
                continue
            if any(p.buffer(size * 0.01).intersects(q) for q in occupied):
                continue
            occupied.append(p)
            if cls == "forest" and rng.uniform() < split_share:
                # split along a straight line, as forest parcels are digitised
                cx, cy = p.centroid.x, p.centroid.y
                ang = rng.uniform(0, np.pi)
                d = np.array([math.cos(ang), math.sin(ang)]) * radius * 3
                parts = split(p, LineString([(cx - d[0], cy - d[1]), (cx + d[0], cy + d[1])]))
                for part in getattr(parts, "geoms", [parts]):
                    polys.append(part)
                    classes.append(cls)
                    groups.append(len(occupied))
            else:
                polys.append(p)
                classes.append(cls)
                groups.append(len(occupied))
            break
    return PolygonScene(polys, classes, (x0, y0, x0 + size, y0 + size), groups=groups)


def write_scene(scene: PolygonScene, path: PathLike) -> Path:
    """The map as a GeoPackage (layer ``polygons``, attributes ``class`` and ``id``)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    schema = {"geometry": "Polygon", "properties": {"id": "int", "class": "str"}}
    with fiona.open(path, "w", driver="GPKG", layer="polygons", crs=scene.crs,
                    schema=schema) as dst:
        for k, (p, c) in enumerate(zip(scene.polygons, scene.classes)):
            dst.write({"geometry": mapping(p), "properties": {"id": k, "class": c}})
    return path


def random_affine(rng: np.random.Generator, gsd: float, width: int, height: int,
                  extent: Tuple[float, float, float, float], scale_range=(0.5, 2.0),
                  shear: float = 0.15, mirror: Optional[bool] = None) -> NDArray[np.float64]:
    """Random image → map affine (3 × 3) whose image centre falls on the map centre.

    Rotation 0–360°, pixel size ``gsd`` × a factor in ``scale_range``, shear up to ``shear``,
    mirrored with probability ½ (beside the usual y flip of image rows).
    """
    s = gsd * rng.uniform(*scale_range)
    ang = rng.uniform(0, 2 * np.pi)
    R = np.array([[math.cos(ang), -math.sin(ang)], [math.sin(ang), math.cos(ang)]])
    Sh = np.array([[1.0, rng.uniform(-shear, shear)], [0.0, 1.0]])
    anis = np.diag([rng.uniform(0.9, 1.1), 1.0])
    flip = np.diag([1.0, -1.0])  # image rows point down
    if mirror is None:
        mirror = bool(rng.uniform() < 0.5)
    if mirror:
        flip = flip @ np.diag([-1.0, 1.0])
    L = s * R @ Sh @ anis @ flip
    cx, cy = 0.5 * (extent[0] + extent[2]), 0.5 * (extent[1] + extent[3])
    T = np.eye(3)
    T[:2, :2] = L
    T[:2, 2] = np.array([cx, cy]) - L @ np.array([(width - 1) / 2, (height - 1) / 2])
    return T


def render(scene: PolygonScene, T_img_to_map: NDArray[np.float64], width: int, height: int,
           seed: int = 0, noise: float = 2.0, texture: float = 1.0, supersample: int = 4
           ) -> NDArray[np.uint8]:
    """Render the map into an image whose pixels map by ``T_img_to_map`` (pixel centres at
    integers); exact-coverage anti-aliasing by supersampling."""
    rng = np.random.default_rng(seed + 1000)
    Tinv = np.linalg.inv(T_img_to_map)
    # map → image corner coordinates (+0.5), then × supersample
    a, b, c, d = Tinv[0, 0], Tinv[0, 1], Tinv[1, 0], Tinv[1, 1]
    e, f = Tinv[0, 2] + 0.5, Tinv[1, 2] + 0.5
    ss = supersample
    values = np.full(len(scene.polygons), GREY["background"])
    groups = scene.groups or list(range(len(scene.polygons)))
    by_group: Dict[int, float] = {}
    for k, cls in enumerate(scene.classes):
        if groups[k] in by_group:  # the parts of one split forest look the same
            values[k] = by_group[groups[k]]
            continue
        if cls == "field":
            values[k] = rng.uniform(140, 200)
        elif cls == "forest":
            values[k] = GREY["forest"] + rng.uniform(-8, 8)
        else:
            values[k] = GREY["lake"] + rng.uniform(-5, 5)
        by_group[groups[k]] = values[k]
    shapes = [(affine_transform(p, [a * ss, b * ss, c * ss, d * ss, e * ss, f * ss]), v)
              for p, v in zip(scene.polygons, values)]
    big = features.rasterize(shapes, out_shape=(height * ss, width * ss),
                             fill=GREY["background"], transform=Affine.identity(),
                             dtype="float32")
    img = big.reshape(height, ss, width, ss).mean(axis=(1, 3))
    # mild texture and sensor noise
    tex = ndimage.gaussian_filter(rng.normal(0, 1, (height, width)), 3.0)
    tex *= texture / max(float(tex.std()), 1e-9)
    img = img + tex + rng.normal(0, noise, img.shape)
    return np.clip(np.round(img), 0, 255).astype(np.uint8)


def write_image(path: PathLike, img: NDArray[Any], transform: Any = None, crs: Any = None
                ) -> Path:
    """Write a one- or multi-band byte image (no georeference unless given)."""
    return write_raster(path, img, transform=transform, crs=crs)


def georef_case(folder: PathLike, seed: int = 0, width: int = 1000, height: int = 1000,
                scene_seed: Optional[int] = None, noise: float = 2.0, texture: float = 1.0,
                scale_range: Tuple[float, float] = (0.5, 2.0), shear: float = 0.15,
                **scene_options: Any) -> Dict[str, Any]:
    """One synthetic case: map GeoPackage, image, truth transform (image → map, 3 × 3).

    ``texture``: standard deviation (DN) of the smooth texture inside every object (large:
    objects that are not homogeneous, as for the area-based search). ``scene_options`` go to
    :func:`make_scene` (e.g. more polygons)."""
    folder = Path(folder)
    scene = make_scene(seed if scene_seed is None else scene_seed, **scene_options)
    rng = np.random.default_rng(seed)
    size = scene.extent[2] - scene.extent[0]
    gsd = size / (1.1 * max(width, height))  # scale 1: the map just covers the image
    T = random_affine(rng, gsd, width, height, scene.extent, scale_range=scale_range,
                      shear=shear)
    img = render(scene, T, width, height, seed=seed, noise=noise, texture=texture)
    ref = write_scene(scene, folder / "map.gpkg")
    image = write_image(folder / "image.tif", img)
    return {"reference": str(ref), "image": str(image), "truth": T, "width": width,
            "height": height, "crs": scene.crs}


def ortho_case(folder: PathLike, seed: int = 0, size_px: int = 1000, gsd: float = 3.0,
               scale: float = 1.3, angle_deg: float = 35.0) -> Dict[str, Any]:
    """A synthetic orthophoto (north-up GeoTIFF) and a rotated, rescaled image of it."""
    folder = Path(folder)
    scene = make_scene(seed)
    x0, y0, x1, y1 = scene.extent
    gsd = (x1 - x0) / size_px
    T_ortho = np.array([[gsd, 0, x0 + 0.5 * gsd], [0, -gsd, y1 - 0.5 * gsd], [0, 0, 1.0]])
    ortho = render(scene, T_ortho, size_px, size_px, seed=seed)
    ortho_path = write_image(folder / "ortho.tif", ortho,
                             transform=Affine(gsd, 0, x0, 0, -gsd, y1), crs=scene.crs)
    w = h = int(size_px * 0.8)
    a = math.radians(angle_deg)
    R = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    L = gsd * scale * R @ np.diag([1.0, -1.0])
    T = np.eye(3)
    T[:2, :2] = L
    cx, cy = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
    T[:2, 2] = np.array([cx, cy]) - L @ np.array([(w - 1) / 2, (h - 1) / 2])
    img = render(scene, T, w, h, seed=seed + 7)
    image = write_image(folder / "image.tif", img)
    return {"reference": str(ortho_path), "image": str(image), "truth": T, "width": w,
            "height": h, "crs": scene.crs}
