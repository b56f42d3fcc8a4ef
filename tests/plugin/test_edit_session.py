"""The standalone tool's edit session (issue 21): memory, undo/redo, atomic save, bad files."""

from __future__ import annotations

import os
import random
import sqlite3
from pathlib import Path
from typing import Any, Dict, List

import pytest

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
pytest.importorskip("pytestqt")

from shapely.geometry import LineString, Point, Polygon

from photodem.algorithms.errors import InputError
from photodem.algorithms.project import edits_save
from photodem.algorithms.project.edits import add_features, create_edits
from photodem.plugin.widgets.edit_session import EditSession

CRS = "EPSG:25832"
X0, Y0 = 402300.0, 5674700.0


def _square(x: float, y: float, d: float = 5.0) -> Polygon:
    return Polygon([(x, y), (x + d, y), (x + d, y + d), (x, y + d)])


@pytest.fixture
def project(tmp_path: Path) -> Path:
    """A project folder with an edits.gpkg holding a few features of every kind."""
    path = create_edits(tmp_path / "edits.gpkg", CRS)
    add_features(path, "start_points", [(Point(X0, Y0), {"height": 51.25, "note": "seed"})])
    add_features(path, "exclusion_areas", [(_square(X0, Y0), {"action": "keep", "note": "lake"}),
                                           (_square(X0 + 10, Y0), {"action": "exclude"})])
    add_features(path, "breaklines", [(LineString([(X0, Y0, 50.0), (X0 + 9, Y0 + 3, 50.5)]),
                                       {"kind": "breakline", "note": "kerb"})])
    add_features(path, "ground_points", [(Point(X0 + 1, Y0 + 2, 49.75), {"note": "road"})])
    add_features(path, "check_points", [(Point(X0 + 3, Y0 + 4, 50.125), {"id": "CP1"})])
    return tmp_path


def snapshot(session: EditSession) -> Dict[str, List[Any]]:
    """Every feature of the session as comparable plain values (WKT with Z, attributes)."""
    return {name: [(fid, g.wkt, a) for fid, g, a in session.features(name)]
            for name in session.layers()}


def test_loads_every_layer_with_fids_z_and_attributes(project: Path, qtbot) -> None:
    s = EditSession(project)
    assert not s.read_only and not s.dirty and s.problem == ""
    (fid, g, a), = s.features("breaklines")
    assert fid == 1 and g.has_z and list(g.coords)[1] == (X0 + 9, Y0 + 3, 50.5)
    assert a == {"kind": "breakline", "note": "kerb"}
    assert [a["action"] for _, _, a in s.features("exclusion_areas")] == ["keep", "exclude"]
    assert s.features("start_points")[0][2] == {"height": 51.25, "note": "seed"}
    assert "25832" in s.crs or "UTM zone 32N" in s.crs
    assert s.source("check_points")() == s.features("check_points")


def test_add_undo_redo(project: Path, qtbot) -> None:
    s = EditSession(project)
    before = snapshot(s)
    seen: List[str] = []
    s.changed.connect(seen.append)
    with qtbot.waitSignal(s.dirty_changed) as blocker:
        fid = s.add("start_points", Point(X0 + 5, Y0 + 5), {"height": 52.0})
    assert blocker.args == [True] and s.dirty
    assert s.undo_stack.undoText() == "Add start point"
    assert fid == 2 and s.feature("start_points", fid)[1] == {"height": 52.0, "note": None}
    s.undo_stack.undo()
    assert snapshot(s) == before and not s.dirty
    s.undo_stack.redo()
    assert s.feature("start_points", fid)[0].equals(Point(X0 + 5, Y0 + 5))
    assert seen == ["start_points"] * 3


