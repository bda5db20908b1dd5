"""The raster path of a view (numba): an orthographic view's first hits found by drawing
its faces into a depth buffer over the view's ray grid instead of tracing each ray, then
weighed and binned by the fused loop's own :func:`._kernels.bin_flat_hits` (or, with
smooth normals, :func:`._kernels.bin_smooth_hits`, each hit's barycentrics found at its
point of the plane), band by band in scan order.

Every ray of an orthographic view travels along −w from its point (S, T) of the grid
plane (:func:`meshladar.raytrace.grid.grid_plan`: the cell centre plus its stratified
offset, in the float32 operations of the packet loop), so the face it meets first is the
face whose projection onto the plane (u, v) holds (S, T) and whose plane lies highest
along w there: each face is projected once, the rays of the cells its span covers on each
row tested against its edge functions (float64, watertight: :func:`_edge`), and its
height at the ray compared with the buffer's. A
closed part's faces turned away from the view are not drawn (a ray from outside meets the
part first on a face turned toward it). A ray on an edge shared by two faces, or on two
coincident faces, takes the first drawn, a face turned toward the view before the others
(Embree may take the other: the hit's range is the same; its face's weight may differ).
"""

from __future__ import annotations

import math

import numpy as np

from ._compiled import njit_loop
from ._fused_kernels import _offsets
from ._kernels import bin_flat_hits, bin_smooth_hits

__all__ = ["zbuffer", "raster_bin_flat", "raster_bin_smooth", "TIE"]


@njit_loop(inline="always")
def _sample(s, t, offsets, sp, a, b):
    """Ray (a, b)'s point (S, T) of the grid plane, in the packet loop's float32
    operations: the cell centre plus its stratified offset (:func:`._fused_kernels._offsets`;
    none on a regular grid)."""
    xi, ku, kv, eta = offsets
    if xi.shape[0] == 0:
        return s[a], t[b]
    du, dv = _offsets(xi, ku, kv, eta, a, b)
    return np.float32(du * sp) + s[a], np.float32(dv * sp) + t[b]


#: Coincident faces' heights agree to this fraction of the grid's extent: a face turned
#: away from the view must lie higher than one turned toward it by more to take its ray.
TIE = 1e-12


@njit_loop(inline="always")
def _edge(as_, at, bs, bt, qs, qt):
    """The edge function of the point (qs, qt) against the edge a → b: twice the signed
    area of (a, b, q), > 0 where q lies to the left of a → b, made from the corner that
    comes first in (S, T) order whichever way the edge runs, so that two faces sharing an
    edge find the same number, of opposite signs where they run it opposite ways: a ray on
    the edge is inside both (0) or inside exactly one, never neither (a watertight
    test)."""
    if (as_, at) <= (bs, bt):
        return (bs - as_) * (qt - at) - (bt - at) * (qs - as_)
    return -((as_ - bs) * (qt - bt) - (at - bt) * (qs - bs))


@njit_loop(inline="always")
def _first_at_least(c, x, inv):
    """The first index i of the ascending ``c`` with c[i] ≥ x (len(c) if none), from the
    guess of a uniform spacing 1 / ``inv`` (the float32 centres' own values decide)."""
    n = c.shape[0]
    i = min(max(int(math.floor((x - c[0]) * inv)), 0), n)
    while i > 0 and c[i - 1] >= x:
        i -= 1
    while i < n and c[i] < x:
        i += 1
    return i


@njit_loop(inline="always")
def _last_at_most(c, x, inv):
    """The last index i of the ascending ``c`` with c[i] ≤ x (−1 if none)."""
    n = c.shape[0]
    i = min(max(int(math.floor((x - c[0]) * inv)) + 1, -1), n - 1)
    while i < n - 1 and c[i + 1] <= x:
        i += 1
    while i >= 0 and c[i] > x:
        i -= 1
    return i


@njit_loop(inline="always")
def _edge_span(s0, t0, s1, t1, inv, lo, hi, span):
    """``span`` (T low, T high) widened to hold the edge (s0, t0)–(s1, t1) clipped to the
    strip lo ≤ S ≤ hi (unchanged where the edge misses it); ``inv`` 1 / (s1 − s0), or 0
    where the edge runs along T."""
    if inv == 0.0:
        if lo <= s0 <= hi:
            return min(span[0], t0, t1), max(span[1], t0, t1)
        return span
    a = (lo - s0) * inv
    b = (hi - s0) * inv
    if a > b:
        a, b = b, a
    a, b = max(a, 0.0), min(b, 1.0)
    if a > b:
        return span
    ta, tb = t0 + a * (t1 - t0), t0 + b * (t1 - t0)
    return min(span[0], ta, tb), max(span[1], ta, tb)


