"""A Gaussian echo's integrals over a record's samples (:func:`meshladar.scan.echoes.waveforms`).

Sample j of an echo of e photoelectrons centred at c samples from the record's start
holds e/2 (erf((j + 1 − c) r) − erf((j − c) r)), r = Δt/(σ√2). With c = b + φ (b its
integer part) that is e K_{j−b}(φ), one function of the phase φ ∈ [0, 1) for each offset
d = j − b: the chunk's records share them. :func:`sample_table` tabulates K_d and its
derivative at φ = k/Q; a group's samples are then the cubic Hermite interpolant between
its phase's two nodes, four table entries and four products a sample instead of an erf.
Q is set from the interpolant's error bound, h⁴/384 max|K⁗| with h = 1/Q: K⁗ is r⁴/2
times a difference of two values of erf⁗, each at most 4.41 in size, so the error is at
most 0.0115 (r/Q)⁴ e, and Q = ⌈:data:`NODES_PER_R` r⌉ holds it to 3.4e-14 of e (the
records promise 1e-13). Where that table would exceed :data:`TABLE_BYTES` (σ under a
thirtieth of a sample or over some 385 samples) the erf differences are evaluated
directly. The matched filter (:func:`matched_filter`) is linear, so the filtered record
of a group is e times the filter of K_d, tabulated beside it the same way: where a
record without noise holds one echo, peak finding reads its filtered samples from the
table (:func:`filtered_span`) instead of filtering the record. An
echo shape that is not a Gaussian is spread through its tabulated CDF
(:func:`accumulate_table`).
"""

from __future__ import annotations

import functools
import math

import numba
import numpy as np

from .._pulses import GaussianPulse
from ._kernels import erf, sort_small

__all__ = ["SUPPORT", "NODES_PER_R", "TABLE_BYTES", "echo_shape", "echo_support",
           "sample_table", "matched_filter", "lit_spans", "accumulate", "filtered_span",
           "accumulate_table"]

#: The echo's Gaussian is cut beyond this many σ (exp(−32) of its peak).
SUPPORT = 8.0
#: Table nodes per unit of r = Δt/(σ√2): the interpolant's error is at most
#: 0.0115 (r/Q)⁴ = 3.4e-14 of a group's photoelectrons (module docstring).
NODES_PER_R = 762.0
#: The largest table made (its four arrays); beyond it the erf differences are evaluated.
TABLE_BYTES = 4 << 20



def echo_shape(pulse, response, dt):
    """The echo's shape, the pulse convolved with the response: None for two Gaussians
    (exact erf integrals), else its CDF tabulated on a step of a 64th of the finer of Δt
    and the shapes' own widths, ``(t0, step, cdf)``.

    Parameters
    ----------
    pulse : GaussianPulse or SampledPulse
        The transmitted pulse.
    response : GaussianPulse, SampledPulse or None
        The receiver's impulse response.
    dt : float
        The sample interval, s.

    Returns
    -------
    tuple or None
        ``(t0, step, cdf)``: the table's first time (s), its step (s) and the CDF at
        ``t0 + i·step``.
    """
    shapes = [pulse] + ([response] if response is not None else [])
    if all(isinstance(x, GaussianPulse) for x in shapes):
        return None
    widths = [x.fwhm if isinstance(x, GaussianPulse) else x.interval for x in shapes]
    step = min([dt] + widths) / 64.0
    dens = None
    for x in shapes:
        a, b = x.support
        k0 = math.floor(a / step)
        d = np.diff(x.cdf(step * np.arange(k0, math.ceil(b / step) + 1)))
        dens = d if dens is None else np.convolve(dens, d)
    cdf = np.concatenate([[0.0], np.cumsum(dens / dens.sum())])
    return step * sum(math.floor(x.support[0] / step) for x in shapes), step, cdf


def echo_support(sigma, shape):
    """(before, after): how far an echo reaches either side of its time, s (SUPPORT σ for
    a Gaussian, ``shape`` None; else the echo shape's table's extent, :func:`echo_shape`).

    Parameters
    ----------
    sigma : float
        The echo's σ, s.
    shape : tuple or None
        :func:`echo_shape`'s table.

    Returns
    -------
    (float, float)
    """
    if shape is None:
        return SUPPORT * sigma, SUPPORT * sigma
    return -shape[0], shape[0] + shape[1] * (len(shape[2]) - 1)


@numba.njit(cache=True, nogil=True)
def _build(r, q, reach):                                  # pragma: no cover - compiled
    """value[k, i], slope[k, i]: K_d(φ) and dK_d/dφ / Q at φ = k/Q for d = i − reach."""
    nd = 2 * reach + 2
    value = np.empty((q + 1, nd))
    slope = np.empty((q + 1, nd))
    g = r / math.sqrt(math.pi) / q
    for k in range(q + 1):
        phi = k / q
        x0 = (-reach - phi) * r
        e0, g0 = math.erf(x0), math.exp(-x0 * x0)
        for i in range(nd):
            x1 = (i - reach + 1 - phi) * r
            e1, g1 = math.erf(x1), math.exp(-x1 * x1)
            value[k, i] = 0.5 * (e1 - e0)
            slope[k, i] = -g * (g1 - g0)
            e0, g0 = e1, g1
    return value, slope


