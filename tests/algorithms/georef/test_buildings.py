"""Buildings mode of the polygon georeferencing (issue 23): small synthetic suburban scenes."""

from __future__ import annotations

import numpy as np
import pytest

from photodem.algorithms.errors import GeometryError, InputError
from photodem.algorithms.georef.buildings import is_buildings, roof_candidates
from photodem.algorithms.georef.fit import corner_error
from photodem.algorithms.georef.pipeline import georeference
from photodem.algorithms.georef.reference_layer import reference_objects_from_vector
from photodem.algorithms.georef.regions import load_image
from photodem.algorithms.synthetic.polygon_scene import georef_case
from photodem.algorithms.synthetic.suburban_scene import suburban_case

#: Corner tolerance of the tests (px); the goal is 1 px (not reached yet, see the bench). The
#: relief displacement of the roofs (0–3 px, radial) alone biases any fit to roofs by a scale
#: about the image centre (1–2 px at the corners, see the module notes).
CORNER_PX = 2.5


def _corners(res, case) -> float:
    return float(np.max(corner_error(res.fit, case["truth"], case["width"], case["height"])))


def test_auto_detection(tmp_path):
    town = suburban_case(tmp_path / "town", seed=2, width=400, height=400)
    ref, _, _ = reference_objects_from_vector(town["reference"])
    assert is_buildings(ref)
    areas = georef_case(tmp_path / "areas", seed=2, width=300, height=300)
    ref, _, _ = reference_objects_from_vector(areas["reference"])
    assert not is_buildings(ref)


def test_candidates_find_the_roofs(tmp_path):
    case = suburban_case(tmp_path, seed=4, width=500, height=500)
    grey, _ = load_image(case["image"])
    cands, info = roof_candidates(grey)
    assert len(info["runs"]) == 3 and any(r["merged"] for r in info["runs"])
    ref, _, _ = reference_objects_from_vector(case["reference"])
    Ti = np.linalg.inv(case["truth"])
    cent = np.array([(Ti @ np.r_[o.ring.mean(axis=0), 1.0])[:2] for o in ref])
    inside = (cent >= 0).all(axis=1) & (cent <= 499).all(axis=1)
    cc = np.array([c.ring.mean(axis=0) for c in cands])
    near = [np.min(np.hypot(*(cc - p).T)) < 6 for p in cent[inside]]
    assert np.mean(near) >= 0.5  # measured: 0.59 (seed 4)


def test_bad_objects_option(tmp_path):
    case = suburban_case(tmp_path, seed=1, width=200, height=200)
    with pytest.raises(InputError, match="objects"):
        georeference(case["image"], case["reference"], objects="houses")


@pytest.mark.slow
@pytest.mark.parametrize("seed, bits", [(0, 8), (1, 12)])
def test_recovers_corners(tmp_path, seed, bits):
    """Rotation (any angle), mirroring (seed 1) and 12-bit data in uint16, 900 × 900 px.

    Goal of issue 23: 1 px. Measured: 2.26 px (seed 0), 1.90 px (seed 1) — the tolerance
    here is what the mode reaches today (see the bench), not the goal. The acceptance gate
    refuses seed 0 (control points over 13 % of the image, halves of them 2.2 px apart at the
    corners) and passes seed 1 (1.9 px: the roofs' relief displacement is a scale about the
    centre that the image evidence cannot see), so the placement is checked with
    ``unverified``."""
    case = suburban_case(tmp_path, seed=seed, bits=bits)
    assert case["mirrored"] == (seed == 1)
    res = georeference(case["image"], case["reference"], objects="buildings", unverified=True)
    assert res.stage == "buildings"
    assert len(res.pairs) >= 3 and res.img_features and res.ref_features
    err = _corners(res, case)
    assert err <= CORNER_PX


@pytest.mark.slow
def test_different_town_fails(tmp_path):
    case = suburban_case(tmp_path, seed=3, width=500, height=500, town_seed=103)
    with pytest.raises(GeometryError, match="Georeferencing failed: the best placement"):
        georeference(case["image"], case["reference"], objects="buildings")
