"""Is a surface in the project CRS? One answer for every reader of DEMs and DSMs.

A DEM/DSM in another CRS than the project gives wrong heights without any error when its
coordinates are simply taken as project coordinates. Readers that can reproject on the fly
(orthorectification: a warped VRT, with a warning) ask :func:`same_horizontal_crs`; readers
that cannot (the DEM sampler of footprints and validation, the start surface of object-space
matching) call :func:`check_surface_crs`, which refuses the file with a message naming both
CRSs.

This module imports only the standard library, pyproj/rasterio and :mod:`.errors`.
"""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Any, Optional, Union

import pyproj

from .errors import InputError


def same_horizontal_crs(a: Any, b: Any) -> bool:
    """True when two CRSs have the same horizontal part (compound CRSs reduced to it).

    A DEM in "projected + vertical" (compound) CRS whose projected part is the project CRS
    needs no reprojection: the heights are used as they are (their datum is the operator's
    choice, as for any DEM). ``a`` and ``b`` are rasterio/pyproj CRS objects or anything
    ``pyproj.CRS.from_user_input`` takes.
    """
    try:
        wkt_a, wkt_b = _wkt(a), _wkt(b)
    except Exception:  # an unparsable CRS is never "the same"
        return False
    return _same_horizontal_wkt(wkt_a, wkt_b)


def _wkt(crs: Any) -> str:
    if hasattr(crs, "to_wkt"):
        return str(crs.to_wkt())

    return str(pyproj.CRS.from_user_input(crs).to_wkt())


@functools.lru_cache(maxsize=64)
def _same_horizontal_wkt(wkt_a: str, wkt_b: str) -> bool:
    # cached: pyproj's parsing costs milliseconds, and every ortho of a block asks again
    try:
        pa, pb = pyproj.CRS.from_wkt(wkt_a), pyproj.CRS.from_wkt(wkt_b)
    except Exception:  # an unparsable CRS is never "the same"
        return False

    def horizontal(c: Any) -> Any:
        return c.sub_crs_list[0] if c.is_compound and c.sub_crs_list else c

    return bool(horizontal(pa).equals(horizontal(pb), ignore_axis_order=True))


def crs_label(crs: Any) -> str:
    """A short name of a CRS for messages (``EPSG:25832 (ETRS89 / UTM zone 32N)``)."""
    try:
        c = pyproj.CRS.from_user_input(_wkt(crs))
        code = c.to_epsg()
        return f"EPSG:{code} ({c.name})" if code else c.name
    except Exception:  # show what we have
        return str(crs)[:60]


def check_surface_crs(path: Union[str, Path], file_crs: Any, project_crs: Optional[Any],
                      what: str = "DEM") -> bool:
    """Refuse a surface raster whose CRS is not the project CRS.

    Parameters
    ----------
    path : path
        The raster, for the message.
    file_crs : CRS or None
        The raster's CRS (``None``: it has none and is taken to be in the project CRS).
    project_crs : CRS or str or None
        The project CRS; ``None``/empty skips the check.
    what : str
        "DEM", "DSM", "start surface"…, for the message.

    Returns
    -------
    bool
        ``False`` when the raster has no CRS (the caller may warn), else ``True``.

    Raises
    ------
    InputError
        Naming the file and both CRSs.
    """
    if not project_crs:
        return True
    if file_crs is None or not str(file_crs):
        return False
    if same_horizontal_crs(file_crs, project_crs):
        return True
    raise InputError(
        f"The {what} '{Path(path).name}' is in {crs_label(file_crs)}, the project in "
        f"{crs_label(project_crs)}; reproject it to the project CRS first (e.g. gdalwarp -t_srs)."
    )


__all__ = ["check_surface_crs", "crs_label", "same_horizontal_crs"]
