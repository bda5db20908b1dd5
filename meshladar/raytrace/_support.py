"""A point set's extent along any direction, from clusters of its points: exactly the least
and greatest p·u over every point, found by projecting only the clusters whose bound could
hold one (a view's grid planning, per view, over a hull of thousands of points).

The points are grouped by their direction from the centroid (an octahedral map of
side × side cells, the side from :data:`SIDE` to 4 × :data:`SIDE` for about
:data:`POINTS_A_CLUSTER` points a cell); each cluster keeps its mean c and radius r (the
farthest of its points from c), so its projections lie in c·u ± r|u|. The cluster with
the greatest such bound is projected first; every other cluster whose bound falls below
the top found is skipped. Along a plain projection a cluster whose sphere reaches the top
is also held to its cone: from the centroid O its points lie within R of O and their
directions within α of an axis d, so (p − O)·u ≤ R|u| cos(max(0, θ − α)), θ the angle of
u from d: a sphere's centre sinks below a curved surface and its bound lets a fringe of
clusters through that the cone, tight on a sphere, keeps out (on an icosphere's 41k
vertices, 2.5 clusters projected a direction instead of 34). Seen in perspective from a
pinhole o (a sensor at a standoff),
a point's value is (q·u)·D / (−q·w), q = p − o: its numerator and depth each lie within
r|u| and r|w| of the centre's, which bounds the ratio the same way (a cluster that
reaches the pinhole's plane is always projected), and its cone's bound on the numerator
over the same depths keeps out the same fringe. Bounds are widened by
``_support_kernels.BOUND_SLACK`` of their terms for rounding, so the extents are exact.
"""

from __future__ import annotations

import math

import numpy as np

from .._lazy import deferred_module
from .grid import dot

# compiled loops, imported (with numba) at their first use: a small run loads neither
_kernels = deferred_module("meshladar.raytrace._support_kernels")

__all__ = ["ClusteredPoints", "SIDE", "POINTS_A_CLUSTER", "points_extent", "axes_extents"]

#: The octahedral map's least cells a side (up to SIDE² clusters); at most 4 × SIDE.
SIDE = 16
#: The points a cluster holds, about, where the side allows: a query's cost, the bounds of
#: every cluster and the points of the few near the top, is least near this (measured on
#: icospheres' 41k and 655k vertices, with the cones: 6.1 and 30 µs an axis; 14 and 230
#: with spheres alone at side 16; elongated hulls, an ellipsoid 5:1:0.3 and a capsule,
#: 20-24 µs at 41k, slower with bigger clusters).
POINTS_A_CLUSTER = 100


class ClusteredPoints:
    """``points`` (k, 3) grouped for :meth:`extent` (module docstring).

    Parameters
    ----------
    points : (k, 3) array_like
        The points, float64 (a copy is kept, sorted by cluster).
    """

    def __init__(self, points):
        p = np.asarray(points, dtype=np.float64)
        d = p - p.mean(axis=0)
        d = d / np.maximum(np.abs(d).sum(axis=1), 1e-300)[:, None]
        x, y = d[:, 0], d[:, 1]
        low = d[:, 2] < 0.0
        x, y = (np.where(low, (1.0 - np.abs(y)) * np.sign(x), x),
                np.where(low, (1.0 - np.abs(x)) * np.sign(y), y))
        side = int(np.clip(round(math.sqrt(len(p) / POINTS_A_CLUSTER)), SIDE, 4 * SIDE))
        cell = (np.clip(((x + 1.0) * 0.5 * side).astype(np.int64), 0, side - 1) * side
                + np.clip(((y + 1.0) * 0.5 * side).astype(np.int64), 0, side - 1))
        order = np.argsort(cell, kind="stable")
        cell = cell[order]
        self.points = np.ascontiguousarray(p[order])
        _, self.starts = np.unique(cell, return_index=True)
        self.starts = np.append(self.starts, len(cell)).astype(np.int64)
        counts = np.diff(self.starts)
        sums = np.add.reduceat(self.points, self.starts[:-1], axis=0)
        self.centres = np.ascontiguousarray(sums / counts[:, None])
        far = np.linalg.norm(self.points - np.repeat(self.centres, counts, axis=0), axis=1)
        self.radii = np.maximum.reduceat(far, self.starts[:-1])
        self.cones = _cones(self.points, self.starts)

    def extent(self, u, origin=None):
        """(least, greatest) q·u over every point, q = p − ``origin``, with
        q·u = q₀u₀ + q₁u₁ + q₂u₂ in that order.

        Parameters
        ----------
        u : (3,) array_like
            The direction (any length).
        origin : (3,) array_like, optional
            Subtracted from every point first (default none: q = p, the same bits).

        Returns
        -------
        (float, float)
        """
        return self._both(u, _NO_AXIS, 1.0, origin)

    def seen_extent(self, u, w, scale, origin):
        """(least, greatest) of (q·u)·scale / d over every point, q = p − ``origin`` and
        d = −q·w > 0 (its depth along −w: a point as a pinhole at ``origin`` looking along
        −w projects it, scaled to a plane at ``scale``), in that order of operations.

        Parameters
        ----------
        u, w : (3,) array_like
            The plane's axis and the viewing direction (unit vectors).
        scale : float
            The plane's distance from the origin, > 0.
        origin : (3,) array_like
            The pinhole; every point must lie in front of it (d > 0).

        Returns
        -------
        (float, float)
        """
        return self._both(u, np.asarray(w, dtype=np.float64), float(scale), origin)

    def extents(self, axes):
        """:meth:`extent` along each row of ``axes`` (k, 3) in one compiled pass
        (:func:`axes_extents`): (k, 2) float64, the same numbers."""
        return axes_extents(self.points, axes, self.clusters)

    @property
    def clusters(self):
        """(starts, centres, radii, cones): the compiled search's arrays
        (:func:`axes_extents`; ``cones`` from :func:`_cones`)."""
        return self.starts, self.centres, self.radii, self.cones

    def _both(self, u, w, scale, origin):
        u = np.asarray(u, dtype=np.float64)
        o = _NO_AXIS if origin is None else np.asarray(origin, dtype=np.float64)
        args = (self.points, self.starts, self.centres, self.radii, self.cones, o)
        return (-_kernels.greatest(*args, -u, w, scale),
                _kernels.greatest(*args, u, w, scale))


