"""3-D reflective tomography: volumes from range profiles over the sphere of views, and from
elevation-resolved returns by stacking 2-D FBP slices.

A range profile of view w is a set of plane integrals: bin k holds the return of the surface
between the planes −p·w = r_k and r_{k+1}. Divided by the bin width it samples the 3-D
Radon transform g(w, s) = ∫ f δ(s − x·w) dx of the surface's return density f at s = −r.
The 3-D inversion formula is local:

    f(x) = −1/(8π²) ∫_{S²} ∂²g/∂s² (w, x·w) dw,

so :func:`fbp3d` takes each profile's second difference (the three-point stencil, exact on
quadratics: a uniform ball's g = π(a² − s²) gives −g'' = 2π inside, and the ball back),
and backprojects over the views with quadrature weights (4π/n each for the Fibonacci
directions of ``meshladar.meshes.fibonacci_sphere``; a solid-angle Voronoi weight otherwise).
A uniform ball of value 1 reconstructs to 1 inside (tests/reconstruct/test_volumes.py).

:func:`fbp_slices` reconstructs from returns resolved in elevation and range for views about
the z axis (:func:`meshladar.forward.resolved.resolve`): each elevation row, per unit height, is a
2-D sinogram of that slice, reconstructed by :func:`meshladar.fbp`.

``radon3d`` and ``fbp_stack`` are the old names of :func:`fbp3d` and :func:`fbp_slices`
(``radon3d`` named the transform it inverts): deprecated aliases for one release.
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple
import warnings

import numpy as np

from .._lazy import deferred_module
from .._validate import (check_count, check_real, check_sinogram, check_size, check_weights,
                         finite_array)
from ..errors import MeshladarWarning, ParameterError, user_stacklevel
from ..images import Volume
from ..meshes import fibonacci_sphere
from ..returns import Returns
from ..sinogram import Sinogram
from .fbp2d import EXTENT_RANGE, bins_across, bins_reach, fbp

# compiled loops, imported (with numba) at their first use: a small run loads neither
_kernels = deferred_module("meshladar.reconstruct._kernels")

__all__ = ["Volume", "fbp3d", "fbp_slices", "sphere_weights", "coverage_gap_deg",
           "views_needed", "MAX_GAP_DEG", "UNDERSAMPLED_FACTOR", "radon3d", "fbp_stack"]


#: fbp3d refuses view sets that leave a direction farther than this from every view (a
#: cap unseen: the inversion formula needs the whole sphere of directions).
MAX_GAP_DEG = 30.0
#: fbp3d warns when its views are more than this many times fewer than the fully sampled
#: count π N²/4 (:func:`views_needed`): their spacing is then over 4 times the full
#: sampling's, where 2-D fbp warns too (below a quarter of its π/2 views per bin across;
#: streaks of a quarter of the peak and more).
UNDERSAMPLED_FACTOR = 16.0


def views_needed(n_across, smooth=0.0) -> int:
    """Views over the sphere that sample the angles at the bins' resolution: π N²/4 for a
    target whose returns span N bins (N / max(1, σ) for a smoothing of σ bins).

    As 2-D FBP's π/2 views per bin across, a spacing Δθ between neighbouring directions
    with R Δθ = 2 Δr at the target's radius R = N Δr/2 (a plane at R moves two bins between
    neighbouring views), so Δθ = 4/N; views with that spacing cover the sphere's 4π in
    4π/Δθ² = π N²/4 (about 1,800 for 48 bins across, 12,900 for 128).

    Parameters
    ----------
    n_across : float
        N, the most bins any view's returns span (first to last non-zero bin). Not
        checked.
    smooth : float, default 0.0
        σ, the Gaussian smoothing of the profiles in bins (as :func:`fbp3d`'s); below 1 it
        changes nothing. Not checked.

    Returns
    -------
    int
        The view count ceil(π n² / 4), with n = N / max(1, σ).
    """
    n = float(n_across) / max(1.0, float(smooth))
    return int(math.ceil(math.pi * n * n / 4.0))


def coverage_gap_deg(view_vectors) -> float:
    """The largest angle (degrees) from any direction of the sphere to the nearest view
    (estimated on 2e4 Fibonacci directions): small for views spread over the sphere, 90 for
    a hemisphere or a plane of views.

    Parameters
    ----------
    view_vectors : (n_views, 3) array_like
        Unit view directions (not normalised here: the chord-to-angle conversion assumes
        unit length).

    Returns
    -------
    float
        The angle in degrees, in [0, 180], from the probe direction farthest from every
        view to its nearest view.

    Raises
    ------
    ParameterError
        When ``view_vectors`` is not a finite (n, 3) array with n >= 1.
    """
    from scipy.spatial import cKDTree        # scipy.spatial: only where it is used (startup)

    w = _view_vectors(view_vectors)
    chord, _ = cKDTree(w).query(fibonacci_sphere(20_000))
    return float(np.degrees(2 * np.arcsin(min(1.0, chord.max() / 2))))


def _view_vectors(value):
    """``value`` as a finite (n, 3) float64 array of view directions, n >= 1 (checked before
    scipy's tree, whose own error names neither the argument nor the shape wanted)."""
    w = finite_array("view_vectors", value)
    if w.ndim != 2 or w.shape[1] != 3 or w.shape[0] < 1:
        raise ParameterError(f"view_vectors must be an (n, 3) array of view directions, "
                             f"n >= 1; got shape {w.shape}")
    return w


def _view_weights(weights, n):
    """The views' solid angles: ``weights`` checked (finite, one per view, ≥ 0, not all
    0), or 4π/n each."""
    if weights is None:
        return np.full(n, 4 * math.pi / n)
    wts = check_weights(weights, (n,), expected=f"{n} solid angles >= 0, shape ({n},) (one "
                        "per view)", sign="solid angles >= 0 (one per view)",
                        zero="every view is dropped and the volume would be 0; give each "
                             "view's solid angle (> 0 for some), e.g. "
                             "sphere_weights(sino.view_vectors)")
    return wts


def _check_view_sampling(sino, smooth):
    """``smooth`` checked (at most the profile's length: 1e6 bins of kernel ran for
    minutes), and a warning when the views are too few over the sphere for the bins across
    the target; returns ``smooth``."""
    smooth = check_real("smooth", smooth, low=0.0, high=float(sino.n_bins))
    across = bins_across(sino)
    need = views_needed(across, smooth)
    if across and sino.n_views * UNDERSAMPLED_FACTOR < need:
        warnings.warn(
            f"{sino.n_views} views are too few over the sphere for the {across} bins across "
            f"the target's returns (smooth={smooth:g}): fbp3d samples the directions fully "
            f"with about {need} (pi N^2/4, N bins across / max(1, smooth)); expect the "
            "planes of sharp returns to streak the volume: use more views, a larger smooth "
            "or wider bins", MeshladarWarning, stacklevel=user_stacklevel())
    return smooth


def sphere_weights(view_vectors) -> np.ndarray:
    """Quadrature weights over the sphere for view directions covering it: each view's
    share of 4π by nearest direction (a spherical Voronoi cell estimated on 2e5 Fibonacci
    points). Views that leave part of the sphere unseen get its area too: right only for
    sets that cover the sphere (:func:`coverage_gap_deg`).

    Parameters
    ----------
    view_vectors : (n_views, 3) array_like
        Unit view directions (not normalised here).

    Returns
    -------
    (n_views,) ndarray of float64
        Each view's solid angle, steradians: 4π / 2e5 times the number of probe points
        nearest to it (they sum to 4π).

    Raises
    ------
    ParameterError
        When ``view_vectors`` is not a finite (n, 3) array with n >= 1.
    """
    from scipy.spatial import cKDTree        # scipy.spatial: only where it is used (startup)

    w = _view_vectors(view_vectors)
    probe = fibonacci_sphere(200_000)
    _, owner = cKDTree(w).query(probe)
    return np.bincount(owner, minlength=len(w)) * (4 * math.pi / probe.shape[0])


class _VolumeGrid(NamedTuple):
    """A cubic voxel grid: n voxels a side, half-width e, centre c (3,) and the voxel
    centres along x, y and z."""

    n: int
    e: float
    c: np.ndarray
    centers: tuple


def _grid(size, extent, center):
    n = check_count("size", size)
    e = check_real("extent", extent, low=EXTENT_RANGE[0], high=EXTENT_RANGE[1])
    c = finite_array("center", center)
    if c.shape != (3,):
        raise ParameterError(f"center must be a point (x, y, z); got shape {c.shape}")
    base = -e + (np.arange(n) + 0.5) * (2 * e / n)
    return _VolumeGrid(n, e, c, (base + c[0], base + c[1], base + c[2]))


def fbp3d(sino, *, size=128, extent=None, center=(0.0, 0.0, 0.0), weights=None,
            smooth=0.0) -> Volume:
    """Invert range profiles over the sphere of views (3-D Radon inversion, module
    docstring).

    Parameters
    ----------
    sino : Sinogram
        Range profiles with ``view_vectors`` spread over the whole sphere (the inversion
        formula integrates over all directions; a view set leaving a cap of more than
        ``MAX_GAP_DEG`` unseen is refused) and uniform bin widths.
    size : int
        Voxels per side (default 128).
    extent : float, optional
        Half-width of the cube. Default: the bins' reach max(|r_0|, |r_n|)
        (:func:`~meshladar.reconstruct.fbp2d.bins_reach`), the cube about the origin that
        holds everything the bins see, as :func:`meshladar.fbp`'s square; the command
        line's ``reconstruct`` uses the same.
    center : (3,) float
        The cube's centre.
    weights : (n_views,) array, optional
        Quadrature weight (solid angle) of each view; default 4π/n for n views, right for
        Fibonacci directions (:func:`sphere_weights` for other sets covering the sphere).
    smooth : float in [0, n_bins]
        Standard deviation (in bins) of a Gaussian applied to each profile before its
        second difference (default 0: none). The second difference amplifies sampling noise
        and few views leave the planes of sharp returns uncancelled: 1-2 bins trade
        resolution for a cleaner volume.

    Returns
    -------
    Volume
        The surface's return density (per unit volume): values integrate, over a thin shell
        around the surface, to its return per unit area. ``values[k, i, j]`` (size, size,
        size) at (x[j], y[i], z[k]), the voxel centres.

    Raises
    ------
    ParameterError
        When ``sino`` is not a :class:`~meshladar.Sinogram`; its bins are not uniform (to
        1e-6 of their mean width) or fewer than 3; its views leave a direction more than
        ``MAX_GAP_DEG`` (30°) from every view; ``size`` is not an integer >= 1 or a
        ``size``³ volume (16 bytes a voxel) would pass meshladar's 4 GiB allocation limit;
        ``extent`` is outside [1e-150, 1e300]; ``center`` is not a finite (3,) point;
        ``weights`` are not n_views finite values ≥ 0 or are all 0 (the message names the
        shape, or the first negative value and its index); or ``smooth`` is outside [0,
        n_bins].

    Warns
    -----
    MeshladarWarning
        When the views are more than ``UNDERSAMPLED_FACTOR`` (16) times fewer than
        :func:`views_needed`, π N²/4 for returns N bins across (N / max(1, ``smooth``)):
        neighbouring directions over 4 times farther apart than the bins resolve, 4/N.

    References
    ----------
    F. Natterer, *The Mathematics of Computerized Tomography*, Wiley (1986), Ch. II (the
    inversion formula of the Radon transform; its local form in three dimensions).
    """
    check_sinogram("sino", sino)
    wts = _view_weights(weights, sino.n_views)
    dr = _check_views_and_bins(sino)
    grid = _grid(size, bins_reach(sino) if extent is None else extent, center)
    n, (x, y, z) = grid.n, grid.centers
    check_size("size", float(n) ** 3, 8 * 2, f"a {n}^3 volume", "give a smaller size")
    smooth = _check_view_sampling(sino, smooth)
    q = _second_differences(sino, dr, smooth)
    out = np.zeros((n, n, n))
    w = sino.view_vectors
    _kernels.backproject3d(q, np.ascontiguousarray(w[:, 0]), np.ascontiguousarray(w[:, 1]),
                           np.ascontiguousarray(w[:, 2]), wts, float(sino.bin_centers[0]),
                           1.0 / dr, x, y, z, out)
    return Volume(out, x=x, y=y, z=z, info=_fbp3d_info(sino, smooth, grid))


def _check_views_and_bins(sino):
    """The bin width of a sinogram :func:`fbp3d` can invert: a
    :class:`~meshladar.Sinogram` with at least 3 uniform bins (to 1e-6 of their mean width)
    and views leaving no direction more than :data:`MAX_GAP_DEG` from them all."""
    check_sinogram("sino", sino)
    widths = np.diff(sino.bin_edges)
    if np.ptp(widths) > 1e-6 * widths.mean():
        raise ParameterError("fbp3d needs uniform range bins")
    if sino.n_bins < 3:
        raise ParameterError(f"fbp3d needs at least 3 range bins; got {sino.n_bins}")
    dr = float(widths.mean())
    gap = coverage_gap_deg(sino.view_vectors)
    if gap > MAX_GAP_DEG:
        raise ParameterError(
            f"fbp3d needs views over the whole sphere of directions; these leave a "
            f"direction {gap:.0f} deg from every view (at most {MAX_GAP_DEG:g}): use views "
            "such as meshladar.meshes.fibonacci_sphere(n) (views about the z axis: fbp, or "
            "fbp_slices of elevation-resolved returns)")
    return dr


def _second_differences(sino, dr, smooth):
    """The profiles' −∂²g/∂s² / (8π²), g = values / ``dr`` smoothed by a Gaussian of
    ``smooth`` bins (when > 0), by the three-point stencil with zeros beyond the bins:
    what :func:`fbp3d` backprojects."""
    from scipy.ndimage import gaussian_filter1d   # only where it is used (startup)

    g = sino.values / dr
    if smooth > 0:
        g = gaussian_filter1d(g, smooth, axis=1, mode="constant", truncate=4.0)
    g = np.pad(g, ((0, 0), (1, 1)))                             # zero beyond the bins
    minus_g2 = -(g[:, 2:] - 2 * g[:, 1:-1] + g[:, :-2]) / (dr * dr)
    return np.ascontiguousarray(minus_g2 / (8 * math.pi ** 2))


def _fbp3d_info(sino, smooth, grid):
    """The ``info`` of :func:`fbp3d`'s volume: the method, its smoothing, the views, the
    data's radiometry and preprocessing, and the voxel grid."""
    info = {"method": "fbp3d", "filter": "second difference", "smooth_bins": smooth,
            "views": sino.n_views,
            "radiometry": sino.radiometry, "size": grid.n, "extent": grid.e,
            "center": grid.c.tolist()}
    if sino.info.get("preprocess"):
        info["preprocess"] = sino.info["preprocess"]
    return info


def fbp_slices(returns, *, size=256, extent=None, filter="ramp") -> Volume:
    """Slices from returns resolved in elevation and range (views about the z axis): each
    elevation row per unit height is a 2-D sinogram, reconstructed by FBP; the slices stack
    at the elevation bins' centres.

    Parameters
    ----------
    returns : meshladar.returns.Returns
        With axes ("elevation", "range") (either order) and views about the z axis.
    size, extent, filter : int >= 1, float or None, str
        As :func:`meshladar.fbp`, per slice (extent by default the range bins' reach);
        keyword-only, defaults 256, None and "ramp". The slices are centred on the z
        axis.

    Returns
    -------
    Volume
        ``values[k, i, j]`` (n_elevation, size, size) the FBP of elevation row k at
        (x[j], y[i], z[k]), z the elevation bins' centres; each row's values are divided
        by its elevation bin height before FBP, so the volume is a density per unit
        volume. ``info``: method "fbp_stack", filter, views, radiometry, slices and, when
        the returns record one, preprocess.

    Raises
    ------
    ParameterError
        When ``returns`` is not a :class:`~meshladar.returns.Returns` resolved in
        ("elevation", "range"), has a view off the x-y plane or unevenly spaced elevation
        bins; and as :func:`meshladar.fbp` for each slice.

    Warns
    -----
    MeshladarWarning
        As :func:`meshladar.fbp`, for each slice.
    """
    if not isinstance(returns, Returns) or set(returns.axes) != {"elevation", "range"}:
        raise ParameterError("fbp_slices needs Returns resolved in ('elevation', 'range')")
    if np.any(returns.view_vectors[:, 2] != 0):
        raise ParameterError("fbp_slices needs views about the z axis (elevation is z)")
    vals = returns.values
    if returns.axes[0] == "range":
        vals = np.swapaxes(vals, 1, 2)                  # (views, elevation, range)
    el = returns.edges[returns.axes.index("elevation")]
    rng = returns.edges[returns.axes.index("range")]
    if np.ptp(np.diff(el)) > 1e-9 * np.diff(el).mean():
        raise ParameterError("fbp_slices needs evenly spaced elevation bins (the volume's z "
                             "axis)")
    extent = bins_reach(rng) if extent is None else extent
    slices = []
    for k in range(el.size - 1):
        s = Sinogram(vals[:, k, :] / (el[k + 1] - el[k]), angles_deg=returns.angles_deg,
                     bin_edges=rng, model="mesh", info=returns.info)
        slices.append(fbp(s, size=size, extent=extent, filter=filter))
    first = slices[0]
    info = {"method": "fbp_stack", "filter": filter, "views": vals.shape[0],
            "radiometry": returns.info.get("radiometry"), "slices": el.size - 1}
    if returns.info.get("preprocess"):
        info["preprocess"] = returns.info["preprocess"]
    return Volume(np.stack([s.values for s in slices]), x=first.x, y=first.y,
                  z=0.5 * (el[1:] + el[:-1]), info=info)


def _renamed(new, old):
    """``new`` under its old name ``old``, warning that the name is deprecated."""
    @functools.wraps(new)
    def alias(*args, **kwargs):
        warnings.warn(f"meshladar {old} is deprecated (one release): use "
                      f"meshladar.reconstruct.{new.__name__}", DeprecationWarning, stacklevel=user_stacklevel())
        return new(*args, **kwargs)

    alias.__name__ = alias.__qualname__ = old
    alias.__doc__ = (f"Deprecated alias of :func:`{new.__name__}` (one release).\n\n"
                     "Parameters\n----------\n*args, **kwargs\n"
                     f"    Passed to :func:`{new.__name__}` unchanged.\n\n"
                     "Returns\n-------\nVolume\n"
                     f"    What :func:`{new.__name__}` returns.\n\n"
                     "Warns\n-----\nDeprecationWarning\n    On every call.\n")
    return alias


#: Deprecated alias of :func:`fbp3d` (one release).
radon3d = _renamed(fbp3d, "radon3d")
#: Deprecated alias of :func:`fbp_slices` (one release).
fbp_stack = _renamed(fbp_slices, "fbp_stack")
