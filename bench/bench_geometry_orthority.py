"""Collinearity and distortion against orthority, an independent implementation.

On the NGI block (4 DMC frames, reference DEM) every DEM cell centre is projected into every
image by PhotoDEM and by orthority; the largest difference in pixels is reported, and the time
ratio. A Brown/OpenCV-distorted camera is compared the same way, which checks that calibrations
carry over between the tools with the same coefficients.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "ngi_aerial_block"


def _version(dist: str) -> str:
    from importlib.metadata import version

    return version(dist)


def _timed(fn, repeat: int = 5):
    best = np.inf
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return out, best


def run() -> dict:
    try:
        import orthority as oty
        from orthority.camera import BrownCamera
    except ImportError:
        return {"skipped": "orthority is not installed (make bench installs it in .venv-bench)"}
    if not DATA.is_dir():
        return {"skipped": f"real data not found at {DATA}"}
    import rasterio

    from photodem.algorithms.geometry.camera import Camera
    from photodem.algorithms.geometry.orientation import ExteriorOrientation
    from photodem.algorithms.geometry.projection import world_to_pixel

    with rasterio.open(DATA / "ngi" / "dem.tif") as src:
        z = src.read(1).astype(float)
        rows, cols = np.mgrid[0 : src.height, 0 : src.width]
        x, y = src.xy(rows.ravel(), cols.ravel())
    xyz = np.column_stack([x, y, z.ravel()])
    xyz = xyz[np.isfinite(xyz[:, 2])]

    cams = oty.FrameCameras(DATA / "io" / "ngi_int_param.yaml", DATA / "io" / "ngi_xyz_opk.csv")
    ours_cam = Camera("dmc", 640, 1152, 120.0, (0.144, 0.144))
    ext = np.genfromtxt(DATA / "io" / "ngi_xyz_opk.csv", delimiter=",", names=True, dtype=None,
                        encoding="utf-8")
    rows_out = []
    for rec in ext:
        name = str(rec["filename"])
        eo = ExteriorOrientation.from_opk([rec["x"], rec["y"], rec["z"]], rec["omega"],
                                          rec["phi"], rec["kappa"], unit="degrees")
        theirs, t_theirs = _timed(lambda name=name: cams.get(name).world_to_pixel(xyz.T))
        (c, r), t_ours = _timed(lambda eo=eo: world_to_pixel(xyz, ours_cam, eo))
        inside = (c > -0.5) & (c < 639.5) & (r > -0.5) & (r < 1151.5)
        diff = np.hypot(c - theirs[0], r - theirs[1])[inside]
        rows_out.append({"case": f"NGI {name[-8:-4]} pinhole", "points": int(inside.sum()),
                         "max_diff_px": float(diff.max()), "time_ratio_ours_over_peer":
                         t_ours / t_theirs})

    # a distorted camera with the same coefficients in both tools
    coeffs = {"k1": -0.12, "k2": 0.05, "p1": 0.0012, "p2": -0.0008, "k3": -0.01}
    opk_deg = (2.0, -1.5, 30.0)
    pos = (1000.0, 2000.0, 1500.0)
    peer = BrownCamera((4000, 3000), 0.9, cx=0.01, cy=-0.02, xyz=pos,
                       opk=tuple(np.radians(opk_deg)), **coeffs)
    px = 0.0045  # mm, any value: focal length and principal point scale with it
    f_mm = 0.9 * 4000 * px
    ours = Camera("brown", 4000, 3000, f_mm, (px, px),
                  principal_point=(0.01 * 4000 * px, 0.02 * 4000 * px), **coeffs)
    eo = ExteriorOrientation.from_opk(pos, *opk_deg, unit="degrees")
    rng = np.random.default_rng(0)
    pts = np.column_stack([rng.uniform(-500, 2500, 200000), rng.uniform(500, 3500, 200000),
                           rng.uniform(0, 200, 200000)])
    theirs, t_theirs = _timed(lambda: peer.world_to_pixel(pts.T))
    (c, r), t_ours = _timed(lambda: world_to_pixel(pts, ours, eo))
    inside = (c >= 0) & (c < 4000) & (r >= 0) & (r < 3000)
    diff = np.hypot(c - theirs[0], r - theirs[1])[inside]
    rows_out.append({"case": "Brown k1-k3 p1 p2, 12 Mpx", "points": int(inside.sum()),
                     "max_diff_px": float(diff.max()),
                     "time_ratio_ours_over_peer": t_ours / t_theirs})
    return {
        "title": "Projection world→pixel vs orthority " + _version("orthority"),
        "rows": rows_out,
        "notes": ["max_diff_px: largest distance between the two tools' pixel coordinates",
                  "time_ratio < 1: PhotoDEM is faster (best of 5 runs each, same process)"],
    }
