"""Dense matching: synthetic pair with a known disparity field, tiles, masks, cancel, registry."""

from __future__ import annotations

from pathlib import Path
from typing import Dict, Tuple

import numpy as np
import pytest
from scipy import ndimage

from photodem.algorithms.errors import Cancelled, InputError
from photodem.algorithms.feedback import Feedback
from photodem.algorithms.matching.dense import (
    DenseOptions,
    fill_holes_rows,
    sgm_disparity,
)
from photodem.algorithms.matching.disparity_run import (
    DisparityStats,
    grey_source,
    run_stereo_disparity,
)
from photodem.algorithms.processing import registry
from photodem.algorithms.raster.io import open_image, write_raster

H, W = 150, 240


def _pair(shift: float = 0.0, seed: int = 1, extra: int = 0) -> Dict[str, np.ndarray]:
    """Left/right grey images and the true left disparity (NaN where occluded).

    The disparity is defined on the right image, ``d_R = 9 + 3·sin(2πy/H)·cos(πx/W) + 6·[x > W/2]
    + shift``; the right image is ``T(x + d_R, y)`` of a texture ``T`` (the left image), with a
    gain of 1.3, an offset of −25 and noise σ = 2. The left truth follows by inverting
    ``x_l = x_r + d_R(x_r)`` along each row. ``extra`` widens the texture for large shifts.
    """
    rng = np.random.default_rng(seed)
    base = ndimage.gaussian_filter(rng.normal(size=(H, W + 80 + extra)), 1.2)
    base = 120.0 + 45.0 * base / base.std()
    yy, xr = np.mgrid[0:H, 0:W].astype(float)
    d_r = 9.0 + 3.0 * np.sin(2 * np.pi * yy / H) * np.cos(np.pi * xr / W) + 6.0 * (xr > W / 2)
    d_r += shift
    off = 40.0  # the texture starts 40 px left of image column 0
    left = base[:, 40:40 + W]
    right = ndimage.map_coordinates(base, [yy, xr + d_r + off], order=3, mode="reflect")
    right = 1.3 * right - 25.0 + rng.normal(0.0, 2.0, size=right.shape)
    truth = np.full((H, W), np.nan)
    xl = xr + d_r
    cols = np.arange(W, dtype=float)
    for r in range(H):  # a test-side inversion, one row at a time
        d = np.interp(cols, xl[r], d_r[r], left=np.nan, right=np.nan)
        # occluded: left pixels jumped over at the step (no right pixel maps near them)
        gap = np.diff(xl[r]) > 1.5
        for i in np.nonzero(gap)[0]:
            d[(cols > xl[r, i] - 2) & (cols < xl[r, i + 1] + 2)] = np.nan
        truth[r] = d
    truth[:, :4] = np.nan
    truth[:4], truth[-4:] = np.nan, np.nan
    return {"left": left.astype(np.float32), "right": right.astype(np.float32), "truth": truth}


@pytest.fixture(scope="module")
def pair() -> Dict[str, np.ndarray]:
    return _pair()


def _score(disp: np.ndarray, truth: np.ndarray) -> Tuple[float, float]:
    ok = np.isfinite(truth)
    has = np.isfinite(disp[ok])
    err = disp[ok][has] - truth[ok][has]
    return float(np.sqrt(np.mean(err ** 2))), float(has.mean())


def test_known_disparity_field(pair) -> None:
    disp = sgm_disparity(pair["left"], pair["right"], 0, 31)
    assert disp.dtype == np.float32 and disp.shape == (H, W)
    rms, valid = _score(disp, pair["truth"])
    assert rms < 0.3, rms
    assert valid >= 0.95, valid


def test_wide_search_range_is_narrowed_by_a_coarse_pass(monkeypatch) -> None:
    """Disparities 169–181 px searched in 100–400: the coarse pass (factor 8) narrows every
    tile's range, and the result is as accurate as the full-range search."""
    from photodem.algorithms.matching import dense

    p = _pair(shift=160.0, seed=3, extra=200)
    depths = []
    real = dense._sgbm

    def spy(cv2, min_d, num_d, *args):
        depths.append(num_d)
        return real(cv2, min_d, num_d, *args)

    monkeypatch.setattr(dense, "_sgbm", spy)
    disp = sgm_disparity(p["left"], p["right"], 100, 400)
    rms, valid = _score(disp, p["truth"])
    assert rms < 0.3 and valid >= 0.95, (rms, valid)
    assert depths[0] <= dense.COARSE_DISPARITIES  # the coarse pass
    assert max(depths[1:]) <= 64, depths  # 12 px of disparities + 2 × (2·8 + 8) px of slack
    depths.clear()
    full = sgm_disparity(p["left"], p["right"], 100, 400, coarse_above=0)
    # every tile searches the whole range, cut to the disparities the images allow
    lo, hi = dense.check_disparity_range(100, 400, p["left"].shape, p["right"].shape)
    assert hi == min(400, p["left"].shape[1] - 1)
    assert set(depths) == {dense._num_disparities(lo, hi)}
    rms_full, valid_full = _score(full, p["truth"])
    assert rms <= rms_full + 0.05 and valid >= valid_full - 0.01, (rms_full, valid_full)


