"""The weigh stage's compiled loops (numba): binning of first hits per ray, flat and smooth
normals, bistatic, at a point or over a footprint (moved here from the dissolved
``meshladar/_kernels.py``: each compiled loop lives beside its stage; a sensor's loop is in
:mod:`._sensor_kernels`). On big meshes each loop prefetches the face rows of a later hit
(:mod:`._prefetch`).

numba is imported here; the stages that use these loops import this module, never
``import meshladar`` itself. Kernels are cached on disk (``cache=True``)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit, types
from numba.extending import overload

from ..brdf._sandford_robertson_kernel import sr_bistatic as _sr_bistatic
from ..brdf._sandford_robertson_kernel import sr_monostatic as _sr_monostatic
from ..precision import BOX_RATIO as _BOX_RATIO
from ..precision import TINY as _TINY
from ._compiled import njit_loop
from ._prefetch import ahead as _ahead
from ._prefetch import prefetch as _prefetch

#: The footprint rows and stamps of a run of point bins (none).
_NO_ROWS = np.empty((0, 4))
_NO_STAMPS = np.empty(0, np.int64)

__all__ = ["bin_flat_hits", "bin_bistatic_hits", "bin_smooth_hits",
           "face_hit", "footprint_row", "footprint_rows", "view_footprint", "edge_on_receiver"]


@njit_loop()
def footprint_row(fp, p, face_normals):                   # pragma: no cover - compiled
    """Face p's footprint row for the view, made at its first hit (called once per face:
    the loops check ``stamps[p]`` themselves): ``fp`` = (rows (n_faces, 4), stamps
    (n_faces,), shifted vertices, faces, w, u, v (3-tuples), spacing δ, 3-D, tag); a row is
    the view's where its stamp is ``tag`` (every row is where ``tag`` < 0:
    :func:`footprint_rows` made them all)."""
    rows, stamps, vertices, faces, w, u, v, spacing, three_d, tag = fp
    a, b, c = faces[p, 0], faces[p, 1], faces[p, 2]
    rows[p, 0], rows[p, 1], rows[p, 2], rows[p, 3] = _row(
        face_normals[p, 0], face_normals[p, 1], face_normals[p, 2], w, u, v, spacing,
        three_d, -(vertices[a, 0] * w[0] + vertices[a, 1] * w[1] + vertices[a, 2] * w[2]),
        -(vertices[b, 0] * w[0] + vertices[b, 1] * w[1] + vertices[b, 2] * w[2]),
        -(vertices[c, 0] * w[0] + vertices[c, 1] * w[1] + vertices[c, 2] * w[2]))
    stamps[p] = tag


@njit_loop(inline="always")
def _row(n0, n1, n2, w, u, v, spacing, three_d, r0, r1, r2):   # pragma: no cover
    """A footprint row from scalars (no array: inlined in loops without reference
    counting): |n·u| / c · ½ · δ, |n·v| / c · ½ · δ (0 in slice mode) with
    c = max(|n·w|, TINY), then the least and greatest of the corners' ranges, in the
    float64 operations of :func:`meshladar.weighing.faces.face_footprints`."""
    cg = max(abs(n0 * w[0] + n1 * w[1] + n2 * w[2]), _TINY)
    a = abs(n0 * u[0] + n1 * u[1] + n2 * u[2]) / cg * 0.5 * spacing
    b = abs(n0 * v[0] + n1 * v[1] + n2 * v[2]) / cg * 0.5 * spacing if three_d else 0.0
    return a, b, min(min(r0, r1), r2), max(max(r0, r1), r2)


@njit(cache=True, nogil=True)
def footprint_rows(fp, face_normals):                     # pragma: no cover - compiled
    """Every face's footprint row (:func:`footprint_row`, the same bits) for the view of
    ``fp``, in one pass over the vertices (their ranges) and one over the faces: what a
    dense grid, which hits most faces, does before its cast (then passed with tag −1)."""
    rows, _, vertices, faces, w, u, v, spacing, three_d, _ = fp
    ranges = np.empty(vertices.shape[0])
    for k in range(vertices.shape[0]):
        ranges[k] = -(vertices[k, 0] * w[0] + vertices[k, 1] * w[1] + vertices[k, 2] * w[2])
    for p in range(faces.shape[0]):
        rows[p, 0], rows[p, 1], rows[p, 2], rows[p, 3] = _row(
            face_normals[p, 0], face_normals[p, 1], face_normals[p, 2], w, u, v, spacing,
            three_d, ranges[faces[p, 0]], ranges[faces[p, 1]], ranges[faces[p, 2]])


def view_footprint(fp, j, wv, face_normals):
    """View j's ``footprint`` argument (:func:`meshladar.weighing.faces.footprint_args`'
    tuple) from a chunk's ``fp`` = (rows, stamps, vertices, faces, u (k, 3), v (k, 3),
    spacing, 3-D, dense): its rows made at their faces' first hits under tag j + 1, or on a
    dense grid every row made now (tag −1); None for None (point bins), typed so in the
    compiled loops (an overload: a branch on ``fp is None`` would make the argument
    optional); only those loops call it."""
    raise NotImplementedError("view_footprint runs inside the compiled loops only")


@overload(view_footprint, inline="always")
def _view_footprint_typed(fp, j, wv, face_normals):     # pragma: no cover - compiled
    if isinstance(fp, types.NoneType):
        return lambda fp, j, wv, face_normals: None

    def made(fp, j, wv, face_normals):
        rows, stamps, vertices, faces, u, v, spacing, three_d, dense = fp
        f = (rows, stamps, vertices, faces, (wv[j, 0], wv[j, 1], wv[j, 2]),
             (u[j, 0], u[j, 1], u[j, 2]), (v[j, 0], v[j, 1], v[j, 2]), spacing, three_d,
             -1 if dense else j + 1)
        if dense:                      # footprint_rows' numbers, without its array
            for p in range(faces.shape[0]):
                footprint_row(f, p, face_normals)
        return f
    return made


@njit_loop()
def _hit_distance(p, c, tf, origins, i, plane_d, face_normals):
    """Ray i's distance to face p, recomputed in float64 against the face's plane from the
    float32 origin as cast (c = n·w); Embree's float32 ``tf`` where the plane is edge-on
    (as meshladar.raytrace.views.refine_t)."""
    if abs(c) <= 1e-6:
        return tf * 1.0
    return (plane_d[p] - (face_normals[p, 0] * origins[i, 0] + face_normals[p, 1] * origins[i, 1]
                          + face_normals[p, 2] * origins[i, 2])) / (-c)


@njit_loop(inline="always")
def face_hit(p, tf, origins, i, w, plane_d, face_normals):
    """Ray i's hit on face p seen along w: (c, t, r) with c = n·w the flat normal's cosine
    (negative on a back face), t the float64 distance (:func:`_hit_distance`) and
    r = t − o·w its range relative to the shifted centre's plane."""
    c = face_normals[p, 0] * w[0] + face_normals[p, 1] * w[1] + face_normals[p, 2] * w[2]
    t = _hit_distance(p, c, tf, origins, i, plane_d, face_normals)
    return c, t, t - (origins[i, 0] * w[0] + origins[i, 1] * w[1] + origins[i, 2] * w[2])