@functools.lru_cache(maxsize=8)
def sample_table(s):
    """The tabulated sample integrals (module docstring) for an echo of σ = ``s`` samples,
    or None where the table would exceed :data:`TABLE_BYTES`.

    Parameters
    ----------
    s : float
        The echo's σ over the sample interval.

    Returns
    -------
    tuple or None
        ``(value, slope, q, reach, filtered, filtered_slope)``: K_d and its derivative over
        Q at the Q + 1 phases, for offsets d = −reach … reach + 1 (the support's samples
        either side); and the same of the matched-filtered record
        (:func:`matched_filter`), Σₜ wₜ K_{d+t−h}, for d = −reach − h … reach + 1 + h.
    """
    r = 1.0 / (s * math.sqrt(2.0))
    q = max(16, int(math.ceil(NODES_PER_R * r)))
    reach = int(math.ceil(SUPPORT * s)) + 2
    taps = matched_filter(s)
    if 16 * (q + 1) * (4 * reach + 3 + len(taps)) > TABLE_BYTES:     # the four arrays
        return None
    value, slope = _build(r, q, reach)
    filtered, filtered_slope = _filtered(value, taps), _filtered(slope, taps)
    for a in (value, slope, filtered, filtered_slope):
        a.setflags(write=False)
    return value, slope, q, reach, filtered, filtered_slope


@functools.lru_cache(maxsize=8)
def matched_filter(s):
    """The matched filter's taps for an echo of σ = ``s`` samples: a Gaussian of that σ
    at the integers −h … h, h = round(4 s) (scipy's ``gaussian_filter1d``, truncate=4),
    summing to 1 (made once per σ; read-only).

    Parameters
    ----------
    s : float
        The echo's σ over the sample interval.

    Returns
    -------
    (2 h + 1,) numpy.ndarray
        The taps.
    """
    h = int(4.0 * s + 0.5)
    taps = np.exp(-0.5 * (np.arange(-h, h + 1) / s) ** 2)
    taps /= taps.sum()
    taps.setflags(write=False)
    return taps


def _filtered(table, taps):
    """Σₜ wₜ table[:, i + t − 2h] (zero beyond the table): the filter of each phase's
    row, on 2h more offsets."""
    h = (len(taps) - 1) // 2
    nd = table.shape[1]
    out = np.zeros((table.shape[0], nd + 2 * h))
    for t, w in enumerate(taps):
        out[:, 2 * h - t:2 * h - t + nd] += w * table
    return out


@numba.njit(cache=True, nogil=True, inline="always")
def _hermite(e, c, q):                                    # pragma: no cover - compiled
    """A group at c's table row k (its phase's node below), its base b and the cubic
    Hermite weights of the nodes k, k + 1 and their slopes, times e."""
    base = int(math.floor(c))
    x = (c - base) * q
    k = min(int(x), q - 1)
    t = x - k
    t2 = t * t
    t3 = t2 * t
    return (k, base, e * (2.0 * t3 - 3.0 * t2 + 1.0), e * (t3 - 2.0 * t2 + t),
            e * (3.0 * t2 - 2.0 * t3), e * (t3 - t2))


@numba.njit(cache=True, nogil=True)
def _group(row, e, c, s, r2, value, slope, q, reach):     # pragma: no cover - compiled
    """row[j] += e K_{j−b}(φ) over the support's samples of a group centred at c."""
    ns = row.shape[0]
    lo = max(0, int(math.floor(c - SUPPORT * s)))
    hi = min(ns, int(math.ceil(c + SUPPORT * s)) + 1)
    if q == 0:                                   # no table: the erf differences
        prev = erf((lo - c) * r2)
        half = 0.5 * e
        for j in range(lo, hi):
            nxt = erf((j + 1 - c) * r2)
            row[j] += half * (nxt - prev)
            prev = nxt
        return
    k, base, h00, h10, h01, h11 = _hermite(e, c, q)
    a, b = lo + reach - base, hi + reach - base
    va, da, vb, db = value[k, a:b], slope[k, a:b], value[k + 1, a:b], slope[k + 1, a:b]
    dst = row[lo:hi]                             # 1-D slices from 0: the loop vectorises
    for j in range(hi - lo):
        dst[j] += h00 * va[j] + h10 * da[j] + h01 * vb[j] + h11 * db[j]


