"""Whether edits.gpkg can take edits now: missing, read-only, locked by another program."""

from __future__ import annotations

import sqlite3

from photodem.algorithms.project.edits import create_edits, edits_access


def test_edits_access_missing_read_only_locked(tmp_path) -> None:
    path = tmp_path / "edits.gpkg"
    assert edits_access(path)[0] == "missing"
    create_edits(path, "EPSG:25832")
    assert edits_access(path) is None
    path.chmod(0o444)
    try:
        assert edits_access(path)[0] == "read-only"
    finally:
        path.chmod(0o644)
    holder = sqlite3.connect(path)
    try:
        holder.execute("BEGIN IMMEDIATE")  # another program's write lock
        kind, detail = edits_access(path)
        assert kind == "locked" and "locked" in detail
    finally:
        holder.rollback()
        holder.close()
    assert edits_access(path) is None
