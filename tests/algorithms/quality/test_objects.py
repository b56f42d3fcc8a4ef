"""Object metrics on small synthetic arrays with closed-form answers."""

from __future__ import annotations

import numpy as np
import pytest

from photodem.algorithms.quality.objects import (
    CompletenessAccumulator,
    completeness,
    mask_margin,
    object_classes,
    object_masks,
    outline_metrics,
    wall_distances,
)

CELL = 0.1


def scene(n=120, size=40, top=30, height=8.0):
    """Flat terrain at 100 m with one box building of ``size``² cells at (top, top)."""
    dtm = np.full((n, n), 100.0)
    dsm = dtm.copy()
    dsm[top:top + size, top:top + size] += height
    labels = np.zeros((n, n), int)
    labels[top:top + size, top:top + size] = 1
    return dsm, dtm, labels


def test_masks_of_a_box_building():
    dsm, dtm, _ = scene()
    m = object_masks(dsm, dtm, CELL)
    assert m.objects.sum() == 40 * 40
    # 1 m inside = 10 cells from each wall: a 20 × 20 interior
    assert m.interior.sum() == 20 * 20
    assert m.interior[40:60, 40:60].all()
    # open: ≥ 1 m from the box: everything outside the box grown by 10 cells (Euclidean corners)
    assert m.open[:20].all() and m.open[80:].all() and not m.open[25:75, 25:75].any()
    assert not (m.open & m.objects).any()


def test_low_objects_are_neither_object_nor_open():
    dsm, dtm, _ = scene(height=1.0)
    m = object_masks(dsm, dtm, CELL)
    assert not m.objects.any() and not m.interior.any()
    assert not m.open[30:70, 30:70].any()  # 1 m above ground: not open either
    classes = object_classes(m)
    assert set(np.unique(classes)) == {3.0, 4.0}


def test_window_with_margin_equals_whole_grid():
    dsm, dtm, _ = scene()
    whole = object_masks(dsm, dtm, CELL)
    k = mask_margin(CELL)
    r0, r1, c0, c1 = 35, 65, 0, 50
    part = object_masks(dsm[r0 - k:r1 + k, max(c0 - k, 0):c1 + k],
                        dtm[r0 - k:r1 + k, max(c0 - k, 0):c1 + k], CELL)
    inner = (slice(k, k + r1 - r0), slice(c0 - max(c0 - k, 0), c0 - max(c0 - k, 0) + c1 - c0))
    assert np.array_equal(part.interior[inner], whole.interior[r0:r1, c0:c1])
    assert np.array_equal(part.open[inner], whole.open[r0:r1, c0:c1])


def test_completeness_counts_empty_cells_as_misses():
    dsm_true, dtm, _ = scene()
    m = object_masks(dsm_true, dtm, CELL)
    dsm = dsm_true.copy()
    # interior rows 40…59: 5 rows at +0.3 m, 5 rows at +0.8 m, 5 rows empty, 5 rows right
    dsm[40:45, 40:60] += 0.3
    dsm[45:50, 40:60] += 0.8
    dsm[50:55, 40:60] = np.nan
    r = completeness(dsm, dsm_true, {"interior": m.interior, "open": m.open})
    assert r["interior"]["cells"] == 400
    assert r["interior"]["measured"] == pytest.approx(0.75)
    assert r["interior"]["within_0_5"] == pytest.approx(0.5)
    assert r["interior"]["within_1"] == pytest.approx(0.75)
    assert r["open"]["within_0_5"] == 1.0


def test_completeness_of_a_dtm_is_zero_on_objects():
    dsm_true, dtm, _ = scene()
    m = object_masks(dsm_true, dtm, CELL)
    r = completeness(dtm, dsm_true, {"interior": m.interior, "objects": m.objects,
                                     "open": m.open})
    assert r["interior"]["within_1"] == 0.0 and r["objects"]["within_0_5"] == 0.0
    assert r["interior"]["measured"] == 1.0 and r["open"]["within_0_5"] == 1.0


