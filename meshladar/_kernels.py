"""Compiled inner loops (numba): backprojection and Siddon ray traversal.

numba is imported here, and this module is imported lazily by the stages that need it, so
``import meshladar`` stays numpy/scipy only. Kernels are cached on disk (``cache=True``) so
the JIT cost (~1 s each) is paid once per installation, not per process.

Why numba: filtered backprojection of 360 × 1024 onto 1024² is 3.8e8 interpolations; numpy
spends ~10 passes over memory on each and cannot beat scikit-image's per-angle loop by the
required 5×; a compiled, cache-friendly loop parallel over image rows does.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numba import njit, prange
from .precision import COS_HORIZON as _COS_HORIZON
from .precision import SIDDON_NUDGE as _NUDGE
from .precision import BOX_RATIO as _BOX_RATIO
from .precision import TINY as _TINY

__all__ = ["backproject", "siddon_project", "siddon_backproject", "siddon_first_hits",
           "set_threads"]


def set_threads(n: int | None):
    """Limit the compiled kernels to n threads (None: all cores)."""
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS if n is None else int(n))


@njit(parallel=True, cache=True, fastmath=False)
def backproject(q, cos_phi, sin_phi, weight, r0, inv_dr, x, y, nearest, out):
    """out[i, j] += Σ_v weight[v] · q_v(r), r = −(x_j cos φ_v + y_i sin φ_v).

    q : (n_views, n_bins) samples at r0 + k/inv_dr; linear (or nearest-sample) interpolation,
    0 outside [r0, r0 + (n_bins − 1)/inv_dr].
    """
    n_views, n_bins = q.shape
    ny = y.size
    nx = x.size
    for i in prange(ny):
        for v in range(n_views):
            c = cos_phi[v]
            s = sin_phi[v]
            wv = weight[v]
            base = (-y[i] * s - r0) * inv_dr
            step = -c * inv_dr
            for j in range(nx):
                u = base + x[j] * step
                if nearest:
                    k = int(math.floor(u + 0.5))
                    if 0 <= k < n_bins:
                        out[i, j] += wv * q[v, k]
                else:
                    fk = math.floor(u)
                    k = int(fk)
                    if 0 <= k < n_bins - 1:
                        f = u - fk
                        out[i, j] += wv * (q[v, k] + f * (q[v, k + 1] - q[v, k]))
                    elif k == n_bins - 1 and u == fk:
                        out[i, j] += wv * q[v, k]


@njit(cache=True)
def _traverse(ox, oy, dx, dy, xmin, ymin, pix, nx, ny, idx, length):
    """Siddon/Jacobs traversal of the line o + α d (|d| = 1) through an nx × ny grid of
    square pixels of side ``pix`` with lower-left corner (xmin, ymin). Fills the flat pixel
    indices (row-major, row = y) and exact intersection lengths in order of increasing α;
    returns (count, α at entry)."""
    big = 1e300
    # parametric range inside the grid's bounding box
    xmax = xmin + nx * pix
    ymax = ymin + ny * pix
    a_lo = -big
    a_hi = big
    if dx != 0.0:
        a1 = (xmin - ox) / dx
        a2 = (xmax - ox) / dx
        a_lo = max(a_lo, min(a1, a2))
        a_hi = min(a_hi, max(a1, a2))
    elif not (xmin <= ox < xmax):
        return 0, 0.0
    if dy != 0.0:
        a1 = (ymin - oy) / dy
        a2 = (ymax - oy) / dy
        a_lo = max(a_lo, min(a1, a2))
        a_hi = min(a_hi, max(a1, a2))
    elif not (ymin <= oy < ymax):
        return 0, 0.0
    if a_hi <= a_lo:
        return 0, 0.0
    # entry pixel: from the point slightly inside along the ray
    am = a_lo + _NUDGE * pix if a_hi - a_lo > 2 * _NUDGE * pix else 0.5 * (a_lo + a_hi)
    px = ox + am * dx
    py = oy + am * dy
    i = min(max(int(math.floor((px - xmin) / pix)), 0), nx - 1)
    j = min(max(int(math.floor((py - ymin) / pix)), 0), ny - 1)
    # next crossings of vertical / horizontal grid lines
    if dx > 0.0:
        step_i = 1
        ax = (xmin + (i + 1) * pix - ox) / dx
        dax = pix / dx
    elif dx < 0.0:
        step_i = -1
        ax = (xmin + i * pix - ox) / dx
        dax = -pix / dx
    else:
        step_i = 0
        ax = big
        dax = big
    if dy > 0.0:
        step_j = 1
        ay = (ymin + (j + 1) * pix - oy) / dy
        day = pix / dy
    elif dy < 0.0:
        step_j = -1
        ay = (ymin + j * pix - oy) / dy
        day = -pix / dy
    else:
        step_j = 0
        ay = big
        day = big
    a = a_lo
    n = 0
    while a < a_hi and 0 <= i < nx and 0 <= j < ny:
        nxt = min(ax, ay, a_hi)
        if nxt > a:
            idx[n] = j * nx + i
            length[n] = nxt - a
            n += 1
        a = nxt
        if ax <= ay:
            ax += dax
            i += step_i
        else:
            ay += day
            j += step_j
    return n, a_lo


@njit(parallel=True, cache=True)
def siddon_project(image, ox, oy, dx, dy, xmin, ymin, pix, out):
    """out[m] = Σ_pixels length(ray m ∩ pixel) · image[pixel] (line integrals)."""
    ny, nx = image.shape
    flat = image.ravel()
    for m in prange(ox.size):
        idx = np.empty(nx + ny + 2, np.int64)
        length = np.empty(nx + ny + 2, np.float64)
        n, _ = _traverse(ox[m], oy[m], dx[m], dy[m], xmin, ymin, pix, nx, ny, idx, length)
        acc = 0.0
        for t in range(n):
            acc += length[t] * flat[idx[t]]
        out[m] = acc


@njit(parallel=True, cache=True)
def siddon_backproject_parallel(values, ox, oy, dx, dy, xmin, ymin, pix, parts):
    """siddon_backproject over ``parts.shape[0]`` contiguous blocks of rays in parallel,
    each into its own image parts[k] (sum them for the backprojection; the order of the
    sum, hence the rounding, is fixed by the number of parts)."""
    n_parts, ny, nx = parts.shape
    n = ox.size
    for k in prange(n_parts):
        flat = parts[k].ravel()
        idx = np.empty(nx + ny + 2, np.int64)
        length = np.empty(nx + ny + 2, np.float64)
        for m in range(k * n // n_parts, (k + 1) * n // n_parts):
            c, _ = _traverse(ox[m], oy[m], dx[m], dy[m], xmin, ymin, pix, nx, ny, idx, length)
            for t in range(c):
                flat[idx[t]] += length[t] * values[m]


@njit(cache=True)
def siddon_backproject(values, ox, oy, dx, dy, xmin, ymin, pix, out):
    """out[pixel] += Σ_m length(ray m ∩ pixel) · values[m]: the exact adjoint of
    siddon_project (serial: rays scatter into shared pixels)."""
    ny, nx = out.shape
    flat = out.ravel()
    idx = np.empty(nx + ny + 2, np.int64)
    length = np.empty(nx + ny + 2, np.float64)
    for m in range(ox.size):
        n, _ = _traverse(ox[m], oy[m], dx[m], dy[m], xmin, ymin, pix, nx, ny, idx, length)
        for t in range(n):
            flat[idx[t]] += length[t] * values[m]


@njit(cache=True)
def _first_hit(m, flat, ox, oy, dx, dy, xmin, ymin, pix, nx, ny, hit_pixel, hit_alpha):
    """Ray m's first pixel with mask > 0 and the α of the middle of its traversal."""
    idx = np.empty(nx + ny + 2, np.int64)
    length = np.empty(nx + ny + 2, np.float64)
    n, a0 = _traverse(ox[m], oy[m], dx[m], dy[m], xmin, ymin, pix, nx, ny, idx, length)
    hit_pixel[m] = -1
    hit_alpha[m] = np.nan
    a = a0
    for t in range(n):
        if flat[idx[t]] > 0:
            hit_pixel[m] = idx[t]
            hit_alpha[m] = a + 0.5 * length[t]
            return
        a += length[t]


