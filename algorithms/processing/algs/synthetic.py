"""Algorithm declarations: synthetic."""

from __future__ import annotations

ALGORITHMS: list = []
