"""The analytic shapes' coating kernel: each ellipse's boundary cut, per view, into N equal
pieces of eccentric angle measured from the point nearest the ladar (the glint's centre,
where the range is stationary), and every piece's visible part split between range bins
exactly.

On an ellipse p(t) = c + R(ψ)(A cos t, B sin t) seen along w, with u = t − t0 the angle from
the nearest point, the range is r_top + 2M sin²(u/2) (monotone in |u|), the transverse
position s_c + K sin(u − δ) (monotone on the facing arc |u − δ| < π/2), cos θ ∝ K cos(u − δ)
and sin θ ∝ M |sin u| (the closed forms of :mod:`meshladar.forward.analytic`). Bin edges,
silhouettes and shadow boundaries are thus crossed at known u and cut the pieces where they
fall; each cut piece's weight is its arc length (midpoint rule in u) and its table angle the
incidence angle at its middle. The error is second order in the piece's length (it falls
4× per doubling of N), also where a glint sits on a bin edge or a shadow boundary.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.sparse import csr_matrix

from ._tables import grid_position

#: Most (piece, view) pairs held at once (memory: ~30 float64 arrays of this size).
_CHUNK = 1_000_000


class _Views:
    """One ellipse's closed-form geometry per view (arrays over views)."""

    def __init__(self, shape, phi):
        a, b = shape.axes
        self.a, self.b = a, b
        beta = phi - shape.angle
        cb, sb = np.cos(beta), np.sin(beta)
        self.M = np.hypot(a * cb, b * sb)
        self.K = np.hypot(b * cb, a * sb)
        self.t0 = np.arctan2(b * sb, a * cb)
        self.delta = np.arctan2(a * sb, b * cb) - self.t0
        cx, cy = shape.center
        self.r_top = -(cx * np.cos(phi) + cy * np.sin(phi)) - self.M
        self.s_c = -cx * np.sin(phi) + cy * np.cos(phi)
        self.s_lo, self.s_hi = self.s_c - self.K, self.s_c + self.K

    def front_range(self, s):
        x = np.clip((s - self.s_c) / self.K, -1.0, 1.0)
        return self.r_top + 2.0 * self.M * np.sin(0.5 * (np.arcsin(x) + self.delta)) ** 2

    def tau(self, edges):
        """(n_views, n_edges): |u| at which the range crosses each bin edge (0 before the
        nearest point, π beyond the farthest)."""
        x = (edges[None, :] - self.r_top[:, None]) / (2.0 * self.M[:, None])
        return 2.0 * np.arcsin(np.sqrt(np.clip(x, 0.0, 1.0)))


def _shadows(geoms, i):
    """(n_views, n_shapes) intervals of u on shape i in the other shapes' shadows (empty,
    at the silhouette, where the other shape is not in front): disjoint convex shapes keep
    one order on every line that meets both."""
    gi = geoms[i]
    lo = np.repeat((gi.delta + 0.5 * math.pi)[:, None], len(geoms), axis=1)
    hi = lo.copy()
    for j, gj in enumerate(geoms):
        if j == i:
            continue
        a = np.maximum(gi.s_lo, gj.s_lo)
        c = np.minimum(gi.s_hi, gj.s_hi)
        mid = 0.5 * (a + c)
        front = (c > a) & (gj.front_range(mid) < gi.front_range(mid))
        for side, S in ((lo, gj.s_lo), (hi, gj.s_hi)):
            u = gi.delta + np.arcsin(np.clip((S - gi.s_c) / gi.K, -1.0, 1.0))
            side[front, j] = u[front]
    return lo, hi


def _visible(ua, ub, g, shadow):
    """Per (piece, view): the visible interval [lo, hi] of the piece [ua, ub] (facing, and
    cut by each shadow from the side it covers)."""
    lo = np.maximum(ua[:, None], (g.delta - 0.5 * math.pi)[None, :])
    hi = np.minimum(ub[:, None], (g.delta + 0.5 * math.pi)[None, :])
    for j in range(shadow[0].shape[1]):
        A, B = shadow[0][None, :, j], shadow[1][None, :, j]
        covered = (A <= lo) & (B >= hi)
        lo, hi = (np.where((A <= lo) & (B > lo), B, lo),
                  np.where((A < hi) & (B >= hi), A, hi))
        lo = np.where(covered, hi, lo)
    return lo, hi


