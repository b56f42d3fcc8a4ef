"""Python and the ``photodem`` CLI give the same results for every real algorithm.

(The QGIS faces — ``processing.run`` and ``qgis_process`` — are compared in tests/qgis.)
"""

from __future__ import annotations

import hashlib
import json
import subprocess
import sys
from pathlib import Path
from typing import Any, Dict

import numpy as np
import pytest
import rasterio

from photodem.algorithms.processing import registry
from photodem.algorithms.raster.io import open_image

pytestmark = pytest.mark.slow

CLI = [sys.executable, "-m", "photodem.algorithms.cli"]


def _cli(alg: str, params: Dict[str, Any]) -> Dict[str, Any]:
    argv = [*CLI, "run", alg, "--json", "--quiet"]
    for key, value in params.items():
        argv += ["--" + key.replace("_", "-"), str(value)]
    done = subprocess.run(argv, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def _swap(value: Any, old: str, new: str) -> Any:
    if isinstance(value, dict):
        return {k: _swap(v, old, new) for k, v in value.items()}
    if isinstance(value, list):
        return [_swap(v, old, new) for v in value]
    return value.replace(old, new) if isinstance(value, str) else value


def _same_files(a: Path, b: Path) -> None:
    """Every file below ``a`` exists below ``b`` with the same content (rasters: same pixels)."""
    names = sorted(p.relative_to(a) for p in a.rglob("*") if p.is_file())
    assert names == sorted(p.relative_to(b) for p in b.rglob("*") if p.is_file())
    for rel in names:
        if rel.name.startswith(".photodem-product"):
            continue  # records the time of writing
        fa, fb = a / rel, b / rel
        if fa.suffix == ".tif":
            with open_image(fa) as x, open_image(fb) as y:
                assert np.array_equal(x.read(), y.read(), equal_nan=True), rel
                assert x.transform == y.transform and x.crs == y.crs, rel
        elif fa.suffix in (".toml", ".json", ".csv"):
            assert fa.read_text().replace(str(a), "<out>") == \
                fb.read_text().replace(str(b), "<out>"), rel
        elif fa.suffix == ".gpkg":  # GeoPackages hold timestamps: compare their features
            assert _features(fa) == _features(fb), rel
        else:
            assert hashlib.sha256(fa.read_bytes()).digest() == \
                hashlib.sha256(fb.read_bytes()).digest(), rel


def _features(path: Path) -> Dict[str, Any]:
    import fiona

    out = {}
    for layer in fiona.listlayers(str(path)):
        with fiona.open(str(path), layer=layer) as src:
            out[layer] = (src.crs.to_wkt() if src.crs else None,
                          [(dict(f["properties"]), f["geometry"]["type"],
                            json.dumps(f["geometry"]["coordinates"], default=list))
                           for f in src])
    return out


@pytest.fixture(scope="module")
def block(tmp_path_factory) -> Dict[str, Any]:
    base = tmp_path_factory.mktemp("faces")
    params = {"size": "tiny", "terrain": "gentle", "seed": 3}
    py = registry.run("synthetic_block", {**params, "output": str(base / "py")})
    cli = _cli("synthetic_block", {**params, "output": str(base / "cli")})
    return {"base": base, "py": py, "cli": cli}


def test_synthetic_block_python_equals_cli(block) -> None:
    base = block["base"]
    assert _swap(block["cli"], str(base / "cli"), "<out>") == \
        _swap(block["py"], str(base / "py"), "<out>")
    _same_files(base / "py", base / "cli")


def test_project_info_python_equals_cli(block) -> None:
    project = block["py"]["project"]
    assert _cli("project_info", {"project": project}) == \
        registry.run("project_info", {"project": project})


def test_epipolar_pair_python_equals_cli(block, tmp_path) -> None:
    project = block["py"]["project"]
    model = registry.run("project_info", {"project": project})["models"][0]["name"]
    py = registry.run("epipolar_pair", {"project": project, "model": model,
                                        "output": str(tmp_path / "py")})
    cli = _cli("epipolar_pair", {"project": project, "model": model,
                                 "output": str(tmp_path / "cli")})
    assert _swap(cli, str(tmp_path / "cli"), "<out>") == _swap(py, str(tmp_path / "py"), "<out>")
    _same_files(tmp_path / "py", tmp_path / "cli")


def test_stereo_models_python_equals_cli(block, tmp_path) -> None:
    import shutil

    params = {"min_overlap": 20.0, "b_h_max": 1.0, "manual": "0101,0201"}
    for face in ("py", "cli"):
        shutil.copytree(block["py"]["project"], tmp_path / face / "project")
    py = registry.run("stereo_models", {**params, "project": str(tmp_path / "py" / "project")})
    cli = _cli("stereo_models", {**params, "project": str(tmp_path / "cli" / "project")})
    assert cli == py
    assert any(m["kind"] == "manual" for m in py["models"])
    _same_files(tmp_path / "py", tmp_path / "cli")


def test_project_create_python_equals_cli(ngi_block: Path, tmp_path: Path) -> None:
    ngi = ngi_block
    params = {"images": str(ngi / "ngi"), "exterior": str(ngi / "io" / "ngi_xyz_opk.csv"),
              "interior": str(ngi / "io" / "ngi_int_param.yaml"), "angle_unit": "degrees",
              "dem": str(ngi / "ngi" / "dem.tif")}
    # the same folder name in both: a project is named after its folder
    py = registry.run("project_create", {**params, "output": str(tmp_path / "py" / "ngi")})
    cli = _cli("project_create", {**params, "output": str(tmp_path / "cli" / "ngi")})
    assert _swap(cli, str(tmp_path / "cli"), "<out>") == _swap(py, str(tmp_path / "py"), "<out>")
    _same_files(tmp_path / "py", tmp_path / "cli")
    with rasterio.open(ngi / "ngi" / "dem.tif"):
        pass  # the input is untouched and still readable


def _quality_inputs(block) -> Dict[str, str]:
    truth = Path(block["py"]["project"]) / "truth"
    with rasterio.open(truth / "dtm.tif") as src:
        b = src.bounds
    dx, dy = b.right - b.left, b.top - b.bottom
    line = (f"{b.left + 0.1 * dx:.3f},{b.bottom + 0.2 * dy:.3f};"
            f"{b.left + 0.9 * dx:.3f},{b.bottom + 0.7 * dy:.3f}")
    return {"dsm": str(truth / "dsm.tif"), "dtm": str(truth / "dtm.tif"),
            "landcover": str(truth / "landcover.tif"),
            "checkpoints": str(truth / "checkpoints.gpkg"), "line": line}


def test_dem_compare_python_equals_cli(block, tmp_path) -> None:
    q = _quality_inputs(block)
    params = {"dem": q["dsm"], "reference": q["dtm"], "classes": q["landcover"],
              "flying_height": 75.0}
    py = registry.run("dem_compare", {**params, "output": str(tmp_path / "py")})
    cli = _cli("dem_compare", {**params, "output": str(tmp_path / "cli")})
    assert _swap(cli, str(tmp_path / "cli"), "<out>") == _swap(py, str(tmp_path / "py"), "<out>")
    _same_files(tmp_path / "py", tmp_path / "cli")  # the HTML report byte for byte


def test_dem_profile_python_equals_cli(block, tmp_path) -> None:
    q = _quality_inputs(block)
    params = {"coordinates": q["line"]}
    py = registry.run("dem_profile", {**params, "dems": [q["dsm"], q["dtm"]],
                                      "output": str(tmp_path / "py")})
    argv = [*CLI, "run", "dem_profile", "--json", "--quiet", "--dems", q["dsm"], q["dtm"],
            "--coordinates", q["line"], "--output", str(tmp_path / "cli")]
    done = subprocess.run(argv, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    cli = json.loads(done.stdout)
    assert _swap(cli, str(tmp_path / "cli"), "<out>") == _swap(py, str(tmp_path / "py"), "<out>")
    _same_files(tmp_path / "py", tmp_path / "cli")
    # a comma-separated list as the help text says: the same result
    comma = _cli("dem_profile", {**params, "dems": f"{q['dsm']},{q['dtm']}",
                                 "output": str(tmp_path / "comma")})
    assert _swap(comma, str(tmp_path / "comma"), "<out>") == \
        _swap(py, str(tmp_path / "py"), "<out>")


def test_point_compare_python_equals_cli(block, tmp_path) -> None:
    q = _quality_inputs(block)
    params = {"points": q["checkpoints"], "dem": q["dsm"], "flying_height": 75.0}
    py = registry.run("point_compare", {**params, "output": str(tmp_path / "py")})
    cli = _cli("point_compare", {**params, "output": str(tmp_path / "cli")})
    assert _swap(cli, str(tmp_path / "cli"), "<out>") == _swap(py, str(tmp_path / "py"), "<out>")
    _same_files(tmp_path / "py", tmp_path / "cli")
    assert py["used"] == py["points"] > 0 and abs(py["stats"]["mean"]) < 0.01


def test_stereo_disparity_python_equals_cli(block, tmp_path) -> None:
    project = block["py"]["project"]
    model = registry.run("project_info", {"project": project})["models"][0]["name"]
    epi = registry.run("epipolar_pair", {"project": project, "model": model,
                                         "output": str(tmp_path / "epipolar")})
    params = {"left": epi["left"], "right": epi["right"], "min_disparity": 80,
              "max_disparity": 130}
    py = registry.run("stereo_disparity", {**params, "output": str(tmp_path / "py" / "d.tif")})
    cli = _cli("stereo_disparity", {**params, "output": str(tmp_path / "cli" / "d.tif")})
    assert _swap(cli, str(tmp_path / "cli"), "<out>") == _swap(py, str(tmp_path / "py"), "<out>")
    _same_files(tmp_path / "py", tmp_path / "cli")
    assert py["valid_share"] > 0.3


@pytest.mark.parametrize("method", ["dense", "fbm_lsm"])
def test_match_model_python_equals_cli(block, tmp_path, method) -> None:
    project = block["py"]["project"]
    model = registry.run("project_info", {"project": project})["models"][0]["name"]
    params = {"project": project, "model": model, "method": method}
    py = registry.run("match_model", {**params, "output": str(tmp_path / "py")})
    cli = _cli("match_model", {**params, "output": str(tmp_path / "cli")})
    assert _swap(cli, str(tmp_path / "cli"), "<out>") == _swap(py, str(tmp_path / "py"), "<out>")
    for name in ("dsm.tif", "count.tif"):
        with open_image(tmp_path / "py" / name) as x, open_image(tmp_path / "cli" / name) as y:
            assert np.array_equal(x.read(), y.read(), equal_nan=True), name
            assert x.transform == y.transform and x.crs == y.crs, name
    reports = [json.loads((tmp_path / f / "report.json").read_text()) for f in ("py", "cli")]
    assert _timeless(reports[0]) == _timeless(reports[1])
    assert py["metrics"]["coverage_pct"] > 50


def _timeless(value):
    """A report without its wall-clock times (every key ending in 'seconds')."""
    if isinstance(value, dict):
        return {k: _timeless(v) for k, v in value.items() if not k.endswith("seconds")}
    if isinstance(value, list):
        return [_timeless(v) for v in value]
    return value


def test_dsm_merge_python_equals_cli(block, tmp_path) -> None:
    q = _quality_inputs(block)
    py = registry.run("dsm_merge", {"inputs": [q["dsm"], q["dtm"]], "mode": "median",
                                    "spacing": 0.5, "output": str(tmp_path / "py" / "m.tif")})
    cli = _cli("dsm_merge", {"inputs": f"{q['dsm']},{q['dtm']}", "mode": "median",
                             "spacing": 0.5, "output": str(tmp_path / "cli" / "m.tif")})
    assert _swap(cli, str(tmp_path / "cli"), "<out>") == _swap(py, str(tmp_path / "py"), "<out>")
    _same_files(tmp_path / "py", tmp_path / "cli")
    seam = py["seams"][0]  # DSM − DTM: objects are above the terrain
    # (−0.02: beside a wall the DSM takes its nearest cell instead of bilinear weights across
    # the wall, so the ground there is off by the terrain slope over up to half a cell)
    assert seam["count"] > 0 and seam["mean"] > 0 and seam["min"] >= -0.02


def test_interpolate_dem_python_equals_cli(block, tmp_path) -> None:
    q = _quality_inputs(block)
    truth = Path(q["dtm"]).parent
    params = {"points": q["checkpoints"], "project": block["py"]["project"],
              "breaklines": str(truth / "breaklines.gpkg"), "spacing": 2.0}
    py = registry.run("interpolate_dem", {**params, "output": str(tmp_path / "py" / "d.tif")})
    cli = _cli("interpolate_dem", {**params, "output": str(tmp_path / "cli" / "d.tif")})
    assert _swap(cli, str(tmp_path / "cli"), "<out>") == _swap(py, str(tmp_path / "py"), "<out>")
    _same_files(tmp_path / "py", tmp_path / "cli")
    # compartments between breaklines without a point stay empty
    assert py["used"] == py["points"] > 0 and py["coverage"] > 0.5 and py["filled"] > 0


def test_filter_evaluate_python_equals_cli(block, tmp_path) -> None:
    q = _quality_inputs(block)
    with rasterio.open(q["dtm"]) as src:
        z, t = src.read(1), src.transform
    rows, cols = (a.ravel() for a in np.mgrid[3:z.shape[0] - 3:29, 3:z.shape[1] - 3:31])
    x, y = t.c + (cols + 0.5) * t.a, t.f + (rows + 0.5) * t.e
    truth = (np.arange(rows.size) % 4 == 0).astype(int)
    guess = np.where(np.arange(rows.size) % 5 == 0, 1 - truth, truth)
    ref, lab = tmp_path / "reference.txt", tmp_path / "labels.txt"
    ref.write_text("".join(f"{a:.3f}\t{b:.3f}\t{c:.3f}\t{k}\n"
                           for a, b, c, k in zip(x, y, z[rows, cols], truth)))
    lab.write_text("".join(f"{k}\n" for k in guess))
    params = {"labels": str(lab), "reference": str(ref), "dtm": q["dtm"],
              "reference_dtm": q["dsm"]}
    py = registry.run("filter_evaluate", {**params, "output": str(tmp_path / "py")})
    cli = _cli("filter_evaluate", {**params, "output": str(tmp_path / "cli")})
    assert _swap(cli, str(tmp_path / "cli"), "<out>") == _swap(py, str(tmp_path / "py"), "<out>")
    _same_files(tmp_path / "py", tmp_path / "cli")
    m = py["metrics"]
    assert m["n"] == rows.size and m["b"] + m["c"] == int(np.count_nonzero(guess != truth))
    assert m["dtm"]["mean"] < 0 and m["dtm_at_ground_points"]["rms"] < 1e-3  # DTM − DSM ≤ 0


def _dsm_crop(dsm: str, out: Path, half: float = 12.0) -> str:
    """The central 2·half m square of a DSM as its own GeoTIFF (small inputs run fast)."""
    from rasterio.windows import from_bounds

    from photodem.algorithms.raster.io import write_raster

    with rasterio.open(dsm) as src:
        b = src.bounds
        cx, cy = 0.5 * (b.left + b.right), 0.5 * (b.bottom + b.top)
        win = from_bounds(cx - half, cy - half, cx + half, cy + half, src.transform)
        win = win.round_offsets().round_lengths()
        data = src.read(1, window=win)
        path = out / "dsm_crop.tif"
        write_raster(path, data, transform=src.window_transform(win), crs=src.crs)
    return str(path)


def test_refine_object_space_python_equals_cli(block, tmp_path) -> None:
    dsm = _dsm_crop(_quality_inputs(block)["dsm"], tmp_path)
    params = {"project": block["py"]["project"], "dsm": dsm, "spacing": 0.6}
    py = registry.run("refine_object_space", {**params, "output": str(tmp_path / "py")})
    cli = _cli("refine_object_space", {**params, "output": str(tmp_path / "cli")})
    assert _swap(cli, str(tmp_path / "cli"), "<out>") == _swap(py, str(tmp_path / "py"), "<out>")
    for name in ("dsm.tif", "sigma.tif"):
        with open_image(tmp_path / "py" / name) as x, open_image(tmp_path / "cli" / name) as y:
            assert np.array_equal(x.read(), y.read(), equal_nan=True), name
            assert x.transform == y.transform and x.crs == y.crs, name
    reports = [json.loads((tmp_path / f / "report.json").read_text()) for f in ("py", "cli")]
    for r in reports:
        r.pop("seconds")  # wall-clock times
    assert reports[0] == reports[1]
    assert py["metrics"]["refined_cells"] > 0.8 * 40 * 40 and py["metrics"]["failures"] == 0


def test_filter_lowpass_python_equals_cli(block, tmp_path) -> None:
    q = _quality_inputs(block)
    params = {"input": q["dsm"], "project": block["py"]["project"], "preset": "urban",
              "write_iterations": True}
    py = registry.run("filter_lowpass", {**params, "output": str(tmp_path / "py")})
    cli = _cli("filter_lowpass", {**params, "output": str(tmp_path / "cli")})
    assert _swap(cli, str(tmp_path / "cli"), "<out>") == _swap(py, str(tmp_path / "py"), "<out>")
    _same_files(tmp_path / "py", tmp_path / "cli")
    assert py["mask"] and py["labels"] is None and 0.0 < py["metrics"]["eliminated_share"] < 0.9


def test_filter_linear_prediction_python_equals_cli(block, tmp_path) -> None:
    q = _quality_inputs(block)
    params = {"input": q["dsm"], "project": block["py"]["project"], "preset": "default",
              "write_levels": True}
    py = registry.run("filter_linear_prediction", {**params, "output": str(tmp_path / "py")})
    cli = _cli("filter_linear_prediction", {**params, "output": str(tmp_path / "cli")})
    assert _swap(cli, str(tmp_path / "cli"), "<out>") == _swap(py, str(tmp_path / "py"), "<out>")
    _same_files(tmp_path / "py", tmp_path / "cli")
    assert py["mask"] and py["labels"] is None and 0.0 < py["metrics"]["eliminated_share"] < 0.9


def test_orthorectify_python_equals_cli(block, tmp_path) -> None:
    q = _quality_inputs(block)
    params = {"project": block["py"]["project"], "image": "0102", "dem": q["dsm"],
              "dsm": q["dsm"], "true_ortho": True, "gsd": 0.3, "resampling": "cubic"}
    py = registry.run("orthorectify", {**params, "output": str(tmp_path / "py" / "o.tif")})
    cli = _cli("orthorectify", {**params, "output": str(tmp_path / "cli" / "o.tif")})
    assert _swap(cli, str(tmp_path / "cli"), "<out>") == _swap(py, str(tmp_path / "py"), "<out>")
    _same_files(tmp_path / "py", tmp_path / "cli")
    assert 0.0 < py["occluded_pct"] < 20.0 and py["gsd"] == 0.3


def test_ortho_displacement_python_equals_cli(block, tmp_path) -> None:
    from photodem.algorithms.ortho.rectify import orthorectify_image

    q = _quality_inputs(block)
    project = block["py"]["project"]
    for image in ("0101", "0102"):
        orthorectify_image(project, image, q["dtm"], tmp_path / f"{image}.tif", gsd=0.3)
    params = {"project": project, "image": "0102", "dem": q["dsm"], "reference": q["dtm"],
              "ortho": str(tmp_path / "0102.tif"), "reference_ortho": str(tmp_path / "0101.tif"),
              "window": 21, "radius": 6}
    py = registry.run("ortho_displacement", {**params, "output": str(tmp_path / "py")})
    cli = _cli("ortho_displacement", {**params, "output": str(tmp_path / "cli")})
    assert _swap(cli, str(tmp_path / "cli"), "<out>") == _swap(py, str(tmp_path / "py"), "<out>")
    _same_files(tmp_path / "py", tmp_path / "cli")
    assert py["predicted"]["max_m"] > 1.0 and py["measured"]["matched"] > 10


def test_mosaic_python_equals_cli(block, tmp_path) -> None:
    from photodem.algorithms.ortho.rectify import orthorectify_image

    q = _quality_inputs(block)
    project = block["py"]["project"]
    for image in ("0101", "0102"):
        orthorectify_image(project, image, q["dtm"], tmp_path / f"{image}.tif", gsd=0.3)
    params = {"inputs": f"{tmp_path / '0101.tif'},{tmp_path / '0102.tif'}", "dsm": q["dsm"],
              "dtm": q["dtm"], "balance": "gain_offset", "feather": 1.5}
    py = registry.run("mosaic", {**params, "inputs": params["inputs"].split(","),
                                 "output": str(tmp_path / "py" / "m.tif")})
    cli = _cli("mosaic", {**params, "output": str(tmp_path / "cli" / "m.tif")})
    assert _swap(cli, str(tmp_path / "cli"), "<out>") == _swap(py, str(tmp_path / "py"), "<out>")
    _same_files(tmp_path / "py", tmp_path / "cli")
    assert py["balance"]["after"]["mean_difference"] <= 2.0 and py["gsd"] == 0.3


def test_georeference_polygons_python_equals_cli(tmp_path) -> None:
    from photodem.algorithms.synthetic.polygon_scene import georef_case

    case = georef_case(tmp_path / "case", seed=5, width=700, height=700)
    params = {"image": case["image"], "reference": case["reference"], "class_field": "class",
              "class_value": "forest", "transform": "affine"}
    params.pop("class_field"), params.pop("class_value")  # all classes: more objects
    py = registry.run("georeference_polygons", {**params, "output": str(tmp_path / "py")})
    cli = _cli("georeference_polygons", {**params, "output": str(tmp_path / "cli")})
    assert _swap(cli, str(tmp_path / "cli"), "<out>") == _swap(py, str(tmp_path / "py"), "<out>")
    _same_files(tmp_path / "py", tmp_path / "cli")
    assert py["n_pairs"] >= 3 and py["rmse_px"] < 1.0