def test_completeness_by_labels_with_names():
    acc = CompletenessAccumulator()
    dz = np.array([0.1, 0.6, np.nan, 2.0])
    acc.add_labels(dz, np.array([1.0, 1.0, 2.0, np.nan]), {1: "a"})
    r = acc.result()
    assert r["a"] == {"cells": 2, "measured": 1.0, "within_0_5": 0.5, "within_1": 1.0}
    assert r["2"]["measured"] == 0.0 and "nan" not in r


def test_wall_distance_of_a_grown_square():
    true = np.zeros((80, 80), bool)
    true[20:60, 20:60] = True
    found = np.zeros_like(true)
    found[18:62, 18:62] = True
    d = wall_distances(found, true)
    assert np.median(d) == pytest.approx(2.0)


def test_outlines_exact_grown_and_missing():
    dsm_true, dtm, labels = scene()
    r = outline_metrics(dsm_true, dtm, dsm_true, labels, CELL, gsd=0.2)
    assert r["count"] == 1 and r["iou_pooled"] == 1.0 and r["wall_median_m"] == 0.0
    grown = dtm.copy()
    grown[28:72, 28:72] += 8.0  # 2 cells (0.2 m = 1 GSD) too wide on every side
    r = outline_metrics(grown, dtm, dsm_true, labels, CELL, gsd=0.2)
    assert r["iou_pooled"] == pytest.approx(1600 / 44 ** 2)
    assert r["wall_median_m"] == pytest.approx(0.2)
    assert r["wall_median_gsd"] == pytest.approx(1.0)
    low = dtm.copy()
    low[30:70, 30:70] += 3.0  # below half the building height: not found
    r = outline_metrics(low, dtm, dsm_true, labels, CELL)
    assert r["iou_pooled"] == 0.0 and r["buildings"][0]["wall_median_m"] is None


def test_outline_ignores_detached_trees_and_neighbours():
    dsm_true, dtm, labels = scene()
    dsm = dsm_true.copy()
    dsm[5:15, 5:15] += 10.0  # a tree well away from the building
    labels2 = labels.copy()
    labels2[30:70, 72:90] = 2  # a second building touching the first (only 2 cells gap)
    dsm_true2 = dsm_true.copy()
    dsm_true2[30:70, 72:90] += 8.0
    dsm[30:70, 70:90] += 8.0  # the DSM bridges the gap
    r = outline_metrics(dsm, dtm, dsm_true2, labels2, CELL)
    b1 = r["buildings"][0]
    assert b1["found_cells"] == 1600 + 2 * 40  # the bridged gap, but not the neighbour
    assert r["count"] == 2


def _files(tmp_path):
    """Truth DSM/DTM (0.1 m grid) with the box building, its footprint, and DSMs on 0.2 m."""
    import fiona
    import rasterio
    from affine import Affine
    from shapely.geometry import box, mapping

    dsm, dtm, _ = scene()
    x0, y0 = 500000.0, 5400000.0
    t = Affine(CELL, 0, x0, 0, -CELL, y0)

    def write(name, arr, transform):
        prof = {"driver": "GTiff", "width": arr.shape[1], "height": arr.shape[0], "count": 1,
                "dtype": "float64", "transform": transform, "crs": "EPSG:25832",
                "nodata": np.nan}
        with rasterio.open(tmp_path / name, "w", **prof) as dst:
            dst.write(arr, 1)
        return tmp_path / name

    fp = box(x0 + 3.0, y0 - 7.0, x0 + 7.0, y0 - 3.0)  # cells 30…69 of the 0.1 m grid
    schema = {"geometry": "Polygon", "properties": {"id": "int"}}
    with fiona.open(tmp_path / "b.gpkg", "w", driver="GPKG", schema=schema,
                    crs="EPSG:25832") as dst:
        dst.write({"geometry": mapping(fp), "properties": {"id": 1}})
    coarse = Affine(2 * CELL, 0, x0, 0, -2 * CELL, y0)
    good = dsm[::2, ::2] + 0.0  # the DSM on a 0.2 m grid (cell corners aligned)
    lost = dtm[::2, ::2].copy()
    lost[:, :5] = np.nan
    return (write("t_dsm.tif", dsm, t), write("t_dtm.tif", dtm, t), tmp_path / "b.gpkg",
            write("good.tif", good, coarse), write("lost.tif", lost, coarse))


