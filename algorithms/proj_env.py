"""A PROJ database from another installation, found before any work starts.

Shells that set up QGIS or OSGeo4W often export ``PROJ_DATA`` (or ``PROJ_LIB``) for their own
PROJ. rasterio then reads that folder's ``proj.db`` instead of the one in its wheel, and when
that database is older than the wheel's PROJ needs, every CRS lookup fails
("proj.db contains DATABASE.LAYOUT.VERSION.MINOR = 2 whereas a number >= 6 is expected") —
often late in a run, when the first output is written. :func:`use_own_proj_data` compares the
two databases' layout versions before rasterio is imported and, when the environment's is
older, drops the variables for this process so that rasterio and pyproj use their own data.

This module imports only the standard library (it runs before rasterio is loaded).
"""

from __future__ import annotations

import importlib.util
import os
import sqlite3
from pathlib import Path
from typing import MutableMapping, Optional, Tuple

PROJ_VARIABLES = ("PROJ_DATA", "PROJ_LIB")


def layout_version(folder: Path) -> Optional[Tuple[int, int]]:
    """(major, minor) of the database layout of ``folder/proj.db``; None where there is none
    or it cannot be read."""
    db = Path(folder) / "proj.db"
    if not db.is_file():
        return None
    try:
        with sqlite3.connect(f"file:{db}?mode=ro", uri=True) as conn:
            rows = dict(conn.execute(
                "SELECT key, value FROM metadata WHERE key LIKE 'DATABASE.LAYOUT.VERSION.%'"))
        key = "DATABASE.LAYOUT.VERSION."
        return int(rows[key + "MAJOR"]), int(rows[key + "MINOR"])
    except (sqlite3.Error, KeyError, ValueError):
        return None


def wheel_proj_data() -> Optional[Path]:
    """The PROJ data folder shipped inside the rasterio package (wheels), without importing
    rasterio; None for a rasterio built against the system's PROJ."""
    spec = importlib.util.find_spec("rasterio")
    if spec is None or not spec.submodule_search_locations:
        return None
    folder = Path(next(iter(spec.submodule_search_locations))) / "proj_data"
    return folder if (folder / "proj.db").is_file() else None


def use_own_proj_data(environ: Optional[MutableMapping[str, str]] = None,
                      own: Optional[Path] = None) -> Optional[str]:
    """Drop ``PROJ_DATA``/``PROJ_LIB`` when they name an older PROJ database than the packages'.

    Parameters
    ----------
    environ : mapping, optional
        The environment to check and change (default ``os.environ``).
    own : path, optional
        The packages' own PROJ data folder (default: the one in the rasterio wheel).

    Returns
    -------
    str or None
        A message for the operator saying what was set aside and why; None when nothing was
        changed (no variable set, no packaged data to compare with, or a database as new as
        the packaged one).
    """
    env = os.environ if environ is None else environ
    name = next((n for n in PROJ_VARIABLES if env.get(n)), None)
    if name is None:
        return None
    own = wheel_proj_data() if own is None else own
    needed = layout_version(own) if own is not None else None
    folders = [f for f in env[name].split(os.pathsep) if f]
    given = next((v for v in map(layout_version, map(Path, folders)) if v is not None), None)
    if needed is None or given is None or given >= needed:
        return None
    folder = env[name]
    for n in PROJ_VARIABLES:
        env.pop(n, None)
    return (f"{name}={folder} holds the database of another PROJ installation (layout "
            f"{given[0]}.{given[1]}; the installed packages need {needed[0]}.{needed[1]}); "
            f"this run uses the packages' own PROJ data instead.")
