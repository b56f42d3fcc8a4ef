r"""Evaluation of a ground filter against reference labels (ISPRS filter test measures).

Sithole & Vosselman (2004, ISPRS J. Photogramm. Remote Sens. 59, 85–101) compare a filter's
ground/object classification with a manually labelled reference in a 2 × 2 table

==================  =====================  =====================
reference / filter  ground                 object
==================  =====================  =====================
ground              :math:`a`              :math:`b` (Type I)
object              :math:`c` (Type II)    :math:`d`
==================  =====================  =====================

with :math:`n = a + b + c + d` and

.. math::

   \text{Type I} = \frac{b}{a + b}, \qquad
   \text{Type II} = \frac{c}{c + d}, \qquad
   \text{total} = \frac{b + c}{n},

Type I = ground rejected / all ground, Type II = objects accepted as ground / all objects. Cohen's
kappa corrects the agreement :math:`p_0 = (a + d)/n` for the agreement expected by chance from
the two marginal distributions,

.. math::

   p_e = \frac{(a + b)(a + c) + (c + d)(b + d)}{n^2}, \qquad
   \kappa = \frac{p_0 - p_e}{1 - p_e},

so :math:`\kappa = 1` for a perfect classifier, :math:`\approx 0` for one independent of the
truth (random, or "everything is ground": :math:`p_0 = p_e`) and negative for worse than
chance: the inverted classifier (:math:`a = d = 0`, :math:`b = G`, :math:`c = O`) has
:math:`p_0 = 0`, :math:`p_e = 2GO/n^2` and :math:`\kappa = -2GO/(G^2 + O^2)`, −1 for balanced
classes. Undefined (NaN → ``null``) when :math:`p_e = 1` (both sides use one class only).
All measures are reported in percent, as in the ISPRS report.

Labels are 0 = ground, 1 = object (PhotoDEM's ``labels.txt`` / ``mask.tif`` and the ISPRS
reference files). Accepted inputs:

* text: one point per line, the label in the **last** column (or ``column``, 1-based; a header
  column named ``label``/``class``/``classification`` is found by name), fields separated by
  whitespace, commas, semicolons or tabs, ``#`` comments; e.g. PhotoDEM's ``labels.txt`` (one
  label per line) or the ISPRS ``X Y Z label`` files. Both files list the same points in the
  same order.
* rasters (``mask.tif``: uint8, 1 = object, 0 = ground, nodata ignored): counted window by
  window; a reference mask on another grid is read on the labels' grid (nearest cell).
* a labels raster against a reference text with coordinates (``X Y Z label``): the mask is
  sampled at the reference points (the cell containing each point).

Optionally the DTM is checked: against a reference DTM (:func:`..quality.compare.compare_dems`,
:math:`\Delta h = h_{DTM} - h_{ref}` on the reference grid) and/or, for a reference with
coordinates, at the reference ground points (bilinear DTM height minus the point height) — the
second needs no reference DTM, which the ISPRS samples do not have.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple, Union

import numpy as np
import rasterio
from numpy.typing import ArrayLike, NDArray
from rasterio.enums import Resampling
from rasterio.vrt import WarpedVRT
from rasterio.windows import Window

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from ..quality.compare import compare_dems
from ..quality.points import sample_dem
from ..quality.report import write_json
from ..quality.stats import difference_stats
from ..raster.io import staged_folder

PathLike = Union[str, Path]

#: File endings read as rasters (everything else is read as text).
RASTER_SUFFIXES = (".tif", ".tiff", ".vrt", ".img")
#: Header names of the label column (lower case).
LABEL_NAMES = ("label", "labels", "class", "classification")
#: DTM statistics copied into the report (see :func:`..quality.stats.difference_stats`).
DTM_KEYS = ("count", "mean", "std", "rms", "nmad", "median", "min", "max", "q95", "share_0_5")
#: Rows per window when counting raster labels.
WINDOW_ROWS = 1024

_SPLIT = re.compile(r"[,;\s]+")


# -- the confusion matrix -------------------------------------------------------------------------


@dataclass(frozen=True)
class Confusion:
    """The ISPRS 2 × 2 table: rows reference (ground, object), columns filter (ground, object).

    ``a`` ground kept, ``b`` ground rejected (Type I), ``c`` object accepted as ground
    (Type II), ``d`` object rejected.
    """

    a: int
    b: int
    c: int
    d: int

    @property
    def n(self) -> int:
        return self.a + self.b + self.c + self.d

    def __add__(self, other: Confusion) -> Confusion:
        return Confusion(self.a + other.a, self.b + other.b, self.c + other.c, self.d + other.d)

    @property
    def type_i(self) -> float:
        """b / (a + b): share of the reference ground the filter rejected (NaN without ground)."""
        return _ratio(self.b, self.a + self.b)

    @property
    def type_ii(self) -> float:
        """c / (c + d): share of the reference objects accepted as ground."""
        return _ratio(self.c, self.c + self.d)

    @property
    def total_error(self) -> float:
        """(b + c) / n."""
        return _ratio(self.b + self.c, self.n)

    @property
    def kappa(self) -> float:
        r"""Cohen's kappa :math:`(p_0 - p_e)/(1 - p_e)`; NaN when :math:`p_e = 1` or n = 0."""
        n = float(self.n)
        if n == 0:
            return float("nan")
        a, b, c, d = (float(v) for v in (self.a, self.b, self.c, self.d))
        p0 = (a + d) / n
        pe = ((a + b) * (a + c) + (c + d) * (b + d)) / (n * n)
        if pe >= 1.0:
            return float("nan")
        return (p0 - pe) / (1.0 - pe)

    def to_dict(self) -> Dict[str, Any]:
        """Counts and the measures in percent (NaN → None)."""
        out: Dict[str, Any] = {"n": self.n, "a": self.a, "b": self.b, "c": self.c, "d": self.d,
                               "reference_ground": self.a + self.b,
                               "reference_objects": self.c + self.d,
                               "labelled_ground": self.a + self.c,
                               "labelled_objects": self.b + self.d}
        for key, value in (("type_i_pct", self.type_i), ("type_ii_pct", self.type_ii),
                           ("total_error_pct", self.total_error), ("kappa_pct", self.kappa)):
            out[key] = None if not math.isfinite(value) else 100.0 * value
        out["accuracy_pct"] = None if self.n == 0 else 100.0 * (self.a + self.d) / self.n
        return out