def test_block_mean_source_ignores_masked_pixels() -> None:
    from photodem.algorithms.matching.dense import array_source, block_mean_source

    img = np.arange(48, dtype=np.float32).reshape(6, 8)
    img[0, 0] = np.nan
    img[4:6, 6:8] = np.nan
    src, shape = array_source(img)
    out = block_mean_source(src, shape, 2, max_pixels=16)  # strips of 4 rows
    assert out.shape == (3, 4)
    assert out[0, 0] == pytest.approx((1 + 8 + 9) / 3)
    assert out[1, 2] == pytest.approx(img[2:4, 4:6].mean())
    assert np.isnan(out[2, 3])
    odd, _ = array_source(np.ones((5, 7), np.float32))
    assert np.array_equal(block_mean_source(odd, (5, 7), 4), np.ones((2, 2), np.float32))


def test_negative_disparities() -> None:
    p = _pair(shift=-20.0, seed=2)
    disp = sgm_disparity(p["left"], p["right"], -16, 0)
    rms, valid = _score(disp, p["truth"])
    assert rms < 0.3 and valid >= 0.95, (rms, valid)
    assert np.nanmax(disp) <= 0.0


def test_gain_offset_needs_normalisation(pair) -> None:
    """Without the local normalisation the gain/offset change costs accuracy or coverage."""
    ours = _score(sgm_disparity(pair["left"], pair["right"], 0, 31), pair["truth"])
    raw = _score(sgm_disparity(pair["left"], pair["right"], 0, 31,
                               options=DenseOptions(normalise_window=0)), pair["truth"])
    assert ours[1] >= raw[1] - 0.01


def test_tiles_equal_one_tile(pair) -> None:
    one = sgm_disparity(pair["left"], pair["right"], 0, 31)
    tiled = sgm_disparity(pair["left"], pair["right"], 0, 31, tile_size=64, margin=48)
    both = np.isfinite(one) & np.isfinite(tiled)
    assert both.sum() > 0.9 * np.isfinite(one).sum()
    diff = np.abs(one - tiled)[both]
    assert np.mean(diff > 0.25) < 0.01, np.mean(diff > 0.25)
    # at the tile borders (columns/rows 64, 128, …) just as well
    border = np.zeros_like(both)
    border[:, [63, 64, 127, 128, 191, 192]] = True
    border[[63, 64, 127, 128], :] = True
    assert np.mean(np.abs(one - tiled)[both & border] > 0.25) < 0.02
    rms, valid = _score(tiled, pair["truth"])
    assert rms < 0.3 and valid >= 0.95


def test_memory_budget_sets_tiles(pair) -> None:
    small = sgm_disparity(pair["left"], pair["right"], 0, 31, max_memory_mb=16)
    rms, valid = _score(small, pair["truth"])
    assert rms < 0.3 and valid >= 0.95


def test_masks_honoured(pair) -> None:
    left, right = pair["left"].copy(), pair["right"].copy()
    left[40:70, 30:90] = np.nan  # no data in the left image
    right[100:130, 150:200] = np.nan  # no data in the right image
    disp = sgm_disparity(left, right, 0, 31, options=DenseOptions(fill_max_width=50))
    assert np.isnan(disp[40:70, 30:90]).all()
    # left pixels whose partner lies in the masked right area have no disparity
    cols = np.mgrid[100:130, 0:W][1]
    partner = cols - pair["truth"][100:130]
    inside = (partner > 152) & (partner < 198)
    assert np.isnan(disp[100:130][inside]).all()
    rms, _ = _score(disp, pair["truth"])
    assert rms < 0.3


def test_edge_erosion_and_range_guard(pair) -> None:
    left = pair["left"].copy()
    left[40:70, 100:140] = np.nan  # a masked area: its rim loses 2 px of disparities
    plain = sgm_disparity(left, pair["right"], 0, 31)
    eroded = sgm_disparity(left, pair["right"], 0, 31, options=DenseOptions(edge_erosion=2))
    ok = np.isfinite(eroded)
    assert np.array_equal(eroded[ok], plain[ok])  # only removes, never changes
    assert np.isnan(eroded[38:72, 98:142]).all()
    assert np.isfinite(plain[38:72, 98:142]).any()
    rms_p, _ = _score(plain, pair["truth"])
    rms_e, valid_e = _score(eroded, pair["truth"])
    assert rms_e <= rms_p + 1e-6 and valid_e > 0.85
    # the guard removes disparities near the range ends: here all below 6 and above 25
    guarded = sgm_disparity(pair["left"], pair["right"], 0, 31,
                            options=DenseOptions(range_guard=6.0))
    g = guarded[np.isfinite(guarded)]
    assert g.size and g.min() >= 6.0 and g.max() <= 25.0


