"""Synthetic block generator: determinism, geometric exactness of the rendering, truth."""

from __future__ import annotations

import csv
import warnings
from pathlib import Path

import numpy as np
import pytest

rasterio = pytest.importorskip("rasterio")
fiona = pytest.importorskip("fiona")

from photodem.algorithms.errors import Cancelled  # noqa: E402
from photodem.algorithms.feedback import Feedback  # noqa: E402
from photodem.algorithms.geometry.projection import world_to_pixel  # noqa: E402
from photodem.algorithms.processing import registry  # noqa: E402
from photodem.algorithms.project.model import Project  # noqa: E402
from photodem.algorithms.synthetic.block import build_scene, generate_block  # noqa: E402
from photodem.algorithms.synthetic.objects import (  # noqa: E402
    BUILDING,
    EMBANKMENT,
    FIELD,
    OPEN,
    ROAD,
    WATER,
)
from photodem.algorithms.synthetic.texture import PAD_FACTOR  # noqa: E402


def _read(path: Path) -> np.ndarray:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # images are not georeferenced on purpose
        with rasterio.open(path) as src:
            return src.read()


@pytest.fixture(scope="module")
def block(tmp_path_factory) -> Path:
    """A tiny gentle block, seed 1, made through the registry (as every face does)."""
    out = tmp_path_factory.mktemp("syn") / "block"
    result = registry.run("synthetic_block", {"output": str(out), "size": "tiny",
                                              "terrain": "gentle", "seed": 1,
                                              "texture_direction": 30})
    for key in ("project", "truth_dtm", "truth_dsm", "truth_landcover", "truth_buildings",
                "truth_breaklines", "truth_checkpoints"):
        assert Path(result[key]).exists(), key
    assert result["images"] == 6 and result["models"] == 4
    assert 0.25 < result["gsd_m"] < 0.35 and result["flying_height_m"] > 50
    return out


def test_registry_outputs_and_project(block: Path) -> None:
    project = Project.load(block)
    assert project.crs == "EPSG:25832"
    assert len(project.images) == 6
    assert (block / "edits.gpkg").is_file()
    try:
        from photodem.algorithms.project.validate import validate_project
    except ImportError:  # pragma: no cover - validation not yet available
        pass
    else:
        report = validate_project(project, check_files=True)
        assert not report.errors and not report.warnings, (report.errors, report.warnings)
    names = {m.name for m in project.models}
    assert names == {"0101_0102", "0102_0103", "0201_0202", "0202_0203"}
    for m in project.models:
        assert m.kind == "in-strip"
        assert 0.3 < m.b_h < 0.45 and 0.5 < m.overlap < 0.7
        assert 0.25 < m.gsd < 0.35 and 60 < m.height_above_ground < 90
    for rec in project.images:
        img = _read(project.image_path(rec))
        cam = project.camera_of(rec)
        assert img.shape == (3, cam.height, cam.width) and img.dtype == np.uint8
        assert 30 < img.mean() < 200 and img.std() > 10
        # base along camera x: the flight direction is ±X, kappa 0 or 180 degrees
        kappa = rec.eo.opk()[2]
        assert min(abs(kappa), abs(abs(kappa) - 180.0)) < 3.0


@pytest.mark.slow
def test_determinism(block: Path, tmp_path: Path) -> None:
    again = generate_block(tmp_path / "again", size="tiny", terrain="gentle", seed=1,
                           texture_direction=30)
    for sub in ("images/0101.tif", "images/0203.tif", "truth/dtm.tif", "truth/dsm.tif",
                "truth/landcover.tif"):
        a, b = _read(block / sub), _read(again.project / sub)
        assert np.array_equal(a, b, equal_nan=a.dtype.kind == "f"), sub
    assert (block / "project.toml").read_text() == (again.project / "project.toml").read_text()
    assert (block / "truth/checkpoints.csv").read_text() == \
        (again.project / "truth/checkpoints.csv").read_text()
    other = build_scene("tiny", "gentle", seed=2)
    assert other.dtm.shape != _read(block / "truth/dtm.tif")[0].shape or not np.allclose(
        other.dtm, _read(block / "truth/dtm.tif")[0])


