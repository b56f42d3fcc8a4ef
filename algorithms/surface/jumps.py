r"""Height jumps between matched points: upper surfaces and automatic breaklines (issue 19).

A DSM keeps its objects only if the surface step neither rejects the points of a roof as
outliers of a groundel that is mostly ground nor bridges roof and ground by a smooth plate.
Two helpers, both on the raw points in object space:

Consistent populations (:func:`point_support`)
    A point's *support* is the number of other points within ``radius`` (m, in plan) whose
    height agrees with its own: :math:`|Z_j - Z_i| \le \text{tol} + \text{slope}\cdot d_{ij}`
    (``slope`` lets a pitched roof agree with itself). A groundel whose points form two such
    populations (roof and ground) then keeps both: an outlier of the groundel's robust value
    with at least ``min_support`` agreeing neighbours is part of an upper (or lower) surface,
    not a blunder; an isolated false match has none.

Jump breaklines (:func:`jump_breaklines`)
    On the Delaunay triangulation of the points (in plan) an edge is a *jump* when
    :math:`|\Delta Z| \ge` ``min_step`` and :math:`|\Delta Z| / \text{length} \ge` ``min_slope``
    and both of its end points are supported. Its breakline piece joins the centroids of the
    two triangles that share the edge (the dual edge): it crosses the jump edge, and the pieces
    of neighbouring jump edges meet in the centroid of their common triangle, so the pieces
    around a roof form a closed line between the roof points and the ground points. The FE
    surface (:func:`.fe_grid.fe_interpolate`) drops its curvature equations across such a line,
    so each side follows its own points; the wall lies halfway between the last roof point and
    the first ground point (within about half the point spacing of the true wall).
"""

from __future__ import annotations

from typing import Any, List

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import Delaunay, QhullError, cKDTree
from shapely.geometry import MultiLineString

Array = NDArray[Any]


def point_support(x: ArrayLike, y: ArrayLike, z: ArrayLike, radius: float, tol: float = 0.3,
                  slope: float = 0.8) -> Array:
    """Number of neighbours within ``radius`` whose height agrees (module notes).

    Parameters
    ----------
    x, y, z : array_like, shape (n,)
        Points (m); non-finite points get support 0 and support nobody.
    radius : float
        Neighbourhood radius in plan (m).
    tol : float
        Height agreement at distance 0 (m).
    slope : float
        Height agreement per metre of distance (a pitched roof up to atan(slope)).

    Returns
    -------
    ndarray (n,) int64
    """
    x, y, z = (np.ravel(np.asarray(a, float)) for a in (x, y, z))
    out = np.zeros(x.size, np.int64)
    ok = np.flatnonzero(np.isfinite(x) & np.isfinite(y) & np.isfinite(z))
    if ok.size < 2:
        return out
    tree = cKDTree(np.column_stack([x[ok], y[ok]]))
    pairs = tree.query_pairs(radius, output_type="ndarray")
    if len(pairs) == 0:
        return out
    i, j = ok[pairs[:, 0]], ok[pairs[:, 1]]
    dist = np.hypot(x[i] - x[j], y[i] - y[j])
    agree = np.abs(z[i] - z[j]) <= tol + slope * dist
    out += np.bincount(i[agree], minlength=x.size) + np.bincount(j[agree], minlength=x.size)
    return out


def jump_breaklines(x: ArrayLike, y: ArrayLike, z: ArrayLike, min_step: float,
                    min_slope: float = 1.0, supported: ArrayLike = None) -> List[Any]:
    """Breaklines between neighbouring points with a height jump (module notes).

    Parameters
    ----------
    x, y, z : array_like, shape (n,)
        Points (m), finite.
    min_step : float
        Smallest height difference of a jump (m).
    min_slope : float
        Smallest height difference per metre of plan distance.
    supported : array_like of bool, optional
        Points that may end a jump edge (default all).

    Returns
    -------
    list of shapely MultiLineString
        One 2-D MultiLineString of all dual pieces (empty list: no jump).
    """
    x, y, z = (np.ravel(np.asarray(a, float)) for a in (x, y, z))
    if x.size < 4:
        return []
    sup = np.ones(x.size, bool) if supported is None else np.ravel(np.asarray(supported, bool))
    try:
        tri = Delaunay(np.column_stack([x, y]))
    except QhullError:  # all points on a line
        return []
    simp, nb = tri.simplices, tri.neighbors
    cen = np.column_stack([x[simp].mean(1), y[simp].mean(1)])
    pieces = []
    for k in range(3):  # edge opposite vertex k of every triangle, shared with nb[:, k]
        a, b = simp[:, (k + 1) % 3], simp[:, (k + 2) % 3]
        other = nb[:, k]
        dz = np.abs(z[a] - z[b])
        length = np.hypot(x[a] - x[b], y[a] - y[b])
        jump = (dz >= min_step) & (dz >= min_slope * length) & sup[a] & sup[b]
        # each inner edge once (from the triangle with the smaller index); hull edges: none
        t = np.flatnonzero(jump & (other > np.arange(len(simp))))
        pieces.append(np.stack([cen[t], cen[other[t]]], axis=1))
    segs = np.concatenate(pieces) if pieces else np.empty((0, 2, 2))
    if len(segs) == 0:
        return []
    return [MultiLineString([tuple(map(tuple, s)) for s in segs])]


__all__ = ["jump_breaklines", "point_support"]
