r"""A complete synthetic block: scene, flight plan, rendered images, project and ground truth.

:func:`generate_block` is deterministic: every random number comes from
``numpy.random.SeedSequence(seed)`` (one child stream per part: layout, terrain, objects,
check points, texture, each image), so the same seed gives byte-identical images and truth
rasters. The output folder is written through :func:`..raster.io.staged_folder`: a failure or
cancellation leaves nothing behind.

Output layout::

    <output>/project.toml          cameras, images (PATB ω-φ-κ), in-strip stereo models
                                   (size ``aerial``: one window camera per image, see
                                   :mod:`.flight`; window offsets in the ``synthetic`` preset)
    <output>/edits.gpkg            empty operator edits
    <output>/images/<name>.tif     8-bit RGB, not georeferenced
    <output>/truth/dtm.tif         float32, NaN nodata, project CRS, cell = GSD/2
    <output>/truth/dsm.tif         float32 (DTM + buildings + trees)
    <output>/truth/landcover.tif   uint8, codes in :data:`.objects.LANDCOVER`
    <output>/truth/buildings.gpkg  footprints with roof type and look, heights, platform height
    <output>/truth/chimneys.gpkg   chimney squares with building id and top height
    <output>/truth/breaklines.gpkg 3-D lines with kind (embankment_crest/_toe, ditch_edge/_bottom)
    <output>/truth/checkpoints.gpkg, checkpoints.csv   3-D centres of the bright target discs

Size ``aerial`` (:mod:`.flight`): three wide-angle film frames (11 500 px, c = 153 mm,
B/H = 0.6, B_px = B/GSD = 4600 px) of which only a window over the common ground patch is
rendered; the truth grid (cell GSD/2) covers that patch — the windows on the lowest and the
highest plausible terrain, because the outer windows look 30° off-nadir.

Memory: the truth grid (cell GSD/2) holds a handful of float32/float64 rasters, ≈ 80 bytes
per cell at the peak (measured: 1.0 GB for the 13.7 M cells of ``small``), i.e. ≈ 12 GB for the
≈ 150 M cells of ``large``; images are rendered in row tiles of ``SizeSpec.tile_rays`` rays
(≈ 300 bytes per ray, ≈ 300 MB), traced in cache-sized chunks, so the render memory does not
grow with the image size.
"""

from __future__ import annotations

import csv
import time
import warnings
from collections import OrderedDict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple, Union

import fiona
import numpy as np
import rasterio.crs
from rasterio.errors import NotGeoreferencedWarning
from shapely.geometry import LineString, Point, Polygon, mapping
from shapely.ops import unary_union

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from ..project.edits import create_edits
from ..project.model import ImageRecord, Project, StereoModel
from ..project.stereo_models import detect_stereo_models
from ..quality.class_legend import write_class_style
from ..raster.io import staged_folder, write_raster
from ..raster.sample import DemSampler, bilinear_grid
from .flight import SIZES, STEEP_GSD_FACTOR, FlightPlan, footprint_points, plan_flight
from .objects import (
    LANDCOVER,
    LANDCOVER_COLOURS,
    SceneObjects,
    choose_checkpoints,
    flatten_sites,
    place_objects,
)
from .render import Renderer, render_image
from .terrain import TERRAIN_TYPES, Grid, make_terrain
from .texture import PAD_FACTOR, make_albedo

CRS = "EPSG:25832"
#: lowest terrain to expect below the mean height, per terrain type (m): sizes the grid
_LOW = {"gentle": 15.0, "dunes": 12.0, "steep": 100.0}
#: extent factor of a drone block's object placement (see build_scene)
DRONE_EXTENT_FACTOR = 1.25
_BASE = {"gentle": (40.0, 120.0), "dunes": (5.0, 40.0), "steep": (700.0, 1200.0)}


@dataclass
class Scene:
    """A synthetic scene in memory (truth rasters, objects, flight plan)."""

    grid: Grid
    dtm: np.ndarray
    dsm: np.ndarray
    landcover: np.ndarray
    albedo: np.ndarray
    objects: SceneObjects
    plan: FlightPlan
    checkpoints: np.ndarray  # (N, 3)
    disc_radius: float
    size: str
    terrain: str
    seed: int
    supersample: int
    tile_rays: int
    models: List[StereoModel] = field(default_factory=list)
    image_seeds: Optional[np.random.SeedSequence] = None  # parent of the per-image streams


