"""BRDF compensation: reconstruct the surface as if it returned light equally to every view.

A surface point's return depends on the view through its BRDF and its normal: the weight
h(θ) = F(θ; −θ) cos θ (``radiometry="paper"``, Eq. 8; times another cos θ for received
power) falls to 0 at glancing incidence, is 0 from behind, and is 0 where another surface
shadows it. FBP assumes every view sees every pixel equally, and the missing glancing and
hidden views are what darkens the inside of a reconstructed boundary (the paper's Sec. 4.A)
and draws the crossed shadow streaks (Sec. 4.B).

Compensation puts that view dependence into the projector instead:

1. a first reconstruction (default: FBP of the log radiance, where weak surfaces show next
   to glints) gives sub-pixel surface points and normals (Steger's ridge detector: across
   a bright thin ridge the Hessian's most negative eigenvector), turned outward by the
   data (the side from which the views see returns), then moved together along their
   normals by the offset (within ±1 bin) that fits the data best;
2. :func:`surface_weights` evaluates, per surface pixel and view, h(θ) / ⟨h⟩ (⟨h⟩ the mean
   of h over all directions in the plane), 0 from behind and, with ``shadows``, 0 where the
   ray to the ladar crosses another surface of the first reconstruction;
3. :class:`SurfaceProjector` projects those points as short straight segments with those
   weights, and :func:`compensate` solves for the image with it (CGLS or SIRT of
   :mod:`meshladar.reconstruct.iterative`), masked to the surface pixels.

The result is in FBP's units: a surface of line density 1 reads ⟨h⟩ per unit length, as a
reflector that returned its view-averaged power to every view would under FBP. The
coatings must be known (``material``: one BRDF, or several with a label image).
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from typing import NamedTuple

import numpy as np

from .._validate import check_choice, check_count, check_sinogram, finite_array
from ..errors import MeshladarWarning, ParameterError, user_stacklevel
from ._kernels import surface_backproject
from .fbp2d import _image_square, default_extent, fbp
from .iterative import ImageGrid, cgls, sirt
from .operators import SurfaceProjector
from .radiance import log_radiance, noise_floor
from .surface import (Surface, _checked_labels, _materials, _segments, _subset, _uniform,
                      estimate_surface, surface_weights)

__all__ = ["Surface", "estimate_surface", "surface_weights", "SurfaceProjector", "compensate",
           "first_image", "SOLVERS", "MAX_PIXEL_BINS", "needed_size"]

#: The widest pixel, in range-bin widths, at which the compensated surface keeps its level
#: and evenness. The surface is one pixel thick: around the b = 0.99 disk with the paper's
#: 512 bins, at 256² (2.5 bins a pixel) it sits half a bin outside the true circle and its
#: line density over ±2 bins is 12 % below ⟨h⟩ · 2πR and 8 % uneven (12° arcs); at 427²
#: (1.5 bins) 2 % and 1.4 %, at 512² 0.2 % and 4.5 % (the same at 256 bins and 1024).
MAX_PIXEL_BINS = 1.5


def needed_size(sino, extent=None):
    """The smallest image size whose pixels (2 ``extent`` / size) are at most
    :data:`MAX_PIXEL_BINS` of the sinogram's bin width wide.

    Parameters
    ----------
    sino : Sinogram
        The data; its bin width is the mean of ``bin_edges``' differences (scene units).
    extent : float, optional
        Half-width of the image square, scene units. Default: :func:`compensate`'s, the
        bins' reach max(|r_0|, |r_n|) (:func:`~meshladar.reconstruct.fbp2d.bins_reach`).

    Returns
    -------
    int
        The size ceil(2 ``extent`` / (:data:`MAX_PIXEL_BINS` × bin width) − 1e-9): 1e-9 keeps
        a quotient a rounding error above an integer at that integer (342 for the paper's
        512 bins of 0.8/256 at their reach 0.8; 427 at extent 1).

    Raises
    ------
    ParameterError
        When ``sino`` is not a :class:`~meshladar.Sinogram`.
    """
    extent = default_extent(sino, extent)
    width = float(np.mean(np.diff(sino.bin_edges)))
    return math.ceil(2.0 * float(extent) / (MAX_PIXEL_BINS * width) - 1e-9)


def _check_resolution(sino, size, extent):
    """Warn when the pixels are wider than :data:`MAX_PIXEL_BINS` bins."""
    need = needed_size(sino, extent)
    if size < need:
        width = float(np.mean(np.diff(sino.bin_edges)))
        warnings.warn(f"compensate at size={size} (extent={float(extent):g}) makes pixels "
                      f"{2.0 * float(extent) / size / width:.2f} range bins wide; the "
                      f"compensated surface needs at most {MAX_PIXEL_BINS:g} "
                      f"(below it comes out low and uneven): use size={need} or more",
                      MeshladarWarning, stacklevel=user_stacklevel())


def _backed(surface, H, sino, keep, share=0.5):
    """For the points ``keep``: whether at least ``share`` of their strong views (weight ≥
    ¼ of their largest) find returns in their bins (above the noise floor, or any count
    in counted data)."""
    sub = _subset(surface, keep)
    h = H[keep]
    strong = (h >= 0.25 * h.max(axis=1, keepdims=True)).astype(float)
    # any count backs a point (at one photoelectron expected per bin, 63 % of its bins
    # hold one); sparse noise counts do not line up along a point's sinusoid
    lit = (sino.values > noise_floor(sino, quanta=0.5) * float(np.abs(sino.values).max())
           ).astype(float)
    e0, inv_dr = _uniform(sino.bin_edges)
    phi = np.deg2rad(sino.angles_deg)
    hits = np.zeros(sub.rows.size)
    args = _segments(sub, strong)
    surface_backproject(lit, *args, np.cos(phi), np.sin(phi), e0, inv_dr, hits)
    return hits >= share * strong.sum(axis=1)


def first_image(sino, size, extent=None, center=(0.0, 0.0)):
    """The default first reconstruction: FBP of the log radiance, its floor at half a
    count (or above the noise) so weak surfaces next to glints show and noise does not
    (FBP's warnings are for FBP's own output, not for this intermediate: every
    :class:`~meshladar.errors.MeshladarWarning` it raises, not only the few-views one, is
    silenced).

    Parameters
    ----------
    sino : Sinogram
        The returns (not their log: it is taken here).
    size : int >= 1
        Pixels along each side of the square image.
    extent : float in [1e-150, 1e300], optional
        Half-width of the image square, scene units; default the bins' reach, as
        :func:`~meshladar.reconstruct.fbp2d.fbp`'s.
    center : (2,) float, default (0, 0)
        Centre of the image square.

    Returns
    -------
    Image
        :func:`~meshladar.reconstruct.fbp2d.fbp` of
        :func:`~meshladar.reconstruct.fbp2d.log_radiance` with the floor
        ``noise_floor(sino, quanta=0.5)``
        (:func:`~meshladar.reconstruct.fbp2d.noise_floor`) on the (size, size) grid.

    Raises
    ------
    ParameterError
        As :func:`~meshladar.reconstruct.fbp2d.log_radiance` and
        :func:`~meshladar.reconstruct.fbp2d.fbp` (``sino`` not a
        :class:`~meshladar.Sinogram`, a bad grid).
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MeshladarWarning)
        return fbp(log_radiance(sino, floor=noise_floor(sino, quanta=0.5)), size=size,
                   extent=extent, center=center)