def test_fill_holes_rows() -> None:
    d = np.array([[5.0, np.nan, np.nan, 2.0, np.nan, np.nan, np.nan, np.nan, 7.0]])
    masked = np.zeros_like(d, bool)
    out = fill_holes_rows(d, masked, 2)
    assert out[0, 1] == out[0, 2] == 2.0  # the smaller neighbour
    assert np.isnan(out[0, 4:8]).all()  # too wide
    masked[0, 5] = True
    out = fill_holes_rows(d, masked, 2)
    assert out[0, 4] == 2.0 and np.isnan(out[0, 5]) and out[0, 6] == out[0, 7] == 7.0


def test_bad_range() -> None:
    with pytest.raises(InputError):
        sgm_disparity(np.zeros((20, 20)), np.zeros((20, 20)), 5, 4)


def _write_pair(folder: Path, pair) -> Tuple[str, str]:
    """RGB + alpha GeoTIFFs in image space, as written by epipolar_pair."""
    out = []
    for side in ("left", "right"):
        g = np.clip(pair[side], 0, 255).astype(np.uint8)
        alpha = np.full(g.shape, 255, np.uint8)
        if side == "left":
            alpha[:, :20] = 0
        path = folder / f"{side}.tif"
        write_raster(path, np.stack([g, g, g, alpha]), photometric="RGB", alpha="YES")
        out.append(str(path))
    return out[0], out[1]


def test_algorithm_through_registry(pair, tmp_path) -> None:
    left, right = _write_pair(tmp_path, pair)
    out = tmp_path / "disp.tif"
    res = registry.run("stereo_disparity", {"left": left, "right": right, "min_disparity": 0,
                                            "max_disparity": 31, "output": str(out)})
    assert res["disparity"] == str(out) and out.is_file()
    with open_image(out) as src:
        assert src.dtypes[0] == "float32" and (src.width, src.height) == (W, H)
        disp = src.read(1)
    assert np.isnan(disp[:, :20]).all()  # alpha = 0 → no disparity
    truth = pair["truth"].copy()
    truth[:, :20] = np.nan
    rms, valid = _score(disp, truth)
    assert rms < 0.35 and valid >= 0.95
    assert 0.8 < res["valid_share"] <= 1.0
    assert 0.0 <= res["min"] < 10.0 and 16.0 < res["max"] <= 31.0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["disp.tif", "left.tif", "right.tif"]


def test_domain_function_matches_the_declaration(pair, tmp_path) -> None:
    """run_stereo_disparity is the orchestration; the declaration only passes parameters."""
    left, right = _write_pair(tmp_path, pair)
    small = tmp_path / "small.tif"
    res = run_stereo_disparity(left, right, small, min_disparity=0, max_disparity=31,
                               memory_mb=16.0)  # several tiles
    via = registry.run("stereo_disparity", {"left": left, "right": right, "min_disparity": 0,
                                            "max_disparity": 31, "memory_mb": 16.0,
                                            "output": str(tmp_path / "via.tif")})
    with open_image(small) as a, open_image(via["disparity"]) as b:
        assert np.array_equal(a.read(1), b.read(1), equal_nan=True)
    assert res["disparity"] == str(small)
    assert {k: res[k] for k in ("valid_share", "min", "max")} == {
        k: via[k] for k in ("valid_share", "min", "max")}
    with open_image(left) as src:  # colour mean, NaN where the alpha band is 0
        read, shape = grey_source(src)
        win = read(-2, 3, 18, 23)
    assert shape == (H, W) and win.shape == (5, 5)
    assert np.isnan(win[:2]).all() and np.isnan(win[2:, :2]).all()
    assert np.isfinite(win[2:, 2:]).all()
    stats = DisparityStats()
    stats.add(np.array([[np.nan, 2.5], [-1.0, np.nan]], np.float32))
    assert (stats.n_valid, stats.d_min, stats.d_max) == (2, -1.0, 2.5)
    for bad in ({"output": tmp_path / "x.png"}, {"min_disparity": 5, "max_disparity": 4},
                {"block_size": 4}):
        kw = dict({"output": tmp_path / "x.tif", "min_disparity": 0, "max_disparity": 31},
                  **bad)
        with pytest.raises(InputError):
            run_stereo_disparity(left, right, **kw)
    assert not (tmp_path / "x.tif").exists()


def test_cancel_leaves_no_output(pair, tmp_path) -> None:
    left, right = _write_pair(tmp_path, pair)
    out = tmp_path / "disp.tif"
    fb = Feedback()
    fb.cancel()
    with pytest.raises(Cancelled):
        registry.run("stereo_disparity", {"left": left, "right": right, "min_disparity": 0,
                                          "max_disparity": 31, "output": str(out)}, fb)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["left.tif", "right.tif"]


def test_cancel_mid_run(pair) -> None:
    calls = []
    fb = Feedback(on_progress=calls.append)

    def cancel_after_first(p: float) -> None:
        calls.append(p)
        if len(calls) > 2:
            fb.cancel()

    fb._on_progress = cancel_after_first
    with pytest.raises(Cancelled):
        sgm_disparity(pair["left"], pair["right"], 0, 31, tile_size=64, feedback=fb)
