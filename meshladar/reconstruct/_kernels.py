"""The compiled loops of reconstruction (numba): 2-D and 3-D backprojection, its exact
transpose (splat), and the surface-segment projector pair with its shadow map.

numba is imported here, at the top; ``import meshladar`` stays numpy/scipy only because the
package reaches this module lazily (its name table). Kernels are cached on disk
(``cache=True``), so the JIT cost is paid once per installation.

Why numba: filtered backprojection of 360 × 1024 onto 1024² is 3.8e8 interpolations; numpy
spends ~10 passes over memory on each; a compiled, cache-friendly loop parallel over image
rows does not.
"""

from __future__ import annotations

import math

from numba import njit, prange

__all__ = ["backproject", "backproject3d", "splat_project", "surface_project",
           "surface_backproject", "surface_shadows"]


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