@njit_loop()
def _bin_of(r, edges, e0, inv):
    """The bin k with edges[k] <= r < edges[k + 1] (r inside the edges): guessed in O(1)
    from uniform edges (``inv`` bins per unit range from ``e0``), checked against the
    edges, by bisection when the guess is off (non-uniform edges)."""
    nb = edges.size - 1
    k = min(max(int((r - e0) * inv), 0), nb - 1)
    if edges[k] <= r and r < edges[k + 1]:
        return k
    lo = 0
    hi = nb
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if edges[mid] <= r:
            lo = mid
        else:
            hi = mid
    return lo


@njit_loop(inline="always")
def _smooth_cos(corner, p, a, b, wx, wy, wz):
    """cos θ of face p's shading normal, interpolated from its ``corner`` normals with
    Embree's barycentrics (a, b) and normalised, against the direction (wx, wy, wz)."""
    nx = (1 - a - b) * corner[p, 0, 0] + a * corner[p, 1, 0] + b * corner[p, 2, 0]
    ny = (1 - a - b) * corner[p, 0, 1] + a * corner[p, 1, 1] + b * corner[p, 2, 1]
    nz = (1 - a - b) * corner[p, 0, 2] + a * corner[p, 1, 2] + b * corner[p, 2, 2]
    norm = math.sqrt(nx * nx + ny * ny + nz * nz)
    return (nx / norm) * wx + (ny / norm) * wy + (nz / norm) * wz


