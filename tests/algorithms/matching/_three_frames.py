"""The rendered three-frame scene of the object-space tests: any surface, the same frames.

Three 240 × 240 px frames along X (GSD 0.2 m, H = 48 m, bases 12 and 24 m: B/H = 0.25 / 0.5)
over band-limited texture, rendered by the synthetic ray caster (box PSF, per-image gain and
offset, vignetting, noise 2 DN), saved as a project with an empty edit layer.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np

from photodem.algorithms.geometry.camera import Camera
from photodem.algorithms.geometry.orientation import ExteriorOrientation
from photodem.algorithms.project.edits import create_edits
from photodem.algorithms.project.model import ImageRecord, Project
from photodem.algorithms.raster.io import write_raster
from photodem.algorithms.synthetic.render import Renderer, render_image
from photodem.algorithms.synthetic.terrain import Grid, band_noise

CRS = "EPSG:25832"
X0, Y0, ZT = 500000.0, 5500000.0, 100.0
GSD, NPX = 0.2, 240
FLY = GSD * NPX  # principal distance = NPX px → H = 48 m
BASE = 12.0


def write_three_frames(root: Path, surface: Callable[[np.ndarray, np.ndarray], np.ndarray],
                       name: str) -> None:
    """Render ``surface(x, y)`` (heights in m on map coordinates) into the three frames and
    save the project ``name`` in ``root``."""
    cell, half = 0.1, 40.0
    n = int(2 * half / cell)
    grid = Grid(X0 - half, Y0 + half, cell, n, n)
    gx, gy = np.meshgrid(grid.xs, grid.ys)
    dsm = surface(gx, gy)
    rng = np.random.default_rng(1)
    alb = np.clip(0.45 + 0.14 * band_noise(rng, grid, 1.2) + 0.07 * band_noise(rng, grid, 0.5),
                  0.05, 0.95).astype(np.float32)
    renderer = Renderer(grid, dsm, np.stack([alb, alb, alb]), np.zeros((0, 3)), 1.0)
    cam = Camera("cam", NPX, NPX, focal_length=NPX * 0.01, pixel_size=(0.01, 0.01))
    (root / "images").mkdir(parents=True)
    seqs = np.random.SeedSequence(7).spawn(3)
    recs = []
    for k, dx in enumerate((-BASE, 0.0, BASE)):
        eo = ExteriorOrientation.from_opk([X0 + dx, Y0, ZT + FLY], 0.5 * (k - 1), -0.3 * k,
                                          1.0 * k)
        img, _ = render_image(renderer, cam, eo, 2, 1 << 18, seqs[k], 0.1)
        write_raster(root / "images" / f"img{k}.tif", img)
        recs.append(ImageRecord(f"img{k}", f"images/img{k}.tif", "cam", eo))
    Project(root=root, name=name, crs=CRS, cameras={"cam": cam}, images=recs,
            terrain_height=ZT).save()
    create_edits(root / "edits.gpkg", CRS)
