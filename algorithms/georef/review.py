"""Operator review of a polygon georeferencing: control points on and off, pairs rejected,
manual points added, another transform — then the products written again.

A review starts from the folder that ``georeference_polygons`` wrote (``report.json``, the
image copy ``<name>_gcps.tif``) and needs nothing else. The points the operator switches off,
and those of rejected object pairs, become check points: they keep their residuals under the
new transform but do not influence it. Saving rewrites the folder's products (``.points``,
``gcps.gpkg``, the georeferenced image, the image with GCPs, the report); the automatic
result is kept as ``report_auto.json`` the first time, so nothing of it is lost.

Independent check points (surveyed, or read from a reference map) come from a text file
(:func:`read_check_points`). They never take part in the fit; the review reports their
residuals and RMSE separately from the check points the operator took out of the fit, and
saving keeps them (with the file's path) in the report's review section, so a later review
session sees them again. Points outside the image are skipped with a warning, not refused: a
file surveyed for a whole map sheet may cover more than one image.
"""

from __future__ import annotations

import json
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Set, Tuple, Union

import numpy as np
import pyproj

from ..errors import InputError
from ..feedback import Feedback
from ..jsonable import json_ready
from ..project.points_io import (
    COLUMN_NAMES,
    field_separator,
    find_column,
    numbered_lines,
    parse_number,
    split_fields,
)
from ..raster.io import staged_folder
from .fit import (
    KINDS,
    MIN_POINTS,
    TransformFit,
    fit_transform,
    inverse_for_resampling,
    points_summary,
    residual_fields,
    rmse,
)
from .products import (
    image_from_points_source,
    image_residuals,
    points_crs,
    product_paths,
    report_html,
    residual_png,
    transform_json,
    write_transform_products,
)
from .refinement import ControlPoint
from .result import GeorefResult

PathLike = Union[str, Path]
#: Pair index of a control point without an object pair: added by hand, or found by a stage
#: without pairs (keypoints, the area search's grid); :attr:`ReviewPoint.origin` tells which.
MANUAL = -1
#: Where a control point comes from: a verified object ``pair``, the keypoint stage's matched
#: patches (``keypoints``), the area-based search's ``grid``, or the operator (``manual``).
ORIGINS = ("pair", "keypoints", "grid", "manual")
#: The origin of the automatic points without a pair, by the stage that found them.
STAGE_ORIGINS = {"keypoints": "keypoints", "area": "grid"}

#: Header names (lower case) of a check-point file's columns. ``col``/``row``: this project's
#: image convention (pixel centres at integers, rows downwards); ``corner``: pixel corners at 0
#: as in QGIS ``.points`` files (line negative) or GDAL (line positive).
CHECK_COLUMNS: Dict[str, Tuple[str, ...]] = {
    "col": ("col", "column", "image_col", "image_column", "img_col", "spalte"),
    "row": ("row", "image_row", "img_row", "zeile"),
    "corner_col": ("sourcex", "pixelx", "pixel", "source_x", "pixel_x"),
    "corner_row": ("sourcey", "pixely", "line", "source_y", "pixel_y"),
    "x": ("mapx", "map_x", *COLUMN_NAMES["x"]),
    "y": ("mapy", "map_y", *COLUMN_NAMES["y"]),
    "id": COLUMN_NAMES["id"],
}


@dataclass
class ReviewPoint:
    """One control point: image (col, row; pixel centres at integers) → map (x, y)."""

    image: Tuple[float, float]
    map: Tuple[float, float]
    pair: int = MANUAL  # the verified object pair it comes from; MANUAL: none
    sharp: bool = False
    enabled: bool = True  # the operator's switch
    origin: str = "manual"  # one of ORIGINS

    @property
    def manual(self) -> bool:
        """Added by the operator (not a keypoint or grid point, which have no pair either)."""
        return self.origin == "manual"