@njit(parallel=True, cache=True)
def siddon_first_hits(mask, ox, oy, dx, dy, xmin, ymin, pix, hit_pixel, hit_alpha):
    """For each ray, the first pixel along it with mask > 0 and the α of the middle of its
    traversal (−1 and nan where the ray meets none); rays in parallel."""
    ny, nx = mask.shape
    flat = mask.ravel()
    for m in prange(ox.size):
        _first_hit(m, flat, ox, oy, dx, dy, xmin, ymin, pix, nx, ny, hit_pixel, hit_alpha)


@njit(cache=True)
def siddon_first_hits_serial(mask, ox, oy, dx, dy, xmin, ymin, pix, hit_pixel, hit_alpha):
    """:func:`siddon_first_hits` on one thread (in a worker process, see
    :func:`meshladar.stream.in_worker`)."""
    ny, nx = mask.shape
    flat = mask.ravel()
    for m in range(ox.size):
        _first_hit(m, flat, ox, oy, dx, dy, xmin, ymin, pix, nx, ny, hit_pixel, hit_alpha)


@njit(cache=True)
def corner_normals(faces, face_normals, face_areas, ptr, face_of, cos_crease, out):
    """out[f, c] = normalised Σ area_g n_g over faces g around vertex faces[f, c] with
    n_g · n_f ≥ cos_crease (always including f itself)."""
    m = faces.shape[0]
    for f in range(m):
        for c in range(3):
            vtx = faces[f, c]
            sx = 0.0
            sy = 0.0
            sz = 0.0
            for k in range(ptr[vtx], ptr[vtx + 1]):
                g = face_of[k]
                d = (face_normals[g, 0] * face_normals[f, 0] + face_normals[g, 1]
                     * face_normals[f, 1] + face_normals[g, 2] * face_normals[f, 2])
                if d >= cos_crease or g == f:
                    sx += face_areas[g] * face_normals[g, 0]
                    sy += face_areas[g] * face_normals[g, 1]
                    sz += face_areas[g] * face_normals[g, 2]
            nn = math.sqrt(sx * sx + sy * sy + sz * sz)
            if nn > 0.0:
                out[f, c, 0] = sx / nn
                out[f, c, 1] = sy / nn
                out[f, c, 2] = sz / nn
            else:
                out[f, c, 0] = face_normals[f, 0]
                out[f, c, 1] = face_normals[f, 1]
                out[f, c, 2] = face_normals[f, 2]




