"""A PROJ_DATA of another PROJ installation is set aside before rasterio loads."""

from __future__ import annotations

import os
import sqlite3
import subprocess
import sys
from pathlib import Path

import pytest

from photodem.algorithms.proj_env import layout_version, use_own_proj_data, wheel_proj_data


def _proj_db(folder: Path, minor: int) -> Path:
    """A folder with a proj.db that holds only the metadata of layout 1.<minor>."""
    folder.mkdir(parents=True, exist_ok=True)
    with sqlite3.connect(folder / "proj.db") as conn:
        conn.execute("CREATE TABLE metadata (key TEXT, value TEXT)")
        conn.executemany("INSERT INTO metadata VALUES (?, ?)",
                         [("DATABASE.LAYOUT.VERSION.MAJOR", "1"),
                          ("DATABASE.LAYOUT.VERSION.MINOR", str(minor))])
    return folder


def test_an_older_database_is_set_aside_with_a_message(tmp_path) -> None:
    old, own = _proj_db(tmp_path / "old", 2), _proj_db(tmp_path / "own", 6)
    env = {"PROJ_DATA": str(old), "PROJ_LIB": str(old), "PATH": "/bin"}
    note = use_own_proj_data(env, own)
    assert env == {"PATH": "/bin"}
    assert "PROJ_DATA=" in note and "1.2" in note and "1.6" in note


def test_a_database_as_new_as_the_packages_is_kept(tmp_path) -> None:
    own = _proj_db(tmp_path / "own", 6)
    for minor in (6, 7):
        given = str(_proj_db(tmp_path / f"given{minor}", minor))
        env = {"PROJ_LIB": given}
        assert use_own_proj_data(env, own) is None and env == {"PROJ_LIB": given}


def test_nothing_changes_without_a_variable_or_a_database_to_compare(tmp_path) -> None:
    old, own = _proj_db(tmp_path / "old", 2), _proj_db(tmp_path / "own", 6)
    assert use_own_proj_data({}, own) is None
    # a folder without proj.db, or packages without their own data: left to PROJ
    env = {"PROJ_DATA": str(tmp_path / "nothing")}
    assert use_own_proj_data(env, own) is None and "PROJ_DATA" in env
    env = {"PROJ_DATA": str(old)}
    assert use_own_proj_data(env, tmp_path / "nothing") is None and "PROJ_DATA" in env


def test_a_search_path_of_several_folders_is_judged_by_its_first_database(tmp_path) -> None:
    old, own = _proj_db(tmp_path / "old", 2), _proj_db(tmp_path / "own", 6)
    env = {"PROJ_DATA": os.pathsep.join([str(tmp_path / "empty"), str(old)])}
    assert use_own_proj_data(env, own) is not None and env == {}
    assert layout_version(old) == (1, 2) and layout_version(tmp_path / "empty") is None


@pytest.mark.skipif(wheel_proj_data() is None,
                    reason="rasterio uses the system's PROJ data (no wheel data to compare)")
def test_crs_lookups_work_with_a_foreign_proj_data(tmp_path) -> None:
    """The real path: rasterio from its wheel in a shell whose PROJ_DATA names an older
    database. Without the check a CRS lookup fails; with it the lookup works."""
    env = dict(os.environ, PROJ_DATA=str(_proj_db(tmp_path / "old", 2)))
    env.pop("PROJ_LIB", None)
    lookup = "import rasterio.crs; print(rasterio.crs.CRS.from_epsg(32632).to_epsg())"
    check = "from photodem.algorithms.proj_env import use_own_proj_data as u; u(); "
    plain = subprocess.run([sys.executable, "-c", lookup], env=env, capture_output=True,
                           text=True)
    assert plain.returncode != 0
    fixed = subprocess.run([sys.executable, "-c", check + lookup], env=env,
                           capture_output=True, text=True)
    assert fixed.returncode == 0, fixed.stderr
    assert fixed.stdout.strip() == "32632"


@pytest.mark.skipif(wheel_proj_data() is None,
                    reason="rasterio uses the system's PROJ data (no wheel data to compare)")
def test_the_command_warns_and_runs(tmp_path) -> None:
    env = dict(os.environ, PROJ_DATA=str(_proj_db(tmp_path / "old", 2)))
    run = subprocess.run([sys.executable, "-m", "photodem.algorithms.cli_entry", "list"],
                         env=env, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert "warning" in run.stderr and "PROJ_DATA" in run.stderr