def _seen(surface, H, sino):
    """(surface, H) kept to the points the data sees and backs. A point no view sees
    (hidden behind another surface in all its front views: an artefact inside a shape)
    carries no data, one seen only at glancing incidence (total weight under 5 % of the
    median point's) would take any value, and a point the data does not back (a noise
    ridge: its strong views' bins mostly empty) is not a surface."""
    total = H.sum(axis=1)
    seen = total > 0.05 * float(np.median(total[total > 0])) if total.any() else total > 0
    seen[seen] = _backed(surface, H, sino, seen)
    if not seen.any():
        raise ParameterError(
            "no surface point of the first reconstruction is seen and backed by the data in "
            f"the square extent={surface.extent:g} about center={tuple(surface.center)}: "
            "check that it holds the scene (default extent: the bins' reach), or give "
            "first= or a lower threshold")
    if not seen.all():
        surface = _subset(surface, seen)
        H = H[seen]
    return surface, H


def _shadowed_fraction(surface, sino):
    """The shadowed share of the front-facing point-views (0 without a shadow map)."""
    phi = np.deg2rad(sino.angles_deg)
    front = (surface.normals[:, :1] * np.cos(phi) + surface.normals[:, 1:] * np.sin(phi)) > 0
    return 0.0 if surface.shadowed is None else float(
        (surface.shadowed & front).sum() / max(1, front.sum()))


