"""The ``scheduler`` parameter the tiled block products share (mosaic, filters, comparison).

One optional text parameter on each product, not a wrapping algorithm: the operator keeps the
product's own form and options and only says where its tiles run. ``""`` runs them here as
before; ``local`` starts a Dask cluster on this machine; ``tcp://host:port`` uses a running one
(:mod:`..raster.tiled_dask`).
"""

from __future__ import annotations

from .spec import Parameter


def scheduler_parameter() -> Parameter:
    """The ``scheduler`` parameter (optional text)."""
    return Parameter(
        "scheduler", "string", "Dask scheduler for the tiles", optional=True,
        help="Empty: the tiles run one after the other in this process. 'local': a Dask "
             "cluster on this machine. tcp://host:8786: that Dask cluster, whose workers "
             "see the inputs and the output folder under the same paths. The result is the "
             "same; needs pip install \"photodem[dask]\".")


def tile_parameter() -> Parameter:
    """The filters' ``tile`` parameter: side of a tile including its overlap (cells)."""
    return Parameter(
        "tile", "integer", "Tile size [cells]", optional=True, minimum=256, maximum=16384,
        unit="cells",
        help="Larger DSMs are filtered in overlapping tiles of at most this many cells a side "
             "(overlap included; the filter's reach). Default 4096; memory about 150 bytes "
             "per cell of a tile.")


__all__ = ["scheduler_parameter", "tile_parameter"]