@njit(cache=True)
def _sr_monostatic(c, s, rho_d, eps, b, e, G, diffuse, specular):
    """F(θ; −θ) of meshladar.brdf.SandfordRobertson from cos θ ≥ 0 and sin θ: the same
    expressions as SandfordRobertson._core (tests hold the two to 1e-13)."""
    den = math.hypot(c, b * s)
    g = (c / den) ** 2 if den > 0.0 else 1.0
    out = 0.0
    if diffuse:
        out += rho_d / (math.pi * G * G) * g * g
    if specular:
        rho_s = max(1.0 - (eps + rho_d) / G * g, 0.0)
        d = math.hypot(e * c, s) ** 2
        k = (1.0 - e) * (1.0 + e)
        kc = k * c
        h_scaled = kc + (2.0 * e * e + kc * kc) / math.hypot(2.0 * e, kc)
        out += rho_s * (2.0 * e * e / (d * d * h_scaled)) / (4.0 * math.pi) / max(c, _COS_HORIZON)
    return out


@njit(cache=True, nogil=True)
def _hit_distance(p, c, tf, origins, i, plane_d, face_normals):
    """Ray i's distance to face p, recomputed in float64 against the face's plane from the
    float32 origin as cast (c = n·w); Embree's float32 ``tf`` where the plane is edge-on
    (as meshladar.raytrace.views._refine_t)."""
    if abs(c) <= 1e-6:
        return tf * 1.0
    return (plane_d[p] - (face_normals[p, 0] * origins[i, 0] + face_normals[p, 1] * origins[i, 1]
                          + face_normals[p, 2] * origins[i, 2])) / (-c)