@dataclass
class BlockResult:
    """Paths and figures of a generated block."""

    project: Path
    truth: Dict[str, Path]
    images: int
    models: int
    gsd: float
    flying_height: float
    seconds: float
    base_px: float = float("nan")  # mean model base / GSD (px): σ_Z/H = σ_px / base_px
    b_h: float = float("nan")  # mean B/H of the models

    def outputs(self) -> Dict[str, Any]:
        """The ``synthetic_block`` outputs."""
        return {
            "project": str(self.project),
            **{f"truth_{k}": str(v) for k, v in self.truth.items()},
            "images": self.images,
            "models": self.models,
            "gsd_m": round(self.gsd, 4),
            "flying_height_m": round(self.flying_height, 2),
            "base_px": round(self.base_px, 1),
            "b_h": round(self.b_h, 4),
        }


def _polygon(points: np.ndarray):
    return Polygon([tuple(p) for p in points]).buffer(0)


def build_scene(size: str = "small", terrain: str = "gentle", seed: int = 1,
                texture_direction: float = 0.0, feedback: Optional[Feedback] = None,
                window: Optional[int] = None) -> Scene:
    """Build the scene and the flight plan (everything but the images) in memory.

    ``window`` (px) overrides the rendered window size of a windowed size (``aerial``), e.g.
    smaller for tests; the flight geometry does not change.

    Raises
    ------
    InputError
        For an unknown size or terrain type, or a window with a non-windowed size.
    """
    if size not in SIZES:
        raise InputError(f"Unknown block size '{size}'; use one of {', '.join(SIZES)}.")
    if terrain not in TERRAIN_TYPES:
        raise InputError(f"Unknown terrain '{terrain}'; use one of {', '.join(TERRAIN_TYPES)}.")
    feedback = ensure_feedback(feedback)
    spec = SIZES[size]
    if window is not None:
        spec = spec.with_window(window)
    # the seventh stream (roof looks, chimneys, crown details) came later: spawning seven
    # children leaves the first six, and so the layout of earlier blocks, unchanged
    streams = np.random.SeedSequence(int(seed)).spawn(7)
    layout, t_rng, o_rng, c_rng, x_rng = (np.random.default_rng(s) for s in streams[:5])
    detail_rng = np.random.default_rng(streams[6])

    gsd = spec.gsd * (STEEP_GSD_FACTOR if terrain == "steep" else 1.0)
    origin = (float(400000 + 100 * layout.integers(0, 1500)),
              float(5500000 + 100 * layout.integers(0, 2500)))
    base = float(np.round(layout.uniform(*_BASE[terrain]), 1))
    plan = plan_flight(spec, size, gsd, origin, base, layout)

    # grid: all footprints on the lowest plausible terrain, plus a margin; windows looking
    # off-nadir also on the highest (terrain is centred on its mean, objects add ≤ 25 m)
    planes = [base - _LOW[terrain]] + ([base + _LOW[terrain] + 25.0] if spec.windowed else [])
    pts = np.concatenate([footprint_points(plan.camera_of(im), im.eo, z)
                          for im in plan.images for z in planes])
    # drone: oblique frames see far (≈ 2 H): a truth cell of one nadir GSD bounds the grid
    cell = gsd if spec.drone else gsd / 2.0
    margin = 0.03 * float(np.ptp(pts[:, 0])) + 20 * cell
    x0 = np.floor((pts[:, 0].min() - margin) / cell) * cell
    y1 = np.ceil((pts[:, 1].max() + margin) / cell) * cell
    ncols = int(np.ceil((pts[:, 0].max() + margin - x0) / cell))
    nrows = int(np.ceil((y1 - pts[:, 1].min() + margin) / cell))
    grid = Grid(float(x0), float(y1), cell, nrows, ncols)
    feedback.info(f"Synthetic {size}/{terrain} block, seed {seed}: {len(plan.images)} images of "
                  f"{spec.width}×{spec.height} px, GSD {gsd:.3f} m, truth grid {ncols}×{nrows} "
                  f"cells of {cell:.3f} m.")
    if spec.windowed:
        feedback.info(f"Windows of {spec.frame}×{spec.frame} px frames (c = {spec.focal_mm} mm): "
                      f"H = {plan.flying_height:.1f} m, B = {plan.base:.1f} m, "
                      f"B/H = {plan.base / plan.flying_height:.3f}, "
                      f"B_px = {plan.base_px:.0f} px.")
    feedback.progress(2.0)

    dtm = make_terrain(terrain, grid, t_rng, base)
    feedback.progress(6.0)
    footprints = [_polygon(footprint_points(plan.camera_of(im), im.eo, base))
                  for im in plan.images]
    covered = unary_union(footprints)
    extent_core = float(np.sqrt(covered.area))
    placement = _drone_patch(footprints) if spec.drone else None
    if placement is not None:
        # the lines (embankment, ditch, road) lie at 0.15–0.28 × extent from the grid centre:
        # a wider extent keeps them at the edge of the drone patch and leaves room for objects
        extent_core *= DRONE_EXTENT_FACTOR
    dtm, dsm, landcover, objects = place_objects(grid, dtm, o_rng, extent_core, detail_rng,
                                                 placement)
    feedback.progress(10.0)

    models = in_strip_models(plan, grid, dtm, all_pairs=spec.drone)
    model_area = unary_union([footprints[_index(plan, m.left)].intersection(
        footprints[_index(plan, m.right)]) for m in models])
    disc_radius = float(np.clip(1.7 * gsd, 0.3, 2.0))
    region = model_area.buffer(-(PAD_FACTOR * disc_radius + 2.0))
    # three per model, at most 18 (the drone block has 15 models on one patch)
    n_check = min(3 * max(len(models), 1), 18)
    checkpoints = choose_checkpoints(grid, dtm, dsm, landcover, region, n_check,
                                     PAD_FACTOR * disc_radius, c_rng)
    checkpoints = flatten_sites(grid, dtm, dsm, checkpoints, PAD_FACTOR * disc_radius + 1.0)
    feedback.progress(12.0)
    albedo = make_albedo(grid, dtm, dsm, landcover, objects, x_rng, terrain, texture_direction,
                         checkpoints, disc_radius)
    feedback.progress(18.0)
    return Scene(grid, dtm, dsm, landcover, albedo, objects, plan, checkpoints, disc_radius,
                 size, terrain, int(seed), spec.supersample, spec.tile_rays, models, streams[5])


