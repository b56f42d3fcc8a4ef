"""Model set-up shared by the matchers: breakline validation."""

from __future__ import annotations

import pytest
from shapely.geometry import LineString

from photodem.algorithms.errors import InputError
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
