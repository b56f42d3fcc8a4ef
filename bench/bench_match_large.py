"""Matching a ``large`` synthetic model: time, throughput and peak memory (issue 4 speed).

The ``large`` block (2 strips × 4 images of 2400 × 3400 px, GSD 0.12 m) is generated once;
model 0101_0102 is then matched by ``match_model`` with each method in its own child process,
so that the peak memory (VmHWM of the child: Python, numpy, GDAL and OpenCV included) is
the matcher's own. Throughput = left epipolar image pixels / wall time of the whole
algorithm (epipolar resampling, matching, gridding, outputs).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, Dict

from . import PEAK_MB_SOURCE

CHILD = PEAK_MB_SOURCE + r"""
import json, sys, time
from photodem.algorithms.processing import registry
t = time.perf_counter()
res = registry.run("match_model", {"project": sys.argv[1], "model": sys.argv[2],
                                   "method": sys.argv[3], "output": sys.argv[4]})
dt = time.perf_counter() - t
rss = peak_mb()
print(json.dumps({"time_s": dt, "peak_mb": rss, "metrics": res.get("metrics", {})}))
"""

MODEL = "0101_0102"


def _child(project: Path, method: str, out: Path) -> Dict[str, Any]:
    env = dict(os.environ, PYTHONWARNINGS="ignore")
    proc = subprocess.run([sys.executable, "-c", CHILD, str(project), MODEL, method, str(out)],
                          capture_output=True, text=True, env=env, check=False)
    if proc.returncode != 0:
        return {"error": (proc.stderr.strip().splitlines() or ["failed"])[-1]}
    return json.loads(proc.stdout.strip().splitlines()[-1])


def run() -> dict:
    import rasterio

    from photodem.algorithms.synthetic.block import generate_block

    rows = []
    with tempfile.TemporaryDirectory(prefix="bench-large-") as tmp:
        tmp = Path(tmp)
        t0 = time.perf_counter()
        block = generate_block(tmp / "block", size="large", terrain="gentle", seed=1)
        t_gen = time.perf_counter() - t0
        first = sorted((block.project / "images").glob("*.tif"))[0]
        with rasterio.open(first) as src:
            size = f"{src.width} × {src.height}"
        for method in ("dense", "fbm_lsm"):
            r = _child(block.project, method, tmp / method)
            if "error" in r:
                rows.append({"case": f"large model {MODEL}, {method}", "status": r["error"]})
                continue
            m = r["metrics"]
            mpx = m.get("epipolar_mpx")
            rows.append({"case": f"large model {MODEL}, {method}", "image_px": size,
                         "epipolar_mpx": mpx, "time_s": round(r["time_s"], 1),
                         "mpx_per_s": round(mpx / r["time_s"], 3) if mpx else None,
                         "peak_mb": round(r["peak_mb"]),
                         "points": m.get("points_raw"), "coverage_pct": m.get("coverage_pct")})
    return {"title": "Matching a large synthetic model: time, throughput, peak memory",
            "rows": rows,
            "notes": [f"block generation (8 images, truth grids): {t_gen:.0f} s, not counted",
                      "peak_mb = VmHWM of the child process running match_model "
                      "(includes Python, numpy, GDAL, OpenCV); 2 CPU cores"]}
