"""Operator review of a polygon georeferencing: control points on and off, pairs rejected,
manual points added, another transform — then the products written again.

A review starts from the folder that ``georeference_polygons`` wrote (``report.json``, the
image copy ``<name>_gcps.tif``) and needs nothing else. The points the operator switches off,
and those of rejected object pairs, become check points: they keep their residuals under the
new transform but do not influence it. Saving rewrites the folder's products (``.points``,
``gcps.gpkg``, the georeferenced image, the image with GCPs, the report); the automatic
result is kept as ``report_auto.json`` the first time, so nothing of it is lost.
"""

from __future__ import annotations

import json
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Set, Tuple, Union

import numpy as np

from ..errors import InputError
from ..processing.feedback import Feedback
from .fit import KINDS, MIN_POINTS, TransformFit, fit_transform, points_summary

PathLike = Union[str, Path]
#: Pair index of a control point the operator added by hand.
MANUAL = -1


@dataclass
class ReviewPoint:
    """One control point: image (col, row; pixel centres at integers) → map (x, y)."""

    image: Tuple[float, float]
    map: Tuple[float, float]
    pair: int = MANUAL  # the verified object pair it comes from; MANUAL = added by hand
    sharp: bool = False
    enabled: bool = True  # the operator's switch

    @property
    def manual(self) -> bool:
        return self.pair == MANUAL


@dataclass
class Review:
    """The editable state of a georeferencing result."""

    folder: Path
    name: str
    crs_wkt: str
    points: List[ReviewPoint]
    kind: str = "affine"
    drop_outliers: bool = True
    rejected_pairs: Set[int] = field(default_factory=set)
    pairs: List[Dict[str, Any]] = field(default_factory=list)  # report rows + ICP figures
    report: Dict[str, Any] = field(default_factory=dict)

    def active(self) -> np.ndarray:
        """Points that may take part in the fit: switched on, pair not rejected."""
        return np.array([p.enabled and p.pair not in self.rejected_pairs for p in self.points],
                        dtype=bool)

    def image_xy(self) -> np.ndarray:
        return np.array([p.image for p in self.points], float).reshape(-1, 2)

    def map_xy(self) -> np.ndarray:
        return np.array([p.map for p in self.points], float).reshape(-1, 2)

    def add_point(self, image: Sequence[float], map_xy: Sequence[float]) -> ReviewPoint:
        """Add a manual control point (image col/row, map x/y in the result's CRS)."""
        vals = [float(v) for v in (*image, *map_xy)]
        if len(vals) != 4 or not np.all(np.isfinite(vals)):
            raise InputError("A control point needs four finite numbers: column, row, X, Y.")
        point = ReviewPoint((vals[0], vals[1]), (vals[2], vals[3]))
        self.points.append(point)
        return point

    def set_pair_rejected(self, pair: int, rejected: bool = True) -> None:
        if rejected:
            self.rejected_pairs.add(int(pair))
        else:
            self.rejected_pairs.discard(int(pair))

    def fit(self) -> TransformFit:
        """The transform from the active points; every point gets a residual.

        Raises
        ------
        InputError
            Too few active points for the transform, or a degenerate point geometry.
        """
        if self.kind not in KINDS:
            raise InputError(f"Unknown transform '{self.kind}'; use {', '.join(KINDS)}.")
        active = self.active()
        need = MIN_POINTS[self.kind]
        if active.sum() < need:
            raise InputError(f"The {self.kind} transform needs at least {need} active control "
                             f"points; {int(active.sum())} are switched on.")
        try:
            return fit_transform(self.image_xy(), self.map_xy(), self.kind,
                                 robust=self.drop_outliers, enabled=active)
        except (ValueError, np.linalg.LinAlgError) as exc:
            raise InputError(f"The active control points do not determine a {self.kind} "
                             f"transform ({exc}); switch on points spread over the image."
                             ) from exc

    def table(self, fit: Optional[TransformFit] = None) -> List[Dict[str, Any]]:
        """One row per point: coordinates, residuals (px, map units), its role.

        Roles: ``control`` (in the fit), ``outlier`` (dropped by the robust step), ``check``
        (switched off), ``rejected`` (its object pair is rejected).
        """
        fit = fit or self.fit()
        img = self.image_xy()
        # the residual in the image (for drawing): map residual through the local inverse
        # of the transform (finite differences: the same for every kind of transform)
        J = np.stack([fit.forward(img + [0.5, 0]) - fit.forward(img - [0.5, 0]),
                      fit.forward(img + [0, 0.5]) - fit.forward(img - [0, 0.5])], axis=-1)
        d_img = np.linalg.solve(J, fit.extras["all_residuals_map"][..., None])[..., 0]
        rows = []
        for k, (p, r) in enumerate(zip(self.points, points_summary(fit))):
            if p.pair in self.rejected_pairs:
                role = "rejected"
            elif not p.enabled:
                role = "check"
            else:
                role = "control" if r["used"] else "outlier"
            rows.append({"id": k, "col": p.image[0], "row": p.image[1], "x": p.map[0],
                         "y": p.map[1], "pair": p.pair, "manual": p.manual,
                         "enabled": p.enabled, "role": role,
                         "dx_px": r["dx_map"] / fit.pixel_size,
                         "dy_px": r["dy_map"] / fit.pixel_size,
                         "dcol": float(d_img[k, 0]), "drow": float(d_img[k, 1]), **r})
        return rows

    def check_rmse(self, fit: TransformFit) -> Tuple[float, int]:
        """RMSE (map units) and count of the check points: the points the operator took out
        (switched off, or of a rejected pair) — not the outliers the robust step dropped."""
        res = fit.extras["all_residuals_map"][~self.active()]
        if not len(res):
            return float("nan"), 0
        return float(np.sqrt(np.mean(np.sum(res * res, axis=1)))), len(res)


