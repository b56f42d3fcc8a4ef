"""Synthetic multi-temporal image pairs: a georeferenced reference and a cloudy later image.

A 10 m landscape (as a Sentinel-2 crop): field parcels (a Voronoi tiling, each parcel its own
crop), forests and lakes (thresholds of smooth random fields), a river, roads, villages of small
houses. It is described once on a fine grid (half the reference pixel) and rendered twice:

* the **reference**: north-up GeoTIFF (EPSG:25832), 2 × 2 cell means of the first date;
* the **target**: the second date through a known image → map affine (any rotation, scale
  0.8–1.25 of the reference pixel, mirrored in half of the seeds), without georeference:
  seasonal change (a quarter of the fields re-cropped or harvested, per-class gain and
  offset, contrast inversion of water and villages), soft-edged clouds over 30–60 % of the
  image and their shadows, sensor noise.

Both as 8-bit, or as 12-bit (or 16-bit) data in uint16.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Dict, Optional, Tuple, Union

import numpy as np
from affine import Affine
from numpy.typing import NDArray
from rasterio import features
from scipy import ndimage
from shapely.geometry import LineString

from ..raster.io import write_raster
from .terrain import Grid, band_noise

PathLike = Union[str, Path]
Array = NDArray[np.float64]

CRS = "EPSG:25832"
#: Top-left corner of the landscape (m, EPSG:25832).
ORIGIN = (560000.0, 5680000.0)
#: Land-cover codes of the landscape grid.
FIELD, FOREST, WATER, ROAD, VILLAGE, HOUSE = range(6)
#: First-date reflectance-like levels (0–1) of the classes other than fields.
LEVEL = {FOREST: 0.16, WATER: 0.06, ROAD: 0.55, VILLAGE: 0.40, HOUSE: 0.62}
#: Texture amplitude per class (× the unit noise fields).
TEXTURE = {FIELD: 0.025, FOREST: 0.05, WATER: 0.01, ROAD: 0.02, VILLAGE: 0.06, HOUSE: 0.04}
#: Full-scale value of the bit depths written.
FULL_SCALE = {8: 255.0, 12: 4095.0, 16: 65535.0}


def _smooth_field(rng: np.random.Generator, grid: Grid, wavelength: float) -> Array:
    """Unit random field, features of about ``wavelength`` m."""
    return band_noise(rng, grid, wavelength).astype(np.float64)


def _metres(grid: Grid) -> Affine:
    """Fine cell (col, row) → metres from the grid's top-left corner, y down (the frame the
    parcels and lines are drawn in)."""
    return Affine(grid.cell, 0.0, 0.0, 0.0, grid.cell, 0.0)


def _parcels(rng: np.random.Generator, grid: Grid) -> NDArray[np.int32]:
    """Field parcel ids (1…n): the Voronoi tiling of jittered seeds 200–450 m apart, as the
    nearest seed of every fine cell (exact Euclidean distance transform; shapely's Voronoi
    crashes with some GEOS builds)."""
    w, h = grid.ncols * grid.cell, grid.nrows * grid.cell
    spacing = rng.uniform(200.0, 450.0)
    gx, gy = np.meshgrid(np.arange(0.0, w, spacing), np.arange(0.0, h, spacing * 0.7))
    pts = np.column_stack([gx.ravel(), gy.ravel()]) + rng.uniform(-0.4, 0.4, (gx.size, 2)) * (
        spacing, 0.7 * spacing)
    cols = np.clip((pts[:, 0] / grid.cell).astype(np.int64), 0, grid.ncols - 1)
    rows = np.clip((pts[:, 1] / grid.cell).astype(np.int64), 0, grid.nrows - 1)
    seeds = np.zeros((grid.nrows, grid.ncols), np.int32)
    seeds[rows, cols] = np.arange(1, len(pts) + 1, dtype=np.int32)
    idx = ndimage.distance_transform_edt(seeds == 0, return_distances=False,
                                         return_indices=True)
    return seeds[idx[0], idx[1]]


def _lines(rng: np.random.Generator, grid: Grid, n: int, width: float) -> NDArray[np.bool_]:
    """``n`` gently bent lines across the grid, ``width`` m wide (roads, a river)."""
    w, h = grid.ncols * grid.cell, grid.nrows * grid.cell
    shapes = []
    for _ in range(n):
        a = rng.uniform(0, math.pi)
        c = rng.uniform(0.1, 0.9, 2) * (w, h)
        d = np.array([math.cos(a), math.sin(a)])
        t = np.linspace(-1.0, 1.0, 9)[:, None] * max(w, h)
        bend = np.cumsum(rng.normal(0, 0.05 * max(w, h) / 9, 9))[:, None] * d[::-1] * (1, -1)
        line = LineString(c + t * d + bend).buffer(width / 2, cap_style=2)
        shapes.append((line, 1))
    mask = features.rasterize(shapes, out_shape=(grid.nrows, grid.ncols),
                              transform=_metres(grid), dtype="uint8")
    return mask.astype(bool)


def _villages(rng: np.random.Generator, grid: Grid, cover: NDArray[np.int8]) -> None:
    """3–6 villages: a grey settlement area with small bright houses (in place)."""
    for _ in range(int(rng.integers(3, 7))):
        r0, c0 = rng.uniform(0.1, 0.9, 2) * (grid.nrows, grid.ncols)
        rad = rng.uniform(250.0, 550.0) / grid.cell
        win = (slice(max(int(r0 - rad), 0), int(r0 + rad) + 1),
               slice(max(int(c0 - rad), 0), int(c0 + rad) + 1))
        rr, cc = np.ogrid[win]
        d = np.hypot(rr - r0, cc - c0)
        sub = cover[win]
        sub[(d < rad) & (sub != WATER)] = VILLAGE
        for _ in range(int(rad * rad * 0.02)):
            hr, hc = rng.normal(0, rad / 2.2, 2) + (r0, c0)
            hs = rng.integers(2, 6, 2)
            r, c = int(hr), int(hc)
            if 0 <= r < grid.nrows - hs[0] and 0 <= c < grid.ncols - hs[1]:
                cover[r:r + hs[0], c:c + hs[1]] = HOUSE


def make_landscape(rng: np.random.Generator, grid: Grid) -> Dict[str, Any]:
    """Land cover, field parcels, their first-date levels and the (date-independent) texture
    of a fine grid."""
    cover = np.full((grid.nrows, grid.ncols), FIELD, np.int8)
    parcels = _parcels(rng, grid)
    cover[_smooth_field(rng, grid, 3000.0) > 0.7] = FOREST
    cover[_smooth_field(rng, grid, 2500.0) > 1.8] = WATER
    cover[_lines(rng, grid, 1, 40.0)] = WATER  # a river
    _villages(rng, grid, cover)
    cover[_lines(rng, grid, int(rng.integers(5, 10)), 12.0)] = ROAD
    fine = _smooth_field(rng, grid, 4.0 * grid.cell)
    coarse = _smooth_field(rng, grid, 120.0)
    field_level = rng.uniform(0.12, 0.5, int(parcels.max()) + 1)
    return {"cover": cover, "parcels": parcels, "fine": fine, "coarse": coarse,
            "field_level": field_level}


def _date_values(rng: np.random.Generator, land: Dict[str, Any], later: bool) -> Array:
    """Reflectance-like values (0–1) of one date on the fine grid.

    The later date: each field re-cropped with probability ¼ (a new level), else its level
    changed a little; per-class gain (0.7–1.3) and offset; water and villages inverted.
    """
    cover, parcels = land["cover"], land["parcels"]
    field_level = land["field_level"]
    n = len(field_level)
    levels = dict(LEVEL)
    gains = dict.fromkeys(TEXTURE, 1.0)
    if later:
        field_level = np.where(rng.uniform(size=n) < 0.25, rng.uniform(0.12, 0.5, n),
                               field_level * rng.uniform(0.85, 1.15, n))
        for c in (FOREST, ROAD, HOUSE):
            levels[c] = LEVEL[c] * rng.uniform(0.7, 1.3) + rng.uniform(-0.03, 0.03)
            gains[c] = rng.uniform(0.7, 1.3)
        levels[WATER], gains[WATER] = rng.uniform(0.25, 0.35), -1.0  # ice / turbid: inverted
        levels[VILLAGE], gains[VILLAGE] = rng.uniform(0.1, 0.2), -1.0
    out = field_level[parcels]
    tex = land["fine"] + 0.5 * land["coarse"]
    for c, amp in TEXTURE.items():
        m = cover == c
        if c != FIELD:
            out[m] = levels[c]
        out[m] += gains[c] * amp * tex[m]
    return out


def _clouds(rng: np.random.Generator, shape: Tuple[int, int], share: float
            ) -> Tuple[Array, Array]:
    """Cloud opacity (0–1, soft edges; ``share`` of the pixels above ½) and the opacity of
    their shadows (the same field shifted away from the sun)."""
    h, w = shape
    pad = 80
    g = Grid(0.0, 0.0, 1.0, h + 2 * pad, w + 2 * pad)
    f = _smooth_field(rng, g, rng.uniform(150.0, 300.0)) + 0.25 * _smooth_field(rng, g, 20.0)
    t = float(np.quantile(f[pad:pad + h, pad:pad + w], 1.0 - share))
    alpha = np.clip(0.5 + (f - t) / 0.6, 0.0, 1.0)
    a = rng.uniform(0, 2 * math.pi)
    dr, dc = (round(v) for v in rng.uniform(20, 50) * np.array([math.sin(a), math.cos(a)]))
    shadow = alpha[pad + dr:pad + dr + h, pad + dc:pad + dc + w]
    return alpha[pad:pad + h, pad:pad + w], shadow


def _target_affine(rng: np.random.Generator, gsd: float, width: int, height: int,
                   centre: Tuple[float, float], mirror: bool) -> Array:
    """Image → map (3 × 3): any rotation, pixel size ``gsd`` × 0.8–1.25 (log-uniform)."""
    s = gsd * math.exp(rng.uniform(math.log(0.8), math.log(1.25)))
    ang = rng.uniform(0, 2 * math.pi)
    R = np.array([[math.cos(ang), -math.sin(ang)], [math.sin(ang), math.cos(ang)]])
    L = s * R @ np.diag([-1.0 if mirror else 1.0, -1.0])  # rows point down
    T = np.eye(3)
    T[:2, :2] = L
    T[:2, 2] = np.asarray(centre) - L @ np.array([(width - 1) / 2, (height - 1) / 2])
    return T


def _sample(values: Array, grid: Grid, T: Array, width: int, height: int) -> Array:
    """The fine-grid ``values`` at the target's pixels (2 × 2 sub-samples, bilinear)."""
    acc = np.zeros((height, width))
    rr, cc = np.mgrid[0:height, 0:width].astype(np.float64)
    for dy in (-0.25, 0.25):
        for dx in (-0.25, 0.25):
            x = T[0, 0] * (cc + dx) + T[0, 1] * (rr + dy) + T[0, 2]
            y = T[1, 0] * (cc + dx) + T[1, 1] * (rr + dy) + T[1, 2]
            col, row = grid.index(x, y)
            acc += ndimage.map_coordinates(values, [row, col], order=1, mode="nearest")
    return acc / 4.0


