"""The fused packet loop (numba): one view from ray grid to bins in one compiled pass, the
hot path of the mesh model on the packet backend. Each packet is cast through the Embree 4
bindings of :mod:`meshladar.raytrace.embree4` and its hits are weighed and binned a
cache-sized block at a time by the weigh stage's loops (:mod:`._kernels`), with no per-ray
arrays."""

from __future__ import annotations

import math

import numpy as np

from ..raytrace.embree4_kernels import init_args, load_packet, tile_shape
from ..raytrace.embree4_ctypes import ARGS_OFF, GEOMID, PRIMID, TFAR, U, V, VALID_OFF
from ._kernels import (bin_bistatic_hits, bin_flat_hits, bin_smooth_hits, face_hit,
                       view_footprint)
from ._sensor_kernels import bin_sensor_hits
from ._compiled import njit_loop
from ._prefetch import ahead as _ahead
from ._prefetch import prefetch as _prefetch

__all__ = ["cast_bin_flat", "cast_bin_flat_views", "cast_bin_smooth", "cast_bin_smooth_views",
           "cast_bin_bistatic", "cast_bin_bistatic_views", "cast_bin_sensor"]


@njit_loop()
def _occlude_block(occ, scene, w, i32, f32, base, prim, tf, o, n, plane_d, face_normals, wv,
                   wr32, lift, inv_scale, one, spare, needed):
    """Occlusion toward the receiver of n hits (face ``prim``, Embree's ``tf``, float32
    origin ``o`` as built): from p = o − t w (t in float64 against the face's plane) lifted
    by ``lift`` along the face's normal turned toward the ladar, rounded to float32 (and
    to unit size), cast along ``wr32`` in packets of w by ``occ`` (rtcOccludedW): the rays
    of meshladar.raytrace.views.trace_view. Fills blocked[:n] (``spare`` = (blocked,
    lifted origins, their hits' indices)). ``needed`` = (wr, ignore_back, skip_below, lone):
    a hit that cannot weigh anything casts no ray and is marked blocked, an ignored back
    face's and, with ``skip_below`` (built-in coatings, whose F is 0 there), one whose face
    turns away from the receiver (n·wr < 0 in float64, the weight's own cosine); and a hit
    on the front of a ``lone`` face (its part sees no part: a convex body alone) casts none
    and is free, as its ray would be."""
    blocked, lifted, index = spare
    wr, ignore_back, skip_below, lone = needed
    m = 0
    ahead = _ahead(face_normals)
    for i in range(n):
        if i + ahead < n:                        # a later hit's face rows (._prefetch)
            _prefetch((face_normals, plane_d), prim[i + ahead])
        p = prim[i]
        c, t, _ = face_hit(p, tf[i], o, i, wv, plane_d, face_normals)
        sign = -1.0 if c < 0.0 else 1.0
        if c < 0.0 and ignore_back:
            blocked[i] = True
            continue
        if skip_below and sign * (face_normals[p, 0] * wr[0] + face_normals[p, 1] * wr[1]
                                  + face_normals[p, 2] * wr[2]) < 0.0:
            blocked[i] = True
            continue
        if c > 0.0 and lone[p]:
            blocked[i] = False
            continue
        for k in range(3):
            q = np.float32((o[i, k] * 1.0 - t * wv[k]) + lift * (face_normals[p, k] * sign))
            lifted[m, k] = q if one else q * inv_scale
        index[m] = i
        m += 1
    for first in range(0, m, w):
        load_packet(f32, i32, lifted, wr32, np.float32(np.inf), first, m, w)
        occ(base + VALID_OFF, scene, base, base + ARGS_OFF)
        for j in range(min(w, m - first)):
            blocked[index[first + j]] = f32[TFAR * w + j] == -np.inf


@njit_loop(inline="always")
def _offsets(xi, ku, kv, eta, a, b):
    """Cell (a, b)'s stratified offsets (du, dv) from their 1-D sequences, in the float32
    operations of :func:`meshladar.raytrace.grid.stratified_offsets`: a sum, less 1 where
    it reaches ½."""
    half, one, zero = np.float32(0.5), np.float32(1.0), np.float32(0.0)
    du = np.float32(xi[a] + ku[b])
    dv = np.float32(kv[a] + eta[b])
    # less 1 or less 0 (x − 0 is x, −0 included): no branch in the ray loop
    return (np.float32(du - (one if du >= half else zero)),
            np.float32(dv - (one if dv >= half else zero)))