@njit_loop()
def _draw(proj, faces, f, s, t, offsets, sp, reach, prim, height, above):
    """Draw face f (its corners' (S, T, height) in ``proj``) into the buffer: over the rows
    whose rays' S can fall within its S range (a ray lies within ``reach`` of its cell's
    float32 centre), and on each the cells whose rays' T can fall within its T span on the
    row's strip, every ray inside its three edges (:func:`_edge`, inclusive) whose height
    there is more than ``above`` above the buffer's takes it."""
    i0, i1, i2 = faces[f, 0], faces[f, 1], faces[f, 2]
    s0, t0, z0 = proj[i0, 0], proj[i0, 1], proj[i0, 2]
    s1, t1, z1 = proj[i1, 0], proj[i1, 1], proj[i1, 2]
    s2, t2, z2 = proj[i2, 0], proj[i2, 1], proj[i2, 2]
    det = (s1 - s0) * (t2 - t0) - (s2 - s0) * (t1 - t0)
    if det == 0.0:                                    # edge-on: no ray meets it
        return
    nt, inv = t.shape[0], 1.0 / sp
    sign = 1.0 if det > 0.0 else -1.0
    dz1, dz2 = z1 - z0, z2 - z0
    e01 = 1.0 / (s1 - s0) if s1 != s0 else 0.0
    e12 = 1.0 / (s2 - s1) if s2 != s1 else 0.0
    e20 = 1.0 / (s0 - s2) if s0 != s2 else 0.0
    for a in range(_first_at_least(s, min(s0, s1, s2) - reach, inv),
                   _last_at_most(s, max(s0, s1, s2) + reach, inv) + 1):
        lo, hi = s[a] - reach, s[a] + reach           # the row's rays' S
        span = (np.inf, -np.inf)
        span = _edge_span(s0, t0, s1, t1, e01, lo, hi, span)
        span = _edge_span(s1, t1, s2, t2, e12, lo, hi, span)
        span = _edge_span(s2, t2, s0, t0, e20, lo, hi, span)
        if span[0] > span[1]:
            continue
        row = a * nt
        for b in range(_first_at_least(t, span[0] - reach, inv),
                       _last_at_most(t, span[1] + reach, inv) + 1):
            S, T = _sample(s, t, offsets, sp, a, b)
            qs, qt = np.float64(S), np.float64(T)
            w0 = sign * _edge(s1, t1, s2, t2, qs, qt)
            w1 = sign * _edge(s2, t2, s0, t0, qs, qt)
            w2 = sign * _edge(s0, t0, s1, t1, qs, qt)
            if w0 < 0.0 or w1 < 0.0 or w2 < 0.0:
                continue
            area = w0 + w1 + w2                       # barycentrics w1, w2 over it
            z = z0 + (w1 * dz1 + w2 * dz2) / area if area > 0.0 else z0
            if z > height[row + b] + above:
                height[row + b] = z
                prim[row + b] = f


@njit_loop()
def zbuffer(proj, faces, normals_w, closed, s, t, offsets, sp, prim, height):
    """Each ray's first face (−1: none) and its height along w, row-major over the grid
    (s, t, offsets, sp as the packet loop's ``grid``) into ``prim`` and ``height``
    (len(s) × len(t) each): ``proj`` the vertices' (u, v, w) coordinates (shifted),
    ``normals_w`` each face's n·w. A face turned away from the view (n·w ≤ 0) of a
    ``closed`` part (watertight, normals outward) is not drawn: a ray from outside meets
    its part first on a face turned toward it. The faces turned toward the view are drawn
    first and a face turned away must lie higher by more than :data:`TIE` of the grid's
    extent to take a ray, so where two faces coincide (a sheet modelled as two faces back
    to back) the one turned toward the view is hit."""
    for k in range(s.shape[0] * t.shape[0]):
        prim[k] = -1
        height[k] = -np.inf
    # a ray's S (T) lies within reach of its cell's float32 centre: half a cell and the
    # float32 round-off of the centre, the offset and their sum (2⁻²⁴ each of the
    # largest coordinate and the spacing, taken twice over)
    extent = max(abs(s[0]), abs(s[-1]), abs(t[0]), abs(t[-1]), sp)
    reach = 0.5 * sp + (extent + sp) * 2.0 ** -22
    for f in range(faces.shape[0]):                # turned toward the view first ...
        if normals_w[f] > 0.0:
            _draw(proj, faces, f, s, t, offsets, sp, reach, prim, height, 0.0)
    # ... so that they win a tie: a face turned away must lie higher by more than the
    # round-off of a height (coincident faces' heights differ by their corners' order)
    for f in range(faces.shape[0]):
        if not normals_w[f] > 0.0 and not closed[f]:
            _draw(proj, faces, f, s, t, offsets, sp, reach, prim, height, TIE * extent)


