"""The compiled loops of reconstruction (numba): 2-D and 3-D backprojection, its exact
transpose (splat), and the surface-segment projector pair with its shadow map.

numba is imported here, at the top; ``import meshladar`` stays numpy/scipy only because the
package reaches this module lazily (its name table). Kernels are cached on disk
(``cache=True``), so the JIT cost is paid once per installation.

Why numba: filtered backprojection of 360 × 1024 onto 1024² is 3.8e8 interpolations; numpy
spends ~10 passes over memory on each; a compiled, cache-friendly loop parallel over image
rows does not, and with the in-range columns of each row found first its inner loop has no
branch and runs in SIMD registers (gathers of the filtered samples).
"""

from __future__ import annotations

import math

import numpy as np
from numba import carray, njit, prange, types
from numba.core import cgutils
from numba.extending import intrinsic

__all__ = ["backproject", "backproject3d", "splat_project", "surface_project",
           "surface_backproject", "surface_shadows"]


#: Columns of an image row that :func:`backproject` accumulates at a time in a buffer on
#: the stack (8 KiB of float64: it stays in the L1 cache with the view's samples).
_CHUNK = 1024


def _stack_buffer(size):
    """A compiled helper returning a pointer to ``size`` float64 on its caller's stack (one
    alloca in the entry block). The backprojection accumulates a row there rather than in
    ``out``: LLVM then knows the stores cannot alias the samples it gathers from ``q`` and
    vectorises the loop (with ``out`` it may not, and leaves it scalar). The loops that
    write the buffer are inlined into its owner by numba (``inline="always"``) so that
    LLVM sees where it comes from; the other helpers are not (inlining them too tripled
    the first compile: 12 s instead of 4, for no measurable speed)."""
    @intrinsic
    def buffer(typingctx):
        def codegen(context, builder, signature, args):
            return cgutils.alloca_once(builder, context.get_value_type(types.float64),
                                       size=size)
        return types.CPointer(types.float64)(), codegen
    return buffer


_row_buffer = _stack_buffer(_CHUNK)


@njit(parallel=True, cache=True, fastmath=False)
def backproject(q, cos_phi, sin_phi, weight, r0, inv_dr, x, y, nearest, out):
    """out[i, j] += Σ_v weight[v] · q_v(r), r = −(x_j cos φ_v + y_i sin φ_v).

    q : (n_views, n_bins) samples at r0 + k/inv_dr; linear (or nearest-sample) interpolation,
    0 outside [r0, r0 + (n_bins − 1)/inv_dr].

    Each sample is u = (−y_i sin φ − r0)·inv_dr + x_j·(−cos φ·inv_dr), interpolated as
    q[k] + (u − k)(q[k+1] − q[k]) with k = ⌊u⌋ (nearest: q[⌊u + ½⌋], halves rounding up),
    and the views are added to ``out[i, j]`` in order: the same operations in the same
    order as a plain per-pixel loop, so the result is bit for bit that loop's. For speed,
    with x non-decreasing (pixel centres) u is monotone along a row, so the columns whose u
    falls in the bins are found per row and view (:func:`_span`), and the loop over them
    has no branch and vectorises (gathers of q); linear views go two at a time over the
    columns both cover. Other x take the plain loop.
    """
    ny, nx = y.size, x.size
    if q.shape[1] == 0:
        return
    ordered = True
    for j in range(nx - 1):
        if not x[j] <= x[j + 1]:
            ordered = False
    for i in prange(ny):
        if not ordered:
            for v in range(q.shape[0]):
                _add_view_scalar(out[i], 0, nx, q, v, weight[v],
                                 (-y[i] * sin_phi[v] - r0) * inv_dr, -cos_phi[v] * inv_dr,
                                 x, nearest)
            continue
        for c0 in range(0, nx, _CHUNK):
            _backproject_row(q, cos_phi, sin_phi, weight, r0, inv_dr, x, y[i], nearest,
                             out[i], c0, min(nx, c0 + _CHUNK))


