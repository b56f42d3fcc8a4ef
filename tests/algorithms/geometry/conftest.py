"""Synthetic cameras, orientations and a rough DEM for the geometry tests."""

from __future__ import annotations

import numpy as np
import pytest
from affine import Affine

from photodem.algorithms.geometry.camera import Camera
from photodem.algorithms.geometry.orientation import ExteriorOrientation
from photodem.algorithms.raster.sample import DemSampler


@pytest.fixture
def distorted_camera() -> Camera:
    """A 2000 × 1500 px frame camera, f = 100 mm, 10 µm pixels, Brown distortion of a few px."""
    return Camera("dist", 2000, 1500, 100.0, (0.01, 0.01), principal_point=(0.12, -0.08),
                  k1=-0.12, k2=0.08, k3=-0.02, p1=2e-4, p2=-1e-4)


@pytest.fixture
def plain_camera() -> Camera:
    return Camera("plain", 2000, 1500, 100.0, (0.01, 0.01))


@pytest.fixture
def rough_dem() -> DemSampler:
    """300 m × 300 m at 1 m: undulations, a 30 m cliff over one cell, a 15 m block, noise.

    Slopes reach 88° at the cliff and the block walls, and about 60° in the noise.
    """
    rng = np.random.default_rng(7)
    n = 301
    y, x = np.mgrid[0:n, 0:n].astype(float)
    z = 100.0 + 12.0 * np.sin(x / 23.0) * np.cos(y / 31.0)
    z += np.where(x > 160, 30.0, 0.0)  # cliff between two cells
    block = (np.abs(x - 110) < 12) & (np.abs(y - 140) < 18)
    z += np.where(block, 15.0, 0.0)  # a building
    z += rng.normal(0.0, 0.8, z.shape)  # rough
    transform = Affine(1.0, 0.0, 1000.0, 0.0, -1.0, 5300.0)  # x 1000…1301, y 4999…5300
    return DemSampler(z.astype(np.float32), transform)


@pytest.fixture
def tilted_eo() -> ExteriorOrientation:
    """About 1000 m above the DEM centre, tilted by a few degrees, κ = 30°."""
    return ExteriorOrientation.from_opk([1150.0, 5150.0, 1120.0], 4.0, -3.0, 30.0)
