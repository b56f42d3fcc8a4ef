"""Outputs of the polygon georeferencing: control points, the georeferenced image, the report.

- ``<name>.points``: the QGIS Georeferencer's control point file. Its source coordinates are
  those of a raster without georeference as QGIS shows it: x = column of the pixel corner grid
  (the left edge of the image is 0), y = −row (the top edge is 0, rows downwards negative).
  Our pixel centres are at integers, so sourceX = col + 0.5, sourceY = −(row + 0.5).
- ``gcps.gpkg``: the control points in the map CRS with image coordinates and residuals.
- ``<name>_georef.tif``: the image resampled into the map CRS by the fitted transform (all
  bands, bilinear, alpha band; tiled with overviews), written tile by tile.
- ``<name>_gcps.tif``: a copy of the image with the control points embedded (GDAL GCPs), for
  GDAL/QGIS tools that warp by themselves.
- ``report.json`` and ``report.html`` with ``overlay.png``: matched polygons over the image,
  the residual table, RMSE in pixels and metres, pairs, warnings.
"""

from __future__ import annotations

import html
import json
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple, Union

import fiona
import numpy as np
import rasterio
from matplotlib.patches import Rectangle
from rasterio.control import GroundControlPoint
from rasterio.transform import Affine
from rasterio.windows import Window
from scipy import ndimage
from scipy.spatial import ConvexHull, QhullError

from ..feedback import Feedback
from ..jsonable import json_ready
from ..quality.report import new_figure
from ..raster.io import atomic_output, gtiff_profile, open_image, overview_factors, staged_folder
from .correspondence import apply
from .evidence import evidence_text
from .fit import TransformFit, points_summary
from .result import GeorefResult

PathLike = Union[str, Path]


def points_source(col: Any, row: Any) -> Tuple[Any, Any]:
    """Image column/row (pixel centres at integers) → sourceX/sourceY of a ``.points`` file
    (pixel corners at 0, rows negative; see the module notes). Scalars or arrays."""
    return col + 0.5, -(row + 0.5)


def image_from_points_source(x: Any, y: Any) -> Tuple[Any, Any]:
    """sourceX/sourceY of a ``.points`` file → image column/row: the inverse of
    :func:`points_source`."""
    return x - 0.5, -y - 0.5


#: Colours of the control point roles on the residual maps (report and review dialog).
ROLE_COLOURS = {"control": "tab:blue", "outlier": "tab:orange", "check": "tab:green",
                "rejected": "tab:red"}
#: Colour of the independent check points on the residual maps.
INDEPENDENT_COLOUR = "tab:purple"


def skipped_ids_text(ids: List[str], most: int = 10) -> str:
    """The first ``most`` ids, comma-separated (… when there are more)."""
    return ", ".join(ids[:most]) + (" …" if len(ids) > most else "")


def skipped_note(ids: List[str]) -> str:
    """The report's sentence on check points skipped outside the image ('' without any)."""
    if not ids:
        return ""
    return f"Skipped check points outside the image ({len(ids)}): {skipped_ids_text(ids)}."


def points_crs(text: str) -> Optional[str]:
    """The CRS of a QGIS ``.points`` file's text: its ``#CRS:`` line (``None`` without one)."""
    for raw in text.splitlines():
        if raw.startswith("#CRS:"):
            return raw.removeprefix("#CRS:").strip()
    return None


def write_points_file(path: PathLike, result: GeorefResult) -> Path:
    """The QGIS Georeferencer ``.points`` file (see the module notes for the convention)."""
    fit = result.fit
    rows = points_summary(fit)
    lines = [f"#CRS: {result.crs.to_wkt()}",
             "mapX,mapY,sourceX,sourceY,enable,dX,dY,residual"]
    for g, r in zip(result.gcps, rows):
        px = fit.pixel_size
        sx, sy = points_source(*g.image)
        lines.append(f"{g.map[0]:.6f},{g.map[1]:.6f},{sx:.6f},{sy:.6f},{1 if r['used'] else 0},"
                     f"{r['dx_map'] / px:.6f},{r['dy_map'] / px:.6f},{r['residual_px']:.6f}")
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")
    return Path(path)


