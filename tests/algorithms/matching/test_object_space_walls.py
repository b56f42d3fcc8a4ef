"""Object-space refinement keeps walls (issue 19): a box building on the rendered test scene.

The scene of ``test_object_space.py`` (three 240 × 240 px frames, GSD 0.2 m, H = 48 m, bases
12 and 24 m) with a flat-roofed building 4 m high, 7 m × 10 m. The start DSM (0.2 m cells, the
wall on its true cell) has the smooth start error on the ground and the roof 0.6 m too high —
a roof correction that a bilinear correction or a curvature regularisation across the wall
would carry onto the ground beside it.
"""

from __future__ import annotations

import numpy as np
import pytest
import rasterio
from _three_frames import CRS, GSD, X0, Y0, ZT, write_three_frames
from affine import Affine

from photodem.algorithms.matching import object_space_window as osw
from photodem.algorithms.matching.object_space import refine_object_space
from photodem.algorithms.raster.io import write_raster

HB = 4.0  # building height (m)
BX0, BX1, BY0, BY1 = 2.0, 9.0, -6.0, 4.0  # footprint relative to (X0, Y0)
ROOF_ERR = 0.6  # start error of the roof (m)


def ground(x, y):
    u, v = np.asarray(x) - X0, np.asarray(y) - Y0
    return ZT + 1.5 * np.sin(2 * np.pi * u / 37.0) * np.cos(2 * np.pi * v / 29.0) + 0.03 * u


def inside(x, y):
    u, v = np.asarray(x) - X0, np.asarray(y) - Y0
    return (u >= BX0) & (u < BX1) & (v >= BY0) & (v < BY1)


def surface(x, y):
    """Roof: flat at the ground height of the footprint's centre plus HB."""
    roof = ground(X0 + 0.5 * (BX0 + BX1), Y0 + 0.5 * (BY0 + BY1)) + HB
    return np.where(inside(x, y), roof, ground(x, y))


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    root = tmp_path_factory.mktemp("object_space_walls") / "project"
    write_three_frames(root, surface, "walls")
    spacing, half_dsm = GSD, 12.0
    m = int(2 * half_dsm / spacing)
    t = Affine(spacing, 0, X0 - half_dsm, 0, -spacing, Y0 + half_dsm)
    cols, rows = np.meshgrid(np.arange(m) + 0.5, np.arange(m) + 0.5)
    x, y = t * (cols, rows)
    z_true = surface(x, y)
    u, v = x - X0, y - Y0
    err = np.where(inside(x, y), ROOF_ERR, 0.15 * np.sin(u / 3.0 + v / 5.0))
    write_raster(root / "start.tif", (z_true + err).astype(np.float32), transform=t, crs=CRS)
    return {"root": root, "dsm": root / "start.tif", "truth": z_true, "x": x, "y": y}


def _wall_figures(scene, path) -> dict:
    """Wall positions (cells) of the rows through the building, roof and ground near the walls."""
    with rasterio.open(path) as src:
        z = src.read(1)
    x, y = scene["x"], scene["y"]
    e = z - scene["truth"]
    nd = z - ground(x, y)
    rows = np.flatnonzero((y[:, 0] - Y0 > BY0 + 1.0) & (y[:, 0] - Y0 < BY1 - 1.0))
    u = x[0] - X0
    west = int(np.argmax(u >= BX0))
    east = int(np.argmax(u >= BX1))
    wall_err = []
    for r in rows:
        up = np.flatnonzero(nd[r, west - 10:east + 10] >= 0.5 * HB)
        if up.size == 0:
            wall_err.append(99)
            continue
        wall_err += [abs(int(up[0]) + west - 10 - west), abs(int(up[-1]) + west - 10 + 1 - east)]
    d_in = np.minimum.reduce([u - BX0, BX1 - u])[None, :] * np.ones_like(x)
    d_in = np.minimum(d_in, np.minimum(y - Y0 - BY0, BY1 - (y - Y0)))
    roof = inside(x, y) & (d_in >= 1.0)
    outer = ~inside(x, y) & (np.abs(d_in) <= 2.0) & (np.abs(u - 0.5 * (BX0 + BX1)) < 6.5)
    outer &= (y - Y0 > BY0 - 2.0) & (y - Y0 < BY1 + 2.0)
    return {"wall_max_cells": max(wall_err), "roof_within_0_5": float(np.mean(
        np.abs(e[roof]) <= 0.5)), "ground_near_rms": float(np.sqrt(np.nanmean(e[outer] ** 2))),
        "ground_near_max": float(np.nanmax(np.abs(e[outer]))),
        "ground_near_measured": float(np.mean(np.isfinite(e[outer])))}


def test_refinement_keeps_the_walls_and_the_roof(scene, tmp_path) -> None:
    res = refine_object_space(scene["root"], scene["dsm"], tmp_path / "out")
    f = _wall_figures(scene, res["dsm"])
    f0 = _wall_figures(scene, scene["dsm"])
    print(f"start {f0}\nrefined {f}")
    assert f["wall_max_cells"] <= 1  # within 1 GSD
    assert f["roof_within_0_5"] >= 0.95
    assert f["ground_near_measured"] >= 0.95
    assert f["ground_near_rms"] <= f0["ground_near_rms"] + 0.02  # no roof correction leaks


def test_same_side_weights_cut_at_walls() -> None:
    idx = np.array([[0, 1, 2, 3]] * 3)
    w = np.array([[0.25, 0.25, 0.25, 0.25]] * 3)
    zn = np.array([0.0, 8.0, 0.0, 8.0])
    ws = osw.same_side_weights(idx, w, zn, np.array([0.1, 8.0, 4.0]), node_m=1.6)
    assert np.allclose(ws[0], [0.5, 0, 0.5, 0]) and np.allclose(ws[1], [0, 0.5, 0, 0.5])
    assert np.all(ws[2] == 0)  # on the wall: keeps its input height
    slope = osw.same_side_weights(idx, w, np.array([0.0, 0.6, 0.0, 0.6]),
                                  np.array([0.3]), node_m=1.6)
    assert np.allclose(slope, 0.25)  # a slope is no wall
    R = osw._second_difference_rows(3, 5, np.array([[0, 0, 8, 8, 8]] * 3, float))
    assert R.shape[0] == 3 * 1 + 5  # two of the three X rows per line cross the wall



def test_without_the_cut_the_roof_correction_leaks(scene, tmp_path, monkeypatch) -> None:
    """The old behaviour (no wall detection): documents what the cut is for."""
    monkeypatch.setattr(osw, "BREAK_M", 1e9)
    res = refine_object_space(scene["root"], scene["dsm"], tmp_path / "old")
    f = _wall_figures(scene, res["dsm"])
    monkeypatch.undo()
    new = _wall_figures(scene, refine_object_space(scene["root"], scene["dsm"],
                                                   tmp_path / "new")["dsm"])
    print(f"without the cut {f}\nwith the cut {new}")
    assert new["ground_near_rms"] < f["ground_near_rms"]