@njit_loop()
def _tile_origins(a0, b0, rows, cols, nt, s, t, offsets, sp, u, v, lw, one, inv_scale,
                  lanes, cast, slot):
    """The float32 origins of the grid's tile at (a0, b0), ``rows`` × ``cols`` rays, packed
    into the first lanes as :func:`meshladar.raytrace.grid.ray_grid` builds them (``lanes``)
    and at unit size (``cast``); ``slot`` receives each lane's position in the band of rows
    a0.., in scan order. The stratified offsets du, dv are made here from their 1-D
    ``offsets`` (xi, ku, kv, eta; empty: a regular grid) with the float32 operations of
    :func:`meshladar.raytrace.grid.stratified_offsets`. Returns the lanes filled."""
    xi, ku, kv, eta = offsets
    jitter = xi.shape[0] > 0
    m = 0
    for da in range(rows):
        a = a0 + da
        for db in range(cols):
            b = b0 + db
            if jitter:
                du, dv = _offsets(xi, ku, kv, eta, a, b)
                S = np.float32(du * sp) + s[a]
                T = np.float32(dv * sp) + t[b]
            else:
                S = s[a]
                T = t[b]
            for k in range(3):
                lanes[m, k] = np.float32(np.float32(S * u[k]) + np.float32(T * v[k])) + lw[k]
                cast[m, k] = lanes[m, k] if one else lanes[m, k] * inv_scale
            slot[m] = da * nt + b
            m += 1
    return m


@njit_loop(inline="always")
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


@njit_loop()
def _cast_band(query, scene, w, ws, a0, grid, d, inv_scale, scale, buffers):
    """Cast the band of rows a0.. of the grid (s, t, offsets, sp, u, v, lw) in tiles
    (:func:`tile_shape`): each tile's float32 origins built as
    :func:`meshladar.raytrace.grid.ray_grid` builds them, cast at unit size, its hits kept
    in the band's slots in scan order. ``query`` (rtcIntersectW, rtcIntersect1, single):
    a packet of w lanes per tile, or with ``single`` each ray on its own (grids sparser
    than their faces, where a packet's rays part at once: see
    :attr:`meshladar.raytrace.plan.TracePlan.coherent`). Returns the band's rays."""
    i32, f32, _, base = ws
    fn, fn1, single = query
    s, t, offsets, sp, u, v, lw = grid
    lanes, cast, slot, band = buffers
    ns, nt = s.shape[0], t.shape[0]
    th, tw = tile_shape(w)
    rows = min(th, ns - a0)
    one = scale == 1.0
    for b0 in range(0, nt, tw):
        m = _tile_origins(a0, b0, rows, min(tw, nt - b0), nt, s, t, offsets, sp, u, v, lw,
                          one, inv_scale, lanes, cast, slot)
        if single:
            for j in range(m):
                load_packet(f32, i32, cast[j:], d, np.float32(np.inf), 0, 1, 1)
                fn1(scene, base, base + ARGS_OFF)
                _keep_hits(i32, f32, 1, 1, one, scale, lanes[j:], slot[j:], band)
            continue
        load_packet(f32, i32, cast, d, np.float32(np.inf), 0, m, w)
        fn(base + VALID_OFF, scene, base, base + ARGS_OFF)
        _keep_hits(i32, f32, w, m, one, scale, lanes, slot, band)
    return rows * nt


# Three kernels, one per kind of view, so that a run compiles (on its first use, and loads
# from the cache after) only the weighing it does: each shares the band cast above and
# differs in how a band's hits are weighed and binned.

@njit_loop()
def cast_bin_flat(query, scene, w, flags, grid, d, inv_scale, scale, plane_d, face_normals,
                  face_material, params, wv, start, edges, area, power, ignore_back, out,
                  stamp, weight, tag, footprint, scratch):
    """One monostatic view with flat normals, grid to bins in one loop (``query``: see
    :func:`_cast_band`): each band's hits (a few rows: they stay in cache), with Embree's
    distance scaled back (× ``scale``), weighed and binned in scan order by
    :func:`._kernels.bin_flat_hits` (point or footprint bins): the numbers of the unfused
    path, summed in its order, without per-ray arrays; ``scratch``
    (:func:`._scratch.scratch`) holds the workspace and the band's buffers. Returns
    (back-face hits, rays cast)."""
    ws, buffers = scratch
    init_args(ws[0], ws[2], ws[3], flags)
    prim, tf, o = buffers[3][0], buffers[3][1], buffers[3][2]
    back = 0
    for a0 in range(0, grid[0].shape[0], tile_shape(w)[0]):
        k = _cast_band(query, scene, w, ws, a0, grid, d, inv_scale, scale, buffers)
        back += bin_flat_hits(prim[:k], tf[:k], o[:k], plane_d, face_normals, face_material,
                              params, wv, start, edges, area, power, ignore_back, out, stamp,
                              weight, tag, footprint, query[2])
    return back, grid[0].shape[0] * grid[1].shape[0]