@njit_loop(inline="always")
def _fp_cdf(x, a, b, box):
    """CDF at x of the footprint's range offset A + B, A ~ U(−a, a), B ~ U(−b, b) (a box
    when ``box``): meshladar.weighing._box_cdf and _trap_cdf, one value at a time."""
    if box:
        return min(max((x + a) / (2 * a if a > 0 else 1.0), 0.0), 1.0)
    num = _half_sq(x + a + b) - _half_sq(x + a - b) - _half_sq(x - a + b) + _half_sq(x - a - b)
    return min(max(num / (4 * a * b if a * b > 0 else 1.0), 0.0), 1.0)


@njit_loop(inline="always")
def _half_sq(y):
    return 0.5 * max(y, 0.0) ** 2


@njit_loop(inline="always")
def _clipped_bin(x, edges, e0, inv):
    """searchsorted(edges, x, "right") − 1 clipped to the bins (as weighing._bin_one)."""
    nb = edges.size - 1
    if x < edges[0]:
        return 0
    if x >= edges[nb]:
        return nb - 1
    return _bin_of(x, edges, e0, inv)


@njit_loop(inline="always")
def _spread_hit(out, r, r_rel, wt, fp, p, edges, e0, inv):
    """Add one hit's weight over the bins its footprint's ranges cover, as
    meshladar.weighing._bin_one with ``footprint``: ``fp[p]`` holds face p's half-widths
    along u and v and its own range interval (min, max) for the view; the offsets are
    clipped to the facet's interval, and a box or trapezoid CDF splits the weight."""
    s0, s1 = fp[p, 0], fp[p, 1]
    a = max(s0, s1)
    b = min(s0, s1)
    lo_c = max(-(a + b), min(fp[p, 2] - r_rel, 0.0))
    hi_c = min(a + b, max(fp[p, 3] - r_rel, 0.0))
    nb = edges.size - 1
    if a <= 0 or hi_c <= lo_c:                      # a point: its own bin
        if edges[0] <= r and r < edges[nb]:
            out[_bin_of(r, edges, e0, inv)] += wt
        return
    if not (r + hi_c >= edges[0] and r + lo_c < edges[nb]) or wt == 0:
        return
    k0 = _clipped_bin(r + lo_c, edges, e0, inv)
    k1 = _clipped_bin(r + hi_c, edges, e0, inv)
    box = b <= _BOX_RATIO * max(a, _TINY)
    c_hi, c_lo = _fp_cdf(hi_c, a, b, box), _fp_cdf(lo_c, a, b, box)
    mass = c_hi - c_lo
    if mass <= 0:
        mass = 1.0
    last_x, last_c = lo_c, c_lo        # the CDF is a pure function: a value computed at the
    for k in range(k0, k1 + 1):        # same x is reused (a bin's upper end is the next
        lo = max(edges[k] - r, lo_c)   # one's lower), the same bits with half the calls
        hi = min(edges[k + 1] - r, hi_c)
        frac = 0.0
        if hi > lo:
            f_lo = last_c if lo == last_x else _fp_cdf(lo, a, b, box)
            f_hi = c_hi if hi == hi_c else _fp_cdf(hi, a, b, box)
            last_x, last_c = hi, f_hi
            frac = f_hi - f_lo
        out[k] += wt * (frac / mass)


