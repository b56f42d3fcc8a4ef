"""Synthetic multi-temporal image pairs: the truth maps the target onto the reference."""

from __future__ import annotations

import numpy as np
import rasterio
from scipy import ndimage

from photodem.algorithms.georef.fit import centre_matrix
from photodem.algorithms.synthetic.image_pairs import image_pair_case


def _truth_ncc(case: dict) -> float:
    """NCC of the target with the reference resampled through the truth, on the cloud-free
    pixels inside the reference."""
    with rasterio.open(case["reference"]) as src:
        ref = src.read(1).astype(np.float64)
        G = centre_matrix(src.transform)
    with rasterio.open(case["image"]) as src:
        img = src.read(1).astype(np.float64)
    with rasterio.open(case["clouds"]) as src:
        clouds = src.read(1)
    M = np.linalg.inv(G) @ case["truth"]
    rr, cc = np.mgrid[0:case["height"], 0:case["width"]].astype(np.float64)
    x = M[0, 0] * cc + M[0, 1] * rr + M[0, 2]
    y = M[1, 0] * cc + M[1, 1] * rr + M[1, 2]
    res = ndimage.map_coordinates(ref, [y, x], order=1, cval=np.nan)
    ok = np.isfinite(res) & (clouds < 13)
    a, b = img[ok] - img[ok].mean(), res[ok] - res[ok].mean()
    return float((a * b).sum() / np.sqrt((a * a).sum() * (b * b).sum()))


def test_truth_maps_the_target_onto_the_reference(tmp_path) -> None:
    for seed, bits in ((0, 8), (3, 12)):
        case = image_pair_case(tmp_path / f"c{seed}", seed=seed, width=400, height=400,
                               bits=bits)
        assert 0.25 <= case["cloud_share"] <= 0.65
        assert case["mirrored"] == bool(seed % 2)
        assert np.linalg.det(case["truth"][:2, :2]) * (1 if case["mirrored"] else -1) > 0
        assert 0.8 <= case["scale"] <= 1.25
        with rasterio.open(case["image"]) as src:
            assert src.dtypes[0] == ("uint8" if bits == 8 else "uint16")
            assert src.read(1).max() <= (255 if bits == 8 else 4095)
        with rasterio.open(case["reference"]) as src:
            assert src.crs.to_epsg() == 25832
        assert _truth_ncc(case) >= 0.5


def test_cases_are_deterministic(tmp_path) -> None:
    a = image_pair_case(tmp_path / "a", seed=5, width=200, height=150)
    b = image_pair_case(tmp_path / "b", seed=5, width=200, height=150)
    np.testing.assert_array_equal(a["truth"], b["truth"])
    for key in ("image", "reference", "clouds"):
        with rasterio.open(a[key]) as sa, rasterio.open(b[key]) as sb:
            np.testing.assert_array_equal(sa.read(), sb.read())