def test_object_metrics_of_files(tmp_path):
    from shapely.geometry import box

    from photodem.algorithms.quality.objects_run import object_metrics

    t_dsm, t_dtm, b, good, lost = _files(tmp_path)
    r = object_metrics(good, t_dsm, t_dtm, buildings=b, gsd=0.2, window_size=16)
    c = r["completeness"]
    assert c["interior"]["cells"] == 400
    # bilinear 0.2 m → 0.1 m: the interior (1 m from the walls) is exact
    assert c["interior"]["within_0_5"] == 1.0 and c["open"]["within_0_5"] == 1.0
    o = r["outlines"]
    assert o["count"] == 1 and o["iou_pooled"] > 0.9 and o["wall_median_gsd"] <= 1.0
    r = object_metrics(lost, t_dsm, t_dtm, buildings=b, window_size=16)
    assert r["completeness"]["interior"]["within_1"] == 0.0
    assert r["outlines"]["iou_pooled"] == 0.0
    assert r["completeness"]["open"]["measured"] < 1.0  # the empty strip is a miss
    whole = object_metrics(lost, t_dsm, t_dtm, window_size=4096)
    assert whole["completeness"] == r["completeness"] and whole["outlines"] is None
    # an area that leaves the building out: no outline, no interior
    area = box(500000.0 + 8.0, 5400000.0 - 12.0, 500000.0 + 12.0, 5400000.0 - 8.0)
    r = object_metrics(good, t_dsm, t_dtm, buildings=b, area=area)
    assert r["outlines"]["count"] == 0 and r["completeness"]["interior"]["cells"] == 0


def test_object_metrics_split_the_interior_by_land_cover(tmp_path):
    """A land cover that calls the left part of the building a crown: the DSM that lost that
    part keeps the building class whole and the crown class none."""
    import rasterio

    from photodem.algorithms.quality.objects_run import object_figures, object_metrics

    t_dsm, t_dtm, _, good, _ = _files(tmp_path)
    with rasterio.open(t_dsm) as src:
        prof, truth = src.profile, src.read(1)
    cover = np.full(truth.shape, 1, np.uint8)
    cover[30:70, 30:49] = 4  # "crown": the building's left part
    cover[30:70, 49:70] = 3
    prof.update(dtype="uint8", nodata=0)
    with rasterio.open(tmp_path / "cover.tif", "w", **prof) as dst:
        dst.write(cover, 1)
    with rasterio.open(good) as src:
        half, gprof = src.read(1), src.profile
    with rasterio.open(t_dtm) as src:
        # the DSM lost the left part: 0.1 m columns up to 48 (bilinear from 0.2 m cells)
        half[:, :24] = src.read(1)[::2, ::2][:, :24]
    with rasterio.open(tmp_path / "half.tif", "w", **gprof) as dst:
        dst.write(half, 1)
    classes = {"buildings": [3], "crowns": [4]}
    r = object_metrics(tmp_path / "half.tif", t_dsm, t_dtm, cover=tmp_path / "cover.tif",
                       cover_classes=classes, window_size=16)
    c = r["completeness"]
    assert c["interior_buildings"]["cells"] + c["interior_crowns"]["cells"] == 400
    f = object_figures(r)
    assert f["interior_buildings_0_5_pct"] == 100.0 and f["interior_crowns_0_5_pct"] == 0.0
    assert f["interior_0_5_pct"] == pytest.approx(55.0)  # interior columns 40…59, 49…59 right
    # without a land cover: no split
    assert "interior_crowns_0_5_pct" not in object_figures(
        object_metrics(tmp_path / "half.tif", t_dsm, t_dtm, window_size=16))
