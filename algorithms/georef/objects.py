"""Area objects shared by every step of the polygon georeferencing.

An object is one closed polygon (outer ring only) from either data set: an image region from
the multiple segmentation, or a reference polygon from a vector layer or a segmented reference
raster. Every later step (moments, invariants, standard position, hypotheses, search, ICP, GCPs)
works on these.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

import numpy as np

#: Object from the image (level-0 image coordinates: x = column, y = row, pixel centres at
#: integer values, so pixel (r, c) covers [c - 0.5, c + 0.5] x [r - 0.5, r + 0.5]).
IMAGE = "image"
#: Object from the reference (map coordinates in the projected CRS the matching runs in).
REFERENCE = "reference"


@dataclass
class PolygonObject:
    """One area object.

    Attributes
    ----------
    id : int
        Running number, unique within its data set (stable: sorted by run, then scan order).
    ring : ndarray, shape (K, 2), float64
        Outer ring, not closed (the first vertex is not repeated), oriented so that its signed
        area (shoelace, in its own coordinates) is positive.
    source : str
        :data:`IMAGE` or :data:`REFERENCE`.
    run : int
        Segmentation run (index into the threshold list); -1 for vector reference polygons.
    threshold : float or None
        The segmentation threshold (DN) of that run.
    touches_border : bool
        The object is cut by the image or reference extent, so its global shape features are
        not valid (it may still be used in the refinement).
    attributes : dict
        Free-form details for reports (e.g. reference feature ids merged into this object).
    """

    id: int
    ring: np.ndarray
    source: str
    run: int = -1
    threshold: Optional[float] = None
    touches_border: bool = False
    attributes: dict = field(default_factory=dict)

    @property
    def area(self) -> float:
        """Area in the object's own units (px² or m²), positive."""
        x, y = self.ring[:, 0], self.ring[:, 1]
        return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def unclosed_ring(ring: np.ndarray) -> np.ndarray:
    """The ring as float64 without a closing vertex equal to its first one.

    Equal means equal: a tolerance relative to the coordinates (``np.allclose``) is metres on
    map coordinates and drops a real last corner of a small footprint."""
    ring = np.asarray(ring, dtype=np.float64)
    if len(ring) > 1 and np.array_equal(ring[0], ring[-1]):
        ring = ring[:-1]
    return ring


def orient_ring(ring: np.ndarray) -> np.ndarray:
    """Return the ring as float64 (K, 2), unclosed, with positive signed area."""
    ring = unclosed_ring(ring)
    x, y = ring[:, 0], ring[:, 1]
    if np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) < 0:
        ring = ring[::-1].copy()
    return ring