def test_texts_of_replace_and_remove(project: Path, qtbot) -> None:
    s = EditSession(project)
    s.replace("breaklines", 1, LineString([(X0, Y0, 1.0), (X0 + 1, Y0, 2.0)]), text="Move vertex")
    assert s.undo_stack.undoText() == "Move vertex"
    assert s.feature("breaklines", 1)[1] == {"kind": "breakline", "note": "kerb"}  # kept
    s.remove("exclusion_areas", 2)
    assert s.undo_stack.undoText() == "Delete exclusion area"
    with pytest.raises(InputError, match="no feature 7"):
        s.remove("exclusion_areas", 7)
    with pytest.raises(InputError, match="no field"):
        s.add("seamlines", LineString([(0, 0), (1, 1)]), {"colour": "red"})
    with pytest.raises(InputError, match="not an edit layer"):
        s.add("roads", Point(0, 0))


def _random_operation(s: EditSession, rng: random.Random, k: int) -> None:
    """One of add / replace / remove on a random layer."""
    layer = rng.choice(["start_points", "exclusion_areas", "breaklines", "check_points"])
    fids = [fid for fid, _, _ in s.features(layer)]
    x, y = X0 + rng.uniform(-50, 50), Y0 + rng.uniform(-50, 50)
    geometry = {"start_points": Point(x, y), "check_points": Point(x, y, 50.0 + k),
                "exclusion_areas": _square(x, y),
                "breaklines": LineString([(x, y, 50.0), (x + 3, y + 1, 51.0 + k)])}[layer]
    attrs = {"start_points": {"height": 50.0 + k}, "check_points": {"id": f"P{k}"},
             "exclusion_areas": {"action": "remove"}, "breaklines": {"kind": "structure_line"}}
    op = rng.choice(["add", "replace", "remove"]) if fids else "add"
    if op == "add":
        s.add(layer, geometry, attrs[layer])
    elif op == "replace":
        s.replace(layer, rng.choice(fids), geometry, attrs[layer] if k % 2 else None)
    else:
        s.remove(layer, rng.choice(fids))


def test_twenty_operations_undone_equal_the_file_as_loaded(project: Path, qtbot) -> None:
    s = EditSession(project)
    loaded = snapshot(s)
    rng = random.Random(21)
    for k in range(20):
        _random_operation(s, rng, k)
    assert s.undo_stack.count() == 20 and snapshot(s) != loaded
    after = snapshot(s)
    while s.undo_stack.canUndo():
        s.undo_stack.undo()
    assert snapshot(s) == loaded and not s.dirty
    while s.undo_stack.canRedo():
        s.undo_stack.redo()
    assert snapshot(s) == after
    s.save()
    assert snapshot(EditSession(project)) == after


def test_save_reload_keeps_attributes_z_crs_and_foreign_content(project: Path, qtbot) -> None:
    path = project / "edits.gpkg"
    con = sqlite3.connect(str(path))  # an operator's own field and table, made in QGIS
    edits_save.register_gpkg_functions(con)  # GDAL's R-tree triggers call them
    con.execute('ALTER TABLE "breaklines" ADD COLUMN "surveyor" TEXT')
    con.execute("UPDATE breaklines SET surveyor = 'ann'")
    con.execute("CREATE TABLE my_notes (id INTEGER PRIMARY KEY, text TEXT)")
    con.execute("INSERT INTO my_notes VALUES (1, 'ask the pilot')")
    con.commit()
    con.close()
    s = EditSession(project)
    assert s.feature("breaklines", 1)[1]["surveyor"] == "ann"
    s.add("breaklines", LineString([(X0, Y0 + 9, 48.5), (X0 + 5, Y0 + 9, 49.0625)]),
          {"kind": "structure_line", "surveyor": "bob"})
    s.remove("exclusion_areas", 1)
    s.add("seamlines", LineString([(X0, Y0), (X0, Y0 + 20)]), {"note": "road"})
    expected = snapshot(s)
    assert s.save() == path and not s.dirty
    again = EditSession(project)
    assert snapshot(again) == expected
    assert [fid for fid, _, _ in again.features("exclusion_areas")] == [2]  # fid kept
    assert again.crs == s.crs
    con = sqlite3.connect(str(path))
    assert con.execute("SELECT text FROM my_notes").fetchall() == [("ask the pilot",)]
    assert con.execute("PRAGMA integrity_check").fetchone() == ("ok",)
    con.close()
    import fiona

    with fiona.open(str(path), layer="breaklines") as src:  # GDAL reads it with Z
        assert src.crs_wkt and len(src) == 2
        assert [f["properties"]["surveyor"] for f in src] == ["ann", "bob"]
    assert not list(project.glob(".edits*"))


