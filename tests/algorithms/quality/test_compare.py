"""The windowed DEM comparison on synthetic GeoTIFFs with known differences."""

from __future__ import annotations

import json

import numpy as np
import pytest
import rasterio
from affine import Affine
from pyproj import Transformer
from rasterio.crs import CRS
from scipy import ndimage

from photodem.algorithms.errors import Cancelled, InputError
from photodem.algorithms.feedback import Feedback
from photodem.algorithms.quality.compare import compare_dems
from photodem.algorithms.quality.stats import difference_stats

X0, Y0, RES = 500000.0, 5400000.0, 1.0
REF_T = Affine(RES, 0, X0, 0, -RES, Y0)
UTM = "EPSG:25832"
KEYS = ("mean", "median", "std", "rms", "nmad", "min", "max", "q68", "q90", "q95", "q99")


def rough_terrain(n, res=2.0, seed=1):
    """Band-limited noise with a median slope of 20° (as in test_coregister)."""
    rng = np.random.default_rng(seed)
    z = ndimage.gaussian_filter(rng.standard_normal((n, n)), 12, mode="wrap")
    return z * np.tan(np.radians(20)) / np.median(np.hypot(*np.gradient(z, res))) + 300.0


def shifted_copy(z, dx, dy, dz, res=2.0):
    """dem(p) = z(p + d) − dz: the DEM that needs (dx, dy, dz) added to match z."""
    coef = ndimage.spline_filter(z, order=3)
    rows, cols = np.mgrid[0 : z.shape[0], 0 : z.shape[1]].astype(float)
    return ndimage.map_coordinates(coef, [rows - dy / res, cols + dx / res], order=3,
                                   prefilter=False, mode="nearest") - dz


def write(path, arr, transform, crs=UTM, nodata=np.nan, dtype="float64"):
    arr = np.asarray(arr)
    profile = {"driver": "GTiff", "width": arr.shape[1], "height": arr.shape[0], "count": 1,
               "dtype": dtype, "transform": transform, "nodata": nodata}
    if crs is not None:
        profile["crs"] = crs
    with rasterio.open(path, "w", **profile) as dst:
        dst.write(arr.astype(dtype), 1)
    return path


def plane(x, y):
    return 200.0 + 0.1 * (x - X0) - 0.05 * (y - Y0)


def centres(transform, h, w):
    rows, cols = np.mgrid[0:h, 0:w] + 0.5
    return transform * (cols, rows)


@pytest.fixture
def ref_plane(tmp_path):
    x, y = centres(REF_T, 120, 160)
    return write(tmp_path / "ref.tif", plane(x, y), REF_T), plane(x, y)


def test_constant_bias_and_blunders_exact(tmp_path, ref_plane):
    ref_path, z = ref_plane
    dem = z + 1.5
    dem[::17, ::23] += 40.0  # planted blunders
    dem[10:20, 10:20] = np.nan
    write(tmp_path / "dem.tif", dem, REF_T)
    out = compare_dems(tmp_path / "dem.tif", ref_path, flying_height=1500.0,
                       difference_path=tmp_path / "dz.tif", window_size=50)
    expected = difference_stats(dem - z, flying_height=1500.0)
    for k in KEYS:
        assert out["stats"][k] == pytest.approx(expected[k], abs=1e-6), k
    assert out["stats"]["median"] == pytest.approx(1.5, abs=1e-9)
    assert out["stats"]["max"] == pytest.approx(41.5, abs=1e-9)
    assert out["stats"]["histogram"] == expected["histogram"]
    assert out["stats"]["permille"]["median"] == pytest.approx(1.0)
    assert out["shift"] is None
    assert out["grid"]["width"] == 160 and out["grid"]["height"] == 120
    assert out["grid"]["resolution"] == [1.0, 1.0]
    # plane slope: atan(|(0.1, -0.05)|) = 6.4° → one slope class (border cells have no slope)
    assert list(out["per_slope"]) == ["5–10°"]
    # the border cells of the reference have no slope (no neighbour outside the raster)
    inner = np.isfinite(dem - z)[1:-1, 1:-1].sum()
    assert out["per_slope"]["5–10°"]["count"] == inner
    with rasterio.open(out["difference"]) as src:
        d = src.read(1)
        assert src.crs == CRS.from_string(UTM) and src.dtypes[0] == "float32"
    np.testing.assert_allclose(d, (dem - z).astype(np.float32), rtol=0, atol=1e-5)
    json.dumps(out, allow_nan=False)