def _drone_patch(footprints: List[Polygon]) -> Optional[Tuple[float, float, float, float]]:
    """Bounds of the ground every frame of a drone block sees (buildings and trees go there,
    so every convergent model has objects to match), widened by 15 m; None if there is none."""
    common = footprints[0]
    for fp in footprints[1:]:
        common = common.intersection(fp)
    if common.is_empty or common.area <= 0:
        return None
    return tuple(common.buffer(15.0).bounds)  # type: ignore[return-value]


def _index(plan: FlightPlan, name: str) -> int:
    return [im.name for im in plan.images].index(name)


def in_strip_models(plan: FlightPlan, grid: Grid, dtm: np.ndarray, all_pairs: bool = False,
                    min_overlap: float = 0.25) -> List[StereoModel]:
    """Consecutive in-strip pairs with base, B/H, overlap, GSD and height above ground.

    The terrain height of an image is the mean DTM along its footprint outline (on the mean
    terrain plane) and at its nadir point; the footprint is then taken at that height.
    ``all_pairs`` (drone blocks): every pair whose footprints overlap by ≥ ``min_overlap``
    instead, kind ``in-strip`` or ``cross-strip``.
    """
    fps, heights = [], []
    for im in plan.images:
        cam = plan.camera_of(im)
        pts = footprint_points(cam, im.eo, plan.terrain_height)
        pts = np.vstack([pts, im.eo.position[None, :2]])
        z = bilinear_grid(dtm, *grid.index(pts[:, 0], pts[:, 1]))
        zt = float(np.nanmean(z)) if np.isfinite(z).any() else plan.terrain_height
        heights.append(float(im.eo.position[2]) - zt)
        fps.append(_polygon(footprint_points(cam, im.eo, zt)))
    models: List[StereoModel] = []
    ims = plan.images
    pairs = ([(a, b) for k, a in enumerate(ims) for b in ims[k + 1:]] if all_pairs
             else list(zip(ims[:-1], ims[1:])))
    for a, b in pairs:
        if a.strip != b.strip and not all_pairs:
            continue
        ia, ib = _index(plan, a.name), _index(plan, b.name)
        # left = smaller coordinate along the base direction, i.e. along camera x
        ahead = float((b.eo.position - a.eo.position) @ a.eo.rotation[:, 0]) > 0
        left, right = (a, b) if ahead else (b, a)
        base = float(np.linalg.norm(a.eo.position - b.eo.position))
        h = 0.5 * (heights[ia] + heights[ib])
        overlap = fps[ia].intersection(fps[ib]).area / min(fps[ia].area, fps[ib].area)
        if all_pairs and overlap < min_overlap:
            continue
        models.append(StereoModel(
            name=f"{left.name}_{right.name}", left=left.name, right=right.name,
            kind="in-strip" if a.strip == b.strip else "cross-strip",
            base=base, b_h=base / h, overlap=float(overlap),
            gsd=float(plan.camera_of(a).gsd(h)), height_above_ground=h))
    return models