def _chunk(g, ua, ub, ctx):
    """(rows, θ, weight) of the pieces [ua, ub] of u, every view."""
    edges, tau_e, shadow, power = ctx
    n_bins = edges.size - 1
    lo, hi = _visible(ua, ub, g, shadow)
    si, vi = np.nonzero(hi > lo)
    lo, hi = lo[si, vi], hi[si, vi]
    sign = np.where(hi > 0, 1.0, -1.0)                 # each piece lies on one side of 0
    ta, tb = np.minimum(np.abs(lo), np.abs(hi)), np.maximum(np.abs(lo), np.abs(hi))
    r_top, two_m = g.r_top[vi], 2.0 * g.M[vi]
    # bins by range, one either side to spare (the overlaps below are exact in τ)
    k0 = np.searchsorted(edges, r_top + two_m * np.sin(0.5 * ta) ** 2, side="right") - 2
    k1 = np.searchsorted(edges, r_top + two_m * np.sin(0.5 * tb) ** 2, side="right")
    rows, thetas, weights = [], [], []
    for q in range(int((k1 - k0).max(initial=0)) + 1):
        k = k0 + q
        sel = (k <= k1) & (k >= 0) & (k < n_bins)
        if not sel.any():
            continue
        kk, v = k[sel], vi[sel]
        o_lo = np.maximum(ta[sel], tau_e[v, kk])
        o_hi = np.minimum(tb[sel], tau_e[v, kk + 1])
        length = np.maximum(o_hi - o_lo, 0.0)
        um = sign[sel] * 0.5 * (o_lo + o_hi)
        t = g.t0[v] + um
        cos_t = g.K[v] * np.cos(um - g.delta[v])
        sin_t = g.M[v] * np.abs(np.sin(um))
        dl = np.hypot(g.a * np.sin(t), g.b * np.cos(t)) * length
        rows.append(v * n_bins + kk)
        thetas.append(np.arctan2(sin_t, np.maximum(cos_t, 0.0)))
        weights.append(dl * (np.maximum(cos_t, 0.0) / np.hypot(cos_t, sin_t) if power
                             else 1.0))
    return rows, thetas, weights


def analytic_triplets(scene, ladar, power, samples):
    """Per shape, (rows, θ, weight) of its pieces over every view (concatenated arrays);
    ``samples`` pieces per boundary (rounded up to even, so that u = 0 is a cut)."""
    phi = np.deg2rad(ladar.angles_deg)
    geoms = [_Views(s, phi) for s in scene.shapes]
    n = samples + samples % 2
    du = 2.0 * math.pi / n
    step = max(1, _CHUNK // max(1, phi.size))
    out = []
    for i, g in enumerate(geoms):
        ctx = (ladar.bin_edges, g.tau(ladar.bin_edges), _shadows(geoms, i), power)
        rows, thetas, weights = [], [], []
        for start in range(0, n, step):
            j = np.arange(start, min(n, start + step))
            r_, t_, w_ = _chunk(g, -math.pi + j * du, -math.pi + (j + 1) * du, ctx)
            rows += r_
            thetas += t_
            weights += w_
        out.append(tuple(np.concatenate(x) if x else np.zeros(0) for x in
                         (rows, thetas, weights)))
    return out


def interp_matrix(rows, theta, omega, n_rows, grid, *, cubic=False):
    """The sparse (n_rows, grid) matrix putting weight ω at angle θ into row ``rows`` by
    interpolation on the θ grid of ``grid`` points on [0, π/2] (at θ = (π/2) u², u even,
    :func:`._tables.grid_position`): linear, or cubic in u (Keys' a = −½, third order: a
    0.007 rad glint's table error falls from ~1e-4 to ~1e-6; the table is even in u about
    0, as it is in θ, and the last interval is linear)."""
    rows = np.asarray(rows, np.int64)
    u = grid_position(theta, grid)
    j = np.minimum(np.floor(u).astype(np.int64), grid - 2)
    f = u - j
    if not cubic:
        cols, vals = (j, j + 1), (1.0 - f, f)
    else:
        f2, f3 = f * f, f * f * f
        last = j == grid - 2
        cols = (np.abs(j - 1), j, j + 1, np.minimum(j + 2, grid - 1))
        vals = (np.where(last, 0.0, 0.5 * (-f3 + 2.0 * f2 - f)),
                np.where(last, 1.0 - f, 0.5 * (3.0 * f3 - 5.0 * f2 + 2.0)),
                np.where(last, f, 0.5 * (-3.0 * f3 + 4.0 * f2 + f)),
                np.where(last, 0.0, 0.5 * (f3 - f2)))
    # CSR straight from the rows' order (column indices unsorted, repeats summed by the
    # products): no COO conversion, no sort within rows
    order = np.argsort(rows, kind="stable")
    indptr = np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=n_rows))])
    indptr = indptr * len(cols)
    data = np.stack([omega[order] * v[order] for v in vals], axis=1).ravel()
    indices = np.stack([c[order] for c in cols], axis=1).ravel()
    return csr_matrix((data, indices.astype(np.int32 if grid < 2 ** 31 else np.int64),
                       indptr), shape=(n_rows, grid))