@dataclass
class CheckPoint:
    """An independent check point: image (col, row; pixel centres at integers) → map (x, y).
    Never part of the fit."""

    id: str
    image: Tuple[float, float]
    map: Tuple[float, float]


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
    check_points: List[CheckPoint] = field(default_factory=list)  # independent, from a file
    check_file: Optional[str] = None
    check_skipped: List[str] = field(default_factory=list)  # ids outside the image

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
            raise InputError.of("A control point needs four finite numbers: column, row, X, "
                                "Y.")
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
            raise InputError.of("Unknown transform '{value}'; use {options}.", value=self.kind,
                                options=", ".join(KINDS))
        active = self.active()
        need = MIN_POINTS[self.kind]
        if active.sum() < need:
            raise InputError.of("The {kind} transform needs at least {need} active control "
                                "points; {count} are switched on.", kind=self.kind, need=need,
                                count=int(active.sum()))
        try:
            return fit_transform(self.image_xy(), self.map_xy(), self.kind,
                                 robust=self.drop_outliers, enabled=active)
        except (ValueError, np.linalg.LinAlgError) as exc:
            raise InputError.of("The active control points do not determine a {kind} "
                                "transform ({error}); switch on points spread over the image.",
                                kind=self.kind, error=exc) from exc

    def table(self, fit: Optional[TransformFit] = None) -> List[Dict[str, Any]]:
        """One row per point: coordinates, residuals (px, map units), its role.

        Roles: ``control`` (in the fit), ``outlier`` (dropped by the robust step), ``check``
        (switched off), ``rejected`` (its object pair is rejected).
        """
        fit = fit or self.fit()
        d_img = image_residuals(fit, self.image_xy(), fit.extras["all_residuals_map"])
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
                         "origin": p.origin,
                         "enabled": p.enabled, "role": role,
                         "dx_px": r["dx_map"] / fit.pixel_size,
                         "dy_px": r["dy_map"] / fit.pixel_size,
                         "dcol": float(d_img[k, 0]), "drow": float(d_img[k, 1]), **r})
        return rows

    def check_rmse(self, fit: TransformFit) -> Tuple[float, int]:
        """RMSE (map units) and count of the check points: the points the operator took out
        (switched off, or of a rejected pair) — not the outliers the robust step dropped."""
        res = fit.extras["all_residuals_map"][~self.active()]
        return rmse(res), len(res)

    def import_check_points(self, path: PathLike) -> List[str]:
        """Read independent check points from a file (:func:`read_check_points`); they
        replace those imported before. Returns the ids of the points skipped (outside the
        image; :func:`~.products.skipped_note` words them).

        Raises
        ------
        InputError
            The file cannot be read or holds no usable check point.
        """
        image = self.report.get("image", {})
        points, skipped = read_check_points(path, image.get("width"), image.get("height"),
                                            self.crs_wkt)
        self.check_points = points
        self.check_file = str(Path(path).resolve())
        self.check_skipped = skipped
        return skipped

    def independent_check(self, fit: TransformFit) -> Dict[str, Any]:
        """Residuals of the independent check points under ``fit``.

        Returns
        -------
        dict
            ``count``; ``rmse_m`` and ``rmse_px`` (NaN without points); ``points``: per point
            id, col, row, x, y, residuals (fitted − measured) in map units and pixels as in
            :func:`~.fit.points_summary`, and ``dcol``/``drow`` (the residual in the image,
            for drawing).
        """
        img = np.array([p.image for p in self.check_points], float).reshape(-1, 2)
        mp = np.array([p.map for p in self.check_points], float).reshape(-1, 2)
        if not len(img):
            return {"count": 0, "rmse_m": float("nan"), "rmse_px": float("nan"), "points": []}
        res = fit.forward(img) - mp
        d_img = image_residuals(fit, img, res)
        points = [{"id": p.id, "col": p.image[0], "row": p.image[1], "x": p.map[0],
                   "y": p.map[1], **residual_fields(r, fit.pixel_size),
                   "dcol": float(di[0]), "drow": float(di[1])}
                  for p, r, di in zip(self.check_points, res, d_img)]
        e = rmse(res)
        return {"count": len(points), "rmse_m": e, "rmse_px": e / fit.pixel_size,
                "points": points}


