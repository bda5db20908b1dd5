"""The problem an iterative solver of :mod:`meshladar.reconstruct.iterative` sets up from its
arguments, with the checks every solver shares: how it runs (iterations, stopping rule,
progress, projector), where it starts (warm start, per-bin weights, mask, non-negativity),
and the checked problem itself (the pixel grid, the projector A, the data b, the weights W,
the mask M and the start x). The iterations that solve it are in ``_iterations``.
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import numpy as np

from .._validate import (check_count, check_real, check_sinogram, check_size, check_weights,
                         finite_array)
from ..errors import ParameterError
from ..forward.siddon import PixelGrid
from ..images import Image
from .fbp2d import EXTENT_RANGE, quiet_fbp
from .operators import build


class _Run(NamedTuple):
    """How a solver runs: at most ``n_iter`` iterations, stopping when a step lowers the
    tracked value by less than ``tol`` relatively (None: never), a progress bar when
    ``progress``; the projector (a name or an operator) and the Siddon projector's lines
    per bin, as the caller gave them."""

    n_iter: int
    tol: object
    progress: bool
    rays_per_bin: object
    projector: object


def _run(n_iter, tol, progress, rays_per_bin, projector):
    """A :class:`_Run`, its ``n_iter`` (an integer >= 1) and ``tol`` (None or > 0) checked in
    that order."""
    n_iter = check_count("n_iter", n_iter)
    tol = None if tol is None else check_real("tol", tol, low=0.0, low_open=True)
    return _Run(n_iter, tol, progress, rays_per_bin, projector)


class _Start(NamedTuple):
    """Where a solver starts: the warm start ``x0``, the per-bin ``weights``, the ``mask``
    and whether the image is kept non-negative."""

    x0: object
    weights: object
    mask: object
    nonneg: bool


class _Problem(NamedTuple):
    """The solvers' problem: the image grid as the caller gave it (size, extent, center: the
    result's), its pixel grid, the projector A (None when not built), the data b, the
    weights W, the mask M and the start x, b and x at unit scale: the sinogram's values and
    the start divided by ``scale`` (:func:`_kept_at_unit_scale`: a power of two, exact), the
    result to be multiplied back; ``sino`` the sinogram with the values b."""

    image: tuple
    grid: PixelGrid
    A: object
    b: np.ndarray
    W: np.ndarray
    M: np.ndarray
    x: np.ndarray
    scale: float
    sino: object


def _setup(sino, image, start, run, build_projector=True):
    """The solvers' :class:`_Problem`. ``image`` an
    :class:`~meshladar.reconstruct.iterative.ImageGrid`, ``start`` a :class:`_Start`, ``run``
    a :class:`_Run` (its projector and lines per bin); ``build_projector`` False builds no
    operator (SART builds one per group of views)."""
    size, extent, center = image
    weights, mask, x0, nonneg = start.weights, start.mask, start.x0, start.nonneg
    check_sinogram("sino", sino)
    if not sino.planar:
        raise ParameterError("iterative reconstruction needs views about the z axis; this "
                             "sinogram has 3-D view vectors (reconstruct them with "
                             "meshladar.reconstruct.volumes.fbp3d)")
    size = check_count("size", size)
    # the solvers hold a few images and the projector's per-view tables: ~8 arrays a pixel
    check_size("size", float(size) ** 2, 8 * 8, f"a {size}² image", "give a smaller size")
    extent = check_real("extent", extent, low=EXTENT_RANGE[0], high=EXTENT_RANGE[1])
    grid = PixelGrid.square(size, extent, center)
    W = _weights(weights, sino.values)
    sino, scale = _kept_at_unit_scale(sino, W)
    b = sino.values
    M = np.ones((size, size)) if mask is None else np.asarray(mask, dtype=bool).astype(float)
    if M.shape != (size, size):
        raise ParameterError(f"mask must be a ({size}, {size}) array; got {M.shape}")
    if not np.any(M):
        raise ParameterError("mask is empty (no pixel is True): there is nothing to "
                             "reconstruct (mark the pixels the target may occupy)")
    A = build(run.projector, grid, sino, run.rays_per_bin) if build_projector else None
    x = _start(sino, x0, (size, extent, center), scale)
    x *= M
    if nonneg:
        x = np.maximum(x, 0.0)
    return _Problem(image, grid, A, b, W, M, x, scale, sino)


def _kept_at_unit_scale(sino, W):
    """(sinogram, scale): ``sino`` with the values the weights W keep (W > 0) divided by
    ``scale`` and the dropped bins at 0, ``scale`` the power of two 2^k that puts the
    largest kept |value| in [1, 2) (1 when they keep only zeros). Dividing by it is exact,
    and the solvers run on data of order 1 whatever its magnitude (1e-300 to 1e307), their
    products (W r², the normal equations) neither underflowing nor overflowing; a dropped
    bin (a glint of any size) sets neither the scale nor, at 0, anything else."""
    keep = W > 0
    peak = float(np.max(np.abs(sino.values[keep])))
    scale = math.ldexp(1.0, math.frexp(peak)[1] - 1) if peak > 0 else 1.0
    if scale == 1.0 and np.all(keep):
        return sino, scale
    b = np.zeros(sino.shape)
    b[keep] = sino.values[keep] / scale
    return dataclasses.replace(sino, values=b), scale


def _weights(weights, b):
    """The per-bin weights W, checked (finite, ≥ 0, one per bin, not all 0) and divided by
    their largest: relative, as every solver is invariant to their scale. None: all 1."""
    W = np.ones_like(b) if weights is None else check_weights(
        weights, b.shape, expected=f"one value >= 0 per bin, shape {b.shape} (n_views, n_bins)",
        sign=">= 0 (0 drops a bin)", zero="every bin is dropped, so there is no data to "
                                          "reconstruct from (keep some bins, weight > 0)")
    return W / W.max()


def _start(sino, x0, square, scale):
    """The warm start as a new (size, size) array at the data's unit scale (``sino`` holds
    the values the weights keep divided by ``scale``, the dropped bins at 0): zeros (``x0``
    None), FBP of ``sino`` on ``square`` (size, extent, center) for "fbp", or an Image's
    values or a finite array divided by ``scale``."""
    size, extent, center = square
    if x0 is None:
        x = np.zeros((size, size))
    elif isinstance(x0, str) and x0 == "fbp":      # the data the weights keep (dropped: 0)
        x = np.array(quiet_fbp(sino, size, extent, center=center))
    elif isinstance(x0, Image):
        x = np.array(x0.values) / scale
    else:
        x = np.array(finite_array("x0", x0)) / scale
    if x.shape != (size, size):
        raise ParameterError(f"x0 must be None, 'fbp', an Image or a ({size}, {size}) array")
    return x
