"""Damaged and unusable inputs end as one-line operator errors (issue 16, points 6–8).

Every case runs through the CLI (``photodem run …``): exit 2, exactly one ``photodem: error:``
line, no traceback, every input file unchanged (hash before = after) and nothing left in the
output folder.
"""

from __future__ import annotations

import hashlib
import os
import shutil
from pathlib import Path
from typing import Dict, List, Tuple

import numpy as np
import pytest
import rasterio

from photodem.algorithms import cli
from photodem.algorithms.errors import InputError
from photodem.algorithms.feedback import Feedback
from photodem.algorithms.input_errors import (
    check_raster,
    display_path,
    operator_errors,
    reading,
)
from photodem.algorithms.memory import check_allocation, format_bytes
from photodem.algorithms.processing import registry

NON_UTF8 = os.fsdecode(b"\xe9t\xe9")  # a Latin-1 name as Linux passes it: surrogate escapes


# -- fixtures ---------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def block(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A tiny synthetic project (never modified by the tests)."""
    root = tmp_path_factory.mktemp("inputs") / "p"
    registry.run("synthetic_block", {"output": str(root), "size": "tiny"})
    return root


@pytest.fixture(scope="module")
def bad(block: Path, tmp_path_factory: pytest.TempPathFactory) -> Dict[str, Path]:
    """Damaged and odd input files beside a copy of the project."""
    folder = tmp_path_factory.mktemp("bad")
    dsm = (block / "truth" / "dsm.tif").read_bytes()
    files = {
        "trunc": folder / "trunc.tif",
        "garbage": folder / "garbage.tif",
        "empty": folder / "empty.tif",
        "nonutf8": folder / f"{NON_UTF8}.tif",
        "dup": folder / "dup.xyz",
        "dup_few": folder / "dup_few.xyz",
        "other_crs": folder / "other_crs.tif",
    }
    files["trunc"].write_bytes(dsm[: len(dsm) // 2])
    files["garbage"].write_bytes(b"this is not a GeoTIFF at all")
    files["empty"].write_bytes(b"")
    shutil.copy(block / "truth" / "dsm.tif", files["nonutf8"])
    files["dup"].write_text("402300.0 5674700.0 55.0\n" * 3000, encoding="utf-8")
    rng = np.random.default_rng(1)
    extra = "".join(f"{402280 + 40 * a:.3f} {5674680 + 40 * b:.3f} {54 + c:.3f}\n"
                    for a, b, c in rng.random((20, 3)))
    files["dup_few"].write_text("402300.0 5674700.0 55.0\n" * 3000 + extra, encoding="utf-8")
    with rasterio.open(block / "truth" / "dtm.tif") as src:
        profile, data = src.profile, src.read()
    profile.update(crs="EPSG:3857")
    with rasterio.open(files["other_crs"], "w", **profile) as dst:
        dst.write(data)
    # a project whose first image is truncated
    trunc_project = folder / "trunc_project"
    shutil.copytree(block, trunc_project)
    image = trunc_project / "images" / "0101.tif"
    raw = image.read_bytes()
    image.write_bytes(raw[: len(raw) // 2])
    files["trunc_project"] = trunc_project
    # epipolar images for stereo_disparity
    epi = folder / "epi"
    registry.run("epipolar_pair", {"project": str(block), "model": "0101_0102",
                                   "output": str(epi)})
    files["epi"] = epi
    left = (epi / "left.tif").read_bytes()
    files["left_trunc"] = folder / "left_trunc.tif"
    files["left_trunc"].write_bytes(left[: len(left) // 2])
    return files


def _hashes(paths: List[Path]) -> Dict[str, str]:
    """SHA-256 of every file below the given files and folders."""
    out = {}
    for p in paths:
        for f in ([p] if p.is_file() else sorted(q for q in p.rglob("*") if q.is_file())):
            out[str(f)] = hashlib.sha256(f.read_bytes()).hexdigest()
    return out


def assert_operator_error(code: int, err: str, *words: str) -> str:
    """Exit 2, one error line, no traceback, the words in it; returns the line."""
    assert code == 2, err
    assert "Traceback" not in err, err
    lines = [line for line in err.splitlines() if line.startswith("photodem: error:")]
    assert len(lines) == 1, err
    for word in words:
        assert word in lines[0], lines[0]
    return lines[0]


# -- the corpus: damaged inputs over the algorithms ---------------------------------------------
def _corpus(b: Path, f: Dict[str, Path], out: Path) -> Dict[str, Tuple[List[str], List[str]]]:
    """Case id → (argv, words the error line must hold)."""
    t, dtm, dsm = str(f["trunc"]), str(b / "truth" / "dtm.tif"), str(b / "truth" / "dsm.tif")
    cases = {
        "dem_compare-trunc": (["dem_compare", "--dem", t, "--reference", dtm,
                               "--output", str(out)], ["trunc.tif", "truncated"]),
        "dem_compare-trunc-reference": (["dem_compare", "--dem", dsm, "--reference", t,
                                         "--output", str(out)], ["'reference'", "truncated"]),
        "dem_compare-garbage": (["dem_compare", "--dem", str(f["garbage"]), "--reference", dtm,
                                 "--output", str(out)], ["garbage.tif"]),
        "dem_compare-empty": (["dem_compare", "--dem", str(f["empty"]), "--reference", dtm,
                               "--output", str(out)], ["empty.tif"]),
        "dem_compare-nonutf8": (["dem_compare", "--dem", str(f["nonutf8"]), "--reference", dtm,
                                 "--output", str(out)], ["UTF-8", "\\xe9t\\xe9"]),
        "match_model-trunc-image": (["match_model", "--project", str(f["trunc_project"]),
                                     "--model", "0101_0102", "--output", str(out)],
                                    ["0101.tif", "truncated"]),
        "stereo_disparity-trunc": (["stereo_disparity", "--left", str(f["left_trunc"]),
                                    "--right", str(f["epi"] / "right.tif"),
                                    "--output", str(out / "d.tif")], ["'left'", "truncated"]),
        "orthorectify-trunc-dem": (["orthorectify", "--project", str(b), "--image", "0101",
                                    "--dem", t, "--output", str(out / "o.tif")],
                                   ["'dem'", "truncated"]),
        "orthorectify-trunc-image": (["orthorectify", "--project", str(f["trunc_project"]),
                                      "--image", "0101", "--dem", dtm,
                                      "--output", str(out / "o.tif")], ["0101.tif", "truncated"]),
        "mosaic-trunc-inputs": (["mosaic", "--inputs", t, "--output", str(out)],
                                ["'inputs'", "truncated"]),
        "mosaic-trunc-dem": (["mosaic", "--project", str(b), "--dem", t, "--output", str(out)],
                             ["'dem'", "truncated"]),
        "filter_evaluate-trunc": (["filter_evaluate", "--dtm", t, "--reference-dtm", dtm,
                                   "--labels", t, "--reference", t, "--output", str(out)],
                                  ["truncated"]),
        "filter_lowpass-trunc": (["filter_lowpass", "--input", t, "--output", str(out)],
                                 ["'input'", "truncated"]),
        "filter_linear_prediction-trunc": (["filter_linear_prediction", "--input", t,
                                            "--output", str(out)], ["'input'", "truncated"]),
        "point_compare-trunc": (["point_compare", "--points",
                                 str(b / "truth" / "checkpoints.csv"), "--dem", t,
                                 "--output", str(out)], ["'dem'", "truncated"]),
        "dsm_merge-trunc": (["dsm_merge", "--inputs", t, "--output", str(out / "m.tif")],
                            ["'inputs'", "truncated"]),
        "refine_object_space-trunc": (["refine_object_space", "--project", str(b), "--dsm", t,
                                       "--output", str(out)], ["'dsm'", "truncated"]),
        "ortho_displacement-trunc": (["ortho_displacement", "--project", str(b), "--image",
                                      "0101", "--dem", t, "--output", str(out)],
                                     ["'dem'", "truncated"]),
        "stereo_models-other-crs": (["stereo_models", "--project", str(b), "--dem",
                                     str(f["other_crs"])], ["EPSG:3857", "EPSG:25832"]),
        "interpolate_dem-one-position": (["interpolate_dem", "--points", str(f["dup"]),
                                          "--crs", "EPSG:25832", "--output", str(out / "d.tif")],
                                         ["dup.xyz", "1 distinct"]),
        "filter_lowpass-one-position": (["filter_lowpass", "--input", str(f["dup"]),
                                         "--crs", "EPSG:25832", "--output", str(out)],
                                        ["dup.xyz", "at least 10"]),
        "interpolate_dem-nonutf8-output": (["interpolate_dem", "--points",
                                            str(b / "truth" / "checkpoints.csv"),
                                            "--crs", "EPSG:25832",
                                            "--output", str(out / f"{NON_UTF8}.tif")],
                                           ["'output'", "UTF-8"]),
    }
    return cases


CASES = ["dem_compare-trunc", "dem_compare-trunc-reference", "dem_compare-garbage",
         "dem_compare-empty", "dem_compare-nonutf8", "match_model-trunc-image",
         "stereo_disparity-trunc", "orthorectify-trunc-dem", "orthorectify-trunc-image",
         "mosaic-trunc-inputs", "mosaic-trunc-dem", "filter_evaluate-trunc",
         "filter_lowpass-trunc", "filter_linear_prediction-trunc", "point_compare-trunc",
         "dsm_merge-trunc", "refine_object_space-trunc", "ortho_displacement-trunc",
         "stereo_models-other-crs", "interpolate_dem-one-position",
         "filter_lowpass-one-position", "interpolate_dem-nonutf8-output"]


@pytest.mark.parametrize("case", CASES)
def test_unusable_input_is_one_line_exit_2(case: str, block: Path, bad: Dict[str, Path],
                                           tmp_path: Path, capsys) -> None:
    out = tmp_path / "out"
    argv, words = _corpus(block, bad, out)[case]
    inputs = [block, *bad.values()]
    before = _hashes(inputs)
    code, err = cli.main(["run", *argv]), capsys.readouterr().err
    assert_operator_error(code, err, *words)
    assert _hashes(inputs) == before  # inputs are never modified
    assert not out.exists() or not any(out.iterdir()), list(out.iterdir())
    assert sorted(p.name for p in tmp_path.iterdir()) in ([], ["out"])  # nothing beside it


# -- usable inputs with a warning --------------------------------------------------------------
def test_repeated_points_are_a_warning_where_enough_remain(bad: Dict[str, Path], block: Path,
                                                           tmp_path: Path) -> None:
    fb = Feedback()
    result = registry.run("point_compare", {"points": str(bad["dup_few"]),
                                            "dem": str(block / "truth" / "dtm.tif"),
                                            "output": str(tmp_path / "pc")}, fb)
    assert result
    assert any("repeat the x, y" in w and "dup_few.xyz" in w for w in fb.warnings), fb.warnings


def test_non_utf8_text_input_works_and_its_name_reaches_the_report(block: Path,
                                                                    tmp_path: Path) -> None:
    points = tmp_path / f"{NON_UTF8}.csv"
    shutil.copy(block / "truth" / "checkpoints.csv", points)
    result = registry.run("point_compare", {"points": str(points),
                                            "dem": str(block / "truth" / "dtm.tif"),
                                            "output": str(tmp_path / "pc")})
    import json

    stats = json.loads(Path(result["json"]).read_text(encoding="utf-8"))
    assert stats["points_file"] == points.name  # the JSON escape reads back as the name


# -- the translation itself --------------------------------------------------------------------
def test_a_programming_error_is_not_turned_into_an_operator_error() -> None:
    with pytest.raises(IndexError), operator_errors():
        np.zeros(3)[5]
    with pytest.raises(KeyError), operator_errors():
        {}["x"]


def test_reading_names_the_file_for_toml_yaml_and_text(tmp_path: Path) -> None:
    from photodem.algorithms.project.toml_io import loads

    toml = tmp_path / "x.toml"
    toml.write_text("a = [1, 2\n", encoding="utf-8")
    with pytest.raises(InputError, match=r"x\.toml"), reading(toml, "TOML file"):
        loads(toml.read_text(encoding="utf-8"))
    yml = tmp_path / "cam.yaml"
    yml.write_text("a: [1, 2\nb: :\n", encoding="utf-8")
    import yaml

    with pytest.raises(InputError, match=r"cam\.yaml"), reading(yml, "camera file"):
        yaml.safe_load(yml.read_text(encoding="utf-8"))
    latin = tmp_path / "latin.txt"
    latin.write_bytes("Höhe 12\n".encode("latin-1"))
    with pytest.raises(InputError, match="not UTF-8"), reading(latin, "text file"):
        latin.read_text(encoding="utf-8")


def test_check_raster_reads_first_and_last_block(block: Path, bad: Dict[str, Path]) -> None:
    check_raster(block / "truth" / "dsm.tif")  # a sound file passes
    with pytest.raises(InputError, match="truncated or damaged"):
        check_raster(bad["trunc"])
    with pytest.raises(InputError, match="UTF-8"):
        check_raster(bad["nonutf8"])


def test_display_path_prints_undecodable_bytes() -> None:
    assert display_path(f"/x/{NON_UTF8}.tif") == "/x/\\xe9t\\xe9.tif"


# -- memory ------------------------------------------------------------------------------------
def test_check_allocation_names_the_parameter() -> None:
    check_allocation(1e6, "a grid", "spacing", available=10**9)
    with pytest.raises(InputError, match="change spacing") as info:
        check_allocation(26e12, "a grid", "spacing", available=8 * 10**9)
    assert "26.0 TB" in str(info.value)
    assert format_bytes(1.5e9) == "1.5 GB"


def test_a_huge_disparity_range_is_cut_to_the_images(bad: Dict[str, Path], tmp_path: Path
                                                     ) -> None:
    """±100 000 px on 224-px-wide images: only ±223 px are possible; the run is quick."""
    import time

    t0 = time.perf_counter()
    result = registry.run("stereo_disparity", {
        "left": str(bad["epi"] / "left.tif"), "right": str(bad["epi"] / "right.tif"),
        "min_disparity": -100000, "max_disparity": 100000,
        "output": str(tmp_path / "d.tif")})
    assert Path(result["disparity"]).is_file()
    assert time.perf_counter() - t0 < 60


def test_a_disparity_range_beyond_memory_is_refused_before_work(
        bad: Dict[str, Path], tmp_path: Path, monkeypatch, capsys) -> None:
    monkeypatch.setenv("PHOTODEM_MEMORY_LIMIT_MB", "20")
    out = tmp_path / "d.tif"
    code = cli.main(["run", "stereo_disparity", "--left", str(bad["epi"] / "left.tif"),
                     "--right", str(bad["epi"] / "right.tif"), "--min-disparity", "-200",
                     "--max-disparity", "200", "--output", str(out)])
    assert_operator_error(code, capsys.readouterr().err, "min_disparity", "memory")
    assert list(tmp_path.iterdir()) == []


def test_a_grid_beyond_memory_is_refused_naming_the_spacing(block: Path, tmp_path: Path,
                                                            capsys) -> None:
    code = cli.main(["run", "interpolate_dem", "--points",
                     str(block / "truth" / "checkpoints.csv"), "--crs", "EPSG:25832",
                     "--spacing", "0.0001", "--output", str(tmp_path / "d.tif")])
    assert_operator_error(code, capsys.readouterr().err, "spacing")
    assert list(tmp_path.iterdir()) == []


# -- the pre-flight covers every raster parameter of every algorithm --------------------------
def _raster_parameters() -> List[Tuple[str, str]]:
    return [(alg.id, p.name) for alg in registry.algorithms().values() for p in alg.parameters
            if p.kind in ("raster", "multiple_rasters")]


@pytest.mark.parametrize("alg_id, name", _raster_parameters())
@pytest.mark.parametrize("damage", ["trunc", "garbage", "empty"])
def test_preflight_refuses_damaged_rasters_for_every_parameter(
        alg_id: str, name: str, damage: str, bad: Dict[str, Path]) -> None:
    from photodem.algorithms.input_errors import check_raster_parameters

    alg = registry.get(alg_id)
    value = [str(bad[damage])] if alg.parameter(name).kind == "multiple_rasters" \
        else str(bad[damage])
    with pytest.raises(InputError) as info:
        check_raster_parameters(alg.parameters, {name: value})
    text = str(info.value)
    assert f"Parameter '{name}'" in text and bad[damage].name in text and "\n" not in text