#: No origin (q = p) / no depth (a plain projection).
_NO_AXIS = np.zeros(3)


#: From this many points on, :func:`points_extent` projects them in one compiled pass;
#: below it with numpy (the same bits), whose temporaries cost little there (0.3 ms for
#: an 82k-face mesh's 41k vertices) and which a run's first call need not compile or load
#: (0.1 s of a one-view command's first run after an install).
COMPILED_FROM = 1 << 17


def points_extent(points, u, origin=None, w=None, scale=1.0):
    """(least, greatest) q·u over every point, q = p − ``origin`` (default q = p), or with
    ``w`` their perspective (q·u)·``scale`` / (−q·w), each by one compiled pass over all
    the points (``_support_kernels.cluster_top``, as a cluster is projected): the numbers
    of numpy's projection then its min and max (the same operations in the same order),
    without its temporaries (a 2.6M-point mesh's two extents a view: 3 ms instead of 42);
    below :data:`COMPILED_FROM` points, by numpy's projection itself.

    Parameters
    ----------
    points : (k, 3) float64 numpy.ndarray
        The points, k ≥ 1.
    u : (3,) array_like
        The direction (any length).
    origin : (3,) array_like, optional
        Subtracted from every point first (with ``w``: the pinhole's position).
    w : (3,) array_like, optional
        Perspective from a pinhole looking along −w (every point in front of it).
    scale : float
        With ``w``: the distance of the plane the points are projected on.

    Returns
    -------
    (float, float)
    """
    u = np.asarray(u, dtype=np.float64)
    o = _NO_AXIS if origin is None else np.asarray(origin, dtype=np.float64)
    b = _NO_AXIS if w is None else np.asarray(w, dtype=np.float64)
    n, seen = points.shape[0], w is not None
    if n < COMPILED_FROM:                       # numpy's own projection, min and max
        q = points if origin is None else points - o
        x = dot(q, u) * scale / -dot(q, b) if seen else dot(q, u)
        return float(x.min()), float(x.max())
    return (-float(_kernels.cluster_top(points, 0, n, o, -u, b, float(scale), seen)),
            float(_kernels.cluster_top(points, 0, n, o, u, b, float(scale), seen)))


def axes_extents(points, axes, clusters=None):
    """(least, greatest) p·u over ``points`` along each row u of ``axes``, in one compiled
    pass (many views' grids planned at once: :func:`meshladar.raytrace.grid.grid_plans`):
    over the points' ``clusters`` (:class:`ClusteredPoints`' starts, centres and radii) as
    :meth:`ClusteredPoints.extent` finds each, else over every point as
    :func:`points_extent` does (numpy's projection, min and max: the same numbers).

    Parameters
    ----------
    points : (n, 3) float64 numpy.ndarray
        The points (sorted by cluster with ``clusters``), n ≥ 1.
    axes : (k, 3) array_like
        The directions (any length).
    clusters : tuple, optional
        :attr:`ClusteredPoints.clusters`; default: the points as one cluster, every point
        projected.

    Returns
    -------
    (k, 2) float64 numpy.ndarray
    """
    axes = np.ascontiguousarray(axes, dtype=np.float64).reshape(-1, 3)
    if clusters is None:                  # one cluster of unbounded radius: every point
        inf = np.array([np.inf])
        clusters = (np.array([0, len(points)], np.int64), np.zeros((1, 3)), inf,
                    (np.zeros(3), np.zeros((1, 3)), -np.ones(1), np.ones(1), inf))
    out = np.empty((len(axes), 2))
    _kernels.axes_extents(points, *clusters, axes, _NO_AXIS, out)
    return out


def _cones(points, starts):
    """Each cluster's cone about the points' centroid O: (O, the unit axes d (c, 3), cos α
    and sin α (c,) of the widest angle of a point's direction from d, the reach R (c,) of
    the farthest point from O); a cluster whose directions do not share a side has α = π,
    and its cone bounds nothing its sphere does not."""
    origin = points.mean(axis=0)
    q = points - origin
    length = np.linalg.norm(q, axis=1)
    unit = q / np.where(length > 0.0, length, 1.0)[:, None]
    counts = np.diff(starts)
    axes = np.add.reduceat(unit, starts[:-1], axis=0)
    size = np.linalg.norm(axes, axis=1)
    wide = size < 1e-3 * counts                       # directions all round: no cone
    axes = axes / np.where(wide, 1.0, size)[:, None]
    cos = np.einsum("ij,ij->i", unit, np.repeat(axes, counts, axis=0))
    cos = np.where(length > 0.0, cos, 1.0)            # a point at O lies in any cone
    cos_alpha = np.where(wide, -1.0, np.clip(np.minimum.reduceat(cos, starts[:-1]), -1, 1))
    sin_alpha = np.sqrt(1.0 - cos_alpha * cos_alpha)
    reach = np.maximum.reduceat(length, starts[:-1])
    return (origin, np.ascontiguousarray(axes), cos_alpha, sin_alpha, reach)