def load_review(folder: PathLike) -> Review:
    """The review state of a ``georeference_polygons`` output folder.

    Raises
    ------
    InputError
        The folder holds no georeferencing result.
    """
    folder = Path(folder)
    report_path = folder / "report.json"
    points = sorted(folder.glob("*.points"))
    if not report_path.is_file() or not points:
        raise InputError(f"'{folder}' holds no georeferencing result (report.json and a "
                         ".points file); choose the output folder of 'Georeference image "
                         "against polygons'.")
    try:
        rep = json.loads(report_path.read_text(encoding="utf-8"))
        crs_wkt = points[0].read_text(encoding="utf-8").splitlines()[0].removeprefix("#CRS: ")
        pts = [ReviewPoint(tuple(g["image"]), tuple(g["map"]), int(g.get("pair", 0)),
                           bool(g.get("sharp", False)), bool(g.get("enabled", True)))
               for g in rep["gcps"]]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise InputError(f"Cannot read the georeferencing result in '{folder}': {exc}") from exc
    state = rep.get("review", {})
    icp = {int(r["pair"]): r for r in rep.get("icp", [])}
    pairs = [{"pair": k, **row, **{key: icp.get(k, {}).get(key) for key in
                                   ("overlap", "icp_rms_px", "iterations", "converged")}}
             for k, row in enumerate(rep.get("pairs", []))]
    return Review(folder=folder, name=points[0].stem, crs_wkt=crs_wkt, points=pts,
                  kind=state.get("transform", rep.get("transform", {}).get("kind", "affine")),
                  drop_outliers=bool(state.get("drop_outliers", True)),
                  rejected_pairs={int(p) for p in state.get("rejected_pairs", [])},
                  pairs=pairs, report=rep)


def save_review(review: Review, feedback: Optional[Feedback] = None) -> Dict[str, str]:
    """Write the folder's products again under the reviewed transform (atomically).

    The automatic result stays as ``report_auto.json``. Returns the paths written.

    Raises
    ------
    InputError
        Too few active points (nothing is written then).
    """
    import pyproj

    from ..processing.spec import json_ready
    from ..raster.io import staged_folder
    from .products import (
        report_html,
        residual_png,
        transform_json,
        write_gcps_gpkg,
        write_georeferenced,
        write_points_file,
        write_with_gcps,
    )
    from .refinement import ControlPoint

    fb = feedback or Feedback()
    fit = review.fit()  # first: a bad state fails before anything is written
    folder, name = review.folder, review.name
    source = folder / f"{name}_gcps.tif"
    if not source.is_file():
        raise InputError(f"'{source.name}' is missing in '{folder}'; the review resamples that "
                         "copy of the image. Run the georeferencing again.")
    gcps = [ControlPoint(p.image, p.map, 0.0, p.pair, p.sharp) for p in review.points]
    inverse_fit = None
    if fit.kind == "poly2":  # no closed inverse: a map → image poly2 for resampling
        inverse_fit = fit_transform(review.map_xy()[fit.used], review.image_xy()[fit.used],
                                    "poly2", robust=False)
    result = {"fit": fit, "inverse_fit": inverse_fit, "gcps": gcps,
              "crs": pyproj.CRS.from_wkt(review.crs_wkt)}
    rep = dict(review.report)
    auto = rep.pop("review", None) is None  # no review yet: report.json is the automatic one
    check_rmse, n_check = review.check_rmse(fit)
    rep.update(transform=transform_json(result), rmse_px=fit.rmse_px, rmse_m=fit.rmse_map,
               sigma0_m=fit.sigma0, pixel_size_m=fit.pixel_size,
               gcps=[{"image": list(p.image), "map": list(p.map), "pair": p.pair,
                      "sharp": p.sharp, "enabled": p.enabled, **r}
                     for p, r in zip(review.points, points_summary(fit))])
    rep["counts"] = {**rep.get("counts", {}), "gcps": int(fit.used.sum())}
    rep["review"] = {"transform": review.kind, "drop_outliers": review.drop_outliers,
                     "rejected_pairs": sorted(review.rejected_pairs),
                     "switched_off": [k for k, p in enumerate(review.points) if not p.enabled],
                     "manual": [k for k, p in enumerate(review.points) if p.manual],
                     "check_points": n_check,
                     "check_rmse_m": None if not n_check else round(check_rmse, 4)}
    with staged_folder(folder, replace=True, product="georeference_polygons") as tmp:
        for keep in ("overlay.png", "report_auto.json"):
            if (folder / keep).is_file():
                shutil.copy2(folder / keep, tmp / keep)
        if auto:
            shutil.copy2(folder / "report.json", tmp / "report_auto.json")
        write_points_file(tmp / f"{name}.points", result)
        write_gcps_gpkg(tmp / "gcps.gpkg", result)
        write_georeferenced(tmp / f"{name}_georef.tif", source, result, feedback=fb)
        write_with_gcps(tmp / f"{name}_gcps.tif", source, result)
        residual_png(tmp / "residuals.png", result, rep["image"]["width"],
                     rep["image"]["height"])
        (tmp / "report.json").write_text(json.dumps(json_ready(rep), indent=1),
                                         encoding="utf-8")
        (tmp / "report.html").write_text(report_html(rep, name), encoding="utf-8")
    review.report = json.loads((folder / "report.json").read_text(encoding="utf-8"))
    return {"folder": str(folder), "points": str(folder / f"{name}.points"),
            "gcps": str(folder / "gcps.gpkg"), "image": str(folder / f"{name}_georef.tif"),
            "report": str(folder / "report.json"), "html": str(folder / "report.html")}