def test_tilted_plane_difference_and_windows_agree(tmp_path, ref_plane):
    ref_path, z = ref_plane
    x, y = centres(REF_T, 120, 160)
    dz = 0.3 + 0.004 * (x - X0) - 0.002 * (Y0 - y)
    write(tmp_path / "dem.tif", z + dz, REF_T)
    a = compare_dems(tmp_path / "dem.tif", ref_path, window_size=37)
    b = compare_dems(tmp_path / "dem.tif", ref_path, window_size=4096)
    expected = difference_stats(dz)
    for k in KEYS:
        assert a["stats"][k] == pytest.approx(expected[k], abs=1e-6), k
        assert b["stats"][k] == pytest.approx(expected[k], abs=1e-6), k
    c = compare_dems(tmp_path / "dem.tif", ref_path, window_size=37, memory_budget=8 * 1000)
    assert c["precision"]["exact"] is False
    for k in ("median", "q68", "q90", "q95", "q99"):
        assert abs(c["stats"][k] - expected[k]) <= 0.00025 + 1e-9


def test_other_crs_grid_and_extent(tmp_path, ref_plane):
    """DEM in EPSG:4326, coarser and offset: bilinear onto the reference grid gives the bias."""
    ref_path, _ = ref_plane
    to_ll = Transformer.from_crs(UTM, "EPSG:4326", always_xy=True)
    to_utm = Transformer.from_crs("EPSG:4326", UTM, always_xy=True)
    lon0, lat1 = to_ll.transform(X0 + 40, Y0 + 20)  # starts inside, ends outside the reference
    lon1, lat0 = to_ll.transform(X0 + 260, Y0 - 90)
    w, h = 150, 80
    t = Affine((lon1 - lon0) / w, 0, lon0, 0, -(lat1 - lat0) / h, lat1)
    lon, lat = centres(t, h, w)
    x, y = to_utm.transform(lon, lat)
    write(tmp_path / "dem_ll.tif", plane(x, y) + 2.0, t, crs="EPSG:4326")
    out = compare_dems(tmp_path / "dem_ll.tif", ref_path)
    assert out["stats"]["mean"] == pytest.approx(2.0, abs=0.01)
    assert out["stats"]["nmad"] < 0.01
    assert out["grid"]["crs"] == UTM
    assert out["grid"]["width"] < 160 and out["grid"]["height"] < 120
    # another resolution in the same CRS
    t2 = Affine(2.5, 0, X0 + 30.0, 0, -2.5, Y0 - 10.0)
    x, y = centres(t2, 30, 40)
    write(tmp_path / "dem25.tif", plane(x, y) - 0.75, t2)
    out = compare_dems(tmp_path / "dem25.tif", ref_path)
    assert out["stats"]["mean"] == pytest.approx(-0.75, abs=1e-6)
    assert out["grid"]["transform"][2] == X0 + 30.0 and out["grid"]["width"] == 100


def _square_polys(path, parts, crs="EPSG:4326"):
    tr = Transformer.from_crs(UTM, crs, always_xy=True)
    feats = []
    for name, (x0, x1, y0, y1) in parts.items():
        ring = [tr.transform(px, py) for px, py in
                [(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)]]
        feats.append({"type": "Feature", "properties": {"lc": name, "id": 1},
                      "geometry": {"type": "Polygon", "coordinates": [ring]}})
    path.write_text(json.dumps({"type": "FeatureCollection", "features": feats}))
    return path


def test_per_class_polygons_and_raster(tmp_path, ref_plane):
    ref_path, z = ref_plane
    dem = z.copy()
    dem[:, 80:] += 3.0  # "buildings" on the right half, open terrain on the left
    write(tmp_path / "dem.tif", dem, REF_T)
    polys = _square_polys(tmp_path / "classes.geojson", {
        "open": (X0, X0 + 80, Y0 - 120, Y0), "building": (X0 + 80, X0 + 160, Y0 - 120, Y0)})
    out = compare_dems(tmp_path / "dem.tif", ref_path, classes=polys, class_field="lc",
                       window_size=64)
    pc = out["per_class"]
    assert set(pc) == {"open", "building"}
    assert pc["open"]["count"] == 80 * 120 and pc["building"]["count"] == 80 * 120
    assert pc["open"]["mean"] == pytest.approx(0.0, abs=1e-9)
    assert pc["building"]["mean"] == pytest.approx(3.0, abs=1e-9)
    assert pc["building"]["std"] == pytest.approx(0.0, abs=1e-9)
    # the same as a class raster at half the resolution, 0 = nodata
    cls = np.zeros((60, 80), np.uint8)
    cls[:, :40] = 1
    cls[:, 40:] = 2
    cls[:5, :] = 0
    write(tmp_path / "cls.tif", cls, Affine(2, 0, X0, 0, -2, Y0), nodata=0, dtype="uint8")
    out = compare_dems(tmp_path / "dem.tif", ref_path, classes=tmp_path / "cls.tif")
    pc = out["per_class"]
    assert list(pc) == ["1", "2"]
    assert pc["1"]["count"] == 80 * 110 and pc["2"]["mean"] == pytest.approx(3.0, abs=1e-9)


