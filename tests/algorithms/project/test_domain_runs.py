"""The project-level domain functions behind the thin declarations, called directly."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from photodem.algorithms.errors import InputError
from photodem.algorithms.feedback import Feedback
from photodem.algorithms.matching.epipolar_images import write_epipolar_pair
from photodem.algorithms.processing import registry
from photodem.algorithms.project.info import project_info
from photodem.algorithms.project.model import Project
from photodem.algorithms.project.stereo_models import run_stereo_models

pytestmark = pytest.mark.filterwarnings("ignore::rasterio.errors.NotGeoreferencedWarning")


@pytest.fixture(scope="module")
def tiny(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("tiny") / "block"
    registry.run("synthetic_block", {"output": str(root), "size": "tiny"})
    return root


def _copy(tiny: Path, tmp_path: Path) -> Path:
    dst = tmp_path / "block"
    shutil.copytree(tiny, dst)
    return dst


def test_project_info_lists_and_validates(tiny: Path) -> None:
    fb = Feedback()
    info = project_info(tiny, fb)
    assert len(info["images"]) == 6 and all(im["exists"] for im in info["images"])
    assert [m["name"] for m in info["models"]] == [m.name for m in Project.load(tiny).models]
    assert info["validation"]["errors"] == []


def test_run_stereo_models_manual_only(tiny: Path, tmp_path: Path) -> None:
    root = _copy(tiny, tmp_path)
    res = run_stereo_models(root, detect=False, manual="0101,0103; 0101,0103")
    assert res["count"] == 1 and res["models"][0]["kind"] == "manual"
    assert sorted(res["unpaired"]) == ["0102", "0201", "0202", "0203"]
    assert [m.name for m in Project.load(root).models] == [res["models"][0]["name"]]


def test_run_stereo_models_refuses_bad_input(tiny: Path, tmp_path: Path) -> None:
    root = _copy(tiny, tmp_path)
    before = (root / "project.toml").read_bytes()
    with pytest.raises(InputError, match="Minimum B/H"):
        run_stereo_models(root, b_h_range=(1.0, 0.5))
    with pytest.raises(InputError, match="two image names"):
        run_stereo_models(root, detect=False, manual="0101,0102,0103")
    assert (root / "project.toml").read_bytes() == before  # nothing saved


def test_write_epipolar_pair_matches_the_declaration(tiny: Path, tmp_path: Path) -> None:
    project = Project.load(tiny)
    model = project.models[0].name
    direct = write_epipolar_pair(project, model, tmp_path / "direct", 0.5, Feedback())
    declared = registry.run("epipolar_pair", {"project": str(tiny), "model": model,
                                              "scale": 0.5, "output": str(tmp_path / "alg")})
    assert direct["size"] == declared["size"]
    assert direct["y_parallax_check_px"] == declared["y_parallax_check_px"]
    for name in ("left.tif", "right.tif", "left_map.tif", "right_map.tif"):
        assert ((tmp_path / "direct" / name).read_bytes()
                == (tmp_path / "alg" / name).read_bytes())
