r"""Rendering of frame images by ray casting against the truth DSM, with occlusion.

Every (sub-)pixel ray :math:`X(t) = C + t\,\mathbf d` (scaled so that :math:`d_z = -1`, i.e.
:math:`t` is the height descended) meets the bilinear DSM surface :math:`S(x, y)` at the
smallest :math:`t` with :math:`f(t) = C_z - t - S(X(t), Y(t)) \le 0`.

**Marching with a max pyramid.** Level 0 is the DSM itself; level :math:`l \ge 1` holds, for
blocks of :math:`4^l` cells, the maximum of the 3×3-dilated DSM over the block, dilated again by
one block (and a border of +∞). A ray segment that starts in a block and moves at most one block
horizontally stays in the 3×3 block neighbourhood, and the bilinear surface there is below the
stored bound :math:`B`, so the segment is *clear* when its lower end is above :math:`B`. Each ray
keeps a level: a clear segment advances it (0.9 blocks) and, after two clear steps in a row,
moves it one level up; otherwise the ray descends to height :math:`B` if it is still above it
and goes one level down. On level 0 the ray advances in steps of ½ DSM cell horizontally (at
most 2 cells vertically) and tests :math:`f` exactly. The first sign change brackets the
**first** crossing (occlusion is exact up to features thinner than half a cell), which 9
bisections and a final regula-falsi step refine to ≈ 10⁻³ of a cell. All rays of a row tile
are processed together in cache-sized chunks; finished rays leave the working set.

**Shading.** The albedo raster is sampled bilinearly at the hit point; check-point targets are
evaluated analytically from their centres: with :math:`\rho` the distance to the centre and
:math:`w` the ground size of a sub-sample, coverage :math:`k(r) = \mathrm{clip}((r-\rho)/w +
\tfrac12, 0, 1)` of the disc (radius r) and the pad (radius 3r) blend the albedos. The ramp is
the exact box-filtered coverage of a straight edge, so the rendered blob is symmetric about the
projected centre and its centroid is the projection of the centre.

**Radiometry.** Sub-samples are averaged (area/box MTF), then
:math:`DN = g_b\,255\,\rho\,v + o + n`, with per-image gains :math:`g_b` (0.92–1.08, ±2 % per
band), offset :math:`o` (±8 DN), vignetting :math:`v = 1 - 0.5\,(1 - \cos^4\theta)` (θ the
off-axis angle) and Gaussian noise σ = 2 DN, rounded and clipped to 8 bit.

Note for later merging: :mod:`..geometry.dem_intersection` does the same marching without the
pyramid (fine for monoplotting a few points, too slow for millions of rays).
"""

from __future__ import annotations

from typing import Callable, List, Optional, Tuple

import numpy as np
from scipy import ndimage

from ..geometry.camera import Camera
from ..geometry.orientation import ExteriorOrientation
from .terrain import Grid
from .texture import DISC_ALBEDO, PAD_ALBEDO, PAD_FACTOR

_FACTOR = 4
_CHUNK = 1 << 17