def test_coregistration_through_files(tmp_path):
    z = rough_terrain(n=300)
    t = Affine(2.0, 0, X0, 0, -2.0, Y0)
    dem = shifted_copy(z, 3.0, -2.0, 0.5)
    write(tmp_path / "ref.tif", z, t)
    write(tmp_path / "dem.tif", dem, t)
    stable = _square_polys(tmp_path / "stable.geojson",
                           {"s": (X0 + 100, X0 + 600, Y0 - 600, Y0 - 50)})
    out = compare_dems(tmp_path / "dem.tif", tmp_path / "ref.tif", coregister=True,
                       stable=stable)
    s = out["shift"]
    assert abs(s["dx"] - 3.0) < 0.1 and abs(s["dy"] + 2.0) < 0.1 and abs(s["dz"] - 0.5) < 0.1
    assert abs(out["stats"]["median"]) < 0.02 and out["stats"]["nmad"] < 0.1
    raw = compare_dems(tmp_path / "dem.tif", tmp_path / "ref.tif")
    assert raw["stats"]["nmad"] > 5 * out["stats"]["nmad"]
    # a stable mask raster works the same way
    mask = np.zeros(z.shape, np.uint8)
    mask[25:300, 50:300] = 1
    write(tmp_path / "mask.tif", mask, t, nodata=None, dtype="uint8")
    out2 = compare_dems(tmp_path / "dem.tif", tmp_path / "ref.tif", coregister=True,
                        stable=tmp_path / "mask.tif")
    assert abs(out2["shift"]["dx"] - 3.0) < 0.1 and abs(out2["shift"]["dy"] + 2.0) < 0.1


def test_operator_errors(tmp_path, ref_plane):
    ref_path, z = ref_plane
    far = Affine(1, 0, X0 + 10_000, 0, -1, Y0)
    write(tmp_path / "far.tif", z, far)
    with pytest.raises(InputError, match="do not overlap"):
        compare_dems(tmp_path / "far.tif", ref_path)
    write(tmp_path / "nocrs.tif", z, REF_T, crs=None)
    with pytest.raises(InputError, match="no coordinate reference system"):
        compare_dems(tmp_path / "nocrs.tif", ref_path)
    with pytest.raises(InputError, match="no coordinate reference system"):
        compare_dems(ref_path, tmp_path / "nocrs.tif")
    write(tmp_path / "empty.tif", np.full(z.shape, -9999.0), REF_T, nodata=-9999.0)
    with pytest.raises(InputError, match=r"^The DEM .* no valid heights"):
        compare_dems(tmp_path / "empty.tif", ref_path)
    with pytest.raises(InputError, match=r"reference DEM .* no valid heights"):
        compare_dems(ref_path, tmp_path / "empty.tif")
    polys = _square_polys(tmp_path / "c.geojson", {"a": (X0, X0 + 10, Y0 - 10, Y0)})
    with pytest.raises(InputError, match=r"no attribute 'landcover'.*fields: lc, id"):
        compare_dems(ref_path, ref_path, classes=polys, class_field="landcover")
    with pytest.raises(InputError, match="class_field"):
        compare_dems(ref_path, ref_path, classes=polys)
    (tmp_path / "junk.tif").write_text("not a raster")
    with pytest.raises(InputError, match="cannot be read"):
        compare_dems(tmp_path / "junk.tif", ref_path)
    with pytest.raises(InputError, match="does not exist"):
        compare_dems(tmp_path / "missing.tif", ref_path)
    with pytest.raises(InputError) as info:
        compare_dems(tmp_path / "far.tif", ref_path)
    assert "\n" not in str(info.value)  # one line


