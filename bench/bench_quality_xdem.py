"""DEM comparison and Nuth & Kääb co-registration against xDEM.

The NGI reference DEM (24 m cells, 149–781 m) is compared with a copy of itself shifted by a
known (dx, dy, dz), with Gaussian noise and a few blunders. Both tools report the statistics of
the differences before co-registration and the co-registration shift; the relative differences
and the run-time ratio are reported.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "ngi_aerial_block"
SHIFT = (30.0, -20.0, 2.0)  # m: planted (dx, dy, dz), to be recovered
NOISE = 0.5  # m


def _shifted_copy(ref: Path, out: Path) -> None:
    """DEM(x, y) = reference(x − dx, y − dy) + dz + noise: the reference moved by (dx, dy, dz)."""
    import rasterio
    from scipy.ndimage import map_coordinates

    with rasterio.open(ref) as src:
        z = src.read(1).astype(float)
        profile = src.profile
        t = src.transform
    rows, cols = np.mgrid[0 : z.shape[0], 0 : z.shape[1]].astype(float)
    src_cols = cols - SHIFT[0] / t.a
    src_rows = rows - SHIFT[1] / t.e
    moved = map_coordinates(z, [src_rows, src_cols], order=3, mode="nearest", cval=np.nan)
    rng = np.random.default_rng(7)
    moved += SHIFT[2] + rng.normal(0.0, NOISE, z.shape)
    blunders = rng.integers(0, z.size, 200)
    moved.flat[blunders] += rng.choice([-40.0, 40.0], blunders.size)
    inside = (src_cols >= 0) & (src_cols <= z.shape[1] - 1) & (src_rows >= 0) & \
        (src_rows <= z.shape[0] - 1)
    moved[~inside] = np.nan
    profile.update(dtype="float32", nodata=np.nan)
    with rasterio.open(out, "w", **profile) as dst:
        dst.write(moved.astype(np.float32), 1)


def _rel(a: float, b: float) -> float:
    return abs(a - b) / max(abs(b), 1e-12)


def run() -> dict:
    try:
        import xdem
    except ImportError:
        return {"skipped": "xdem is not installed (make bench installs it in .venv-bench)"}
    if not DATA.is_dir():
        return {"skipped": f"real data not found at {DATA}"}
    from importlib.metadata import version

    from photodem.algorithms.quality.compare import compare_dems
    from photodem.algorithms.quality.stats import difference_stats

    ref = DATA / "ngi" / "dem.tif"
    with tempfile.TemporaryDirectory() as tmp:
        dem = Path(tmp) / "shifted.tif"
        _shifted_copy(ref, dem)

        t0 = time.perf_counter()
        plain = compare_dems(dem, ref)
        t1 = time.perf_counter()
        ours = compare_dems(dem, ref, coregister=True)
        t2 = time.perf_counter()
        t_ours = (t1 - t0, t2 - t1)

        t0 = time.perf_counter()
        x_ref = xdem.DEM(str(ref))
        x_dem = xdem.DEM(str(dem))
        dh = (x_dem - x_ref).data.compressed().astype(float)
        x_stats = {"mean": float(np.mean(dh)), "std": float(np.std(dh, ddof=1)),
                   "nmad": float(xdem.spatialstats.nmad(dh))}
        t1 = time.perf_counter()
        nk = xdem.coreg.NuthKaab()
        nk.fit(x_ref, x_dem)
        x_shift = nk.to_translations()
        t2 = time.perf_counter()
        t_peer = (t1 - t0, t2 - t1)

    # Both tools return the translation that moves the DEM onto the reference (ours: what to add
    # to the DEM's coordinates, see coregister.py); the planted displacement is its negative.
    peer = {"dx": -float(x_shift[0]), "dy": -float(x_shift[1]), "dz": -float(x_shift[2])}
    our_shift = ours["shift"]
    ours_aligned = {k: -float(our_shift[k]) for k in ("dx", "dy", "dz")}
    rows = []
    for key in ("mean", "std", "nmad"):
        rows.append({"quantity": f"Δh {key} [m] (before co-registration)",
                     "photodem": plain["stats"][key], "xdem": x_stats[key],
                     "rel_diff_pct": 100 * _rel(plain["stats"][key], x_stats[key])})
    for key, planted in zip(("dx", "dy", "dz"), SHIFT):
        rows.append({"quantity": f"displacement {key} [m] (planted {planted:+.1f})",
                     "photodem": ours_aligned[key], "xdem": peer[key],
                     "rel_diff_pct": 100 * _rel(ours_aligned[key], peer[key])})
    check = difference_stats(dh)
    return {
        "title": f"DEM comparison and Nuth & Kääb vs xDEM {version('xdem')} (NGI DEM, 24 m)",
        "rows": rows,
        "notes": [
            f"run time photodem / xdem: comparison {t_ours[0] / t_peer[0]:.2f} "
            f"({t_ours[0]:.2f} s / {t_peer[0]:.2f} s), co-registration "
            f"{t_ours[1] / t_peer[1]:.2f} ({t_ours[1]:.2f} s / {t_peer[1]:.2f} s; ours includes "
            "the comparison after it)",
            f"cells compared: photodem {plain['stats']['count']}, xdem {dh.size} "
            f"(our statistics on xdem's differences: mean {check['mean']:.4f}, "
            f"nmad {check['nmad']:.4f})",
            f"photodem co-registration: {our_shift['iterations']} iterations, "
            f"converged {our_shift['converged']}",
            "displacement = the negative of the translation each tool returns to align the DEM",
        ],
    }
