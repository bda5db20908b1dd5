"""The scan's compiled loops: sub-ray directions in the world, hits refined in float64,
and each return's ground truth; each the twin of the numpy it replaced (the docstrings of
:mod:`.cast` and :mod:`.run` say what they compute)."""

from __future__ import annotations

import math

import numba
import numpy as np

__all__ = ["MIN_RANGE", "world_sub_rays", "offset_table", "pulse_sub_rays", "pack_rays",
           "refine_hits", "refine_hit", "assign_truth", "erf", "sort_small", "discrete_returns"]

#: The nearest hit a sub-ray can range, m: a hit at this distance from its origin or
#: nearer (zero or, by rounding, negative: a sensor on a surface) is a miss, and the
#: sub-ray ends there. Far below any ladar's range; far above float64's rounding of a hit
#: at the origin (~1e-16 of the scene's size) in any scene under 10⁹ m.
MIN_RANGE = 1e-6

#: :func:`erf`'s table: nodes every 1/64 on [−6, 6] (beyond, erf is ±1 in float64:
#: erfc(5.93) < 2⁻⁵⁴), the erf and 2/√π exp(−x²) at each.
_ERF_STEP = 64.0
_ERF_MAX = 6.0
_ERF_X = np.arange(-384, 385) / _ERF_STEP
_ERF_F = np.array([math.erf(x) for x in _ERF_X])
_ERF_G = 2.0 / math.sqrt(math.pi) * np.exp(-_ERF_X ** 2)
#: Terms of the Taylor series about the nearest node (|δ| ≤ 1/128: the 9th is < 1e-20).
_ERF_TERMS = 8

@numba.njit(cache=True, nogil=True, inline="always")
def erf(x):                                              # pragma: no cover - compiled
    """erf(x) to 1 ulp of 1 (as libm's), five times faster: the Taylor series about the
    nearest of :data:`_ERF_X`, erf(xᵢ + δ) = erf(xᵢ) + 2/√π exp(−xᵢ²) Σₙ (−1)ⁿ⁻¹
    Hₙ₋₁(xᵢ) δⁿ / n! with the Hermite polynomials Hₙ by their recurrence."""
    x = min(max(x, -_ERF_MAX), _ERF_MAX)
    i = int(x * _ERF_STEP + (_ERF_MAX * _ERF_STEP + 0.5))
    xi = _ERF_X[i]
    d = x - xi
    h0 = 1.0
    h1 = 2.0 * xi
    q = d
    acc = q
    for n in range(1, _ERF_TERMS):
        q = -q * d / (n + 1)
        acc += q * h1
        h0, h1 = h1, 2.0 * xi * h1 - 2.0 * n * h0
    return _ERF_F[i] + _ERF_G[i] * acc


@numba.njit(cache=True, nogil=True)
def sort_small(values, order):                           # pragma: no cover - compiled
    """order[:] = the stable argsort of ``values`` (no NaN): insertion sort for a pulse's
    few sub-rays (no allocation), a bottom-up merge sort beyond 64 (written here: numpy's
    argsort, and the slice assignment of its result, took 3.4 s to compile)."""
    m = values.shape[0]
    if m > 64:
        _merge_sort(values, order)
        return
    for i in range(m):
        j = i
        while j > 0 and values[order[j - 1]] > values[i]:
            order[j] = order[j - 1]
            j -= 1
        order[j] = i


@numba.njit(cache=True, nogil=True)
def _merge_sort(values, order):                           # pragma: no cover - compiled
    """The stable argsort of ``values`` into ``order`` by merging runs of 1, 2, 4, …
    (the left run's element first where two are equal)."""
    m = values.shape[0]
    src = np.arange(m)
    dst = np.empty(m, np.int64)
    width = 1
    while width < m:
        for lo in range(0, m, 2 * width):
            mid, hi = min(lo + width, m), min(lo + 2 * width, m)
            i, j, k = lo, mid, lo
            while i < mid and j < hi:
                if values[src[j]] < values[src[i]]:
                    dst[k] = src[j]
                    j += 1
                else:
                    dst[k] = src[i]
                    i += 1
                k += 1
            while i < mid:
                dst[k] = src[i]
                i += 1
                k += 1
            while j < hi:
                dst[k] = src[j]
                j += 1
                k += 1
        src, dst = dst, src
        width *= 2
    for i in range(m):
        order[i] = src[i]


