"""Buildings mode of the polygon georeferencing (issue 23): small synthetic suburban scenes."""

from __future__ import annotations

import numpy as np
import pytest
from shapely.geometry import Polygon

from photodem.algorithms.errors import GeometryError, InputError
from photodem.algorithms.georef.buildings import is_buildings, mirrored_wholes, roof_candidates
from photodem.algorithms.georef.correspondence import apply
from photodem.algorithms.georef.fit import corner_error
from photodem.algorithms.georef.pipeline import georeference
from photodem.algorithms.georef.reference_layer import reference_objects_from_vector
from photodem.algorithms.georef.regions import label_rings, load_image
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


def _found(cands, ref, truth, width: int, height: int):
    """Footprints inside the image with a whole-roof candidate (IoU > 0.6) and with a
    roof-half candidate (30–70 % of the footprint, centroid inside): (inside, whole, half)."""
    Ti = np.linalg.inv(truth)
    polys = [Polygon(c.ring).buffer(0) for c in cands]
    boxes = np.array([c.bounds for c in polys])  # (minx, miny, maxx, maxy)
    inside = whole = half = 0
    for o in ref:
        p = Polygon(apply(Ti, o.ring))
        if not (0 < p.centroid.x < width - 1 and 0 < p.centroid.y < height - 1):
            continue
        inside += 1
        x0, y0, x1, y1 = p.bounds  # shapely 1.8 and 2: no STRtree (its query differs)
        near = [polys[k] for k in np.nonzero((boxes[:, 0] <= x1) & (boxes[:, 2] >= x0)
                                             & (boxes[:, 1] <= y1) & (boxes[:, 3] >= y0))[0]]
        whole += any(p.intersection(c).area / p.union(c).area > 0.6 for c in near)
        half += any(0.3 < c.area / p.area < 0.7 and p.contains(c.centroid) for c in near)
    return inside, whole, half


def test_candidates_find_the_roofs(tmp_path):
    """Seed 2 (8-bit), 500 × 500 px, no relief displacement. Measured: 71 footprints inside,
    41 with a whole-roof candidate (20 without the mirrored halves), 53 with a half, 1191
    candidates of which 656 mirrored (at 900 × 900 px the former flat-zone candidates found
    5 and 30 of 73, the segments 21 and 46)."""
    case = suburban_case(tmp_path, seed=2, width=500, height=500, relief_px=0.0)
    grey, _ = load_image(case["image"])
    cands, info = roof_candidates(grey)
    assert len(info["runs"]) == 2 and any(r["merged"] for r in info["runs"])
    assert all(r["mirrored"] for r in info["runs"])
    ref, _, _ = reference_objects_from_vector(case["reference"])
    inside, whole, half = _found(cands, ref, case["truth"], 500, 500)
    assert inside >= 50
    assert whole >= 0.5 * inside and half >= 0.65 * inside
    own = [c for c in cands if not c.attributes["mirrored"]]
    assert len(own) <= 15 * inside  # clutter stays bounded
    assert len(cands) - len(own) <= 2 * len(own)


def _rectangle(c: np.ndarray, angle: float, a: float, b: float) -> np.ndarray:
    u = np.array([np.cos(np.radians(angle)), np.sin(np.radians(angle))])
    v = np.array([-u[1], u[0]])
    return np.array([c + s * a * u + t * b * v for s, t in ((-1, -1), (1, -1), (1, 1), (-1, 1))])


@pytest.mark.parametrize("angle", [0.0, 17.0, 45.0, 71.0])
@pytest.mark.parametrize("a, b", [(12.0, 4.0), (8.0, 3.0), (20.0, 6.0)])
def test_mirrored_wholes_restore_the_roof(angle, a, b):
    """A rasterised roof half (half width b, 3–6 px): one of its two mirror images is the
    whole roof. Measured IoU 0.87–0.995 (the other 0.29–0.34)."""
    from matplotlib.path import Path

    centre = np.array([40.0, 40.0])
    u = np.array([np.cos(np.radians(angle)), np.sin(np.radians(angle))])
    whole = Polygon(_rectangle(centre, angle, a, 2 * b))
    half = _rectangle(centre + b * np.array([-u[1], u[0]]), angle, a, b)
    yy, xx = np.mgrid[0:80, 0:80]
    mask = Path(half).contains_points(np.c_[xx.ravel(), yy.ravel()]).reshape(80, 80)
    ring = label_rings(mask.astype(np.int32))[0][1] - 0.5  # pixel centres at integers
    got = mirrored_wholes(ring, int(mask.sum()))
    assert len(got) == 2
    iou = sorted(whole.intersection(Polygon(w)).area / whole.union(Polygon(w)).area
                 for w in got)
    assert iou[1] >= 0.85 and iou[0] <= 0.4
    # a square segment is no roof half; a whole beyond the size limit is not made
    assert mirrored_wholes(_rectangle(centre, angle, 5.0, 5.0), 100) == []
    assert mirrored_wholes(ring, int(mask.sum()), max_area=4.0 * a * b) == []