class Renderer:
    """Ray caster for one scene.

    Parameters
    ----------
    grid : Grid
    dsm : ndarray (rows, cols)
        Truth DSM (finite everywhere).
    albedo : ndarray (3, rows, cols) float32
    discs : ndarray (N, 3)
        Check-point target centres.
    disc_radius : float
        Radius (m) of the bright disc; the dark pad has 3 × this radius.
    """

    def __init__(self, grid: Grid, dsm: np.ndarray, albedo: np.ndarray, discs: np.ndarray,
                 disc_radius: float) -> None:
        self.grid = grid
        self.dsm = np.ascontiguousarray(dsm, dtype=np.float64)
        self.flat = self.dsm.ravel()
        self.albedo = [np.ascontiguousarray(albedo[b]).ravel() for b in range(albedo.shape[0])]
        self.zmin = float(self.dsm.min())
        self.zmax = float(self.dsm.max())
        # max pyramid; every level gets a border of one block of +inf (never clear)
        level = ndimage.maximum_filter(self.dsm, size=3, mode="nearest")
        bounds: List[np.ndarray] = []
        while max(level.shape) > 4:
            h, w = level.shape
            H, W = -(-h // _FACTOR) * _FACTOR, -(-w // _FACTOR) * _FACTOR
            padded = np.pad(level, ((0, H - h), (0, W - w)), mode="edge")
            level = padded.reshape(H // _FACTOR, _FACTOR, W // _FACTOR, _FACTOR).max(axis=(1, 3))
            bound = ndimage.maximum_filter(level, size=3, mode="nearest")
            bounds.append(np.pad(bound, 1, mode="constant", constant_values=np.inf))
        self.levels = len(bounds)  # levels 1..L
        self.bound_flat = np.concatenate([b.ravel() for b in bounds])
        self.offsets = np.concatenate([[0, 0], np.cumsum([b.size for b in bounds])[:-1]]
                                      ).astype(np.intp)
        self.ncols_l = np.array([1] + [b.shape[1] for b in bounds], dtype=np.intp)
        self.block = np.array([float(_FACTOR ** k) for k in range(self.levels + 1)])
        self.inv_block = 1.0 / self.block
        self.step = np.where(np.arange(self.levels + 1) == 0, 0.5, 0.9 * self.block)
        # check-point targets: lookup grid of cells 2 pad radii wide
        self.discs = np.asarray(discs, dtype=float).reshape(-1, 3)
        self.disc_radius = float(disc_radius)
        self.pad_radius = PAD_FACTOR * self.disc_radius
        self.disc_cell = 2.0 * self.pad_radius
        nr = int(np.ceil(grid.nrows * grid.cell / self.disc_cell)) + 1
        nc = int(np.ceil(grid.ncols * grid.cell / self.disc_cell)) + 1
        self.disc_lookup = np.full((nr, nc), -1, dtype=np.intp)
        for k, (x, y, _z) in enumerate(self.discs):
            i = int((grid.y1 - y) // self.disc_cell)
            j = int((x - grid.x0) // self.disc_cell)
            self.disc_lookup[max(i - 1, 0):i + 2, max(j - 1, 0):j + 2] = k

    # -- sampling --------------------------------------------------------------------------------
    def _bilinear(self, flat: np.ndarray, u: np.ndarray, v: np.ndarray
                  ) -> Tuple[np.ndarray, np.ndarray]:
        """Bilinear value at grid coordinates u (cols), v (rows) with cell edges at integers.

        Returns the values and a mask of points inside the hull of cell centres.
        """
        nr, nc = self.grid.nrows, self.grid.ncols
        col = u - 0.5
        row = v - 0.5
        inside = (col >= 0) & (col <= nc - 1) & (row >= 0) & (row <= nr - 1)
        # indices are clipped only to stay valid; values outside the hull are flagged
        c0 = np.minimum(np.maximum(np.floor(col), 0.0), nc - 2).astype(np.intp)
        r0 = np.minimum(np.maximum(np.floor(row), 0.0), nr - 2).astype(np.intp)
        fc = col - c0
        fr = row - r0
        i00 = r0 * nc + c0
        z00, z01 = flat[i00], flat[i00 + 1]
        z10, z11 = flat[i00 + nc], flat[i00 + nc + 1]
        top = z00 + fc * (z01 - z00)
        bottom = z10 + fc * (z11 - z10)
        return top + fr * (bottom - top), inside

    # -- ray casting -----------------------------------------------------------------------------
    def trace(self, origin: np.ndarray, directions: np.ndarray, n_bisect: int = 9
              ) -> np.ndarray:
        """First intersections of rays from ``origin`` with the DSM.

        Parameters
        ----------
        origin : ndarray (3,)
            Projection centre.
        directions : ndarray (N, 3)
            Ray directions pointing downwards (d_z < 0).

        Returns
        -------
        ndarray (N, 3)
            Hit points; NaN rows for rays that leave the grid or do not point down.
        """
        g = self.grid
        d = np.asarray(directions, dtype=float)
        n = d.shape[0]
        if n > _CHUNK:  # chunks that stay in the CPU cache are markedly faster
            return np.concatenate([self.trace(origin, d[k:k + _CHUNK], n_bisect)
                                   for k in range(0, n, _CHUNK)])
        with np.errstate(divide="ignore", invalid="ignore"):
            dn = d / -d[:, 2:3]
        down = d[:, 2] < 0
        du = np.where(down, dn[:, 0] / g.cell, 0.0)
        dv = np.where(down, -dn[:, 1] / g.cell, 0.0)
        speed = np.maximum(np.hypot(du, dv), 1e-12)
        cz = float(origin[2])
        u0 = (float(origin[0]) - g.x0) / g.cell
        v0 = (g.y1 - float(origin[1])) / g.cell
        t_lo = np.full(n, np.nan)
        t_hi = np.full(n, np.nan)
        top = self.levels
        ray = np.nonzero(down)[0]
        du_w, dv_w = du[ray], dv[ray]
        s_w = speed[ray]
        t = np.full(ray.size, max(cz - self.zmax - 1e-3, 0.0))
        # start on the level whose blocks match the horizontal travel through the height range
        travel = s_w * (self.zmax - self.zmin + 1.0)
        lvl = np.clip(np.ceil(np.log(np.maximum(travel, 1.0)) / np.log(_FACTOR)), 1, top
                      ).astype(np.intp) if top else np.zeros(ray.size, dtype=np.intp)
        cap = np.full(top + 1, np.inf)
        cap[0] = 2.0 * g.cell  # longest vertical step on level 0 (m)
        up = np.minimum(np.arange(top + 1) + 1, top)
        streak = np.zeros(ray.size, dtype=bool)
        for _ in range(100000):
            if ray.size == 0:
                break
            dt = np.minimum(self.step[lvl] / s_w, cap[lvl])
            t1 = t + dt
            z1 = cz - t1
            fine = lvl == 0
            # after a clear step: one level up if the previous step was clear too (hysteresis
            # avoids the costly up-blocked-down cycle), else stay
            new_lvl = np.where(streak, up[lvl], lvl)
            new_streak = ~streak
            advance = np.ones(ray.size, dtype=bool)
            done = np.zeros(ray.size, dtype=bool)
            ci = np.nonzero(~fine)[0]
            if ci.size:
                lc = lvl[ci]
                tc = t[ci]
                inv = self.inv_block[lc]
                bi = ((u0 + tc * du_w[ci]) * inv + 1.0).astype(np.intp)
                bj = ((v0 + tc * dv_w[ci]) * inv + 1.0).astype(np.intp)
                bound = self.bound_flat[self.offsets[lc] + bj * self.ncols_l[lc] + bi]
                short = z1[ci] <= bound
                blocked = ci[short]
                # a ray still above the bound may descend to it before going a level down
                partial = short & (cz - tc > bound)
                t1[ci[partial]] = cz - bound[partial]
                advance[blocked] = partial[short]
                new_lvl[blocked] = lvl[blocked] - 1
                new_streak[blocked] = False
            fi = np.nonzero(fine)[0]
            if fi.size:
                tt = t1[fi]
                surf, inside = self._bilinear(self.flat, u0 + tt * du_w[fi], v0 + tt * dv_w[fi])
                hit = z1[fi] <= surf
                hr = fi[hit & inside]
                t_lo[ray[hr]] = t[hr]
                t_hi[ray[hr]] = t1[hr]
                done[fi[hit | ~inside]] = True
            t = np.where(advance, t1, t)
            if done.any():
                keep = ~done
                ray, t, lvl, streak = ray[keep], t[keep], new_lvl[keep], new_streak[keep]
                du_w, dv_w, s_w = du_w[keep], dv_w[keep], s_w[keep]
            else:
                lvl, streak = new_lvl, new_streak

        ok = np.isfinite(t_lo)
        ray = np.nonzero(ok)[0]
        a, b = t_lo[ray], t_hi[ray]
        for _ in range(n_bisect):
            m = 0.5 * (a + b)
            surf, _inside = self._bilinear(self.flat, u0 + m * du[ray], v0 + m * dv[ray])
            above = cz - m > surf
            a = np.where(above, m, a)
            b = np.where(above, b, m)
        fa = cz - a - self._bilinear(self.flat, u0 + a * du[ray], v0 + a * dv[ray])[0]
        fb = cz - b - self._bilinear(self.flat, u0 + b * du[ray], v0 + b * dv[ray])[0]
        denom = fa - fb
        frac = np.where(denom > 0, fa / np.where(denom > 0, denom, 1.0), 0.5)
        t_hit = a + np.clip(frac, 0.0, 1.0) * (b - a)
        points = np.full((n, 3), np.nan)
        points[ray, 0] = origin[0] + t_hit * dn[ray, 0]
        points[ray, 1] = origin[1] + t_hit * dn[ray, 1]
        points[ray, 2] = cz - t_hit
        return points

    # -- albedo ----------------------------------------------------------------------------------
    def shade(self, points: np.ndarray, ramp: float) -> np.ndarray:
        """Albedo (N, bands) at hit points; NaN points give 0. ``ramp``: sub-sample size (m)."""
        g = self.grid
        ok = np.isfinite(points[:, 0])
        x = np.where(ok, points[:, 0], g.x0)
        y = np.where(ok, points[:, 1], g.y1)
        u = (x - g.x0) / g.cell
        v = (g.y1 - y) / g.cell
        out = np.empty((points.shape[0], len(self.albedo)))
        for b, flat in enumerate(self.albedo):
            out[:, b] = self._bilinear(flat, u, v)[0]
        if self.discs.size:
            i = np.floor((g.y1 - y) / self.disc_cell).astype(np.intp)
            j = np.floor((x - g.x0) / self.disc_cell).astype(np.intp)
            nr, nc = self.disc_lookup.shape
            k = self.disc_lookup[np.clip(i, 0, nr - 1), np.clip(j, 0, nc - 1)]
            sel = np.nonzero((k >= 0) & ok)[0]
            if sel.size:
                c = self.discs[k[sel]]
                rho = np.hypot(x[sel] - c[:, 0], y[sel] - c[:, 1])
                pad = np.clip((self.pad_radius - rho) / ramp + 0.5, 0.0, 1.0)
                disc = np.clip((self.disc_radius - rho) / ramp + 0.5, 0.0, 1.0)
                target = PAD_ALBEDO + (DISC_ALBEDO - PAD_ALBEDO) * disc
                out[sel] = out[sel] * (1.0 - pad)[:, None] + (pad * target)[:, None]
        out[~ok] = 0.0
        return out


def render_image(renderer: Renderer, camera: Camera, eo: ExteriorOrientation, supersample: int,
                 tile_rays: int, seed_sequence: np.random.SeedSequence, ramp: float,
                 progress: Optional[Callable[[float], None]] = None) -> Tuple[np.ndarray, int]:
    """Render one 8-bit image (bands, rows, cols) and count the rays that missed the DSM.

    Parameters
    ----------
    supersample : int
        ss: ss × ss rays per pixel at offsets (k + ½)/ss − ½, averaged.
    tile_rays : int
        Rays per row tile (bounds memory).
    seed_sequence : numpy.random.SeedSequence
        Source of this image's radiometry (gains, offset, noise per tile).
    ramp : float
        Ground size (m) of one sub-sample, for the analytic targets.
    progress : callable, optional
        Called with the fraction done (0–1) after each tile; may raise Cancelled.
    """
    ss = int(supersample)
    W, H = camera.width, camera.height
    rows_per_tile = max(1, tile_rays // (W * ss * ss))
    rad_seq, *tile_seqs = seed_sequence.spawn(1 + -(-H // rows_per_tile))
    rrng = np.random.default_rng(rad_seq)
    gain = rrng.uniform(0.92, 1.08) * (1.0 + rrng.uniform(-0.02, 0.02, len(renderer.albedo)))
    offset = rrng.uniform(-8.0, 8.0)
    sub = (np.arange(ss) + 0.5) / ss - 0.5
    image = np.empty((len(renderer.albedo), H, W), dtype=np.uint8)
    misses = 0
    cols = np.arange(W, dtype=float)
    for k, r0 in enumerate(range(0, H, rows_per_tile)):
        r1 = min(r0 + rows_per_tile, H)
        nr = r1 - r0
        rr = (np.arange(r0, r1, dtype=float)[:, None, None, None] + sub[None, :, None, None])
        cc = (cols[None, None, :, None] + sub[None, None, None, :])
        rr, cc = np.broadcast_arrays(rr, cc)
        dirs = camera.pixel_to_camera(cc.ravel(), rr.ravel()) @ eo.rotation.T
        pts = renderer.trace(eo.position, dirs)
        misses += int(np.count_nonzero(~np.isfinite(pts[:, 0])))
        alb = renderer.shade(pts, ramp).reshape(nr, ss, W, ss, -1).mean(axis=(1, 3))
        del pts, dirs
        # vignetting from the off-axis angle of the pixel centre
        x, y = camera.pixel_to_image(cols[None, :], np.arange(r0, r1, dtype=float)[:, None])
        cos2 = camera.focal_length ** 2 / (camera.focal_length ** 2 + x * x + y * y)
        vig = 1.0 - 0.5 * (1.0 - cos2 * cos2)
        noise_rng = np.random.default_rng(tile_seqs[k])
        for b in range(alb.shape[-1]):
            dn = gain[b] * 255.0 * alb[..., b] * vig + offset + noise_rng.normal(0.0, 2.0, (nr, W))
            image[b, r0:r1] = np.clip(np.rint(dn), 0, 255).astype(np.uint8)
        if progress is not None:
            progress(r1 / H)
    return image, misses
