"""Binning one view's weighted hits by range (:func:`bin_one`): at each hit's range, over
the range interval its footprint covers on a flat facet (a box or a trapezoid, the
distribution of the sum of two uniform offsets), or over its cell on the locally circular
exact surface. The weights come from :mod:`.hit_weights`."""

from __future__ import annotations

import numpy as np

from ..precision import BOX_RATIO, TINY
from .hit_weights import scaled, weights

__all__ = ["bin_one"]


def bin_one(r, cos_t, sin_t, mat, spread, materials, edges, area, *, footprint=False,
            bi=None, factor=None, curve=None, power=False, receive=None):
    """One view's profile (n_bins,) from its k hits: ranges ``r``, ``cos_t``/``sin_t`` of
    incidence, material ids ``mat``, footprints ``spread`` (k, 4), the coatings, bin
    edges and δA⊥; binned at a point or over the footprint; ``bi`` (k, 4) the bistatic
    angles, ``factor`` a per-hit weight factor, ``curve`` (k, 4) curved footprints,
    ``power`` received power, ``receive`` the sensor's receiver factors (applied under
    received power only).

    Bins are half-open, [edges[j], edges[j + 1]); a hit binned at a point outside the
    edges is dropped. With ``footprint``, each hit's weight is spread over the range
    interval r + [−(a + b), a + b] of its footprint's half-widths a and b, clipped to its
    facet's own interval (``spread[:, 2:]``), by the distribution of the sum of two
    uniform offsets (a box where b is negligible, a trapezoid otherwise), renormalised
    over the clipped interval; weight outside the edges is lost. With ``curve`` as well,
    rows with ρ > 0 are spread uniformly in θ over their cell on the locally circular
    surface, the rest as flat footprints.

    Parameters
    ----------
    r : (k,) numpy.ndarray
        The hits' ranges (scene units, in the frame of ``edges``).
    cos_t, sin_t : (k,) numpy.ndarray
        cos θ and sin θ of the hits' incidence (:func:`weights`).
    mat : (k,) numpy.ndarray of int
        The hits' material indices into ``materials``.
    spread : (k, 4) numpy.ndarray
        The hits' footprints: range half-widths along the two transverse axes, and the
        facet's own range interval relative to the hit (≤ 0, ≥ 0); read only with
        ``footprint``.
    materials : sequence of BRDF
        One coating per material index.
    edges : (n_bins + 1,) numpy.ndarray
        Increasing range bin edges (scene units).
    area : float
        δA⊥ of one ray.
    footprint : bool
        Spread each hit over its footprint (default False: bin at its range).
    bi : (k, 4) numpy.ndarray, optional
        Bistatic angles (:func:`weights`); default None, monostatic.
    factor : (k,) numpy.ndarray, optional
        Per-hit weight factors (:func:`scaled`); default None.
    curve : (k, 4) numpy.ndarray, optional
        Rows (θ at the hit, θ at the cell's two ends, ρ): signed incidence angles in
        radians and the surface's radius of curvature (0 for none); read only with
        ``footprint``. Default None.
    power : bool
        Received power (True) or the paper's Eq. 8 (default False).
    receive : (k,) numpy.ndarray, optional
        Receiver factors (:func:`scaled`, under ``power`` only); default None.

    Returns
    -------
    (n_bins,) float64 numpy.ndarray
        The view's profile: per bin, the sum of the weights (F·δA⊥ under Eq. 8) that fall
        in it.

    Warns
    -----
    MeshladarWarning
        As :func:`weights`, for bistatic hits edge-on to the receiver.

    References
    ----------
    Jin & Levine (2009), Eq. 8 (P[k] = Σ F(θ_hit) δA⊥ over the hits in bin k).
    """
    wt = scaled(weights(cos_t, sin_t, mat, materials, area, bi, power), factor, receive,
                power=power)
    if footprint and curve is not None:
        curved = curve[:, 3] > 0
        out = _curved_spread(r[curved], wt[curved], curve[curved], edges)
        flat = ~curved
        return out + bin_one(r[flat], cos_t[flat], sin_t[flat], mat[flat], spread[flat],
                             materials, edges, area, footprint=True,
                             bi=None if bi is None else bi[flat], power=power)
    if not footprint:
        return _point_bins(r, wt, edges)
    return _footprint_bins(r, wt, spread, edges)


def _point_bins(r, wt, edges):
    """Each hit's weight in the bin holding its range (half-open bins; outside: dropped)."""
    nb = len(edges) - 1
    k = np.searchsorted(edges, r, side="right") - 1
    ok = (k >= 0) & (k < nb)
    return np.bincount(k[ok], weights=wt[ok], minlength=nb)