@njit(cache=True, nogil=True, inline="always")
def _face_hit(p, tf, origins, i, w, plane_d, face_normals):
    """Ray i's hit on face p seen along w: (c, t, r) with c = n·w the flat normal's cosine
    (negative on a back face), t the float64 distance (:func:`_hit_distance`) and
    r = t − o·w its range relative to the shifted centre's plane."""
    c = face_normals[p, 0] * w[0] + face_normals[p, 1] * w[1] + face_normals[p, 2] * w[2]
    t = _hit_distance(p, c, tf, origins, i, plane_d, face_normals)
    return c, t, t - (origins[i, 0] * w[0] + origins[i, 1] * w[1] + origins[i, 2] * w[2])


@njit(cache=True, nogil=True)
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


@njit(cache=True, nogil=True, inline="always")
def _smooth_cos(corner, p, a, b, wx, wy, wz):
    """cos θ of face p's shading normal, interpolated from its ``corner`` normals with
    Embree's barycentrics (a, b) and normalised, against the direction (wx, wy, wz)."""
    nx = (1 - a - b) * corner[p, 0, 0] + a * corner[p, 1, 0] + b * corner[p, 2, 0]
    ny = (1 - a - b) * corner[p, 0, 1] + a * corner[p, 1, 1] + b * corner[p, 2, 1]
    nz = (1 - a - b) * corner[p, 0, 2] + a * corner[p, 1, 2] + b * corner[p, 2, 2]
    norm = math.sqrt(nx * nx + ny * ny + nz * nz)
    return (nx / norm) * wx + (ny / norm) * wy + (nz / norm) * wz


@njit(cache=True, nogil=True, inline="always")
def _fp_cdf(x, a, b, box):
    """CDF at x of the footprint's range offset A + B, A ~ U(−a, a), B ~ U(−b, b) (a box
    when ``box``): meshladar.weighing._box_cdf and _trap_cdf, one value at a time."""
    if box:
        return min(max((x + a) / (2 * a if a > 0 else 1.0), 0.0), 1.0)
    num = _half_sq(x + a + b) - _half_sq(x + a - b) - _half_sq(x - a + b) + _half_sq(x - a - b)
    return min(max(num / (4 * a * b if a * b > 0 else 1.0), 0.0), 1.0)


@njit(cache=True, nogil=True, inline="always")
def _half_sq(y):
    return 0.5 * max(y, 0.0) ** 2


@njit(cache=True, nogil=True, inline="always")
def _clipped_bin(x, edges, e0, inv):
    """searchsorted(edges, x, "right") − 1 clipped to the bins (as weighing._bin_one)."""
    nb = edges.size - 1
    if x < edges[0]:
        return 0
    if x >= edges[nb]:
        return nb - 1
    return _bin_of(x, edges, e0, inv)


@njit(cache=True, nogil=True)
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
    mass = _fp_cdf(hi_c, a, b, box) - _fp_cdf(lo_c, a, b, box)
    if mass <= 0:
        mass = 1.0
    for k in range(k0, k1 + 1):
        lo = max(edges[k] - r, lo_c)
        hi = min(edges[k + 1] - r, hi_c)
        frac = (_fp_cdf(hi, a, b, box) - _fp_cdf(lo, a, b, box)) if hi > lo else 0.0
        out[k] += wt * (frac / mass)