@njit_loop()
def _band_hits(proj, faces, zbuf, grid, L, a0, rows, band):
    """The hits of rows a0 … a0 + rows − 1 of a drawn grid, in scan order, into ``band`` =
    (prim, distance, origins, u, v): each hit's face, distance L − height, float32 origin as
    the packet loop builds it (``grid`` = (s, t, offsets, sp, u, v, lw)) and, where ``u``
    holds any slot, its barycentrics of corners 1 and 2 (Embree's u, v) at the ray's point
    of the plane. Returns the rays."""
    s, t, offsets, sp, u, v, lw = grid
    prim, height = zbuf
    band_prim, band_t, band_o, band_u, band_v = band
    nt = t.shape[0]
    m = 0
    for a in range(a0, min(a0 + rows, s.shape[0])):
        for b in range(nt):
            k = a * nt + b
            p = prim[k]
            band_prim[m] = p
            if p >= 0:
                S, T = _sample(s, t, offsets, sp, a, b)
                for c in range(3):
                    band_o[m, c] = np.float32(np.float32(S * u[c]) + np.float32(T * v[c])) \
                        + lw[c]
                band_t[m] = np.float32(L - height[k])
                if band_u.shape[0]:
                    band_u[m], band_v[m] = _barycentrics(proj, faces, p, S, T)
            m += 1
    return m


@njit_loop(inline="always")
def _barycentrics(proj, faces, f, S, T):
    """Face f's barycentrics of its corners 1 and 2 at the point (S, T) of the plane."""
    i0, i1, i2 = faces[f, 0], faces[f, 1], faces[f, 2]
    s0, t0 = proj[i0, 0], proj[i0, 1]
    s1, t1 = proj[i1, 0], proj[i1, 1]
    s2, t2 = proj[i2, 0], proj[i2, 1]
    qs, qt = np.float64(S), np.float64(T)
    w1 = _edge(s2, t2, s0, t0, qs, qt)                # the edge functions _draw tested
    w2 = _edge(s0, t0, s1, t1, qs, qt)
    area = _edge(s1, t1, s2, t2, qs, qt) + w1 + w2
    return np.float32(w1 / area), np.float32(w2 / area)


@njit_loop(inline="always")
def _drawn(proj, faces, normals_w, closed, grid, zbuf, wv):
    """Draw the grid (:func:`zbuffer` into ``zbuf``); returns (the start distance L of its
    rays along w, its rows, its columns)."""
    s, t, offsets, sp, u, v, lw = grid
    zbuffer(proj, faces, normals_w, closed, s, t, offsets, sp, zbuf[0], zbuf[1])
    L = np.float64(lw[0]) * wv[0] + np.float64(lw[1]) * wv[1] + np.float64(lw[2]) * wv[2]
    return L, s.shape[0], t.shape[0]


@njit_loop()
def raster_bin_flat(proj, faces, normals_w, closed, grid, zbuf, rows, plane_d, face_normals,
                    face_material, params, wv, start, edges, area, power, ignore_back, out,
                    stamp, weight, tag, footprint, band):
    """One monostatic view with flat normals: its first hits by :func:`zbuffer` (into
    ``zbuf`` = (prim, height)), then ``rows`` rows at a time in scan order
    (:func:`_band_hits`) weighed and binned by :func:`._kernels.bin_flat_hits`: the packet
    loop's numbers where the two find the same faces. Returns (back-face hits, rays)."""
    L, ns, nt = _drawn(proj, faces, normals_w, closed, grid, zbuf, wv)
    back = 0
    for a0 in range(0, ns, rows):
        m = _band_hits(proj, faces, zbuf, grid, L, a0, rows, band)
        back += bin_flat_hits(band[0][:m], band[1][:m], band[2][:m], plane_d, face_normals,
                              face_material, params, wv, start, edges, area, power,
                              ignore_back, out, stamp, weight, tag, footprint, False)
    return back, ns * nt


@njit_loop()
def raster_bin_smooth(proj, faces, normals_w, closed, grid, zbuf, rows, plane_d,
                      face_normals, face_material, params, wv, start, edges, area, power,
                      ignore_back, out, footprint, corner, min_cos_facet, band):
    """:func:`raster_bin_flat` with smooth normals: each hit's barycentrics found at its
    point of the plane, weighed and binned by :func:`._kernels.bin_smooth_hits`.
    Returns (back-face hits, rays)."""
    L, ns, nt = _drawn(proj, faces, normals_w, closed, grid, zbuf, wv)
    back = 0
    for a0 in range(0, ns, rows):
        m = _band_hits(proj, faces, zbuf, grid, L, a0, rows, band)
        back += bin_smooth_hits(band[0][:m], band[1][:m], band[3][:m], band[4][:m],
                                band[2][:m], plane_d, face_normals, corner, face_material,
                                params, wv, start, edges, area, power, ignore_back,
                                min_cos_facet, out, footprint, False)
    return back, ns * nt
