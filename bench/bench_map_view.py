"""Speed and memory of the standalone map view on big rasters (issue 21), with a GDAL peer.

Data (made once, cached in ``$PHOTODEM_BENCH_DATA`` or ``<tmp>/photodem-bench/map_view``): a
20 000 × 20 000 px RGB Cloud-Optimised GeoTIFF mosaic (deflate, 256² tiles, overviews; a
synthetic field texture written window by window, never as a whole array) and a
10 000 × 10 000 float32 DSM with overviews.

Measured in a child process (so the peak memory is the GUI process's own) with an offscreen
``QApplication`` and the real ``MapView`` (``plugin/widgets/map_view.py``; without it the
layer's ``paint`` on an image of the same size, the path the view takes):

- open: ``RasterLayer`` created (statistics from the smallest overview);
- first draw: the whole extent, until every tile is in;
- step: 50 pan and zoom steps (pan by a third of the view, zoom in/out by 2 around a point),
  each until every tile of the new view is in — median and p90 — and the time to the first
  frame (the coarser level drawn scaled at once);
- peak RSS (VmHWM) of the process;
- the peer: rasterio/GDAL reading the same view at the same ``out_shape`` (decimated read, the
  overview GDAL chooses), without tiles, threads or colouring — ratio ours / peer.

Targets (issue 21): first draw ≤ 0.5 s, step ≤ 100 ms (median), RSS ≤ 600 MB.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from . import PEAK_MB_SOURCE

MOSAIC_SIZE = 20_000
DSM_SIZE = 10_000
VIEW = (1280, 800)
STEPS = 50

CHILD = PEAK_MB_SOURCE + r"""
import json, os, statistics, sys, time
os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
import numpy as np
import rasterio
from rasterio.enums import Resampling
from rasterio.windows import from_bounds
from photodem.plugin.qt import QtWidgets
app = QtWidgets.QApplication.instance() or QtWidgets.QApplication([])
from photodem.plugin.widgets.raster_tiles import RasterLayer

path, kind, width, height, steps = sys.argv[1], sys.argv[2], *map(int, sys.argv[3:6])
from photodem.plugin.widgets.map_view import MapView

t = time.perf_counter()
layer = RasterLayer(path, kind=kind, map_crs="EPSG:25832")
t_open = time.perf_counter() - t
view = MapView()
view.set_crs("EPSG:25832")
view.resize(width, height)
view.show()
app.processEvents()
view.add_layer(layer)
render = lambda: view.render_layers()
bounds = layer.bounds()

t = time.perf_counter()
view.set_extent(bounds)
ok = view.wait_rendered(60000)
t_first = time.perf_counter() - t

src = rasterio.open(path)
def peer(extent):
    w = from_bounds(*extent, transform=src.transform)
    t = time.perf_counter()
    src.read(window=w, out_shape=(src.count, height, width), boundless=False,
             resampling=Resampling.nearest)
    return time.perf_counter() - t

peer_first = peer(bounds)

# steps: start zoomed in 8× on the centre, then alternate pans and zooms
cx, cy = (bounds[0] + bounds[2]) / 2, (bounds[1] + bounds[3]) / 2
span = (bounds[2] - bounds[0]) / 8
view.set_extent((cx - span / 2, cy - span / 2 * height / width, cx + span / 2,
                 cy + span / 2 * height / width))