def test_cancel_leaves_no_difference_raster(tmp_path, ref_plane):
    ref_path, z = ref_plane
    write(tmp_path / "dem.tif", z + 1, REF_T)
    fb = Feedback(on_progress=lambda p: fb.cancel() if p > 20 else None)
    out_dir = tmp_path / "out"
    with pytest.raises(Cancelled):
        compare_dems(tmp_path / "dem.tif", ref_path, difference_path=out_dir / "dz.tif",
                     window_size=32, feedback=fb)
    assert not any(out_dir.iterdir())


def _building_scene(tmp_path):
    """A 0.5 m grid: flat DTM, a 40 × 40-cell box 8 m high; the DEM lost the building."""
    t = Affine(0.5, 0, X0, 0, -0.5, Y0)
    dtm = np.full((120, 120), 100.0)
    dsm = dtm.copy()
    dsm[40:80, 40:80] += 8.0
    dem = dtm.copy()
    dem[:, :10] = np.nan  # a strip the DEM does not measure (open terrain)
    classes = np.where(dsm > dtm, 2.0, 1.0)
    return (write(tmp_path / "ref.tif", dsm, t), write(tmp_path / "dtm.tif", dtm, t),
            write(tmp_path / "dem.tif", dem, t), write(tmp_path / "cls.tif", classes, t))


def test_object_classes_and_completeness(tmp_path):
    ref, dtm, dem, cls = _building_scene(tmp_path)
    plain = compare_dems(dem, ref, classes=cls, window_size=16)  # same windows: same sums
    res = compare_dems(dem, ref, classes=cls, dtm=dtm, window_size=16)
    # the existing statistics do not change with the object classes
    for key in ("stats", "per_class", "per_slope"):
        assert json.dumps(res[key], sort_keys=True) == json.dumps(plain[key], sort_keys=True)
    assert "per_object" not in plain and plain["completeness"]["per_object"] is None
    comp = res["completeness"]["per_object"]
    # 1 m inside = 2 cells of 0.5 m: a 36 × 36 interior; the edge is the 4·(40² − 36²) rest
    assert comp["object interior"]["cells"] == 36 * 36
    assert comp["object edge"]["cells"] == 40 * 40 - 36 * 36
    assert comp["object interior"]["measured"] == 1.0
    assert comp["object interior"]["within_1"] == 0.0
    o = comp["open"]
    assert o["measured"] == pytest.approx(o["within_0_5"]) and o["measured"] < 1.0
    assert o["cells"] - round(o["measured"] * o["cells"]) == 120 * 10  # the empty strip
    assert res["per_object"]["object interior"]["median"] == pytest.approx(-8.0)
    by_class = res["completeness"]["per_class"]
    assert by_class["2"]["within_0_5"] == 0.0 and by_class["1"]["within_0_5"] < 1.0
    whole = compare_dems(dem, ref, dtm=dtm)  # one window: the same masks
    assert whole["completeness"]["per_object"] == comp


def test_dem_compare_writes_completeness(tmp_path):
    from photodem.algorithms.processing import registry

    ref, dtm, _dem, _ = _building_scene(tmp_path)
    out = registry.run("dem_compare", {"dem": str(ref), "reference": str(ref), "dtm": str(dtm),
                                       "output": str(tmp_path / "cmp")})
    rows = (tmp_path / "cmp" / "completeness.csv").read_text().splitlines()
    assert rows[0] == "scope,name,cells,measured,within_0_5,within_1"
    assert "object,object interior,1296,1.000000,1.000000,1.000000" in rows
    assert "Completeness" in (tmp_path / "cmp" / "report.html").read_text()
    assert out["completeness"]["per_object"]["open"]["within_0_5"] == 1.0
    plain = registry.run("dem_compare", {"dem": str(ref), "reference": str(ref),
                                         "output": str(tmp_path / "cmp2")})
    assert plain["completeness"] is None and plain["completeness_csv"] is None
    assert not (tmp_path / "cmp2" / "completeness.csv").exists()


def test_object_classes_need_a_projected_reference(tmp_path):
    t = Affine(0.0001, 0, 10.0, 0, -0.0001, 50.0)
    z = np.full((20, 20), 100.0)
    ref = write(tmp_path / "ref.tif", z, t, crs="EPSG:4326")
    dtm = write(tmp_path / "dtm.tif", z, t, crs="EPSG:4326")
    with pytest.raises(InputError, match="projected CRS"):
        compare_dems(ref, ref, dtm=dtm)
