"""Iterative reconstruction on the projectors of :mod:`meshladar.reconstruct.operators`: SIRT,
SART and CGLS, with non-negativity, per-bin weights, a mask, a warm start from FBP, a
stopping rule and progress.

The data model is FBP's: a sinogram's ``values / bin_width`` are line integrals
of the image along the iso-range lines −p·w = r. A projector
(:class:`~meshladar.reconstruct.operators.RangeProjector`, Siddon's exact pixel lengths;
:class:`~meshladar.reconstruct.operators.LinearProjector`, the pixel-driven pair) is that
operator A on a pixel grid with its exact adjoint Aᵀ, so ``A @ image`` is directly
comparable with ``sino.values``. By default (``projector="auto"``) the solvers use the
linear pair where the bins are uniform (about 20× faster at 256²) and Siddon's where they are not.

``sirt`` solves min ‖W^½ (A x − b)‖ (Landweber with SIRT's row and column scaling, so each
step is a weighted average that needs no step size), ``cgls`` the same least-squares
problem by conjugate gradients (its residual never grows). Weights W ≥ 0 per bin let a user
down-weight glint bins or shadow-gapped views instead of clipping them; 0 drops a bin.

Each solver here checks its arguments and sets up its problem (the private ``_problem``:
the checks the solvers share, the grid, projector, data, weights, mask and start), then
runs its iterations (the private ``_iterations``: each method's loop and record).

The solvers are invariant to the data's scale: they run on the values divided by the power
of two 2^k nearest below the largest value the weights keep, and multiply the image back,
so data of any magnitude (tested from 1e-300 to 1e300) gives the unit-scale run's image
times the scale (exactly for a power of two, to round-off otherwise) and the same
residuals, without underflow or overflow; an image beyond float64's range is refused.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .._validate import check_choice, check_count, check_real, check_sinogram
from ..errors import ParameterError
from ._iterations import _cgls, _fista, _sart, _sirt
from ._problem import _Run, _run, _setup, _Start
from ._tv import MAX_TV
from .fbp2d import default_extent
from .operators import PROJECTORS, LinearProjector, RangeProjector
from .radiance import PAPER_CLIP, noise_floor

__all__ = ["RangeProjector", "LinearProjector", "sirt", "sart", "cgls", "tv_fista",
           "glint_weights", "ImageGrid", "METHODS", "PROJECTORS"]

#: The iterative methods of this module.
METHODS = ("sirt", "sart", "cgls", "tv_fista")


class ImageGrid(NamedTuple):
    """The square image grid of a reconstruction: ``size`` pixels a side, half-width
    ``extent``, centred on ``center`` (as :func:`meshladar.fbp`).

    Attributes
    ----------
    size : int
        Pixels along each side.
    extent : float
        Half-width of the square, scene units.
    center : tuple
        Centre (x, y) of the square.
    """

    size: int
    extent: float
    center: tuple


def sirt(sino, size=256, extent=None, *, center=(0.0, 0.0), n_iter=50, x0=None, weights=None,
         mask=None, nonneg=True, tol=None, rays_per_bin=2, projector="auto",
         progress=False):
    """SIRT: x ← x + C Aᵀ W R (b − A x), R and C the inverse row and column sums of A
    (weighted by W), projected onto x ≥ 0 (``nonneg``) and the mask.

    Parameters
    ----------
    sino : Sinogram
        Views about z; ``values`` bin integrals (any radiometry, log or clipped input).
    size, extent, center : int >= 1, float or None, (2,) float
        The image grid, as :func:`meshladar.fbp` (defaults 256; None: the bins' reach,
        :func:`~meshladar.reconstruct.fbp2d.bins_reach`; (0, 0)). ``extent`` in
        [1e-150, 1e300]; ``center`` keyword-only.
    n_iter : int >= 1, default 50
        Most iterations.
    x0 : None, "fbp", Image or (size, size) array
        Warm start (default zeros); an Image's values are taken as they are (its grid is
        not compared). "fbp": FBP of the data the weights keep, the dropped
        bins (weight 0) set to 0: a dropped glint is then not in the start either (from
        all the data its bright ring stays, as only the dropped bins could lower it).
    weights : (n_views, n_bins) array, optional
        Per-bin weights ≥ 0 (glint bins down-weighted, 0 drops a bin); relative: only their
        ratios matter (they are scaled so that the largest is 1).
    mask : (size, size) bool array, optional
        Pixels allowed to be non-zero (the start is masked too).
    nonneg : bool, default True
        Project onto x ≥ 0 after each step.
    tol : float > 0, optional
        Stop when the weighted residual falls by less than ``tol`` (relative) in a step.
    rays_per_bin : int >= 1, default 2
        Iso-range lines per bin in the Siddon projector.
    projector : {"auto", "siddon", "linear"} or operator, default "auto"
        Siddon lines with exact pixel lengths (:class:`RangeProjector`, any bins), the
        pixel-driven linear-interpolation pair (:class:`LinearProjector`, uniform bins;
        about 20× faster at 256², the same image error), or any operator with ``@``,
        ``.T`` and a ``grid`` equal to the image's (e.g.
        :class:`meshladar.reconstruct.operators.SurfaceProjector`). "auto" (default):
        "linear" where the bins are uniform, "siddon" where not
        (:func:`~meshladar.reconstruct.operators.projector_name`).
    progress : bool, default False
        A progress bar over the iterations (on a terminal).

    Returns
    -------
    Image
        ``info``: method, iterations, ``residuals`` (weighted ‖A x − b‖ per iteration,
        relative to the weighted ‖b‖), stopped ("n_iter" or "tol"), projector (the pair
        used, or the operator's class name), nonneg, rays_per_bin, radiometry. Scaling the
        data by 2^k scales the image by 2^k exactly and leaves the residuals as they are
        (module docstring).

    Raises
    ------
    ParameterError
        When ``sino`` is not a :class:`~meshladar.Sinogram` or has views off the x-y
        plane; ``size`` is not an integer >= 1 or its images (about 64 bytes a pixel)
        would pass meshladar's 4 GiB allocation limit; ``extent`` is outside [1e-150,
        1e300]; ``n_iter`` is not an integer >= 1, or ``rays_per_bin`` where the Siddon
        projector is built; ``tol`` is not > 0; ``weights`` are not finite, one per bin
        and ≥ 0 (the first negative named, with its index), or are all 0; ``mask`` is not
        (size, size) or is empty; the image would pass float64's range; ``x0`` is not
        None, "fbp", an Image or a finite (size, size) array; or ``projector`` is neither
        a name above nor an operator with ``@``, ``.T`` and a matching ``grid`` (the
        linear pair also refuses non-uniform bins).

    References
    ----------
    A. C. Kak and M. Slaney, *Principles of Computerized Tomographic Imaging*, IEEE Press
    (1988), Ch. 7 (algebraic reconstruction); J. Gregor and T. Benson, "Computational
    analysis and improvement of SIRT", IEEE Trans. Med. Imaging 27 (2008) (SIRT with the
    inverse row and column sums).
    """
    extent = default_extent(sino, extent)
    run = _run(n_iter, tol, progress, rays_per_bin, projector)
    pr = _setup(sino, ImageGrid(size, extent, center), _Start(x0, weights, mask, nonneg), run)
    return _sirt(sino, pr, run, nonneg)


def sart(sino, size=256, extent=None, *, center=(0.0, 0.0), n_iter=10, subsets=None,
         relax=1.0, x0=None, weights=None, mask=None, nonneg=True, tol=None, rays_per_bin=2,
         projector="auto", progress=False):
    """SART in ordered subsets (OS-SART, as ASTRA's and TIGRE's): each iteration sweeps the
    views in ``subsets`` interleaved groups, and after each group takes SIRT's scaled step
    on that group alone (x ← x + λ C_s A_sᵀ W_s R_s (b_s − A_s x), then x ≥ 0 and the mask).
    One sweep costs what one SIRT iteration costs and, with s groups, moves about as far as
    s SIRT iterations. ``subsets`` defaults to one group per 36 views (10 for 360 views;
    ``subsets=n_views`` is classic one-view SART); ``relax`` is λ in (0, 2). Other
    parameters and ``info`` as :func:`sirt`; ``residuals`` are gathered over each sweep
    (each group's residual just before its step, as ordered-subset methods report it, at
    no extra projection).

    Group k holds views k, k + s, k + 2s, ... in the sinogram's order, and the groups are
    swept in the order k = 0, 1, ..., s − 1 every iteration.

    Parameters
    ----------
    sino : Sinogram
        Views about z; ``values`` bin integrals (any radiometry, log or clipped input).
    size, extent, center : int >= 1, float or None, (2,) float
        The image grid, as :func:`sirt` (defaults 256, the bins' reach, (0, 0)).
    n_iter : int >= 1, default 10
        Most sweeps over all the groups.
    subsets : int in [1, n_views], optional
        Number of groups s; default max(1, n_views // 36).
    relax : float in (0, 2), default 1.0
        Relaxation λ multiplying each group's step.
    x0 : None, "fbp", Image or (size, size) array, default None
        Warm start, as :func:`sirt` (default zeros).
    weights : (n_views, n_bins) array, optional
        Per-bin weights ≥ 0, relative, as :func:`sirt`.
    mask : (size, size) bool array, optional
        Pixels allowed to be non-zero, as :func:`sirt`.
    nonneg : bool, default True
        Project onto x ≥ 0 after each step.
    tol : float > 0, optional
        Relative stopping tolerance, as :func:`sirt`.
    rays_per_bin : int >= 1, default 2
        Iso-range lines per bin in the Siddon projector.
    projector : {"auto", "siddon", "linear"}, default "auto"
        The projector pair, built once per group; unlike :func:`sirt`, an operator is
        refused.
    progress : bool, default False
        A progress bar over the sweeps (on a terminal).

    Returns
    -------
    Image
        ``info`` as :func:`sirt`'s, with method "sart", subsets and relax; ``residuals``
        per sweep, relative to the weighted ‖b‖.

    Raises
    ------
    ParameterError
        As :func:`sirt`; also when ``relax`` is outside (0, 2), ``subsets`` is not an
        integer in [1, n_views], or ``projector`` is not one of the names above.

    References
    ----------
    A. H. Andersen and A. C. Kak, "Simultaneous algebraic reconstruction technique
    (SART): a superior implementation of the ART algorithm", Ultrasonic Imaging 6 (1984).
    """
    extent = default_extent(sino, extent)
    run = _run(n_iter, tol, progress, rays_per_bin, projector)
    relax = check_real("relax", relax, low=0.0, high=2.0, low_open=True, high_open=True)
    if not isinstance(projector, str):
        raise ParameterError("sart builds one projector per group of views: give projector "
                             f"as one of {('auto',) + PROJECTORS}")
    check_choice("projector", projector, ("auto",) + PROJECTORS)
    pr = _setup(sino, ImageGrid(size, extent, center), _Start(x0, weights, mask, nonneg), run,
                build_projector=False)                    # one projector per group of views
    return _sart(sino, pr, run, subsets, relax, nonneg)


def cgls(sino, size=256, extent=None, *, center=(0.0, 0.0), n_iter=30, x0=None, weights=None,
         mask=None, tol=None, rays_per_bin=2, projector="auto", progress=False):
    """CGLS: conjugate gradients on the normal equations of min ‖W^½ (A x − b)‖ over the
    masked pixels (no non-negativity: CG's residual then never grows). Parameters as
    :func:`sirt`; ``info["residuals"]`` is non-increasing.

    Parameters
    ----------
    sino : Sinogram
        Views about z; ``values`` bin integrals (any radiometry, log or clipped input).
    size, extent, center : int >= 1, float or None, (2,) float
        The image grid, as :func:`sirt` (defaults 256, the bins' reach, (0, 0)).
    n_iter : int >= 1, default 30
        Most iterations.
    x0 : None, "fbp", Image or (size, size) array
        Warm start, as :func:`sirt` (default zeros); masked, and not clipped to x ≥ 0.
    weights : (n_views, n_bins) array, optional
        Per-bin weights ≥ 0, relative, as :func:`sirt`.
    mask : (size, size) bool array, optional
        Pixels allowed to be non-zero, as :func:`sirt`.
    tol : float > 0, optional
        Relative stopping tolerance, as :func:`sirt`.
    rays_per_bin : int >= 1, default 2
        Iso-range lines per bin in the Siddon projector.
    projector : {"auto", "siddon", "linear"} or operator, default "auto"
        The projector, as :func:`sirt`.
    progress : bool, default False
        A progress bar over the iterations (on a terminal).

    Returns
    -------
    Image
        ``info``: method "cgls", iterations, residuals (weighted ‖A x − b‖ per iteration,
        relative to the weighted ‖b‖), stopped ("n_iter", "tol", or "converged" when the
        masked gradient is 0 or the search direction projects to 0), projector,
        rays_per_bin, radiometry.

    Raises
    ------
    ParameterError
        As :func:`sirt`.

    References
    ----------
    M. R. Hestenes and E. Stiefel, "Methods of conjugate gradients for solving linear
    systems", J. Res. Natl. Bur. Stand. 49 (1952); Å. Björck, *Numerical Methods for
    Least Squares Problems*, SIAM (1996) (CGLS).
    """
    extent = default_extent(sino, extent)
    run = _run(n_iter, tol, progress, rays_per_bin, projector)
    pr = _setup(sino, ImageGrid(size, extent, center), _Start(x0, weights, mask, False), run)
    return _cgls(sino, pr, run)


def glint_weights(sino, *, threshold=None, floor=0.0, max_share=0.1):
    """Per-bin weights that drop (or down-weight to ``floor``) the bins brighter than
    ``threshold`` × the sinogram's maximum (default the paper's clip level, 0.008): a
    glint's few bright bins then stop hiding the diffuse parts, without clipping the data
    the other bins fit. For :func:`sirt`, :func:`cgls` and :func:`tv_fista` (their warm
    start ``x0="fbp"`` leaves the dropped bins out too).

    A glint is a few bins: only when the bright bins are at most ``max_share`` of the bins
    that hold returns (above the noise floor) are they dropped; otherwise the scene does
    not glint and every weight is 1 (measured at 1° views: 2-4 % on the paper's glinting
    pairs, 42-45 % on the diffuse disk and the gray pair).

    The bins that hold returns are those above min(``threshold``, the noise floor) × the
    maximum (:func:`~meshladar.reconstruct.fbp2d.noise_floor`).

    Parameters
    ----------
    sino : Sinogram
        The data.
    threshold : float in (0, 1], keyword-only, optional
        Bins above ``threshold`` × the maximum value are bright; default
        :data:`~meshladar.reconstruct.fbp2d.PAPER_CLIP` (0.008).
    floor : float in [0, 1], keyword-only, default 0.0
        The weight of a bright bin (0 drops it).
    max_share : float in [0, 1], keyword-only, default 0.1
        The largest share of the returning bins that may be bright for them to be
        down-weighted.

    Returns
    -------
    (n_views, n_bins) ndarray of float64
        ``floor`` at the bright bins and 1 elsewhere, or 1 everywhere when the bright bins
        are more than ``max_share`` of the returning ones.

    Raises
    ------
    ParameterError
        When ``sino`` is not a :class:`~meshladar.Sinogram`, or ``threshold``, ``floor``
        or ``max_share`` is outside its range.

    References
    ----------
    Jin & Levine (2009), Sec. 4.B, Fig. 11(b) (the default threshold, 0.008 of the
    maximum).
    """
    check_sinogram("sino", sino)
    thr = check_real("threshold", PAPER_CLIP if threshold is None else threshold, low=0.0,
                     high=1.0, low_open=True)
    floor = check_real("floor", floor, low=0.0, high=1.0)
    max_share = check_real("max_share", max_share, low=0.0, high=1.0)
    v = sino.values
    peak = float(v.max(initial=0.0))
    bright = v > thr * peak
    returning = v > min(thr, noise_floor(sino)) * peak
    if bright.sum() > max_share * max(1, returning.sum()):
        return np.ones_like(v)
    return np.where(bright, floor, 1.0)


def tv_fista(sino, size=256, extent=None, *, center=(0.0, 0.0), tv=0.005, n_iter=100,
             x0="fbp", weights=None, mask=None, nonneg=True, tol=None, rays_per_bin=2,
             projector="auto", progress=False):
    """Total-variation regularised reconstruction by FISTA:
    min ½‖W^½ (A x − b)‖² + λ TV(x) over x ≥ 0 and the mask, each step a gradient step on
    the data term (step 1/L, L = ‖W^½ A‖² by power iteration) and the TV proximal map
    (isotropic TV, Beck and Teboulle's fast gradient projection on the dual, 20 inner
    steps, warm-started from the previous step's dual).

    ``tv`` sets λ relative to the image's scale: λ = tv · L · s with s the 99th percentile
    of |FBP image| of the data the weights keep (dropped bins at 0), so each step smooths
    away jumps below about tv × s (the default 0.005: half a per cent of the image's
    level; on an exact disk sinogram at 10° view spacing
    the error is then 0.092, below FBP's 0.104 at 1°). Other parameters as :func:`sirt`
    (default warm start from FBP). ``info["residuals"]`` holds the data term,
    ``info["objective"]`` the whole objective per iteration relative to ½‖W^½ b‖² (its value
    at x = 0, so that, like the residuals, it does not change with the data's scale;
    monotone only on average: FISTA is not a descent method).

    L is estimated by 15 power iterations on M Aᵀ W A M from a seeded random start
    (``numpy.random.default_rng(0)``), so runs repeat exactly. TV is the sum over pixels
    of the length of the forward-difference gradient (differences zero at the last row
    and column). With ``tol``, the run stops when the objective, not the residual,
    changes by less than ``tol`` (relative) in a step.

    Parameters
    ----------
    sino : Sinogram
        Views about z; ``values`` bin integrals (any radiometry, log or clipped input).
    size, extent, center : int >= 1, float or None, (2,) float
        The image grid, as :func:`sirt` (defaults 256, the bins' reach, (0, 0)).
    tv : float in [0, 100], keyword-only, default 0.005
        The regularisation relative to the image's scale (above); 0: FISTA on the data
        term alone, with the constraints.
    n_iter : int >= 1, default 100
        Most iterations.
    x0 : None, "fbp", Image or (size, size) array, default "fbp"
        Warm start, as :func:`sirt`.
    weights : (n_views, n_bins) array, optional
        Per-bin weights ≥ 0, relative, as :func:`sirt`.
    mask : (size, size) bool array, optional
        Pixels allowed to be non-zero, as :func:`sirt`.
    nonneg : bool, default True
        Keep x ≥ 0 (a constraint of the TV proximal map, and of the start).
    tol : float > 0, optional
        Stop when the objective changes by less than ``tol`` (relative) in a step.
    rays_per_bin : int >= 1, default 2
        Iso-range lines per bin in the Siddon projector.
    projector : {"auto", "siddon", "linear"} or operator, default "auto"
        The projector, as :func:`sirt`.
    progress : bool, default False
        A progress bar over the iterations (on a terminal).

    Returns
    -------
    Image
        ``info``: method "tv_fista", tv, lambda (λ, in the data's units), lipschitz (L),
        iterations, residuals (weighted ‖A x − b‖ relative to the weighted ‖b‖, per
        iteration), objective (relative to ½‖W^½ b‖²), stopped ("n_iter" or "tol"), nonneg,
        projector, radiometry.

    Raises
    ------
    ParameterError
        As :func:`sirt`; also when ``tv`` is outside [0, 100].

    References
    ----------
    A. Beck and M. Teboulle, "A fast iterative shrinkage-thresholding algorithm for linear
    inverse problems", SIAM J. Imaging Sci. 2 (2009) (FISTA); A. Beck and M. Teboulle,
    "Fast gradient-based algorithms for constrained total variation image denoising and
    deblurring problems", IEEE Trans. Image Process. 18 (2009) (the TV proximal map).
    """
    extent = default_extent(sino, extent)
    n_iter = check_count("n_iter", n_iter)
    tv = check_real("tv", tv, low=0.0, high=MAX_TV)
    tol = None if tol is None else check_real("tol", tol, low=0.0, low_open=True)
    run = _Run(n_iter, tol, progress, rays_per_bin, projector)
    pr = _setup(sino, ImageGrid(size, extent, center), _Start(x0, weights, mask, nonneg), run)
    return _fista(sino, pr, run, tv, nonneg)