@numba.njit(cache=True, nogil=True)
def world_sub_rays(rot, local, offsets, pitch, out):     # pragma: no cover - compiled
    """out[p, k] = rot[p] @ (pulse p's sub-ray k in the sensor frame), normalised; a beam's
    offsets are angles about the pulse's direction (pitch < 0), a flash pixel's fractions
    of ``pitch`` on the focal plane x = 1."""
    ab = offset_table(offsets, pitch)                    # once, not per pulse
    for p in range(local.shape[0]):
        pulse_sub_rays(rot, local, p, ab, pitch, out, p)


@numba.njit(cache=True, nogil=True, inline="always")
def offset_table(offsets, pitch):                         # pragma: no cover - compiled
    """:func:`pulse_sub_rays`' table of the sub-rays' offsets, (m, 3): a beam's (pitch < 0)
    tan a, tan b and 1/√(1 + tan²a + tan²b), the length's inverse of d + tan a u + tan b v
    for orthonormal d, u, v; a flash pixel's offsets as they are (the third column 0)."""
    m = offsets.shape[0]
    ab = np.zeros((m, 3))
    for k in range(m):
        if pitch >= 0.0:
            ab[k, 0], ab[k, 1] = offsets[k, 0], offsets[k, 1]
        else:
            ab[k, 0], ab[k, 1] = math.tan(offsets[k, 0]), math.tan(offsets[k, 1])
            ab[k, 2] = 1.0 / math.sqrt(1.0 + ab[k, 0] * ab[k, 0] + ab[k, 1] * ab[k, 1])
    return ab


@numba.njit(cache=True, nogil=True, inline="always")
def pulse_sub_rays(rot, local, p, ab, pitch, out, q):     # pragma: no cover - compiled
    """out[q, k] = rot[p] @ (pulse p's sub-ray k in the sensor frame), normalised
    (:func:`world_sub_rays`; ``ab`` :func:`offset_table`'s; indices, not array views, in
    the hot loop). The pulse's frame d, u, v is turned once, each sub-ray is then
    D + a U + b V: a beam's scaled by its table's 1/length (d normalised here, u and v
    orthonormal to it), a flash pixel's normalised itself. Either is a unit vector to a
    few ulp (the sub-ray's direction, not its length, differs from normalising rot @ s
    after the turn by ~1e-16)."""
    dx, dy, dz = local[p, 0], local[p, 1], local[p, 2]
    if pitch >= 0.0:
        ux, uy, uz = 0.0, pitch, 0.0
        vx, vy, vz = 0.0, 0.0, pitch
        dx, dy, dz = 1.0, dy / local[p, 0], dz / local[p, 0]
    else:
        nd = 1.0 / math.sqrt(dx * dx + dy * dy + dz * dz)
        dx, dy, dz = dx * nd, dy * nd, dz * nd
        # u = ref × d normalised, v = d × u (ref = z unless d is near z)
        if abs(dz) < 0.9:
            ux, uy, uz = -dy, dx, 0.0
        else:
            ux, uy, uz = dz, 0.0, -dx
        nu = math.sqrt(ux * ux + uy * uy + uz * uz)
        ux, uy, uz = ux / nu, uy / nu, uz / nu
        vx, vy, vz = dy * uz - dz * uy, dz * ux - dx * uz, dx * uy - dy * ux
    d0, d1, d2 = _turn(rot, p, dx, dy, dz)
    u0, u1, u2 = _turn(rot, p, ux, uy, uz)
    v0, v1, v2 = _turn(rot, p, vx, vy, vz)
    for k in range(ab.shape[0]):
        a, b = ab[k, 0], ab[k, 1]
        s0 = d0 + a * u0 + b * v0
        s1 = d1 + a * u1 + b * v1
        s2 = d2 + a * u2 + b * v2
        inv = ab[k, 2] if pitch < 0.0 else 1.0 / math.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
        out[q, k, 0] = inv * s0
        out[q, k, 1] = inv * s1
        out[q, k, 2] = inv * s2


