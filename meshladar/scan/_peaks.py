"""The detector's compiled loops (:func:`meshladar.scan.echoes.find_returns`): peaks of
the matched-filtered records, their centroids, the Gaussian decomposition of overlapping
echoes, and a chunk's returns put in order."""

from __future__ import annotations

import math

import numba
import numpy as np

from ._kernels import sort_small
from ._sampling import filtered_span

__all__ = ["order_returns", "find_peaks", "size_peaks", "centroids", "fit_gaussians"]


@numba.njit(cache=True, nogil=True)
def order_returns(pulse, time, order, number, count):    # pragma: no cover - compiled
    """order: returns sorted by pulse, then time (stable), where ``pulse`` is already in
    order; each return's number within its pulse and its pulse's count, in that order.
    Returns False (nothing written) where ``pulse`` is out of order."""
    n = pulse.shape[0]
    for i in range(1, n):
        if pulse[i] < pulse[i - 1]:
            return False
    a = 0
    while a < n:
        b = a
        while b < n and pulse[b] == pulse[a]:
            b += 1
        if b == a + 1:                  # a pulse's one return: no sort
            order[a], number[a], count[a] = a, 1, 1
            a = b
            continue
        sort_small(time[a:b], order[a:b])
        for i in range(a, b):
            order[i] += a
            number[i] = i - a + 1
            count[i] = b - a
        a = b
    return True


@numba.njit(cache=True, nogil=True)
def _filter_span(waves, p, lo, hi, weights, filt):       # pragma: no cover - compiled
    """filt[j + 1] = the matched-filtered sample j of pulse p (zeros beyond the record)
    for lo ≤ j ≤ hi: taps outer, samples inner, each sample's sum in tap order."""
    ns = waves.shape[1]
    r = (weights.shape[0] - 1) // 2
    row = waves[p]
    for j in range(lo, hi + 1):
        filt[j + 1] = 0.0
    for k in range(weights.shape[0]):
        off = k - r
        w = weights[k]
        a = max(lo, -off)
        b = min(hi, ns - 1 - off) + 1
        src = row[a + off:b + off]                # 1-D slices: the loop vectorises
        dst = filt[a + 1:b + 1]
        for j in range(b - a):
            dst[j] += w * src[j]


@numba.njit(cache=True, nogil=True, inline="always")
def _stretch(detect, level, p, half, i):                  # pragma: no cover - compiled
    """The next stretch [a, b) of pulse p's samples whose window [j − half, j + half]
    holds a sample of ``detect`` at or above its ``level``, from the first such sample at
    or after i: (a, b, where the search for the next goes on); (ns, ns, ns) if none. A
    stretch is the union of its samples' windows, up to where a gap of more than
    2 half + 1 samples holds none."""
    ns = detect.shape[1]
    while i < ns and not detect[p, i] >= level[p, i]:
        i += 1
    if i >= ns:
        return ns, ns, ns
    a = max(i - half, 0)
    end = i + half + 1                        # exclusive: the windows so far
    i += 1
    while i < ns and i - half <= end:
        if detect[p, i] >= level[p, i]:
            end = i + half + 1
        i += 1
    return a, min(end, ns), i


