"""The fused packet loop (numba): one view from ray grid to bins in one compiled pass, the
hot path of the mesh model on the packet backend. Each packet is cast through the Embree 4
bindings of :mod:`meshladar.raytrace.embree4` and its hits are weighed and binned a
cache-sized block at a time by the weigh stage's loops (:mod:`._kernels`), with no per-ray
arrays."""

from __future__ import annotations

import numpy as np
from numba import njit

from ..raytrace.embree4_kernels import init_args, load_packet, tile_shape, workspace
from ..raytrace.embree4_ctypes import ARGS_OFF, GEOMID, PRIMID, TFAR, U, V, VALID_OFF
from ._kernels import bin_bistatic_hits, bin_flat_hits, bin_smooth_hits, face_hit

__all__ = ["cast_bin_grid"]


@njit(cache=True, nogil=True)
def _occlude_block(occ, scene, w, i32, f32, base, prim, tf, o, n, plane_d, face_normals, wv,
                   wr32, lift, inv_scale, one, lifted, blocked):
    """Occlusion toward the receiver of n hits (face ``prim``, Embree's ``tf``, float32
    origin ``o`` as built): from p = o − t w (t in float64 against the face's plane) lifted
    by ``lift`` along the face's normal turned toward the ladar, rounded to float32 (and
    to unit size), cast along ``wr32`` in packets of w by ``occ`` (rtcOccludedW): the rays
    of meshladar.raytrace.views.trace_view. Fills blocked[:n]."""
    for i in range(n):
        p = prim[i]
        c, t, _ = face_hit(p, tf[i], o, i, wv, plane_d, face_normals)
        sign = -1.0 if c < 0.0 else 1.0
        for k in range(3):
            q = np.float32((o[i, k] * 1.0 - t * wv[k]) + lift * (face_normals[p, k] * sign))
            lifted[i, k] = q if one else q * inv_scale
    for first in range(0, n, w):
        load_packet(f32, i32, lifted, wr32, np.float32(np.inf), first, n, w)
        occ(base + VALID_OFF, scene, base, base + ARGS_OFF)
        for j in range(min(w, n - first)):
            blocked[first + j] = f32[TFAR * w + j] == -np.inf


#: Bistatic hits per block handed to the occlusion and binning kernels: small enough to
#: stay in cache, large enough that the call costs nothing per ray.
_BLOCK = 1024


@njit(cache=True, nogil=True)
def _tile_origins(a0, b0, rows, cols, nt, s, t, du, dv, sp, u, v, lw, one, inv_scale,
                  lanes, cast, slot):
    """The float32 origins of the grid's tile at (a0, b0), ``rows`` × ``cols`` rays, packed
    into the first lanes as :func:`meshladar.raytrace.grid.ray_grid` builds them (``lanes``)
    and at unit size (``cast``); ``slot`` receives each lane's position in the band of rows
    a0.., in scan order. Returns the lanes filled."""
    jitter = du.shape[0] > 0
    m = 0
    for da in range(rows):
        a = a0 + da
        for db in range(cols):
            b = b0 + db
            if jitter:
                S = np.float32(du[a, b] * sp) + s[a]
                T = np.float32(dv[a, b] * sp) + t[b]
            else:
                S = s[a]
                T = t[b]
            for k in range(3):
                lanes[m, k] = np.float32(np.float32(S * u[k]) + np.float32(T * v[k])) + lw[k]
                cast[m, k] = lanes[m, k] if one else lanes[m, k] * inv_scale
            slot[m] = da * nt + b
            m += 1
    return m


@njit(cache=True, nogil=True, inline="always")
def _keep_hits(i32, f32, w, m, one, scale, lanes, slot, band):
    """The packet's hits (face, distance scaled back, origin as built, barycentrics) into
    the ``band``'s slots; -1 where a lane missed."""
    band_prim, band_t, band_o, band_u, band_v = band
    for j in range(m):
        q = slot[j]
        if i32[GEOMID * w + j] == -1:
            band_prim[q] = -1
            continue
        tf = f32[TFAR * w + j]
        band_prim[q] = i32[PRIMID * w + j]
        band_t[q] = tf if one else np.float32(tf * scale)
        for k in range(3):
            band_o[q, k] = lanes[j, k]
        if band_u.shape[0]:
            band_u[q] = f32[U * w + j]
            band_v[q] = f32[V * w + j]


@njit(cache=True, nogil=True)
def _bin_band(band, k, plane_d, face_normals, face_material, params, wv, start, edges, area,
              power, ignore_back, out, stamp, weight, tag, footprint, smooth):
    """Weigh and bin a band's first k slots in scan order (misses -1, skipped): flat
    normals, or smooth with ``smooth`` = (corner normals, min_cos_facet) when the corners
    are not empty. Returns the back-face hits."""
    prim, tf, o, bu, bv = band[0][:k], band[1][:k], band[2][:k], band[3], band[4]
    corner, min_cos_facet = smooth
    if corner.shape[0] == 0:
        return bin_flat_hits(prim, tf, o, plane_d, face_normals, face_material, params, wv,
                             start, edges, area, power, ignore_back, out, stamp, weight, tag,
                             footprint)
    return bin_smooth_hits(prim, tf, bu[:k], bv[:k], o, plane_d, face_normals, corner,
                           face_material, params, wv, start, edges, area, power,
                           ignore_back, min_cos_facet, out, footprint)


