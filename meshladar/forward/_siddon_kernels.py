"""The Siddon projector's compiled loops (numba): exact traversal of a pixel grid, forward
projection, backprojection and first hits (moved here from the dissolved ``_kernels.py``:
each compiled loop lives beside its stage). Cached on disk (``cache=True``)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ..precision import SIDDON_NUDGE as _NUDGE

__all__ = ["siddon_project", "siddon_backproject", "siddon_backproject_parallel",
           "siddon_first_hits", "siddon_first_hits_serial"]


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
    """out[m] = Σ_pixels length(ray m ∩ pixel) · image[pixel] (line integrals).

    Parameters
    ----------
    image : (ny, nx) float64, C-contiguous
        Pixel values; row i along y.
    ox, oy, dx, dy : (n,) float64
        The rays' origins and unit directions; each ray's whole line through the grid is
        walked (α < 0 too).
    xmin, ymin : float
        The grid's lower-left corner.
    pix : float
        The pixels' side, > 0.
    out : (n,) float64
        Filled with the line integrals (rays in parallel).
    """
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
    sum, hence the rounding, is fixed by the number of parts).

    Parameters
    ----------
    values : (n,) float64
        One value per ray.
    ox, oy, dx, dy : (n,) float64
        The rays' origins and unit directions; each ray's whole line through the grid is
        walked (α < 0 too).
    xmin, ymin : float
        The grid's lower-left corner.
    pix : float
        The pixels' side, > 0.
    parts : (n_parts, ny, nx) float64, C-contiguous
        Added to (zero it first): block k of the rays goes into ``parts[k]``.
    """
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
    siddon_project (serial: rays scatter into shared pixels).

    Parameters
    ----------
    values : (n,) float64
        One value per ray.
    ox, oy, dx, dy : (n,) float64
        The rays' origins and unit directions; each ray's whole line through the grid is
        walked (α < 0 too).
    xmin, ymin : float
        The grid's lower-left corner.
    pix : float
        The pixels' side, > 0.
    out : (ny, nx) float64, C-contiguous
        Added to.
    """
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
    traversal (−1 and nan where the ray meets none); rays in parallel.

    Parameters
    ----------
    mask : (ny, nx) float64, C-contiguous
        > 0 on the filled pixels.
    ox, oy, dx, dy : (n,) float64
        The rays' origins and unit directions; each ray's whole line through the grid is
        walked (α < 0 too).
    xmin, ymin : float
        The grid's lower-left corner.
    pix : float
        The pixels' side, > 0.
    hit_pixel : (n,) int64
        Filled with the flat (row-major) index of each ray's first filled pixel, or −1.
    hit_alpha : (n,) float64
        Filled with α at the middle of the ray's path through that pixel, or NaN.
    """
    ny, nx = mask.shape
    flat = mask.ravel()
    for m in prange(ox.size):
        _first_hit(m, flat, ox, oy, dx, dy, xmin, ymin, pix, nx, ny, hit_pixel, hit_alpha)


@njit(cache=True)
def siddon_first_hits_serial(mask, ox, oy, dx, dy, xmin, ymin, pix, hit_pixel, hit_alpha):
    """``siddon_first_hits`` on one thread (in a worker process, see
    :func:`meshladar.stream.in_worker`).

    Parameters
    ----------
    mask, ox, oy, dx, dy, xmin, ymin, pix, hit_pixel, hit_alpha
        As ``siddon_first_hits``.
    """
    ny, nx = mask.shape
    flat = mask.ravel()
    for m in range(ox.size):
        _first_hit(m, flat, ox, oy, dx, dy, xmin, ymin, pix, nx, ny, hit_pixel, hit_alpha)
