"""Orthorectification against synthetic truth.

Two scenes: the tiny synthetic block (check-point discs on the ground, truth DTM/DSM), and a
"city" rendered here with the block's ray caster: flat ground, three flat-roofed blocks 10–20 m
high with red roofs, one camera 150 m above ground — so that relief displacement, occlusion and
ghosting are large and known in closed form.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

rasterio = pytest.importorskip("rasterio")
pytest.importorskip("cv2")

from photodem.algorithms.errors import Cancelled, InputError  # noqa: E402
from photodem.algorithms.feedback import Feedback  # noqa: E402
from photodem.algorithms.geometry.camera import Camera  # noqa: E402
from photodem.algorithms.geometry.orientation import ExteriorOrientation  # noqa: E402
from photodem.algorithms.geometry.projection import world_to_pixel  # noqa: E402
from photodem.algorithms.ortho.rectify import (  # noqa: E402
    orthorectify_image,
    project_grid,
    surface_heights,
)
from photodem.algorithms.processing import registry  # noqa: E402
from photodem.algorithms.project.model import ImageRecord, Project  # noqa: E402
from photodem.algorithms.quality.targets import target_centroids  # noqa: E402
from photodem.algorithms.raster.io import (  # noqa: E402
    open_image,
    overview_factors,
    write_raster,
)
from photodem.algorithms.raster.sample import bilinear  # noqa: E402
from photodem.algorithms.synthetic.block import generate_block  # noqa: E402
from photodem.algorithms.synthetic.render import Renderer, render_image  # noqa: E402
from photodem.algorithms.synthetic.terrain import Grid  # noqa: E402

CRS = "EPSG:25832"
GROUND = 100.0
#: the city's blocks: xmin, xmax, ymin, ymax (relative to X0, Y0) and height (m)
BLOCKS = [(-40.0, -28.0, 10.0, 25.0, 20.0), (20.0, 34.0, 18.0, 28.0, 15.0),
          (-10.0, 2.0, -40.0, -30.0, 10.0)]
X0, Y0 = 500000.0, 5500000.0


def _read(path):
    with rasterio.open(path) as src:
        return src.read(), src.transform, src.tags()


def _cells(transform, shape):
    h, w = shape
    xs = transform.c + (np.arange(w) + 0.5) * transform.a
    ys = transform.f + (np.arange(h) + 0.5) * transform.e
    return np.meshgrid(xs, ys)


# -- the city ----------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def city(tmp_path_factory) -> dict:
    root = tmp_path_factory.mktemp("city")
    cell = 0.1
    grid = Grid(X0 - 75.0, Y0 + 75.0, cell, 1500, 1500)
    gx, gy = grid.xs + 0 * grid.ys, grid.ys + 0 * grid.xs
    dtm = np.full(grid.shape, GROUND)
    dsm = dtm.copy()
    rng = np.random.default_rng(4)
    # smooth green-grey ground texture, red roofs with a grey parapet ring of one cell
    from scipy.ndimage import gaussian_filter

    tex = gaussian_filter(rng.normal(0.0, 1.0, grid.shape), 4.0)
    tex /= tex.std()
    albedo = np.stack([0.25 + 0.05 * tex, 0.35 + 0.06 * tex, 0.25 + 0.05 * tex])
    for x0, x1, y0, y1, h in BLOCKS:
        inside = (gx > X0 + x0) & (gx < X0 + x1) & (gy > Y0 + y0) & (gy < Y0 + y1)
        dsm[inside] = GROUND + h
        roof = (gx > X0 + x0 + cell) & (gx < X0 + x1 - cell) & (gy > Y0 + y0 + cell) & (
            gy < Y0 + y1 - cell)
        for b, v in enumerate((0.75, 0.1, 0.1)):
            albedo[b][inside] = 0.3
            albedo[b][roof] = v
    camera = Camera("city", 500, 500, 30.0, (0.04, 0.04))  # GSD = 150 · 0.04 / 30 = 0.2 m
    eo = ExteriorOrientation.from_opk([X0 + 3.0, Y0 - 2.0, GROUND + 150.0], 1.0, -0.8, 12.0)
    renderer = Renderer(grid, dsm, albedo.astype(np.float32), np.zeros((0, 3)), 0.5)
    image, misses = render_image(renderer, camera, eo, 2, 1 << 18, np.random.SeedSequence(9),
                                 0.1)
    assert misses == 0
    (root / "images").mkdir()
    write_raster(root / "images" / "c1.tif", image, photometric="RGB")
    project = Project(root=root, name="city", crs=CRS, cameras={"city": camera},
                      images=[ImageRecord("c1", "images/c1.tif", "city", eo)])
    project.save()
    write_raster(root / "dtm.tif", dtm.astype(np.float32), grid.transform, CRS)
    write_raster(root / "dsm.tif", dsm.astype(np.float32), grid.transform, CRS)
    return {"root": root, "project": project, "eo": eo, "camera": camera}


def _footprints(gx, gy):
    mask = np.zeros(gx.shape, dtype=bool)
    for x0, x1, y0, y1, _ in BLOCKS:
        mask |= (gx > X0 + x0) & (gx < X0 + x1) & (gy > Y0 + y0) & (gy < Y0 + y1)
    return mask


def _red(bands):
    r, g, b = (bands[k].astype(float) for k in range(3))
    return (r > 80) & (r > 2.5 * g) & (r > 2.5 * b) & (bands[3] == 255)


def _shadow(gx, gy, centre):
    """Closed form: ground cells whose segment to the centre passes through a block."""
    occ = np.zeros(gx.shape, dtype=bool)
    for x0, x1, y0, y1, h in BLOCKS:
        t_lo = np.zeros(gx.shape)
        t_hi = np.full(gx.shape, h / (centre[2] - GROUND))
        for p, c, lo, hi in ((gx, centre[0], X0 + x0, X0 + x1), (gy, centre[1], Y0 + y0,
                                                                  Y0 + y1)):
            with np.errstate(divide="ignore", invalid="ignore"):
                a, b = (lo - p) / (c - p), (hi - p) / (c - p)
            t_lo = np.maximum(t_lo, np.minimum(a, b))
            t_hi = np.minimum(t_hi, np.maximum(a, b))
        occ |= t_lo < t_hi
    return occ & ~_footprints(gx, gy)


def test_true_ortho_roofs_on_footprints_and_occlusion(city, tmp_path) -> None:
    root = city["root"]
    res = orthorectify_image(root, "c1", root / "dsm.tif", tmp_path / "true.tif",
                             dsm=root / "dsm.tif")
    assert res["gsd"] == pytest.approx(0.2) and res["occluded_pct"] > 1.0
    bands, T, tags = _read(res["ortho"])
    vis = _read(res["visibility"])[0][0]
    assert tags["PHOTODEM_TRUE_ORTHO"] == "1" and tags["PHOTODEM_IMAGE"] == "c1"
    assert float(tags["PHOTODEM_CAMERA_Z"]) == pytest.approx(GROUND + 150.0)
    gx, gy = _cells(T, vis.shape)
    foot = _footprints(gx, gy)
    red = _red(bands)
    iou = (red & foot).sum() / (red | foot).sum()
    assert iou >= 0.9, iou
    # no ghosting: no visible roof colour on the ground beyond one cell from the footprints
    from scipy.ndimage import binary_dilation

    ghosts = red & ~binary_dilation(foot, iterations=1)
    assert ghosts.sum() <= 0.002 * foot.sum(), ghosts.sum()
    # occlusion: the flagged cells are the closed-form shadows of the blocks
    truth = _shadow(gx, gy, city["eo"].position)
    occ = vis == 2
    assert truth.sum() > 3000
    iou_occ = (occ & truth).sum() / (occ | truth).sum()
    assert iou_occ >= 0.9, iou_occ
    assert (bands[3][occ] == 0).all() and (bands[:3, occ] == 0).all()
    assert ((vis == 1) == (bands[3] == 255)).all()
    # both rasters carry overviews for display (the occlusions are worth looking at); the
    # ortho is a Cloud-Optimised GeoTIFF
    for path in (res["ortho"], res["visibility"]):
        with rasterio.open(path) as src:
            assert src.overviews(1) == overview_factors(src.width, src.height) != []
    with rasterio.open(res["ortho"]) as src:
        assert src.tags(ns="IMAGE_STRUCTURE").get("LAYOUT") == "COG"


def test_classical_ortho_shows_building_lean(city, tmp_path) -> None:
    """On the DTM a flat roof at height h is moved radially by ΔR = h·R/H."""
    root = city["root"]
    res = orthorectify_image(root, "c1", root / "dtm.tif", tmp_path / "dtm.tif", gsd=0.2)
    bands, T, tags = _read(res["ortho"])
    # a classical ortho's visibility repeats its alpha band: written without overviews
    with rasterio.open(res["ortho"]) as a, rasterio.open(res["visibility"]) as v:
        assert a.overviews(1) and not v.overviews(1)
    assert tags["PHOTODEM_TRUE_ORTHO"] == "0" and res["occluded_pct"] == 0.0
    gx, gy = _cells(T, bands.shape[1:])
    red = _red(bands)
    C = city["eo"].position
    H = C[2] - GROUND
    from scipy.ndimage import label

    lab, n = label(red)
    assert n >= 3
    for x0, x1, y0, y1, h in BLOCKS:
        cx, cy = X0 + 0.5 * (x0 + x1), Y0 + 0.5 * (y0 + y1)
        # the roof centroid, projected along its ray onto the ground: R = r·H/(H − h)
        scale = H / (H - h)
        px, py = C[0] + (cx - C[0]) * scale, C[1] + (cy - C[1]) * scale
        R = np.hypot(px - C[0], py - C[1])
        blob = lab == lab.ravel()[np.argmin(np.hypot(gx - px, gy - py))]
        mx, my = gx[blob].mean(), gy[blob].mean()
        shift = np.hypot(mx - cx, my - cy)
        assert shift == pytest.approx(h * R / H, rel=0.03, abs=0.1), (h, shift, h * R / H)
        # and radially outwards
        assert (mx - cx) * (cx - C[0]) + (my - cy) * (cy - C[1]) > 0


def test_resampling_and_tiles(city, tmp_path) -> None:
    root = city["root"]
    ref = orthorectify_image(root, "c1", root / "dtm.tif", tmp_path / "a.tif", gsd=0.25,
                             resampling="cubic")
    tiled = orthorectify_image(root, "c1", root / "dtm.tif", tmp_path / "b.tif", gsd=0.25,
                               resampling="cubic", tile=96)
    a, b = _read(ref["ortho"])[0], _read(tiled["ortho"])[0]
    assert a.shape == b.shape and np.array_equal(a[3], b[3])
    assert np.abs(a.astype(int) - b.astype(int)).max() <= 1
    near = orthorectify_image(root, "c1", root / "dtm.tif", tmp_path / "n.tif", gsd=0.25,
                              resampling="nearest")
    with open_image(root / "images" / "c1.tif") as src:
        colours = set(map(tuple, src.read().reshape(3, -1).T))
    n = _read(near["ortho"])[0]
    valid = n[3] == 255
    sample = n[:3, valid].T[::97]
    assert all(tuple(c) in colours for c in sample)
    # an explicit extent gives exactly that grid
    ext = (X0 - 10.0, Y0 - 5.0, X0 + 10.0, Y0 + 5.0)
    part = orthorectify_image(root, "c1", root / "dtm.tif", tmp_path / "p.tif", gsd=0.25,
                              extent=ext)
    assert part["cells"] == [80, 40] and part["valid_pct"] == 100.0


def test_tiles_in_threads_equal_one_thread(city, tmp_path, monkeypatch) -> None:
    """Tiles computed on several cores give the same true ortho as on one, and a cancel
    between tiles stops the workers and leaves nothing behind."""
    import photodem.algorithms.ortho.rectify as rectify

    root = city["root"]
    kw = {"dsm": root / "dsm.tif", "resampling": "cubic", "tile": 96}
    monkeypatch.setattr(rectify.os, "cpu_count", lambda: 4)
    many = orthorectify_image(root, "c1", root / "dsm.tif", tmp_path / "many.tif", **kw)
    monkeypatch.setattr(rectify.os, "cpu_count", lambda: 1)
    one = orthorectify_image(root, "c1", root / "dsm.tif", tmp_path / "one.tif", **kw)
    assert many["occluded_pct"] == one["occluded_pct"] > 0
    assert np.array_equal(_read(many["ortho"])[0], _read(one["ortho"])[0])
    assert np.array_equal(_read(many["visibility"])[0], _read(one["visibility"])[0])

    class CancelLater(Feedback):
        def progress(self, percent: float) -> None:
            if percent > 20:
                self.cancel()
            super().progress(percent)

    monkeypatch.setattr(rectify.os, "cpu_count", lambda: 4)
    out = tmp_path / "cancelled" / "o.tif"
    with pytest.raises(Cancelled):
        orthorectify_image(root, "c1", root / "dsm.tif", out, feedback=CancelLater(), **kw)
    assert not out.parent.exists() or not any(out.parent.iterdir())


def test_grid_helpers_match_the_reference_functions(city) -> None:
    rng = np.random.default_rng(1)
    from affine import Affine

    dem = rng.normal(100.0, 5.0, (40, 50))
    dem[10:13, 20:22] = np.nan
    T = Affine(2.0, 0.0, 1000.0, 0.0, -2.0, 3000.0)
    xs = np.linspace(995.0, 1105.0, 73)
    ys = np.linspace(3005.0, 2915.0, 61)
    got = surface_heights(dem, T, xs, ys)
    ref = bilinear(dem, T, xs[None, :], ys[:, None])
    assert np.array_equal(np.isnan(got), np.isnan(ref))
    assert np.allclose(got, ref, equal_nan=True, rtol=0, atol=1e-9)
    cam = Camera("d", 800, 600, 50.0, (0.01, 0.01), principal_point=(0.1, -0.05), k1=-0.1,
                 k2=0.02, p1=1e-4)
    eo = ExteriorOrientation.from_opk([1050.0, 2960.0, 400.0], 3.0, -2.0, 40.0)
    z = np.full((ys.size, xs.size), 100.0) + 0.01 * xs[None, :]
    col, row = project_grid(cam, eo, xs, ys, z)
    gx, gy = np.meshgrid(xs, ys)
    c2, r2 = world_to_pixel(np.stack([gx, gy, z], axis=-1), cam, eo)
    assert np.allclose(col, c2, atol=1e-9) and np.allclose(row, r2, atol=1e-9)


def test_bad_inputs_fail_with_one_line_and_write_nothing(city, tmp_path) -> None:
    root = city["root"]
    out = tmp_path / "o" / "x.tif"
    with pytest.raises(InputError, match="not in project") as err:
        orthorectify_image(root, "nope", root / "dtm.tif", out)
    assert "\n" not in str(err.value)
    # a DEM far away: the footprint misses it
    with rasterio.open(root / "dtm.tif") as src:
        far = src.read(1)
        T = src.transform
    from affine import Affine

    write_raster(tmp_path / "far.tif", far, Affine(T.a, 0, T.c + 5000.0, 0, T.e, T.f), CRS)
    with pytest.raises(InputError, match="misses the DEM") as err:
        orthorectify_image(root, "c1", tmp_path / "far.tif", out)
    assert "\n" not in str(err.value)
    with pytest.raises(InputError, match="needs a DSM"):
        registry.run("orthorectify", {"project": str(root), "image": "c1",
                                      "dem": str(root / "dtm.tif"), "true_ortho": True,
                                      "output": str(out)})
    with pytest.raises(InputError, match="resampling"):
        orthorectify_image(root, "c1", root / "dtm.tif", out, resampling="lanczos")
    fb = Feedback()
    fb.cancel()
    with pytest.raises(Cancelled):
        orthorectify_image(root, "c1", root / "dtm.tif", out, feedback=fb)
    assert not out.parent.exists() or not any(out.parent.iterdir())


def test_dem_in_another_crs_is_reprojected_with_a_warning(city, tmp_path) -> None:
    from rasterio.warp import calculate_default_transform, reproject

    root = city["root"]
    with rasterio.open(root / "dtm.tif") as src:
        dst_crs = "EPSG:3035"
        T, w, h = calculate_default_transform(src.crs, dst_crs, src.width, src.height,
                                              *src.bounds)
        data = np.full((h, w), np.nan, dtype=np.float32)
        reproject(src.read(1), data, src_transform=src.transform, src_crs=src.crs,
                  dst_transform=T, dst_crs=dst_crs, dst_nodata=np.nan)
    write_raster(tmp_path / "laea.tif", data, T, dst_crs)
    fb = Feedback()
    ext = (X0 - 20.0, Y0 - 20.0, X0 + 20.0, Y0 + 20.0)
    res = orthorectify_image(root, "c1", tmp_path / "laea.tif", tmp_path / "o.tif", gsd=0.25,
                             extent=ext, feedback=fb)
    assert any("reprojected" in w for w in fb.warnings)
    ref = orthorectify_image(root, "c1", root / "dtm.tif", tmp_path / "r.tif", gsd=0.25,
                             extent=ext)
    a, b = _read(res["ortho"])[0], _read(ref["ortho"])[0]
    assert np.array_equal(a, b)  # the DTM is flat: the same heights, the same ortho


def test_dem_in_a_compound_crs_is_read_directly(city, tmp_path) -> None:
    """A DEM in "project CRS + vertical datum" needs no reprojection (no warp, no warning)."""
    import rasterio.crs

    from photodem.algorithms.ortho.rectify import open_surface, same_horizontal_crs

    compound = rasterio.crs.CRS.from_user_input("EPSG:25832+5783")  # ETRS89 / UTM 32N + DHHN2016
    assert same_horizontal_crs(compound, rasterio.crs.CRS.from_user_input(CRS))
    assert not same_horizontal_crs(compound, rasterio.crs.CRS.from_user_input("EPSG:25833"))
    root = city["root"]
    with rasterio.open(root / "dtm.tif") as src:
        data, T = src.read(1), src.transform
    write_raster(tmp_path / "compound.tif", data, T, compound)
    fb = Feedback()
    with open_surface(tmp_path / "compound.tif", CRS, fb) as ds:
        assert type(ds).__name__ != "WarpedVRT"
    assert not fb.warnings
    ext = (X0 - 20.0, Y0 - 20.0, X0 + 20.0, Y0 + 20.0)
    a = orthorectify_image(root, "c1", tmp_path / "compound.tif", tmp_path / "a.tif", gsd=0.25,
                           extent=ext)
    b = orthorectify_image(root, "c1", root / "dtm.tif", tmp_path / "b.tif", gsd=0.25,
                           extent=ext)
    assert np.array_equal(_read(a["ortho"])[0], _read(b["ortho"])[0])


# -- the tiny synthetic block: check-point discs -----------------------------------------------
@pytest.fixture(scope="module")
def block(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("ortho_block") / "block"
    generate_block(out, size="tiny", terrain="gentle", seed=1)
    return out


def test_checkpoint_discs_within_a_third_of_a_cell(block, tmp_path) -> None:
    project = Project.load(block)
    with open(block / "truth" / "checkpoints.csv", newline="") as fh:
        pts = np.array([[float(r["x"]), float(r["y"])] for r in csv.DictReader(fh)])
    radius_m = project.presets["synthetic"]["disc_radius_m"]
    errors = []
    for rec in project.images:
        res = orthorectify_image(project, rec.name, block / "truth" / "dtm.tif",
                                 tmp_path / f"{rec.name}.tif", resampling="bilinear")
        bands, T, _ = _read(res["ortho"])
        gsd = res["gsd"]
        grey = np.where(bands[3] == 255, bands[:3].astype(float).mean(axis=0), np.nan)
        col = (pts[:, 0] - T.c) / gsd - 0.5
        row = (T.f - pts[:, 1]) / gsd - 0.5
        c, r, ok = target_centroids(grey, col, row, radius_m / gsd + 1.0, min_contrast=30.0)
        errors.append(np.hypot(c - col, r - row)[ok])
    err = np.concatenate(errors)
    assert err.size >= 10, err.size
    rmse = float(np.sqrt(np.mean(err ** 2)))
    assert rmse < 0.3, (rmse, err)
