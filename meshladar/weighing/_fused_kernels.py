"""The fused packet loop (numba): one view from ray grid to bins in one compiled pass, the
hot path of the mesh model on the packet backend. Each packet is cast through the Embree 4
bindings of :mod:`meshladar.raytrace.embree4` and its hits are weighed and binned a
cache-sized block at a time by the weigh stage's loops (:mod:`._kernels`), with no per-ray
arrays."""

from __future__ import annotations

import numpy as np
from numba import njit

from ..raytrace.embree4_kernels import init_args, load_packet, workspace
from ..raytrace.embree4_ctypes import ARGS_OFF, GEOMID, PRIMID, TFAR, VALID_OFF
from ._kernels import bin_bistatic_hits, bin_flat_hits, face_hit

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


#: Rays per block of hits handed to the weigh-and-bin kernel: small enough to stay in cache,
#: large enough that the call costs nothing per ray.
_BLOCK = 1024


@njit(cache=True, nogil=True)
def cast_bin_grid(fn, scene, w, flags, s, t, du, dv, sp, u, v, lw, d, inv_scale, scale,
                  plane_d, face_normals, face_material, params, wv, start, edges, area,
                  power, ignore_back, out, stamp, weight, tag, footprint, occ, wr, lift):
    """One view, grid to bins in one loop (monostatic, flat normals, point or footprint
    bins): each
    packet's float32 origins are built as :func:`meshladar.raytrace.grid.ray_grid` builds
    them (o = (S u + T v) + L w, S = s (+ δ du), T = t (+ δ dv) when ``du`` is not empty),
    cast at unit size (× ``inv_scale``), and the hits, with Embree's distance scaled back
    (× ``scale``), are weighed and binned a cache-sized block at a time by
    :func:`._kernels.bin_flat_hits`: the numbers of the unfused path, without
    per-ray arrays. With a receiver direction ``wr`` (3,) (empty: monostatic) each block's
    hits first cast their occlusion rays toward it with ``occ`` (rtcOccludedW; see
    :func:`_occlude_block`), and :func:`._kernels.bin_bistatic_hits` bins them
    with the per-face bistatic weights in ``weight``. Returns (back-face hits, rays
    cast)."""
    i32, f32, i64, base = workspace()
    init_args(i32, i64, base, flags)
    ns, nt = s.shape[0], t.shape[0]
    n = ns * nt
    jitter = du.shape[0] > 0
    one = scale == 1.0
    lanes = np.empty((w, 3), np.float32)          # origins as built (for the ranges)
    cast = np.empty((w, 3), np.float32)           # and as cast (at unit size)
    hit_prim = np.empty(_BLOCK + w, np.int32)
    hit_t = np.empty(_BLOCK + w, np.float32)
    hit_o = np.empty((_BLOCK + w, 3), np.float32)
    bistatic = wr.shape[0] == 3
    blocked = np.zeros(_BLOCK + w if bistatic else 0, np.bool_)
    lifted = np.empty((_BLOCK + w if bistatic else 0, 3), np.float32)
    wr32 = np.empty((1, 3), np.float32)
    if bistatic:
        for k in range(3):
            wr32[0, k] = wr[k]
    held = 0
    back = 0
    for first in range(0, n, w):
        m = min(w, n - first)
        for j in range(m):
            a, b = (first + j) // nt, (first + j) % nt
            if jitter:
                S = np.float32(du[a, b] * sp) + s[a]
                T = np.float32(dv[a, b] * sp) + t[b]
            else:
                S = s[a]
                T = t[b]
            for k in range(3):
                lanes[j, k] = np.float32(np.float32(S * u[k]) + np.float32(T * v[k])) + lw[k]
                cast[j, k] = lanes[j, k] if one else lanes[j, k] * inv_scale
        load_packet(f32, i32, cast, d, np.float32(np.inf), 0, m, w)
        fn(base + VALID_OFF, scene, base, base + ARGS_OFF)
        for j in range(m):
            if i32[GEOMID * w + j] == -1:
                continue
            tf = f32[TFAR * w + j]
            hit_prim[held] = i32[PRIMID * w + j]
            hit_t[held] = tf if one else np.float32(tf * scale)
            hit_o[held, 0] = lanes[j, 0]
            hit_o[held, 1] = lanes[j, 1]
            hit_o[held, 2] = lanes[j, 2]
            held += 1
        if held >= _BLOCK or first + w >= n:
            if bistatic:
                _occlude_block(occ, scene, w, i32, f32, base, hit_prim, hit_t, hit_o, held,
                               plane_d, face_normals, wv, wr32, lift, inv_scale, one,
                               lifted, blocked)
                init_args(i32, i64, base, flags)
                back += bin_bistatic_hits(hit_prim[:held], hit_t[:held], hit_o[:held],
                                          blocked[:held], plane_d, face_normals, wv, wr,
                                          start, edges, ignore_back, out, weight)
            else:
                back += bin_flat_hits(hit_prim[:held], hit_t[:held], hit_o[:held], plane_d,
                                      face_normals, face_material, params, wv, start, edges,
                                      area, power, ignore_back, out, stamp, weight, tag,
                                      footprint)
            held = 0
    return back, n