# -- independent check points from a file -------------------------------------------------------
def read_check_points(path: PathLike, width: Optional[int] = None,
                      height: Optional[int] = None, crs_wkt: Optional[str] = None
                      ) -> Tuple[List[CheckPoint], List[str]]:
    """Independent check points from a CSV/TXT file with a header.

    The separator is a comma, semicolon, tab or whitespace (with a semicolon or tab, a decimal
    comma is read as a point); ``#`` starts a comment. The
    columns are found by name (:data:`CHECK_COLUMNS`): image ``col,row`` (pixel centres at
    integers, rows downwards) or ``pixel,line`` / ``sourceX,sourceY`` / ``pixelX,pixelY``
    (pixel corners at 0, as in a QGIS Georeferencer ``.points`` file — there the line is
    negative; all lines ≥ 0 are taken as GDAL's downward lines); map ``x,y`` (or ``mapX,mapY``,
    ``easting,northing`` …); an optional ``id``. Other columns (a ``.points`` file's
    ``enable``, residuals) are ignored: every row is a check point.

    Parameters
    ----------
    width, height : int, optional
        The image size: points outside the image are skipped with a warning.
    crs_wkt : str, optional
        The result's CRS: a ``#CRS:`` line (``.points`` file) must name the same CRS.

    Returns
    -------
    points, skipped
        The check points inside the image, and the ids of those outside it.

    Raises
    ------
    InputError
        A missing file, no header, missing columns, a non-numeric value, no rows, another
        CRS, or no point inside the image.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError.of("The check-point file '{path}' does not exist.", path=path)
    text = path.read_text(encoding="utf-8-sig", errors="replace")
    crs_line, lines = points_crs(text), numbered_lines(text)
    if not lines:
        raise InputError.of("The check-point file '{name}' holds no check points.",
                            name=path.name)
    sep = field_separator(lines[0][1])
    header = split_fields(lines[0][1], sep)
    columns, corner = _check_columns(path.name, header)
    ids, values = _check_values(path.name, lines[1:], sep, header, columns)
    if not ids:
        raise InputError.of("The check-point file '{name}' has a header but no check points.",
                            name=path.name)
    col, row, x, y = values.T
    if corner:
        col, row = _corner_to_image(path.name, col, row)
    if crs_line and crs_wkt:
        _check_crs(path.name, crs_line, crs_wkt)
    points = [CheckPoint(i, (float(c), float(r)), (float(u), float(v)))
              for i, c, r, u, v in zip(ids, col, row, x, y)]
    return _inside_image(path.name, points, width, height)


def _check_columns(name: str, header: Sequence[str]) -> Tuple[List[Optional[int]], bool]:
    """Indices of id, col, row, x, y in the header, and whether col/row are corner-based."""
    if all(parse_number(t) is not None for t in header if t):
        raise InputError.of("'{name}' has no header line; the first line must name the "
                            "columns, e.g. col,row,x,y or pixel,line,mapX,mapY.", name=name)
    find = {key: find_column(header, names) for key, names in CHECK_COLUMNS.items()}
    corner = find["col"] is None or find["row"] is None
    col, row = (find["corner_col"], find["corner_row"]) if corner else (find["col"], find["row"])
    missing = [label for label, idx in (("image column", col), ("image row", row),
                                        ("map x", find["x"]), ("map y", find["y"]))
               if idx is None]
    if missing:
        raise InputError.of("The header of '{name}' lacks {missing} (found: {found}); name "
                            "the columns col,row,x,y or pixel,line,mapX,mapY.", name=name,
                            missing=", ".join(missing), found=", ".join(header))
    return [find["id"], col, row, find["x"], find["y"]], corner


def _check_values(name: str, lines: Sequence[Tuple[int, str]], sep: Optional[str],
                  header: Sequence[str], columns: Sequence[Optional[int]]
                  ) -> Tuple[List[str], np.ndarray]:
    """Ids and (col, row, x, y) of the data lines; a bad value names its line and column."""
    cid, *idx = columns
    # a semicolon or tab file may come from a spreadsheet with decimal commas (German locale)
    comma = sep in (";", "\t")
    ids: List[str] = []
    values: List[List[float]] = []
    for number, text in lines:
        tokens = split_fields(text, sep)
        row: List[float] = []
        for c in idx:
            token = tokens[c] if c < len(tokens) else ""
            value = parse_number(token.replace(",", ".") if comma else token)
            if value is None:
                raise InputError.of("'{name}' line {number}: {column} '{token}' is not a "
                                    "number.", name=name, number=number, column=header[c],
                                    token=token)
            row.append(value)
        ids.append(tokens[cid] if cid is not None and cid < len(tokens) and tokens[cid]
                   else str(number))
        values.append(row)
    return ids, np.array(values, float).reshape(-1, 4)


def _corner_to_image(name: str, col: np.ndarray, row: np.ndarray
                     ) -> Tuple[np.ndarray, np.ndarray]:
    """Corner-based pixel/line → image col/row: QGIS's negative lines through the
    ``.points`` convention, GDAL's positive lines as their negatives."""
    if (row > 0).any() and (row < 0).any():
        raise InputError.of("'{name}': the line column mixes positive and negative values; a "
                            "QGIS .points file has negative lines, a GDAL list positive ones.",
                            name=name)
    return image_from_points_source(col, row if (row <= 0).all() else -row)