def test_truth_surfaces_and_landcover(block: Path) -> None:
    from rasterio.features import rasterize
    from shapely.geometry import shape

    dtm = _read(block / "truth/dtm.tif")[0].astype(float)
    dsm = _read(block / "truth/dsm.tif")[0].astype(float)
    lc = _read(block / "truth/landcover.tif")[0]
    with rasterio.open(block / "truth/dtm.tif") as src:
        transform, crs = src.transform, src.crs
    assert crs.to_epsg() == 25832
    assert np.isfinite(dtm).all() and np.isfinite(dsm).all()
    assert (dsm >= dtm - 1e-4).all()
    ground = np.isin(lc, [OPEN, ROAD, WATER, EMBANKMENT, FIELD])
    assert np.array_equal(dsm[ground], dtm[ground])
    assert set(np.unique(lc)) <= {1, 2, 3, 4, 5, 6, 7}
    assert {2, 3, 4, 5, 6} <= set(np.unique(lc))

    with fiona.open(block / "truth/buildings.gpkg") as src:
        buildings = [(shape(f["geometry"]), dict(f["properties"])) for f in src]
    assert len(buildings) >= 4
    assert {p["roof"] for _, p in buildings} == {"flat", "gabled"}
    # every block mixes the plain roof looks with textured ones
    styles = {p["style"] for _, p in buildings}
    assert {"stripes", "plain"} & styles and {"tiles", "two_tone", "gravel", "fixtures"} & styles
    with fiona.open(block / "truth/chimneys.gpkg") as src:
        chimneys = [(shape(f["geometry"]), dict(f["properties"])) for f in src]
    assert len(chimneys) == sum(p["chimneys"] for _, p in buildings) > 0
    fixture = np.zeros(lc.shape, dtype=bool)
    for poly, p in chimneys:
        # the chimney's flat top is burned into the truth DSM exactly (cells wholly inside)
        core = rasterize([(poly.buffer(-transform.a), 1)], out_shape=lc.shape,
                         transform=transform, fill=0, dtype="uint8").astype(bool)
        assert core.any() and np.allclose(dsm[core], p["top_z"], atol=1e-3)
        fixture |= rasterize([(poly.buffer(transform.a), 1)], out_shape=lc.shape,
                             transform=transform, fill=0, dtype="uint8").astype(bool)
    inside_any = np.zeros(lc.shape, dtype=bool)
    cell = transform.a
    for poly, p in buildings:
        mask = rasterize([(poly, 1)], out_shape=lc.shape, transform=transform, fill=0,
                         dtype="uint8").astype(bool)
        inside_any |= mask
        mask &= ~fixture  # DSM − DTM is the roof height outside the chimneys
        h = (dsm - dtm)[mask]
        assert np.allclose(dtm[mask], p["base_z"], atol=1e-3)
        if p["roof"] == "flat":
            assert np.allclose(h, p["height"], atol=1e-3)
        else:
            slope = (p["ridge_height"] - p["height"]) / (p["width"] / 2.0)
            assert h.min() >= p["height"] - 1e-3 and h.min() <= p["height"] + slope * cell
            assert h.max() <= p["ridge_height"] + 1e-3
            assert h.max() >= p["ridge_height"] - slope * cell
    # land cover 3 exactly on the footprints (ties on the boundary aside)
    agree = (lc == BUILDING) == inside_any
    assert agree.mean() > 0.9995
    assert (lc[inside_any] == BUILDING).mean() > 0.995

    with fiona.open(block / "truth/breaklines.gpkg") as src:
        kinds = [f["properties"]["kind"] for f in src]
        coords = [np.asarray(f["geometry"]["coordinates"]) for f in src]
    assert {"embankment_crest", "embankment_toe", "ditch_edge"} <= set(kinds)
    assert all(c.shape[1] == 3 and len(c) >= 2 for c in coords)
    crest = np.concatenate([c for k, c in zip(kinds, coords) if k == "embankment_crest"])
    toe = np.concatenate([c for k, c in zip(kinds, coords) if k == "embankment_toe"])
    assert 4.0 < crest[:, 2].mean() - toe[:, 2].mean() < 9.0