@njit_loop(inline="always")
def _footprint_ahead(footprint, prim, i, ahead, n, rows, stamps, tag):  # pragma: no cover
    """Prefetch the footprint row of the hit ``ahead`` places on (and, where rows are made
    at first hits, its stamp and its face's row of ``faces``), and the corners of the hit
    half as far on whose row is still to be made (its row of faces fetched before, so
    read from cache)."""
    if i + ahead < n and prim[i + ahead] >= 0:
        _prefetch(rows, prim[i + ahead])
        if tag >= 0:
            _prefetch((stamps, footprint[3]), prim[i + ahead])
    k = i + (ahead >> 1)
    if tag >= 0 and k < n:
        q = prim[k]
        if q >= 0 and stamps[q] != tag:
            faces = footprint[3]
            _prefetch(footprint[2], faces[q, 0])
            _prefetch(footprint[2], faces[q, 1])
            _prefetch(footprint[2], faces[q, 2])


@njit_loop()
def bin_flat_hits(prim, tfar, origins, plane_d, face_normals, face_material, params,
                  w, start, edges, area, power, ignore_back, out, stamp, weight, tag,
                  footprint, single=False):
    """Monostatic, flat-normal weighing and binning of one view's Embree hits, fused:
    out[k] += F(θ)·area (``power``: F(θ)·cos θ·area, received power) for each hit with range start + t − o·w in bin k (o the float32 origin
    as cast), t the hit distance recomputed in float64 against the face's plane (as
    meshladar.raytrace.views.refine_t).
    ``params`` rows are (rho_d, epsilon, b, e, G, has_diffuse, has_specular) per material.
    With flat normals F·area is one number per face and view: it is evaluated at a face's
    first hit and kept in ``weight`` (n_faces,), valid where ``stamp`` equals ``tag`` (a
    number unique to the view), so the BRDF costs O(faces hit), not O(rays). The bin is
    found in O(1) on uniform edges (a guess from the first and last edge, checked against
    the edges exactly as a binary search would place the range), by bisection otherwise.
    ``footprint`` (:func:`footprint_row`'s tuple: each face's row made at its first hit)
    spreads each hit over its footprint's ranges (:func:`_spread_hit`) instead of binning
    it at a point; None bins at a point (numba then prunes the spreading branches: a run
    of point bins does not compile them). ``single``: the hits' rays were cast one at a
    time (a sparse grid), so the faces' rows are prefetched at any mesh size
    (:func:`._prefetch.ahead`); where footprint rows are made at first hits, a face's
    corners are prefetched half as far ahead (its row of faces already fetched): on
    2,000 sparse views of an 82k sphere 12-15 % faster; with point bins a face is hit about
    once a view there, so an unstamped face's weight (a built-in coating's: the others'
    are stamped first) is binned at once, not kept: 1-3 % faster, the same numbers.
    Returns the number of back-face hits."""
    nb = edges.size - 1
    e0 = edges[0]
    inv = nb / (edges[nb] - edges[0])
    back = 0
    rows, stamps, tag_fp = _NO_ROWS, _NO_STAMPS, -1    # out of the tuple once, not per hit
    if footprint is not None:
        rows, stamps, tag_fp = footprint[0], footprint[1], footprint[9]
    ahead, n = _ahead(face_normals, single), prim.size
    for i in range(n):
        if i + ahead < n and prim[i + ahead] >= 0:   # a later hit's rows (._prefetch)
            if single and footprint is None:
                _prefetch((face_normals, plane_d, stamp, face_material), prim[i + ahead])
            else:
                _prefetch((face_normals, plane_d, stamp, weight), prim[i + ahead])
        if footprint is not None:
            _footprint_ahead(footprint, prim, i, ahead, n, rows, stamps, tag_fp)
        p = prim[i]
        if p < 0:
            continue
        c, t, r_rel = face_hit(p, tfar[i], origins, i, w, plane_d, face_normals)
        if c < 0.0:
            back += 1
            if ignore_back:
                continue
            c = -c
        r = start + r_rel
        if footprint is None:
            if r < edges[0] or r >= edges[nb]:
                continue
        if single and footprint is None and stamp[p] != tag:
            m = face_material[p]
            out[_bin_of(r, edges, e0, inv)] += _sr_monostatic(
                c, max(1.0 - c * c, 0.0), params[m, 0], params[m, 1], params[m, 2],
                params[m, 3], params[m, 4], params[m, 5] > 0.5, params[m, 6] > 0.5
            ) * (area * c if power else area)
            continue
        if stamp[p] != tag:
            m = face_material[p]
            weight[p] = _sr_monostatic(c, max(1.0 - c * c, 0.0), params[m, 0], params[m, 1],
                                       params[m, 2], params[m, 3], params[m, 4],
                                       params[m, 5] > 0.5, params[m, 6] > 0.5
                                       ) * (area * c if power else area)
            stamp[p] = tag
        if footprint is None:
            out[_bin_of(r, edges, e0, inv)] += weight[p]
        else:
            if tag_fp >= 0 and stamps[p] != tag_fp:
                footprint_row(footprint, p, face_normals)
            _spread_hit(out, r, r_rel, weight[p], rows, p, edges, e0, inv)
    return back