@numba.njit(cache=True, nogil=True, inline="always")
def _turn(rot, p, x, y, z):                               # pragma: no cover - compiled
    """rot[p] @ (x, y, z)."""
    return (rot[p, 0, 0] * x + rot[p, 0, 1] * y + rot[p, 0, 2] * z,
            rot[p, 1, 0] * x + rot[p, 1, 1] * y + rot[p, 1, 2] * z,
            rot[p, 2, 0] * x + rot[p, 2, 1] * y + rot[p, 2, 2] * z)


@numba.njit(cache=True, nogil=True)
def pack_rays(origins, dirs, o32, d32):                   # pragma: no cover - compiled
    """The cast's float32 rays: o32[p m + k] = origins[p], d32[p m + k] = dirs[p, k]."""
    n, m = dirs.shape[0], dirs.shape[1]
    for p in range(n):
        for k in range(m):
            for j in range(3):
                o32[p * m + k, j] = origins[p, j]
                d32[p * m + k, j] = dirs[p, k, j]


@numba.njit(cache=True, nogil=True)
def refine_hits(prim, tfar, origins, dirs, normals, plane_d, min_cos, center, face, dist,
                cos, points):                             # pragma: no cover - compiled
    """Per sub-ray (flat index i = p m + k): the hit face (−1 on a miss), the float64
    distance from the float64 origin (shifted by ``center``) to its plane, |n·d|, and
    the hit point, (shifted origin + t d) + center."""
    n, m = dirs.shape[0], dirs.shape[1]
    for p in range(n):
        for k in range(m):
            i = p * m + k
            refine_hit(prim[i], np.float64(tfar[i]), origins[p, 0], origins[p, 1],
                       origins[p, 2], dirs[p, k, 0], dirs[p, k, 1], dirs[p, k, 2], normals,
                       plane_d, min_cos, center, face, dist, cos, points, p, k)


@numba.njit(cache=True, nogil=True, inline="always")
def refine_hit(f, tf, o0, o1, o2, d0, d1, d2, normals, plane_d, min_cos, center, face, dist,
               cos, points, p, k):                        # pragma: no cover - compiled
    """:func:`refine_hits` of one sub-ray (p, k) from origin o along d (scalars: no array
    views in the hot loop): face f (−1: a miss), Embree's distance tf (kept where
    |n·d| ≤ ``min_cos``). A hit at :data:`MIN_RANGE` or nearer (a surface through the
    sensor's origin) cannot be ranged: it is a miss, and the sub-ray ends there."""
    face[p, k] = f
    if f < 0:
        dist[p, k] = np.inf
        cos[p, k] = 0.0
        points[p, k, 0] = points[p, k, 1] = points[p, k, 2] = np.nan
        return
    den = normals[f, 0] * d0 + normals[f, 1] * d1 + normals[f, 2] * d2
    if abs(den) > min_cos:
        num = plane_d[f] - (normals[f, 0] * o0 + normals[f, 1] * o1 + normals[f, 2] * o2)
        t = num / den
    else:
        t = tf
    if t > MIN_RANGE:
        dist[p, k] = t
        cos[p, k] = abs(den)
        points[p, k, 0] = (o0 + t * d0) + center[0]
        points[p, k, 1] = (o1 + t * d1) + center[1]
        points[p, k, 2] = (o2 + t * d2) + center[2]
    else:                                # a surface through the origin: not ranged
        face[p, k] = -1
        dist[p, k] = np.inf
        cos[p, k] = 0.0
        points[p, k, 0] = points[p, k, 1] = points[p, k, 2] = np.nan