def _ratio(num: int, den: int) -> float:
    return float(num) / float(den) if den else float("nan")


def confusion(labels: ArrayLike, reference: ArrayLike,
              valid: Optional[ArrayLike] = None) -> Confusion:
    """Count the 2 × 2 table of ``labels`` (filter) against ``reference`` (0 ground, 1 object).

    Parameters
    ----------
    labels, reference : array_like of int, same shape
        0 = ground, 1 = object.
    valid : array_like of bool, optional
        Only these entries are counted (e.g. cells with data in both).

    Returns
    -------
    Confusion
        With ``a`` = #(ref 0, lab 0), ``b`` = #(0, 1), ``c`` = #(1, 0), ``d`` = #(1, 1).
    """
    lab = np.asarray(labels)
    ref = np.asarray(reference)
    if lab.shape != ref.shape:
        raise InputError(f"The labels ({lab.size} values) and the reference ({ref.size} values) "
                         "differ in size; both must describe the same points or cells.")
    if valid is not None:
        m = np.asarray(valid, dtype=bool)
        lab, ref = lab[m], ref[m]
    # index 2·ref + lab: 0 = a, 1 = b, 2 = c, 3 = d
    counts = np.bincount((2 * ref.astype(np.int64) + lab.astype(np.int64)).ravel(),
                         minlength=4)
    return Confusion(int(counts[0]), int(counts[1]), int(counts[2]), int(counts[3]))


# -- reading labels -------------------------------------------------------------------------------


@dataclass
class LabelSet:
    """Labels read from a text file; ``xyz`` when the file also has coordinates."""

    labels: NDArray[np.int8]
    xyz: Optional[NDArray[np.float64]]
    column: int  # 0-based column the labels came from (−1 = last)


