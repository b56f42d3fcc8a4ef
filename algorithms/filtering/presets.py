"""Parameter presets of the DSM → DTM filters, in operator units (metres, per cent).

One ``default`` set serves all terrain types; ``flat``, ``hilly``, ``urban``, ``forest`` and
``steep`` are tuned variants. Options the operator gives override the preset's values.

Low-pass (:mod:`.lowpass`, the iterative "Phoenics" method, Raguse 2000 §3.3.1):

``windows_m``
    Side of the square smoothing window of every iteration (m), largest first. The largest
    window should be 2–3 × the largest building width; objects wider than about half the
    largest window survive (mark them as ``remove`` exclusion areas).
``thresholds_m``
    Height above the smoothed surface (m) beyond which a cell is an object, per iteration.
``down_threshold_m``
    Depth below the smoothed surface (m) beyond which a cell is a blunder (matching error); it
    grows by the same slope allowance as the height threshold (a plane lies above a valley
    as it lies below a ridge). Isolated pits are caught earlier by ``low_outlier_m``.
``low_outlier_m``
    Depth (m) below the second lowest neighbour (5 × 5 cells) beyond which a cell is a low
    blunder before the first iteration (slope-invariant net cut from below); 0 = off.
``slope_pct``
    Allowance for breaks of slope (ridges, hill tops, embankment edges in keep areas' vicinity):
    the threshold of an iteration grows by ``slope_pct/100 · window/4`` — the largest offset a
    least-squares plane over the window has at a ridge whose slopes differ by ``slope_pct`` %.
``final_smoothing_m``
    Window (m) of a last light smoothing of the ground cells ("interpolation with filtering":
    ground heights are not kept exactly); 0 = off.
``height_margin_m``
    Cells more than this below the 0.5 % or above the 99.5 % height quantile of the DSM are
    blunders before the first iteration.
``ground_tolerance_m``
    Points within this of the DTM are labelled ground (point input) on flat terrain.
``ground_slope_factor``
    The tolerance grows by this factor × local DTM slope × grid spacing (SMRF-style elevation
    threshold; the DTM misses slope × spacing between its nodes on steep terrain).
``refine_radius_m``, ``refine_tolerances_m``
    ``steep`` only: after the iterations, remaining cells more than each tolerance in turn
    above the least-squares plane through the remaining cells within ± ``refine_radius_m``
    are eliminated (shrubs and low crowns among sparse ground returns,
    :mod:`.steep_ground`).
``trend_window_m``
    ``steep`` only: the holes are filled as a local plane trend (window of this side) plus the
    membrane fill of the residuals, so the DTM follows the slope across gaps and at the border.
"""

from __future__ import annotations

from typing import Any, Dict

from ..errors import InputError

