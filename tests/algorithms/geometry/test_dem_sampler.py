"""raster.sample: bilinear sampling at world coordinates and the DEM sampler."""

from __future__ import annotations

import numpy as np
import pytest
import rasterio
from affine import Affine

from photodem.algorithms.errors import InputError
from photodem.algorithms.raster.sample import DemSampler, bilinear, grid_to_world


def _plane_dem():
    # z = 2 + 0.5 x − 0.25 y on a 10 × 8 grid of 2 m cells: bilinear is exact on planes
    transform = Affine(2.0, 0.0, 100.0, 0.0, -2.0, 300.0)
    rows, cols = np.mgrid[0:8, 0:10]
    x, y = grid_to_world(transform, cols, rows)
    return 2.0 + 0.5 * x - 0.25 * y, transform


def test_bilinear_exact_on_plane_and_nan_outside():
    z, t = _plane_dem()
    rng = np.random.default_rng(1)
    # cell centres span x 101…119, y 285…299
    x = rng.uniform(101, 119, 500)
    y = rng.uniform(285, 299, 500)
    np.testing.assert_allclose(bilinear(z, t, x, y), 2.0 + 0.5 * x - 0.25 * y, atol=1e-10)
    # the last centre row/column is inside, half a cell beyond is outside
    assert np.isfinite(bilinear(z, t, 119.0, 285.0))
    assert np.isnan(bilinear(z, t, 119.5, 290.0))
    assert np.isnan(bilinear(z, t, 100.5, 290.0))
    assert np.isnan(bilinear(z, t, np.nan, 290.0))


def test_bilinear_at_centres_and_nan_neighbours():
    z, t = _plane_dem()
    z = z.copy()
    z[3, 4] = np.nan
    x, y = grid_to_world(t, np.arange(10), np.full(10, 2))
    np.testing.assert_allclose(bilinear(z, t, x, y), z[2], atol=1e-12)
    # any point whose four neighbours include the NaN cell is NaN
    xc, yc = grid_to_world(t, np.array([3.5, 4.0, 4.5, 3.2]), np.array([2.5, 3.0, 3.5, 3.9]))
    assert np.isnan(bilinear(z, t, xc, yc)).all()
    xo, yo = grid_to_world(t, np.array([6.5]), np.array([3.5]))
    assert np.isfinite(bilinear(z, t, xo, yo)).all()


def test_dem_sampler_properties_and_window(tmp_path):
    z, t = _plane_dem()
    z = z.astype(np.float32)
    z[0, 0] = -9999.0
    path = tmp_path / "dem.tif"
    with rasterio.open(path, "w", driver="GTiff", width=10, height=8, count=1,
                       dtype="float32", transform=t, nodata=-9999.0) as dst:
        dst.write(z, 1)
    dem = DemSampler.from_file(path)
    assert np.isnan(dem.array[0, 0])
    assert dem.cell_size == 2.0
    assert dem.min == pytest.approx(np.min(z[z > -9999]))
    assert dem.max == pytest.approx(np.max(z))
    part = DemSampler.from_file(path, bounds=(106.0, 288.0, 110.0, 292.0), margin_cells=1)
    assert part.shape[0] < 8 and part.shape[1] < 10
    np.testing.assert_allclose(part.height(108.3, 290.1), dem.height(108.3, 290.1), atol=1e-6)
    with pytest.raises(InputError):
        DemSampler.from_file(path, bounds=(1e6, 1e6, 1e6 + 10, 1e6 + 10))
    with pytest.raises(InputError):
        DemSampler(np.full((3, 3), np.nan), t)
