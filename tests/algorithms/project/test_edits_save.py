"""The whole-file writer of edits.gpkg (issue 21): atomic, fids, Z, every column, GDAL reads it."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import fiona
import pytest
import shapely
from shapely import wkb
from shapely.geometry import LineString, MultiLineString, MultiPolygon, Point, Polygon, shape

from photodem.algorithms.errors import InputError
from photodem.algorithms.project import edits_save
from photodem.algorithms.project.edits import EDIT_LAYERS, add_features, create_edits, read_layer
from photodem.algorithms.project.edits_save import (
    blob_to_geometry,
    geometry_to_blob,
    iso_wkb,
    read_edits,
    save_edits,
)

CRS = "EPSG:25832"
SQUARE = Polygon([(0, 0), (4, 0), (4, 4), (0, 4)], [[(1, 1), (2, 1), (2, 2), (1, 1)]])


@pytest.mark.parametrize("geometry", [Point(1.5, 2.5), Point(1, 2, 3.25),
                                      LineString([(0, 0, 1), (5, 5, 2.5)]), SQUARE,
                                      MultiPolygon([SQUARE, Polygon([(9, 9), (10, 9), (10, 10)])]),
                                      MultiLineString([[(0, 0, 1), (1, 1, 2)],
                                                       [(5, 5, 0), (6, 6, 1)]])])
def test_blob_round_trip(geometry) -> None:
    blob = geometry_to_blob(geometry, 25832)
    assert blob[:2] == b"GP" and int.from_bytes(blob[4:8], "little") == 25832
    back = blob_to_geometry(blob)
    assert back.equals_exact(geometry, 0) and back.has_z == geometry.has_z
    assert geometry_to_blob(None, 1) is None and blob_to_geometry(None) is None
    # shapely 2 writes ISO WKB itself (Debian's shapely 1.8 cannot: hence our writer)
    if shapely.__version__ >= "2":
        assert iso_wkb(geometry) == wkb.dumps(geometry, byte_order=1, flavor="iso")


def test_new_file_is_read_by_gdal_and_the_core_reader(tmp_path: Path) -> None:
    path = tmp_path / "edits.gpkg"
    line = LineString([(10, 20, 30.5), (11, 21, 31.25)])
    save_edits(path, {"breaklines": [(7, line, {"kind": "breakline", "note": "n"}),
                                     (LineString([(0, 0, 1), (1, 0, 1)]), {"kind": None})],
                      "exclusion_areas": [(SQUARE, {"action": "keep"})]}, CRS)
    assert set(fiona.listlayers(str(path))) == set(EDIT_LAYERS)
    with fiona.open(str(path), layer="breaklines") as src:
        feats = list(src)
        assert "25832" in src.crs.to_string() or "UTM" in src.crs_wkt
    assert [int(f.id) for f in feats] == [7, 8]  # given fid kept, a new one after it
    assert shape(feats[0].geometry).equals_exact(line, 0) and shape(feats[0].geometry).has_z
    (geom, props), = read_layer(path, "exclusion_areas")
    assert geom.equals(SQUARE) and props["action"] == "keep"
    content = read_edits(path)
    assert content.layers["breaklines"][0] == (7, content.layers["breaklines"][0][1],
                                               {"kind": "breakline", "note": "n"})


def test_rows_without_geometry_and_other_layers_are_kept(tmp_path: Path) -> None:
    path = create_edits(tmp_path / "edits.gpkg", CRS)
    add_features(path, "seamlines", [(LineString([(0, 0), (1, 1)]), {"note": "a"})])
    with fiona.open(str(path), "w", driver="GPKG", layer="notes",
                    schema={"geometry": "Point", "properties": {"t": "str"}}, crs=CRS) as dst:
        dst.write({"geometry": {"type": "Point", "coordinates": (5.0, 6.0)},
                   "properties": {"t": "mine"}})
    con = sqlite3.connect(str(path))
    edits_save.register_gpkg_functions(con)  # GDAL's R-tree triggers call them
    con.execute("INSERT INTO seamlines (geom, note) VALUES (NULL, 'no geometry')")
    con.commit()
    con.close()
    content = read_edits(path)
    assert [(fid, g is None, a["note"]) for fid, g, a in content.layers["seamlines"]] == \
        [(1, False, "a"), (2, True, "no geometry")]
    save_edits(path, {"seamlines": content.layers["seamlines"]
                      + [(None, LineString([(2, 2), (3, 3)]), {"note": "b"})]})
    assert [a["note"] for _, _, a in read_edits(path).layers["seamlines"]] == \
        ["a", "no geometry", "b"]
    with fiona.open(str(path), layer="notes") as src:
        assert [f["properties"]["t"] for f in src] == ["mine"]


def test_bad_input_changes_nothing(tmp_path: Path, monkeypatch) -> None:
    path = create_edits(tmp_path / "edits.gpkg", CRS)
    old = path.read_bytes()
    with pytest.raises(InputError, match="not an edit layer"):
        save_edits(path, {"roads": []})
    with pytest.raises(InputError, match="no field"):
        save_edits(path, {"boundaries": [(SQUARE, {"colour": "red"})]})
    with pytest.raises(InputError, match="same fid"):
        save_edits(path, {"boundaries": [(1, SQUARE, {}), (1, SQUARE, {})]})
    monkeypatch.setattr(edits_save, "_check",
                        lambda staging, layers: (_ for _ in ()).throw(InputError("bad copy")))
    with pytest.raises(InputError, match="bad copy"):
        save_edits(path, {"boundaries": [(SQUARE, {"name": "A"})]})
    assert path.read_bytes() == old
    assert [p.name for p in tmp_path.iterdir()] == ["edits.gpkg"]
    with pytest.raises(InputError, match="no CRS"):
        save_edits(tmp_path / "other.gpkg", {})


def test_unreadable_file_is_named(tmp_path: Path) -> None:
    path = tmp_path / "edits.gpkg"
    path.write_bytes(b"not a database at all" * 100)
    with pytest.raises(InputError, match=r"edits\.gpkg"):
        read_edits(path)
    with pytest.raises(InputError, match="does not exist"):
        read_edits(tmp_path / "none.gpkg")