def test_interrupted_save_keeps_the_old_file(project: Path, qtbot, monkeypatch) -> None:
    path = project / "edits.gpkg"
    old = path.read_bytes()
    s = EditSession(project)
    s.add("start_points", Point(X0, Y0 + 1), {"height": 50.0})
    calls = []

    def failing(con, table, features):
        calls.append(table.name)
        if len(calls) == 3:
            raise OSError("disk full")
        return real(con, table, features)

    real = edits_save._write_table
    monkeypatch.setattr(edits_save, "_write_table", failing)
    with pytest.raises(OSError, match="disk full"):
        s.save()
    assert path.read_bytes() == old and s.dirty
    assert sorted(p.name for p in project.iterdir()) == ["edits.gpkg"]


def test_missing_file_is_created_on_save(tmp_path: Path, qtbot) -> None:
    s = EditSession(tmp_path, crs=CRS)
    assert not s.read_only and s.features("breaklines") == []
    assert not (tmp_path / "edits.gpkg").exists()
    s.add("ground_points", Point(X0, Y0, 50.5), {"note": "n"})
    s.save()
    again = EditSession(tmp_path)
    assert snapshot(again) == snapshot(s)


@pytest.mark.parametrize("damage", ["garbage", "truncated"])
def test_corrupt_file_is_read_only_and_never_written(project: Path, qtbot, damage) -> None:
    path = project / "edits.gpkg"
    if damage == "garbage":
        path.write_bytes(os.urandom(4096))
    else:
        path.write_bytes(path.read_bytes()[:3000])
    old = path.read_bytes()
    s = EditSession(project)
    assert s.read_only and str(path) in s.problem and "read-only" in s.problem
    with pytest.raises(InputError):
        s.add("start_points", Point(X0, Y0), {"height": 1.0})
    with pytest.raises(InputError):
        s.remove("start_points", 1)
    with pytest.raises(InputError):
        s.save()
    assert s.maybe_save(None) and not s.dirty
    assert path.read_bytes() == old
    assert sorted(p.name for p in project.iterdir()) == ["edits.gpkg"]


def test_read_only_file_is_shown_but_not_edited(project: Path, qtbot) -> None:
    path = project / "edits.gpkg"
    path.chmod(0o444)
    try:
        s = EditSession(project)
        assert s.read_only and "read-only" in s.problem
        assert len(s.features("exclusion_areas")) == 2  # still shown
        with pytest.raises(InputError):
            s.add("start_points", Point(X0, Y0), {"height": 1.0})
    finally:
        path.chmod(0o644)


@pytest.mark.parametrize("answer, closes, saved", [("save", True, True),
                                                   ("discard", True, False),
                                                   ("cancel", False, False)])
def test_maybe_save(project: Path, qtbot, answer, closes, saved) -> None:
    s = EditSession(project)
    asked = []
    s.ask = lambda parent, session: asked.append(session) or answer
    assert s.maybe_save(None)  # nothing to save: no question
    assert not asked
    s.add("start_points", Point(X0, Y0 + 2), {"height": 50.0})
    assert s.maybe_save(None) is closes
    assert asked == [s]
    assert len(EditSession(project).features("start_points")) == (2 if saved else 1)
    assert s.dirty is not saved
