"""``dem_compare`` and ``point_compare``: the comparisons with all their files in one folder.

Each run stages its folder and renames it into place only when every file is written, so a
failed or cancelled run leaves nothing behind (and an earlier folder of the same algorithm
stays until the new one is complete).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Dict, Optional, Union

from ..feedback import Feedback, ensure_feedback
from ..raster.io import staged_folder
from .compare import class_names_of, compare_dems
from .names import report_path
from .objects import OBJECT_HEIGHT
from .points import point_compare
from .rasters import write_difference_style, write_hillshade, write_slope
from .report import write_completeness_csv, write_csv, write_json, write_report

PathLike = Union[str, Path]

#: Files of a ``dem_compare`` folder, by output name.
DEM_COMPARE_FILES = {"difference": "difference.tif", "hillshade": "hillshade.tif",
                     "slope": "slope.tif", "report": "report.html", "json": "stats.json",
                     "csv": "stats.csv"}
#: Completeness table of a ``dem_compare`` folder (with classes or a DTM only).
COMPLETENESS_FILE = "completeness.csv"


def _dem_compare_files(tmp: Path, dem: PathLike, reference: PathLike, result: Dict[str, Any],
                       flying_height: Optional[float], feedback: Feedback) -> None:
    """Style, hillshade, slope, statistics (JSON, CSV) and the HTML report into ``tmp``."""
    names = DEM_COMPARE_FILES
    write_difference_style(tmp / names["difference"])
    write_hillshade(dem, tmp / names["hillshade"], feedback=feedback.step(60.0, 68.0))
    write_slope(dem, tmp / names["slope"], feedback=feedback.step(68.0, 75.0))
    summary = {
        "dem": Path(dem).name,
        "reference": Path(reference).name,
        "dem_path": str(Path(dem).absolute()),
        "reference_path": str(Path(reference).absolute()),
        "flying_height": flying_height,
        **{k: v for k, v in result.items() if k != "difference"},
        "files": {k: v for k, v in names.items() if k != "json"},
    }
    write_json(tmp / names["json"], summary)
    write_csv(tmp / names["csv"], result, flying_height)
    if result.get("completeness"):
        write_completeness_csv(tmp / COMPLETENESS_FILE, result["completeness"])
    write_report(tmp / names["report"], result, dem=report_path(dem),
                 reference=report_path(reference), difference=tmp / names["difference"],
                 hillshade=tmp / names["hillshade"], flying_height=flying_height,
                 feedback=feedback.step(75.0, 99.0))


def run_dem_compare(dem: PathLike, reference: PathLike, output: PathLike, *,
                    coregister: bool = False, stable: Optional[PathLike] = None,
                    classes: Optional[PathLike] = None, class_field: Optional[str] = None,
                    flying_height: Optional[float] = None, dtm: Optional[PathLike] = None,
                    object_height: Optional[float] = None,
                    class_legend: Optional[PathLike] = None, window_size: int = 1024,
                    scheduler: str = "",
                    feedback: Optional[Feedback] = None) -> Dict[str, Any]:
    """Compare a DEM with a reference and write :data:`DEM_COMPARE_FILES` into ``output``.

    With classes or a DTM also :data:`COMPLETENESS_FILE`.

    Parameters
    ----------
    dem, reference, coregister, stable, classes, class_field, flying_height, dtm
        As :func:`.compare.compare_dems`.
    object_height : float, optional
        As :func:`.compare.compare_dems` (None: its default, 2.5 m).
    class_legend : path, optional
        Names of the codes of a class raster (:func:`.class_legend.read_class_legend`; by
        default the QGIS style beside the raster). The report shows "name (code)"; the
        statistics stay keyed by code, and ``class_names`` maps code → name.
    window_size, scheduler
        As :func:`.compare.compare_dems` (tiles, and where they run).
    output : path
        Output folder (an earlier ``dem_compare`` folder there is replaced).
    feedback : Feedback, optional

    Returns
    -------
    dict
        ``stats``, ``shift``, ``per_class``, ``per_slope`` (as :func:`.compare.compare_dems`)
        and the path of every file of :data:`DEM_COMPARE_FILES`.
    """
    feedback = ensure_feedback(feedback)
    out = Path(output)
    names = DEM_COMPARE_FILES
    legend = class_names_of(classes, class_legend)
    with staged_folder(out, replace=True, product="dem_compare") as tmp:
        result = compare_dems(
            dem, reference, coregister=coregister, stable=stable, classes=classes,
            class_field=class_field, flying_height=flying_height,
            difference_path=tmp / names["difference"], dtm=dtm,
            object_height=OBJECT_HEIGHT if object_height is None else float(object_height),
            window_size=window_size, scheduler=scheduler, feedback=feedback.step(0.0, 60.0))
        if legend:
            result["class_names"] = {k: legend[k] for k in result.get("per_class") or {}
                                     if k in legend}
        _dem_compare_files(tmp, dem, reference, result, flying_height, feedback)
    stats = result.get("stats") or {}
    feedback.info(f"Δh over {stats.get('count', 0)} cells: mean {stats.get('mean', 0):+.3f} "
                  f"m, NMAD {stats.get('nmad', 0):.3f} m, RMS {stats.get('rms', 0):.3f} m.")
    comp = result.get("completeness")
    if comp and comp.get("per_object"):
        o = comp["per_object"].get("object interior") or {}
        if o.get("cells"):
            feedback.info(f"Object interior: {100 * o['within_0_5']:.1f} % within 0.5 m of the "
                          f"reference, {100 * o['measured']:.1f} % measured.")
    return {
        "stats": result.get("stats"),
        "shift": result.get("shift"),
        "per_class": result.get("per_class"),
        "class_names": result.get("class_names"),
        "per_slope": result.get("per_slope"),
        "per_object": result.get("per_object"),
        "completeness": comp,
        **{k: str(out / v) for k, v in names.items()},
        "completeness_csv": str(out / COMPLETENESS_FILE) if comp else None,
    }


def run_point_compare(points: PathLike, dem: PathLike, output: PathLike, *,
                      flying_height: Optional[float] = None,
                      feedback: Optional[Feedback] = None) -> Dict[str, Any]:
    """Compare points with a DEM; ``residuals.csv``, ``stats.json``, ``stats.csv`` in ``output``.

    Parameters
    ----------
    points, dem, flying_height
        As :func:`.points.point_compare`.
    output : path
        Output folder (an earlier ``point_compare`` folder there is replaced).
    feedback : Feedback, optional

    Returns
    -------
    dict
        ``stats``, ``points``, ``used``, ``outside`` and the paths ``residuals``, ``json``,
        ``csv``.
    """
    feedback = ensure_feedback(feedback)
    out = Path(output)
    with staged_folder(out, replace=True, product="point_compare") as tmp:
        result = point_compare(points, dem, residuals_path=tmp / "residuals.csv",
                               flying_height=flying_height, feedback=feedback)
        summary = {"points_file": Path(points).name,
                   "dem": Path(dem).name, "flying_height": flying_height,
                   **{k: v for k, v in result.items() if k != "residuals"},
                   "files": {"residuals": "residuals.csv", "csv": "stats.csv"}}
        write_json(tmp / "stats.json", summary)
        write_csv(tmp / "stats.csv", {"stats": result["stats"]}, flying_height)
    stats = result["stats"]
    feedback.info(f"{result['used']} of {result['points']} points on the DEM: mean Δz "
                  f"{stats.get('mean', 0):+.3f} m, RMS {stats.get('rms', 0):.3f} m.")
    return {"stats": stats, "points": result["points"], "used": result["used"],
            "outside": result["outside"], "residuals": str(out / "residuals.csv"),
            "json": str(out / "stats.json"), "csv": str(out / "stats.csv")}


__all__ = ["COMPLETENESS_FILE", "DEM_COMPARE_FILES", "run_dem_compare", "run_point_compare"]