@numba.njit(cache=True, nogil=True)
def assign_truth(first, count, ret_time, reach, tau, pe, distance, points, face, shift,
                 true_range, true_xyz, true_face, doppler):   # pragma: no cover - compiled
    """Each return's photoelectron-weighted true range, point and Doppler ``shift`` (0 where
    ``shift`` has no rows), and the face of its strongest sub-ray, from the lit sub-rays
    whose echo lies nearest it in time and within its reach of it: ``reach`` = (each
    return's, s; each pulse's further reach for a return earlier than the echo, s: a
    first-photon detector's walk). A return no sub-ray's echo reaches (a false alarm of the
    noise) has none (NaN, face −1)."""
    reach, walk = reach
    n, m = tau.shape
    n_ret = ret_time.shape[0]
    total = np.zeros(n_ret)
    best = np.zeros(n_ret)
    for p in range(n):
        c = count[p]
        if c == 0:
            continue
        for k in range(m):
            e = pe[p, k]
            if e <= 0.0:
                continue
            r = first[p]
            gap = abs(ret_time[r] - tau[p, k])
            for q in range(first[p] + 1, first[p] + c):
                g = abs(ret_time[q] - tau[p, k])
                if g < gap:
                    gap, r = g, q
            if gap > reach[r] + (walk[p] if ret_time[r] < tau[p, k] else 0.0):
                continue
            total[r] += e
            true_range[r] += e * distance[p, k]
            if shift.shape[0]:                   # (none: nothing moves)
                doppler[r] += e * shift[p, k]
            for j in range(3):
                true_xyz[r, j] += e * points[p, k, j]
            if e > best[r]:
                best[r] = e
                true_face[r] = face[p, k]
    for r in range(n_ret):
        if total[r] > 0.0:
            true_range[r] /= total[r]
            doppler[r] /= total[r]
            for j in range(3):
                true_xyz[r, j] /= total[r]
        else:
            true_range[r] = np.nan
            true_xyz[r, 0] = true_xyz[r, 1] = true_xyz[r, 2] = np.nan


@numba.njit(cache=True, nogil=True)
def discrete_returns(tau, pe, gap, level, max_returns, out_p, out_t, out_e, out_w):
    """Per pulse, its lit sub-rays grouped in time (a new group where the next arrival is
    more than ``gap`` after the last), each group at or above ``level`` photoelectrons a
    return at its photoelectron-weighted time with its photoelectrons and RMS spread, the
    strongest ``max_returns`` kept. Returns how many. A pulse whose lit sub-rays all
    arrive within ``gap`` of its first is one group (index order)."""  # pragma: no cover
    n, m = tau.shape
    count = 0
    gt = np.empty(m)
    ge = np.empty(m)
    gs = np.empty(m)
    order = np.empty(m, np.int64)
    rank = np.empty(m, np.int64)
    lit = np.empty(m)
    for p in range(n):
        lo, hi = np.inf, -np.inf
        for k in range(m):
            if pe[p, k] > 0.0:
                lo, hi = min(lo, tau[p, k]), max(hi, tau[p, k])
        if hi < lo:                                  # nothing lit
            continue
        if hi - lo <= gap:                           # one group
            g = 0
            gt[0] = ge[0] = gs[0] = 0.0
            for k in range(m):
                e = pe[p, k]
                if e > 0.0:
                    t = tau[p, k]
                    gt[0] += e * t
                    ge[0] += e
                    gs[0] += e * t * t
        else:
            g = _groups(tau, pe, p, gap, lit, order, gt, ge, gs)
        for r in range(g + 1):
            lit[r] = -ge[r]
        sort_small(lit[:g + 1], rank[:g + 1])        # strongest first, ties in time order
        kept = 0
        for r in rank[:g + 1]:
            if kept == max_returns or ge[r] < level:
                break
            mean = gt[r] / ge[r]
            out_p[count] = p
            out_t[count] = mean
            out_e[count] = ge[r]
            out_w[count] = math.sqrt(max(gs[r] / ge[r] - mean * mean, 0.0))
            count += 1
            kept += 1
    return count


@numba.njit(cache=True, nogil=True)
def _groups(tau, pe, p, gap, lit, order, gt, ge, gs):      # pragma: no cover - compiled
    """:func:`discrete_returns`' groups of pulse p in time order (their sums into gt, ge,
    gs); returns the last group's index."""
    m = tau.shape[1]
    for k in range(m):
        lit[k] = tau[p, k]
    sort_small(lit, order)
    g = -1
    prev = -np.inf
    for o in order:
        e = pe[p, o]
        if e <= 0.0:
            continue
        t = tau[p, o]
        if g < 0 or t - prev > gap:
            g += 1
            gt[g] = 0.0
            ge[g] = 0.0
            gs[g] = 0.0
        gt[g] += e * t
        ge[g] += e
        gs[g] += e * t * t
        prev = t
    return g
