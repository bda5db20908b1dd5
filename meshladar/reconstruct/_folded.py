"""Backprojection of views 180° apart folded into one: half the interpolations of FBP over
the full circle.

Range is r = −x·w(φ), so the view at φ + 180° sees every point at the opposite range, and on
bins symmetric about 0 (up to a whole number of bins) its sample k lands on sample m − k of
the view at φ, m = −2 r₀ / Δr. Linear interpolation commutes with that reversal, so inside
the range both views cover, view a's filtered profile plus view b's reversed one,
interpolated once, is the two views' sum: one pass of gathers instead of two. Where only
one view's bins reach (a few bins at either end when m ≠ n − 1), and within
:data:`END_MARGIN` of where that changes, each view is sampled on its own line as
:func:`~meshladar.reconstruct._kernels.backproject` samples it, so a pixel exactly on a
profile's last sample is in or out as it is there. The image equals the
unfolded one to rounding (tests/reconstruct/test_folded.py states the tolerance); the
order of the additions differs, so not bit for bit.
"""

from __future__ import annotations

import numpy as np
from numba import carray, njit, prange

from ._kernels import (_CHUNK, _add_linear, _add_view_scalar, _finite_ends, _first,
                       _row_buffer, _view_line, backproject)

__all__ = ["END_MARGIN", "FOLD_REACH", "FOLD_TOL", "backproject_views", "opposite_pairs"]

_EPS = float(np.finfo(np.float64).eps)

#: The largest |cos φ_a + cos φ_b| and |sin φ_a + sin φ_b| of a pair of views folded, and
#: (times max(1, |m|)) the largest distance of m = −2 r₀ / Δr from a whole number: 8 units
#: in the last place of 1. Angles 180° apart in floating point give directions opposite to
#: 4.6 of them (measured over 10⁵ angles), so view b's positions m − u differ from its own by
#: no more than the rounding both already have; angles that differ from 180° by more (made
#: by repeated addition, say: 2e-11° off) are backprojected view by view.
FOLD_TOL = 8 * _EPS

#: The reach of pixels and bins from range zero, (max |x| + max |y| + |r₀|) / Δr, in bins,
#: beyond which nothing is folded: sample positions are rounded to ~1e-16 of it, which must
#: stay well below :data:`END_MARGIN`.
FOLD_REACH = 1e7

#: Columns whose u lies within this many bins of either end of the range both views cover
#: are sampled view by view on each view's own line (u_b = m − u holds there only to
#: rounding, below 1e-8 bins within :data:`FOLD_REACH`, and a sample on a profile's last
#: bin is in or out by it).
END_MARGIN = 1e-6


def opposite_pairs(angles_deg, cos_phi, sin_phi):
    """(a, b): views a[p] and b[p] 180° apart (a the earlier), each view in at most one
    pair, their directions opposite to :data:`FOLD_TOL` (repeated angles pair in order)."""
    key = np.round(np.mod(np.asarray(angles_deg, float), 360.0) * 1e6).astype(np.int64)
    key %= 360_000_000
    waiting = {}
    a, b = [], []
    for i, k in enumerate(key.tolist()):
        queue = waiting.get((k + 180_000_000) % 360_000_000)
        j = queue.pop(0) if queue else None
        if j is not None and (abs(cos_phi[i] + cos_phi[j]) <= FOLD_TOL
                              and abs(sin_phi[i] + sin_phi[j]) <= FOLD_TOL):
            a.append(j)
            b.append(i)
            continue
        if j is not None:
            queue.insert(0, j)
        waiting.setdefault(k, []).append(i)
    return np.array(a, dtype=np.int64), np.array(b, dtype=np.int64)