def _uniform_fit(A, m, b, W):
    """(x0, weighted residual) of the best uniform surface c·m."""
    Am = A @ m
    c = float(np.sum(W * Am * b)) / (float(np.sum(W * Am * Am)) or 1.0)
    return c * m, float(np.sum(W * (b - c * Am) ** 2))


class _Settled(NamedTuple):
    """:func:`_settle`'s answer: the shifted surface, its shift, its projector and the
    uniform start."""

    surface: Surface
    shift: float
    projector: SurfaceProjector
    x0: np.ndarray


def _settle(surface, sino, H, W, m, smooth):
    """Shift every surface point along its normal by the one offset in ±1 bin that lets a
    uniform surface fit the data best. A first reconstruction puts a thin surface at the
    centre of the bin its returns pile into, up to half a bin off (inward on a convex
    surface); the projector is exact, so that offset shows as a residual. Returns a
    :class:`_Settled` (surface, shift, projector, uniform start): the uniform start keeps the solvers from
    speckling along the surface, where neighbouring points share their ranges."""
    dr = float(np.mean(np.diff(sino.bin_edges)))
    best = None
    for shift in np.linspace(-1.0, 1.0, 9) * dr:
        s = dataclasses.replace(surface, points=surface.points + shift * surface.normals)
        A = SurfaceProjector(s, sino.angles_deg, sino.bin_edges, H, smooth)
        x0, res = _uniform_fit(A, m, sino.values, W)
        if best is None or res < best[0]:
            best = (res, _Settled(s, float(shift), A, x0))
    return best[1]


#: Solvers for :func:`compensate`.
SOLVERS = ("cgls", "sirt")


def _check_returns(sino):
    """A sinogram with returns to compensate: some value > 0 (a negated or log sinogram
    said only "first has no bright ridge")."""
    check_sinogram("sino", sino)
    if not np.any(sino.values > 0):
        raise ParameterError(f"sino has no positive return to compensate; its largest value "
                             f"is {float(sino.values.max()) + 0.0:.4g} (pass the returns themselves: "
                             "the log input of the first reconstruction is made inside)")