@njit(cache=True, nogil=True)
def bin_flat_hits(prim, tfar, origins, plane_d, face_normals, face_material, params,
                  w, start, edges, area, power, ignore_back, out, stamp, weight, tag,
                  footprint):
    """Monostatic, flat-normal weighing and binning of one view's Embree hits, fused:
    out[k] += F(θ)·area (``power``: F(θ)·cos θ·area, received power) for each hit with range start + t − o·w in bin k (o the float32 origin
    as cast), t the hit distance recomputed in float64 against the face's plane (as
    meshladar.raytrace.views._refine_t).
    ``params`` rows are (rho_d, epsilon, b, e, G, has_diffuse, has_specular) per material.
    With flat normals F·area is one number per face and view: it is evaluated at a face's
    first hit and kept in ``weight`` (n_faces,), valid where ``stamp`` equals ``tag`` (a
    number unique to the view), so the BRDF costs O(faces hit), not O(rays). The bin is
    found in O(1) on uniform edges (a guess from the first and last edge, checked against
    the edges exactly as a binary search would place the range), by bisection otherwise.
    ``footprint`` (n_faces, 4), when not empty, spreads each hit over its footprint's
    ranges (:func:`_spread_hit`) instead of binning it at a point.
    Returns the number of back-face hits."""
    nb = edges.size - 1
    e0 = edges[0]
    inv = nb / (edges[nb] - edges[0])
    spread = footprint.shape[0] > 0
    back = 0
    for i in range(prim.size):
        p = prim[i]
        if p < 0:
            continue
        c, t, r_rel = _face_hit(p, tfar[i], origins, i, w, plane_d, face_normals)
        if c < 0.0:
            back += 1
            if ignore_back:
                continue
            c = -c
        r = start + r_rel
        if not spread and (r < edges[0] or r >= edges[nb]):
            continue
        if stamp[p] != tag:
            s = math.sqrt(max(1.0 - c * c, 0.0))
            m = face_material[p]
            weight[p] = _sr_monostatic(c, s, params[m, 0], params[m, 1], params[m, 2],
                                       params[m, 3], params[m, 4], params[m, 5] > 0.5,
                                       params[m, 6] > 0.5) * (area * c if power else area)
            stamp[p] = tag
        if spread:
            _spread_hit(out, r, r_rel, weight[p], footprint, p, edges, e0, inv)
        else:
            out[_bin_of(r, edges, e0, inv)] += weight[p]
    return back


@njit(cache=True, nogil=True)
def bin_bistatic_hits(prim, tfar, origins, blocked, plane_d, face_normals, w, wr, start,
                      edges, ignore_back, out, weight):
    """Bistatic (receiver direction ``wr``), flat-normal binning of one view's hits, fused:
    ``weight`` holds each face's F·area for the pair (w, wr) (0 where either direction is
    below the face's horizon), ``blocked`` whether the ray from the hit toward the receiver
    meets the scene. A hit at p = o − t w has range start + ((t − o·w) − p·wr)/2, the
    two-way path, as meshladar.raytrace.views._trace_view. Returns the back-face hits."""
    nb = edges.size - 1
    e0 = edges[0]
    inv = nb / (edges[nb] - edges[0])
    back = 0
    for i in range(prim.size):
        p = prim[i]
        if p < 0:
            continue
        c, t, r_rel = _face_hit(p, tfar[i], origins, i, w, plane_d, face_normals)
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
        out[_bin_of(r, edges, e0, inv)] += weight[p]
    return back


