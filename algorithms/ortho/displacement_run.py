"""``ortho_displacement``: the predicted displacement and/or the measured shift in one folder.

The folder receives ``displacement.tif`` (predicted, :func:`.displacement.predict_displacement`),
``shifts.gpkg`` and ``shifts.csv`` (measured, :func:`.displacement.measure_shift`; with the
prediction sampled at every window when both are asked for) and ``summary.json``. It is staged
and renamed into place only when everything is written.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, Optional, Union

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from ..raster.io import staged_folder
from .displacement import (
    compare_shifts,
    measure_shift,
    predict_displacement,
    sample_prediction,
    write_shift_points,
)

PathLike = Union[str, Path]

#: Keys of the result, in the order of the algorithm's outputs.
RESULT_KEYS = ("displacement", "predicted", "points", "csv", "measured", "comparison", "json")


@dataclass
class DisplacementInputs:
    """What to analyse: the prediction's project, image and heights; the orthos to match.

    Attributes
    ----------
    project, image : optional
        Project (folder, project.toml or :class:`~..project.model.Project`) and image name of
        the predicted displacement.
    error, dem, reference : path, optional
        DEM error raster, or the DEM and the reference DEM (see
        :func:`.displacement.predict_displacement`).
    terrain_height : float, optional
        True height for H when only the error raster is given.
    ortho, reference_ortho : path, optional
        The orthos of the measured shift.
    """

    project: Any = None
    image: Optional[str] = None
    error: Optional[PathLike] = None
    dem: Optional[PathLike] = None
    reference: Optional[PathLike] = None
    terrain_height: Optional[float] = None
    ortho: Optional[PathLike] = None
    reference_ortho: Optional[PathLike] = None

    @property
    def predict(self) -> bool:
        """Is a predicted displacement asked for?"""
        return bool(self.image or self.error or (self.dem and self.reference))

    @property
    def measure(self) -> bool:
        """Is a measured shift asked for?"""
        return bool(self.ortho or self.reference_ortho)

    def check(self) -> None:
        """One-line errors for an incomplete request."""
        if not self.predict and not self.measure:
            raise InputError("Nothing to do: give an image with a DEM error (or DEM and "
                             "reference DEM) for the predicted displacement, and/or two orthos "
                             "('ortho', 'reference_ortho') for the measured shift.")
        if self.predict and not (self.project and self.image):
            raise InputError("The predicted displacement needs the project and the image.")
        if self.measure and not (self.ortho and self.reference_ortho):
            raise InputError("The measured shift needs two orthos: 'ortho' and "
                             "'reference_ortho'.")


@dataclass
class MatchSettings:
    """Matching of the measured shift (see :func:`.displacement.measure_shift`)."""

    window: int = 31
    radius: int = 8
    spacing: Optional[int] = None
    min_ncc: float = 0.6


def _predict_into(tmp: Path, inputs: DisplacementInputs, feedback: Feedback
                  ) -> Dict[str, Any]:
    """Write ``displacement.tif`` into the staging folder; its statistics for the summary."""
    pred = predict_displacement(
        inputs.project, inputs.image, tmp / "displacement.tif",  # type: ignore[arg-type]
        error=inputs.error, dem=inputs.dem, reference=inputs.reference,
        terrain_height=inputs.terrain_height, feedback=feedback)
    pred.pop("seconds", None)
    pred["displacement"] = "displacement.tif"
    return pred


def _measure_into(tmp: Path, inputs: DisplacementInputs, match: MatchSettings, predicted: bool,
                  summary: Dict[str, Any], feedback: Feedback) -> None:
    """Write ``shifts.gpkg`` and ``shifts.csv``; add ``measured`` (and ``comparison``)."""
    shifts = measure_shift(inputs.ortho, inputs.reference_ortho,  # type: ignore[arg-type]
                           spacing=match.spacing, window=match.window, radius=match.radius,
                           min_ncc=match.min_ncc, feedback=feedback)
    at = sample_prediction(tmp / "displacement.tif", shifts.x, shifts.y) if predicted else None
    write_shift_points(tmp / "shifts.gpkg", shifts, at)
    write_shift_points(tmp / "shifts.csv", shifts, at)
    summary["measured"] = shifts.summary()
    if at is not None:
        summary["comparison"] = compare_shifts(shifts, at)


def run_ortho_displacement(output: PathLike, inputs: DisplacementInputs,
                           match: Optional[MatchSettings] = None,
                           feedback: Optional[Feedback] = None) -> Dict[str, Any]:
    """Predicted displacement and/or measured shift into the folder ``output``.

    Parameters
    ----------
    output : path
        Output folder (an earlier ``ortho_displacement`` folder there is replaced).
    inputs : DisplacementInputs
        What to analyse; :meth:`DisplacementInputs.check` runs first.
    match : MatchSettings, optional
        Matching of the measured shift; default :class:`MatchSettings` ().
    feedback : Feedback, optional

    Returns
    -------
    dict
        :data:`RESULT_KEYS`: the paths written (``displacement``, ``points``, ``csv``,
        ``json``; None when not asked for) and the statistics ``predicted``, ``measured`` and
        ``comparison`` (as in ``summary.json``; None when absent).
    """
    feedback = ensure_feedback(feedback)
    match = match or MatchSettings()
    inputs.check()
    predict, measure = inputs.predict, inputs.measure
    out = Path(output)
    result: Dict[str, Any] = dict.fromkeys(RESULT_KEYS[:-1])
    with staged_folder(out, replace=True, product="ortho_displacement") as tmp:
        summary: Dict[str, Any] = {}
        if predict:
            summary["predicted"] = _predict_into(
                tmp, inputs, feedback.step(0.0, 40.0 if measure else 99.0))
            result.update(displacement=str(out / "displacement.tif"),
                          predicted=summary["predicted"])
        if measure:
            _measure_into(tmp, inputs, match, predict, summary,
                          feedback.step(40.0 if predict else 0.0, 95.0))
            result.update(points=str(out / "shifts.gpkg"), csv=str(out / "shifts.csv"),
                          measured=summary["measured"], comparison=summary.get("comparison"))
        (tmp / "summary.json").write_text(json.dumps(summary, indent=2), encoding="utf-8")
    result["json"] = str(out / "summary.json")
    m = result["measured"]
    if m and m.get("matched"):
        feedback.info(f"Measured shift over {m['matched']} windows: mean {m['mean_shift_m']} "
                      f"m ({m['mean_shift_px']} px), RMS {m['rms_shift_m']} m.")
    return result


__all__ = ["RESULT_KEYS", "DisplacementInputs", "MatchSettings", "run_ortho_displacement"]
