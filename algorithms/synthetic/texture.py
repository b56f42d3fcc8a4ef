r"""Object-space texture (RGB albedo) of a synthetic scene.

The albedo raster lies on the truth grid (cell ≤ GSD/2) and is sampled bilinearly by the
renderer. Per land-cover class it holds: meadow, furrowed fields (sinusoidal furrows of period
1.5–2.5 m whose lines run at ``texture_direction`` degrees counter-clockwise from the flight
direction +X), crop rows, bare soil, asphalt roads with dashed centre lines, a gravel crest with
rails on the embankment, water in the ditch, roofs in several looks (:func:`roof_albedo`), dark
tree crowns (their clumps textured by the shading). Everything is modulated by band-limited
noise (λ ≈ 1 m and 5 m, plus a small per-band part) and by Lambert shading of the DSM,

.. math:: s = \frac{0.35 + 0.65\,\max(0, \mathbf n\cdot\mathbf l)}{0.35 + 0.65\,l_z}

(sun from azimuth 150°, elevation 45°; 1 on flat ground). Check-point targets (a bright disc of
radius :math:`r` on a dark pad of radius 3r) are painted here too, but the renderer evaluates
them analytically from their centres (see :mod:`.render`).
"""

from __future__ import annotations

from typing import Dict, Tuple

import numpy as np

from .objects import (
    BUILDING,
    EMBANKMENT,
    ROAD,
    TREE,
    WATER,
    Building,
    SceneObjects,
    parcel_type_map,
)
from .terrain import Grid, band_noise

#: albedo of the check-point disc and its pad (all bands)
DISC_ALBEDO = 0.92
PAD_ALBEDO = 0.08
PAD_FACTOR = 3.0

_COLOURS = {
    "meadow": (0.30, 0.42, 0.22),
    "furrowed": (0.44, 0.34, 0.25),
    "crop": (0.46, 0.50, 0.26),
    "bare": (0.56, 0.48, 0.37),
    "road": (0.23, 0.23, 0.24),
    "slope": (0.33, 0.41, 0.23),
    "gravel": (0.52, 0.49, 0.44),
    "water": (0.10, 0.16, 0.21),
    "tree": (0.14, 0.27, 0.11),
    "roof_red": (0.56, 0.26, 0.19),
    "roof_grey": (0.40, 0.37, 0.36),
    "roof_flat": (0.58, 0.58, 0.55),
    "roof_moss": (0.36, 0.33, 0.24),
    "chimney": (0.50, 0.30, 0.24),
}
_SAND = {"meadow": (0.62, 0.55, 0.42), "bare": (0.68, 0.60, 0.46)}
_ROCK = {"meadow": (0.45, 0.43, 0.40), "bare": (0.52, 0.49, 0.45)}


def hillshade(dsm: np.ndarray, cell: float, azimuth: float = 150.0, elevation: float = 45.0
              ) -> np.ndarray:
    """Lambert shading factor of a height grid, 1 on flat ground (float32)."""
    gy, gx = np.gradient(dsm.astype(np.float32), cell)
    gy = -gy  # rows run southwards
    az, el = np.radians(azimuth), np.radians(elevation)
    lx, ly, lz = np.sin(az) * np.cos(el), np.cos(az) * np.cos(el), np.sin(el)
    dot = (-gx * lx - gy * ly + lz) / np.sqrt(gx * gx + gy * gy + 1.0)
    return ((0.35 + 0.65 * np.clip(dot, 0.0, None)) / (0.35 + 0.65 * lz)).astype(np.float32)


def _paint(albedo: np.ndarray, mask: np.ndarray, colour: Tuple[float, float, float],
           factor: object = 1.0) -> None:
    for b in range(3):
        value = colour[b] * factor if np.ndim(factor) == 0 else (colour[b] * factor)[mask]
        albedo[b][mask] = value


