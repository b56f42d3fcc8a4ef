"""Algorithm declarations: quality control of DEMs."""

from __future__ import annotations

ALGORITHMS: list = []