@njit(cache=True, nogil=True)
def bin_smooth_hits(prim, tfar, bu, bv, origins, plane_d, face_normals, corner, face_material,
                    params, w, start, edges, area, power, ignore_back, min_cos_facet, out,
                    footprint):
    """Monostatic weighing and binning with smooth normals, as :func:`bin_flat_hits` with
    flat ones: the shading normal interpolated from the face's ``corner`` normals (m, 3, 3)
    with Embree's barycentrics (bu, bv), F of the SR coating at its angle, and the area
    factor cos θs / max(|cos θg|, ``min_cos_facet``) of meshladar.raytrace.views.
    _shading_factor, so each ray weighs F(θs)·area·factor (``power``: times cos θs; 0 where
    the shading normal faces away); ``footprint`` as in :func:`bin_flat_hits` (the flat
    facet's extent). Returns the number of back-face hits."""
    nb = edges.size - 1
    e0 = edges[0]
    inv = nb / (edges[nb] - edges[0])
    spread = footprint.shape[0] > 0
    back = 0
    for i in range(prim.size):
        p = prim[i]
        if p < 0:
            continue
        cg, t, r_rel = _face_hit(p, tfar[i], origins, i, w, plane_d, face_normals)
        c = _smooth_cos(corner, p, bu[i] * 1.0, bv[i] * 1.0, w[0], w[1], w[2])
        if cg < 0.0:
            back += 1
            if ignore_back:
                continue
            c = -c
        if c <= 0.0:
            continue                                   # the shading normal faces away
        r = start + r_rel
        if not spread and (r < edges[0] or r >= edges[nb]):
            continue
        s = math.sqrt(max(1.0 - c * c, 0.0))
        m = face_material[p]
        f = _sr_monostatic(c, s, params[m, 0], params[m, 1], params[m, 2], params[m, 3],
                           params[m, 4], params[m, 5] > 0.5, params[m, 6] > 0.5)
        f = f * c if power else f
        wt = f * area * (c / max(abs(cg), min_cos_facet))
        if spread:
            _spread_hit(out, r, r_rel, wt, footprint, p, edges, e0, inv)
        else:
            out[_bin_of(r, edges, e0, inv)] += wt
    return back


@njit(cache=True, nogil=True)
def bin_sensor_hits(prim, t_cast, S, T, bu, bv, u, v, w, D, sensor_pos, range_offset,
                    plane_d, face_normals, corner, smooth, face_material, params, beam,
                    extinction, edges, area, power, ignore_back, min_cos_facet, refine_min_cos,
                    out):
    """Monostatic weighing and binning of one view seen by a sensor at standoff D, fused
    (the numbers of meshladar.raytrace.perspective._trace_sensor_view then
    meshladar.weighing._bin_one, without per-hit arrays): ray i leaves ``sensor_pos``
    along q/|q|, q = S[i] u + T[i] v − D w; its hit distance R is recomputed in float64
    against the hit face's plane (``t_cast`` where the plane is edge-on); its weight is
    F·area × cos³α (R/D)² × the beam's relative irradiance (× the smooth normal's area
    factor), and under ``power`` × cos θ (D/R)² exp(−2σR); its range R − ``range_offset``.
    ``beam`` = (kind, radius or −1, waist, divergence, ax, ay, az): kind 0 a flood (a
    top-hat of ``radius`` at distance D when ≥ 0), 1 a Gaussian of 1/e² radius
    sqrt(waist² + (divergence z)²) about the axis (ax, ay, az) from the sensor. Returns
    the number of back-face hits."""
    nb = edges.size - 1
    e0 = edges[0]
    inv = nb / (edges[nb] - edges[0])
    back = 0
    kind = beam[0]
    ax, ay, az = beam[4], beam[5], beam[6]
    w_ref = math.sqrt(beam[2] * beam[2] + (beam[3] * D) ** 2)
    for i in range(prim.size):
        p = prim[i]
        if p < 0:
            continue
        qx = S[i] * u[0] + T[i] * v[0] - D * w[0]
        qy = S[i] * u[1] + T[i] * v[1] - D * w[1]
        qz = S[i] * u[2] + T[i] * v[2] - D * w[2]
        length = math.sqrt(S[i] * S[i] + T[i] * T[i] + D * D)
        dx, dy, dz = qx / length, qy / length, qz / length
        nx, ny, nz = face_normals[p, 0], face_normals[p, 1], face_normals[p, 2]
        denom = nx * dx + ny * dy + nz * dz
        if abs(denom) > refine_min_cos:
            R = (plane_d[p] - (nx * sensor_pos[0] + ny * sensor_pos[1]
                               + nz * sensor_pos[2])) / denom
        else:
            R = t_cast[i]
        cg = -denom
        if smooth:
            c = _smooth_cos(corner, p, bu[i] * 1.0, bv[i] * 1.0, -dx, -dy, -dz)
        else:
            c = cg
        if cg < 0.0:
            back += 1
            if ignore_back:
                continue
            c = -c
        if c <= 0.0:
            continue
        r = R - range_offset
        if r < edges[0] or r >= edges[nb]:
            continue
        k = _bin_of(r, edges, e0, inv)
        px, py, pz = R * dx, R * dy, R * dz          # the hit relative to the sensor
        z = px * ax + py * ay + pz * az
        rx, ry, rz = px - z * ax, py - z * ay, pz - z * az
        rho2 = rx * rx + ry * ry + rz * rz
        if kind == 0:
            rel = D * D / (rho2 + z * z)
            if beam[1] >= 0.0 and math.sqrt(rho2) * D > beam[1] * z:
                rel = 0.0
        else:
            wz2 = beam[2] * beam[2] + (beam[3] * z) ** 2
            rel = w_ref * w_ref / wz2 * math.exp(-2.0 * rho2 / wz2)
        factor = (D / length) ** 3 * (R / D) ** 2 * rel
        if smooth:
            factor *= c / max(abs(cg), min_cos_facet)
        s = math.sqrt(max(1.0 - c * c, 0.0))
        m = face_material[p]
        f = _sr_monostatic(c, s, params[m, 0], params[m, 1], params[m, 2], params[m, 3],
                           params[m, 4], params[m, 5] > 0.5, params[m, 6] > 0.5)
        wt = f * area * factor
        if power:
            wt *= c * (D / R) ** 2 * math.exp(-2.0 * extinction * R)
        out[k] += wt
    return back