def test_bad_objects_option(tmp_path):
    case = suburban_case(tmp_path, seed=1, width=200, height=200)
    with pytest.raises(InputError, match="objects"):
        georeference(case["image"], case["reference"], objects="houses")


@pytest.mark.slow
@pytest.mark.parametrize("seed, bits", [(0, 8), (1, 12)])
def test_recovers_corners(tmp_path, seed, bits):
    """Rotation (any angle), mirroring (seed 1) and 12-bit data in uint16, 900 × 900 px.

    Goal of issue 23: 1 px. Measured: 0.86 px (seed 0), 0.63 px (seed 1) — the tolerance
    here is what the mode reaches with the roofs' relief displacement (a scale about the
    centre that a fit to roofs cannot see; relief 0: 0.25 / 0.23 px), not the goal; the
    placement is checked with ``unverified``."""
    case = suburban_case(tmp_path, seed=seed, bits=bits)
    assert case["mirrored"] == (seed == 1)
    res = georeference(case["image"], case["reference"], objects="buildings", unverified=True)
    assert res.stage == "buildings"
    assert len(res.pairs) >= 3 and res.img_features and res.ref_features
    err = _corners(res, case)
    assert err <= CORNER_PX


@pytest.mark.slow
def test_relief0_within_1px(tmp_path):
    """Roofs exactly over their footprints (no relief displacement): the candidates and the
    consensus alone place the image within 1 px at the corners, verified. Measured: seed 0
    (8-bit, 900 × 900 px) 0.37 px."""
    case = suburban_case(tmp_path, seed=0, relief_px=0.0)
    res = georeference(case["image"], case["reference"], objects="buildings")
    assert res.stage == "buildings" and res.verified
    assert _corners(res, case) <= 1.0


@pytest.mark.slow
def test_different_town_fails(tmp_path):
    case = suburban_case(tmp_path, seed=3, width=500, height=500, town_seed=103)
    with pytest.raises(GeometryError, match="Georeferencing failed: the best placement"):
        georeference(case["image"], case["reference"], objects="buildings")


def test_mirrored_16bit_small_scene(tmp_path):
    """Mirrored image map, rotation −73°, 16-bit data, 600 × 600 px, no relief: whole roofs
    from the mirrored halves carry the verification. Measured: 0.34 px, verified, 28 roofs,
    3.1 s (other seeds at this size fail with a message: fewer buildings, no clear lead)."""
    case = suburban_case(tmp_path, seed=2, width=600, height=600, bits=16, mirror=True,
                         relief_px=0.0)
    assert case["mirrored"]
    res = georeference(case["image"], case["reference"], objects="buildings")
    assert res.stage == "buildings" and res.verified
    assert len(res.pairs) >= 20
    assert any(res.img_features[h.i].obj.attributes.get("mirrored") for h in res.pairs)
    assert _corners(res, case) <= 0.6


@pytest.mark.slow
def test_gate_refuses_a_buildings_result_moved_by_a_few_pixels(tmp_path):
    """A right buildings result (seed 0, 900 × 900 px, relief 3 px) moved by a similarity —
    shift, rotation or scale alone — that puts its worst corner 2.5 px off, its control points
    moved with it (a consistently wrong result): the gate refuses each. Measured on seeds
    0–11 with random similarities: 0 of 103 results 2–6 px off verified, 2 of 25 at 1.5–2 px
    (docs/decisions.md)."""
    from dataclasses import replace

    from photodem.algorithms.georef.area import similarity
    from photodem.algorithms.georef.evidence import assess
    from photodem.algorithms.georef.fit import fit_transform, inverse_for_resampling
    from photodem.algorithms.georef.pipeline import _roof_level

    case = suburban_case(tmp_path, seed=0, bits=8)
    res = georeference(case["image"], case["reference"], objects="buildings")
    assert res.verified and _corners(res, case) <= 1.0
    objs, _, _ = reference_objects_from_vector(case["reference"])
    outlines = [b for o in objs for b in o.attributes.get("outlines", [o.ring])]
    img = np.array([g.image for g in res.gcps], float)
    mp = np.array([g.map for g in res.gcps], float)
    w, h = case["width"], case["height"]
    centre = np.array([(w - 1) / 2, (h - 1) / 2])
    half_diagonal = float(np.hypot(w, h) / 2)
    for shift, turn, grow in (((1.77, 1.77), 0.0, 0.0), ((0.0, 0.0), 2.5, 0.0),
                              ((0.0, 0.0), 0.0, 2.5)):
        S = similarity(turn / half_diagonal, 1.0 + grow / half_diagonal)
        S[:2, 2] = centre + np.array(shift) - S[:2, :2] @ centre
        moved = res.fit.forward(apply(S, img)) - (res.fit.forward(img) - mp)
        fit = fit_transform(img, moved, res.fit.kind)
        wrong = replace(res, fit=fit, gcps=[replace(g, map=tuple(m))
                                            for g, m in zip(res.gcps, moved)],
                        inverse_fit=inverse_for_resampling(fit, img[fit.used],
                                                           moved[fit.used]))
        assert _corners(wrong, case) > 2.0
        ev = assess(wrong, _roof_level(wrong, outlines), buildings=True)
        assert not ev.verified, (shift, turn, grow, ev.reasons)