@numba.njit(cache=True, nogil=True)
def filtered_span(e, c, tables, lo, hi, filt):            # pragma: no cover - compiled
    """filt[j + 1] = sample j of the matched-filtered record of one echo of e
    photoelectrons centred at c, for lo ≤ j ≤ hi, from the filtered table (``tables``:
    :func:`sample_table`'s; 0 beyond the table's offsets)."""
    value, q, fvalue, fslope = tables[0], tables[2], tables[4], tables[5]
    reach = tables[3] + (fvalue.shape[1] - value.shape[1]) // 2
    k, base, h00, h10, h01, h11 = _hermite(e, c, q)
    off = reach - base                           # table offset i = j + off
    a = min(max(lo, -off), hi + 1)               # the samples within the table: a … b − 1
    b = max(min(hi + 1, fvalue.shape[1] - off), a)
    filt[lo + 1:a + 1] = 0.0
    filt[b + 1:hi + 2] = 0.0
    va, da = fvalue[k, a + off:b + off], fslope[k, a + off:b + off]
    vb, db = fvalue[k + 1, a + off:b + off], fslope[k + 1, a + off:b + off]
    dst = filt[a + 1:b + 1]                      # 1-D slices from 0: the loop vectorises
    for j in range(b - a):
        dst[j] = h00 * va[j] + h10 * da[j] + h01 * vb[j] + h11 * db[j]


@numba.njit(cache=True, nogil=True)
def lit_spans(tau, pe):                                   # pragma: no cover - compiled
    """Each pulse's earliest and latest time of a sub-ray with photoelectrons (inf and
    −inf where none has)."""
    n, m = tau.shape
    first = np.full(n, math.inf)
    last = np.full(n, -math.inf)
    for p in range(n):
        for k in range(m):
            if pe[p, k] > 0.0:
                first[p] = min(first[p], tau[p, k])
                last[p] = max(last[p], tau[p, k])
    return first, last


@numba.njit(cache=True, nogil=True)
def accumulate(tau, pe, start, dt, sigma, merge, tables, out, echo):   # pragma: no cover
    """out[p] += each of pulse p's groups of lit sub-rays (photoelectrons > 0; those within
    ``merge`` s of the group's earliest, at their photoelectron-weighted mean time) spread
    over its samples (``tables``: :func:`sample_table`'s, q 0 for none); echo[p] = the
    group's (photoelectrons, centre in samples) where pulse p has exactly one and its
    record holds its support whole, else (0, 0). A pulse whose lit sub-rays all lie
    within ``merge`` of its earliest is one group, summed in index order without
    sorting."""
    n, m = tau.shape
    s = sigma / dt
    r2 = 1.0 / (s * math.sqrt(2.0))
    value, slope, q, reach = tables[0], tables[1], tables[2], tables[3]
    order = np.empty(m, np.int64)
    lit = np.empty(m)
    for p in range(n):
        echo[p, 0] = echo[p, 1] = 0.0
        lo, hi, e, et = math.inf, -math.inf, 0.0, 0.0
        for k in range(m):
            w = pe[p, k]
            if w > 0.0:
                t = tau[p, k]
                lo, hi = min(lo, t), max(hi, t)
                e += w
                et += w * t
        if hi - lo <= merge:                     # one group (or nothing lit)
            if e > 0.0:
                c = (et / e - start[p]) / dt
                _group(out[p], e, c, s, r2, value, slope, q, reach)
                if c - SUPPORT * s >= 0.0 and math.ceil(c + SUPPORT * s) + 1 <= out.shape[1]:
                    echo[p, 0], echo[p, 1] = e, c
            continue
        for k in range(m):                       # an unlit sub-ray never arrives
            lit[k] = tau[p, k] if pe[p, k] > 0.0 else math.inf
        sort_small(lit, order)
        k = 0
        while k < m:
            t0 = lit[order[k]]
            if not t0 < math.inf:                # the rest unlit (sorted: inf last)
                break
            e, et = 0.0, 0.0
            while k < m and lit[order[k]] - t0 <= merge:
                w = pe[p, order[k]]
                e += w
                et += w * lit[order[k]]
                k += 1
            _group(out[p], e, (et / e - start[p]) / dt, s, r2, value, slope, q, reach)


@numba.njit(cache=True, nogil=True)
def accumulate_table(tau, pe, start, dt, t0, step, cdf, out):   # pragma: no cover
    """out[p, j] += e (C(t_{j+1} − τ) − C(t_j − τ)) for every lit sub-ray, with C the echo
    shape's CDF tabulated at t0 + i·step (0 before, 1 after the table)."""
    n, m = tau.shape
    ns = out.shape[1]
    last = cdf.shape[0] - 1
    for p in range(n):
        for k in range(m):
            e = pe[p, k]
            if e <= 0.0:
                continue
            c = tau[p, k] - start[p]
            lo = max(0, int(math.floor((c + t0) / dt)))
            hi = min(ns, int(math.ceil((c + t0 + last * step) / dt)) + 1)
            prev = _table(cdf, (lo * dt - c - t0) / step, last)
            for j in range(lo, hi):
                nxt = _table(cdf, ((j + 1) * dt - c - t0) / step, last)
                out[p, j] += e * (nxt - prev)
                prev = nxt


@numba.njit(cache=True, nogil=True, inline="always")
def _table(cdf, x, last):                                 # pragma: no cover - compiled
    if x <= 0.0:
        return 0.0
    if x >= last:
        return 1.0
    i = int(x)
    f = x - i
    return cdf[i] * (1.0 - f) + cdf[i + 1] * f
