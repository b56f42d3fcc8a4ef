"""Every real algorithm: Python (registry.run) = processing.run = qgis_process.bin run.

Outputs are compared after replacing the run-specific output folder by a placeholder: the result
dicts must be equal and the files below the output folders must have the same contents (text
files after the same path mapping, GeoTIFFs by pixels/CRS/transform). An algorithm that is not in
the registry yet is skipped with the reason.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Callable, Dict

import pytest
from _qgis_helpers import (
    DIGITS,
    QGIS_PROCESS,
    normalise,
    qgis_process_env,
    qgis_process_results,
    run_qgis_process,
    to_cli_args,
    to_qgis_params,
    tree_digest,
)

pytestmark = pytest.mark.qgis

ROOT = Path(__file__).resolve().parents[2]
# As tests/conftest.py (not importable by name here: every conftest module is "conftest").
SHARED_DATA = Path(os.environ.get("PHOTODEM_SHARED_DATA", ROOT.parent / "shared" / "data"))


def _require(algorithm_id: str):
    from photodem.algorithms.processing import registry

    algs = registry.algorithms()
    if algorithm_id not in algs:
        pytest.skip(f"{algorithm_id} is not in the registry yet (being written in parallel)")
    return algs[algorithm_id]


@pytest.fixture(scope="module")
def synthetic_project(tmp_path_factory, plugin) -> Path:
    """A tiny synthetic block made once through Python; project_info/epipolar_pair read it."""
    from photodem.algorithms.processing import registry

    _require("synthetic_block")
    out = tmp_path_factory.mktemp("synthetic") / "block"
    result = registry.run("synthetic_block",
                          {"output": str(out), "size": "tiny", "terrain": "gentle", "seed": 3})
    return Path(result.get("project", out))


def _first_model(project: Path) -> str:
    from photodem.algorithms.project.model import Project

    models = Project.load(project).models
    if not models:
        pytest.skip(f"the synthetic project {project} has no stereo model")
    return models[0].name


def _ngi() -> Path:
    path = SHARED_DATA / "ngi_aerial_block"
    if not path.is_dir():
        pytest.skip(f"real data 'ngi_aerial_block' not found at {path}")
    return path


def _project_copy(project: Path, out: Path) -> Path:
    """A private copy for algorithms that update the project itself."""
    import shutil

    copy = out / "project"
    if not copy.exists():
        shutil.copytree(project, copy)
    return copy


def _truth(project: Path, name: str) -> str:
    """A ground-truth file of the synthetic block (``truth/`` beside project.toml)."""
    path = Path(project) / "truth" / name
    if not path.exists():
        pytest.skip(f"the synthetic project has no {path}")
    return str(path)


def _diagonal(raster: str) -> str:
    """'x1,y1;x2,y2' across the inner part of a raster (profile coordinates)."""
    import rasterio

    with rasterio.open(raster) as src:
        b = src.bounds
    dx, dy = b.right - b.left, b.top - b.bottom
    return (f"{b.left + 0.1 * dx:.3f},{b.bottom + 0.2 * dy:.3f};"
            f"{b.left + 0.5 * dx:.3f},{b.bottom + 0.5 * dy:.3f};"
            f"{b.left + 0.9 * dx:.3f},{b.bottom + 0.6 * dy:.3f}")


def _epipolar(project: Path) -> Dict[str, Any]:
    """The epipolar pair of the first model of the synthetic block, made once beside it."""
    from photodem.algorithms.processing import registry

    folder = Path(project).parent / "epipolar_for_matching"
    if not (folder / "epipolar.json").is_file():
        registry.run("epipolar_pair", {"project": str(project), "model": _first_model(project),
                                       "output": str(folder)})
    return {"left": str(folder / "left.tif"), "right": str(folder / "right.tif")}


def _filter_labels(project: Path) -> Dict[str, str]:
    """Filter labels and reference labels (X Y Z label) on the truth DTM, made once beside it."""
    import numpy as np
    import rasterio

    folder = Path(project).parent / "filter_labels"
    lab, ref = folder / "labels.txt", folder / "reference.txt"
    if not ref.is_file():
        folder.mkdir(exist_ok=True)
        with rasterio.open(_truth(project, "dtm.tif")) as src:
            z, t = src.read(1), src.transform
        rows, cols = (a.ravel() for a in np.mgrid[5:z.shape[0] - 5:37, 5:z.shape[1] - 5:41])
        x, y = t.c + (cols + 0.5) * t.a, t.f + (rows + 0.5) * t.e
        truth = (np.arange(rows.size) % 3 == 0).astype(int)
        guess = truth.copy()
        guess[::7] = 1 - guess[::7]
        ref.write_text("".join(f"{a:.3f} {b:.3f} {c:.3f} {k}\n"
                               for a, b, c, k in zip(x, y, z[rows, cols], truth)))
        lab.write_text("".join(f"{k}\n" for k in guess))
    return {"labels": str(lab), "reference": str(ref)}


def _dsm_crop(project: Path) -> str:
    """The central 24 m × 24 m of the truth DSM (object-space refinement runs fast on it)."""
    import rasterio
    from rasterio.windows import from_bounds

    from photodem.algorithms.raster.io import write_raster

    path = Path(project).parent / "dsm_crop" / "dsm.tif"
    if not path.is_file():
        with rasterio.open(_truth(project, "dsm.tif")) as src:
            b = src.bounds
            cx, cy = 0.5 * (b.left + b.right), 0.5 * (b.bottom + b.top)
            win = from_bounds(cx - 12, cy - 12, cx + 12, cy + 12, src.transform)
            win = win.round_offsets().round_lengths()
            write_raster(path, src.read(1, window=win), transform=src.window_transform(win),
                         crs=src.crs)
    return str(path)


def _ortho_pair(project: Path) -> Dict[str, str]:
    """Orthos of images 0101 and 0102 on the truth DTM (0.3 m), made once beside the project."""
    from photodem.algorithms.ortho.rectify import orthorectify_image

    folder = Path(project).parent / "ortho_pair"
    paths = {"ortho": folder / "0102.tif", "reference_ortho": folder / "0101.tif"}
    for key, image in (("reference_ortho", "0101"), ("ortho", "0102")):
        if not paths[key].is_file():
            orthorectify_image(project, image, _truth(project, "dtm.tif"), paths[key], gsd=0.3)
    return {k: str(v) for k, v in paths.items()}


def _georef_case(project: Path) -> Dict[str, str]:
    """A synthetic image of a polygon map (unknown georeference), made once beside the project."""
    from photodem.algorithms.synthetic.polygon_scene import georef_case

    folder = Path(project).parent / "georef_case"
    if not (folder / "image.tif").is_file():
        georef_case(folder, seed=5, width=600, height=600)
    return {"image": str(folder / "image.tif"), "reference": str(folder / "map.gpkg")}


# Inputs per algorithm; ``out`` is the run's own output folder.
CASES: Dict[str, Callable[..., Dict[str, Any]]] = {
    "stereo_models": lambda out, req: {
        "project": str(_project_copy(req("project"), out)), "min_overlap": 20.0,
        "b_h_max": 1.0, "manual": "0101,0201"},
    "synthetic_block": lambda out, req: {
        "output": str(out / "block"), "size": "tiny", "terrain": "gentle", "seed": 3},
    "project_info": lambda out, req: {"project": str(req("project"))},
    "epipolar_pair": lambda out, req: {
        "project": str(req("project")), "model": _first_model(req("project")),
        "output": str(out / "epipolar")},
    "project_create": lambda out, req: {
        "images": str(_ngi() / "ngi"),
        "exterior": str(_ngi() / "io" / "ngi_xyz_opk.csv"),
        "interior": str(_ngi() / "io" / "ngi_int_param.yaml"),
        "angle_unit": "degrees",
        "dem": str(_ngi() / "ngi" / "dem.tif"),
        "output": str(out / "ngi_project")},
    "dem_compare": lambda out, req: {
        "dem": _truth(req("project"), "dsm.tif"), "reference": _truth(req("project"), "dtm.tif"),
        "classes": _truth(req("project"), "landcover.tif"), "flying_height": 75.0,
        "output": str(out / "compare")},
    "dem_profile": lambda out, req: {
        "dems": [_truth(req("project"), "dsm.tif"), _truth(req("project"), "dtm.tif")],
        "coordinates": _diagonal(_truth(req("project"), "dtm.tif")), "spacing": 0.5,
        "output": str(out / "profile")},
    "point_compare": lambda out, req: {
        "points": _truth(req("project"), "checkpoints.gpkg"),
        "dem": _truth(req("project"), "dsm.tif"), "flying_height": 75.0,
        "output": str(out / "points")},
    "stereo_disparity": lambda out, req: {
        **_epipolar(req("project")), "min_disparity": 80, "max_disparity": 130,
        "method": "sgm", "output": str(out / "disparity" / "disparity.tif")},
    "match_model": lambda out, req: {
        "project": str(req("project")), "model": _first_model(req("project")),
        "method": "dense", "output": str(out / "dsm")},
    "dsm_merge": lambda out, req: {
        "inputs": [_truth(req("project"), "dsm.tif"), _truth(req("project"), "dtm.tif")],
        "mode": "median", "spacing": 0.5, "output": str(out / "merge" / "merged.tif")},
    "interpolate_dem": lambda out, req: {
        "points": _truth(req("project"), "checkpoints.gpkg"), "project": str(req("project")),
        "breaklines": _truth(req("project"), "breaklines.gpkg"), "spacing": 2.0,
        "max_gap": 100.0, "output": str(out / "dem" / "dem.tif")},
    "filter_evaluate": lambda out, req: {
        **_filter_labels(req("project")), "dtm": _truth(req("project"), "dtm.tif"),
        "reference_dtm": _truth(req("project"), "dsm.tif"), "output": str(out / "evaluate")},
    "filter_lowpass": lambda out, req: {
        "input": _truth(req("project"), "dsm.tif"), "project": str(req("project")),
        "preset": "urban", "write_iterations": True, "output": str(out / "lowpass")},
    "filter_linear_prediction": lambda out, req: {
        "input": _truth(req("project"), "dsm.tif"), "project": str(req("project")),
        "preset": "default", "write_levels": True, "output": str(out / "linear_prediction")},
    "orthorectify": lambda out, req: {
        "project": str(req("project")), "image": "0102", "dem": _truth(req("project"), "dsm.tif"),
        "gsd": 0.3, "resampling": "cubic", "true_ortho": True,
        "dsm": _truth(req("project"), "dsm.tif"), "output": str(out / "ortho" / "0102.tif")},
    "ortho_displacement": lambda out, req: {
        "project": str(req("project")), "image": "0102", "dem": _truth(req("project"), "dsm.tif"),
        "reference": _truth(req("project"), "dtm.tif"), **_ortho_pair(req("project")),
        "window": 21, "radius": 6, "output": str(out / "displacement")},
    "mosaic": lambda out, req: {
        "inputs": [v for _, v in sorted(_ortho_pair(req("project")).items())],
        "dsm": _truth(req("project"), "dsm.tif"), "dtm": _truth(req("project"), "dtm.tif"),
        "seamlines": "auto", "balance": "gain_offset", "feather": 1.5,
        "output": str(out / "mosaic" / "mosaic.tif")},
    "georeference_polygons": lambda out, req: {
        **_georef_case(req("project")), "transform": "affine", "thresholds": "5,6,7,8",
        "output": str(out / "georef")},
    "refine_object_space": lambda out, req: {
        "project": str(req("project")), "dsm": _dsm_crop(req("project")), "spacing": 0.6,
        "output": str(out / "refined")},
}


def _inputs(spec, out: Path, request) -> Dict[str, Any]:
    def req(name: str):
        if name == "project":
            return request.getfixturevalue("synthetic_project")
        raise KeyError(name)

    raw = CASES[spec.id](out, req)
    known = {p.name for p in spec.parameters}
    return {k: v for k, v in raw.items() if k in known}  # e.g. 'dem' only if declared


@pytest.fixture(scope="module")
def qp_plain_env(tmp_path_factory):
    if not Path(QGIS_PROCESS).is_file():
        pytest.skip(f"{QGIS_PROCESS} not installed (Debian package 'qgis')")
    env = qgis_process_env(tmp_path_factory.mktemp("qgis_process_real"), ROOT)
    proc = run_qgis_process(env, "plugins", "enable", "photodem")
    assert proc.returncode == 0, proc.stderr
    return env


def test_every_algorithm_has_a_case(plugin):
    from photodem.algorithms.processing import registry

    assert set(registry.algorithms()) <= set(CASES) | {"fixture_all_kinds"}


@pytest.mark.parametrize("algorithm_id", sorted(CASES))
def test_python_equals_processing_run(algorithm_id, plugin, tmp_path, request):
    import processing

    from photodem.algorithms.processing import registry

    spec = _require(algorithm_id)
    out_py, out_q = tmp_path / "py", tmp_path / "qgis"
    expected = registry.run(algorithm_id, _inputs(spec, out_py, request))
    got = processing.run(f"photodem:{algorithm_id}",
                         to_qgis_params(spec, _inputs(spec, out_q, request)))
    map_py, map_q = {str(out_py): "<OUT>"}, {str(out_q): "<OUT>"}
    assert normalise(got, map_q) == normalise(expected, map_py)
    if out_py.exists() or out_q.exists():
        assert tree_digest(out_q, map_q) == tree_digest(out_py, map_py)


@pytest.mark.parametrize("algorithm_id", sorted(CASES))
def test_python_equals_qgis_process(algorithm_id, plugin, qp_plain_env, tmp_path, request):
    """Under qgis_process the plugin runs on Debian's system Python (numpy 1.24, shapely 1.8)."""
    from photodem.algorithms.processing import registry

    spec = _require(algorithm_id)
    out_py, out_qp = tmp_path / "py", tmp_path / "qp"
    expected = registry.run(algorithm_id, _inputs(spec, out_py, request))
    got = qgis_process_results(qp_plain_env, algorithm_id,
                               to_cli_args(spec, _inputs(spec, out_qp, request)))
    map_py, map_qp = {str(out_py): "<OUT>"}, {str(out_qp): "<OUT>"}
    # Another process: floats may differ in the last bit (seen: epipolar homographies, 1e-15).
    assert normalise(got, map_qp, DIGITS) == normalise(expected, map_py, DIGITS)
    if out_py.exists() or out_qp.exists():
        assert tree_digest(out_qp, map_qp, DIGITS) == tree_digest(out_py, map_py, DIGITS)