def write_gcps_gpkg(path: PathLike, result: GeorefResult) -> Path:
    """Control points as a point layer in the map CRS."""
    fit = result.fit
    schema = {"geometry": "Point",
              "properties": {"id": "int", "image_col": "float", "image_row": "float",
                             "residual_m": "float", "residual_px": "float", "loo_m": "float",
                             "enabled": "int", "pair": "int"}}
    with fiona.open(path, "w", driver="GPKG", layer="gcps", crs_wkt=result.crs.to_wkt(),
                    schema=schema) as dst:
        for k, (g, r) in enumerate(zip(result.gcps, points_summary(fit))):
            loo = r["loo_map"]
            dst.write({"geometry": {"type": "Point", "coordinates": g.map},
                       "properties": {"id": k, "image_col": g.image[0], "image_row": g.image[1],
                                      "residual_m": r["residual_map"],
                                      "residual_px": r["residual_px"],
                                      "loo_m": None if not np.isfinite(loo) else loo,
                                      "enabled": int(r["used"]), "pair": g.pair}})
    return Path(path)


def _inverse_points(result: GeorefResult, xy: np.ndarray) -> np.ndarray:
    """Map → image for the fitted transform (poly2: Newton steps on the forward model)."""
    fit = result.fit
    if fit.matrix is not None:
        return apply(np.linalg.inv(fit.matrix), xy)
    return result.inverse_fit.forward(xy)  # poly2: its own map → image fit


