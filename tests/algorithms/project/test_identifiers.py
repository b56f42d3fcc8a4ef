"""Names that become path parts, and values of the wrong type in project.toml (issue 16, 2 and 6).

A model, image or camera name is a folder or file name later (``products/<model>/``), so one
that could leave its folder is refused when a project is loaded, saved or validated; a value of
the wrong type is refused at load time, naming the file, the entry and the key.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path
from typing import Pattern, Union

import numpy as np
import pytest

from photodem.algorithms import cli
from photodem.algorithms.errors import InputError
from photodem.algorithms.geometry.camera import Camera
from photodem.algorithms.geometry.orientation import ExteriorOrientation
from photodem.algorithms.processing import registry
from photodem.algorithms.project.model import (
    ImageRecord,
    Project,
    StereoModel,
    check_identifier,
    identifier_problem,
)
from photodem.algorithms.project.validate import validate_project

CAM = Camera("c", 100, 80, 1.0, (0.01, 0.01))


@pytest.fixture(scope="module")
def block(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("ids") / "p"
    registry.run("synthetic_block", {"output": str(root), "size": "tiny"})
    return root


def _copy_with(block: Path, tmp_path: Path, old: Union[str, Pattern[str]], new: str) -> Path:
    """A copy of the project whose project.toml has the first ``old`` (text or pattern)
    replaced by ``new``."""
    p = tmp_path / "p"
    shutil.copytree(block, p)
    toml = p / "project.toml"
    text = toml.read_text(encoding="utf-8")
    pattern = old if isinstance(old, re.Pattern) else re.compile(re.escape(old))
    assert pattern.search(text), old
    toml.write_text(pattern.sub(lambda _: new, text, count=1), encoding="utf-8")
    return p


# -- check_identifier --------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["0101_0102", "strip-1", "Bild 7", "ä_ö", "a.b"])
def test_usable_identifiers(name: str) -> None:
    assert check_identifier(name, "stereo model") == name
    assert identifier_problem(name) is None


@pytest.mark.parametrize("name, problem", [
    ("", "empty"),
    ("   ", "empty"),
    ("../../../x", "separator"),
    ("a/b", "separator"),
    ("a\\b", "separator"),
    (".", "'.' and '..'"),
    ("..", "'.' and '..'"),
    (".hidden", "starts with a dot"),
    ("a\nb", "control character"),
    ("a\x00b", "control character"),
    ("tab\there", "control character"),
    ("\udce9t\udce9", "UTF-8"),
    (12, "text"),
    (None, "text"),
])
def test_unusable_identifiers_are_refused(name: object, problem: str) -> None:
    with pytest.raises(InputError, match="stereo model") as info:
        check_identifier(name, "stereo model", "'p/project.toml'")
    text = str(info.value)
    assert problem in text and "\n" not in text and text.startswith("'p/project.toml'")


# -- at load, save and validation --------------------------------------------------------------
@pytest.mark.parametrize("old, new, words", [
    ('name = "0101_0102"', 'name = "../../../x"', ["stereo model", "../../../x"]),
    ('left = "0101"', 'left = "../0101"', ["image", "../0101"]),
    ('name = "0101"', 'name = "/etc"', ["image", "/etc"]),
    ('name = "0101"', 'name = ".."', ["image", "'..'"]),
    ('[cameras.synthetic_tiny]', '["cameras"."../cam"]', ["camera", "../cam"]),
    ('camera = "synthetic_tiny"', 'camera = "a/b"', ["camera", "a/b"]),
])
def test_path_names_are_refused_at_load(block: Path, tmp_path: Path, old: str, new: str,
                                        words: list) -> None:
    p = _copy_with(block, tmp_path, old, new)
    with pytest.raises(InputError) as info:
        Project.load(p)
    for w in words:
        assert w in str(info.value), str(info.value)
    assert "project.toml" in str(info.value)


def test_match_model_refuses_a_model_leaving_the_project(block: Path, tmp_path: Path,
                                                         capsys) -> None:
    """Issue 16, point 2: ``--model ../../../x`` never reaches a folder outside the project."""
    p = _copy_with(block, tmp_path, 'name = "0101_0102"', 'name = "../../../x"')
    outside = tmp_path / "x"
    outside.mkdir()
    (outside / "keep.txt").write_text("operator's file", encoding="utf-8")
    code = cli.main(["run", "match_model", "--project", str(p), "--model", "../../../x"])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err and err.count("photodem: error:") == 1, err
    assert "../../../x" in err
    assert (outside / "keep.txt").read_text(encoding="utf-8") == "operator's file"


def test_save_and_validation_refuse_path_names(tmp_path: Path) -> None:
    eo = ExteriorOrientation.from_opk([0.0, 0.0, 1000.0], 0.0, 0.0, 0.0)
    p = Project(root=tmp_path / "p", name="p", crs="EPSG:32633", cameras={"c": CAM},
                images=[ImageRecord("a", "a.tif", "c", eo), ImageRecord("b", "b.tif", "c", eo)])
    p.models = [StereoModel("../escape", "a", "b")]
    with pytest.raises(InputError, match="escape"):
        p.save()
    assert not (tmp_path / "p" / "project.toml").exists()
    rep = validate_project(p, check_files=False, stereo_partners=False)
    assert any("../escape" in e for e in rep.errors), rep.errors


# -- values of the wrong type ------------------------------------------------------------------
OPK = re.compile(r"opk = \[[^\]]*\]")  # the first image's (its digits vary by numpy)
POS = "position = [402273.01432063925, 5674670.423631551, 127.56881843801533]"


@pytest.mark.parametrize("old, new, words", [
    (OPK, 'opk = "abc"', ["image '0101'", "'opk'", "3 numbers"]),
    (OPK, "opk = [1.0, 2.0]", ["image '0101'", "'opk'", "3 numbers"]),
    (OPK, 'opk = [1.0, "x", 2.0]', ["'opk'"]),
    (OPK, "", ["image '0101'", "'opk' is missing"]),
    (POS, "position = [1, 2]", ["image '0101'", "'position'"]),
    (POS, "position = true", ["'position'"]),
    ('path = "images/0101.tif"', "path = 3.5", ["image '0101'", "'path'", "text"]),
    ('path = "images/0101.tif"', "", ["'path' is missing"]),
    ("width = 224", 'width = "224"', ["camera 'synthetic_tiny'", "'width'"]),
    ("width = 224", "width = 224.5", ["'width'", "whole number"]),
    ("focal_length_mm = 100.0", "", ["'focal_length_mm' is missing"]),
    ("focal_length_mm = 100.0", "focal_length_mm = -1.0", ["focal length"]),
    ("pixel_size_mm = [0.4017857142857143, 0.4017857142857143]", "pixel_size_mm = 0.4",
     ["'pixel_size_mm'", "2 numbers"]),
    ("terrain_height_m = 53.9", 'terrain_height_m = "high"', ["[project]",
                                                              "'terrain_height_m'"]),
    ('crs = "EPSG:25832"', "crs = 25832.5", ["'crs'", "text"]),
    ('angle_unit = "degrees"', 'angle_unit = "grad"', ["[project]", "angle unit"]),
    ("base_m = 27.2729", 'base_m = "long"', ["stereo model '0101_0102'", "'base_m'"]),
    ('left = "0101"', "left = [1]", ["'left'", "text"]),
    ("[project]", 'project = "x"\n[xproject]', ["'project'", "table"]),
    ('name = "synthetic', 'name = synthetic', ["not valid TOML"]),
])
def test_wrong_values_are_refused_at_load(block: Path, tmp_path: Path, old: str, new: str,
                                          words: list, capsys) -> None:
    p = _copy_with(block, tmp_path, old, new)
    with pytest.raises(InputError) as info:
        Project.load(p)
    text = str(info.value)
    for w in words:
        assert w in text, text
    assert "project.toml" in text and "\n" not in text
    # and through the CLI: one line, exit 2
    code = cli.main(["run", "project_info", "--project", str(p)])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err and err.count("photodem: error:") == 1, err


def test_project_toml_in_another_encoding(block: Path, tmp_path: Path) -> None:
    p = _copy_with(block, tmp_path, 'name = "synthetic', 'name = "Höhe synthetic')
    toml = p / "project.toml"
    toml.write_bytes(toml.read_text(encoding="utf-8").encode("latin-1"))
    with pytest.raises(InputError, match="not UTF-8"):
        Project.load(p)


def test_a_sound_project_loads_as_before(block: Path, tmp_path: Path) -> None:
    shutil.copytree(block, tmp_path / "p")
    project = Project.load(tmp_path / "p")
    assert [m.name for m in project.models][:1] == ["0101_0102"]
    assert project.terrain_height == pytest.approx(53.9, abs=50)
    again = Project.load(project.save())
    assert np.allclose(again.images[0].eo.rotation, project.images[0].eo.rotation)
