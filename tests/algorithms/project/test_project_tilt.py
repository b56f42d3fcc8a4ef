"""Tilt is a fact, not an error: a 35° drone frame through project_create (registry and CLI),
a camera looking up refused, project_info's exit code with an error."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import rasterio

from photodem.algorithms import cli
from photodem.algorithms.errors import InputError
from photodem.algorithms.feedback import Feedback
from photodem.algorithms.processing import registry
from photodem.algorithms.project.model import Project

pytestmark = pytest.mark.filterwarnings("ignore::rasterio.errors.NotGeoreferencedWarning")
CAM_YAML = "c:\n  type: pinhole\n  im_size: [100, 80]\n  focal_len: 1.0\n  sensor_size: [1, 0.8]\n"


def inputs(tmp_path: Path, omega_b: float, phi_b: float = 0.0) -> dict:
    """Two 100 × 80 px images 150 m apart at 1000 m; image b tilted by (omega_b, phi_b)."""
    images = tmp_path / "images"
    images.mkdir(exist_ok=True)
    for name in ("a", "b"):
        with rasterio.open(images / f"{name}.tif", "w", driver="GTiff", width=100, height=80,
                           count=1, dtype="uint8") as dst:
            dst.write(np.zeros((1, 80, 100), np.uint8))
    (tmp_path / "cam.yaml").write_text(CAM_YAML)
    (tmp_path / "ext.csv").write_text(
        "filename,x,y,z,omega,phi,kappa\n"
        f"a,0,0,1000,0,0,0\nb,150,0,1000,{omega_b},{phi_b},0\n")
    return {"images": str(images), "exterior": str(tmp_path / "ext.csv"),
            "interior": str(tmp_path / "cam.yaml"), "crs": "EPSG:32633",
            "terrain_height": "0", "output": str(tmp_path / "p")}


def test_35_degree_frame_is_accepted_with_a_warning(tmp_path: Path) -> None:
    fb = Feedback()
    out = registry.run("project_create", inputs(tmp_path, 0.0, 35.0), fb)
    tilt = [w for w in out["warnings"] if "max_tilt" in w]
    assert len(tilt) == 1 and "'b'" in tilt[0] and "phi = 35.000°" in tilt[0]
    assert "angle unit" in tilt[0] and tilt[0] in fb.warnings
    assert Project.load(out["project"]).images[1].eo.opk()[1] == pytest.approx(35.0)
    info = registry.run("project_info", {"project": out["project"]}, Feedback())
    assert info["validation"]["errors"] == [] and len(info["validation"]["warnings"]) >= 1
    quiet = registry.run("project_info", {"project": out["project"], "max_tilt": 40.0},
                         Feedback())
    assert not any("max_tilt" in w for w in quiet["validation"]["warnings"])


def test_35_degree_frame_through_the_cli(tmp_path: Path, capsys) -> None:
    argv = ["run", "project_create"]
    for key, value in inputs(tmp_path, -35.0).items():
        argv += [f"--{key.replace('_', '-')}", value]
    assert cli.main(argv) == 0
    err = capsys.readouterr().err
    assert "omega = -35.000°" in err and "max_tilt" in err
    assert cli.main(["run", "project_info", "--project", str(tmp_path / "p"),
                     "--max-tilt", "36"]) == 0
    assert "max_tilt" not in capsys.readouterr().err


def test_camera_looking_up_is_refused(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="horizon"):
        registry.run("project_create", inputs(tmp_path, 100.0), Feedback())
    assert not (tmp_path / "p").exists()


def test_project_info_exits_2_with_an_error(tmp_path: Path, capsys) -> None:
    out = registry.run("project_create", inputs(tmp_path, 10.0), Feedback())
    (Path(out["project"]).parent / "images" / "b.tif").unlink()
    assert cli.main(["run", "project_info", "--project", out["project"]]) == 2
    err = capsys.readouterr().err
    assert "ERROR:" in err and "'b'" in err and "not found" in err
    assert "error:" in err.splitlines()[-1]
    with pytest.raises(InputError, match="not found"):
        registry.run("project_info", {"project": out["project"]}, Feedback())
