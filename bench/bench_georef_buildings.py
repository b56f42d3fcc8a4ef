"""Georeferencing against building footprints (issue 23 goals).

Synthetic suburban scenes (:mod:`photodem.algorithms.synthetic.suburban_scene`): 30–80
buildings per image, 900 × 900 px (0.8 Mpx), random affine maps (rotation 0–360°, scale
0.5–2 of a 0.5 m pixel, shear, mirroring in half of them), relief displacement of the roofs
0–3 px; even seeds 8-bit, odd seeds 12-bit data in uint16. Rows: share within 1 px (and 2 px)
at the image corners (goal ≥ 90 % within 1 px), wrong results (a corner > 3 px off returned as
a success; goal 0), failures, median and max seconds (goal ≤ 30 s). Then seeds 0–9 without
relief displacement (the roof candidates and the consensus alone) and three "different town"
cases (the footprints of another seed): each must fail.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple

import numpy as np

N_CASES = 20
N_OTHER_TOWN = 3
#: Scenes without relief displacement (roofs exactly over their footprints): the quality of
#: the roof candidates and the consensus alone.
N_RELIEF0 = 10


def _one(tmp: Path, seed: int, town_seed: Optional[int] = None, relief_px: float = 3.0
         ) -> Tuple[Optional[float], float, str, Dict[str, Any]]:
    """(largest corner error in px or None for a failure, seconds, message, counts)."""
    from photodem.algorithms.errors import PhotodemError
    from photodem.algorithms.georef.fit import corner_error
    from photodem.algorithms.georef.pipeline import georeference
    from photodem.algorithms.synthetic.suburban_scene import suburban_case

    case = suburban_case(tmp / f"s{seed}_{town_seed}_{relief_px:g}", seed=seed,
                         bits=8 if seed % 2 == 0 else 12, town_seed=town_seed,
                         relief_px=relief_px)
    t0 = time.perf_counter()
    try:
        res = georeference(case["image"], case["reference"])
    except PhotodemError as exc:
        return None, time.perf_counter() - t0, str(exc), exc.counts
    dt = time.perf_counter() - t0
    err = float(np.max(corner_error(res.fit, case["truth"], case["width"], case["height"])))
    return err, dt, res.stage, res.counts


def _relief0_row(tmp: Path, notes: List[str]) -> Dict[str, Any]:
    """Seeds 0 … :data:`N_RELIEF0` - 1 without relief displacement."""
    errs, times = [], []
    for seed in range(N_RELIEF0):
        err, dt, why, _ = _one(tmp, seed, relief_px=0.0)
        times.append(dt)
        errs.append(np.inf if err is None else err)
        notes.append(f"relief 0, seed {seed}: " + (f"{err:.2f} px" if err is not None else
                                                   "failed: " + why.split("(")[0].strip())
                     + f", {dt:.1f} s")
    e = np.array(errs)
    return {"case": f"suburban without relief displacement, {N_RELIEF0} scenes",
            "within_1px_pct": 100.0 * float(np.mean(e <= 1.0)),
            "within_2px_pct": 100.0 * float(np.mean(e <= 2.0)),
            "wrong": int(np.sum(np.isfinite(e) & (e > 3.0))),
            "failures": int(np.sum(~np.isfinite(e))),
            "median_s": float(np.median(times)), "max_s": float(np.max(times)),
            "goal": "roof candidates and consensus alone (no relief bias)"}


def run(n: int = N_CASES) -> Dict[str, Any]:
    rows: List[Dict[str, Any]] = []
    notes: List[str] = []
    with tempfile.TemporaryDirectory(prefix="photodem-bench-buildings-") as d:
        tmp = Path(d)
        errs, times, fails = [], [], []
        for seed in range(n):
            err, dt, why, _ = _one(tmp, seed)
            times.append(dt)
            errs.append(np.inf if err is None else err)
            notes.append(f"seed {seed} ({'8' if seed % 2 == 0 else '12'}-bit): "
                         + (f"{err:.2f} px, {why}" if err is not None else
                            "failed: " + why.split("(")[0].strip()) + f", {dt:.1f} s")
            if err is None:
                fails.append(seed)
        e = np.array(errs)
        rows.append({"case": f"suburban, {n} scenes (900 × 900 px, 8/12-bit)",
                     "within_1px_pct": 100.0 * float(np.mean(e <= 1.0)),
                     "within_2px_pct": 100.0 * float(np.mean(e <= 2.0)),
                     "wrong": int(np.sum(np.isfinite(e) & (e > 3.0))),
                     "failures": len(fails),
                     "median_s": float(np.median(times)), "max_s": float(np.max(times)),
                     "goal": "≥ 90 % within 1 px, 0 wrong, ≤ 30 s"})
        rows.append(_relief0_row(tmp, notes))
        other_ok, other_t = 0, []
        for k in range(N_OTHER_TOWN):
            err, dt, why, _ = _one(tmp, 100 + k, town_seed=200 + k)
            other_t.append(dt)
            other_ok += int(err is None)
            notes.append(f"different town {k}: " + ("failed (right): " + why.split("(")[0]
                                                    if err is None else
                                                    f"RESULT {err:.1f} px ({why})"))
        rows.append({"case": f"different town, {N_OTHER_TOWN} scenes (must fail)",
                     "failures": other_ok, "wrong": N_OTHER_TOWN - other_ok,
                     "median_s": float(np.median(other_t)), "max_s": float(np.max(other_t)),
                     "goal": f"{N_OTHER_TOWN} failures"})
    return {"title": "Georeferencing against building footprints", "rows": rows,
            "notes": notes}