@njit_loop(inline="always")
def _view_grid(grids, j):
    """View j's grid (s, t, offsets, sp, u, v, lw) of a chunk's ``grids`` =
    (s, s_at, t, t_at, (xi, ku, kv, eta), sp, u, v, lw):
    :class:`meshladar.raytrace.grid.GridPlans`' centres in float32, xi packed as s and eta
    as t, ku and kv the Kronecker sequences of the longest rows and columns (all four
    empty on a regular grid)."""
    s, s_at, t, t_at, seq, sp, u, v, lw = grids
    xi, ku, kv, eta = seq
    a, b, c, e = s_at[j], s_at[j + 1], t_at[j], t_at[j + 1]
    return (s[a:b], t[c:e], (xi[a:b], ku[:e - c], kv[:b - a], eta[c:e]), sp, u[j], v[j],
            lw[j])


@njit_loop()
def cast_bin_flat_views(query, scene, w, flags, grids, d, inv_scale, scale, plane_d,
                        face_normals, face_material, params, wv, start, edges, area, power,
                        ignore_back, out, stamp, weight, fp, counts, scratch):
    """Many monostatic views with flat normals in one call, view j as
    :func:`cast_bin_flat` casts it alone (a run of many small views pays the call once a
    chunk): its grid j of ``grids`` (:func:`_view_grid`), the direction ``d[j]`` (1, 3),
    ``wv[j]``, ``start[j]``, its bins ``out[j]`` and tag j + 1 in the shared weight cache;
    binned at a point (``fp`` None) or over footprints (:func:`._kernels.view_footprint`).
    Fills ``counts[j]`` with (back-face hits, rays cast)."""
    for j in range(grids[1].shape[0] - 1):
        f = view_footprint(fp, j, wv, face_normals)
        counts[j, 0], counts[j, 1] = cast_bin_flat(
            query, scene, w, flags, _view_grid(grids, j), d[j], inv_scale, scale, plane_d,
            face_normals, face_material, params, wv[j], start[j], edges, area, power,
            ignore_back, out[j], stamp, weight, j + 1, f, scratch)


@njit_loop()
def cast_bin_smooth_views(query, scene, w, flags, grids, d, inv_scale, scale, plane_d,
                          face_normals, face_material, params, wv, start, edges, area, power,
                          ignore_back, out, fp, corner, min_cos_facet, counts, scratch):
    """:func:`cast_bin_flat_views` with smooth normals: view j as :func:`cast_bin_smooth`
    casts it alone. Fills ``counts[j]`` with (back-face hits, rays cast)."""
    for j in range(grids[1].shape[0] - 1):
        f = view_footprint(fp, j, wv, face_normals)
        counts[j, 0], counts[j, 1] = cast_bin_smooth(
            query, scene, w, flags, _view_grid(grids, j), d[j], inv_scale, scale, plane_d,
            face_normals, face_material, params, wv[j], start[j], edges, area, power,
            ignore_back, out[j], f, corner, min_cos_facet, scratch)


@njit_loop()
def cast_bin_bistatic_views(query, scene, w, flags, grids, d, inv_scale, scale, plane_d,
                            face_normals, wv, start, edges, ignore_back, out, weight, occ,
                            wr, lift, stamp, coating, lone, counts, scratch):
    """:func:`cast_bin_flat_views` for bistatic views: view j as :func:`cast_bin_bistatic`
    casts it alone, toward its receiver ``wr[j]``, its half vector ``coating[2][j]``
    (``coating`` = (face materials, SR table, half vectors (k, 3), area, power, built
    in)). Fills ``counts[j]`` with (back-face hits, rays cast)."""
    for j in range(grids[1].shape[0] - 1):
        own = (coating[0], coating[1], coating[2][j], coating[3], coating[4], coating[5])
        counts[j, 0], counts[j, 1] = cast_bin_bistatic(
            query, scene, w, flags, _view_grid(grids, j), d[j], inv_scale, scale, plane_d,
            face_normals, wv[j], start[j], edges, ignore_back, out[j], weight, occ, wr[j],
            lift, stamp, j + 1, own, lone, scratch)


