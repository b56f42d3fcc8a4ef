"""The output policy: checked by registry.run for every algorithm before any work (issue 16)."""

from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from photodem.algorithms import cli, output_policy
from photodem.algorithms.errors import InputError
from photodem.algorithms.processing import registry
from photodem.algorithms.processing.spec import Algorithm, Output, Parameter
from photodem.algorithms.raster.io import PRODUCT_MARKER, write_raster


# -- fixtures ------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def block_template(tmp_path_factory):
    """One tiny synthetic project per module (copied per test: tests may try to damage it)."""
    out = tmp_path_factory.mktemp("tpl") / "p"
    registry.run("synthetic_block", {"output": str(out), "size": "tiny"})
    return out


@pytest.fixture
def block(block_template, tmp_path):
    dest = tmp_path / "p"
    shutil.copytree(block_template, dest)
    return dest


def tree_hash(root: Path) -> dict:
    """Path → sha256 of every file below ``root`` (to prove that nothing changed)."""
    return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(root.rglob("*")) if p.is_file()}


class WriteTif(Algorithm):
    """Writes one small GeoTIFF (and a sidecar report) through write_raster."""

    id = "test_write_tif"
    name = "Test: write a GeoTIFF"
    parameters = (Parameter("output", "output_raster", "Raster"),)
    outputs = (Output("raster", "raster", "Raster"),)

    def sidecars(self, name, path):
        return [path.with_name(f"{path.stem}_report.json")]

    def run(self, params, feedback):
        from photodem.algorithms.raster.io import atomic_output

        out = Path(params["output"])
        write_raster(out, np.ones((4, 5), np.float32))
        with atomic_output(out.with_name(f"{out.stem}_report.json")) as tmp:
            tmp.write_text("{}")
        return {"raster": str(out)}


class OtherTif(WriteTif):
    id = "test_other_tif"


@pytest.fixture
def tif_algs(monkeypatch):
    monkeypatch.setattr(registry, "_CACHE", registry.algorithms())
    registry.add(WriteTif())
    registry.add(OtherTif())


# -- point 1: a project is never replaced --------------------------------------------------------
def test_dem_compare_into_the_project_is_refused(block, capsys):
    before = tree_hash(block)
    code = cli.main(["run", "dem_compare", "--dem", str(block / "truth/dsm.tif"),
                     "--reference", str(block / "truth/dtm.tif"), "--output", str(block)])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and err.startswith("photodem: error:") and "project" in err
    assert tree_hash(block) == before


def test_projects_carry_no_product_marker(block, tmp_path):
    assert not (block / PRODUCT_MARKER).exists()
    with pytest.raises(InputError, match="project"):
        registry.run("dem_profile", {"dems": [str(block / "truth/dsm.tif")],
                                     "coordinates": "0,0;1,1", "output": str(block)})


def test_a_folder_that_contains_a_project_is_refused(block, tmp_path):
    outer = block.parent
    (outer / PRODUCT_MARKER).write_text(json.dumps({"product": "dem_compare"}))
    with pytest.raises(InputError, match="contains a PhotoDEM project"):
        registry.run("dem_compare", {"dem": str(block / "truth/dsm.tif"),
                                     "reference": str(block / "truth/dtm.tif"),
                                     "output": str(outer)})
    assert (block / "project.toml").is_file()


# -- point 2: derived defaults stay inside the project -------------------------------------------
@pytest.mark.parametrize("alg_id", ["match_model", "epipolar_pair"])
def test_a_model_name_cannot_lead_outside_products(block, alg_id, monkeypatch):
    text = (block / "project.toml").read_text()
    (block / "project.toml").write_text(text.replace('"0101_0102"', '"../../../x"'))
    alg = registry.get(alg_id)
    monkeypatch.setattr(type(alg), "run", _must_not_run)
    with pytest.raises(InputError):
        registry.run(alg_id, {"project": str(block), "model": "../../../x"})
    assert not (block.parent.parent / "x").exists()


