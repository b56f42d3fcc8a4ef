"""Model set-up shared by the matchers: breakline validation, parallax per metre."""

from __future__ import annotations

import numpy as np
import pytest
from shapely.geometry import LineString, box

from photodem.algorithms.errors import InputError
from photodem.algorithms.geometry.camera import Camera
from photodem.algorithms.geometry.epipolar import EpipolarPair
from photodem.algorithms.geometry.orientation import ExteriorOrientation
from photodem.algorithms.matching.model_setup import ModelSetup, prepare_model
from photodem.algorithms.project.breaklines import check_breaklines
from photodem.algorithms.project.model import Project


def test_crossing_breaklines_are_refused() -> None:
    a = LineString([(0, 0, 1), (10, 10, 2)])
    b = LineString([(0, 10, 1), (10, 0, 2)])
    with pytest.raises(InputError, match=r"Breaklines 1 and 2 cross at \(5\.00, 5\.00\)"):
        check_breaklines([a, b])


def test_touching_breaklines_are_refused() -> None:
    a = LineString([(0, 0), (10, 0)])
    b = LineString([(5, 0), (5, 10)])  # T-junction: ends on the other line
    with pytest.raises(InputError, match="must not cross or touch"):
        check_breaklines([a, b])


def test_self_crossing_breakline_is_refused() -> None:
    a = LineString([(0, 0), (10, 10), (10, 0), (0, 10)])
    with pytest.raises(InputError, match="Breakline 1 crosses itself"):
        check_breaklines([a])


def test_continuing_and_separate_breaklines_pass() -> None:
    a = LineString([(0, 0), (10, 0)])
    b = LineString([(10, 0), (20, 5)])  # continues a
    c = LineString([(0, 5), (8, 5)])
    check_breaklines([a, b, c])


def _setup(base: float, height: float, overlap=None) -> ModelSetup:
    """A nadir model over the plane Z = 0: focal length 100 mm, pixels of 10 µm (c = 10 000
    px); only the pair, the flying height and the overlap are filled in."""
    cam = Camera("c", 2000, 1500, 100.0, (0.01, 0.01))
    eo_l = ExteriorOrientation.from_opk([0.0, 0.0, height], 0.0, 0.0, 0.0)
    eo_r = ExteriorOrientation.from_opk([base, 0.0, height], 0.0, 0.0, 0.0)
    pair = EpipolarPair.from_orientations(cam, eo_l, cam, eo_r, names=("l", "r"))
    return ModelSetup(project=None, model=None, records=[], cameras=[cam, cam], pair=pair,
                      z_min=-0.3 * height, z_max=0.3 * height, z_mid=0.0,
                      flying_height=height, gsd=height / 10000.0, spacing=height / 10000.0,
                      min_d=0, max_d=1, overlap=overlap, extent=None, grid=None)


def _disparity_per_metre(setup: ModelSetup, x: float, y: float, z: float = 0.0) -> float:
    """The pair's own disparity change for 1 m of height at (x, y), around ``z``."""
    pts = np.array([[x, y, z - 0.5], [x, y, z + 0.5]])
    col_l, _ = setup.pair.world_to_epipolar(pts, "left")
    col_r, _ = setup.pair.world_to_epipolar(pts, "right")
    return float(abs((col_l[1] - col_r[1]) - (col_l[0] - col_r[0])))


@pytest.mark.parametrize("base, height", [(300.0, 1000.0), (690.0, 1148.0), (60.0, 156.0)])
def test_parallax_per_metre_is_the_closed_form_and_the_pairs_own(base: float,
                                                                 height: float) -> None:
    """p = B·c / H² px per metre (= B / (GSD·H) with GSD = H / c), and what the pair's
    projection gives for a point raised by 1 m at the model's centre."""
    setup = _setup(base, height)
    ppm = setup.parallax_per_metre
    assert ppm == pytest.approx(base * 10000.0 / height ** 2, rel=1e-9)
    assert ppm == pytest.approx(base / (setup.gsd * height), rel=1e-9)
    pts = np.array([[0.5 * base, 10.0, 0.0], [0.5 * base, 10.0, 1.0]])
    col_l, _ = setup.pair.world_to_epipolar(pts, "left")
    col_r, _ = setup.pair.world_to_epipolar(pts, "right")
    d = col_l - col_r
    # p(Z) = B·c / Z: one metre up at Z = H changes it by B·c / (H·(H − 1))
    assert d[1] - d[0] == pytest.approx(ppm * height / (height - 1.0), rel=1e-6)


def test_parallax_per_metre_of_a_nadir_model_with_its_overlap_is_the_closed_form() -> None:
    setup = _setup(300.0, 1000.0, overlap=box(100.0, -50.0, 200.0, 50.0))
    assert setup.parallax_per_metre == pytest.approx(300.0 * 10000.0 / 1000.0 ** 2, rel=1e-6)


@pytest.mark.slow
def test_parallax_per_metre_of_convergent_models_is_measured_on_the_pair(drone_block) -> None:
    """Drone pairs (frames tilted 0–35° in different directions): the set-up gives the pair's
    own disparity change of 1 m at the overlap's centre; the nadir closed form B·c / H² would
    be more than 20 % off on some of them."""
    project = Project.load(drone_block)
    worst = 0.0
    for model in project.models:
        setup = prepare_model(project, model.name)
        c = setup.overlap.centroid
        measured = _disparity_per_metre(setup, c.x, c.y, setup.z_mid)
        assert setup.parallax_per_metre == pytest.approx(measured, rel=1e-9)
        closed = setup.pair.base * setup.pair.focal_px / setup.flying_height ** 2
        worst = max(worst, abs(closed / measured - 1.0))
    assert worst > 0.2
