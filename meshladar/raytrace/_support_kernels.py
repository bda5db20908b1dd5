"""The compiled loops of :mod:`._support` (its module docstring): a cluster's projection,
the bounds that skip clusters, and the search over them. Imported (with numba) at their
first use."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["cluster_top", "cone_bound", "seen_bound", "greatest", "axes_extents",
           "BOUND_SLACK", "CONE_SLACK"]

#: A bound is widened by this fraction of the magnitudes it is made of (its rounding is
#: some 1e-15 of them).
BOUND_SLACK = 1e-9


@njit(cache=True, nogil=True)
def cluster_top(points, lo, hi, o, a, b, scale, seen):   # pragma: no cover - compiled
    """The greatest value over points lo..hi (:func:`greatest`)."""
    top = -np.inf
    for i in range(lo, hi):
        q0, q1, q2 = points[i, 0] - o[0], points[i, 1] - o[1], points[i, 2] - o[2]
        x = q0 * a[0] + q1 * a[1] + q2 * a[2]
        if seen:
            x = x * scale / -(q0 * b[0] + q1 * b[1] + q2 * b[2])
        top = max(top, x)
    return top


#: The cone bound's allowance for its rounding, a fraction of the cluster's reach: its
#: cosines come through square roots of 1 − c² near c = 1, good to some 3e-8.
CONE_SLACK = 1e-6


@njit(cache=True, nogil=True, inline="always")
def cone_bound(cones, c, oa, a, la):                       # pragma: no cover - compiled
    """A bound on (p − o)·a over cluster c's points from its cone (``_support._cones``): with
    p − O = ρ e, ρ ≤ R and e within α of the cone's axis d, e·a ≤ |a| cos(max(0, θ − α)),
    θ the angle of a from d; so (p − o)·a ≤ (O − o)·a + R |a| max(0, cos(max(0, θ − α)))
    (``oa`` = (O − o)·a). Tight where the points lie on a sphere about O, which the
    clusters' spheres are not (their centres sink below the surface)."""
    _, axes, cos_alpha, sin_alpha, reach = cones
    ct = (axes[c, 0] * a[0] + axes[c, 1] * a[1] + axes[c, 2] * a[2]) / la
    ct = min(1.0, max(-1.0, ct))
    cb = 1.0
    if ct < cos_alpha[c]:
        cb = max(0.0, ct * cos_alpha[c] + math.sqrt(1.0 - ct * ct) * sin_alpha[c])
    r = reach[c] * la
    return oa + r * (cb + CONE_SLACK) + BOUND_SLACK * (abs(oa) + r)


@njit(cache=True, nogil=True, inline="always")
def seen_bound(hi, centres, radii, c, o, b, lb, scale):     # pragma: no cover - compiled
    """A bound on (q·a)·scale / (−q·b) over cluster c's points from ``hi``, a bound on
    their q·a: their depth −q·b lies within r|b| of its centre's, so the ratio is at most
    ``hi`` · scale over the least depth (``hi`` ≥ 0) or the greatest (``hi`` < 0); inf
    where the cluster reaches the pinhole's plane."""
    q0, q1, q2 = centres[c, 0] - o[0], centres[c, 1] - o[1], centres[c, 2] - o[2]
    nb = -(q0 * b[0] + q1 * b[1] + q2 * b[2])
    rb = radii[c] * lb
    near = nb - rb - BOUND_SLACK * (abs(nb) + rb)
    if near <= 0.0:
        return np.inf
    return hi * scale / (near if hi >= 0.0 else nb + rb)


@njit(cache=True, nogil=True)
def greatest(points, starts, centres, radii, cones, o, a, b, scale):  # pragma: no cover
    """The greatest of q·a (b = 0) or of (q·a)·scale / (−q·b) over the points, q = p − o
    (module docstring): the cluster of the greatest bound projected first, then every
    cluster whose bound reaches the top found, and whose cone's bound
    (:func:`cone_bound`; in perspective over the sphere's depths, :func:`seen_bound`)
    reaches it too."""
    seen = b[0] != 0.0 or b[1] != 0.0 or b[2] != 0.0
    la = math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])
    lb = math.sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2])
    k = centres.shape[0]
    bounds = np.empty(k)
    first = 0
    origin = cones[0]
    oa = ((origin[0] - o[0]) * a[0] + (origin[1] - o[1]) * a[1]
          + (origin[2] - o[2]) * a[2])
    for c in range(k):
        q0, q1, q2 = centres[c, 0] - o[0], centres[c, 1] - o[1], centres[c, 2] - o[2]
        na = q0 * a[0] + q1 * a[1] + q2 * a[2]
        ra = radii[c] * la
        hi = na + ra + BOUND_SLACK * (abs(na) + ra)
        if seen:
            hi = seen_bound(hi, centres, radii, c, o, b, lb, scale)
        bounds[c] = hi
        if hi > bounds[first]:
            first = c
    top = cluster_top(points, starts[first], starts[first + 1], o, a, b, scale, seen)
    cone = la > 0.0
    for c in range(k):
        if c != first and bounds[c] >= top:
            if cone:
                hi = cone_bound(cones, c, oa, a, la)
                if seen:
                    hi = seen_bound(hi, centres, radii, c, o, b, lb, scale)
                if hi < top:
                    continue                   # its sphere reaches the top, its cone not
            top = max(top, cluster_top(points, starts[c], starts[c + 1], o, a, b, scale,
                                        seen))
    return top


@njit(cache=True, nogil=True)
def axes_extents(points, starts, centres, radii, cones, axes, zero, out):  # pragma: no cover
    """``_support.axes_extents``' loop: each axis's least value as −(greatest along −u), as
    ``ClusteredPoints.extent`` finds it."""
    neg = np.empty(3)
    for j in range(axes.shape[0]):
        for k in range(3):
            neg[k] = -axes[j, k]
        out[j, 0] = -greatest(points, starts, centres, radii, cones, zero, neg, zero, 1.0)
        out[j, 1] = greatest(points, starts, centres, radii, cones, zero, axes[j], zero, 1.0)