def backproject_views(q, angles_deg, weight, r0, inv_dr, x, y, nearest, out):
    """:func:`~meshladar.reconstruct._kernels.backproject` of views at ``angles_deg``
    (degrees), with the pairs of views 180° apart folded (:func:`backproject_folded`)
    where that gives each view's own image to rounding: linear interpolation, x
    non-decreasing, bins symmetric about 0 to a whole number m − n + 1 of bins with
    |m − (n − 1)| ≤ n / 8, directions opposite to :data:`FOLD_TOL`, everything within
    :data:`FOLD_REACH` bins of range zero, and the pair's folded profile finite (w_a > 0).
    Every other view is backprojected on its own. Returns the number of pairs folded."""
    phi = np.deg2rad(angles_deg)
    cos_phi, sin_phi = np.cos(phi), np.sin(phi)
    n = q.shape[1]
    m = -2.0 * r0 * inv_dr
    whole = float(np.round(m)) if np.isfinite(m) else np.nan
    with np.errstate(over="ignore", invalid="ignore"):       # inf or NaN: not folded
        reach = (np.max(np.abs(x), initial=0.0) + np.max(np.abs(y), initial=0.0)
                 + abs(r0)) * inv_dr
    if (nearest or n == 0 or not abs(m - whole) <= FOLD_TOL * max(1.0, abs(m))
            or abs(whole - (n - 1)) > n / 8 or not reach <= FOLD_REACH
            or not np.all(x[:-1] <= x[1:])):
        backproject(q, cos_phi, sin_phi, weight, r0, inv_dr, x, y, nearest, out)
        return 0
    a, b, folded, mi = _folded_profiles(q, angles_deg, cos_phi, sin_phi, weight, int(whole))
    rest = np.setdiff1d(np.arange(q.shape[0]), np.concatenate([a, b]))
    if rest.size:
        backproject(np.ascontiguousarray(q[rest]), cos_phi[rest], sin_phi[rest], weight[rest],
                    r0, inv_dr, x, y, False, out)
    if a.size:
        backproject_folded(q, folded, a, b, mi, cos_phi, sin_phi, weight, r0, inv_dr, x, y,
                           out)
    return int(a.size)


def _folded_profiles(q, angles_deg, cos_phi, sin_phi, weight, m):
    """(a, b, folded, m): the pairs to fold and their profiles q_a[k] + (w_b / w_a) q_b[m − k]
    on [max(0, m − n + 1), min(n − 1, m)], only pairs whose folded profile is finite (a
    NaN or inf in either view, or an overflow, leaves the pair to go view by view)."""
    n = q.shape[1]
    a, b = opposite_pairs(angles_deg, cos_phi, sin_phi)
    keep = weight[a] > 0
    a, b = a[keep], b[keep]
    lo, hi = max(0, m - (n - 1)), min(n - 1, m)
    k = np.arange(lo, hi + 1)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        rho = weight[b] / weight[a]
        folded = np.zeros((a.size, n))
        folded[:, lo:hi + 1] = q[a][:, k] + rho[:, None] * q[b][:, m - k]
    finite = np.all(np.isfinite(folded), axis=1)
    return a[finite], b[finite], np.ascontiguousarray(folded[finite]), m


@njit(parallel=True, cache=True)
def backproject_folded(q, folded, a, b, m, cos_phi, sin_phi, weight, r0, inv_dr, x, y,
                       out):
    """out[i, j] += Σ_p w_a (q_a(u) + ρ_p q_b(m − u)), u view a's sample position at pixel
    (x_j, y_i) as :func:`~meshladar.reconstruct._kernels.backproject` computes it, each
    profile linear between its samples and 0 outside them; ``folded[p]`` holds
    q_a[k] + ρ_p q_b[m − k] for k in [max(0, m − n + 1), min(n − 1, m)], ρ_p = w_b / w_a,
    sampled once where u lies in that range by more than :data:`END_MARGIN`; elsewhere
    each view is sampled on its own line. x must be non-decreasing."""
    for i in prange(y.size):
        for c0 in range(0, x.size, _CHUNK):
            _folded_row(q, folded, a, b, m, cos_phi, sin_phi, weight, r0, inv_dr, x,
                        y[i], out[i], c0, min(x.size, c0 + _CHUNK))