def write_georeferenced(path: PathLike, image: PathLike, result: GeorefResult,
                        gsd: Optional[float] = None, tile: int = 512,
                        feedback: Optional[Feedback] = None) -> Path:
    """The image resampled into the map CRS (bilinear, alpha band), tile by tile."""
    fb = feedback or Feedback()
    fit = result.fit
    with open_image(image) as src:
        W, H, count, dtype = src.width, src.height, src.count, src.dtypes[0]
        corners = np.array([[-0.5, -0.5], [W - 0.5, -0.5], [-0.5, H - 0.5], [W - 0.5, H - 0.5]])
        mc = fit.forward(corners)
        px = gsd or fit.pixel_size
        x0, y1 = np.floor(mc.min(axis=0) / px) * px
        x1, y0 = np.ceil(mc.max(axis=0) / px) * px
        x0, x1 = float(min(x0, x1)), float(max(x0, x1))
        ylo, yhi = float(min(y0, y1)), float(max(y0, y1))
        cols, rows = round((x1 - x0) / px), round((yhi - ylo) / px)
        transform = Affine(px, 0, x0, 0, -px, yhi)
        profile = gtiff_profile(cols, rows, count + 1, dtype, result.crs.to_wkt(),
                                transform=transform, nodata=None)
        amax = 255 if dtype == "uint8" else np.iinfo(dtype).max if np.issubdtype(
            np.dtype(dtype), np.integer) else 1.0
        with atomic_output(path) as tmp, open_image(tmp, "w", **profile) as dst:
            n_tiles = ((rows + tile - 1) // tile) * ((cols + tile - 1) // tile)
            done = 0
            for r0 in range(0, rows, tile):
                for c0 in range(0, cols, tile):
                    fb.check()
                    th, tw = min(tile, rows - r0), min(tile, cols - c0)
                    cc, rr = np.meshgrid(c0 + np.arange(tw) + 0.5, r0 + np.arange(th) + 0.5)
                    xy = np.column_stack([x0 + cc.ravel() * px, yhi - rr.ravel() * px])
                    ij = _inverse_points(result, xy)
                    ci, ri = ij[:, 0], ij[:, 1]
                    inside = (ci >= -0.5) & (ci <= W - 0.5) & (ri >= -0.5) & (ri <= H - 0.5)
                    out = np.zeros((count + 1, th * tw), dtype=dtype)
                    if inside.any():
                        # the source window this tile needs (never the whole image)
                        wc0 = max(int(np.floor(ci[inside].min())) - 1, 0)
                        wr0 = max(int(np.floor(ri[inside].min())) - 1, 0)
                        wc1 = min(int(np.ceil(ci[inside].max())) + 2, W)
                        wr1 = min(int(np.ceil(ri[inside].max())) + 2, H)
                        data = src.read(window=Window(wc0, wr0, wc1 - wc0, wr1 - wr0))
                        coords = np.vstack([ri[inside] - wr0, ci[inside] - wc0])
                        for b in range(count):
                            v = ndimage.map_coordinates(data[b].astype(np.float64), coords,
                                                        order=1, mode="nearest")
                            if np.issubdtype(np.dtype(dtype), np.integer):
                                v = np.round(v)
                            out[b, inside] = v.astype(dtype)
                        out[count, inside] = amax
                    dst.write(out.reshape(count + 1, th, tw), window=Window(c0, r0, tw, th))
                    done += 1
                    fb.progress(100.0 * done / n_tiles)
            factors = overview_factors(cols, rows)
            if factors:
                dst.build_overviews(factors, rasterio.enums.Resampling.average)
            dst.colorinterp = [*dst.colorinterp[:count],
                               rasterio.enums.ColorInterp.alpha]
    return Path(path)


def write_with_gcps(path: PathLike, image: PathLike, result: GeorefResult) -> Path:
    """A copy of the image with the used control points embedded as GDAL GCPs."""
    fit = result.fit
    gcps = [GroundControlPoint(row=g.image[1] + 0.5, col=g.image[0] + 0.5, x=g.map[0],
                               y=g.map[1], id=str(k))
            for k, (g, u) in enumerate(zip(result.gcps, fit.used)) if u]
    with open_image(image) as src:
        profile = src.profile.copy()
        profile.pop("transform", None)
        profile.pop("crs", None)
        profile.update(driver="GTiff")
        with atomic_output(path) as tmp, open_image(tmp, "w", **profile) as dst:
            for _, window in src.block_windows(1):
                dst.write(src.read(window=window), window=window)
            dst.gcps = (gcps, result.crs.to_wkt())
    return Path(path)


def overlay_png(path: PathLike, result: GeorefResult) -> Path:
    """Matched image polygons (green) and reference polygons taken into the image (red)."""
    grey = result.grey
    fi, fr = result.img_features, result.ref_features
    H, W = grey.shape
    # no pyplot: the review saves from inside QGIS, whose backend must stay as it is
    fig = new_figure(8, 8 * H / max(W, 1))
    ax = fig.add_subplot()
    ax.imshow(grey, cmap="gray", extent=(-0.5, W - 0.5, H - 0.5, -0.5))
    outlines = [(fi[h.i].obj.ring, "lime") for h in result.pairs]
    outlines += [(_inverse_points(result, fr[h.j].obj.ring), "red") for h in result.pairs]
    # the area-based stage matched the whole map: all reference outlines
    outlines += [(_inverse_points(result, r), "red") for r in result.reference_rings]
    for ring, colour in outlines:
        p = np.vstack([ring, ring[:1]])
        ax.plot(p[:, 0], p[:, 1], "-", color=colour, lw=0.8)
    g = np.array([p.image for p in result.gcps]) if result.gcps else np.zeros((0, 2))
    if len(g):
        ax.plot(g[:, 0], g[:, 1], "+", color="yellow", ms=4)
    ax.set_xlim(-0.5, W - 0.5)
    ax.set_ylim(H - 0.5, -0.5)
    ax.set_title({"area": "reference polygons through the area-based transform (red); "
                          "control points (+)",
                  "keypoints": "control points: image patches located in the reference "
                               "raster (+)"}.get(
        result.stage, "matched objects: image (green), reference (red); control points (+)"))
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    return Path(path)


def report_dict(result: GeorefResult) -> Dict[str, Any]:
    """Everything an operator checks, JSON-ready."""
    fit = result.fit
    fi, fr = result.img_features, result.ref_features
    return {
        "transform": transform_json(result),
        "rmse_px": fit.rmse_px, "rmse_m": fit.rmse_map, "sigma0_m": fit.sigma0,
        "pixel_size_m": fit.pixel_size, "counts": result.counts,
        "pairs": [{"image_object": fi[h.i].obj.id, "reference_object": fr[h.j].obj.id,
                   "run": fi[h.i].obj.run, "threshold": fi[h.i].obj.threshold,
                   "q": h.q, "d4_alternative": h.alternative,
                   # paired under the verified transform, not by invariants (cut by the
                   # image border: refinement.border_pairs)
                   "cut_by_border": bool(fi[h.i].obj.touches_border),
                   "reference_features": fr[h.j].obj.attributes.get("features")}
                  for h in result.pairs],
        "icp": result.icp,
        "gcps": [{"image": list(g.image), "map": list(g.map), "pair": g.pair,
                  "sharp": bool(g.sharp), **r}
                 for g, r in zip(result.gcps, points_summary(fit))],
        "segmentation": result.segmentation, "reference": result.reference,
        "reference_kind": result.reference_kind, "image": result.image_info,
        "parameters": result.parameters, "warnings": result.warnings,
        "stage": result.stage,
        "area_search": result.area,
        "verified": result.verified,
        "evidence": None if result.evidence is None else result.evidence.to_json(),
        "extensions": ["area-based global search" if result.stage == "area" else None,
                       "smoothing before segmentation" if result.parameters["smooth"]
                       else None,
                       "merging of similar adjacent regions" if result.parameters["merge"]
                       else None,
                       "D4 alternatives for ambiguous standard positions",
                       "least-squares re-estimate of the global affine after verification",
                       "joint ICP of all verified outlines with outline offset",
                       "control points along outlines" if result.parameters["gcp_mode"]
                       == "outline" else None],
    }


def transform_json(result: GeorefResult) -> Dict[str, Any]:
    """The final transform: kind, 3 × 3 matrix (image col/row → map) or poly2 coefficients."""
    fit = result.fit
    out: Dict[str, Any] = {"kind": fit.kind, "crs": result.crs.to_string()}
    if fit.matrix is not None:
        out["matrix"] = [[float(v) for v in row] for row in fit.matrix]
    else:
        Ns, Nd, coef = fit.poly
        out["poly2"] = {"normalise_image": Ns.tolist(), "normalise_map": Nd.tolist(),
                        "x": coef[0].tolist(), "y": coef[1].tolist(),
                        "terms": ["1", "x", "y", "x²", "xy", "y²"]}
    return out


def image_residuals(fit: TransformFit, img: np.ndarray, res_map: np.ndarray) -> np.ndarray:
    """Map residuals (fitted − measured) at image points taken into the image, in pixels (for
    drawing): through the local inverse of the transform (finite differences, the same for
    every kind of transform)."""
    J = np.stack([fit.forward(img + [0.5, 0]) - fit.forward(img - [0.5, 0]),
                  fit.forward(img + [0, 0.5]) - fit.forward(img - [0, 0.5])], axis=-1)
    return np.linalg.solve(J, res_map[..., None])[..., 0]


def residual_scale(residuals: np.ndarray, extent: float, share: float = 0.1) -> float:
    """A round exaggeration for residual vectors: 1, 2 or 5 × 10^k, at most the factor that
    draws the longest of ``residuals`` (n, 2) as ``share`` of ``extent`` (both in pixels)."""
    longest = float(np.hypot(*np.asarray(residuals, float).reshape(-1, 2).T).max(initial=0.0))
    if longest <= 0 or extent <= 0:
        return 1.0
    scale = share * extent / longest
    step = 10.0 ** np.floor(np.log10(scale))
    return float(step * max(f for f in (1, 2, 5) if f * step <= scale))


def draw_residuals(ax: Any, xy: np.ndarray, residuals: np.ndarray, scale: float, colour: str,
                   marker: str = ".", size: float = 3, width: float = 0.003,
                   **marker_style: Any) -> None:
    """Points ``xy`` (n, 2, image col/row) with their ``residuals`` (n, 2, px) drawn as arrows
    ``scale`` times their length on the matplotlib axes ``ax``; ``marker_style`` goes to the
    points (``label``, ``mec``, …)."""
    xy = np.asarray(xy, float).reshape(-1, 2)
    if not len(xy):
        return
    d = np.asarray(residuals, float).reshape(-1, 2) * scale
    ax.quiver(xy[:, 0], xy[:, 1], d[:, 0], d[:, 1], color=colour, angles="xy",
              scale_units="xy", scale=1, width=width)
    ax.plot(xy[:, 0], xy[:, 1], marker, color=colour, ms=size, linestyle="none",
            **marker_style)


def residual_png(path: PathLike, result: GeorefResult, width: int, height: int,
                 check: Optional[Tuple[np.ndarray, np.ndarray]] = None) -> Path:
    """Control points over the image frame with their residual vectors (fitted − measured,
    exaggerated, as in the review dialog): points in the fit blue, the others (outliers,
    check points) orange; the convex hull of the points in the fit dashed — where the
    transform is interpolated, not extrapolated.
    ``check``: independent check points (image (n, 2), map (n, 2)), purple triangles."""
    fit = result.fit
    xy = np.array([g.image for g in result.gcps], float).reshape(-1, 2)
    mp = np.array([g.map for g in result.gcps], float).reshape(-1, 2)
    # fitted − measured, in the image: the arrows of the review dialog
    res = image_residuals(fit, xy, fit.forward(xy) - mp)
    cxy = np.zeros((0, 2)) if check is None else np.asarray(check[0], float).reshape(-1, 2)
    cres = (image_residuals(fit, cxy, fit.forward(cxy) - np.asarray(check[1], float)
                            .reshape(-1, 2)) if len(cxy) else np.zeros((0, 2)))
    fig = new_figure(7, 7 * height / max(width, 1))
    ax = fig.add_subplot()
    ax.add_patch(Rectangle((-0.5, -0.5), width, height, fill=False, color="0.3"))
    scale = residual_scale(np.vstack([res, cres]), float(np.hypot(width, height)))
    for used, role in ((fit.used, "control"), (~fit.used, "outlier")):
        draw_residuals(ax, xy[used], res[used], scale, ROLE_COLOURS[role])
    draw_residuals(ax, cxy, cres, scale, INDEPENDENT_COLOUR, marker="^", size=5)
    if fit.used.sum() >= 3:
        try:
            hull = ConvexHull(xy[fit.used])
            ring = xy[fit.used][np.append(hull.vertices, hull.vertices[0])]
            ax.plot(ring[:, 0], ring[:, 1], "--", color=ROLE_COLOURS["control"], lw=0.8)
        except QhullError:  # collinear points: no hull to draw
            pass
    ax.set_xlim(-0.05 * width, 1.05 * width)
    ax.set_ylim(1.05 * height, -0.05 * height)
    ax.set_aspect("equal")
    title = (f"residuals ×{scale:g}; RMSE {fit.rmse_px:.2f} px, "
             f"{int(fit.used.sum())} of {len(xy)} points in the fit")
    if len(cxy):
        title += f"\n{len(cxy)} independent check points (purple)"
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    return Path(path)


def write_report(folder: Path, result: GeorefResult, name: str) -> Dict[str, Path]:
    """report.json, report.html, overlay.png and residuals.png in ``folder``."""

    rep = report_dict(result)
    rep["extensions"] = [e for e in rep["extensions"] if e]
    (folder / "report.json").write_text(json.dumps(json_ready(rep), indent=1),
                                        encoding="utf-8")
    overlay_png(folder / "overlay.png", result)
    info = result.image_info
    residual_png(folder / "residuals.png", result, info["width"], info["height"])
    (folder / "report.html").write_text(report_html(rep, name), encoding="utf-8")
    return {"report": folder / "report.json", "html": folder / "report.html",
            "overlay": folder / "overlay.png"}


def report_html(rep: Dict[str, Any], name: str) -> str:
    """The HTML report of a report dict (automatic or reviewed)."""
    rows = "".join(
        f"<tr><td>{k}</td><td>{g['image'][0]:.2f}</td><td>{g['image'][1]:.2f}</td>"
        f"<td>{g['map'][0]:.2f}</td><td>{g['map'][1]:.2f}</td><td>{g['residual_px']:.3f}</td>"
        f"<td>{g['residual_map']:.3f}</td><td>{g['loo_map']:.3f}</td>"
        f"<td>{'yes' if g['used'] else 'no'}</td></tr>"
        for k, g in enumerate(rep["gcps"]))
    review = rep.get("review")
    if review:
        check = (f"{review['check_points']} check points, RMSE {review['check_rmse_m']} m"
                 if review.get("check_points") else "no check points")
        reviewed = (f"<p>Reviewed by the operator: transform {review['transform']}, outlier "
                    f"removal {'on' if review['drop_outliers'] else 'off'}, "
                    f"{len(review['switched_off'])} points switched off, "
                    f"{len(review['manual'])} added by hand, rejected pairs "
                    f"{review['rejected_pairs'] or 'none'}; {check}. The automatic result is "
                    "in report_auto.json.</p>" + _independent_html(review))
    else:
        reviewed = ""
    warn = "".join(f"<li>{html.escape(w)}</li>" for w in rep["warnings"]) or "<li>none</li>"
    c = rep["counts"]
    if rep["stage"] == "area":
        how = (f"boundary-orientation score {c.get('boundary_score')}"
               if (rep.get("area_search") or {}).get("method") == "boundary orientation"
               else f"ECC correlation {c.get('area_ecc')}")
        source = (f"{c.get('gcps')} control points on a grid through the affine of the "
                  f"area-based search ({how}; {c.get('reference_objects')} reference objects)")
    elif rep["stage"] == "keypoints":
        source = (f"{c.get('gcps')} control points from {c.get('patches_agreeing')} image "
                  f"patches located in the reference raster, after {c.get('detector')} "
                  f"keypoints ({c.get('inlier_share', 0) * 100:.0f} % of the matches inliers"
                  f"{', image mirrored' if c.get('mirrored') else ''})")
    else:
        source = (f"{c.get('gcps')} control points from {c.get('verified_pairs')} verified "
                  f"object pairs ({c.get('hypotheses')} hypotheses, {c.get('image_objects')} "
                  f"image and {c.get('reference_objects')} reference objects)")
    unverified = (' — <span style="color:#b00">UNVERIFIED</span>'
                  if rep.get("verified") is False else "")
    page = f"""<!doctype html><html><head><meta charset="utf-8">
<title>Georeferencing {html.escape(name)}</title>
<style>body{{font-family:sans-serif;margin:2em}}td,th{{padding:2px 8px;text-align:right}}
table{{border-collapse:collapse}}tr:nth-child(even){{background:#eee}}</style></head><body>
<h1>Georeferencing of {html.escape(name)}{unverified}</h1>
<p>Transform: <b>{rep['transform']['kind']}</b> into {html.escape(rep['transform']['crs'])}.
RMSE <b>{rep['rmse_px']:.3f} px</b> = {rep['rmse_m']:.3f} m (pixel size
{rep['pixel_size_m']:.3f} m); {source}.</p>{reviewed}
{_evidence_html(rep)}
<h2>Warnings</h2><ul>{warn}</ul>
<img src="overlay.png" style="max-width:100%">
<h2>Residuals</h2><img src="residuals.png" style="max-width:100%">
<h2>Control points</h2>
<table><tr><th>#</th><th>col</th><th>row</th><th>X</th><th>Y</th><th>residual px</th>
<th>residual m</th><th>leave-one-out m</th><th>used</th></tr>{rows}</table>
</body></html>"""
    return page


def _evidence_html(rep: Dict[str, Any]) -> str:
    """The report's evidence section: the verdict (UNVERIFIED in red) and its figures."""
    ev = rep.get("evidence")
    if ev is None:
        return ""
    if rep.get("verified"):
        head = "<p><b>Verified</b> by independent evidence: "
    else:
        head = ('<p style="color:#b00"><b>UNVERIFIED</b> — written on request; the '
                "independent evidence does not support it: "
                + html.escape("; ".join(ev.get("reasons", []))) + ". Figures: ")
    names = ("top left", "top right", "bottom left", "bottom right")
    local = ", ".join(f"{n} {v:.2f} px" for n, v in zip(names, ev.get("local_offsets_px") or [])
                      if v is not None) or "none"
    return (f"<h2>Evidence</h2>{head}{html.escape(evidence_text(ev))}.</p>"
            f"<p>Agreement peak offsets per quadrant: {html.escape(local)}; "
            f"{ev.get('points')} control points.</p>")


def _independent_html(review: Dict[str, Any]) -> str:
    """The independent check points of a review section (none: an empty string)."""
    check = review.get("independent_check")
    if not check or not check.get("count"):
        return ""
    rows = "".join(
        f"<tr><td>{html.escape(str(p['id']))}</td><td>{p['image'][0]:.2f}</td>"
        f"<td>{p['image'][1]:.2f}</td><td>{p['map'][0]:.2f}</td><td>{p['map'][1]:.2f}</td>"
        f"<td>{p['residual_px']:.3f}</td><td>{p['residual_map']:.3f}</td></tr>"
        for p in check["points"])
    note = skipped_note([str(i) for i in check.get("skipped", [])])
    return (f"<h2>Independent check points</h2><p>{check['count']} points from "
            f"{html.escape(str(check.get('file')))}, not used in the fit: RMSE "
            f"<b>{check['rmse_px']:.3f} px</b> = {check['rmse_m']:.3f} m.</p>"
            + (f"<p>{html.escape(note)}</p>" if note else "")
            + "<table><tr><th>id</th><th>col</th><th>row</th><th>X</th><th>Y</th>"
            f"<th>residual px</th><th>residual m</th></tr>{rows}</table>")


def write_outputs(output: PathLike, image: PathLike, result: GeorefResult,
                  feedback: Optional[Feedback] = None, replace: bool = False
                  ) -> Dict[str, Any]:
    """All products into the folder ``output`` (staged: nothing half-written is left)."""
    name = Path(image).stem
    out = Path(output)
    with staged_folder(out, replace=replace, product="georeference_polygons") as tmp:
        write_transform_products(tmp, image, result, name, feedback)
        write_report(tmp, result, name)
    return product_paths(out, name)


def write_transform_products(folder: Path, image: PathLike, result: GeorefResult, name: str,
                             feedback: Optional[Feedback] = None) -> None:
    """The products of the transform in ``folder``: the ``.points`` file, ``gcps.gpkg``, the
    georeferenced image and the image copy with GCPs (automatic run and review alike)."""
    write_points_file(folder / f"{name}.points", result)
    write_gcps_gpkg(folder / "gcps.gpkg", result)
    write_georeferenced(folder / f"{name}_georef.tif", image, result, feedback=feedback)
    write_with_gcps(folder / f"{name}_gcps.tif", image, result)


def product_paths(folder: Path, name: str) -> Dict[str, str]:
    """The paths of a georeferencing folder's products (the algorithm's outputs)."""
    return {"folder": str(folder), "points": str(folder / f"{name}.points"),
            "gcps": str(folder / "gcps.gpkg"), "image": str(folder / f"{name}_georef.tif"),
            "image_gcps": str(folder / f"{name}_gcps.tif"),
            "report": str(folder / "report.json"), "html": str(folder / "report.html")}


def summary(result: GeorefResult, paths: Dict[str, Any]) -> Dict[str, Any]:
    """The algorithm's JSON result."""
    fit = result.fit
    return {"transform": transform_json(result), "rmse_px": float(fit.rmse_px),
            "rmse_m": float(fit.rmse_map), "gcps": paths["points"],
            "gcps_gpkg": paths["gcps"], "image": paths["image"], "report": paths["report"],
            "n_pairs": int(result.counts["verified_pairs"]),
            "n_gcps": int(result.counts["gcps"]),
            "verified": verified_word(result.verified)}


def verified_word(verified: Optional[bool]) -> str:
    """"yes", "no" (UNVERIFIED) or "not assessed" for a result's or report's verdict."""
    return {True: "yes", False: "no"}.get(verified, "not assessed")  # type: ignore[arg-type]


def points_list(result: GeorefResult) -> List[Dict[str, Any]]:
    return report_dict(result)["gcps"]
