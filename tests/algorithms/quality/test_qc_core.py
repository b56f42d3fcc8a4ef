"""The QC panel's core: area statistics, blunder spots, profiles and identify, closed forms."""

from __future__ import annotations

import numpy as np
import pytest
import rasterio
from affine import Affine
from rasterio.features import geometry_mask
from shapely import wkt
from shapely.geometry import LineString, Point, Polygon, box

from photodem.algorithms.errors import InputError
from photodem.algorithms.project.edits import add_features, create_edits, read_layer
from photodem.algorithms.quality.compare import compare_dems
from photodem.algorithms.quality.qc_blunders import (
    find_blunders,
    spot_to_exclusion,
    spot_to_ground_point,
)
from photodem.algorithms.quality.qc_profile import identify, surface_profile, write_profile_csv
from photodem.algorithms.quality.qc_stats import area_statistics, rebin_histogram
from photodem.algorithms.quality.stats import difference_stats

X0, Y0, RES, N = 400000.0, 5600000.0, 0.5, 120
T = Affine(RES, 0, X0, 0, -RES, Y0)
CRS = "EPSG:25832"
KEYS = ("count", "mean", "median", "std", "rms", "nmad", "min", "max", "q68", "q90", "q95",
        "q99", "share_0_25", "share_0_5", "share_1")


def write(path, z, transform=T, nodata=None):
    with rasterio.open(path, "w", driver="GTiff", width=z.shape[1], height=z.shape[0], count=1,
                       dtype="float32", crs=CRS, transform=transform, nodata=nodata) as dst:
        dst.write(z.astype(np.float32), 1)
    return path


@pytest.fixture
def pair(tmp_path):
    """A plane reference and a DEM = reference + noise (seeded)."""
    rows, cols = np.mgrid[0:N, 0:N]
    ref = 100.0 + 0.05 * cols - 0.02 * rows
    rng = np.random.default_rng(7)
    dem = ref + rng.normal(0.0, 0.2, ref.shape)
    return write(tmp_path / "dem.tif", dem), write(tmp_path / "ref.tif", ref), dem - ref


POLY = Polygon([(X0 + 7.3, Y0 - 5.1), (X0 + 40.2, Y0 - 9.8), (X0 + 33.7, Y0 - 44.6),
                (X0 + 12.9, Y0 - 30.0)])


def test_area_stats_equal_full_difference_masked_by_polygon(pair, tmp_path):
    dem, ref, _ = pair
    full = compare_dems(dem, ref, difference_path=tmp_path / "d.tif")
    with rasterio.open(tmp_path / "d.tif") as src:
        d = src.read(1).astype(np.float64)
        inside = geometry_mask([POLY], out_shape=d.shape, transform=src.transform, invert=True)
    expected = difference_stats(d[inside])
    got = compare_dems(dem, ref, area=POLY)["stats"]
    for k in KEYS:
        assert got[k] == pytest.approx(expected[k], abs=1e-6), k
    assert got["count"] == int(inside.sum()) > 100
    assert full["stats"]["count"] == N * N
    # the QC entry point returns the very same numbers (it is the same call) + a histogram
    qc = area_statistics(dem, ref, POLY.wkt)
    assert all(qc["stats"][k] == got[k] for k in KEYS)
    assert sum(qc["histogram"]["counts"]) + qc["histogram"]["under"] + \
        qc["histogram"]["over"] == got["count"]


def test_area_reads_only_its_window(pair):
    dem, ref, _ = pair
    res = compare_dems(dem, ref, area=(X0 + 10, Y0 - 20, X0 + 20, Y0 - 10))
    assert res["area"] == {"row": 20, "col": 20, "height": 20, "width": 20}
    assert res["stats"]["count"] == 400


def test_area_outside_is_an_error(pair):
    dem, ref, _ = pair
    with pytest.raises(InputError, match="outside"):
        compare_dems(dem, ref, area=box(X0 - 100, Y0 - 100, X0 - 50, Y0 - 50))


