"""Structure against content of ``project.toml`` (issue 16, point 6 follow-up).

A file whose *structure* is broken (no ``[project]`` table, an unsupported format version, a
value of the wrong type, a reference to an unknown camera or image, a name used twice) is
refused by ``Project.load`` with one line naming ``project.toml`` and the entry. A file whose
*content* is unusable (an unknown CRS, no images…) loads; ``validate_project`` reports it and
``project_info`` lists every error, then exits 2 naming the first.
"""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import List

import pytest

from photodem.algorithms import cli
from photodem.algorithms.errors import InputError
from photodem.algorithms.feedback import Feedback
from photodem.algorithms.processing import registry
from photodem.algorithms.project.model import Project
from photodem.algorithms.project.validate import ValidationReport, validate_project

HEAD = '[project]\nname = "x"\ncrs = "EPSG:25832"\n'


@pytest.fixture(scope="module")
def block(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("structure") / "p"
    registry.run("synthetic_block", {"output": str(root), "size": "tiny"})
    return root


def _copy(block: Path, tmp_path: Path) -> Path:
    p = tmp_path / "p"
    shutil.copytree(block, p)
    return p


def _edited(block: Path, tmp_path: Path, old: str, new: str, append: str = "") -> Path:
    """A copy of the project with the first ``old`` of project.toml replaced by ``new`` and
    ``append`` added at its end."""
    p = _copy(block, tmp_path)
    toml = p / "project.toml"
    text = toml.read_text(encoding="utf-8")
    assert old in text, old
    toml.write_text(text.replace(old, new, 1) + append, encoding="utf-8")
    return p


def _cli_error(p: Path, capsys) -> List[str]:
    """Run ``project_info`` on ``p`` through the CLI; assert exit 2 and one error line last;
    return the stderr lines."""
    code = cli.main(["run", "project_info", "--project", str(p)])
    lines = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert code == 2, lines
    assert not any("Traceback" in line for line in lines), lines
    errors = [line for line in lines if line.startswith("photodem: error:")]
    assert len(errors) == 1 and lines[-1] == errors[0], lines
    assert all(line.startswith("photodem: warning:") for line in lines[:-1]), lines
    return lines


IMAGE = ('\n[[images]]\nname = "0101"\npath = "images/0101.tif"\ncamera = "synthetic_tiny"\n'
         'position = [402273.0, 5674670.4, 127.5]\nopk = [0.0, 0.0, 0.0]\n')
MODEL = '\n[[models]]\nname = "0101_0102"\nleft = "0101"\nright = "0102"\nkind = "in-strip"\n'


# -- structure: refused at load ----------------------------------------------------------------
@pytest.mark.parametrize("old, new, append, words", [
    ('crs = "EPSG:25832"', "crs = 25832", "", ["[project]", "'crs'", "text in quotes"]),
    ("format_version = 1", "format_version = 99", "",
     ["'format_version' is 99", "newer PhotoDEM"]),
    ("format_version = 1", "format_version = 0", "", ["'format_version' is 0", "reads"]),
    ("format_version = 1", 'format_version = "1"', "", ["'format_version'", "number"]),
    ('left = "0101"', "left = 101", "", ["stereo model '0101_0102'", "'left'", "text"]),
    ('right = "0102"', 'right = "0102.tif"', "", ["stereo model '0101_0102'", "'0102.tif'",
                                                   "not defined in [[images]]"]),
    ('left = "0101"', 'left = "0102"', "", ["stereo model '0101_0102'", "both image '0102'"]),
    ('camera = "synthetic_tiny"', 'camera = "nocam"', "",
     ["image '0101'", "camera 'nocam'", "not defined in [cameras]", "synthetic_tiny"]),
    ('name = "0101"', "name = 101", "", ["[[images]] #1", "'name'", "text"]),
    ("[project]", "[project]", IMAGE, ["image name '0101'", "used already by [[images]] #1"]),
    ("[project]", "[project]", MODEL, ["stereo model name '0101_0102'",
                                       "used already by [[models]] #1"]),
])
def test_broken_structure_is_refused_at_load(block: Path, tmp_path: Path, old: str, new: str,
                                             append: str, words: List[str], capsys) -> None:
    p = _edited(block, tmp_path, old, new, append)
    with pytest.raises(InputError) as info:
        Project.load(p)
    text = str(info.value)
    assert "project.toml" in text and "\n" not in text, text
    for w in words:
        assert w in text, text
    lines = _cli_error(p, capsys)
    assert len(lines) == 1, lines  # refused before any validation warning


@pytest.mark.parametrize("content, words", [
    ("", ["no [project] table", "it is empty"]),
    ("# only a comment\n", ["no [project] table", "it is empty"]),
    ('[batch]\nproject = "x"\n', ["no [project] table", "not a PhotoDEM project file"]),
    ('images = 3\n' + HEAD, ["'images'", "array of tables"]),
    (HEAD + "[[images]]\nname = 1\n", ["[[images]] #1", "'name'", "text"]),
    (HEAD + "[cameras]\nc = 3\n", ["'c'", "must be a table"]),
])
def test_files_without_a_project_structure(tmp_path: Path, content: str, words: List[str],
                                           capsys) -> None:
    (tmp_path / "project.toml").write_text(content, encoding="utf-8")
    with pytest.raises(InputError) as info:
        Project.load(tmp_path)
    text = str(info.value)
    assert "project.toml" in text and "\n" not in text, text
    for w in words:
        assert w in text, text
    _cli_error(tmp_path, capsys)


def test_no_model_is_dropped_silently(block: Path, tmp_path: Path) -> None:
    """A model whose image is not text used to load as image '101' and leave 0101 and 0102
    "without a stereo partner"; now the file is refused, naming the model."""
    p = _edited(block, tmp_path, 'left = "0101"', "left = 101")
    with pytest.raises(InputError, match="stereo model '0101_0102'"):
        Project.load(p)


def test_a_sound_file_without_format_version_loads(block: Path, tmp_path: Path) -> None:
    p = _edited(block, tmp_path, "format_version = 1\n", "")
    assert Project.load(p).images


# -- content: loaded, reported by validation, project_info exits 2 -----------------------------
@pytest.mark.parametrize("old, new, error", [
    ('crs = "EPSG:25832"', 'crs = "EPSG:1"', "not understood by PROJ"),
    ('crs = "EPSG:25832"', 'crs = ""', "no CRS"),
    ('path = "images/0101.tif"', 'path = "images/none.tif"', "not found"),
])
def test_unusable_content_loads_and_project_info_fails(block: Path, tmp_path: Path, old: str,
                                                       new: str, error: str, capsys) -> None:
    p = _edited(block, tmp_path, old, new)
    project = Project.load(p)  # the structure is sound
    report = validate_project(project)
    assert len(report.errors) == 1 and error in report.errors[0], report.errors
    feedback = Feedback()
    with pytest.raises(InputError) as info:
        registry.run("project_info", {"project": str(p)}, feedback=feedback)
    text = str(info.value)
    assert text.startswith("The project has 1 error (listed above): ") and error in text
    assert any(w.startswith("ERROR: ") and error in w for w in feedback.warnings)
    lines = _cli_error(p, capsys)
    assert any(error in line for line in lines[:-1]), lines  # listed before the error line


def test_project_without_images(tmp_path: Path, capsys) -> None:
    (tmp_path / "project.toml").write_text(HEAD + "images_ = 3\n", encoding="utf-8")
    assert Project.load(tmp_path).images == []
    lines = _cli_error(tmp_path, capsys)
    assert "no images" in lines[-1], lines


def test_project_info_of_a_sound_project_still_succeeds(block: Path) -> None:
    info = registry.run("project_info", {"project": str(block)})
    assert info["validation"]["errors"] == [] and info["images"]


# -- ValidationReport --------------------------------------------------------------------------
def test_raise_if_errors_is_one_line() -> None:
    rep = ValidationReport(errors=["The project has no CRS.", "Image 'a': file 'x' not found."])
    with pytest.raises(InputError) as info:
        rep.raise_if_errors()
    assert str(info.value) == ("The project has 2 errors: The project has no CRS; "
                               "Image 'a': file 'x' not found.")
    ValidationReport(warnings=["w"]).raise_if_errors()  # warnings alone pass


def test_raise_first_error_names_the_count_and_the_first() -> None:
    rep = ValidationReport(errors=["first.", "second."])
    with pytest.raises(InputError, match=r"^The project has 2 errors \(listed above\): first\.$"):
        rep.raise_first_error()
    ValidationReport().raise_first_error()


# -- save: a file that load would refuse is never written --------------------------------------
def test_save_refuses_a_broken_structure(tmp_path: Path) -> None:
    from photodem.algorithms.geometry.camera import Camera
    from photodem.algorithms.geometry.orientation import ExteriorOrientation
    from photodem.algorithms.project.model import ImageRecord, StereoModel, structure_errors

    eo = ExteriorOrientation.from_opk([0.0, 0.0, 1000.0], 0.0, 0.0, 0.0)
    p = Project(root=tmp_path / "p", name="p", crs="EPSG:32633",
                cameras={"c": Camera("c", 100, 80, 1.0, (0.01, 0.01))},
                images=[ImageRecord("a", "a.tif", "c", eo), ImageRecord("b", "b.tif", "c", eo)],
                models=[StereoModel("a_b", "a", "b")])
    assert structure_errors(p) == []
    Project.load(p.save())  # sound: written and read back
    for broken, words in [
        (StereoModel("a_x", "a", "x"), "names image 'x'"),
        (StereoModel("a_a", "a", "a"), "on both sides"),
        (StereoModel("a_b", "b", "a"), "'a_b' is used 2 times"),
    ]:
        p.models.append(broken)
        with pytest.raises(InputError, match=words):
            p.save()
        p.models.pop()
    p.images.append(ImageRecord("c", "c.tif", "nocam", eo))
    with pytest.raises(InputError, match="names camera 'nocam'"):
        p.save()
    assert Project.load(p.root).images[-1].name == "b"  # the last sound file is kept