@njit_loop()
def cast_bin_smooth(query, scene, w, flags, grid, d, inv_scale, scale, plane_d, face_normals,
                    face_material, params, wv, start, edges, area, power, ignore_back, out,
                    footprint, corner, min_cos_facet, scratch):
    """One monostatic view with smooth normals, as :func:`cast_bin_flat` with the packets'
    barycentrics kept and the shading normal interpolated from the faces' ``corner``
    normals (:func:`._kernels.bin_smooth_hits`). Returns (back-face hits, rays cast)."""
    ws, buffers = scratch
    init_args(ws[0], ws[2], ws[3], flags)
    prim, tf, o, bu, bv = buffers[3]
    back = 0
    for a0 in range(0, grid[0].shape[0], tile_shape(w)[0]):
        k = _cast_band(query, scene, w, ws, a0, grid, d, inv_scale, scale, buffers)
        back += bin_smooth_hits(prim[:k], tf[:k], bu[:k], bv[:k], o[:k], plane_d,
                                face_normals, corner, face_material, params, wv, start,
                                edges, area, power, ignore_back, min_cos_facet, out,
                                footprint, query[2])
    return back, grid[0].shape[0] * grid[1].shape[0]


@njit_loop()
def cast_bin_bistatic(query, scene, w, flags, grid, d, inv_scale, scale, plane_d, face_normals,
                      wv, start, edges, ignore_back, out, weight, occ, wr, lift, stamp, tag,
                      coating, lone, scratch):
    """One bistatic view (receiver direction ``wr``), flat normals: each band's hits first
    cast their occlusion rays toward the receiver with ``occ`` (rtcOccludedW; see
    :func:`_occlude_band`), then :func:`._kernels.bin_bistatic_hits` bins the band in scan
    order with the per-face bistatic weights in ``weight`` (those whose ``stamp`` is not
    ``tag`` evaluated at their first hit from ``coating``); hits on the front of ``lone``
    faces cast no occlusion ray; ``scratch``: the workspace, the band's buffers and the
    occlusion pass's (:func:`._scratch.scratch`). Returns (back-face hits, rays cast)."""
    ws, buffers, hits, spare = scratch
    i32, f32, i64, base = ws
    init_args(i32, i64, base, flags)
    nt = grid[1].shape[0]
    band_prim, band_t, band_o = buffers[3][0], buffers[3][1], buffers[3][2]
    for k in range(3):
        spare[3][0, k] = wr[k]
    one = scale == 1.0
    back = 0
    for a0 in range(0, grid[0].shape[0], tile_shape(w)[0]):
        k = _cast_band(query, scene, w, ws, a0, grid, d, inv_scale, scale, buffers)
        _occlude_band(occ, scene, w, ws, buffers[3], k // nt, nt, hits, spare, plane_d,
                      face_normals, wv, lift, inv_scale, one,
                      (wr, ignore_back, coating[5], lone))
        init_args(i32, i64, base, flags)
        back += bin_bistatic_hits(band_prim[:k], band_t[:k], band_o[:k], spare[4][:k],
                                  plane_d, face_normals, wv, wr, start, edges, ignore_back,
                                  out, weight, stamp, tag, coating)
    return back, grid[0].shape[0] * grid[1].shape[0]


@njit_loop()
def _occlude_band(occ, scene, w, ws, band, rows, nt, hits, spare, plane_d, face_normals, wv,
                  lift, inv_scale, one, needed):
    """The occlusion of a band's hits (``band``: face, distance, origin per slot, rows ×
    ``nt`` in scan order) toward the receiver, into ``spare[4]`` per slot: the hits taken
    in tile order (:func:`tile_shape`: a packet's occlusion rays leave neighbouring points,
    as its first rays did) into ``hits`` (face, distance, origin, slot), then cast by
    :func:`_occlude_block` (``spare``: blocked, lifted origins, indices, wr in float32,
    and the band's blocked flags)."""
    i32, f32, _, base = ws
    tw = tile_shape(w)[1]
    held = 0
    for b0 in range(0, nt, tw):
        for da in range(rows):
            for db in range(min(tw, nt - b0)):
                q = da * nt + b0 + db
                if band[0][q] < 0:
                    continue
                hits[0][held], hits[1][held], hits[3][held] = band[0][q], band[1][q], q
                for k in range(3):
                    hits[2][held, k] = band[2][q, k]
                held += 1
    _occlude_block(occ, scene, w, i32, f32, base, hits[0], hits[1], hits[2], held, plane_d,
                   face_normals, wv, spare[3], lift, inv_scale, one, spare[:3], needed)
    for j in range(held):
        spare[4][hits[3][j]] = spare[0][j]


