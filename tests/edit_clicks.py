"""Clicks of the editing tools → the features they must write (plain data, no Qt).

Shared by the QGIS tests (``tests/qgis/test_edit_tools.py``) and the standalone map's tests
(``tests/plugin/test_map_edit_tools.py``), with the surface (:func:`write_surface`), the
expectation check (:func:`check_written`) and the form stand-in (:class:`FakeAsk`).
Coordinates are map coordinates in EPSG:25832 on the tiny synthetic block (``synthetic_block
--size tiny``); heights come from the analytic surface :data:`SURFACE` (a plane, so bilinear
sampling is exact to rounding: asserted to 1e-6 m).
"""

from __future__ import annotations

from typing import Any, Dict, List, Tuple

XY = Tuple[float, float]

#: The analytic surface z = z0 + gx·(x − x0) + gy·(y − y0) written as a GeoTIFF by the tests;
#: ``bounds`` (xmin, ymin, xmax, ymax) cover the block, ``res`` is the cell size (m), and the
#: cells inside ``nodata_box`` are nodata.
SURFACE: Dict[str, object] = {
    "z0": 50.0, "x0": 402300.0, "y0": 5674700.0, "gx": 0.01, "gy": 0.02,
    "bounds": (402200.0, 5674600.0, 402400.0, 5674800.0), "res": 0.5,
    "nodata_box": (402330.0, 5674735.0, 402345.0, 5674750.0), "crs": "EPSG:25832",
}

#: The canvas extent of the tests (the block with a margin).
EXTENT = (402230.0, 5674615.0, 402370.0, 5674790.0)


def surface_z(x: float, y: float) -> float:
    """The analytic height of :data:`SURFACE` at (x, y)."""
    s = SURFACE
    return float(s["z0"]) + float(s["gx"]) * (x - float(s["x0"])) \
        + float(s["gy"]) * (y - float(s["y0"]))


#: One entry per tool: the layer, the left clicks (a right click finishes lines and polygons),
#: what the form answers, and what must be in ``edits.gpkg`` after *Save layer edits*.
#: ``z: "surface"`` — each vertex's Z (or the start point's ``height``) is :func:`surface_z` at
#: the clicked pixel's map point.
CLICKS: List[Dict[str, object]] = [
    {"layer": "start_points", "clicks": [(402290.0, 5674660.0)],
     "answer": {"text": "seed"}, "geometry": "Point", "z": "surface",
     "attributes": {"note": "seed"}},
    {"layer": "ground_points", "clicks": [(402300.0, 5674700.0)],
     "answer": {"text": "road"}, "geometry": "Point", "z": "surface",
     "attributes": {"note": "road"}},
    {"layer": "check_points", "clicks": [(402315.0, 5674690.0)],
     "answer": {"text": "CP1"}, "geometry": "Point", "z": "surface",
     "attributes": {"id": "CP1"}},
    {"layer": "exclusion_areas",
     "clicks": [(402280.0, 5674650.0), (402300.0, 5674650.0), (402300.0, 5674670.0),
                (402280.0, 5674670.0)],
     "answer": {"action": "keep", "text": "lake"}, "geometry": "Polygon",
     "attributes": {"action": "keep", "note": "lake"}},
    {"layer": "boundaries",
     "clicks": [(402270.0, 5674640.0), (402330.0, 5674640.0), (402330.0, 5674760.0),
                (402270.0, 5674760.0)],
     "answer": {"text": "area A"}, "geometry": "Polygon", "attributes": {"name": "area A"}},
    {"layer": "breaklines",
     "clicks": [(402270.0, 5674700.0), (402290.0, 5674710.0), (402320.0, 5674705.0)],
     "answer": {"kind": "breakline"}, "geometry": "LineString", "z": "surface",
     "attributes": {"kind": "breakline"}},
    {"layer": "seamlines",
     "clicks": [(402300.0, 5674630.0), (402300.0, 5674770.0)],
     "answer": {}, "geometry": "LineString", "attributes": {}},
]

#: A breakline crossing the one of :data:`CLICKS` (near (402285, 5674707.5)): refused.
CROSSING_BREAKLINE: List[XY] = [(402285.0, 5674690.0), (402285.0, 5674725.0)]

#: A bow tie (self-intersecting at (402300, 5674700)): refused, or repaired with consent.
BOW_TIE: List[XY] = [(402290.0, 5674690.0), (402310.0, 5674710.0), (402310.0, 5674690.0),
                     (402290.0, 5674710.0)]

#: Interpolated breakline: typed end heights, the inner vertex linear in the 2-D length.
INTERPOLATED: Dict[str, object] = {
    "clicks": [(402270.0, 5674740.0), (402290.0, 5674740.0), (402310.0, 5674740.0)],
    "ends": (40.0, 44.0),
}