@njit(cache=True)
def _backproject_row(q, cos_phi, sin_phi, weight, r0, inv_dr, x, yi, nearest, row, c0, c1):
    """Every view's contribution to row[c0:c1] (the row at y = yi), accumulated on the
    stack: views whose samples are not all finite pixel by pixel, nearest views one at a
    time, linear views in pairs."""
    acc = carray(_row_buffer(), (_CHUNK,))
    n_views, n_bins = q.shape
    m = c1 - c0
    src = row[c0:c1]
    for j in range(m):
        acc[j] = src[j]
    v = 0
    while v < n_views:
        wv, base, step = _view_line(cos_phi, sin_phi, weight, r0, inv_dr, yi, v)
        if not _finite_ends(x, c0, c1, base, step):
            _add_view_scalar(acc, c0, c1, q, v, wv, base, step, x, nearest)
            v += 1
            continue
        if nearest:
            ja, jb = _span(x, c0, c1, base, step, 0.5, float(n_bins))
            _add_nearest(acc, c0, q, v, wv, base, step, x, ja, jb)
            v += 1
            continue
        ja, jb = _span(x, c0, c1, base, step, 0.0, float(n_bins - 1))
        w1, base1, step1, ka, kb = 0.0, 0.0, 0.0, 0, 0
        pair = v + 1 < n_views
        if pair:
            w1, base1, step1 = _view_line(cos_phi, sin_phi, weight, r0, inv_dr, yi, v + 1)
            pair = _finite_ends(x, c0, c1, base1, step1)
        lo, hi = ja, ja                      # the columns both views cover
        if pair:
            ka, kb = _span(x, c0, c1, base1, step1, 0.0, float(n_bins - 1))
            lo = max(ja, ka)
            hi = max(lo, min(jb, kb))
        # per pixel the views still add in order: v outside [lo, hi), then both in it,
        # then v + 1 outside it (a pixel exactly on the last bin is outside both spans)
        _add_linear(acc, c0, q, v, wv, base, step, x, ja, min(jb, lo))
        _add_linear(acc, c0, q, v, wv, base, step, x, max(ja, hi), jb)
        _add_last_bin(acc, c0, c1, q, v, wv, base, step, x, ja, jb)
        if not pair:
            v += 1
            continue
        _add_linear_pair(acc, c0, q, v, wv, base, step, w1, base1, step1, x, lo, hi)
        _add_linear(acc, c0, q, v + 1, w1, base1, step1, x, ka, min(kb, lo))
        _add_linear(acc, c0, q, v + 1, w1, base1, step1, x, max(ka, hi), kb)
        _add_last_bin(acc, c0, c1, q, v + 1, w1, base1, step1, x, ka, kb)
        v += 2
    dst = row[c0:c1]
    for j in range(m):
        dst[j] = acc[j]


@njit(cache=True)
def _view_line(cos_phi, sin_phi, weight, r0, inv_dr, yi, v):
    """(weight, base, step) of view v on the row at yi: sample u_j = base + x_j·step."""
    return weight[v], (-yi * sin_phi[v] - r0) * inv_dr, -cos_phi[v] * inv_dr


@njit(cache=True)
def _finite_ends(x, c0, c1, base, step):
    """True when u is finite at both ends of columns [c0, c1), hence (x ordered) all of
    them."""
    return math.isfinite(base + x[c0] * step) and math.isfinite(base + x[c1 - 1] * step)


@njit(cache=True)
def _past(x, j, base, step, h, t, up):
    """Whether column j's u + h has reached t: u_j + h >= t going up (step >= 0),
    u_j + h < t going down. Monotone in j: false, then true."""
    s = (base + x[j] * step) + h
    return s >= t if up else s < t


@njit(cache=True)
def _first(x, lo, hi, base, step, h, t):
    """The first column j in [lo, hi) that is :func:`_past` t (hi when none), with u
    evaluated exactly as the sampling loops do: a guess from u's ends, then steps."""
    up = step >= 0.0
    if lo >= hi or _past(x, lo, base, step, h, t, up):
        return lo
    if not _past(x, hi - 1, base, step, h, t, up):
        return hi
    u_lo = base + x[lo] * step
    frac = (t - h - u_lo) / ((base + x[hi - 1] * step) - u_lo)
    if not 0.0 <= frac <= 1.0:
        frac = 0.5
    j = min(max(lo + int(frac * (hi - 1 - lo)), lo + 1), hi - 1)
    while j > lo + 1 and _past(x, j - 1, base, step, h, t, up):
        j -= 1
    while not _past(x, j, base, step, h, t, up):
        j += 1
    return j