def _tiles(b: Building, u: np.ndarray, v: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Factor of a tiled roof: courses of 0.4 m down the slope, tiles 0.35 m wide, offset by
    half a tile every other course, each tile ±8 % brighter or darker, a dark seam under every
    course, dark ridge tiles and a bright gutter at the eaves."""
    course, tile = 0.4, 0.35
    iv = np.floor(np.abs(v) / course).astype(np.int64)
    shift = np.where(iv % 2 == 1, tile / 2.0, 0.0)
    iu = np.floor((u + b.length / 2.0 + 1.0 + shift) / tile).astype(np.int64)
    table = 1.0 + 0.08 * rng.standard_normal((int(b.length / tile) + 8, int(b.width) + 4))
    factor = table[np.clip(iu, 0, table.shape[0] - 1), np.clip(iv, 0, table.shape[1] - 1)]
    frac = np.mod(np.abs(v), course) / course
    factor = np.where(frac > 0.78, 0.72 * factor, factor)  # shadowed seam under a course
    factor = np.where(np.abs(v) < 0.2, 0.62, factor)  # ridge tiles
    return np.where(np.abs(v) > b.width / 2.0 - 0.25, 1.3, factor)  # gutter


def _fixtures(b: Building, u: np.ndarray, v: np.ndarray, rng: np.random.Generator,
              factor: np.ndarray) -> np.ndarray:
    """Skylights (1–1.4 m, dark glass in a bright frame) and vents (0.3–0.5 m, dark or bright)
    painted on a flat roof, kept 1 m inside its edge."""
    n_sky, n_vent = int(rng.integers(1, 4)), int(rng.integers(2, 6))
    for k in range(n_sky + n_vent):
        side = rng.uniform(1.0, 1.4) if k < n_sky else rng.uniform(0.3, 0.5)
        cu = rng.uniform(-1.0, 1.0) * (b.length / 2.0 - 1.0 - side / 2.0)
        cv = rng.uniform(-1.0, 1.0) * (b.width / 2.0 - 1.0 - side / 2.0)
        d = np.maximum(np.abs(u - cu), np.abs(v - cv))
        if k < n_sky:
            factor = np.where(d <= side / 2.0, 1.35, factor)
            factor = np.where(d <= side / 2.0 - 0.12, 0.3, factor)
        else:
            factor = np.where(d <= side / 2.0, 0.45 if rng.uniform() < 0.6 else 1.45, factor)
    return factor


def roof_albedo(b: Building, u: np.ndarray, v: np.ndarray, fine: np.ndarray,
                colours: Dict[str, Tuple[float, float, float]]) -> np.ndarray:
    """RGB albedo (3, …) of the roof of ``b`` at building-frame coordinates ``u``, ``v``.

    Looks by ``b.style`` (:data:`.objects.ROOF_STYLES`): gabled ``stripes`` (the plain 1 m
    pattern across the slope), ``tiles`` (2-D tile courses, ridge and eaves lines) and
    ``two_tone`` (tiles whose two halves differ in colour, e.g. one mossy); flat ``plain``
    (faint noise with a bright rim), ``gravel`` (per-cell grain of 4–10 % contrast at the
    0.1–0.2 m cell) and ``fixtures`` (gravel with skylights and vents). Chimney squares get
    brick with a dark flue on top. Random parts come from ``b.texture_seed``.
    """
    rng = np.random.default_rng(b.texture_seed)
    u, v = np.broadcast_arrays(u, v)
    one = np.ones(u.shape, dtype=np.float32)
    rim = (np.abs(u) > b.length / 2.0 - 0.4) | (np.abs(v) > b.width / 2.0 - 0.4)
    if b.roof == "gabled":
        colour = colours["roof_red"] if b.id % 3 else colours["roof_grey"]
        rgb = np.stack([one * c for c in colour])
        if b.style in ("tiles", "two_tone"):
            factor = _tiles(b, u, v, rng) * (1.0 + 0.04 * fine)
            if b.style == "two_tone":
                other = colours["roof_moss"] if b.id % 2 else colours["roof_grey"]
                rgb = np.where(v[None] > 0.0, np.array(other)[:, None, None], rgb)
        else:
            factor = 0.85 + 0.15 * np.sin(2.0 * np.pi * np.abs(v) / 1.0)
    else:
        rgb = np.stack([one * c for c in colours["roof_flat"]])
        if b.style in ("gravel", "fixtures"):
            grain = rng.uniform(0.04, 0.10)
            factor = 1.0 + grain * rng.standard_normal(u.shape) + 0.04 * fine
            factor = np.where(rim, 1.2, factor)
            if b.style == "fixtures":
                factor = _fixtures(b, u, v, rng, factor)
        else:
            factor = np.where(rim, 1.25, 0.95 + 0.1 * fine)
    for cu, cv, side, _top in b.chimneys:
        d = np.maximum(np.abs(u - cu), np.abs(v - cv))
        brick = d <= side / 2.0
        rgb = np.where(brick[None], np.array(colours["chimney"])[:, None, None], rgb)
        factor = np.where(brick, np.where(d <= side / 2.0 - 0.15, 0.25, 1.0), factor)
    return (rgb * factor).astype(np.float32)


def make_albedo(grid: Grid, dtm: np.ndarray, dsm: np.ndarray, landcover: np.ndarray,
                obj: SceneObjects, rng: np.random.Generator, terrain: str,
                texture_direction: float, discs: np.ndarray, disc_radius: float) -> np.ndarray:
    """RGB albedo (3, rows, cols) float32 in [0, 1].

    Parameters
    ----------
    texture_direction : float
        Direction of the furrow lines, degrees counter-clockwise from +X (the flight direction).
    discs : ndarray (N, 3)
        Check-point centres; painted as disc + pad.
    disc_radius : float
        Radius of the bright disc (m); the pad has :data:`PAD_FACTOR` × this radius.
    """
    X, Y = grid.xs, grid.ys
    albedo = np.empty((3,) + grid.shape, dtype=np.float32)
    colours = dict(_COLOURS)
    if terrain == "dunes":
        colours.update(_SAND)
    elif terrain == "steep":
        colours.update(_ROCK)

    ptype = parcel_type_map(grid, obj)
    fine = band_noise(rng, grid, 1.0)
    _paint(albedo, ptype == 0, colours["meadow"], 1.0 + 0.10 * fine)
    theta = np.radians(texture_direction)
    period = rng.uniform(1.5, 2.5)
    w = -X * np.sin(theta) + Y * np.cos(theta)
    furrow = (0.78 + 0.22 * np.sin(2.0 * np.pi * w / period)).astype(np.float32)
    del w
    # band-limited noise under the furrows and crop rows as well (seed-000 §7: "band-limited
    # noise plus field patches"): soil clods and gaps; a pure sinusoid would be ambiguous
    # by whole periods across the furrows, which real fields are not
    _paint(albedo, ptype == 1, colours["furrowed"], furrow * (1.0 + 0.10 * fine))
    del furrow
    c, s = np.cos(obj.parcel_angle), np.sin(obj.parcel_angle)
    rows_ = (0.85 + 0.15 * np.sin(2.0 * np.pi * (X * c + Y * s) / 3.0)).astype(np.float32)
    _paint(albedo, ptype == 2, colours["crop"], rows_ * (1.0 + 0.10 * fine))
    del rows_
    _paint(albedo, ptype == 3, colours["bare"], 1.0 + 0.15 * fine)
    del ptype

    # road with a dashed centre line
    road = landcover == ROAD
    d_r = obj.road.across(X, Y)
    s_r = obj.road.along(X, Y)
    dash = (np.abs(d_r) < 0.09) & (np.mod(s_r, 9.0) < 3.0) & road
    _paint(albedo, road, colours["road"], 1.0 + 0.05 * fine)
    _paint(albedo, dash, (0.85, 0.85, 0.83))
    del d_r, s_r, dash, road

    # embankment: grass slopes, gravel crest with two tracks
    emb = landcover == EMBANKMENT
    d_e = obj.embankment.across(X, Y)
    _paint(albedo, emb, colours["slope"], 1.0 + 0.12 * fine)
    crest = emb & (np.abs(d_e) <= obj.crest_width / 2.0)
    _paint(albedo, crest, colours["gravel"], 1.0 + 0.2 * fine)
    rails = np.zeros(grid.shape, dtype=bool)
    for track in (-2.0, 2.0):
        for rail in (-0.72, 0.72):
            rails |= np.abs(d_e - track - rail) < 0.07
    _paint(albedo, rails & crest, (0.16, 0.15, 0.15))
    del d_e, crest, rails, emb

    water = landcover == WATER
    d_d = np.abs(obj.ditch.across(X, Y))
    _paint(albedo, water, colours["slope"], 0.85 + 0.1 * fine)
    _paint(albedo, water & (d_d <= obj.ditch_bottom / 2.0 + 0.4), colours["water"],
           1.0 + 0.05 * fine)
    del d_d, water

    # roofs
    for b in obj.buildings:
        r_, c_ = grid.window(b.x - b.radius, b.y - b.radius, b.x + b.radius, b.y + b.radius)
        u, v = b.local(X[:, c_], Y[r_, :])
        inside = (landcover[r_, c_] == BUILDING) & (np.abs(u) <= b.length / 2.0) & (
            np.abs(v) <= b.width / 2.0)
        rgb = roof_albedo(b, u, v, fine[r_, c_], colours)
        for k in range(3):
            sub = albedo[k, r_, c_]
            sub[inside] = rgb[k][inside]
    _paint(albedo, landcover == TREE, colours["tree"], 1.0 + 0.25 * fine)

    # band-limited noise over everything, a little of it per band, then shading
    common = 1.0 + 0.08 * band_noise(rng, grid, 5.0) + 0.05 * band_noise(rng, grid, 20.0)
    shade = hillshade(dsm, grid.cell)
    for k in range(3):
        albedo[k] *= common * shade * (1.0 + 0.03 * band_noise(rng, grid, 2.0))
    del common, shade, fine
    np.clip(albedo, 0.02, 0.95, out=albedo)

    # check-point targets
    for x, y, _z in discs:
        R = PAD_FACTOR * disc_radius
        r_, c_ = grid.window(x - R, y - R, x + R, y + R)
        d = np.hypot(X[:, c_] - x, Y[r_, :] - y)
        for k in range(3):
            sub = albedo[k, r_, c_]
            sub[d <= R] = PAD_ALBEDO
            sub[d <= disc_radius] = DISC_ALBEDO
    return albedo