# -- point 3: inputs are never overwritten -------------------------------------------------------
def test_orthorectify_onto_a_project_image_is_refused(block):
    before = tree_hash(block)
    with pytest.raises(InputError, match="images"):
        registry.run("orthorectify", {"project": str(block), "image": "0101",
                                      "dem": str(block / "truth/dsm.tif"),
                                      "output": str(block / "images/0101.tif")})
    assert tree_hash(block) == before


def test_mosaic_onto_its_input_or_another_product_is_refused(block, tmp_path):
    with pytest.raises(InputError, match="input"):
        registry.run("mosaic", {"inputs": [str(block / "truth/dsm.tif")],
                                "output": str(block / "truth/dsm.tif")})
    with pytest.raises(InputError, match="did not write"):
        registry.run("mosaic", {"inputs": [str(block / "truth/dsm.tif")],
                                "output": str(block / "truth/dtm.tif")})


def test_an_output_that_contains_an_input_is_refused(block, tmp_path):
    data = tmp_path / "data"
    data.mkdir()
    shutil.copy(block / "truth/dsm.tif", data / "dsm.tif")
    (data / PRODUCT_MARKER).write_text(json.dumps({"product": "dem_compare"}))
    with pytest.raises(InputError, match="contains the input"):
        registry.run("dem_compare", {"dem": str(data / "dsm.tif"),
                                     "reference": str(block / "truth/dtm.tif"),
                                     "output": str(data)})
    assert (data / "dsm.tif").is_file()


# -- same algorithm only -------------------------------------------------------------------------
def test_only_an_earlier_result_of_the_same_algorithm_is_replaced(tif_algs, tmp_path):
    out = tmp_path / "r.tif"
    registry.run("test_write_tif", {"output": str(out)})
    assert output_policy.file_product(out) == "test_write_tif"
    assert output_policy.file_product(out.with_name("r_report.json")) is None  # sidecar
    registry.run("test_write_tif", {"output": str(out)})  # a rerun replaces it
    with pytest.raises(InputError, match="product of 'test_write_tif'"):
        registry.run("test_other_tif", {"output": str(out)})
    assert output_policy.file_product(out) == "test_write_tif"


def test_a_folder_of_another_algorithm_is_refused(block, tmp_path):
    out = tmp_path / "cmp"
    out.mkdir()
    (out / "keep.txt").write_text("mine")
    (out / PRODUCT_MARKER).write_text(json.dumps({"product": "dem_profile"}))
    with pytest.raises(InputError, match="product of 'dem_profile'"):
        registry.run("dem_compare", {"dem": str(block / "truth/dsm.tif"),
                                     "reference": str(block / "truth/dtm.tif"),
                                     "output": str(out)})
    assert (out / "keep.txt").read_text() == "mine"


def test_a_sidecar_of_someone_else_is_refused(tif_algs, tmp_path):
    out = tmp_path / "r.tif"
    (tmp_path / "r_report.json").write_text("operator's notes")
    with pytest.raises(InputError, match=r"r_report\.json"):
        registry.run("test_write_tif", {"output": str(out)})
    assert not out.exists()


def test_a_product_without_its_mark_is_refused(tif_algs, tmp_path):
    out = tmp_path / "r.tif"
    write_raster(out, np.zeros((3, 3), np.float32))  # written outside a run: no tag
    with pytest.raises(InputError, match="did not write"):
        registry.run("test_write_tif", {"output": str(out)})


# -- bad output paths (point 6) ------------------------------------------------------------------
def test_wrong_kinds_and_bad_paths(tif_algs, block, tmp_path, monkeypatch):
    (tmp_path / "folder.tif").mkdir()
    with pytest.raises(InputError, match="is a folder, but a file is expected"):
        registry.run("test_write_tif", {"output": str(tmp_path / "folder.tif")})
    (tmp_path / "file").write_text("x")
    with pytest.raises(InputError, match="is a file, but a folder is expected"):
        registry.run("dem_compare", {"dem": str(block / "truth/dsm.tif"),
                                     "reference": str(block / "truth/dtm.tif"),
                                     "output": str(tmp_path / "file")})
    with pytest.raises(InputError, match="which is a file"):
        registry.run("test_write_tif", {"output": str(tmp_path / "file" / "r.tif")})
    monkeypatch.chdir(tmp_path)
    with pytest.raises(InputError, match="working"):
        registry.run("dem_compare", {"dem": str(block / "truth/dsm.tif"),
                                     "reference": str(block / "truth/dtm.tif"),
                                     "output": "."})
    assert not list(tmp_path.glob(".*partial*"))