def test_per_class_with_names_and_slope(pair, tmp_path):
    dem, ref, _ = pair
    cls = np.ones((N, N))
    cls[:, N // 2:] = 2
    write(tmp_path / "cls.tif", cls)
    (tmp_path / "legend.csv").write_text("value,name\n1,meadow\n2,forest\n")
    res = area_statistics(dem, ref, box(X0 + 5, Y0 - 35, X0 + 55, Y0 - 5),
                          classes=tmp_path / "cls.tif", class_legend=tmp_path / "legend.csv")
    assert res["class_names"] == {"1": "meadow", "2": "forest"}
    assert res["per_class"]["1"]["count"] == res["per_class"]["2"]["count"] == 50 * 60
    assert sum(s["count"] for s in res["per_slope"].values()) == res["stats"]["count"]


def test_rebin_histogram_is_exact_on_fine_edges():
    hist = {"edges": np.linspace(-1, 1, 201).tolist(), "counts": [1] * 200}
    edges, counts = rebin_histogram(hist, -0.5, 0.5, bins=10)
    assert edges[0] == -0.5 and edges[-1] == 0.5
    assert counts.tolist() == [10] * 10


def test_blunders_finds_every_planted_spot(tmp_path):
    _, cols = np.mgrid[0:N, 0:N]
    ref = 50.0 + 0.03 * cols
    rng = np.random.default_rng(3)
    dem = ref + rng.normal(0, 0.1, ref.shape).clip(-0.25, 0.25)
    planted = [((10, 10), (4, 5), 3.0), ((60, 80), (3, 3), -2.0), ((100, 30), (1, 2), 5.0)]
    for (r, c), (h, w), dz in planted:
        dem[r:r + h, c:c + w] += dz
    write(tmp_path / "dem.tif", dem)
    write(tmp_path / "ref.tif", ref)
    res = find_blunders(tmp_path / "dem.tif", tmp_path / "ref.tif", k=3.0)
    assert res["total"] == 3
    sizes = [s["cells"] for s in res["spots"]]
    assert sizes == [20, 9, 2]
    for s, ((r, c), (h, w), dz) in zip(res["spots"], planted):
        cx, cy = T * (c + w / 2, r + h / 2)
        assert s["centroid"] == pytest.approx((cx, cy), abs=1e-6)
        assert s["area_m2"] == pytest.approx(h * w * RES * RES)
        assert s["bounds"] == pytest.approx((*(T * (c, r + h)), *(T * (c + w, r))))
        assert abs(s["max_dh"] - dz) < 0.3
        assert wkt.loads(s["outline"]).area == pytest.approx(h * w * RES ** 2)


def test_spot_to_edits(tmp_path):
    edits = create_edits(tmp_path / "edits.gpkg", CRS)
    spot = {"id": 1, "outline": box(X0, Y0 - 2, X0 + 2, Y0).wkt, "centroid": (X0 + 1, Y0 - 1)}
    poly = spot_to_exclusion(edits, spot, "remove", margin=0.5)
    assert poly.is_valid and poly.area == pytest.approx(9.0)
    spot_to_ground_point(edits, spot, 51.5)
    (g, props), = read_layer(edits, "exclusion_areas")
    assert props["action"] == "remove" and g.equals(poly)
    (p, _), = read_layer(edits, "ground_points")
    assert (p.x, p.y, p.z) == (X0 + 1, Y0 - 1, 51.5)
    corner = {"id": 2, "outline": box(0, 0, 1, 1).union(box(1, 1, 2, 2)).wkt, "centroid": (1, 1)}
    assert spot_to_exclusion(edits, corner).geom_type == "Polygon"
    with pytest.raises(InputError):
        spot_to_exclusion(edits, spot, "delete")


def test_profile_equals_surfaces_at_stations(pair, tmp_path):
    dem, ref, _ = pair
    edits = create_edits(tmp_path / "edits.gpkg", CRS)
    add_features(edits, "breaklines", [(LineString([(X0 + 20, Y0 - 1, 90.0),
                                                     (X0 + 20, Y0 - 59, 92.0)]), {})])
    add_features(edits, "check_points", [(Point(X0 + 30, Y0 - 20.5, 101.0), {"id": "cp1"}),
                                         (Point(X0 + 30, Y0 - 40, 101.0), {"id": "far"})])
    line = [(X0 + 5.2, Y0 - 20.1, 100.0), (X0 + 50.7, Y0 - 21.3, 102.0)]
    prof = surface_profile([dem, ref], line, edits=edits, near=1.0)
    from photodem.algorithms.quality.points import sample_dem

    for name, path in zip(prof["names"], (dem, ref)):
        assert np.allclose(prof["heights"][name], sample_dem(path, prof["x"], prof["y"]),
                           atol=1e-6, equal_nan=True)
    assert prof["spacing"] == RES and prof["distance"][-1] == pytest.approx(prof["length"])
    (cross,) = prof["crossings"]
    assert cross["x"] == pytest.approx(X0 + 20)
    assert cross["distance"] == pytest.approx(np.hypot(14.8, 14.8 * 1.2 / 45.5))
    assert cross["z"] == pytest.approx(90.0 + 2.0 * (cross["y"] - (Y0 - 1)) / -58.0)
    assert [c["id"] for c in prof["check_points"]] == ["cp1"]
    assert prof["vertices"]["z"].tolist() == [100.0, 102.0]
    out = write_profile_csv(tmp_path / "p.csv", prof)
    assert out.read_text().splitlines()[0] == "distance,x,y,dem,ref"


def test_profile_limits(pair):
    dem = pair[0]
    with pytest.raises(InputError, match="1 to 5"):
        surface_profile([dem] * 6, [(X0, Y0), (X0 + 1, Y0)])
    with pytest.raises(InputError, match=r"two vertices|zero length"):
        surface_profile([dem], [(X0 + 1, Y0 - 1)])


def test_identify_values_and_differences(pair):
    dem, ref, dz = pair
    x, y = T * (10.5, 20.5)  # a cell centre: bilinear = the cell value
    res = identify([dem, ref], x, y)
    assert res["values"]["ref"] == pytest.approx(100.0 + 0.05 * 10 - 0.02 * 20, abs=1e-4)
    (a, b, d), = res["differences"]
    assert (a, b) == ("dem", "ref") and d == pytest.approx(dz[20, 10], abs=1e-4)
    assert identify([dem], X0 - 10, Y0)["values"]["dem"] is None