# -- writing ---------------------------------------------------------------------------------------
def _crs_wkt() -> str:
    return rasterio.crs.CRS.from_string(CRS).to_wkt()


def _write_chimneys(scene: Scene, paths: Dict[str, Path], wkt: str) -> None:
    """Chimney squares with their building and absolute top height (truth/chimneys.gpkg)."""
    schema = {"geometry": "Polygon", "properties": OrderedDict(
        [("building", "int"), ("top_z", "float")])}
    with fiona.open(str(paths["chimneys"]), "w", driver="GPKG", layer="chimneys",
                    schema=schema, crs_wkt=wkt) as dst:
        for b in scene.objects.buildings:
            e = np.array([np.cos(b.angle), np.sin(b.angle)])
            n = np.array([-e[1], e[0]])
            for cu, cv, side, top in b.chimneys:
                c = np.array([b.x, b.y]) + cu * e + cv * n
                h = side / 2.0
                ring = [tuple(c + su * h * e + sv * h * n)
                        for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
                dst.write({"geometry": mapping(Polygon(ring)), "properties": OrderedDict(
                    [("building", b.id), ("top_z", round(b.base_z + top, 4))])})


def _write_vectors(scene: Scene, truth: Path) -> Dict[str, Path]:
    wkt = _crs_wkt()
    paths = {"buildings": truth / "buildings.gpkg", "breaklines": truth / "breaklines.gpkg",
             "checkpoints": truth / "checkpoints.gpkg", "chimneys": truth / "chimneys.gpkg"}
    schema = {"geometry": "Polygon", "properties": OrderedDict(
        [("id", "int"), ("roof", "str"), ("height", "float"), ("ridge_height", "float"),
         ("base_z", "float"), ("length", "float"), ("width", "float"), ("style", "str"),
         ("chimneys", "int")])}
    with fiona.open(str(paths["buildings"]), "w", driver="GPKG", layer="buildings",
                    schema=schema, crs_wkt=wkt) as dst:
        for b in scene.objects.buildings:
            dst.write({"geometry": mapping(Polygon([tuple(c) for c in b.corners()])),
                       "properties": OrderedDict(
                           [("id", b.id), ("roof", b.roof), ("height", round(b.height, 4)),
                            ("ridge_height", round(b.ridge_height, 4)),
                            ("base_z", round(b.base_z, 4)), ("length", round(b.length, 4)),
                            ("width", round(b.width, 4)), ("style", b.style),
                            ("chimneys", len(b.chimneys))])})
    _write_chimneys(scene, paths, wkt)
    schema = {"geometry": "3D LineString",
              "properties": OrderedDict([("id", "int"), ("kind", "str")])}
    with fiona.open(str(paths["breaklines"]), "w", driver="GPKG", layer="breaklines",
                    schema=schema, crs_wkt=wkt) as dst:
        for k, (kind, xyz) in enumerate(scene.objects.breaklines, start=1):
            dst.write({"geometry": mapping(LineString([tuple(p) for p in xyz])),
                       "properties": OrderedDict([("id", k), ("kind", kind)])})
    schema = {"geometry": "3D Point", "properties": OrderedDict([("id", "str")])}
    with fiona.open(str(paths["checkpoints"]), "w", driver="GPKG", layer="checkpoints",
                    schema=schema, crs_wkt=wkt) as dst:
        for k, (x, y, z) in enumerate(scene.checkpoints, start=1):
            dst.write({"geometry": mapping(Point(x, y, z)),
                       "properties": OrderedDict([("id", f"CP{k:03d}")])})
    csv_path = truth / "checkpoints.csv"
    with open(csv_path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(["id", "x", "y", "z"])
        for k, (x, y, z) in enumerate(scene.checkpoints, start=1):
            w.writerow([f"CP{k:03d}", f"{x:.4f}", f"{y:.4f}", f"{z:.4f}"])
    paths["checkpoints_csv"] = csv_path
    return paths


def checkpoint_ids(n: int) -> List[str]:
    """Ids of the check points as written (CP001, CP002, …)."""
    return [f"CP{k:03d}" for k in range(1, n + 1)]


def generate_block(output: Union[str, Path], size: str = "small", terrain: str = "gentle",
                   seed: int = 1, texture_direction: float = 0.0,
                   feedback: Optional[Feedback] = None, replace: bool = False,
                   window: Optional[int] = None) -> BlockResult:
    """Generate a synthetic block with ground truth into the folder ``output``.

    Parameters
    ----------
    output : path
        Output folder (must not exist or be empty unless ``replace``).
    size : {"tiny", "small", "medium", "large", "aerial"}
        Image size and block layout, see :data:`.flight.SIZES`; ``aerial`` renders windows of
        a real wide-angle film geometry (B_px ≈ 4600 px).
    terrain : {"gentle", "dunes", "steep"}
    seed : int
        Seed of every random choice; equal seeds give byte-identical results.
    texture_direction : float
        Direction of the field furrows, degrees counter-clockwise from the flight direction.
    feedback : Feedback, optional
        Progress per image tile; cancellation leaves no output.
    window : int, optional
        Window size (px) of a windowed size (``aerial``), default that of the size.

    Returns
    -------
    BlockResult
    """
    feedback = ensure_feedback(feedback)
    start = time.perf_counter()
    out = Path(output)
    with staged_folder(out, replace=replace) as tmp:
        scene = build_scene(size, terrain, seed, texture_direction, feedback, window)
        plan = scene.plan
        renderer = Renderer(scene.grid, scene.dsm, scene.albedo, scene.checkpoints,
                            scene.disc_radius)
        image_dir = tmp / "images"
        image_dir.mkdir()
        seeds = scene.image_seeds.spawn(len(plan.images))  # type: ignore[union-attr]
        records: List[ImageRecord] = []
        n = len(plan.images)
        total_miss = 0
        for k, im in enumerate(plan.images):
            def progress(frac: float, k: int = k) -> None:
                feedback.progress(20.0 + 75.0 * (k + frac) / n)

            camera = plan.camera_of(im)
            image, misses = render_image(renderer, camera, im.eo, scene.supersample,
                                         scene.tile_rays, seeds[k], plan.gsd / scene.supersample,
                                         progress)
            total_miss += misses
            path = image_dir / f"{im.name}.tif"
            with warnings.catch_warnings():  # images carry no georeference on purpose
                warnings.simplefilter("ignore", NotGeoreferencedWarning)
                write_raster(path, image, photometric="RGB")
            records.append(ImageRecord(im.name, f"images/{im.name}.tif", camera.name, im.eo))
        if total_miss:
            feedback.warning(f"{total_miss} rays missed the truth DSM (rendered black).")
        feedback.info(f"Rendered {n} images in {time.perf_counter() - start:.1f} s.")

        project = Project(root=tmp, name=f"synthetic_{size}_{terrain}_{seed}", crs=CRS,
                          cameras=plan.cameras, images=records,
                          models=list(scene.models), terrain_height=plan.terrain_height)
        project.models = _detected_models(project, scene, feedback)
        project.presets["synthetic"] = {"size": size, "terrain": terrain, "seed": int(seed),
                                        "texture_direction_deg": float(texture_direction),
                                        "disc_radius_m": scene.disc_radius,
                                        "landcover_codes": {str(k): v for k, v in
                                                            LANDCOVER.items()},
                                        **_geometry_summary(scene, project.models)}
        project.save()
        _create_edits(tmp)

        truth = tmp / "truth"
        truth.mkdir()
        g = scene.grid
        write_raster(truth / "dtm.tif", scene.dtm.astype(np.float32), g.transform, CRS)
        write_raster(truth / "dsm.tif", scene.dsm.astype(np.float32), g.transform, CRS)
        write_raster(truth / "landcover.tif", scene.landcover, g.transform, CRS, nodata=0)
        write_class_style(truth / "landcover.tif", {code: (name, LANDCOVER_COLOURS[code])
                                                    for code, name in LANDCOVER.items() if code})
        vec = _write_vectors(scene, truth)
        feedback.progress(99.0)
        names = {"dtm": "dtm.tif", "dsm": "dsm.tif", "landcover": "landcover.tif"}
        n_models = len(project.models)
        gsd, height = plan.gsd, plan.flying_height
        figures = _geometry_summary(scene, project.models)
    truth_paths = {k: out / "truth" / v for k, v in names.items()}
    truth_paths.update({k: out / "truth" / p.name for k, p in vec.items()
                        if k != "checkpoints_csv"})
    return BlockResult(out, truth_paths, n, n_models, gsd, height, time.perf_counter() - start,
                       figures["base_px"], figures["b_h"])


def _geometry_summary(scene: Scene, models: List[StereoModel]) -> Dict[str, Any]:
    """Flight figures for the ``synthetic`` preset and the outputs: GSD, H, mean B/H and
    base_px = B/GSD over the models (σ_Z/H = σ_px/base_px), per model, and the windows."""
    plan = scene.plan
    per_model = {m.name: {"base_px": round(m.base / m.gsd, 1), "b_h": round(m.b_h, 4)}
                 for m in models}
    out: Dict[str, Any] = {
        "gsd_m": round(plan.gsd, 4),
        "flying_height_m": round(plan.flying_height, 2),
        "base_px": round(float(np.mean([m.base / m.gsd for m in models])), 1) if models
        else float("nan"),
        "b_h": round(float(np.mean([m.b_h for m in models])), 4) if models else float("nan"),
        "models": per_model,
    }
    windows = {im.name: list(im.window) for im in plan.images if im.window is not None}
    if windows:
        out["frame_px"] = [plan.camera.width, plan.camera.height]
        out["windows"] = windows  # top-left (col, row) of each window in its frame
    return out


def _detected_models(project: Project, scene: Scene, feedback: Feedback) -> List[StereoModel]:
    """The planned in-strip pairs with the figures of
    :func:`..project.stereo_models.detect_stereo_models` (run on the true DTM) when that finds them
    all; else the planned pairs with our own figures and a warning. Further pairs the detection
    may accept (e.g. image 1 with image 3 over high mountains) are not added: the block's
    models are the consecutive in-strip pairs."""
    dem = DemSampler(scene.dtm, scene.grid.transform)
    if scene.plan.camera is not None and SIZES[scene.size].drone:
        # drone: the models are what the detection finds on the terrain (convergent pairs too)
        found_all = detect_stereo_models(project, dem=dem)
        if found_all:
            return found_all
        feedback.warning("Stereo-model detection found no model; the planned pairs are kept.")
        return list(scene.models)
    found = {m.name: m for m in detect_stereo_models(project, dem=dem, in_strip_only=True)}
    planned = [m.name for m in scene.models]
    if all(name in found for name in planned):
        return [found[name] for name in planned]
    feedback.warning(
        f"Stereo-model detection found {sorted(found)}, not all of the planned in-strip pairs "
        f"{planned}; the planned pairs are kept.")
    return list(scene.models)


def _create_edits(root: Path) -> None:
    """An empty ``edits.gpkg`` (all layers) in the project folder."""
    create_edits(root / "edits.gpkg", CRS)


def scene_summary(scene: Scene) -> Dict[str, Any]:
    """Figures of a scene for logs and tests."""
    return {
        "grid": (scene.grid.ncols, scene.grid.nrows, scene.grid.cell),
        "buildings": len(scene.objects.buildings),
        "trees": int(scene.objects.trees.shape[0]),
        "checkpoints": int(scene.checkpoints.shape[0]),
        "models": [m.name for m in scene.models],
        "relief": float(np.ptp(scene.dtm)),
        "gsd": scene.plan.gsd,
        "flying_height": scene.plan.flying_height,
        "base_px": scene.plan.base_px,
        "b_h": {m.name: m.b_h for m in scene.models},
    }


__all__: Tuple[str, ...] = (
    "BlockResult",
    "Scene",
    "build_scene",
    "checkpoint_ids",
    "generate_block",
    "in_strip_models",
    "scene_summary",
)
