"""A static scan's cast in one compiled loop (the packet backend's): each pulse's sub-ray
directions (:func:`._kernels.pulse_sub_rays`), the sub-rays in packets of the library's
width in their flat order (a packet may hold the end of one pulse and the start of the
next), Embree's first hits, and each hit refined in float64 (:func:`._kernels.refine_hit`).
The rays, packets and hits are those of the staged path (:func:`.cast.cast_chunk` over
:func:`.cast.world_directions`) number for number, without its per-sub-ray direction,
origin and distance arrays. Where the coatings have compiled rows, each hit is weighed
in the loop too: its photoelectrons, those of :func:`.cast.photoelectrons` bit for bit
(the same compiled twin, :func:`projected`)."""

from __future__ import annotations

import math

import numba
import numpy as np

from ..brdf._sandford_robertson_kernel import sr_monostatic
from ..raytrace.embree4_ctypes import ARGS_OFF, GEOMID, PRIMID, TFAR, VALID_OFF
from ..raytrace.embree4_kernels import init_args, load_packet, workspace
from ._kernels import offset_table, pulse_sub_rays, refine_hit

__all__ = ["cast_pulses", "projected", "projected_weights", "link_budget"]


@numba.njit(cache=True, nogil=True)
def cast_pulses(fn, handle, w, flags, origins, rot, local, offsets, pitch, inverse, scale,
                geometry, out, link):                     # pragma: no cover - compiled
    """First hits of every pulse's sub-rays, refined (module docstring).

    ``fn``, ``handle``, ``w``, ``flags``: the library's rtcIntersect{w}, the scene, the
    width and the query flags; ``origins`` (n, 3) the pulses' origins less the geometry's
    center; ``rot``, ``local``, ``offsets``, ``pitch`` as :func:`._kernels.world_sub_rays`;
    ``inverse`` and ``scale`` (float32) the Embree scene's unit-size factors;
    ``geometry`` = (normals, plane_d, min_cos, center); ``out`` = (face, dist, cos,
    points), each (n, m[, 3]); ``link`` = (each face's material, the coatings' compiled
    rows, the sub-rays' energy shares, the link budget's scale, the extinction, pe): where
    pe has rows, each sub-ray's photoelectrons (:func:`.cast.photoelectrons`) into it."""
    normals, plane_d, min_cos, center = geometry
    face, dist, cos, points = out
    material, params, shares, budget, extinction, pe = link
    i32, f32, i64, base = workspace()
    init_args(i32, i64, base, flags)
    n, m = local.shape[0], offsets.shape[0]
    ab = offset_table(offsets, pitch)
    dirs = np.empty((1, m, 3))                    # the current pulse's sub-rays, float64
    lane_d = np.empty((w, 3))                     # each lane's, float64, and its sub-ray
    lane_p = np.empty(w, np.int64)
    lane_k = np.empty(w, np.int64)
    sub = np.empty((w, 3), np.float32)
    sub_d = np.empty((w, 3), np.float32)
    o32 = np.empty(3, np.float32)                 # the current pulse's origin, as cast
    p, k = 0, 0                                   # the next sub-ray (counted, not divided)
    current = -1
    total = n * m
    for i0 in range(0, total, w):
        lanes = min(w, total - i0)
        for j in range(lanes):
            if p != current:
                pulse_sub_rays(rot, local, p, ab, pitch, dirs, 0)
                for c in range(3):
                    o32[c] = np.float32(origins[p, c]) * inverse
                current = p
            lane_p[j], lane_k[j] = p, k
            for c in range(3):
                lane_d[j, c] = dirs[0, k, c]
                sub[j, c] = o32[c]
                sub_d[j, c] = np.float32(dirs[0, k, c])
            k += 1
            if k == m:
                p, k = p + 1, 0
        load_packet(f32, i32, sub, sub_d, np.float32(np.inf), 0, lanes, w)
        fn(base + VALID_OFF, handle, base, base + ARGS_OFF)
        for j in range(lanes):
            q = lane_p[j]
            f, tf = -1, np.inf
            if i32[GEOMID * w + j] != -1:
                f = i32[PRIMID * w + j]
                tf = np.float64(f32[TFAR * w + j] * scale)
            refine_hit(f, tf, origins[q, 0], origins[q, 1], origins[q, 2], lane_d[j, 0],
                       lane_d[j, 1], lane_d[j, 2], normals, plane_d, min_cos, center, face,
                       dist, cos, points, q, lane_k[j])
            if pe.shape[0]:                 # (a hit at the origin is a miss by now)
                f = face[q, lane_k[j]]
                pe[q, lane_k[j]] = 0.0 if f < 0 else _photoelectrons(
                    min(cos[q, lane_k[j]], 1.0), dist[q, lane_k[j]], params, material[f],
                    shares[lane_k[j]], budget, extinction)


@numba.njit(cache=True, nogil=True, inline="always")
def _photoelectrons(c, r, params, i, share, budget, extinction):   # pragma: no cover
    """A hit's photoelectrons: the link budget (:mod:`.cast`) with F·cos θ from its
    coating's compiled row, params[i]."""
    return link_budget(projected(c, max(0.0, 1.0 - c * c), params, i), r, share,
                       budget, extinction)


@numba.njit(cache=True, nogil=True, inline="always")
def link_budget(weight, r, share, budget, extinction):    # pragma: no cover - compiled
    """A hit's photoelectrons from its F·cos θ ``weight`` at distance r (the link budget,
    :mod:`.cast`'s module docstring): the one formula of both the cast's loop and
    :func:`.cast.photoelectrons`."""
    out = budget * share * weight / (r * r)
    if extinction:                         # (× exp(−0) = 1 would change no bit)
        out = out * math.exp(-2.0 * extinction * r)
    return out


@numba.njit(cache=True, nogil=True, inline="always")
def projected(c, s2, params, i):                          # pragma: no cover - compiled
    """F(θ; −θ)·cos θ of the coating whose compiled row is params[i] (read by index: no
    row view per hit), from cos θ and sin²θ. A diffuse-only row with b = 0 and G = 1 (a
    Lambertian's) is ρd/π · cos θ, as its numpy ``projected`` computes it and bit for bit
    the SR expression's value there (g ≡ 1), without evaluating it."""
    if params[i, 6] <= 0.5 and params[i, 5] > 0.5 and params[i, 2] == 0.0 \
            and params[i, 4] == 1.0:
        return params[i, 0] / math.pi * c
    return sr_monostatic(c, s2, params[i, 0], params[i, 1], params[i, 2], params[i, 3],
                         params[i, 4], params[i, 5] > 0.5, params[i, 6] > 0.5) * c


@numba.njit(cache=True, nogil=True)
def projected_weights(c, face, material, params, out):     # pragma: no cover - compiled
    """out[i] = :func:`projected` of hit i (cos θ ``c[i]``) on face ``face[i]``, its
    coating's row params[material[face[i]]]."""
    for i in range(c.shape[0]):
        out[i] = projected(c[i], max(0.0, 1.0 - c[i] * c[i]), params, material[face[i]])