view.wait_rendered(60000)
rng = np.random.default_rng(5)
full, frame, peers = [], [], []
for i in range(steps):
    x0, y0, x1, y1 = view.extent()
    w, h = x1 - x0, y1 - y0
    if i % 3 == 2:  # zoom in or out by 2 around the centre
        f = 0.5 if (i // 3) % 2 == 0 else 2.0
        mx, my = (x0 + x1) / 2, (y0 + y1) / 2
        new = (mx - w * f / 2, my - h * f / 2, mx + w * f / 2, my + h * f / 2)
    else:  # pan by a third of the view in a random direction
        a = rng.uniform(0, 2 * np.pi)
        dx, dy = np.cos(a) * w / 3, np.sin(a) * h / 3
        new = (x0 + dx, y0 + dy, x1 + dx, y1 + dy)
    # keep the view over the raster
    sx = min(max(new[0], bounds[0]), bounds[2] - (new[2] - new[0])) - new[0]
    sy = min(max(new[1], bounds[1]), bounds[3] - (new[3] - new[1])) - new[1]
    new = (new[0] + sx, new[1] + sy, new[2] + sx, new[3] + sy)
    t = time.perf_counter()
    view.set_extent(new)
    render()  # the first frame: cached + coarser tiles
    frame.append(time.perf_counter() - t)
    ok = view.wait_rendered(60000) and ok
    full.append(time.perf_counter() - t)
    peers.append(peer(view.extent()))

q = lambda v, p: float(np.percentile(v, p))
print(json.dumps({"view": "MapView",
                  "open_s": t_open, "first_s": t_first, "first_peer_s": peer_first,
                  "step_median_s": q(full, 50), "step_p90_s": q(full, 90),
                  "frame_median_s": q(frame, 50), "peer_median_s": q(peers, 50),
                  "peer_p90_s": q(peers, 90), "peak_mb": peak_mb(), "complete": ok}))
"""


def data_dir() -> Path:
    folder = Path(os.environ.get("PHOTODEM_BENCH_DATA",
                                 Path(tempfile.gettempdir()) / "photodem-bench" / "map_view"))
    folder.mkdir(parents=True, exist_ok=True)
    return folder


def _texture(rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """RGB fields of 600 × 450 px in five colours with furrows, a road grid and noise."""
    palette = np.array([[96, 128, 60], [140, 110, 70], [170, 160, 90], [70, 100, 50],
                        [120, 120, 115]], dtype=np.float32)
    field = ((cols // 600) * 7 + (rows // 450) * 3) % 5
    rgb = palette[field]
    furrow = 1.0 + 0.12 * np.sin((cols + 2 * rows) / 6.0)
    rgb *= furrow[..., None]
    road = ((cols % 2400) < 18) | ((rows % 1800) < 18)
    rgb[road] = (60, 60, 62)
    noise = np.random.default_rng(int(rows[0, 0])).normal(0, 6, rgb.shape[:2])
    rgb += noise[..., None].astype(np.float32)
    return np.clip(rgb, 0, 255).astype(np.uint8).transpose(2, 0, 1)


def make_mosaic(path: Path, n: int = MOSAIC_SIZE) -> Path:
    """The RGB COG mosaic, written in strips of 512 rows, then copied to a COG."""
    import rasterio
    from affine import Affine
    from rasterio.shutil import copy as gdal_copy
    from rasterio.windows import Window

    if path.is_file():
        return path
    tmp = path.with_name(".strips.tif")
    profile = {"driver": "GTiff", "width": n, "height": n, "count": 3, "dtype": "uint8",
               "crs": "EPSG:25832", "transform": Affine(0.1, 0, 400000.0, 0, -0.1,
                                                         5600000.0 + n * 0.1),
               "tiled": True, "blockxsize": 256, "blockysize": 256, "compress": "deflate",
               "zlevel": 1, "BIGTIFF": "YES", "photometric": "RGB"}
    with rasterio.open(tmp, "w", **profile) as dst:
        for r in range(0, n, 512):
            h = min(512, n - r)
            rows, cols = np.mgrid[r:r + h, 0:n]
            dst.write(_texture(rows, cols), window=Window(0, r, n, h))
    partial = path.with_name(".partial.tif")
    with rasterio.Env(GDAL_NUM_THREADS="2"):
        gdal_copy(tmp, partial, driver="COG", COMPRESS="DEFLATE", LEVEL=1, BLOCKSIZE=256,
                  OVERVIEWS="AUTO", RESAMPLING="AVERAGE", BIGTIFF="YES")
    tmp.unlink()
    partial.rename(path)
    return path


def make_dsm(path: Path, n: int = DSM_SIZE) -> Path:
    """The float32 DSM (smooth terrain + blocks), written in strips, with overviews."""
    import rasterio
    from affine import Affine
    from rasterio.enums import Resampling
    from rasterio.windows import Window

    if path.is_file():
        return path
    partial = path.with_name(".partial_dsm.tif")
    profile = {"driver": "GTiff", "width": n, "height": n, "count": 1, "dtype": "float32",
               "crs": "EPSG:25832", "transform": Affine(0.2, 0, 400000.0, 0, -0.2,
                                                         5600000.0 + n * 0.2),
               "nodata": float("nan"), "tiled": True, "blockxsize": 256, "blockysize": 256,
               "compress": "deflate", "predictor": 3, "BIGTIFF": "IF_SAFER"}
    with rasterio.open(partial, "w", **profile) as dst:
        for r in range(0, n, 500):
            h = min(500, n - r)
            rows, cols = np.mgrid[r:r + h, 0:n].astype(np.float32)
            z = 300 + 25 * np.sin(cols / 900.0) * np.cos(rows / 700.0) + 0.002 * cols
            z += 8.0 * (((cols // 60) % 5 == 0) & ((rows // 50) % 4 == 0))  # buildings
            dst.write(z.astype(np.float32), 1, window=Window(0, r, n, h))
        dst.build_overviews([2, 4, 8, 16, 32, 64], Resampling.average)
    partial.rename(path)
    return path


def _measure(path: Path, kind: str) -> dict:
    env = dict(os.environ, QT_QPA_PLATFORM="offscreen")
    out = subprocess.run([sys.executable, "-c", CHILD, str(path), kind, str(VIEW[0]),
                          str(VIEW[1]), str(STEPS)], capture_output=True, text=True, env=env,
                         timeout=1800)
    if out.returncode != 0:
        raise RuntimeError(out.stderr[-3000:])
    return json.loads(out.stdout.strip().splitlines()[-1])


def run() -> dict:
    folder = data_dir()
    t = time.perf_counter()
    mosaic = make_mosaic(folder / f"mosaic_{MOSAIC_SIZE}.tif")
    dsm = make_dsm(folder / f"dsm_{DSM_SIZE}.tif")
    made = time.perf_counter() - t
    rows = []
    for name, path, kind in (("RGB COG mosaic 20 000²", mosaic, "mosaic"),
                             ("float32 DSM 10 000²", dsm, "dsm")):
        r = _measure(path, kind)
        rows.append({
            "raster": name, "view": r["view"], "open s": r["open_s"],
            "first draw s": r["first_s"], "peer first s": r["first_peer_s"],
            "first ratio": r["first_s"] / max(r["first_peer_s"], 1e-9),
            "step median ms": 1000 * r["step_median_s"], "step p90 ms": 1000 * r["step_p90_s"],
            "first frame median ms": 1000 * r["frame_median_s"],
            "peer step median ms": 1000 * r["peer_median_s"],
            "step ratio": r["step_median_s"] / max(r["peer_median_s"], 1e-9),
            "peak RSS MB": r["peak_mb"], "complete": r["complete"],
        })
    ok = all(r["first draw s"] <= 0.5 and r["step median ms"] <= 100 and r["peak RSS MB"] <= 600
             for r in rows)
    return {
        "title": "Map view: big rasters (issue 21)",
        "rows": rows,
        "notes": [
            f"view {VIEW[0]} × {VIEW[1]} px, {STEPS} steps (2 pans : 1 zoom), offscreen Qt, "
            f"{os.cpu_count()} CPUs; data in {folder} (made in {made:.0f} s this run)",
            "step = until every tile of the new view is in; first frame = the frame drawn at "
            "once from cached and coarser tiles",
            "peer = rasterio decimated read of the same view at the same out_shape (no "
            "colouring, no threads)",
            f"targets first ≤ 0.5 s, step ≤ 100 ms, RSS ≤ 600 MB: {'met' if ok else 'NOT met'}",
        ],
    }
