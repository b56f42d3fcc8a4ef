"""Seamlines: nadir partition, least-cost routing around objects, operator regions, polygons."""

from __future__ import annotations

import numpy as np
import pytest
from affine import Affine
from shapely.geometry import LineString, box

from photodem.algorithms.ortho.seamlines import (
    SeamImage,
    adjacent_pairs,
    boundary_cells,
    cut_regions,
    fill_invalid,
    nadir_labels,
    partition_polygons,
    rasterize_regions,
    route_seams,
    seam_lines,
)

TR = Affine(1.0, 0, 0.0, 0, -1.0, 100.0)  # 1 m cells, 100 × 160


def _images(occluded=None):
    rng = np.random.default_rng(2)
    grey = rng.random((100, 160)).astype(np.float32)
    a = SeamImage("A", (30.0, 50.0), 0, 0, np.ones((100, 110), np.float32), grey[:, :110])
    fb = np.ones((100, 110), np.float32)
    b = SeamImage("B", (130.0, 50.0), 0, 50, fb, grey[:, 50:])
    if occluded is not None:
        a.cover = a.frac.copy()
        a.frac = a.frac.copy()
        a.frac[occluded] = 0.0
    return [a, b]


def test_nadir_partition_is_the_voronoi_bisector() -> None:
    labels = nadir_labels((100, 160), TR, _images())
    assert (labels[:, :80] == 0).all() and (labels[:, 80:] == 1).all()
    assert adjacent_pairs(labels) == [(0, 1)]
    assert boundary_cells(labels).sum() == 200


def test_routing_goes_around_an_object() -> None:
    images = _images()
    labels = nadir_labels((100, 160), TR, images)
    hag = np.zeros((100, 160), np.float32)
    hag[30:60, 70:95] = 12.0  # a building across the bisector
    routed, stats = route_seams(labels, images, hag, corridor=25, min_height=2.0, margin=1)
    assert stats["seam_cells_on_objects_before"] > 0
    assert stats["seam_cells_on_objects_after"] == 0 and stats["routed"] == 1
    assert len(np.unique(routed[30:60, 70:95])) == 1  # the roof from one image
    # far from the corridor nothing changes; every cell still has a valid image
    assert (routed[:, :50] == 0).all() and (routed[:, 110:] == 1).all()
    # only two regions, each connected
    from scipy import ndimage

    assert ndimage.label(routed == 0)[1] == 1 and ndimage.label(routed == 1)[1] == 1


def test_occluded_cells_go_to_the_next_image() -> None:
    occ = (slice(40, 50), slice(60, 70))
    images = _images(occluded=occ)
    geo = nadir_labels((100, 160), TR, images, geometric=True)
    valid = nadir_labels((100, 160), TR, images)
    assert (geo[occ] == 0).all() and (valid[occ] == 1).all()
    filled = fill_invalid(geo, images, valid)
    assert (filled[occ] == 1).all() and (filled[:, :60] == 0).all()


def test_operator_lines_cut_regions_and_polygons() -> None:
    labels = nadir_labels((100, 160), TR, _images())
    regions = cut_regions([LineString([(60, -5), (60, 105)])], (0, 0, 160, 100), labels, TR, 2)
    assert sorted(k for _, k in regions) == [0, 1]
    lab = rasterize_regions(regions, (100, 160), TR)
    assert (lab[:, :60] == 0).all() and (lab[:, 60:] == 1).all()
    polys = partition_polygons(lab, TR, 2)
    assert polys[0].equals(box(0, 0, 60, 100)) and polys[1].equals(box(60, 0, 160, 100))
    (i, j, line), = seam_lines(polys)
    assert (i, j) == (0, 1) and line.length == 100.0


def test_split_objects_go_whole_to_one_image() -> None:
    from photodem.algorithms.ortho.seamlines import keep_objects_whole

    images = _images()
    labels = nadir_labels((100, 160), TR, images)
    objects = np.zeros((100, 160), bool)
    objects[30:60, 72:95] = True  # straddles the bisector x = 80, mostly in B
    objects[5:10, 10:20] = True  # inside A only: untouched
    out, stats = keep_objects_whole(labels, images, objects)
    assert stats == {"objects": 2, "objects_moved": 1, "objects_not_covered": 0}
    assert (out[30:60, 72:95] == 1).all()  # the image holding most of it
    assert (out[5:10, 10:20] == 0).all()
    assert (out[~objects] == labels[~objects]).all()
    # the seam runs along the object's outline: its inner cells touch one image only
    from scipy import ndimage

    assert not (boundary_cells(out) & ndimage.binary_erosion(objects)).any()


@pytest.mark.slow
def test_auto_seamlines_cross_no_building_of_a_true_ortho_mosaic(tmp_path) -> None:
    """Acceptance (issue 6): automatic seamlines (vector output) cross no truth building
    footprint of a synthetic block (true-ortho mosaic with DSM and DTM); trees are avoided
    where possible."""
    fiona = pytest.importorskip("fiona")
    pytest.importorskip("cv2")
    from shapely.geometry import shape
    from shapely.ops import unary_union

    from photodem.algorithms.ortho.mosaic import mosaic_project
    from photodem.algorithms.synthetic.block import generate_block

    block = tmp_path / "block"
    generate_block(block, size="tiny", terrain="gentle", seed=1)
    truth = block / "truth"
    with fiona.open(truth / "buildings.gpkg") as src:
        buildings = [shape(f["geometry"]) for f in src]
    crossed = {}
    for mode in ("nadir", "auto"):
        res = mosaic_project(block, truth / "dsm.tif", tmp_path / mode / "m.tif",
                             dsm=truth / "dsm.tif", true_ortho=True, dtm=truth / "dtm.tif",
                             seamlines=mode)
        with fiona.open(res["seamlines"], layer="seamlines") as src:
            seams = unary_union([shape(f["geometry"]) for f in src])
        assert seams.length > 0
        crossed[mode] = sum(seams.intersection(b).length > 0 for b in buildings)
        if mode == "auto":
            stats = res["seams"]
    assert crossed["nadir"] > 0  # the test scene has buildings on the nadir seams
    assert crossed["auto"] == 0
    assert stats["seam_cells_on_objects_after"] == 0