@njit(cache=True)
def _folded_row(q, folded, a, b, m, cos_phi, sin_phi, weight, r0, inv_dr, x, yi, row,
                c0, c1):
    """Every pair's contribution to row[c0:c1], accumulated on the stack: the folded
    profile over the columns whose u both views cover (within :data:`END_MARGIN`), each
    view on its own line at the columns beyond (and at every column where u is not finite
    at the row's ends)."""
    acc = carray(_row_buffer(), (_CHUNK,))
    n = q.shape[1]
    lo = max(0, m - (n - 1)) + END_MARGIN
    hi = min(n - 1, m) - END_MARGIN
    bottom, top = float(min(0, m - (n - 1)) - 1), float(max(n - 1, m) + 1)
    src = row[c0:c1]
    for j in range(c1 - c0):
        acc[j] = src[j]
    for p in range(a.size):
        ka, kb, wv, base, step = _ends_and_middle(acc, c0, c1, q, a[p], b[p], cos_phi,
                                                  sin_phi, weight, r0, inv_dr, x, yi, lo, hi,
                                                  bottom, top)
        _add_linear(acc, c0, folded, p, wv, base, step, x, ka, kb)
    dst = row[c0:c1]
    for j in range(c1 - c0):
        dst[j] = acc[j]


@njit(cache=True)
def _ends_and_middle(acc, c0, c1, q, va, vb, cos_phi, sin_phi, weight, r0, inv_dr, x, yi, lo,
                     hi, bottom, top):
    """Adds views va and vb (180° apart) where one of them is sampled on its own line, and
    returns the columns [ka, kb) left to the folded profile, with view va's line (w, base,
    step): no columns (0, 0) when u is not finite at the row's ends (both views then added
    pixel by pixel, bounds tested on each)."""
    wa, base, step = _view_line(cos_phi, sin_phi, weight, r0, inv_dr, yi, va)
    wb, base_b, step_b = _view_line(cos_phi, sin_phi, weight, r0, inv_dr, yi, vb)
    if not (_finite_ends(x, c0, c1, base, step) and _finite_ends(x, c0, c1, base_b, step_b)):
        _add_view_scalar(acc, c0, c1, q, va, wa, base, step, x, False)
        _add_view_scalar(acc, c0, c1, q, vb, wb, base_b, step_b, x, False)
        return 0, 0, wa, base, step
    ja, jb = _window(x, c0, c1, base, step, bottom, top)
    ka, kb = _window(x, ja, jb, base, step, lo, hi)
    _add_ends(acc, c0, q, va, wa, base, step, vb, wb, base_b, step_b, x, ja, ka)
    _add_ends(acc, c0, q, va, wa, base, step, vb, wb, base_b, step_b, x, kb, jb)
    return ka, kb, wa, base, step


@njit(cache=True)
def _window(x, c0, c1, base, step, bottom, top):
    """(ja, jb): the columns [ja, jb) of [c0, c1) with bottom <= u < top (u monotone)."""
    if step >= 0.0:
        ja = _first(x, c0, c1, base, step, 0.0, bottom)
        return ja, _first(x, ja, c1, base, step, 0.0, top)
    ja = _first(x, c0, c1, base, step, 0.0, top)
    return ja, _first(x, ja, c1, base, step, 0.0, bottom)


@njit(cache=True)
def _add_ends(acc, c0, q, va, wa, base_a, step_a, vb, wb, base_b, step_b, x, j0, j1):
    """Columns [j0, j1) pixel by pixel, each view sampled on its own line."""
    for j in range(j0, j1):
        acc[j - c0] += wa * _sample(q, va, base_a + x[j] * step_a)
        acc[j - c0] += wb * _sample(q, vb, base_b + x[j] * step_b)


@njit(cache=True)
def _sample(q, v, u):
    """q_v at sample position u: linear between samples, the last sample at u = n − 1
    exactly, 0 outside [0, n − 1]."""
    last = q.shape[1] - 1
    if 0.0 <= u < last:
        k = int(u)
        return q[v, k] + (u - k) * (q[v, k + 1] - q[v, k])
    if u == last:
        return q[v, last]
    return 0.0