@njit(cache=True)
def _span(x, c0, c1, base, step, h, top):
    """(ja, jb): the columns [ja, jb) of [c0, c1) with 0 <= u + h < top (u monotone)."""
    if step >= 0.0:
        ja = _first(x, c0, c1, base, step, h, 0.0)
        return ja, _first(x, ja, c1, base, step, h, top)
    ja = _first(x, c0, c1, base, step, h, top)
    return ja, _first(x, ja, c1, base, step, h, 0.0)


@njit(cache=True, inline="always")
def _add_linear(acc, c0, q, v, wv, base, step, x, ja, jb):
    """acc[j − c0] += wv·(linear sample of q_v at u_j) for j in [ja, jb), all inside
    0 <= u < n_bins − 1 (so k = trunc u = ⌊u⌋, no test: the loop vectorises)."""
    if jb <= ja:
        return
    a = acc[ja - c0:jb - c0]
    xs = x[ja:jb]
    one = np.uint64(1)
    for j in range(a.size):
        u = base + xs[j] * step
        k = np.uint64(u)
        f = u - np.float64(k)
        lo = q[v, k]
        a[j] += wv * (lo + f * (q[v, k + one] - lo))


@njit(cache=True, inline="always")
def _add_linear_pair(acc, c0, q, v, wv, base, step, w1, base1, step1, x, lo, hi):
    """:func:`_add_linear` of views v and then v + 1 over [lo, hi), which both cover, in
    one pass (x and acc loaded once)."""
    if hi <= lo:
        return
    a = acc[lo - c0:hi - c0]
    xs = x[lo:hi]
    one = np.uint64(1)
    v1 = v + 1
    for j in range(a.size):
        xj = xs[j]
        u = base + xj * step
        k = np.uint64(u)
        f = u - np.float64(k)
        u1 = base1 + xj * step1
        k1 = np.uint64(u1)
        f1 = u1 - np.float64(k1)
        s0 = q[v, k]
        s1 = q[v1, k1]
        s = a[j] + wv * (s0 + f * (q[v, k + one] - s0))
        a[j] = s + w1 * (s1 + f1 * (q[v1, k1 + one] - s1))


@njit(cache=True)
def _add_last_bin(acc, c0, c1, q, v, wv, base, step, x, ja, jb):
    """The columns next to the span [ja, jb) whose u is exactly the last sample n_bins − 1
    (the linear span stops just before it): they take q_v's last sample."""
    n_bins = q.shape[1]
    last = float(n_bins - 1)
    j, d = (jb, 1) if step >= 0.0 else (ja - 1, -1)
    while c0 <= j < c1 and base + x[j] * step == last:
        acc[j - c0] += wv * q[v, n_bins - 1]
        j += d


@njit(cache=True, inline="always")
def _add_nearest(acc, c0, q, v, wv, base, step, x, ja, jb):
    """acc[j − c0] += wv·q_v[⌊u_j + ½⌋] for j in [ja, jb), all inside 0 <= u + ½ < n_bins
    (trunc = floor there; halves round up)."""
    if jb <= ja:
        return
    a = acc[ja - c0:jb - c0]
    xs = x[ja:jb]
    for j in range(a.size):
        a[j] += wv * q[v, np.uint64((base + xs[j] * step) + 0.5)]


@njit(cache=True)
def _add_view_scalar(acc, c0, c1, q, v, wv, base, step, x, nearest):
    """View v's contribution to acc[j − c0], j in [c0, c1), pixel by pixel with the bounds
    tested on each (on u itself, before any conversion to an index, so a u that is not
    finite or too large for an integer adds nothing): for rows where u is not finite at
    both ends, and x that is not ordered."""
    n_bins = q.shape[1]
    for j in range(c0, c1):
        u = base + x[j] * step
        if nearest:
            g = u + 0.5
            if 0.0 <= g < n_bins:
                acc[j - c0] += wv * q[v, int(g)]
        elif 0.0 <= u < n_bins - 1:
            k = int(u)
            f = u - k
            acc[j - c0] += wv * (q[v, k] + f * (q[v, k + 1] - q[v, k]))
        elif u == n_bins - 1:
            acc[j - c0] += wv * q[v, n_bins - 1]


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