@njit(cache=True, nogil=True)
def cast_bin_grid(fn, scene, w, flags, s, t, du, dv, sp, u, v, lw, d, inv_scale, scale,
                  plane_d, face_normals, face_material, params, wv, start, edges, area,
                  power, ignore_back, out, stamp, weight, tag, footprint, occ, wr, lift,
                  corner, min_cos_facet):
    """One view, grid to bins in one loop (monostatic or bistatic, flat normals; or
    monostatic with smooth ones, interpolated from the faces' ``corner`` normals when it is
    not empty, as :func:`._kernels.bin_smooth_hits`; point or footprint bins). The grid is cast in tiles (:func:`tile_shape`) a band of rows at a
    time: each packet's float32 origins are built as
    :func:`meshladar.raytrace.grid.ray_grid` builds them (o = (S u + T v) + L w, S = s
    (+ δ du), T = t (+ δ dv) when ``du`` is not empty), cast at unit size (×
    ``inv_scale``), and the band's hits (a few rows: it stays in cache), with Embree's
    distance scaled back (× ``scale``), are weighed and binned in scan order by
    :func:`._kernels.bin_flat_hits`: the numbers of the unfused path, summed in its order,
    without per-ray arrays. With a receiver direction ``wr`` (3,) (empty: monostatic) the
    band's hits are taken a block at a time, and each block's hits first cast their occlusion rays toward it with ``occ`` (rtcOccludedW; see
    :func:`_occlude_block`), and :func:`._kernels.bin_bistatic_hits` bins them with the
    per-face bistatic weights in ``weight``. Returns (back-face hits, rays cast)."""
    i32, f32, i64, base = workspace()
    init_args(i32, i64, base, flags)
    ns, nt = s.shape[0], t.shape[0]
    th, tw = tile_shape(w)
    one = scale == 1.0
    lanes = np.empty((w, 3), np.float32)          # origins as built (for the ranges)
    cast = np.empty((w, 3), np.float32)           # and as cast (at unit size)
    slot = np.empty(w, np.int64)
    nb = th * nt if corner.shape[0] else 0        # barycentrics: smooth normals only
    band = (np.empty(th * nt, np.int32), np.empty(th * nt, np.float32),
            np.empty((th * nt, 3), np.float32), np.empty(nb, np.float32),
            np.empty(nb, np.float32))
    band_prim, band_t, band_o = band[0], band[1], band[2]
    bistatic = wr.shape[0] == 3
    block = _BLOCK if bistatic else 0
    hits = (np.empty(block, np.int32), np.empty(block, np.float32),
            np.empty((block, 3), np.float32))
    spare = (np.zeros(block, np.bool_), np.empty((block, 3), np.float32),
             np.empty((1, 3), np.float32))
    for k in range(3 if bistatic else 0):
        spare[2][0, k] = wr[k]
    held = 0
    back = 0
    for a0 in range(0, ns, th):
        rows = min(th, ns - a0)
        for b0 in range(0, nt, tw):
            m = _tile_origins(a0, b0, rows, min(tw, nt - b0), nt, s, t, du, dv, sp, u, v,
                              lw, one, inv_scale, lanes, cast, slot)
            load_packet(f32, i32, cast, d, np.float32(np.inf), 0, m, w)
            fn(base + VALID_OFF, scene, base, base + ARGS_OFF)
            _keep_hits(i32, f32, w, m, one, scale, lanes, slot, band)
        if not bistatic:                          # the band in scan order (misses: -1)
            back += _bin_band(band, rows * nt, plane_d, face_normals, face_material, params,
                              wv, start, edges, area, power, ignore_back, out, stamp,
                              weight, tag, footprint, (corner, min_cos_facet))
            continue
        for q in range(rows * nt):                # the band's hits in scan order
            if band_prim[q] < 0:
                continue
            hits[0][held], hits[1][held] = band_prim[q], band_t[q]
            for k in range(3):
                hits[2][held, k] = band_o[q, k]
            held += 1
            if held == _BLOCK:
                back += _bin_block(occ, scene, w, flags, i32, f32, i64, base, hits, held,
                                   spare, plane_d, face_normals, wv, wr, lift, inv_scale,
                                   one, start, edges, ignore_back, out, weight)
                held = 0
    if held:
        back += _bin_block(occ, scene, w, flags, i32, f32, i64, base, hits, held, spare,
                           plane_d, face_normals, wv, wr, lift, inv_scale, one, start,
                           edges, ignore_back, out, weight)
    return back, ns * nt


@njit(cache=True, nogil=True)
def _bin_block(occ, scene, w, flags, i32, f32, i64, base, hits, held, spare, plane_d,
               face_normals, wv, wr, lift, inv_scale, one, start, edges, ignore_back, out,
               weight):
    """Bin the ``held`` bistatic hits of ``hits`` (face, distance, origin) after their
    occlusion rays toward the receiver ``wr`` (``spare``: blocked, lifted origins, wr in
    float32). Returns the block's back-face hits."""
    prim, tf, o = hits[0][:held], hits[1][:held], hits[2][:held]
    blocked, lifted, wr32 = spare
    _occlude_block(occ, scene, w, i32, f32, base, prim, tf, o, held, plane_d, face_normals,
                   wv, wr32, lift, inv_scale, one, lifted, blocked)
    init_args(i32, i64, base, flags)
    return bin_bistatic_hits(prim, tf, o, blocked[:held], plane_d, face_normals, wv, wr,
                             start, edges, ignore_back, out, weight)