@njit(parallel=True, cache=True)
def backproject3d(q, wx, wy, wz, weight, r0, inv_dr, x, y, z, out):
    """out[k, i, j] += Σ_v weight[v] · q_v(r), r = −(x_j wx_v + y_i wy_v + z_k wz_v): the
    3-D backprojection over view directions. q : (n_views, n_bins) samples at
    r0 + m/inv_dr, linearly interpolated, 0 outside."""
    n_views, n_bins = q.shape
    nz, ny, nx = z.size, y.size, x.size
    for k in prange(nz):
        for v in range(n_views):
            wv = weight[v]
            step = -wx[v] * inv_dr
            for i in range(ny):
                base = (-(y[i] * wy[v] + z[k] * wz[v]) - r0) * inv_dr
                for j in range(nx):
                    u = base + x[j] * step
                    fk = math.floor(u)
                    m = int(fk)
                    if 0 <= m < n_bins - 1:
                        f = u - fk
                        out[k, i, j] += wv * (q[v, m] + f * (q[v, m + 1] - q[v, m]))


@njit(parallel=True, cache=True)
def splat_project(image, cos_phi, sin_phi, weight, r0, inv_dr, x, y, out):
    """The exact transpose of :func:`backproject` (linear interpolation): out[v, k] +=
    weight[v] · image[i, j] · (the linear weight of sample k at r = −(x_j cos φ_v +
    y_i sin φ_v)); parallel over views (each writes its own row)."""
    n_views, n_bins = out.shape
    ny, nx = image.shape
    for v in prange(n_views):
        c = cos_phi[v]
        s = sin_phi[v]
        wv = weight[v]
        step = -c * inv_dr
        for i in range(ny):
            base = (-y[i] * s - r0) * inv_dr
            for j in range(nx):
                u = base + x[j] * step
                fk = math.floor(u)
                k = int(fk)
                if 0 <= k < n_bins - 1:
                    f = u - fk
                    val = wv * image[i, j]
                    out[v, k] += val * (1.0 - f)
                    out[v, k + 1] += val * f
                elif k == n_bins - 1 and u == fk:
                    out[v, k] += wv * image[i, j]