def _check_crs(name: str, crs_line: str, crs_wkt: str) -> None:
    """A ``.points`` file's CRS must be the result's (no reprojection of check points)."""
    try:
        same = pyproj.CRS.from_user_input(crs_line).equals(pyproj.CRS.from_wkt(crs_wkt),
                                                           ignore_axis_order=True)
    except pyproj.exceptions.CRSError:
        return  # an unreadable CRS comment: trust the operator, as for files without one
    if not same:
        raise InputError.of("'{name}' is in another CRS than the georeferencing result; "
                            "export the check points in the result's CRS.", name=name)


def _inside_image(name: str, points: List[CheckPoint], width: Optional[int],
                  height: Optional[int]) -> Tuple[List[CheckPoint], List[str]]:
    """The points inside the image (pixel edges included), and the ids of the others."""
    if not width or not height:
        return points, []
    ok = [-0.5 <= p.image[0] <= width - 0.5 and -0.5 <= p.image[1] <= height - 0.5
          for p in points]
    inside = [p for p, k in zip(points, ok) if k]
    if not inside:
        raise InputError.of("None of the {count} check points in '{name}' lies in the image "
                            "({width} × {height} pixels); col,row count pixel centres from 0, "
                            "pixel,line are QGIS .points coordinates.", count=len(points),
                            name=name, width=width, height=height)
    return inside, [p.id for p, k in zip(points, ok) if not k]


def _origin(pair: int, manual: bool, stage: Optional[str]) -> str:
    """The origin of a stored point (:data:`ORIGINS`): its pair, the saved review's list of
    manual points, else the stage that wrote the result (points without a pair of the
    keypoint stage and the area search; of other stages: added by hand)."""
    if pair != MANUAL:
        return "pair"
    if manual:
        return "manual"
    return STAGE_ORIGINS.get(stage or "", "manual")


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
        raise InputError.of("'{folder}' holds no georeferencing result (report.json and a "
                            ".points file); choose the output folder of 'Georeference image "
                            "against polygons'.", folder=folder)
    try:
        rep = json.loads(report_path.read_text(encoding="utf-8"))
        crs_wkt = points_crs(points[0].read_text(encoding="utf-8")) or ""
        manual = set(rep.get("review", {}).get("manual", []))
        pts = [ReviewPoint(tuple(g["image"]), tuple(g["map"]), int(g.get("pair", 0)),
                           bool(g.get("sharp", False)), bool(g.get("enabled", True)),
                           _origin(int(g.get("pair", 0)), k in manual, rep.get("stage")))
               for k, g in enumerate(rep["gcps"])]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise InputError.of("Cannot read the georeferencing result in '{folder}': {error}",
                            folder=folder, error=exc) from exc
    state = rep.get("review", {})
    icp = {int(r["pair"]): r for r in rep.get("icp", [])}
    pairs = [{"pair": k, **row, **{key: icp.get(k, {}).get(key) for key in
                                   ("overlap", "icp_rms_px", "iterations", "converged")}}
             for k, row in enumerate(rep.get("pairs", []))]
    check = state.get("independent_check") or {}
    return Review(folder=folder, name=points[0].stem, crs_wkt=crs_wkt, points=pts,
                  kind=state.get("transform", rep.get("transform", {}).get("kind", "affine")),
                  drop_outliers=bool(state.get("drop_outliers", True)),
                  rejected_pairs={int(p) for p in state.get("rejected_pairs", [])},
                  pairs=pairs, report=rep,
                  check_points=[CheckPoint(str(p["id"]), tuple(p["image"]), tuple(p["map"]))
                                for p in check.get("points", [])],
                  check_file=check.get("file"),
                  check_skipped=[str(i) for i in check.get("skipped", [])])