#: Low-pass presets (see the module notes for the meaning of every entry).
LOWPASS_PRESETS: Dict[str, Dict[str, Any]] = {
    "default": {
        "windows_m": (60.0, 40.0, 20.0, 10.0),
        "thresholds_m": (2.5, 1.5, 1.0, 0.5),
        "down_threshold_m": 8.0,
        "slope_pct": 20.0,
        "final_smoothing_m": 3.0,
        "height_margin_m": 10.0,
        "ground_tolerance_m": 0.5,
        "low_outlier_m": 1.5,
        "ground_slope_factor": 1.25,
    },
    "flat": {
        "windows_m": (60.0, 40.0, 20.0, 10.0),
        "thresholds_m": (2.0, 1.0, 0.6, 0.3),
        "down_threshold_m": 3.0,
        "slope_pct": 5.0,
        "final_smoothing_m": 3.0,
        "height_margin_m": 5.0,
        "ground_tolerance_m": 0.3,
        "low_outlier_m": 1.0,
        "ground_slope_factor": 1.0,
    },
    "hilly": {
        "windows_m": (60.0, 40.0, 20.0, 10.0),
        "thresholds_m": (3.0, 2.0, 1.0, 0.6),
        "down_threshold_m": 5.0,
        "slope_pct": 35.0,
        "final_smoothing_m": 3.0,
        "height_margin_m": 15.0,
        "ground_tolerance_m": 0.6,
        "low_outlier_m": 1.5,
        "ground_slope_factor": 1.25,
    },
    "urban": {
        "windows_m": (100.0, 60.0, 30.0, 15.0, 8.0),
        "thresholds_m": (2.5, 1.5, 1.0, 0.6, 0.4),
        "down_threshold_m": 4.0,
        "slope_pct": 15.0,
        "final_smoothing_m": 3.0,
        "height_margin_m": 10.0,
        "ground_tolerance_m": 0.5,
        "low_outlier_m": 1.5,
        "ground_slope_factor": 1.25,
    },
    "forest": {
        "windows_m": (120.0, 80.0, 40.0, 20.0, 10.0),
        "thresholds_m": (3.0, 2.0, 1.2, 0.8, 0.5),
        "down_threshold_m": 6.0,
        "slope_pct": 25.0,
        "final_smoothing_m": 5.0,
        "height_margin_m": 15.0,
        "ground_tolerance_m": 0.6,
        "low_outlier_m": 2.0,
        "ground_slope_factor": 1.25,
    },
    # steep: tuned on the synthetic steep forest (algorithms/synthetic/forest_scene.py, slopes
    # 31–45°, 93 % canopy, 4 % ground returns): no low-outlier cut (ground returns under a
    # closed canopy are isolated pits among crown returns), planes take the slope, so the
    # slope allowance covers curvature only (30 %, was 60 %) and the thresholds can be lower;
    # then the plane test (± 8 m) drops the shrubs and low crowns among the remaining cells
    # and the trend fill (30 m) follows the slope across gaps (.steep_ground): DTM RMS
    # 1.70 → 0.12 m on the small scene, 1.51 → 0.09 m on the bench scene
    "steep": {
        "windows_m": (40.0, 25.0, 15.0, 8.0),
        "thresholds_m": (2.5, 1.5, 1.0, 0.6),
        "down_threshold_m": 8.0,
        "slope_pct": 30.0,
        "final_smoothing_m": 3.0,
        "height_margin_m": 30.0,
        "ground_tolerance_m": 1.0,
        "low_outlier_m": 0.0,
        "ground_slope_factor": 1.5,
        "refine_radius_m": 8.0,
        "refine_tolerances_m": (1.5, 0.8, 0.5, 0.4),
        "trend_window_m": 30.0,
    },
}

