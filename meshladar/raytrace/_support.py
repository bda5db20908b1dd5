"""A point set's extent along any direction, from clusters of its points: exactly the least
and greatest p·u over every point, found by projecting only the clusters whose bound could
hold one (a view's grid planning, per view, over a hull of thousands of points).

The points are grouped by their direction from the centroid (an octahedral map of
:data:`SIDE` × :data:`SIDE` cells); each cluster keeps its mean c and radius r (the
farthest of its points from c), so its projections lie in c·u ± r|u|, and its greatest is at
least c·u (a mean is no more than the largest). The greatest c·u is therefore a lower bound
of the extent's top, every cluster whose c·u + r falls below it is skipped, and the others
are projected in the order of their bounds until the next bound falls below the top found.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["ClusteredPoints", "SIDE"]

#: The octahedral map's cells a side: up to SIDE² clusters.
SIDE = 16


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
        cell = (np.clip(((x + 1.0) * 0.5 * SIDE).astype(np.int64), 0, SIDE - 1) * SIDE
                + np.clip(((y + 1.0) * 0.5 * SIDE).astype(np.int64), 0, SIDE - 1))
        order = np.argsort(cell, kind="stable")
        cell = cell[order]
        self.points = np.ascontiguousarray(p[order])
        used, self.starts = np.unique(cell, return_index=True)
        self.starts = np.append(self.starts, len(cell)).astype(np.int64)
        counts = np.diff(self.starts)
        sums = np.add.reduceat(self.points, self.starts[:-1], axis=0)
        self.centres = np.ascontiguousarray(sums / counts[:, None])
        far = np.linalg.norm(self.points - np.repeat(self.centres, counts, axis=0), axis=1)
        self.radii = np.maximum.reduceat(far, self.starts[:-1])
        # a bound's rounding (c·u + r in float64) is far below this
        self.slack = 1e-12 * float(np.abs(self.points).max() + self.radii.max() + 1.0)

    def extent(self, u):
        """(least, greatest) p·u over every point, with p·u = p₀u₀ + p₁u₁ + p₂u₂ in that
        order.

        Parameters
        ----------
        u : (3,) array_like
            The direction (any length).

        Returns
        -------
        (float, float)
        """
        return _extent(self.points, self.starts, self.centres, self.radii,
                       np.asarray(u, dtype=np.float64), self.slack)


@njit(cache=True, nogil=True)
def _top(points, starts, centres, radii, u, slack):     # pragma: no cover - compiled
    """The greatest p·u (module docstring)."""
    k = centres.shape[0]
    norm = np.sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2])
    slack = slack * norm
    proj = np.empty(k)
    floor = -np.inf
    for c in range(k):
        proj[c] = centres[c, 0] * u[0] + centres[c, 1] * u[1] + centres[c, 2] * u[2]
        floor = max(floor, proj[c])
    cand = np.empty(k, np.int64)
    bound = np.empty(k)
    m = 0
    for c in range(k):
        if proj[c] + radii[c] * norm + slack >= floor:
            cand[m] = c
            bound[m] = -(proj[c] + radii[c] * norm)
            m += 1
    top = -np.inf
    for j in np.argsort(bound[:m]):
        c = cand[j]
        if -bound[j] + slack < top:
            break
        for i in range(starts[c], starts[c + 1]):
            x = points[i, 0] * u[0] + points[i, 1] * u[1] + points[i, 2] * u[2]
            if x > top:
                top = x
    return top


@njit(cache=True, nogil=True)
def _extent(points, starts, centres, radii, u, slack):  # pragma: no cover - compiled
    neg = np.empty(3)
    for i in range(3):
        neg[i] = -u[i]
    return -_top(points, starts, centres, radii, neg, slack), \
        _top(points, starts, centres, radii, u, slack)
