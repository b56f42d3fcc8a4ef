"""Model set-up shared by the matchers: breakline validation, parallax per metre."""

from __future__ import annotations

import numpy as np
import pytest
from shapely.geometry import LineString

from photodem.algorithms.errors import InputError
from photodem.algorithms.geometry.camera import Camera
from photodem.algorithms.geometry.epipolar import EpipolarPair
from photodem.algorithms.geometry.orientation import ExteriorOrientation
from photodem.algorithms.matching.model_setup import ModelSetup
from photodem.algorithms.project.breaklines import check_breaklines


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


def _setup(base: float, height: float) -> ModelSetup:
    """A nadir model over the plane Z = 0: focal length 100 mm, pixels of 10 µm (c = 10 000
    px); only the pair and the flying height are filled in."""
    cam = Camera("c", 2000, 1500, 100.0, (0.01, 0.01))
    eo_l = ExteriorOrientation.from_opk([0.0, 0.0, height], 0.0, 0.0, 0.0)
    eo_r = ExteriorOrientation.from_opk([base, 0.0, height], 0.0, 0.0, 0.0)
    pair = EpipolarPair.from_orientations(cam, eo_l, cam, eo_r, names=("l", "r"))
    return ModelSetup(project=None, model=None, records=[], cameras=[cam, cam], pair=pair,
                      z_min=-0.3 * height, z_max=0.3 * height, z_mid=0.0,
                      flying_height=height, gsd=height / 10000.0, spacing=height / 10000.0,
                      min_d=0, max_d=1, overlap=None, extent=None, grid=None)


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