#: Linear-prediction presets (:mod:`.linear_prediction`; keys are ``LPParameters`` fields):
#: ``coarse_spacing`` cell size (m) of the coarsest pyramid level (≈ the largest building or
#: wood that shrinks away by the two-lowest-cells reduction; larger ones are bridged);
#: ``half_weight`` residual (m) above the shift where the weight is ½; ``cutoff`` residual (m)
#: above the shift beyond which the weight is 0; ``low_cutoff`` depth (m) below the shift that
#: is a blunder; ``band_above``/``band_below`` (m) ground candidates around the coarser level's
#: DTM; ``slope`` (m/m) terrain allowance added to the cut-off and the band at every level
#: (``slope``·cell/2); ``shift_factor``/``max_shift`` shift g = −min(k·σ₋, g_max) (m);
#: ``iterations``/``fine_iterations`` robust iterations per level (coarse / the two finest);
#: ``ground_tolerance`` |DSM − DTM| (m) labelled ground, widened by ``ground_slope_factor``·slope·
#: cell on slopes; ``low_outlier`` depth (m) of a low blunder below its second lowest neighbour;
#: ``refine_radius``/``refine_tolerances``/``trend_window`` (``steep`` only): the plane test of
#: the ground cells and the trend fill of the DTM at the end (:mod:`.steep_ground`).
#: ``band_above`` 2 m in the default: on steep slopes the coarse levels may lie below the
#: ground; the fine levels' own robust weights then reject objects within the band.
LINEAR_PREDICTION_PRESETS: Dict[str, Dict[str, Any]] = {
    "default": {"coarse_spacing": 32.0, "half_weight": 0.5, "cutoff": 1.5, "low_cutoff": 5.0,
                "band_above": 2.0, "band_below": 5.0, "slope": 0.15, "shift_factor": 1.0,
                "max_shift": 0.5, "iterations": 4, "fine_iterations": 2,
                "ground_tolerance": 0.5,
               "low_outlier": 1.5, "ground_slope_factor": 1.25},
    "flat": {"coarse_spacing": 32.0, "half_weight": 0.2, "cutoff": 0.6, "low_cutoff": 3.0,
             "band_above": 0.6, "band_below": 3.0, "slope": 0.05, "shift_factor": 1.0,
             "max_shift": 0.3, "iterations": 4, "fine_iterations": 2, "ground_tolerance": 0.3,
            "low_outlier": 1.0, "ground_slope_factor": 1.0},
    "hilly": {"coarse_spacing": 32.0, "half_weight": 0.4, "cutoff": 1.2, "low_cutoff": 5.0,
              "band_above": 1.5, "band_below": 5.0, "slope": 0.35, "shift_factor": 1.0,
              "max_shift": 0.5, "iterations": 4, "fine_iterations": 2, "ground_tolerance": 0.6,
             "low_outlier": 1.5, "ground_slope_factor": 1.25},
    "urban": {"coarse_spacing": 64.0, "half_weight": 0.3, "cutoff": 0.8, "low_cutoff": 4.0,
              "band_above": 0.8, "band_below": 4.0, "slope": 0.15, "shift_factor": 1.0,
              "max_shift": 0.5, "iterations": 4, "fine_iterations": 2, "ground_tolerance": 0.5,
             "low_outlier": 1.5, "ground_slope_factor": 1.25},
    "forest": {"coarse_spacing": 64.0, "half_weight": 0.3, "cutoff": 1.0, "low_cutoff": 6.0,
               "band_above": 1.0, "band_below": 6.0, "slope": 0.25, "shift_factor": 1.5,
               "max_shift": 1.0, "iterations": 5, "fine_iterations": 2,
               "ground_tolerance": 0.6,
              "low_outlier": 2.0, "ground_slope_factor": 1.25},
    # steep: tuned on the synthetic steep forest like the low-pass preset (no low-outlier cut;
    # the coarser levels' trend takes the slope: allowance 0.3, tighter weights; the same
    # plane test and trend fill at the end as low-pass: RMS 2.62 → 0.16 m small, 2.79 →
    # 0.06 m bench)
    "steep": {"coarse_spacing": 32.0, "half_weight": 0.3, "cutoff": 1.0, "low_cutoff": 8.0,
              "band_above": 1.0, "band_below": 8.0, "slope": 0.3, "shift_factor": 1.0,
              "max_shift": 1.0, "iterations": 4, "fine_iterations": 2, "ground_tolerance": 1.0,
             "low_outlier": 0.0, "ground_slope_factor": 1.5, "refine_radius": 8.0,
             "refine_tolerances": (1.5, 0.8, 0.5, 0.4), "trend_window": 30.0},
}

#: Preset names, in the order the GUIs list them.
PRESET_NAMES = ("default", "flat", "hilly", "urban", "forest", "steep")

#: What the filter algorithms offer: the named presets and ``auto`` (the default, chosen from
#: the input's slope and vegetation share, :mod:`.auto_preset`; last, so that the positions of
#: the older names stay).
FILTER_PRESET_CHOICES = PRESET_NAMES + ("auto",)


def preset(table: Dict[str, Dict[str, Any]], name: str) -> Dict[str, Any]:
    """A copy of preset ``name`` of ``table``.

    Raises
    ------
    InputError
        For an unknown name (the message lists the known ones).
    """
    key = (name or "default").strip().lower()
    if key not in table:
        raise InputError.of("Unknown preset '{name}'; use one of {options}.", name=name,
                            options=", ".join(table))
    return dict(table[key])


def lowpass_preset(name: str = "default") -> Dict[str, Any]:
    """A copy of the low-pass preset ``name``."""
    return preset(LOWPASS_PRESETS, name)


def linear_prediction_preset(name: str = "default") -> Dict[str, Any]:
    """A copy of the linear-prediction preset ``name``."""
    return preset(LINEAR_PREDICTION_PRESETS, name)


__all__ = ["FILTER_PRESET_CHOICES", "LINEAR_PREDICTION_PRESETS", "LOWPASS_PRESETS", "PRESET_NAMES",
           "linear_prediction_preset", "lowpass_preset", "preset"]
