"""Algorithm declarations: geometry."""

from __future__ import annotations

ALGORITHMS: list = []