def compensate(sino, material, *, size=256, extent=None, center=(0.0, 0.0), first=None,
               labels=None, method="cgls", n_iter=30, weights=None, threshold=0.2, sigma=1.5,
               shadows=True, blur_deg=1.0, smooth=2.0, surface=None, tol=None, progress=False):
    """BRDF- and shadow-compensated reconstruction (see the module docstring).

    Parameters
    ----------
    sino : Sinogram
        Views about z, uniform bins; its ``info["radiometry"]`` picks h(θ).
    material : BRDF or sequence of BRDFs
        The coatings (with ``labels`` when several).
    size, extent, center : int >= 1, float in [1e-150, 1e300] or None, (2,) float
        The image grid, as :func:`~meshladar.reconstruct.fbp2d.fbp`'s (defaults 256, None:
        the bins' reach max(|r_0|, |r_n|), the square about the origin that holds all the
        bins see, in any units; and (0, 0)). Pixels at most :data:`MAX_PIXEL_BINS` (1.5)
        bins wide, or the one-pixel-thick surface comes out low and uneven (warned;
        :func:`needed_size`: 342 for the paper's 512 bins at their reach 0.8).
    first : Image, optional
        The first reconstruction on that grid (default :func:`first_image`).
    labels : (size, size) int array, optional
        Each pixel's index into ``material``; needed for several, checked whenever given.
    method : {"cgls", "sirt"}, default "cgls"
        The solver (:mod:`meshladar.reconstruct.iterative`), warm-started from the uniform
        surface that fits the data best (the multiple of the surface mask with the least
        weighted residual), masked to the surface pixels.
    n_iter : int >= 1, default 30
        Most iterations of the solver.
    weights : (n_views, n_bins) array, optional
        Per-bin data weights (e.g. :func:`~meshladar.reconstruct.iterative.glint_weights`).
    threshold, sigma, shadows : float, float, bool
        :func:`estimate_surface`'s (defaults 0.2, 1.5 pixels, True); unused with ``surface``.
    blur_deg : float in [0, 90], default 1.0
        Angular blur of h(θ), degrees, for the normals' uncertainty.
    smooth : float in [0, size], default 2.0
        Width, pixels, of the Gaussian along the surface that the solution is built from
        (x = S z, :class:`SurfaceProjector`): neighbouring surface points share their
        ranges in most views; without it (0) the solution speckles along the surface.
    surface : Surface, optional
        Use these surface pixels and normals instead of estimating them.
    tol, progress : float or None, bool
        As :func:`~meshladar.reconstruct.iterative.sirt` (defaults None and False).

    Returns
    -------
    Image
        (size, size) values, zero off the surface pixels. ``info``: the solver's
        (iterations, residuals, stopped, ...) with method "compensated", solver,
        radiometry, surface_pixels, shadowed_fraction (of front-facing point-views),
        blur_deg, shadows (whether a shadow map was used), surface_shift (the offset along
        the normals, scene units) and smooth.

    Raises
    ------
    ParameterError
        When ``sino`` is not a :class:`~meshladar.Sinogram`, holds no value > 0 or has
        non-uniform bins; before any work, when ``method``, ``size``, ``extent`` or
        ``center`` is invalid (as fbp's), a material is not a BRDF, or ``labels`` is
        missing for several materials or not a (size, size) image of whole numbers in [0,
        len(material)); when ``surface`` is not a
        :class:`~meshladar.reconstruct.surface.Surface` or not on the grid (size, extent,
        center); when no surface point is seen and backed by the data; and as
        :func:`estimate_surface`, :func:`surface_weights`, :class:`SurfaceProjector` and
        the solver for their arguments.

    Warns
    -----
    MeshladarWarning
        When ``size`` is below :func:`needed_size` (pixels wider than
        :data:`MAX_PIXEL_BINS` bins).

    References
    ----------
    Jin & Levine (2009), Eq. 8 (the view weight h(θ) = F(θ; −θ) cos θ), Sec. 4.A-4.B (the
    artefacts compensated). C. Steger, "An unbiased detector of curvilinear structures",
    IEEE Trans. Pattern Anal. Mach. Intell. 20 (1998) (the ridge detector of
    :func:`estimate_surface`).
    """
    return _compensated(sino, material, ImageGrid(size, extent, center),
                        _Surfacing(first, surface, threshold, sigma, shadows, labels, blur_deg),
                        _Solving(method, n_iter, weights, smooth, tol, progress))


