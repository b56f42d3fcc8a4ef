"""Nuth & Kääb co-registration on a rough synthetic terrain with a planted shift."""

from __future__ import annotations

import numpy as np
import pytest
from affine import Affine
from scipy import ndimage

from photodem.algorithms.errors import InputError
from photodem.algorithms.quality.coregister import apply_shift, nuth_kaab

RES = 2.0
T = Affine(RES, 0, 500000.0, 0, -RES, 5400000.0)


def rough_terrain(n=400, seed=1):
    """Band-limited noise scaled to a median slope of 20° (5 %–95 %: about 6–36°)."""
    rng = np.random.default_rng(seed)
    z = ndimage.gaussian_filter(rng.standard_normal((n, n)), 12, mode="wrap")
    g = np.hypot(*np.gradient(z, RES))
    return z * np.tan(np.radians(20)) / np.median(g) + 300.0


def shifted_copy(z, dx, dy, dz):
    """The DEM that needs (dx, dy, dz) added to match z: dem(p) = z(p + d) − dz (cubic spline)."""
    coef = ndimage.spline_filter(z, order=3)
    rows, cols = np.mgrid[0 : z.shape[0], 0 : z.shape[1]].astype(float)
    # p + d in pixel units: col + dx/res, row − dy/res (rows grow southwards)
    out = ndimage.map_coordinates(coef, [rows - dy / RES, cols + dx / RES], order=3,
                                  prefilter=False, mode="nearest")
    return out - dz


@pytest.fixture(scope="module")
def terrain():
    return rough_terrain()


def test_slopes_in_range(terrain):
    s = np.degrees(np.arctan(np.hypot(*np.gradient(terrain, RES))))
    lo, hi = np.percentile(s, [5, 95])
    assert 4 < lo < 10 and 30 < hi < 45


def test_recovers_planted_shift(terrain):
    dem = shifted_copy(terrain, 3.0, -2.0, 0.5)
    r = nuth_kaab(dem, terrain, T)
    assert r.converged
    assert abs(r.dx - 3.0) < 0.1 and abs(r.dy + 2.0) < 0.1 and abs(r.dz - 0.5) < 0.1
    assert r.residual_nmad < 0.05
    # applying the shift gives back the reference where both exist
    z2, t2 = apply_shift(dem, T, r.dx, r.dy, r.dz)
    assert t2.c == pytest.approx(T.c + r.dx) and t2.f == pytest.approx(T.f + r.dy)
    assert np.nanmedian(z2 - dem) == pytest.approx(r.dz)


def test_stable_mask_ignores_changed_area(terrain):
    dem = shifted_copy(terrain, -1.5, 2.5, -1.0)
    dem[:, :150] += 20.0 + np.linspace(0, 10, 150)  # e.g. a glacier that changed
    stable = np.ones(dem.shape, bool)
    stable[:, :160] = False
    r = nuth_kaab(dem, terrain, T, stable=stable)
    assert abs(r.dx + 1.5) < 0.1 and abs(r.dy - 2.5) < 0.1 and abs(r.dz + 1.0) < 0.1


def test_decimated_grid_and_nan(terrain):
    dem = shifted_copy(terrain, 3.0, -2.0, 0.5)
    dem[50:120, 200:260] = np.nan
    r = nuth_kaab(dem, terrain, T, max_cells=40_000)
    assert abs(r.dx - 3.0) < 0.2 and abs(r.dy + 2.0) < 0.2 and abs(r.dz - 0.5) < 0.1


def test_flat_terrain_is_an_operator_error():
    flat = np.full((50, 50), 100.0)
    with pytest.raises(InputError, match="slope"):
        nuth_kaab(flat + 1, flat, T)
