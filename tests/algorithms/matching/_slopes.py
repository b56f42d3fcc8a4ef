"""A synthetic slope seen at two scales: the left image and a right one that sees it
foreshortened (tests of the dense slant passes and their LSM refinement)."""

from __future__ import annotations

import numpy as np
from scipy import ndimage


def slope_pair(k: float, periodic: bool = False, h: int = 96, w: int = 128, seed: int = 3
               ) -> tuple:
    """Left image, right image and the true disparity of every left column: left pixel x
    matches right pixel ``k·x + 8`` (a slope with ``∂x_r/∂x_l = k``). Random texture, or
    (``periodic``) stripes of 8 px period across the rows with a weak texture along the
    columns. The right image is NaN beyond the texture."""
    rng = np.random.default_rng(seed)
    if periodic:
        tex = 128.0 + 60.0 * np.sin(2 * np.pi * np.arange(2 * w) / 8.0)[None, :]
        tex = tex + 20.0 * np.sin(np.arange(h) / 3.0)[:, None] + rng.normal(0, 2, (h, 2 * w))
    else:
        tex = ndimage.gaussian_filter(rng.normal(size=(h, 2 * w)), 1.2)
        tex = 128.0 + 60.0 * tex / tex.std()
    src = (np.arange(int(k * w) + 24) - 8.0) / k
    right = np.stack([np.interp(src, np.arange(2 * w), row, left=np.nan, right=np.nan)
                      for row in tex])
    x = np.arange(w, dtype=np.float64)
    return tex[:, :w].astype(np.float32), right.astype(np.float32), x - (k * x + 8.0)
