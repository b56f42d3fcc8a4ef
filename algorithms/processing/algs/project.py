"""Algorithm declarations: project."""

from __future__ import annotations

ALGORITHMS: list = []
