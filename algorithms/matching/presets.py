"""Strategy presets of the FBM + LSM model matcher (:mod:`.fbm_model`).

A module of plain data, so that the algorithm declarations can offer the presets without
importing the matcher and its surface and report modules (``photodem list`` stays fast).
"""

from __future__ import annotations

from typing import Any, Dict

#: Strategy presets (seed-000 §3.1: empirical parameter sets per terrain type). Keys are
#: fields of :class:`.hierarchy.FbmLsmOptions` or the surface options of
#: :func:`.fbm_model.match_model_fbm_lsm` (``groundel_gsd``, ``reduction``, ``smoothing``).
PRESETS: Dict[str, Dict[str, Any]] = {
    # open, gently undulating terrain: large windows and groundels, L1 planes, smooth surface
    "flat": {"fbm_window": 32, "groundel_gsd": 40.0, "reduction": "l1", "smoothing": 1.0},
    # hills: smaller windows follow the relief; medium groundels
    "hilly": {"fbm_window": 24, "groundel_gsd": 24.0, "reduction": "l1", "smoothing": 0.3},
    # buildings: small windows, tight bidirectional check, small groundels, median, little
    # smoothing so that roofs and walls stay sharp
    "urban": {"fbm_window": 16, "bidir_tol": 0.5, "groundel_gsd": 10.0,
              "reduction": "median", "smoothing": 0.05},
    # vegetation: the lower envelope of the points of a groundel is taken as the terrain
    "forest": {"fbm_window": 24, "groundel_gsd": 30.0, "reduction": "lower",
               "smoothing": 0.3},
}
PRESET_NAMES = tuple(PRESETS)
DEFAULT_PRESET = "flat"
#: Default DSM spacing in GSD; the presets' ``smoothing`` refers to cells of this size, so a
#: DSM asked for at another spacing gets the same surface, sampled differently.
SPACING_GSD = 2.0

POINT_FORMATS = ("gpkg", "las")

__all__ = ["DEFAULT_PRESET", "POINT_FORMATS", "PRESETS", "PRESET_NAMES", "SPACING_GSD"]