def _centroid(grey: np.ndarray, col: float, row: float, r_px: float) -> tuple:
    """Intensity-weighted centroid of the bright disc after subtracting the pad background."""
    h, w = grey.shape
    rr, cc = np.mgrid[0:h, 0:w]
    c, r = col, row
    for _ in range(3):  # re-centre on the blob itself, not on the prediction
        d = np.hypot(cc - c, rr - r)
        ring = (d >= r_px + 1.2) & (d <= PAD_FACTOR * r_px - 1.2)
        background = np.median(grey[ring])
        core = d <= r_px + 1.5
        wgt = np.clip(grey[core] - background, 0.0, None)
        c = float((wgt * cc[core]).sum() / wgt.sum())
        r = float((wgt * rr[core]).sum() / wgt.sum())
    return c, r


def test_checkpoint_discs_are_geometrically_exact(block: Path) -> None:
    from photodem.algorithms.geometry.dem_intersection import intersect_rays_dem
    from photodem.algorithms.raster.sample import DemSampler

    project = Project.load(block)
    with rasterio.open(block / "truth/dsm.tif") as src:
        dsm = DemSampler(src.read(1), src.transform)
    with open(block / "truth/checkpoints.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    with fiona.open(block / "truth/checkpoints.gpkg") as src:
        gpkg = {f["properties"]["id"]: f["geometry"]["coordinates"] for f in src}
    points = np.array([[float(r["x"]), float(r["y"]), float(r["z"])] for r in rows])
    assert len(points) >= 6
    assert np.allclose(points, [gpkg[r["id"]] for r in rows], atol=1e-3)
    disc_r = float(project.presets["synthetic"]["disc_radius_m"])
    pad_r = PAD_FACTOR * disc_r
    ang = np.linspace(0.0, 2.0 * np.pi, 16, endpoint=False)
    errors = []
    for rec in project.images:
        cam = project.camera_of(rec)
        grey = _read(project.image_path(rec)).astype(float).sum(axis=0)
        col, row = world_to_pixel(points, cam, rec.eo)
        for k, p in enumerate(points):
            dist = float(np.linalg.norm(p - rec.eo.position))
            r_px = disc_r / (dist * cam.pixel_size[0] / cam.focal_length)
            margin = PAD_FACTOR * r_px + 3
            if not (margin <= col[k] <= cam.width - 1 - margin
                    and margin <= row[k] <= cam.height - 1 - margin):
                continue
            # fully visible: the rays to the centre and to the pad rim meet the DSM there
            rim = np.column_stack([p[0] + pad_r * np.cos(ang), p[1] + pad_r * np.sin(ang)])
            rim = np.column_stack([rim, dsm.height(rim[:, 0], rim[:, 1])])
            targets = np.vstack([p, rim])
            hits = intersect_rays_dem(rec.eo.position, targets - rec.eo.position, dsm)
            if not np.all(np.linalg.norm(hits - targets, axis=1) < 0.02):
                continue
            c, r = _centroid(grey, col[k], row[k], r_px)
            errors.append(np.hypot(c - col[k], r - row[k]))
    errors = np.array(errors)
    assert errors.size >= 2 * len(points), errors.size
    rms = float(np.sqrt(np.mean(errors ** 2)))
    print(f"disc centroids: n={errors.size} max={errors.max():.4f} px rms={rms:.4f} px")
    assert errors.max() < 0.1, (errors.max(), np.sqrt(np.mean(errors ** 2)))


def test_cancel_leaves_no_output(tmp_path: Path) -> None:
    out = tmp_path / "cancelled"
    fb = Feedback()
    seen = []

    def on_progress(pct: float) -> None:
        seen.append(pct)
        if pct > 25.0:
            fb.cancel()

    fb._on_progress = on_progress
    with pytest.raises(Cancelled):
        generate_block(out, size="tiny", feedback=fb)
    assert not out.exists()
    assert list(tmp_path.iterdir()) == []
    assert seen and max(seen) < 40.0


def test_terrain_types() -> None:
    steep = build_scene("tiny", "steep", seed=3)
    slope = np.degrees(np.arctan(np.hypot(*np.gradient(steep.dtm, steep.grid.cell))))
    assert np.ptp(steep.dtm) > 100.0
    assert (slope > 45.0).mean() > 0.01
    dunes = build_scene("tiny", "dunes", seed=3)
    assert 2.0 < np.ptp(dunes.dtm) < 30.0
    with pytest.raises(Exception, match="Unknown terrain"):
        build_scene("tiny", "alps", seed=3)