def _town_on_a_grid(seed: int):
    """Footprints (map, m) of random size and orientation at the nodes of a 25 m grid; the
    roofs seen in the image (px) through ``truth`` (image → map): whole roofs for even
    footprints, one roof half for odd ones."""
    from photodem.algorithms.georef.buildings import roof_halves
    from photodem.algorithms.georef.objects import IMAGE, REFERENCE, PolygonObject, orient_ring

    rng = np.random.default_rng(seed)
    truth = np.array([[0.8, 0.3, 1000.0], [-0.25, 0.9, 2000.0], [0.0, 0.0, 1.0]])
    ref = []
    for k, (x, y) in enumerate(np.mgrid[0:6, 0:6].reshape(2, -1).T * 25.0):
        ring = _rectangle(np.array([1000.0 + x, 2000.0 + y]), rng.uniform(0, 180),
                          rng.uniform(4.0, 10.0), rng.uniform(2.5, 5.0))
        ref.append(PolygonObject(id=k, ring=orient_ring(ring), source=REFERENCE))
    halves, _ = roof_halves(ref)
    inv = np.linalg.inv(truth)
    cands = [PolygonObject(id=k, ring=orient_ring(apply(inv, (o if k % 2 == 0 else
                                                              halves[2 * k]).ring)),
                           source=IMAGE, attributes={"mirrored": False})
             for k, o in enumerate(ref)]
    return ref, halves, cands, truth


def test_shape_count_tells_the_placement():
    """A placement one grid step off puts every roof's centroid on a footprint centroid (a
    full centroid count) but few roofs on a footprint's shape; the right one, 1.6 m off
    (within the centroid tolerance of 2.6 m), covers all after the refit."""
    from photodem.algorithms.georef.buildings import MIN_LEAD, _refine, _shapes, roof_halves
    from photodem.algorithms.georef.invariants import object_features

    ref, _, cands, truth = _town_on_a_grid(5)
    halves, owner = roof_halves(ref)
    fr, fi = object_features(ref), object_features(cands)
    shapes = _shapes(fr, object_features(halves), owner)
    rings = [o.ring for o in ref] + [h.ring for h in halves]
    base_tol = 0.25 * float(np.sqrt(np.median([f.area for f in fr])))
    shift = np.eye(3)
    shift[:2, 2] = (1.2, -1.0)
    T, right = _refine(shift @ truth, fi, shapes, rings, base_tol)
    assert right == len(ref)
    corners = np.array([[0.0, 0.0], [150.0, 0.0], [0.0, 150.0], [150.0, 150.0]])
    assert np.max(np.abs(apply(T, corners) - apply(truth, corners))) < 0.01
    shift[:2, 2] = (25.0, 0.0)  # the neighbour's node
    _, wrong = _refine(shift @ truth, fi, shapes, rings, base_tol)
    assert wrong <= 0.4 * len(ref) < right / MIN_LEAD  # measured 10 of 36


def test_decision_by_shapes_not_centroids():
    """The placement with more centroid matches but few shape matches loses; a lead below
    :data:`MIN_LEAD` is no consensus."""
    from photodem.algorithms.georef.buildings import MIN_LEAD, _decision, _Placement

    cr = np.array([[x, y] for x in range(0, 100, 10) for y in range(0, 50, 10)], float)
    ident = np.eye(3)
    right = _Placement(20, ident, np.arange(20), np.arange(20), shapes=30)
    wrong = _Placement(25, ident, np.arange(20, 45), np.arange(25), shapes=6)
    counts: dict = {}
    ok, _ = _decision([wrong, right], cr, (100, 100), counts)
    assert ok and counts["shape_pairs"] == 30 and counts["runner_up_shapes"] == 6
    wrong.shapes = int(30 / MIN_LEAD) + 1
    ok, why = _decision([wrong, right], cr, (100, 100), counts)
    assert not ok and why.startswith("the best placement")