def save_review(review: Review, feedback: Optional[Feedback] = None,
                fit: Optional[TransformFit] = None) -> Dict[str, str]:
    """Write the folder's products again under the reviewed transform (atomically).

    The automatic result stays as ``report_auto.json``. ``fit``: the review's current
    :meth:`Review.fit`, if the caller has it (a dialog does), else it is computed. Returns
    the paths written.

    Raises
    ------
    InputError
        Too few active points (nothing is written then).
    """
    fb = feedback or Feedback()
    if fit is None:
        fit = review.fit()  # first: a bad state fails before anything is written
    folder, name = review.folder, review.name
    source = folder / f"{name}_gcps.tif"
    if not source.is_file():
        raise InputError.of("'{name}' is missing in '{folder}'; the review resamples that copy "
                            "of the image. Run the georeferencing again.", name=source.name,
                            folder=folder)
    gcps = [ControlPoint(p.image, p.map, 0.0, p.pair, p.sharp) for p in review.points]
    inverse_fit = inverse_for_resampling(fit, review.image_xy()[fit.used],
                                         review.map_xy()[fit.used])
    result = GeorefResult(fit=fit, inverse_fit=inverse_fit, gcps=gcps,
                          crs=pyproj.CRS.from_wkt(review.crs_wkt))
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
                     "check_rmse_m": None if not n_check else round(check_rmse, 4),
                     "independent_check": _independent_json(review, fit)}
    with staged_folder(folder, replace=True, product="georeference_polygons") as tmp:
        for keep in ("overlay.png", "report_auto.json"):
            if (folder / keep).is_file():
                shutil.copy2(folder / keep, tmp / keep)
        if auto:
            shutil.copy2(folder / "report.json", tmp / "report_auto.json")
        write_transform_products(tmp, source, result, name, fb)
        check = ((np.array([c.image for c in review.check_points], float),
                  np.array([c.map for c in review.check_points], float))
                 if review.check_points else None)
        residual_png(tmp / "residuals.png", result, rep["image"]["width"],
                     rep["image"]["height"], check=check)
        text = json.dumps(json_ready(rep), indent=1)
        (tmp / "report.json").write_text(text, encoding="utf-8")
        (tmp / "report.html").write_text(report_html(rep, name), encoding="utf-8")
    review.report = json.loads(text)
    return product_paths(folder, name)


def _independent_json(review: Review, fit: TransformFit) -> Optional[Dict[str, Any]]:
    """The report's record of the independent check points (``None`` without any)."""
    check = review.independent_check(fit)
    if not check["count"]:
        return None
    return {"file": review.check_file, "count": check["count"],
            "rmse_m": round(check["rmse_m"], 4), "rmse_px": round(check["rmse_px"], 5),
            "skipped": review.check_skipped,
            "points": [{"id": p["id"], "image": [p["col"], p["row"]], "map": [p["x"], p["y"]],
                        **{k: p[k] for k in ("dx_map", "dy_map", "residual_map",
                                             "residual_px")}}
                       for p in check["points"]]}
