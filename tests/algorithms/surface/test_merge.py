"""dsm_merge: closed-form mosaics, seam statistics, grids, CRSs, σ, cancel and errors."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import rasterio
from affine import Affine

from photodem.algorithms.errors import Cancelled, InputError
from photodem.algorithms.feedback import Feedback
from photodem.algorithms.processing import registry
from photodem.algorithms.raster.io import write_raster
from photodem.algorithms.surface.merge import merge_dsms, sibling_paths

CRS = "EPSG:25832"


def _plane(path: Path, x0: float, y0: float, w: int, h: int, s: float = 1.0,
           offset: float = 0.0, crs=CRS, sigma=None) -> str:
    """z = 100 + 0.25 x' + 0.5 y' (x', y' cell-centre coordinates relative to 1000/2000)."""
    cols, rows = np.meshgrid(np.arange(w), np.arange(h))
    x = x0 + (cols + 0.5) * s - 1000.0
    y = y0 - (rows + 0.5) * s - 2000.0
    z = (100.0 + 0.25 * x + 0.5 * y + offset).astype(np.float32)
    data = z if sigma is None else np.stack([z, np.broadcast_to(sigma, z.shape)
                                             .astype(np.float32)])
    write_raster(path, data, transform=Affine(s, 0, x0, 0, -s, y0), crs=crs)
    return str(path)


def _read(path) -> np.ndarray:
    with rasterio.open(path) as src:
        return src.read(1)


def test_two_planes_with_offset_give_exact_seam_stats(tmp_path) -> None:
    a = _plane(tmp_path / "a.tif", 1000, 2000, 60, 40)
    b = _plane(tmp_path / "b.tif", 1030, 1990, 60, 40, offset=0.5)
    res = merge_dsms([a, b], tmp_path / "m.tif", "mean")
    assert len(res["seams"]) == 1
    seam = res["seams"][0]
    assert (seam["a"], seam["b"]) == ("a.tif", "b.tif")
    assert seam["count"] == 30 * 30  # overlap x 1030..1060, y 1960..1990
    assert seam["mean"] == -0.5 and seam["median"] == -0.5 and seam["rms"] == 0.5
    assert seam["std"] == 0.0 and seam["nmad"] == 0.0
    with rasterio.open(res["dsm"]) as src:
        assert (src.width, src.height) == (90, 50)
        assert src.transform == Affine(1, 0, 1000, 0, -1, 2000)
        assert src.crs.to_epsg() == 25832 and src.dtypes[0] == "float32"
        assert src.tags(ns="IMAGE_STRUCTURE").get("LAYOUT") == "COG"  # a final product
        z = src.read(1)
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "a.tif", "b.tif", "m.tif", "m_count.tif", "m_seams.csv", "m_seams.json"]
    ov = z[10:40, 30:60]  # overlap: mean of a and a + 0.5
    cols, rows = np.meshgrid(np.arange(30, 60), np.arange(10, 40))
    truth = 100.0 + 0.25 * (cols + 0.5) + 0.5 * (-(rows + 0.5)) + 0.25
    assert np.allclose(ov, truth, atol=1e-4)
    cnt = _read(res["count"])
    assert cnt.dtype == np.uint16 and cnt[20, 40] == 2 and cnt[0, 0] == 1 and cnt[45, 5] == 0
    assert np.isnan(z[45, 5]) and res["coverage"] == pytest.approx(3900 / 4500)
    rep = json.loads(Path(res["report"]).read_text())
    assert rep["seams"] == res["seams"] and rep["inputs"] == ["a.tif", "b.tif"]
    lines = Path(res["csv"]).read_text().splitlines()
    assert lines[0].startswith("a,b,count,mean") and lines[1].startswith("a.tif,b.tif,900,")


def test_median_and_mean_exact(tmp_path) -> None:
    paths = []
    for k, v in enumerate((1.0, 2.0, 10.0)):
        paths.append(str(tmp_path / f"c{k}.tif"))
        write_raster(paths[-1], np.full((20, 30), v, np.float32),
                     transform=Affine(0.5, 0, 0, 0, -0.5, 100), crs=CRS)
    med = merge_dsms(paths, tmp_path / "med.tif", "median")
    mean = merge_dsms(paths, tmp_path / "mean.tif", "mean", step=0.0)
    assert np.all(_read(med["dsm"]) == 2.0)
    assert np.allclose(_read(mean["dsm"]), 13.0 / 3.0, rtol=1e-6)
    # with the step rule (default), 10 is another surface: the mean of the majority {1, 2}
    robust = merge_dsms(paths, tmp_path / "robust.tif", "mean")
    assert np.all(_read(robust["dsm"]) == 1.5)
    assert np.all(_read(med["count"]) == 3)
    assert [(s["a_index"], s["b_index"], s["mean"]) for s in med["seams"]] == \
        [(0, 1, -1.0), (0, 2, -9.0), (1, 2, -8.0)]


def test_disjoint_inputs_have_no_seams(tmp_path) -> None:
    a = _plane(tmp_path / "a.tif", 0, 50, 20, 20)
    b = _plane(tmp_path / "b.tif", 40, 50, 20, 20)
    res = merge_dsms([a, b], tmp_path / "m.tif", "median")
    assert res["seams"] == []
    z, cnt = _read(res["dsm"]), _read(res["count"])
    assert z.shape == (20, 60) and np.isnan(z[:, 20:40]).all() and (cnt[:, 20:40] == 0).all()
    assert res["coverage"] == pytest.approx(40 / 60)


def test_different_grids_and_windows(tmp_path) -> None:
    a = _plane(tmp_path / "a.tif", 1000, 2000, 80, 80)
    b = _plane(tmp_path / "b.tif", 1010.5, 1990.5, 20, 20, s=2.0, offset=0.5)
    big = merge_dsms([a, b], tmp_path / "m.tif", "mean")
    small = merge_dsms([a, b], tmp_path / "t.tif", "mean", tile=16)
    assert big["spacing"] == 1.0
    assert np.array_equal(_read(big["dsm"]), _read(small["dsm"]), equal_nan=True)
    assert big["seams"] == small["seams"]
    seam = big["seams"][0]
    # bilinear resampling of a plane is exact; edge cells of b may be partial
    assert seam["median"] == pytest.approx(-0.5, abs=1e-4)
    assert seam["nmad"] == pytest.approx(0.0, abs=1e-4)
    fixed = merge_dsms([a, b], tmp_path / "s.tif", "mean", spacing=4.0)
    with rasterio.open(fixed["dsm"]) as src:
        assert src.res == (4.0, 4.0) and src.width == 20


def test_other_crs_is_reprojected(tmp_path) -> None:
    from rasterio.warp import transform_bounds

    a = _plane(tmp_path / "a.tif", 500000, 5500100, 100, 100)
    # b covers the same area in EPSG:25833 at 2 m
    x0, bt, r, t = transform_bounds(CRS, "EPSG:25833", 500020, 5500020, 500080, 5500080)
    write_raster(tmp_path / "b.tif", np.full((int((t - bt) / 2), int((r - x0) / 2)), 7.0,
                                             np.float32),
                 transform=Affine(2, 0, x0, 0, -2, t), crs="EPSG:25833")
    res = merge_dsms([a, str(tmp_path / "b.tif")], tmp_path / "m.tif", "median")
    with rasterio.open(res["dsm"]) as src:
        assert src.crs.to_epsg() == 25832
    assert res["seams"][0]["count"] > 2500
    assert _read(res["count"]).max() == 2


def test_best_sigma(tmp_path) -> None:
    sig_a = np.full((20, 20), 0.1, np.float32)
    sig_a[:, 10:] = 1.0
    a = _plane(tmp_path / "a.tif", 0, 20, 20, 20, sigma=sig_a)
    b = _plane(tmp_path / "b.tif", 0, 20, 20, 20, offset=1.0, sigma=0.5)
    res = merge_dsms([a, b], tmp_path / "m.tif", "best_sigma")
    z, za = _read(res["dsm"]), _read(a)
    assert np.array_equal(z[:, :10], za[:, :10]) and np.array_equal(z[:, 10:], za[:, 10:] + 1)
    # a sibling <name>_sigma.tif; an input without σ is used only where nothing else is
    c = tmp_path / "s"
    c.mkdir()
    pa = _plane(c / "a.tif", 0, 20, 20, 20)
    write_raster(c / "a_sigma.tif", np.full((20, 20), 0.2, np.float32),
                 transform=Affine(1, 0, 0, 0, -1, 20), crs=CRS)
    pb = _plane(c / "b.tif", 0, 20, 30, 20, offset=1.0)
    fb = Feedback()
    res = merge_dsms([pa, pb], tmp_path / "n.tif", "best_sigma", feedback=fb)
    z = _read(res["dsm"])
    assert np.array_equal(z[:, :20], _read(pa)) and np.array_equal(z[:, 20:], _read(pb)[:, 20:])
    assert res["seams"][0]["mean"] == -1.0 and any("no σ" in w for w in fb.warnings)


def test_best_sigma_without_sigma_is_median(tmp_path) -> None:
    paths = [_plane(tmp_path / f"{k}.tif", 0, 20, 20, 20, offset=o)
             for k, o in enumerate((0.0, 3.0, 1.0))]
    fb = Feedback()
    best = merge_dsms(paths, tmp_path / "b.tif", "best_sigma", feedback=fb)
    med = merge_dsms(paths, tmp_path / "m.tif", "median")
    assert np.array_equal(_read(best["dsm"]), _read(med["dsm"]))
    assert any("median is used" in w for w in fb.warnings)


def test_cancel_leaves_nothing(tmp_path) -> None:
    a = _plane(tmp_path / "in" / "a.tif", 0, 20, 20, 20)
    fb = Feedback()
    fb.cancel()
    out = tmp_path / "out"
    with pytest.raises(Cancelled):
        merge_dsms([a], out / "m.tif", feedback=fb)
    assert not out.exists() or list(out.iterdir()) == []


def test_one_line_errors(tmp_path) -> None:
    a = _plane(tmp_path / "a.tif", 0, 20, 20, 20)
    write_raster(tmp_path / "nocrs.tif", np.zeros((5, 5), np.float32),
                 transform=Affine(1, 0, 0, 0, -1, 5))
    write_raster(tmp_path / "empty.tif", np.full((5, 5), np.nan, np.float32),
                 transform=Affine(1, 0, 0, 0, -1, 5), crs=CRS)
    cases = [
        ([], "No input DSMs"),
        ([str(tmp_path / "empty.tif")], "has a height"),
        ([a, str(tmp_path / "nocrs.tif")], "no CRS"),
        ([str(tmp_path / "missing.tif")], "does not exist"),
    ]
    for inputs, text in cases:
        with pytest.raises(InputError, match=text) as err:
            merge_dsms(inputs, tmp_path / "o" / "m.tif")
        assert "\n" not in str(err.value)
    with pytest.raises(InputError, match="Unknown merge mode"):
        merge_dsms([a], tmp_path / "o" / "m.tif", mode="max")
    with pytest.raises(InputError, match="overwrite an input"):
        merge_dsms([a], a)
    assert not (tmp_path / "o").exists() or list((tmp_path / "o").iterdir()) == []


def test_registry_run(tmp_path) -> None:
    a = _plane(tmp_path / "a.tif", 1000, 2000, 30, 30)
    b = _plane(tmp_path / "b.tif", 1010, 1990, 30, 30, offset=0.25)
    out = tmp_path / "m.tif"
    res = registry.run("dsm_merge", {"inputs": f"{a},{b}", "output": str(out),
                                     "mode": "mean"})
    assert set(res) == {"dsm", "count", "seams", "report", "csv", "coverage"}
    assert res["seams"][0]["mean"] == -0.25
    assert all(Path(p).is_file() for p in sibling_paths(out).values())


# -- walls (issue 19): no averaging of a roof and the ground -----------------------------------
ROOF = 8.0  # building height above the ground (m)


def _box_dsm(path: Path, wall_col: int, s: float = 0.2, x0: float = 0.0, hole=None,
             n: int = 100) -> str:
    """Sloped ground (1 %) with a flat-roofed building over cols ≥ ``wall_col``, rows 30–69."""
    cols, rows = np.meshgrid(np.arange(n), np.arange(n))
    x = x0 + (cols + 0.5) * s
    z = 100.0 + 0.01 * x
    z = np.where((cols >= wall_col) & (cols < 80) & (rows >= 30) & (rows < 70), z + ROOF, z)
    if hole is not None:
        z[hole] = np.nan
    write_raster(path, z.astype(np.float32), transform=Affine(s, 0, x0, 0, -s, 20.0), crs=CRS)
    return str(path)


def _wall_col(row: np.ndarray, x0: float = 0.0, s: float = 0.2) -> int:
    """First column of a row whose height is at least half the building above the ground."""
    ground = 100.0 + 0.01 * (x0 + (np.arange(row.size) + 0.5) * s)
    return int(np.argmax(row - ground >= 0.5 * ROOF))


def _between(z: np.ndarray, s: float = 0.2) -> int:
    """Cells neither on the ground nor on the roof (more than 0.5 m from both)."""
    cols = np.arange(z.shape[1])
    ground = 100.0 + 0.01 * (cols + 0.5) * s
    d = z - ground[None, :]
    return int((np.isfinite(d) & (np.abs(d) > 0.5) & (np.abs(d - ROOF) > 0.5)).sum())


def test_two_dsms_with_a_shifted_wall_keep_a_step(tmp_path) -> None:
    a = _box_dsm(tmp_path / "a.tif", 40)
    b = _box_dsm(tmp_path / "b.tif", 42)  # the same wall two cells (0.4 m) further in
    plain = _read(merge_dsms([a, b], tmp_path / "plain.tif", "median", step=0.0)["dsm"])
    assert _between(plain) == 2 * 40  # the old rule: half height on the disputed cells
    for mode in ("median", "mean"):
        z = _read(merge_dsms([a, b], tmp_path / f"{mode}.tif", mode, tile=32)["dsm"])
        assert _between(z) == 0
        walls = [_wall_col(z[r]) for r in range(32, 68)]
        assert all(40 <= c <= 42 for c in walls) and max(walls) - min(walls) <= 1
        assert np.allclose(z[50, 50:78] - (100.0 + 0.01 * (np.arange(50, 78) + 0.5) * 0.2),
                           ROOF, atol=1e-4)  # the roof keeps its height


def test_majority_wall_and_roof_hole_on_another_grid(tmp_path) -> None:
    a = _box_dsm(tmp_path / "a.tif", 40)
    hole = (slice(40, 60), slice(50, 70))
    b = _box_dsm(tmp_path / "b.tif", 40, hole=hole)
    c = _box_dsm(tmp_path / "c.tif", 45)  # one input with the wall 1 m off
    z = _read(merge_dsms([a, b, c], tmp_path / "m.tif", "mean")["dsm"])
    assert _between(z) == 0
    assert all(_wall_col(z[r]) == 40 for r in range(31, 69))  # the majority's wall
    # b half a cell off the grid: resampled, but the cells at the wall take the nearest cell
    b2 = _box_dsm(tmp_path / "b2.tif", 40, x0=0.1, hole=hole)
    m2 = merge_dsms([a, b2], tmp_path / "m2.tif", "median")
    z2 = _read(m2["dsm"])
    assert _between(z2[:, 1:-1]) == 0
    assert all(abs(_wall_col(z2[r]) - 40) <= 1 for r in range(32, 68))
    ground = 100.0 + 0.01 * (np.arange(50, 70) + 0.5) * 0.2
    assert np.allclose(z2[40:60, 50:70] - ground[None, :], ROOF, atol=0.01)  # hole: a's roof
    plain = _read(merge_dsms([a, b2], tmp_path / "p2.tif", "median", step=0.0)["dsm"])
    assert _between(plain[:, 1:-1]) > 0  # bilinear across the wall without the rule