@njit_loop()
def bin_bistatic_hits(prim, tfar, origins, blocked, plane_d, face_normals, w, wr, start,
                      edges, ignore_back, out, weight, stamp, tag, coating):
    """Bistatic (receiver direction ``wr``), flat-normal binning of one view's hits, fused:
    ``weight`` holds each face's F·area for the pair (w, wr) (F·cos θr·area under received
    power; 0 where either direction is below the face's horizon), valid where ``stamp`` equals ``tag``; a face whose weight
    is not yet the view's gets it at its first hit from ``coating`` (:func:`_bistatic_face`),
    so the BRDF costs O(faces hit). ``blocked`` says whether the ray from the hit toward the
    receiver meets the scene. A hit at p = o − t w has range start + ((t − o·w) − p·wr)/2,
    the two-way path, as meshladar.raytrace.views.trace_view. Returns the back-face hits."""
    nb = edges.size - 1
    e0 = edges[0]
    inv = nb / (edges[nb] - edges[0])
    back = 0
    ahead, n = _ahead(face_normals), prim.size
    for i in range(n):
        if i + ahead < n and prim[i + ahead] >= 0:   # a later hit's rows (._prefetch)
            _prefetch((face_normals, plane_d, stamp, weight), prim[i + ahead])
        p = prim[i]
        if p < 0:
            continue
        c, t, r_rel = face_hit(p, tfar[i], origins, i, w, plane_d, face_normals)
        if c < 0.0:
            back += 1
            if ignore_back:
                continue
        if blocked[i]:
            continue
        px = origins[i, 0] * 1.0 - t * w[0]
        py = origins[i, 1] * 1.0 - t * w[1]
        pz = origins[i, 2] * 1.0 - t * w[2]
        r = start + 0.5 * (r_rel + -(px * wr[0] + py * wr[1] + pz * wr[2]))
        if r < edges[0] or r >= edges[nb]:
            continue
        if stamp[p] != tag:
            weight[p] = _bistatic_face(face_normals, p, c, wr, coating)
            stamp[p] = tag
        out[_bin_of(r, edges, e0, inv)] += weight[p]
    return back


@njit_loop(inline="always")
def _bistatic_face(face_normals, p, c, wr, coating):
    """F·area of face p for the receiver along ``wr`` (flat normal n, c = n·w as the hit
    found it; a back face's normal and c are turned toward the ladar here), as meshladar.weighing.faces.face_bistatic_weights computes
    it for a built-in coating: ``coating`` = (face_material, params, half, area, power,
    built-in), ``half`` the unit half vector of w and wr, ``params`` the SR table's rows;
    F·cos θr under ``power``, F otherwise (:func:`sr_bistatic`)."""
    face_material, params, half, area, power = coating[:5]
    sign = -1.0 if c < 0.0 else 1.0
    n0, n1, n2 = face_normals[p, 0] * sign, face_normals[p, 1] * sign, face_normals[p, 2] * sign
    c = c * sign
    cr = n0 * wr[0] + n1 * wr[1] + n2 * wr[2]
    x, y, z = n1 * wr[2] - n2 * wr[1], n2 * wr[0] - n0 * wr[2], n0 * wr[1] - n1 * wr[0]
    sr = math.sqrt(x * x + y * y + z * z)
    ca = n0 * half[0] + n1 * half[1] + n2 * half[2]
    x, y, z = n1 * half[2] - n2 * half[1], n2 * half[0] - n0 * half[2], n0 * half[1] - n1 * half[0]
    sa = math.sqrt(x * x + y * y + z * z)
    m = face_material[p]
    return _sr_bistatic(c, math.sqrt(max(1.0 - c * c, 0.0)), cr, sr, ca, sa, params[m, 0],
                        params[m, 1], params[m, 2], params[m, 3], params[m, 4],
                        params[m, 5] > 0.5, params[m, 6] > 0.5, power) * area