@njit_loop()
def _sensor_tile(a0, b0, rows, cols, plane, sensor, one, inv_scale, lanes, dirs, slot, band):
    """The rays of the sensor grid's tile at (a0, b0) into the first lanes, as
    :func:`meshladar.raytrace.perspective.sensor_cast` builds them in numpy, operation for
    operation: S = s + δ du, T = t + δ dv in float64 (du, dv the float32 offsets of
    :func:`_tile_origins`), q = S u + T v − D w, direction q/|q|, origin the sensor's
    position + t0 × direction in float32 (× ``inv_scale`` to unit size); each ray's float64
    direction and |q| kept in the band's slots. Returns the lanes filled."""
    s, t, offsets, sp, u, v, w = plane
    xi, ku, kv, eta = offsets
    D, pos, t0 = sensor
    nt = t.shape[0]
    m = 0
    for da in range(rows):
        a = a0 + da
        for db in range(cols):
            b = b0 + db
            S, T = s[a], t[b]
            if xi.shape[0] > 0:
                du, dv = _offsets(xi, ku, kv, eta, a, b)
                S = S + np.float64(du) * sp
                T = T + np.float64(dv) * sp
            q = da * nt + b
            length = math.sqrt(S * S + T * T + D * D)
            band[5][q] = length
            for k in range(3):
                dk = (S * u[k] + T * v[k] - D * w[k]) / length
                band[4][q, k] = dk
                o = np.float32(pos[k] + t0 * dk)
                lanes[m, k] = o if one else np.float32(o * inv_scale)
                dirs[m, k] = np.float32(dk)
            slot[m] = q
            m += 1
    return m


@njit_loop()
def cast_bin_sensor(query, scene, w, flags, plane, sensor, inv_scale, scale, smooth, binning,
                    out, scratch):
    """One view seen by a sensor at a standoff, grid to bins in one loop: each tile's rays
    built as :func:`meshladar.raytrace.perspective.sensor_cast` builds them
    (:func:`_sensor_tile`), cast with their own directions in a packet (or, with
    ``query``'s ``single``, one at a time: :func:`_cast_band`), and each band of
    rows weighed and binned in scan order by :func:`._sensor_kernels.bin_sensor_hits` (its
    arguments after ``sensor_pos`` but ``out``: ``binning``), with the hit distance
    t0 + Embree's (scaled back) as the per-hit path has it. The same numbers, without
    per-ray arrays; ``scratch``: the workspace, (lanes, directions, slots) and the band's
    buffers (:func:`._scratch.scratch`). Returns (back-face hits, rays cast)."""
    ws, (lanes, dirs, slot), band = scratch
    i32, f32, i64, base = ws
    fn, fn1, single = query
    init_args(i32, i64, base, flags)
    ns, nt = plane[0].shape[0], plane[1].shape[0]
    th, tw = tile_shape(w)
    one = scale == 1.0
    back = 0
    for a0 in range(0, ns, th):
        rows = min(th, ns - a0)
        for b0 in range(0, nt, tw):
            m = _sensor_tile(a0, b0, rows, min(tw, nt - b0), plane, sensor, one, inv_scale,
                             lanes, dirs, slot, band)
            if single:                           # each ray on its own (see _cast_band)
                for j in range(m):
                    load_packet(f32, i32, lanes[j:], dirs[j:], np.float32(np.inf), 0, 1, 1)
                    fn1(scene, base, base + ARGS_OFF)
                    _keep_sensor_hits(i32, f32, 1, 1, one, scale, sensor[2], slot[j:], band,
                                      smooth)
                continue
            load_packet(f32, i32, lanes, dirs, np.float32(np.inf), 0, m, w)
            fn(base + VALID_OFF, scene, base, base + ARGS_OFF)
            _keep_sensor_hits(i32, f32, w, m, one, scale, sensor[2], slot, band, smooth)
        k = rows * nt
        back += bin_sensor_hits(band[0][:k], band[1][:k], band[4][:k], band[5][:k],
                                band[2][:k], band[3][:k], sensor[0], sensor[1], *binning,
                                out)
    return back, ns * nt


@njit_loop(inline="always")
def _keep_sensor_hits(i32, f32, w, m, one, scale, t0, slot, band, smooth):
    """The packet's hits into the band's slots: face (-1 on a miss), t0 + Embree's distance
    scaled back (float64, as the per-hit path adds them) and, for smooth normals, the
    barycentrics."""
    for j in range(m):
        q = slot[j]
        if i32[GEOMID * w + j] == -1:
            band[0][q] = -1
            continue
        tf = f32[TFAR * w + j]
        band[0][q] = i32[PRIMID * w + j]
        band[1][q] = t0 + np.float64(tf if one else np.float32(tf * np.float32(scale)))
        if smooth:
            band[2][q], band[3][q] = f32[U * w + j], f32[V * w + j]
