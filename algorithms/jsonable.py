"""Values made ready for ``json.dumps``: paths, numpy scalars and arrays, tuples, NaN.

Reports, run results and batch summaries are written as JSON; this is the one conversion they
share. A ground-floor module: it imports only the standard library.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any


def json_ready(value: Any) -> Any:
    """Convert paths, numpy scalars/arrays and tuples so that ``json.dumps`` accepts them."""
    if isinstance(value, dict):
        return {str(k): json_ready(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_ready(v) for v in value]
    if isinstance(value, Path):
        return str(value)
    if hasattr(value, "tolist"):  # numpy scalars and arrays
        return json_ready(value.tolist())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


__all__ = ["json_ready"]
