"""A scene's extents along view directions (:meth:`meshladar.scene.Scene.view_ranges`): its
nearest and farthest range per view, over a mesh's support points or over analytic
shapes' exact boundaries."""

from __future__ import annotations

import numpy as np

from .shapes import to_frame

__all__ = ["HULL_MIN_VIEWS", "point_ranges", "shape_ranges", "circle_about_box"]

#: From this many views on, a mesh scene's extents (ranges, ray grids) are taken over its
#: convex hull's vertices, built once (:meth:`meshladar.scene.Scene.support_points`); fewer
#: views project every vertex, which costs less than the hull: measured on a 41k-vertex
#: sphere, qhull took 0.20 s, one projection of every vertex 33 µs, and a view's planning
#: makes about five (its range, its grid's extent along u and v, twice).
HULL_MIN_VIEWS = 512


def point_ranges(points, w):
    """(nearest, farthest) range r = −p·w over ``points`` (k, 3) for each view vector of
    ``w`` (n, 3), in blocks of views (memory bounded: k × block)."""
    lo, hi = np.empty(len(w)), np.empty(len(w))
    block = max(1, min(256, int(4e6 // len(points))))
    for start in range(0, len(w), block):
        r = -(points @ w[start:start + block].T)
        lo[start:start + block], hi[start:start + block] = r.min(axis=0), r.max(axis=0)
    return lo, hi


def shape_ranges(shapes, w):
    """(nearest, farthest) range over analytic ``shapes`` for each view vector of ``w``
    (n, 3; x and y used): an ellipse's support along −w is its centre's range ∓ its
    half-width along w."""
    lo, hi = np.full(len(w), np.inf), np.full(len(w), -np.inf)
    for s in shapes:
        a, b = s.axes
        wx, wy = w[:, 0], w[:, 1]
        xl, yl = to_frame(s.angle, wx, wy)
        half = np.hypot(a * xl, b * yl)
        rc = -(s.center[0] * wx + s.center[1] * wy)
        lo, hi = np.minimum(lo, rc - half), np.maximum(hi, rc + half)
    return lo, hi


def circle_about_box(centres, radii):
    """((x, y), r): the circle about the centre of the x-y bounding box of circles
    (``centres`` (n, 2), ``radii`` (n,); points where the radii are 0) that holds them all."""
    lo = (centres - radii[:, None]).min(axis=0)
    hi = (centres + radii[:, None]).max(axis=0)
    c = 0.5 * (lo + hi)
    return (float(c[0]), float(c[1])), float(np.max(np.hypot(*(centres - c).T) + radii))