def _is_number(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def _check_values(values: NDArray[np.float64], path: Path, what: str) -> NDArray[np.int8]:
    bad = ~np.isin(values, (0.0, 1.0))
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise InputError(f"The {what} '{path.name}' holds the label {values[i]:g} (entry "
                         f"{i + 1}); labels must be 0 (ground) or 1 (object).")
    return values.astype(np.int8)


def read_label_text(path: PathLike, column: Optional[int] = None,
                    what: str = "labels") -> LabelSet:
    """Labels (0/1) from a text file, one point per line.

    Parameters
    ----------
    path : path
        Text with the label in the last column (or ``column``); a first line without numbers is
        a header, where a column named ``label``/``class``/``classification`` is the label.
    column : int, optional
        1-based column of the label; default: the named header column, else the last.
    what : str
        Name used in error messages ("labels", "reference").

    Returns
    -------
    LabelSet
        ``labels`` int8 (n,), ``xyz`` (n, 3) when the label is not among the first three
        columns and these are numbers on every line (the ISPRS ``X Y Z label`` format).

    Raises
    ------
    InputError
        Missing/unreadable file, too few columns, labels other than 0/1, no line at all.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"The {what} file '{path}' does not exist.")
    try:
        text = path.read_text(encoding="utf-8-sig", errors="replace")
    except OSError as exc:
        raise InputError(f"The {what} file '{path}' cannot be read ({exc}).") from None
    rows = [_SPLIT.split(s.strip()) for s in (line.split("#", 1)[0] for line in
                                               text.splitlines()) if s.strip()]
    if rows and not any(_is_number(t) for t in rows[0]):
        header = [t.strip("\"'").lower() for t in rows.pop(0)]
        if column is None:
            named = [i for i, t in enumerate(header) if t in LABEL_NAMES]
            if named:
                column = named[0] + 1
    if not rows:
        raise InputError(f"The {what} file '{path.name}' holds no labels (only comments, a "
                         "header or empty lines).")
    col = -1 if column is None else int(column) - 1
    if col < -1:
        raise InputError(f"The label column must be 1 or more, not {column}.")
    widths = np.fromiter((len(r) for r in rows), dtype=np.int64, count=len(rows))
    short = widths < (col + 1 if col >= 0 else 1)
    if short.any():
        i = int(np.flatnonzero(short)[0])
        raise InputError(f"Line {i + 1} of the {what} file '{path.name}' has only {widths[i]} "
                         f"column(s); the label column is {col + 1}.")
    try:
        values = np.array([r[col] for r in rows], dtype=np.float64)
    except ValueError:
        raise InputError(f"The {what} file '{path.name}' has a label that is not a number in "
                         f"column {'last' if col < 0 else col + 1}.") from None
    labels = _check_values(values, path, what)
    xyz = None
    label_at = col if col >= 0 else int(widths.min()) - 1
    if widths.min() >= 4 and label_at >= 3 and widths.min() == widths.max():
        try:
            xyz = np.array([r[:3] for r in rows], dtype=np.float64)
        except ValueError:
            xyz = None  # e.g. an id in the first column: labels only
    return LabelSet(labels, xyz, col)


def _is_raster(path: PathLike) -> bool:
    return Path(path).suffix.lower() in RASTER_SUFFIXES


def _open_mask(path: PathLike, what: str) -> Any:
    p = Path(path)
    if not p.exists():
        raise InputError(f"The {what} raster '{p}' does not exist.")
    try:
        return rasterio.open(p)
    except Exception as exc:  # rasterio raises several error types for unreadable files
        raise InputError(f"The {what} raster '{p}' cannot be read ({exc}).") from None


def _mask_values(block: Any, path: PathLike, what: str) -> Tuple[NDArray[Any], NDArray[Any]]:
    """(labels int64, valid bool) of a masked raster block; values other than 0/1 are an error."""
    data = np.ma.getdata(block)
    valid = ~np.ma.getmaskarray(block)
    if np.issubdtype(data.dtype, np.floating):
        valid &= np.isfinite(data)
    bad = valid & (data != 0) & (data != 1)
    if bad.any():
        raise InputError(f"The {what} raster '{Path(path).name}' holds the value "
                         f"{data[bad].flat[0]!s} (not nodata); a mask must be 0 (ground), "
                         "1 (object) or nodata.")
    return np.where(valid, data, 0).astype(np.int64), valid


def confusion_rasters(labels: PathLike, reference: PathLike,
                      feedback: Optional[Feedback] = None) -> Tuple[Confusion, Dict[str, Any]]:
    """The 2 × 2 table of two mask rasters, window by window on the labels' grid.

    The reference is read directly when it has the labels' grid, else through a ``WarpedVRT``
    (nearest cell) onto it. Cells that are nodata in either are not counted.

    Returns
    -------
    (Confusion, dict)
        The table and ``{"cells", "labelled_cells", "reference_cells"}``.
    """
    fb = ensure_feedback(feedback)
    total = Confusion(0, 0, 0, 0)
    n_lab = n_ref = 0
    with _open_mask(labels, "labels") as lab_src, _open_mask(reference, "reference") as ref_src:
        same = (lab_src.crs == ref_src.crs and lab_src.transform == ref_src.transform
                and lab_src.shape == ref_src.shape)
        if not same and (lab_src.crs is None) != (ref_src.crs is None):
            raise InputError("Only one of the labels and reference rasters has a CRS; assign "
                             "the same CRS to both.")
        vrt = None
        if not same:
            kw: Dict[str, Any] = {}
            if ref_src.nodata is not None:
                kw["src_nodata"] = ref_src.nodata
            vrt = WarpedVRT(ref_src, crs=lab_src.crs or ref_src.crs,
                            transform=lab_src.transform, width=lab_src.width,
                            height=lab_src.height, resampling=Resampling.nearest,
                            nodata=255, dtype="uint8", **kw)
        src_ref = vrt if vrt is not None else ref_src
        try:
            h, w = lab_src.height, lab_src.width
            for r in range(0, h, WINDOW_ROWS):
                win = Window(0, r, w, min(WINDOW_ROWS, h - r))
                lab, lv = _mask_values(lab_src.read(1, window=win, masked=True), labels,
                                       "labels")
                ref, rv = _mask_values(src_ref.read(1, window=win, masked=True), reference,
                                       "reference")
                n_lab += int(lv.sum())
                n_ref += int(rv.sum())
                total = total + confusion(lab, ref, lv & rv)
                fb.progress(100.0 * min(r + WINDOW_ROWS, h) / h)
        finally:
            if vrt is not None:
                vrt.close()
    return total, {"cells": total.n, "labelled_cells": n_lab, "reference_cells": n_ref}


def sample_mask(path: PathLike, x: ArrayLike, y: ArrayLike) -> NDArray[np.int64]:
    """Mask value (0/1) of the cell containing each point; −1 outside or nodata."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    out = np.full(x.shape, -1, dtype=np.int64)
    with _open_mask(path, "labels") as src:
        inv = ~src.transform
        col = np.floor(inv.a * x + inv.b * y + inv.c).astype(np.int64)
        row = np.floor(inv.d * x + inv.e * y + inv.f).astype(np.int64)
        inside = (col >= 0) & (row >= 0) & (col < src.width) & (row < src.height)
        if not inside.any():
            return out
        r0, r1 = int(row[inside].min()), int(row[inside].max()) + 1
        c0, c1 = int(col[inside].min()), int(col[inside].max()) + 1
        block = src.read(1, window=Window(c0, r0, c1 - c0, r1 - r0), masked=True)
        vals, valid = _mask_values(block, path, "labels")
        idx = np.flatnonzero(inside)
        rr, cc = row[idx] - r0, col[idx] - c0
        ok = valid[rr, cc]
        out[idx[ok]] = vals[rr[ok], cc[ok]]
    return out


# -- DTM accuracy ---------------------------------------------------------------------------------


def _dtm_subset(stats: Dict[str, Any]) -> Dict[str, Any]:
    return {k: stats.get(k) for k in DTM_KEYS}


def dtm_against_reference(dtm: PathLike, reference_dtm: PathLike,
                          feedback: Optional[Feedback] = None) -> Dict[str, Any]:
    """DTM − reference DTM on the reference grid: count, mean, std, RMS, NMAD, 95 % |Δh| …"""
    res = compare_dems(dtm, reference_dtm, feedback=feedback)
    return _dtm_subset(res["stats"])


def dtm_at_points(dtm: PathLike, xyz: NDArray[np.float64],
                  crs: Any = None) -> Dict[str, Any]:
    """DTM (bilinear) minus point heights at the given points; ``outside`` = not sampled."""
    z = sample_dem(dtm, xyz[:, 0], xyz[:, 1], crs=crs)
    d = z - xyz[:, 2]
    out = _dtm_subset(difference_stats(d))
    out["outside"] = int(np.count_nonzero(~np.isfinite(d)))
    return out


# -- the whole evaluation -------------------------------------------------------------------------


def evaluate(labels: PathLike, reference: PathLike, *, column: Optional[int] = None,
             dtm: Optional[PathLike] = None, reference_dtm: Optional[PathLike] = None,
             feedback: Optional[Feedback] = None) -> Dict[str, Any]:
    """Classification measures (and optionally DTM accuracy) of a filter result.

    Parameters
    ----------
    labels : path
        The filter's labels: ``labels.txt`` (one 0/1 per point) or ``mask.tif``.
    reference : path
        Reference labels: text with the label in the last column (or ``column``), or a mask
        raster.
    column : int, optional
        1-based column of the label in a reference text.
    dtm, reference_dtm : path, optional
        The filter's DTM and a reference DTM: DTM − reference statistics (``dtm``). With a
        reference text holding coordinates, the DTM is also checked at the reference ground
        points (``dtm_at_ground_points``).

    Returns
    -------
    dict
        ``{"classification": Confusion.to_dict(), "inputs": {…}, "unlabelled": int,
        "dtm": stats or None, "dtm_at_ground_points": stats or None}``.

    Raises
    ------
    InputError
        Unreadable inputs, different point counts, labels other than 0/1, a text labels file
        against a raster reference, a DTM check without anything to check against.
    """
    fb = ensure_feedback(feedback)
    if reference_dtm is not None and dtm is None:
        raise InputError("A reference DTM was given but no DTM to check; give the filter's "
                         "dtm.tif as well.")
    ref_xyz: Optional[NDArray[np.float64]] = None
    ref_labels: Optional[NDArray[np.int8]] = None
    unlabelled = 0
    if _is_raster(reference):
        if not _is_raster(labels):
            raise InputError("The reference is a mask raster but the labels are a text file; "
                             "evaluate the filter's mask.tif against it (point labels need "
                             "reference labels per point).")
        conf, info = confusion_rasters(labels, reference, fb.step(0, 70))
        unlabelled = info["reference_cells"] - info["cells"]
        kind = "raster"
    else:
        ref = read_label_text(reference, column, "reference")
        ref_xyz, ref_labels = ref.xyz, ref.labels
        if _is_raster(labels):
            if ref.xyz is None:
                raise InputError("The labels are a mask raster; the reference text then needs "
                                 "coordinates (X Y Z label) to sample the mask at its points.")
            lab = sample_mask(labels, ref.xyz[:, 0], ref.xyz[:, 1])
            ok = lab >= 0
            unlabelled = int(np.count_nonzero(~ok))
            conf = confusion(np.where(ok, lab, 0), ref.labels, ok)
            kind = "raster at reference points"
        else:
            lab_set = read_label_text(labels, None, "labels")
            if lab_set.labels.size != ref.labels.size:
                raise InputError(
                    f"The labels file has {lab_set.labels.size} labels but the reference has "
                    f"{ref.labels.size} points; both must list the same points in the same "
                    "order (the filter's labels.txt follows its input points).")
            conf = confusion(lab_set.labels, ref.labels)
            kind = "points"
        fb.progress(70.0)
    if unlabelled:
        fb.warning(f"{unlabelled} reference points/cells have no label from the filter "
                   "(outside its grid or nodata) and are not counted.")
    if conf.n == 0:
        raise InputError("The labels and the reference share no labelled point or cell; check "
                         "that they describe the same area.")
    result: Dict[str, Any] = {
        "classification": conf.to_dict(),
        "inputs": {"labels": Path(labels).name, "reference": Path(reference).name,
                   "kind": kind, "reference_column": column},
        "unlabelled": unlabelled,
        "dtm": None,
        "dtm_at_ground_points": None,
    }
    if dtm is not None:
        if reference_dtm is None and ref_xyz is None:
            raise InputError("A DTM check needs a reference DTM, or a reference text with "
                             "coordinates (X Y Z label); give one of them.")
        if reference_dtm is not None:
            result["dtm"] = dtm_against_reference(dtm, reference_dtm, fb.step(70, 95))
        if ref_xyz is not None and ref_labels is not None:
            ground = ref_labels == 0
            result["dtm_at_ground_points"] = dtm_at_points(dtm, ref_xyz[ground])
        result["inputs"].update(dtm=Path(dtm).name,
                                reference_dtm=None if reference_dtm is None
                                else Path(reference_dtm).name)
    c = result["classification"]
    fb.info(f"Type I {_pct(c['type_i_pct'])}, Type II {_pct(c['type_ii_pct'])}, total "
            f"{_pct(c['total_error_pct'])}, kappa {_pct(c['kappa_pct'])} ({conf.n} compared).")
    return result


def _pct(value: Optional[float]) -> str:
    return "–" if value is None else f"{value:.2f} %"


#: Columns of ``report.csv`` (one row per evaluation, so several runs append into one table).
CSV_COLUMNS = ("labels", "reference", "n", "a", "b", "c", "d", "type_i_pct", "type_ii_pct",
               "total_error_pct", "kappa_pct", "unlabelled", "dtm_count", "dtm_mean", "dtm_std",
               "dtm_rms", "dtm_nmad", "dtm_q95", "gp_count", "gp_mean", "gp_std", "gp_rms",
               "gp_nmad", "gp_q95")


def csv_row(result: Dict[str, Any]) -> List[str]:
    """The values of :data:`CSV_COLUMNS` for one evaluation result."""
    c = result["classification"]
    values: Dict[str, Any] = {"labels": result["inputs"]["labels"],
                              "reference": result["inputs"]["reference"],
                              "unlabelled": result["unlabelled"]}
    values.update({k: c.get(k) for k in ("n", "a", "b", "c", "d", "type_i_pct", "type_ii_pct",
                                         "total_error_pct", "kappa_pct")})
    for prefix, key in (("dtm", "dtm"), ("gp", "dtm_at_ground_points")):
        stats = result.get(key) or {}
        for k in ("count", "mean", "std", "rms", "nmad", "q95"):
            values[f"{prefix}_{k}"] = stats.get(k)

    def fmt(v: Any) -> str:
        if v is None:
            return ""
        if isinstance(v, float):
            return f"{v:.6f}" if math.isfinite(v) else ""
        return str(v).replace(",", ";")

    return [fmt(values.get(k)) for k in CSV_COLUMNS]


def run_filter_evaluate(labels: PathLike, reference: PathLike, output: PathLike, *,
                        column: Optional[int] = None, dtm: Optional[PathLike] = None,
                        reference_dtm: Optional[PathLike] = None,
                        feedback: Optional[Feedback] = None) -> Dict[str, Any]:
    """:func:`evaluate`, written to ``output`` (report.json, report.csv) in a staged folder.

    Returns
    -------
    dict
        ``{"report": path of report.json, "csv": path of report.csv, "metrics": {Type I/II,
        total error, kappa (percent), counts, DTM statistics}}``.
    """
    fb = ensure_feedback(feedback)
    result = evaluate(labels, reference, column=column, dtm=dtm, reference_dtm=reference_dtm,
                      feedback=fb.step(0, 95))
    out = Path(output)
    with staged_folder(out, replace=True, product="filter_evaluate") as tmp:
        write_json(tmp / "report.json", result)
        (tmp / "report.csv").write_text(",".join(CSV_COLUMNS) + "\n" + ",".join(csv_row(result))
                                        + "\n", encoding="utf-8")
    c = result["classification"]
    metrics: Dict[str, Any] = {k: c[k] for k in ("type_i_pct", "type_ii_pct", "total_error_pct",
                                                 "kappa_pct", "n", "a", "b", "c", "d")}
    metrics["unlabelled"] = result["unlabelled"]
    metrics["dtm"] = result["dtm"]
    metrics["dtm_at_ground_points"] = result["dtm_at_ground_points"]
    return {"report": str(out / "report.json"), "csv": str(out / "report.csv"),
            "metrics": metrics}


__all__ = [
    "Confusion",
    "LabelSet",
    "confusion",
    "confusion_rasters",
    "csv_row",
    "dtm_against_reference",
    "dtm_at_points",
    "evaluate",
    "read_label_text",
    "run_filter_evaluate",
    "sample_mask",
]