@pytest.mark.slow
def test_right_placement_by_shapes_and_centre_out(tmp_path):
    """Seed 10 (8-bit, 900 × 900 px, relief 3): the right placement is hypothesis 41–60 by
    support, matches 24 footprints by shape against 3 for any other (by centroid 24 against
    9), and its consensus, 6.9 px off after the refit on all pairs, is pulled in to 1.8 px by
    the centre-out refit. Before: no consensus (lead 10 : 10 within 40 tries). Measured:
    0.80 px, verified, 18 roofs, 5.6 s (0.36 px while the relief step dropped the last corner
    of many footprints, docs/decisions.md 2026-11-27)."""
    case = suburban_case(tmp_path, seed=10, bits=8)
    res = georeference(case["image"], case["reference"], objects="buildings")
    assert res.stage == "buildings" and res.verified
    assert res.counts["tries"] > 40 and res.counts["centre_out_refit"]
    assert res.counts["shape_pairs"] >= 20 and res.counts["runner_up_shapes"] <= 6
    assert _corners(res, case) <= 0.9


@pytest.mark.parametrize("mirror", [False, True])
def test_pair_hypotheses_recover_a_known_map(mirror):
    """Every building seen only as one roof half (random size and direction on a 25 m grid,
    a sheared image → map affine, mirrored or not). The pair hypotheses — two neighbouring
    halves against the halves of two neighbouring footprints, a similarity each — include
    the right placement, and the consensus round on them (growth, shape count, decision)
    returns the known affine (36 footprints by shape against 9 for the runner-up)."""
    from scipy.spatial import cKDTree

    from photodem.algorithms.feedback import Feedback
    from photodem.algorithms.georef.buildings import (
        MAX_TRIES,
        MIN_TRIES,
        _consensus,
        _grow,
        _pair_hypotheses,
        _Reference,
        _shapes,
        _sites,
        roof_halves,
    )
    from photodem.algorithms.georef.invariants import object_features
    from photodem.algorithms.georef.objects import IMAGE, PolygonObject, orient_ring

    ref, _, _, truth = _town_on_a_grid(3)
    if mirror:
        truth = truth @ np.diag([1.0, -1.0, 1.0])
    grid = np.array([[1000.0, 2000.0], [1125.0, 2000.0], [1000.0, 2125.0], [1125.0, 2125.0]])
    shift = np.eye(3)  # the town's corners 20 px inside the image
    shift[:2, 2] = apply(np.linalg.inv(truth), grid).min(axis=0) - 20.0
    truth = truth @ shift
    halves, owner = roof_halves(ref)
    inv = np.linalg.inv(truth)
    cands = [PolygonObject(id=k, ring=orient_ring(apply(inv, halves[2 * k].ring)),
                           source=IMAGE) for k in range(len(ref))]
    fr, fi = object_features(ref), object_features(cands)
    shapes = _shapes(fr, object_features(halves), owner)
    cr = np.array([f.centroid for f in fr])
    base_tol = 0.25 * float(np.sqrt(np.median([f.area for f in fr])))
    corners = apply(inv, grid)
    shape = (int(corners[:, 1].max()) + 20, int(corners[:, 0].max()) + 20)
    sites, site_of = _sites(fi, 3.0, [True] * len(fi))
    hyps = _pair_hypotheses(fi, shapes, sites, site_of, cr, base_tol, float(np.prod(shape)))
    # a similarity each (the map is sheared): right once grown
    tree = cKDTree(shapes.centroid)
    grown = [_grow(T0, sites, shapes.centroid, tree, base_tol, xy)[0]
             for _, T0, xy in hyps[:MIN_TRIES]]
    errs = np.array([np.max(np.abs(apply(T, corners) - apply(truth, corners))) for T in grown])
    assert np.sum(errs < 0.01) >= 25  # measured 31 of the first 40 (806 in all)
    counts: dict = {}
    rings = [o.ring for o in ref] + [h.ring for h in halves]
    T, why = _consensus(fi, [True] * len(fi), _Reference(shapes, rings, cr, base_tol), None,
                        shape, counts, MAX_TRIES, Feedback())
    assert T is not None, why
    assert np.max(np.abs(apply(T, corners) - apply(truth, corners))) < 0.01
    assert counts["shape_pairs"] == len(ref) and counts["runner_up_shapes"] <= 12