@numba.njit(cache=True, nogil=True)
def find_peaks(waves, echoes, tables, detect, level, weights, half, separation, max_returns,
               out_p, out_j, out_f):                      # pragma: no cover - compiled
    """Per pulse, the maxima of the matched-filtered waveform (``weights``, zero beyond the
    record; from the filtered table ``tables`` where ``echoes`` has rows and gives the
    record's one echo, :func:`._sampling.filtered_span`) where a sample of ``detect`` within
    ``half`` samples reaches its ``level``, farther than ``separation`` samples from a
    stronger one, the strongest ``max_returns`` first; their
    pulse, sample and filtered values at j − 1, j, j + 1. Returns how many. The filter
    runs over each stretch of such samples and one beyond, not the whole record."""
    n, ns = waves.shape
    filt = np.empty(ns + 2)                  # filt[j + 1]: sample j; −inf beyond the ends
    filt[0] = filt[ns + 1] = -np.inf
    amp = np.empty(ns)
    neg = np.empty(ns)
    order = np.empty(ns, np.int64)
    at = np.empty(ns, np.int64)
    kept = np.empty(max_returns, np.int64)
    count = 0
    for p in range(n):
        c = 0
        nxt = 0
        while nxt < ns:
            a, j, nxt = _stretch(detect, level, p, half, nxt)
            if a >= ns:
                break
            if echoes.shape[0] and echoes[p, 0] > 0.0:
                filtered_span(echoes[p, 0], echoes[p, 1], tables, max(a - 1, 0),
                              min(j, ns - 1), filt)
            else:
                _filter_span(waves, p, max(a - 1, 0), min(j, ns - 1), weights, filt)
            for i in range(a, j):
                f = filt[i + 1]
                if f > 0.0 and f >= filt[i] and f > filt[i + 2]:
                    amp[c] = f
                    at[c] = i
                    c += 1
        if c == 0:
            continue
        if c == 1 and max_returns > 0:  # the one peak: kept, no sort
            count = _keep_peak(p, at[0], amp[0], filt, out_p, out_j, out_f, count)
            continue
        for i in range(c):
            neg[i] = -amp[i]
        sort_small(neg[:c], order[:c])             # strongest first, ties in time order
        nk = 0
        for r in range(c):
            o = order[r]
            if nk == max_returns:
                break
            ok = True
            for q in range(nk):
                if abs(at[o] - kept[q]) <= separation:
                    ok = False
                    break
            if not ok:
                continue
            kept[nk] = at[o]
            nk += 1
            count = _keep_peak(p, at[o], amp[o], filt, out_p, out_j, out_f, count)
    return count


@numba.njit(cache=True, nogil=True, inline="always")
def _keep_peak(p, i, f, filt, out_p, out_j, out_f, count):   # pragma: no cover - compiled
    """:func:`find_peaks`' output row ``count``: pulse p's peak at sample i (filtered
    value f, its neighbours from ``filt``). Returns the next row."""
    out_p[count] = p
    out_j[count] = i
    out_f[count, 0] = filt[i]
    out_f[count, 1] = f
    out_f[count, 2] = filt[i + 2]
    return count + 1


@numba.njit(cache=True, nogil=True)
def size_peaks(f3, j, ns, s, centre, s_e, height):        # pragma: no cover - compiled
    """Each peak's Gaussian through its three filtered samples ``f3`` (j − 1, j, j + 1):
    its centre (samples, from the record's start), the echo's σ (the filtered one's less
    the filter's σ = ``s`` in quadrature, at least s/2) and height (the filter has unit
    area); where the samples do not make a downward parabola in the log, or j is an end,
    the filtered echo's σ, s√2, at the middle sample."""
    tiny = 1e-300
    root = math.sqrt(2.0 * math.pi)
    for i in range(j.shape[0]):
        a, b, c = f3[i, 0], f3[i, 1], f3[i, 2]
        la, lb, lc = math.log(max(a, tiny)), math.log(max(b, tiny)), math.log(max(c, tiny))
        curv = la - 2.0 * lb + lc
        if a > 0 and c > 0 and curv < 0 and 0 < j[i] < ns - 1:
            delta = min(max(0.5 * (la - lc) / curv, -0.5), 0.5)
            s_f = math.sqrt(-1.0 / curv)
            h_f = math.exp(lb - 0.25 * (la - lc) * delta)
        else:
            delta, s_f, h_f = 0.0, s * math.sqrt(2.0), max(b, 0.0)
        centre[i] = j[i] + 0.5 + delta
        s_e[i] = math.sqrt(max(s_f ** 2 - s ** 2, 0.25 * s ** 2))
        height[i] = h_f * s_f * root / (s_e[i] * root)