@njit_loop()
def edge_on_receiver(face_normals, w, wr, ignore_back, cos_max):
    """Whether a face toward the ladar (a back face turned toward it, unless back faces
    are ignored) lies edge-on to the receiver, 0 ≤ cos θr < ``cos_max``: the faces
    meshladar.weighing.hit_weights warns of under the paper's radiometry, in one pass."""
    for p in range(face_normals.shape[0]):
        n0, n1, n2 = face_normals[p, 0], face_normals[p, 1], face_normals[p, 2]
        c = n0 * w[0] + n1 * w[1] + n2 * w[2]
        if c == 0.0 or (c < 0.0 and ignore_back):
            continue
        cr = (n0 * wr[0] + n1 * wr[1] + n2 * wr[2]) * (-1.0 if c < 0.0 else 1.0)
        if 0.0 <= cr < cos_max:
            return True
    return False


@njit_loop()
def bin_smooth_hits(prim, tfar, bu, bv, origins, plane_d, face_normals, corner, face_material,
                    params, w, start, edges, area, power, ignore_back, min_cos_facet, out,
                    footprint, single=False):
    """Monostatic weighing and binning with smooth normals, as :func:`bin_flat_hits` with
    flat ones: the shading normal interpolated from the face's ``corner`` normals (m, 3, 3)
    with Embree's barycentrics (bu, bv), F of the SR coating at its angle, and the area
    factor cos θs / max(|cos θg|, ``min_cos_facet``) of meshladar.raytrace.views.
    _shading_factor, so each ray weighs F(θs)·area·factor (``power``: times cos θs; 0 where
    the shading normal faces away); ``footprint`` as in :func:`bin_flat_hits` (the flat
    facet's extent); ``single`` as in :func:`bin_flat_hits`. Returns the number of
    back-face hits."""
    nb = edges.size - 1
    e0 = edges[0]
    inv = nb / (edges[nb] - edges[0])
    back = 0
    rows, stamps, tag_fp = _NO_ROWS, _NO_STAMPS, -1    # out of the tuple once, not per hit
    if footprint is not None:
        rows, stamps, tag_fp = footprint[0], footprint[1], footprint[9]
    ahead, n = _ahead(face_normals, single), prim.size
    for i in range(n):
        if i + ahead < n and prim[i + ahead] >= 0:   # a later hit's rows (._prefetch)
            _prefetch((face_normals, plane_d, corner, face_material), prim[i + ahead])
        if footprint is not None:
            _footprint_ahead(footprint, prim, i, ahead, n, rows, stamps, tag_fp)
        p = prim[i]
        if p < 0:
            continue
        cg, t, r_rel = face_hit(p, tfar[i], origins, i, w, plane_d, face_normals)
        c = _smooth_cos(corner, p, bu[i] * 1.0, bv[i] * 1.0, w[0], w[1], w[2])
        if cg < 0.0:
            back += 1
            if ignore_back:
                continue
            c = -c
        if c <= 0.0:
            continue                                   # the shading normal faces away
        r = start + r_rel
        if footprint is None:
            if r < edges[0] or r >= edges[nb]:
                continue
        m = face_material[p]
        f = _sr_monostatic(c, max(1.0 - c * c, 0.0), params[m, 0], params[m, 1], params[m, 2],
                           params[m, 3], params[m, 4], params[m, 5] > 0.5, params[m, 6] > 0.5)
        f = f * c if power else f
        wt = f * area * (c / max(abs(cg), min_cos_facet))
        if footprint is None:
            out[_bin_of(r, edges, e0, inv)] += wt
        else:
            if tag_fp >= 0 and stamps[p] != tag_fp:
                footprint_row(footprint, p, face_normals)
            _spread_hit(out, r, r_rel, wt, rows, p, edges, e0, inv)
    return back
