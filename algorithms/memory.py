"""Memory estimates before large allocations.

A parameter slip (a disparity range of ±100 000 px, a grid spacing of 1 mm over a block) must
end with a message naming the parameter, not with minutes of work followed by a
``MemoryError`` — or by the machine swapping. :func:`check_allocation` compares an estimate with
the memory available now.

This module imports only the standard library and :mod:`.errors`.
"""

from __future__ import annotations

import os
from typing import Optional

from .errors import InputError

#: Share of the available memory one allocation may take (the rest is for the other arrays
#: of the run, the libraries and the operating system).
USABLE_SHARE = 0.8

#: Environment variable that caps the memory PhotoDEM assumes available (MB), e.g. on shared
#: machines; unset = what the operating system reports.
MEMORY_LIMIT_ENV = "PHOTODEM_MEMORY_LIMIT_MB"


def available_bytes() -> Optional[int]:
    """Memory available for new allocations (bytes), or ``None`` when unknown.

    ``MemAvailable`` of ``/proc/meminfo`` (Linux), else free physical pages from
    ``os.sysconf``; capped by :data:`MEMORY_LIMIT_ENV` when set.
    """
    found: Optional[int] = None
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    found = int(line.split()[1]) * 1024
                    break
    except (OSError, ValueError, IndexError):
        found = None
    if found is None:
        try:
            found = int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
        except (AttributeError, ValueError, OSError):
            found = None
    limit = os.environ.get(MEMORY_LIMIT_ENV, "").strip()
    if limit:
        try:
            cap = int(float(limit) * 1e6)
        except ValueError:
            raise InputError(f"{MEMORY_LIMIT_ENV} = '{limit}' is not a number of MB.") from None
        found = cap if found is None else min(found, cap)
    return found


def format_bytes(nbytes: float) -> str:
    """``nbytes`` in the largest fitting unit (``"3.2 GB"``)."""
    value = float(nbytes)
    for unit in ("B", "kB", "MB", "GB", "TB", "PB"):
        if abs(value) < 1000.0 or unit == "PB":
            return f"{value:.0f} {unit}" if unit == "B" else f"{value:.1f} {unit}"
        value /= 1000.0
    return f"{value:.1f} PB"  # pragma: no cover


def check_allocation(nbytes: float, what: str, parameter: str,
                     available: Optional[int] = None) -> None:
    """Refuse an allocation that cannot fit in memory, before any work.

    Parameters
    ----------
    nbytes : float
        Estimated size (bytes) of the allocation.
    what : str
        What is allocated ("the dense matching of one tile", "the output grid"), for the message.
    parameter : str
        The parameter(s) the operator changes to make it fit, for the message.
    available : int, optional
        Available memory (bytes); default :func:`available_bytes`.

    Raises
    ------
    InputError
        When ``nbytes`` exceeds :data:`USABLE_SHARE` of the available memory.
    """
    avail = available_bytes() if available is None else available
    if avail is None or nbytes <= USABLE_SHARE * avail:
        return
    raise InputError(
        f"{what[0].upper()}{what[1:]} needs about {format_bytes(nbytes)} of memory but only "
        f"{format_bytes(avail)} is available; change {parameter}."
    )


__all__ = ["MEMORY_LIMIT_ENV", "USABLE_SHARE", "available_bytes", "check_allocation",
           "format_bytes"]