def _quantise(v: Array, bits: int, rng: np.random.Generator, noise: float) -> NDArray[Any]:
    """0–1 values with sensor noise as ``bits``-bit integers (uint8 or uint16)."""
    full = FULL_SCALE[bits]
    q = np.round(np.clip(v + rng.normal(0, noise, v.shape), 0.0, 1.0) * full)
    return q.astype(np.uint8 if bits == 8 else np.uint16)


def image_pair_case(folder: PathLike, seed: int = 0, width: int = 1000, height: int = 1000,
                    gsd: float = 10.0, ref_factor: float = 1.4, bits: int = 8,
                    cloud_share: Optional[float] = None, mirror: Optional[bool] = None,
                    noise: float = 0.01) -> Dict[str, Any]:
    """One multi-temporal case: reference GeoTIFF, target image, truth (image → map, 3 × 3).

    Parameters
    ----------
    folder : path
        Written: ``reference.tif`` (georeferenced), ``image.tif`` (none), ``clouds.tif``
        (cloud opacity of the target, 0–255).
    seed : int
        Everything follows from it (landscape, change, geometry, clouds).
    width, height : int
        Target size (px); the reference is ``ref_factor`` × the larger side, square.
    gsd : float
        Reference pixel size (m).
    bits : {8, 12, 16}
        8: uint8; 12 or 16: uint16 with that many significant bits.
    cloud_share : float, optional
        Share of target pixels under cloud (default: 0.3–0.6 by the seed).
    mirror : bool, optional
        Mirror the target (default: odd seeds).
    noise : float
        Sensor noise σ (share of full scale).

    Returns
    -------
    dict
        ``reference``, ``image``, ``clouds`` (paths), ``truth`` (3 × 3), ``width``, ``height``,
        ``crs``, ``cloud_share``, ``mirrored``, ``scale`` (target / reference pixel),
        ``angle_deg``, ``bits``.
    """
    if bits not in FULL_SCALE:
        raise ValueError(f"bits must be one of {sorted(FULL_SCALE)}")
    folder = Path(folder)
    rng = np.random.default_rng(seed)
    n_ref = round(ref_factor * max(width, height))
    x0, y1 = ORIGIN
    centre = (x0 + 0.5 * n_ref * gsd, y1 - 0.5 * n_ref * gsd)
    mirror = bool(seed % 2) if mirror is None else bool(mirror)
    shift = rng.uniform(-0.08, 0.08, 2) * n_ref * gsd
    T = _target_affine(rng, gsd, width, height, (centre[0] + shift[0], centre[1] + shift[1]),
                       mirror)
    # the fine grid covers the reference and the whole target footprint
    half = max(0.5 * n_ref * gsd, 0.5 * math.hypot(width, height) * 1.25 * gsd
               + float(np.abs(shift).max())) + 4 * gsd
    cell = gsd / 2
    n_fine = 2 * math.ceil(half / cell)  # even: the reference pixels are whole 2 × 2 cells
    grid = Grid(centre[0] - n_fine * cell / 2, centre[1] + n_fine * cell / 2, cell, n_fine,
                n_fine)
    land = make_landscape(rng, grid)
    first = _date_values(rng, land, later=False)
    later = _date_values(rng, land, later=True)
    # reference: 2 × 2 means of the fine cells inside its extent
    c0 = round((x0 - grid.x0) / cell)
    r0 = round((grid.y1 - y1) / cell)
    ref = first[r0:r0 + 2 * n_ref, c0:c0 + 2 * n_ref].reshape(n_ref, 2, n_ref, 2).mean((1, 3))
    share = rng.uniform(0.3, 0.6) if cloud_share is None else float(cloud_share)
    alpha, shadow = _clouds(rng, (height, width), share)
    tgt = _sample(later, grid, T, width, height) * (1.0 - 0.4 * shadow)
    cloud_tex = 0.04 * _smooth_field(rng, Grid(0.0, 0.0, 1.0, height, width), 12.0)
    tgt = (1.0 - alpha) * tgt + alpha * (0.85 + cloud_tex)
    ref_path = write_raster(folder / "reference.tif", _quantise(ref, bits, rng, noise),
                            transform=Affine(gsd, 0, x0, 0, -gsd, y1), crs=CRS)
    img_path = write_raster(folder / "image.tif", _quantise(tgt, bits, rng, noise))
    clouds = write_raster(folder / "clouds.tif", np.round(alpha * 255).astype(np.uint8))
    ang = math.degrees(math.atan2(T[1, 0], T[0, 0])) % 360.0
    return {"reference": str(ref_path), "image": str(img_path), "clouds": str(clouds),
            "truth": T, "width": width, "height": height, "crs": CRS,
            "cloud_share": float((alpha > 0.5).mean()), "mirrored": mirror,
            "scale": float(math.sqrt(abs(np.linalg.det(T[:2, :2]))) / gsd),
            "angle_deg": ang, "bits": bits}
