"""Strategy presets of the FBM + LSM model matcher (:mod:`.fbm_model`).

A module of plain data, so that the algorithm declarations can offer the presets without
importing the matcher and its surface and report modules (``photodem list`` stays fast).
"""

from __future__ import annotations

from typing import Any, Dict, Optional, Tuple

#: Strategy presets (seed-000 §3.1: empirical parameter sets per terrain type). Keys are
#: fields of :class:`.hierarchy.FbmLsmOptions` or the surface options of
#: :func:`.fbm_model.match_model_fbm_lsm` (``groundel_gsd``, ``reduction``, ``smoothing``,
#: ``objects``; ``object_height_m``: the grid densification's upward search in metres,
#: converted per model into ``object_search`` px; ``wall_offset_gsd``: automatic breaklines
#: this far from the upper point of a jump; ``jump_weak_slope``: jump edges grow by hysteresis
#: along edges of at least this height difference per metre, so the breakline closes round a
#: roof whose ground points lie far off, behind the wall; only along steps up to
#: ``object_height_m``).
PRESETS: Dict[str, Dict[str, Any]] = {
    # terrain only (was "flat"): large windows and groundels, L1 planes, smooth surface — a
    # DTM-like surface: buildings and trees are reduced away as outliers (issue 19)
    "terrain": {"fbm_window": 32, "groundel_gsd": 40.0, "reduction": "l1", "smoothing": 1.0},
    # hills: smaller windows follow the relief; medium groundels
    "hilly": {"fbm_window": 24, "groundel_gsd": 24.0, "reduction": "l1", "smoothing": 0.3},
    # the DSM default (issue 19): urban's object surface and finest-level pull-in, with
    # 32 px windows, 20-GSD groundels and ρ ≥ 0.55 — on open aerial terrain urban's 16 px
    # windows with the 20 px pull-in find clusters of wrong, mutually agreeing points
    # (0.21 ‰ H against 0.044 here); on the roofs of the small blocks as good (tuning table in
    # docs/decisions.md, "fbm_lsm keeps objects"); urban's upward search and wall placement
    # (below) as well: on the wide-angle aerial block the pull-in alone reaches no roof
    # (object interior 0.3 % on seed 1); the jump hysteresis keeps roofs out of the point-free
    # ring round buildings (open land of the small block, issue 19 part K)
    "general": {"fbm_window": 32, "bidir_tol": 0.5, "object_pull_in": 20.0, "rho_min": 0.55,
                "groundel_gsd": 20.0, "reduction": "median", "smoothing": 0.05,
                "objects": True, "object_height_m": 15.0, "wall_offset_gsd": 8.0,
                "jump_weak_slope": 0.7},
    # buildings: small windows, tight bidirectional check, small groundels, median, little
    # smoothing; groundel outliers that form a consistent upper surface stay,
    # and height jumps between points become breaklines (``objects``), so roofs and walls stay;
    # a level-0 pull-in of 20 px reaches roofs about 10 m above the ground plane of a window
    # at B/H ≈ 0.35 (issue 19: with the default 4–8 px roof points took the ground's disparity);
    # grid nodes not matched near the plane search up to 15 m above it in px of the model's
    # parallax (≈ 62 px on the wide-angle aerial block, where 20 px is only ≈ 5 m), and the
    # breaklines lie 8 GSD from the upper point of a jump (the ground behind a wall is hidden
    # from one image; halfway put walls 2–3 m out); the jump hysteresis as in general (on
    # since issue 19 part M: it no longer closes lines round roofs of a few barely supported
    # points, which had cost 3.5 points of roof on small seed 2)
    "urban": {"fbm_window": 16, "bidir_tol": 0.5, "object_pull_in": 20.0, "groundel_gsd": 10.0,
              "reduction": "median", "smoothing": 0.05, "objects": True,
              "object_height_m": 15.0, "wall_offset_gsd": 8.0, "jump_weak_slope": 0.7},
    # vegetation: the lower envelope of the points of a groundel is taken as the terrain
    "forest": {"fbm_window": 24, "groundel_gsd": 30.0, "reduction": "lower",
               "smoothing": 0.3},
}
PRESET_NAMES = tuple(PRESETS)
#: Old preset names still accepted (batch files); the run logs the new name.
PRESET_ALIASES: Dict[str, str] = {"flat": "terrain"}
#: The default keeps objects: a DSM is the surface with its buildings and trees (issue 19),
#: without spoiling open terrain.
DEFAULT_PRESET = "general"
#: Default DSM spacing in GSD; the presets' ``smoothing`` refers to cells of this size, so a
#: DSM asked for at another spacing gets the same surface, sampled differently.
SPACING_GSD = 2.0

POINT_FORMATS = ("gpkg", "las")



def resolve_preset(name: str) -> Tuple[str, Optional[str]]:
    """The preset a name stands for, and a deprecation note for an old name (else None)."""
    new = PRESET_ALIASES.get(name)
    if new is None:
        return name, None
    return new, (f"Preset '{name}' is now called '{new}' (a terrain preset: it removes "
                 f"buildings and trees); '{name}' will be dropped in a later version.")


__all__ = ["DEFAULT_PRESET", "POINT_FORMATS", "PRESETS", "PRESET_ALIASES", "PRESET_NAMES",
           "SPACING_GSD", "resolve_preset"]
