"""Dense DSMs (match_model, method dense) against truth.

(a) Synthetic ``small`` block: every model → DSM; RMS / NMAD against the true DSM on open
    textured land cover (classes 1 open, 7 field) in m and ‰ of the flying height, coverage and
    time per model.
(b) NGI pair 0182/0184: DSM against the 24 m reference ``dem.tif`` in the overlap (the DSM is
    gridded at 24 m so that both describe the same cells): RMS, NMAD, coverage.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "ngi_aerial_block"
OPEN = (1, 7)


def _open_stats(res: dict) -> tuple:
    sq = n = 0.0
    nm = []
    for key, s in res["per_class"].items():
        if int(float(key)) in OPEN and s.get("count"):
            sq += s["rms"] ** 2 * s["count"]
            n += s["count"]
            nm.append((s["nmad"], s["count"]))
    nmad = sum(a * c for a, c in nm) / max(sum(c for _, c in nm), 1)
    return float(np.sqrt(sq / max(n, 1))), float(nmad)


def _synthetic(tmp: Path) -> dict:
    from photodem.algorithms.processing import registry
    from photodem.algorithms.quality.compare import compare_dems

    block = registry.run("synthetic_block", {"size": "small", "terrain": "gentle", "seed": 1,
                                             "output": str(tmp / "small")})
    info = registry.run("project_info", {"project": block["project"]})
    rows = []
    for m in info["models"]:
        t0 = time.perf_counter()
        r = registry.run("match_model", {"project": block["project"], "model": m["name"],
                                         "method": "dense",
                                         "output": str(tmp / "dsm" / m["name"])})
        dt = time.perf_counter() - t0
        h = m["height_above_ground_m"]
        c = compare_dems(r["dsm"], block["truth_dsm"], classes=block["truth_landcover"])
        rms, nmad = _open_stats(c)
        rows.append({"model": m["name"], "rms_m": rms, "nmad_m": nmad,
                     "rms_permille_h": 1000 * rms / h, "nmad_permille_h": 1000 * nmad / h,
                     "coverage_pct": r["metrics"]["coverage_pct"],
                     "valid_disparity_pct": r["metrics"]["valid_disparity_pct"],
                     "seconds": dt, "mpx_per_s": r["metrics"]["epipolar_mpx"] / dt})
    keys = ("rms_m", "nmad_m", "rms_permille_h", "nmad_permille_h", "coverage_pct", "seconds")
    mean = {k: float(np.mean([r[k] for r in rows])) for k in keys}
    return {"gsd_m": block["gsd_m"], "flying_height_m": block["flying_height_m"],
            "models": rows, "mean": mean, "target_rms_permille_h": 0.15}


def _ngi(tmp: Path) -> dict:
    from photodem.algorithms.processing import registry
    from photodem.algorithms.quality.compare import compare_dems

    proj = tmp / "ngi"
    registry.run("project_create", {
        "images": str(DATA / "ngi"), "exterior": str(DATA / "io" / "ngi_xyz_opk.csv"),
        "interior": str(DATA / "io" / "ngi_int_param.yaml"), "angle_unit": "degrees",
        "dem": str(DATA / "ngi" / "dem.tif"), "output": str(proj)})
    info = registry.run("project_info", {"project": str(proj)})
    model = next((m for m in info["models"]
                  if {"0182" in m["left"], "0184" in m["right"]} == {True}
                  or {"0184" in m["left"], "0182" in m["right"]} == {True}), None)
    if model is None:
        return {"skipped": "no model 0182/0184 in the created project"}
    out = {}
    for spacing in (None, 24.0):
        t0 = time.perf_counter()
        r = registry.run("match_model", {"project": str(proj), "model": model["name"],
                                         "method": "dense", "min_height": 100.0,
                                         "max_height": 850.0, "spacing": spacing,
                                         "output": str(tmp / f"ngi_dsm_{spacing}")})
        dt = time.perf_counter() - t0
        c = compare_dems(r["dsm"], DATA / "ngi" / "dem.tif")
        s = c["stats"]
        h = model["height_above_ground_m"]
        out["gsd" if spacing is None else "24m"] = {
            "spacing_m": r["metrics"]["spacing_m"], "rms_m": s["rms"], "nmad_m": s["nmad"],
            "mean_m": s["mean"], "rms_permille_h": 1000 * s["rms"] / h,
            "nmad_permille_h": 1000 * s["nmad"] / h,
            "coverage_pct": r["metrics"]["coverage_pct"],
            "valid_disparity_pct": r["metrics"]["valid_disparity_pct"], "seconds": dt}
    out["model"] = model["name"]
    out["height_above_ground_m"] = model["height_above_ground_m"]
    return out


def run() -> dict:
    with tempfile.TemporaryDirectory(prefix="bench-dense-") as tmp:
        result = {"synthetic_small": _synthetic(Path(tmp))}
        if DATA.is_dir():
            result["ngi_0182_0184"] = _ngi(Path(tmp))
        else:
            result["ngi_0182_0184"] = {"skipped": f"real data not found at {DATA}"}
    rows = [{"case": f"synthetic small {m['model']} (open classes)", **{
        k: m[k] for k in ("rms_m", "nmad_m", "rms_permille_h", "nmad_permille_h",
                          "coverage_pct", "seconds")}}
        for m in result["synthetic_small"]["models"]]
    ngi = result["ngi_0182_0184"]
    for key in ("gsd", "24m"):
        if key in ngi:
            r = ngi[key]
            rows.append({"case": f"NGI 0182_0184 vs dem.tif, {r['spacing_m']:.1f} m grid",
                         **{k: r[k] for k in ("rms_m", "nmad_m", "rms_permille_h",
                                              "nmad_permille_h", "coverage_pct", "seconds")}})
    result.update(
        title="Dense DSM (match_model, method dense) against truth",
        rows=rows,
        notes=[f"target RMS on open textured terrain: "
               f"{result['synthetic_small']['target_rms_permille_h']} ‰ H (issue 4)",
               "blunder filters: disparities within 2 px of holes/masks/image borders dropped "
               "(edge_erosion), DSM cells off their neighbourhood median by more than "
               "max(1 px parallax, 3·1.4826·MAD) emptied and re-filled; the remaining RMS "
               "excess comes from roof heights on open cells next to buildings (0.5 % of the "
               "cells on small 0201_0202, |dz| ≈ 8 m)"])
    return result
