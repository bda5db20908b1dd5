"""The raster path of a view (numba): an orthographic view's first hits found by drawing
its faces into a depth buffer over the view's ray grid instead of tracing each ray, then
weighed and binned by the fused loop's own :func:`._kernels.bin_flat_hits` (or, with
smooth normals, :func:`._kernels.bin_smooth_hits`, each hit's barycentrics found at its
point of the plane), band by band in scan order.

Every ray of an orthographic view travels along −w from its point (S, T) of the grid
plane (:func:`meshladar.raytrace.grid.grid_plan`: the cell centre plus its stratified
offset, in the float32 operations of the packet loop), so the face it meets first is the
face whose projection onto the plane (u, v) holds (S, T) and whose plane lies highest
along w there: each face is projected once, the cells of its bounding box tested against
its edge functions (float64), and its height at the ray compared with the buffer's. A
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
#: The cells a face's span covers are widened by this fraction of a cell each side, so that
#: round-off in the cells' float32 centres loses no ray on the span's edge.
_SPAN_MARGIN = 1e-3


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
def _draw(proj, faces, f, s, t, offsets, sp, prim, height, above):
    """Draw face f (its corners' (S, T, height) in ``proj``) into the buffer: row by row
    over the rows its S range covers, every ray of the cells its T span on the row's strip
    covers that lies inside its three edges (inclusive) and where its height is more than
    ``above`` above the buffer's takes it."""
    i0, i1, i2 = faces[f, 0], faces[f, 1], faces[f, 2]
    s0, t0, z0 = proj[i0, 0], proj[i0, 1], proj[i0, 2]
    s1, t1, z1 = proj[i1, 0], proj[i1, 1], proj[i1, 2]
    s2, t2, z2 = proj[i2, 0], proj[i2, 1], proj[i2, 2]
    det = (s1 - s0) * (t2 - t0) - (s2 - s0) * (t1 - t0)
    if det == 0.0:                                    # edge-on: no ray meets it
        return
    ns, nt = s.shape[0], t.shape[0]
    inv, first_s, first_t = 1.0 / sp, np.float64(s[0]), np.float64(t[0])
    a_lo = max(int(math.floor((min(s0, s1, s2) - first_s) * inv + 0.5 - _SPAN_MARGIN)), 0)
    a_hi = min(int(math.floor((max(s0, s1, s2) - first_s) * inv + 0.5 + _SPAN_MARGIN)),
               ns - 1)
    r = 1.0 / det                                     # barycentrics of corners 1 and 2
    a1, b1, c1 = (t2 - t0) * r, (s0 - s2) * r, (s2 * t0 - s0 * t2) * r
    a2, b2, c2 = (t0 - t1) * r, (s1 - s0) * r, (s0 * t1 - s1 * t0) * r
    dz1, dz2 = z1 - z0, z2 - z0
    e01 = 1.0 / (s1 - s0) if s1 != s0 else 0.0
    e12 = 1.0 / (s2 - s1) if s2 != s1 else 0.0
    e20 = 1.0 / (s0 - s2) if s0 != s2 else 0.0
    for a in range(a_lo, a_hi + 1):
        lo = first_s + (a - 0.5 - _SPAN_MARGIN) * sp  # the row's strip of S
        hi = first_s + (a + 0.5 + _SPAN_MARGIN) * sp
        span = (np.inf, -np.inf)
        span = _edge_span(s0, t0, s1, t1, e01, lo, hi, span)
        span = _edge_span(s1, t1, s2, t2, e12, lo, hi, span)
        span = _edge_span(s2, t2, s0, t0, e20, lo, hi, span)
        if span[0] > span[1]:
            continue
        b_lo = max(int(math.floor((span[0] - first_t) * inv + 0.5 - _SPAN_MARGIN)), 0)
        b_hi = min(int(math.floor((span[1] - first_t) * inv + 0.5 + _SPAN_MARGIN)), nt - 1)
        row = a * nt
        for b in range(b_lo, b_hi + 1):
            S, T = _sample(s, t, offsets, sp, a, b)
            qs, qt = np.float64(S), np.float64(T)
            l1 = a1 * qs + b1 * qt + c1
            l2 = a2 * qs + b2 * qt + c2
            if l1 < 0.0 or l2 < 0.0 or l1 + l2 > 1.0:
                continue
            z = z0 + l1 * dz1 + l2 * dz2
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
    for f in range(faces.shape[0]):                # turned toward the view first ...
        if normals_w[f] > 0.0:
            _draw(proj, faces, f, s, t, offsets, sp, prim, height, 0.0)
    # ... so that they win a tie: a face turned away must lie higher by more than the
    # round-off of a height (coincident faces' heights differ by their corners' order)
    above = TIE * max(abs(s[0]), abs(s[-1]), abs(t[0]), abs(t[-1]), sp)
    for f in range(faces.shape[0]):
        if not normals_w[f] > 0.0 and not closed[f]:
            _draw(proj, faces, f, s, t, offsets, sp, prim, height, above)


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
    r = 1.0 / ((s1 - s0) * (t2 - t0) - (s2 - s0) * (t1 - t0))
    qs, qt = np.float64(S), np.float64(T)
    return (np.float32(((t2 - t0) * qs + (s0 - s2) * qt + (s2 * t0 - s0 * t2)) * r),
            np.float32(((t0 - t1) * qs + (s1 - s0) * qt + (s0 * t1 - s1 * t0)) * r))


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