#: A click inside the block but outside every stereo model: the start point tool warns and the
#: form asks for a typed height (no pre-filled value).
OUTSIDE_MODELS: XY = (402250.0, 5674660.0)

#: A click on the surface's nodata cells (a ground point: the form asks for a typed height).
ON_NODATA: XY = (402337.0, 5674742.0)


def write_surface(path, crs=SURFACE["crs"]):
    """The analytic plane of :data:`SURFACE` as a float64 GeoTIFF (with its nodata box)."""
    import numpy as np
    import rasterio
    from rasterio.transform import from_origin

    xmin, ymin, xmax, ymax = SURFACE["bounds"]
    res = SURFACE["res"]
    cols, rows = int((xmax - xmin) / res), int((ymax - ymin) / res)
    x = xmin + (np.arange(cols) + 0.5) * res
    y = ymax - (np.arange(rows) + 0.5) * res
    xx, yy = np.meshgrid(x, y)
    z = surface_z(xx, yy)
    bx0, by0, bx1, by1 = SURFACE["nodata_box"]
    z[(xx > bx0) & (xx < bx1) & (yy > by0) & (yy < by1)] = -9999.0
    profile = {"driver": "GTiff", "width": cols, "height": rows, "count": 1,
               "dtype": "float64", "transform": from_origin(xmin, ymax, res, res),
               "nodata": -9999.0}
    if crs:
        profile["crs"] = crs
    with rasterio.open(path, "w", **profile) as dst:
        dst.write(z, 1)
    return path


def write_mosaic_seamlines(path):
    """A mosaic's seamlines file with one line at x = 402301 (the seamline tool snaps to it)."""
    import fiona  # lazy: the click table itself is plain data

    schema = {"geometry": "LineString", "properties": {"id": "int"}}
    with fiona.open(path, "w", driver="GPKG", layer="seamlines", schema=schema,
                    crs="EPSG:25832") as dst:
        dst.write({"geometry": {"type": "LineString",
                                "coordinates": [(402301.0, 5674600.0), (402301.0, 5674800.0)]},
                   "properties": {"id": 1}})
    return path


def check_written(case: Dict[str, object], hits: List[XY], rows: List[Tuple[object, dict]]
                  ) -> None:
    """Assert what a tool of ``case`` wrote (``rows``: (shapely geometry, properties) read back
    from edits.gpkg) for the clicked pixels' map points ``hits``: one feature, its geometry
    type, attributes, vertices at the hits and Z (or the start point's height) on the surface
    to 1e-6 m. The QGIS and the standalone tests expect the same."""
    assert len(rows) == 1, rows
    geometry, props = rows[0]
    assert case["geometry"] in geometry.geom_type
    for key, value in case["attributes"].items():
        assert props[key] == value, (key, props)
    coords = (list(geometry.exterior.coords)[:-1] if "Polygon" in geometry.geom_type
              else list(geometry.coords))
    assert len(coords) == len(hits)
    for (x, y, *_z), (hx, hy) in zip(coords, hits):
        assert abs(x - hx) <= 1e-6 and abs(y - hy) <= 1e-6, ((x, y), (hx, hy))
    if case.get("z") == "surface":
        if case["layer"] == "start_points":
            assert abs(props["height"] - surface_z(*hits[0])) <= 1e-6
        else:
            for x, y, z in coords:
                assert abs(z - surface_z(x, y)) <= 1e-6
    if case["layer"] == "exclusion_areas":
        assert props["action"] in ("keep", "remove", "exclude")


class FakeAsk:
    """The tools' questions answered from ``answer`` (no dialog); every call is recorded."""

    def __init__(self) -> None:
        self.answer: Dict[str, Any] = {}
        self.calls: List[Tuple[Any, ...]] = []

    def height(self, title, height, message="", text_label=""):
        self.calls.append(("height", height, message))
        value = self.answer.get("height", height)
        return None if value is None else (value, self.answer.get("text", ""))

    def action(self):
        self.calls.append(("action",))
        return self.answer.get("action", "remove"), self.answer.get("text", "")

    def breakline(self, heights, editable, message=""):
        self.calls.append(("breakline", list(heights), list(editable), message))
        typed = self.answer.get("heights")
        out = [typed[i] if (typed and free) else z
               for i, (z, free) in enumerate(zip(heights, editable))]
        return out, self.answer.get("kind", "breakline")

    def text(self, title, label):
        self.calls.append(("text", title))
        return self.answer.get("text", "")

    def repair(self, message):
        self.calls.append(("repair", message))
        return bool(self.answer.get("repair", False))