class _Surfacing(NamedTuple):
    """How :func:`compensate` finds the surface and weighs its views: the ``surface`` given,
    or one estimated from ``first`` (None: :func:`first_image`) with ``threshold``,
    ``sigma`` and ``shadows``; the materials' ``labels`` and the blur ``blur_deg`` of
    h(θ)."""

    first: object
    surface: object
    threshold: object
    sigma: object
    shadows: bool
    labels: object
    blur_deg: object


class _Solving(NamedTuple):
    """How :func:`compensate` solves for the surface's values: the solver ``method``, at
    most ``n_iter`` iterations, the per-bin ``weights``, the smoothing ``smooth`` along the
    surface (pixels), ``tol`` and ``progress``."""

    method: object
    n_iter: object
    weights: object
    smooth: object
    tol: object
    progress: bool


def _compensated(sino, material, image, surfacing, solving):
    """:func:`compensate` on the image grid ``image`` (an
    :class:`~meshladar.reconstruct.iterative.ImageGrid`), its other arguments in a
    :class:`_Surfacing` and a :class:`_Solving`: the checks, the surface seen by the data
    and its view weights, the settled surface and its uniform start, the solve."""
    _check_returns(sino)
    method = check_choice("method", solving.method, SOLVERS)
    size = check_count("size", image.size)
    extent, c = _image_square(sino, image.extent, image.center)
    center = (float(c[0]), float(c[1]))
    mats = _materials(material)
    labels = _checked_labels(surfacing.labels, size, len(mats))
    radiometry = sino.radiometry or "paper"
    surface = _surface_on_grid(sino, ImageGrid(size, extent, center), surfacing)
    H = surface_weights(surface, sino.angles_deg, mats, labels=labels,
                        radiometry=radiometry, blur_deg=surfacing.blur_deg)
    surface, H = _seen(surface, H, sino)
    _check_resolution(sino, size, extent)
    weights = solving.weights
    W = np.ones(sino.shape) if weights is None else finite_array("weights", weights)
    m = surface.mask.astype(float)
    settled = _settle(surface, sino, H, W, m, solving.smooth)
    surface, shift, A, x0 = settled.surface, settled.shift, settled.projector, settled.x0
    solve = cgls if method == "cgls" else sirt
    img = solve(sino, size=size, extent=extent, center=center, n_iter=solving.n_iter, x0=x0,
                weights=weights, mask=surface.mask, projector=A, tol=solving.tol,
                progress=solving.progress)
    values = np.array(img.values)
    if A.smooth is not None:                          # the solution is x = S z
        values[surface.rows, surface.cols] = A.smooth @ values[surface.rows, surface.cols]
    info = dict(img.info, method="compensated", solver=method, radiometry=radiometry,
                surface_pixels=int(surface.rows.size),
                shadowed_fraction=_shadowed_fraction(surface, sino),
                blur_deg=surfacing.blur_deg, shadows=surface.shadowed is not None,
                surface_shift=shift, smooth=solving.smooth)
    return type(img)(values, img.extent, img.center, info=info)


def _surface_on_grid(sino, image, surfacing):
    """The surface given, or estimated from the first reconstruction (by default
    :func:`first_image` on ``image``); refused unless a
    :class:`~meshladar.reconstruct.surface.Surface` on that grid."""
    size, extent, center = image
    surface, first = surfacing.surface, surfacing.first
    if surface is None:
        if first is None:
            first = first_image(sino, size, extent, center)
        surface = estimate_surface(first, sino, threshold=surfacing.threshold,
                                   sigma=surfacing.sigma, shadows=surfacing.shadows)
    elif not isinstance(surface, Surface):
        raise ParameterError(f"surface must be a meshladar.reconstruct.surface.Surface; got "
                             f"{type(surface).__name__}")
    if (surface.size, surface.extent, tuple(surface.center)) != (size, extent, center):
        raise ParameterError(f"surface must be on the image grid (size, extent, center) = "
                             f"({size}, {extent:g}, {center}); got ({surface.size}, "
                             f"{surface.extent:g}, {tuple(surface.center)})")
    return surface