@njit(cache=True, inline="always")
def _segment_bins(r, a, e0, inv_dr, n_bins):
    """(first bin, last bin + 1, lo, hi) of the range interval [r − a, r + a] in bin units
    (bin k spans [k, k + 1]), clipped to the bins."""
    lo = (r - a - e0) * inv_dr
    hi = (r + a - e0) * inv_dr
    k0 = max(0, int(math.floor(lo)))
    k1 = min(n_bins, int(math.floor(hi)) + 1)
    return k0, k1, lo, hi


@njit(cache=True, inline="always")
def _overlap(k, lo, hi):
    """The fraction of [lo, hi] inside [k, k + 1] (all of it when hi − lo is 0)."""
    if hi - lo <= 1e-12:
        return 1.0 if k <= lo < k + 1 else 0.0
    return max(0.0, min(hi, k + 1.0) - max(lo, float(k))) / (hi - lo)


@njit(parallel=True, cache=True)
def surface_project(values, px, py, tx, ty, half, H, cos_phi, sin_phi, e0, inv_dr, out):
    """The view-weighted projector of surface segments: segment n (centre (px, py), unit
    tangent (tx, ty), half-length half[n]) adds H[n, v] · values[n] to the bins its range
    interval r ± half·|t·w| covers, in proportion to the overlap (bin k spans
    [e0 + k/inv_dr, e0 + (k + 1)/inv_dr]); parallel over views."""
    n_views, n_bins = out.shape
    for v in prange(n_views):
        c = cos_phi[v]
        s = sin_phi[v]
        for n in range(px.size):
            val = H[n, v] * values[n]
            if val == 0.0:
                continue
            r = -(px[n] * c + py[n] * s)
            a = half[n] * abs(tx[n] * c + ty[n] * s)
            k0, k1, lo, hi = _segment_bins(r, a, e0, inv_dr, n_bins)
            for k in range(k0, k1):
                out[v, k] += val * _overlap(k, lo, hi)


@njit(parallel=True, cache=True)
def surface_backproject(q, px, py, tx, ty, half, H, cos_phi, sin_phi, e0, inv_dr, out):
    """The exact transpose of :func:`surface_project`: out[n] = Σ_v H[n, v] · (the
    overlap-weighted mean of q_v over segment n's bins); parallel over segments."""
    n_views, n_bins = q.shape
    for n in prange(px.size):
        acc = 0.0
        for v in range(n_views):
            h = H[n, v]
            if h == 0.0:
                continue
            c = cos_phi[v]
            s = sin_phi[v]
            r = -(px[n] * c + py[n] * s)
            a = half[n] * abs(tx[n] * c + ty[n] * s)
            k0, k1, lo, hi = _segment_bins(r, a, e0, inv_dr, n_bins)
            for k in range(k0, k1):
                acc += h * q[v, k] * _overlap(k, lo, hi)
        out[n] = acc


@njit(parallel=True, cache=True)
def surface_shadows(occupied, rows, cols, cos_phi, sin_phi, out):
    """out[n, v] = True where the ray from pixel n's centre toward the ladar of view v
    (direction w = (cos φ, sin φ), in pixel units) leaves the occupied pixels it starts in,
    stays out for two pixels (so a staircase gap in its own surface does not count) and
    then enters occupied pixels again: another surface lies between it and the ladar.
    Steps of half a pixel; parallel over pixels."""
    ny, nx = occupied.shape
    for n in prange(rows.size):
        for v in range(cos_phi.size):
            c = 0.5 * cos_phi[v]
            s = 0.5 * sin_phi[v]
            px = cols[n] + 0.5
            py = rows[n] + 0.5
            outside = 0
            while True:
                px += c
                py += s
                if px < 0.0 or py < 0.0 or px >= nx or py >= ny:
                    break
                if occupied[int(py), int(px)]:
                    if outside >= 4:
                        out[n, v] = True
                        break
                    outside = 0
                else:
                    outside += 1
