"""Synthetic suburban scenes: counts, data types, truth, determinism (issue 23)."""

from __future__ import annotations

import fiona
import numpy as np
import pytest
import rasterio
from affine import Affine
from rasterio import features
from shapely.affinity import affine_transform
from shapely.geometry import shape

from photodem.algorithms.synthetic.suburban_scene import roof_mask, suburban_case


def _footprints(path):
    with fiona.open(path) as src:
        crs = src.crs
        return [shape(f["geometry"]) for f in src], crs


@pytest.fixture(scope="module")
def case8(tmp_path_factory):
    return suburban_case(tmp_path_factory.mktemp("sub8"), seed=3, width=600, height=500)


def test_counts_and_types(case8, tmp_path):
    town = case8["town"]
    polys, crs = _footprints(case8["reference"])
    assert len(polys) == len(town.footprints) >= 30
    assert "25832" in str(crs)
    kinds = set(town.kinds)
    assert {"rectangle", "terrace"} <= kinds and kinds & {"l", "t"}
    assert {p.kind for p in town.roofs} == {"gabled", "hipped", "flat"}
    assert town.trees
    with rasterio.open(case8["image"]) as src:
        assert src.dtypes[0] == "uint8" and (src.width, src.height) == (600, 500)
    c12 = suburban_case(tmp_path, seed=3, width=300, height=300, bits=12)
    with rasterio.open(c12["image"]) as src:
        a = src.read(1)
        assert src.dtypes[0] == "uint16" and 255 < a.max() <= 4095


def test_truth_maps_footprints_onto_roofs(case8):
    """Mean share of roof pixels (per building) inside the mapped footprints ≥ 0.8."""
    T = case8["truth"]
    w, h = case8["width"], case8["height"]
    Ti = np.linalg.inv(T)
    m = [Ti[0, 0], Ti[0, 1], Ti[1, 0], Ti[1, 1], Ti[0, 2] + 0.5, Ti[1, 2] + 0.5]
    polys, _ = _footprints(case8["reference"])
    town = case8["town"]
    groups = np.asarray(town.footprint_building)
    inside = features.rasterize([(affine_transform(p, m), int(g) + 1)
                                 for p, g in zip(polys, groups)], out_shape=(h, w),
                                transform=Affine.identity(), dtype="int32")
    roofs = roof_mask(town, T, w, h)
    lab, n = __import__("scipy.ndimage", fromlist=["label"]).label(roofs)
    shares = []
    for k in range(1, n + 1):
        r = lab == k
        if r.sum() >= 20:
            shares.append(float((inside[r] > 0).mean()))
    assert len(shares) >= 20
    assert np.mean(shares) >= 0.8


def test_deterministic_and_different_town(tmp_path):
    a = suburban_case(tmp_path / "a", seed=5, width=300, height=300)
    b = suburban_case(tmp_path / "b", seed=5, width=300, height=300)
    c = suburban_case(tmp_path / "c", seed=5, width=300, height=300, town_seed=105)
    with rasterio.open(a["image"]) as sa, rasterio.open(b["image"]) as sb, \
            rasterio.open(c["image"]) as sc:
        ia, ib, ic = sa.read(1), sb.read(1), sc.read(1)
    assert np.array_equal(ia, ib) and np.array_equal(ia, ic)
    np.testing.assert_array_equal(a["truth"], b["truth"])
    pa, _ = _footprints(a["reference"])
    pc, _ = _footprints(c["reference"])
    assert [p.wkt for p in pa] == [p.wkt for p in _footprints(b["reference"])[0]]
    assert [p.wkt for p in pa] != [p.wkt for p in pc]