def test_output_checks_come_before_the_work(block, tmp_path, monkeypatch):
    out = tmp_path / "busy"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    alg = registry.get("filter_lowpass")
    monkeypatch.setattr(type(alg), "run", _must_not_run)
    with pytest.raises(InputError, match="did not write"):
        registry.run("filter_lowpass", {"input": str(block / "truth/dsm.tif"),
                                        "output": str(out)})


# -- every algorithm: a forbidden output is refused before run is entered ------------------------
def _must_not_run(self, params, feedback):
    raise AssertionError(f"{self.id}.run was entered although its output is forbidden")


def _fill(alg: Algorithm, block: Path) -> dict:
    """Plausible values for the required parameters (inputs from the tiny project)."""
    values = {}
    by_kind = {
        "project": str(block), "model": "0101_0102", "image": "0101",
        "raster": str(block / "truth/dsm.tif"), "vector": str(block / "edits.gpkg"),
        "file": str(block / "project.toml"), "folder": str(block / "images"),
        "multiple_rasters": [str(block / "truth/dsm.tif")], "string": "x",
        "number": 1.0, "integer": 1, "crs": "EPSG:25832", "extent": "0,0,1,1",
        "bool": "false",
    }
    for p in alg.parameters:
        if p.is_output or not p.required:
            continue
        values[p.name] = p.options[0] if p.kind == "enum" else by_kind[p.kind]
    return values


def _output_algorithms():
    return sorted(a.id for a in registry.algorithms().values()
                  if any(p.is_output for p in a.parameters))


@pytest.mark.parametrize("alg_id", _output_algorithms())
def test_every_algorithm_refuses_a_forbidden_output_before_running(alg_id, block, monkeypatch):
    alg = registry.get(alg_id)
    monkeypatch.setattr(type(alg), "run", _must_not_run)
    values = _fill(alg, block)
    before = tree_hash(block)
    for p in alg.parameters:
        if not p.is_output:
            continue
        forbidden = block if p.kind == "output_folder" else block / "images" / "0101.tif"
        with pytest.raises(InputError) as info:
            registry.run(alg_id, {**values, p.name: str(forbidden)})
        message = str(info.value)
        assert p.name in message and ("project" in message or "input" in message), message
    assert tree_hash(block) == before


def test_a_sidecar_path_that_is_a_folder_is_refused_before_work(tif_algs, tmp_path):
    (tmp_path / "r_report.json").mkdir()
    with pytest.raises(InputError, match="is a folder, but a file is expected"):
        registry.run("test_write_tif", {"output": str(tmp_path / "r.tif")})
    assert not (tmp_path / "r.tif").exists()


def test_a_non_utf8_name_is_one_line(block, tmp_path, capsys):
    bad = str(tmp_path).encode() + b"/cmp\xff"
    code = cli.main(["run", "dem_compare", "--dem", str(block / "truth/dsm.tif"),
                     "--reference", str(block / "truth/dtm.tif"),
                     "--output", bad.decode("utf-8", "surrogateescape")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "not valid UTF-8" in err


def test_the_default_outputs_of_a_project_stay_in_products(block):
    for alg_id, values, expected in [
        ("match_model", {"model": "0101_0102"}, "products/dsm/0101_0102"),
        ("epipolar_pair", {"model": "0101_0102"}, "products/epipolar/0101_0102"),
        ("orthorectify", {"image": "0101", "dem": str(block / "truth/dsm.tif")},
         "products/ortho/0101.tif"),
        ("mosaic", {"dem": str(block / "truth/dsm.tif")}, "products/mosaic/mosaic.tif"),
        ("refine_object_space", {"dsm": str(block / "truth/dsm.tif")},
         "products/dsm_refined/dsm"),
    ]:
        alg = registry.get(alg_id)
        targets = alg.output_targets({"project": str(block), **values})
        assert targets[0].path == block / expected, alg_id
