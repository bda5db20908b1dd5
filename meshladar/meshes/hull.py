"""Convex hulls of mesh vertices: the points every extreme of a linear (or perspective)
function of position is attained at, found once per part or scene.

Above 100 000 points the hull is found in two steps: the points strictly inside the
polytope of their extremes along 64 directions are dropped first (Akl–Toussaint); Qhull
then runs on at most 200 000 points.
"""

from __future__ import annotations

import numpy as np

from .directions import fibonacci_sphere

__all__ = ["convex_hull"]

#: Above this many points the hull is found in two steps: the points strictly inside the
#: polytope of their extremes along :data:`_FILTER_DIRECTIONS` directions are dropped
#: first (Akl–Toussaint), in O(points × facets).
_HULL_FILTER_ABOVE = 100_000
#: Qhull runs on at most this many points (it takes ~10 s on 655k points of a sphere, all
#: on the hull); beyond, the filtered points themselves are the answer: a superset of the
#: hull's vertices, so every extreme of a linear or perspective function is the same.
_QHULL_MAX = 200_000
_FILTER_DIRECTIONS = 64


def convex_hull(v):
    """Points (n, 3) that include every vertex of their convex hull (exactly the hull's
    vertices unless they are very many, over 200 000 after filtering), read-only; all the
    points when the hull is degenerate (a flat sheet) or they are few (64 or fewer).

    Above 100 000 points, the points strictly inside the polytope of their extremes along
    64 Fibonacci-lattice directions are dropped first (Akl–Toussaint; a point within
    1e-9 × (largest coordinate extent + largest |coordinate|) of that polytope's boundary
    is kept). Qhull then runs when between 65 and 200 000 points are
    left; beyond 200 000 the filtered points are returned, a superset of the hull's
    vertices, so every extreme of a linear or perspective function of position is the
    same.

    Parameters
    ----------
    v : (n, 3) ndarray
        Points, in scene units; not validated.

    Returns
    -------
    (k, 3) ndarray
        Read-only and C-contiguous, of ``v``'s dtype; always a new array (where no point
        was dropped, a copy of ``v``), so ``v`` and its flags are left as they were.
    """
    from scipy.spatial import ConvexHull, QhullError    # here: a slow import, seldom needed

    hull = v
    if len(v) > _HULL_FILTER_ABOVE:
        hull = _outside_extremes(v)
    if 64 < len(hull) <= _QHULL_MAX:
        try:
            hull = hull[ConvexHull(hull).vertices]
        except (QhullError, ValueError):
            pass
    # a copy where nothing was dropped: making the caller's own array read-only would
    # change their data's flags behind their back
    hull = np.array(hull, order="C") if hull is v else np.ascontiguousarray(hull)
    hull.flags.writeable = False
    return hull


def _outside_extremes(v):
    """The points of v not strictly inside the convex polytope of their extremes along
    :data:`_FILTER_DIRECTIONS` directions: every vertex of v's hull is among them (the
    polytope lies inside the hull, so a hull vertex cannot be inside it). A tolerance of
    1e-9 of the points' extent keeps points on the polytope's faces."""
    dirs = fibonacci_sphere(_FILTER_DIRECTIONS)
    step = 1 << 15                                      # bounded memory
    best = np.full(len(dirs), -np.inf)
    arg = np.zeros(len(dirs), np.int64)
    for a in range(0, len(v), step):                    # each direction's extreme point
        proj = v[a:a + step] @ dirs.T
        k = np.argmax(proj, axis=0)
        top = proj[k, np.arange(len(dirs))]
        better = top > best
        best[better], arg[better] = top[better], a + k[better]
    ext = np.unique(arg)
    from scipy.spatial import ConvexHull, QhullError

    try:
        eq = ConvexHull(v[ext]).equations               # a·x + b <= 0 inside
    except (QhullError, ValueError):
        return v
    span = max(float(v[:, c].max() - v[:, c].min()) for c in range(3))   # not ptp(axis=0): slow
    tol = 1e-9 * (span + float(np.abs(v).max()))
    keep = np.zeros(len(v), bool)
    for a in range(0, len(v), step):
        keep[a:a + step] = (v[a:a + step] @ eq[:, :3].T + eq[:, 3]).max(axis=1) > -tol
    keep[ext] = True
    return v[keep]
