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


__all__ = ["scheduler_parameter"]
