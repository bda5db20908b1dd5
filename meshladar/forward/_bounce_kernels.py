"""Compiled twin of the bounce sampling (:mod:`meshladar.forward.bounces`): a direction per
path from the one-sample mixture (cosine about the normal; a Beckmann half vector of the
coating's lobe width, reflected) and the mixture's density, in one pass."""

from __future__ import annotations

import math

from numba import njit, prange

__all__ = ["sample_mixture"]


@njit(cache=True, inline="always")
def _lobe_density(n0, n1, n2, w0, w1, w2, d0, d1, d2, s):
    """Density (1/sr) of direction d under the lobe of width s about n (wi = w)."""
    h0, h1, h2 = w0 + d0, w1 + d1, w2 + d2
    norm = max(math.sqrt(h0 * h0 + h1 * h1 + h2 * h2), 1e-300)
    h0, h1, h2 = h0 / norm, h1 / norm, h2 / norm
    c = min(max(n0 * h0 + n1 * h1 + n2 * h2, 1e-100), 1.0)
    tan2 = max(1.0 - c * c, 0.0) / (c * c)
    ph = math.exp(-min(tan2 / (s * s), 700.0)) / (math.pi * s * s * c * c * c)
    return ph / (4.0 * max(d0 * h0 + d1 * h1 + d2 * h2, 1e-300))


@njit(parallel=True, cache=True)
def sample_mixture(n, wi, width, u1, u2, pick, wide, d, pdf):
    """Fill ``d`` (k, 3) and ``pdf`` (k,) for unit normals ``n`` and directions toward the
    source ``wi`` (k, 3), lobe widths ``width`` (k,; nan: none; at least ``wide``: the
    cosine alone) and uniform numbers ``u1``, ``u2``, ``pick`` (k,)."""
    for i in prange(n.shape[0]):
        n0, n1, n2 = n[i, 0], n[i, 1], n[i, 2]
        w0, w1, w2 = wi[i, 0], wi[i, 1], wi[i, 2]
        s = width[i]
        q = 0.0 if (math.isnan(s) or s >= wide) else 0.5
        # a frame about n: u = helper × n normalised, v = n × u
        if abs(n2) < 0.9:
            a0, a1, a2 = -n1, n0, 0.0          # (0, 0, 1) × n
        else:
            a0, a1, a2 = 0.0, -n2, n1          # (1, 0, 0) × n
        norm = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
        a0, a1, a2 = a0 / norm, a1 / norm, a2 / norm
        b0, b1, b2 = n1 * a2 - n2 * a1, n2 * a0 - n0 * a2, n0 * a1 - n1 * a0
        lobe = pick[i] < q
        if lobe:
            cos_t = 1.0 / math.sqrt(1.0 - s * s * math.log1p(-u1[i]))
        else:
            cos_t = math.sqrt(1.0 - u1[i])
        sin_t = math.sqrt(max(0.0, 1.0 - cos_t * cos_t))
        phi = 2.0 * math.pi * u2[i]
        cp, sp = math.cos(phi) * sin_t, math.sin(phi) * sin_t
        m0 = cos_t * n0 + cp * a0 + sp * b0
        m1 = cos_t * n1 + cp * a1 + sp * b1
        m2 = cos_t * n2 + cp * a2 + sp * b2
        if lobe:
            k = 2.0 * (w0 * m0 + w1 * m1 + w2 * m2)
            m0, m1, m2 = k * m0 - w0, k * m1 - w1, k * m2 - w2
        d[i, 0], d[i, 1], d[i, 2] = m0, m1, m2
        cos_d = n0 * m0 + n1 * m1 + n2 * m2
        if cos_d <= 0.0:
            pdf[i] = 0.0
            continue
        p = (1.0 - q) * cos_d / math.pi
        if q > 0.0:
            p += q * _lobe_density(n0, n1, n2, w0, w1, w2, m0, m1, m2, s)
        pdf[i] = p