@numba.njit(cache=True, nogil=True)
def centroids(waves, background, p, centre, half, rounds):  # pragma: no cover - compiled
    """Each echo's centroid (samples) within ``half`` of its centre, less its record's
    ``background`` per sample, the edge samples weighed by their part inside the window,
    re-centred ``rounds`` times (in place). Sample i (centred at i + 1/2) weighs
    min(1, max(0, half + 1/2 − |i + 1/2 − c|)): those wholly inside, a … z, are summed in
    four interleaved partial sums (independent chains), the two edge ones apart."""
    ns = waves.shape[1]
    for e in range(p.shape[0]):
        row = waves[p[e]]
        b = background[e]
        for _ in range(rounds):
            c = centre[e]
            a = int(math.ceil(c - half))
            z = int(math.floor(c + half - 1.0))
            tot, mom = _edge(row, b, c, half, a - 1)
            if z + 1 != a - 1:                   # (one sample when the window is narrow)
                w, wx = _edge(row, b, c, half, z + 1)
                tot, mom = tot + w, mom + wx
            t0 = t1 = t2 = t3 = m0 = m1 = m2 = m3 = 0.0
            i, hi = max(a, 0), min(z + 1, ns)
            while i + 4 <= hi:
                w0, w1, w2, w3 = row[i] - b, row[i + 1] - b, row[i + 2] - b, row[i + 3] - b
                t0, t1, t2, t3 = t0 + w0, t1 + w1, t2 + w2, t3 + w3
                m0, m1 = m0 + w0 * (i + 0.5), m1 + w1 * (i + 1.5)
                m2, m3 = m2 + w2 * (i + 2.5), m3 + w3 * (i + 3.5)
                i += 4
            while i < hi:
                w0 = row[i] - b
                t0, m0 = t0 + w0, m0 + w0 * (i + 0.5)
                i += 1
            tot += (t0 + t1) + (t2 + t3)
            mom += (m0 + m1) + (m2 + m3)
            if tot > 0.0:
                centre[e] = mom / tot


@numba.njit(cache=True, nogil=True, inline="always")
def _edge(row, b, c, half, i):                            # pragma: no cover - compiled
    """An edge sample's weight and moment in :func:`centroids`' window (0 off the record)."""
    if i < 0 or i >= row.shape[0]:
        return 0.0, 0.0
    x = i + 0.5
    w = min(1.0, max(0.0, half + 0.5 - abs(x - c))) * (row[i] - b)
    return w, w * x


@numba.njit(cache=True, nogil=True)
def _gauss_cost(x, y, v, k, r):                           # pragma: no cover - compiled
    cost = 0.0
    for j in range(x.shape[0]):
        m = 0.0
        for i in range(k):
            d = (x[j] - v[k + i]) / v[2 * k + i]
            m += v[i] * math.exp(-0.5 * d * d)
        r[j] = m - y[j]
        cost += r[j] * r[j]
    return cost


@numba.njit(cache=True, nogil=True)
def fit_gaussians(x, y, v, lower, upper, iterations):    # pragma: no cover - compiled
    """Least squares of a sum of k Gaussians (heights, centres, widths in ``v``, 3k) to
    (x, y) by Levenberg-Marquardt, each step clipped to [lower, upper] (in place)."""
    k = v.shape[0] // 3
    n = x.shape[0]
    r = np.empty(n)
    jac = np.empty((n, 3 * k))
    trial = np.empty(3 * k)
    cost = _gauss_cost(x, y, v, k, r)
    lam = 1e-3
    for _ in range(iterations):
        for j in range(n):
            for i in range(k):
                s = v[2 * k + i]
                d = x[j] - v[k + i]
                g = math.exp(-0.5 * d * d / (s * s))
                jac[j, i] = g
                jac[j, k + i] = v[i] * g * d / (s * s)
                jac[j, 2 * k + i] = v[i] * g * d * d / (s * s * s)
        jtj = jac.T @ jac
        grad = jac.T @ r
        improved = False
        for _attempt in range(10):
            a = jtj.copy()
            for i in range(3 * k):
                a[i, i] += lam * (jtj[i, i] + 1e-300)
            step = np.linalg.solve(a, -grad)
            for i in range(3 * k):
                trial[i] = min(max(v[i] + step[i], lower[i]), upper[i])
            new = _gauss_cost(x, y, trial, k, np.empty(n))
            if new < cost:
                change = cost - new
                v[:] = trial
                cost = _gauss_cost(x, y, v, k, r)
                lam = max(lam / 3.0, 1e-12)
                improved = True
                if change <= 1e-12 * cost:
                    return
                break
            lam *= 5.0
        if not improved:
            return