def _footprint_bins(r, wt, spread, edges):
    """Each hit's weight spread over its flat footprint's range interval, clipped to its
    facet's own (:func:`bin_one`'s ``footprint``): a box or a trapezoid, renormalised over
    the clipped interval; a hit without an interval is binned at its range."""
    nb = len(edges) - 1
    a = np.maximum(spread[:, 0], spread[:, 1])
    b = np.minimum(spread[:, 0], spread[:, 1])
    # the footprint's interval, clipped to the facet's own range interval
    lo_c = np.maximum(-(a + b), spread[:, 2])
    hi_c = np.minimum(a + b, spread[:, 3])
    point = (a <= 0) | (hi_c <= lo_c)
    k0 = np.clip(np.searchsorted(edges, r + lo_c, side="right") - 1, 0, nb - 1)
    k1 = np.clip(np.searchsorted(edges, r + hi_c, side="right") - 1, 0, nb - 1)
    k0 = np.where(point, np.clip(np.searchsorted(edges, r, side="right") - 1, 0, nb - 1), k0)
    k1 = np.where(point, k0, k1)
    inside = (r + hi_c >= edges[0]) & (r + lo_c < edges[-1]) & (wt != 0)
    cnt = np.where(inside, k1 - k0 + 1, 0)
    rows = np.repeat(np.arange(r.size), cnt)
    kk = k0[rows] + np.arange(rows.size) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    lo = np.maximum(edges[kk] - r[rows], lo_c[rows])
    hi = np.minimum(edges[kk + 1] - r[rows], hi_c[rows])
    ar, br = a[rows], b[rows]
    tiny = br <= BOX_RATIO * np.maximum(ar, TINY)

    def cdf(x):
        return np.where(tiny, _box_cdf(x, ar), _trap_cdf(x, ar, br))

    mass = cdf(hi_c[rows]) - cdf(lo_c[rows])
    frac = np.where(hi > lo, cdf(hi) - cdf(lo), 0.0) / np.where(mass > 0, mass, 1.0)
    frac = np.where(point[rows], ((edges[kk] <= r[rows]) & (r[rows] < edges[kk + 1]))
                    .astype(float), frac)
    return np.bincount(kk, weights=wt[rows] * frac, minlength=nb)


def _box_cdf(x, h):
    return np.clip((x + h) / np.where(h > 0, 2 * h, 1.0), 0.0, 1.0)


def _trap_cdf(x, a, b):
    """CDF of A + B, A ~ U(−a, a), B ~ U(−b, b): second differences of Q(y) = y₊²/2."""
    def q(y):
        return 0.5 * np.maximum(y, 0.0) ** 2

    return np.clip((q(x + a + b) - q(x + a - b) - q(x - a + b) + q(x - a - b))
                   / np.where(a * b > 0, 4 * a * b, 1.0), 0.0, 1.0)


def _curved_spread(r, wt, curve, edges):
    """Bin each ray's weight over its cell on the locally circular exact surface.

    ``curve`` rows: (θ at the hit, θ at the cell's two ends, ρ), θ signed incidence angles.
    Range along the circle is r(θ) = r_hit + ρ(cos θ_hit − cos θ), monotone in |θ|, and the
    weight is spread uniformly in θ (arc length) over the cell; a cell straddling the top
    (θ = 0) is split there."""
    nb = len(edges) - 1
    th, ta, tb, rho = curve.T
    total = np.maximum(tb - ta, TINY)
    # pieces in |θ|: [lo, hi] with their weight share
    straddle = (ta < 0) & (tb > 0)
    lo1 = np.where(straddle, 0.0, np.minimum(np.abs(ta), np.abs(tb)))
    hi1 = np.where(straddle, -ta, np.maximum(np.abs(ta), np.abs(tb)))
    lo2 = np.zeros_like(lo1)
    hi2 = np.where(straddle, tb, 0.0)
    out = np.zeros(nb)
    ct = np.cos(th)
    for lo, hi in ((lo1, hi1), (lo2, hi2)):
        ok = hi > lo
        if not ok.any():
            continue
        rr, w, c0, rh, l, h, tot = r[ok], wt[ok], ct[ok], rho[ok], lo[ok], hi[ok], total[ok]
        r_lo = rr + rh * (c0 - np.cos(l))
        r_hi = rr + rh * (c0 - np.cos(h))
        k0 = np.clip(np.searchsorted(edges, r_lo, side="right") - 1, 0, nb - 1)
        k1 = np.clip(np.searchsorted(edges, r_hi, side="right") - 1, 0, nb - 1)
        inside = (r_hi >= edges[0]) & (r_lo < edges[-1])
        cnt = np.where(inside, k1 - k0 + 1, 0)
        rows = np.repeat(np.arange(rr.size), cnt)
        kk = k0[rows] + np.arange(rows.size) - np.repeat(np.cumsum(cnt) - cnt, cnt)

        def theta_at(edge, i):
            # |θ| where r(θ) = edge, clipped to the piece
            x = np.clip(c0[i] - (edge - rr[i]) / rh[i], -1.0, 1.0)
            return np.clip(np.arccos(x), l[i], h[i])

        t1 = theta_at(edges[kk], rows)
        t2 = theta_at(edges[kk + 1], rows)
        out += np.bincount(kk, weights=w[rows] * (t2 - t1) / tot[rows], minlength=nb)
    return out
