"""Coatings from ladar data: fit BRDF parameters of chosen parts to a measured sinogram,
the geometry known (a :class:`~meshladar.fit.kernels.CoatingKernel`), with uncertainties
and an identifiability report.

:func:`fit_coatings` minimises the misfit over the free parameters within bounds: least
squares (``noise="gaussian"``, σ estimated from the residuals) or the Poisson or speckle
(negative binomial, M cells) likelihood of photoelectron counts, by iteratively reweighted
least squares (the score equations Σ (d − m)/V(m) ∂m/∂p = 0 are the maximum-likelihood ones
for V(m) = m and V(m) = m + m²/M). The covariance is the inverse Fisher information
(Jᵀ V⁻¹ J)⁻¹, optionally checked by a parametric bootstrap; the report names the
parameters the data cannot determine (no effect on the data, or an uncertainty beyond
their range, or a near-perfect correlation with another) and warns.

The solver lives in :mod:`._irls`, the parameters in :mod:`._params`, the covariance and
identifiability in :mod:`._identify`, the result record :class:`CoatingFit` in
:mod:`._coating_fit`.
"""

from __future__ import annotations

import functools
import math
import warnings
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .._validate import (check_choice, check_count, check_real, check_seed, check_sinogram,
                         short)
from ..errors import MeshladarWarning, ParameterError, user_stacklevel
from ..hits import Hits
from ..ladar import Ladar
from ..precision import ANGLE_TOL_DEG
from ..waveforms import Waveforms
from ..scene import Scene
from . import _bias, _irls, _profile
from ._coating_fit import NOTED_BIAS, CoatingFit
from ._identify import NULL_REL, _correlation, _misfit, _uncertainty, describe
from ._building import parts_of, scene_aliases
from ._params import PartList, _materials, _resolve_params
from ._resolution import (KERNEL_TOL, MAX_SAMPLES, MIN_KERNEL_TOL, KernelErrorWarning, Ladder,
                          kernel_shift, with_kernel_error)
from ._tables import _table
from .kernels import MAX_KERNEL_SAMPLES, CoatingKernel, coating_kernel

__all__ = ["fit_coatings", "CoatingFit", "IdentifiabilityWarning", "KernelErrorWarning",
           "NOISE_MODELS", "KERNEL_TOL", "NOTED_BIAS"]

#: Noise models of :func:`fit_coatings`.
NOISE_MODELS = ("gaussian", "poisson")


class IdentifiabilityWarning(MeshladarWarning):
    """A fitted parameter that the data cannot determine."""


def fit_coatings(geometry, measured, *, parts=None, free=None, bounds=None, initial=None,
                 noise="gaussian", photons_per_unit=None, speckle_cells=None, background=0.0,
                 bootstrap=0, seed=0, samples=None, kernel_tol=KERNEL_TOL,
                 max_samples=MAX_SAMPLES, max_iter=50):
    """Fit coating parameters of chosen parts to a measured sinogram, the geometry known.

    Parameters
    ----------
    geometry : CoatingKernel, Scene or Hits
        The traced geometry (:func:`coating_kernel`); a Scene (analytic or mesh, with
        trace's defaults) is traced on the measured views and bins. The kernel of the
        user's own Hits is used as it is, its error not estimated. A kernel (or Hits) must
        have the data's views, bin edges and radiometry (where ``measured`` says).
    measured : Sinogram or Waveforms
        The data (its ``info["radiometry"]`` picks the radiometry for a Scene); waveforms
        need a waveform kernel (:meth:`CoatingKernel.received`).
    parts : sequence, optional
        Parts (names or indices) whose coatings are fitted (default all; a mesh's are its
        coatings, or a Scene part's name for one it holds alone); the others keep theirs.
    free : sequence or dict, optional
        Parameter names to fit (dataclass fields of each part's BRDF; default all four SR
        parameters, or ρd and b of a diffuse-only SR coating, or every float field of
        another BRDF); a dict gives them per part (its keys parts that are fitted).
    bounds : dict, optional
        "part.param", "index.param" or "param" of a free parameter → (low, high), limits of
        the search only, not of σ (default, and at most, the built-in coatings' valid ranges
        as their classes check them, but SR's e from 1e-4: :data:`SR_BOUNDS`; [0, 1] but
        Phong's exponent, ≥ 0, and GGX's α, [1e-4, 1]; a user's BRDF's fields unbounded).
    initial : dict, optional
        part → BRDF to start from (default the geometry's own coatings).
    noise : {"gaussian", "poisson"}
        Least squares with σ from the residuals (default), or photoelectron counts.
    photons_per_unit : float
        Counts per unit of ``measured.values`` (required for ``"poisson"``).
    speckle_cells : float, optional
        ``"poisson"`` only: M ≥ 1 speckle cells a bin, negative binomial counts (default None).
    background : float
        Known mean background counts per bin (``"poisson"`` only; default 0), not subtracted.
    bootstrap, seed : int
        Parametric-bootstrap refits (0: none) from the fitted model, and their seed.
    samples : float
        Pieces per boundary an analytic Scene's kernel starts from (default 2048); rays
        per bin width a mesh Scene's (default trace's).
    kernel_tol : float or None
        The kernel's error allowed, in σ (default 0.1, at least 1e-6): N doubles until the
        change from N to 2N (a mesh traced again at half the spacing) is at most this in each
        bin and each parameter's shift (a mesh: the shift alone); the fit uses 2N. None: no check.
    max_samples : int
        The most N (default 2^16, at most 2^20; a mesh stops at 2^23 rays too); above it
        a :class:`KernelErrorWarning` gives the error and the N that would do.
    max_iter : int
        Most outer (reweighting) iterations.

    Returns
    -------
    CoatingFit
        Warns :class:`IdentifiabilityWarning` naming any parameter the data cannot
        determine and the combinations they do.
    """
    noise, waveforms = _check_measured(measured, noise)
    bootstrap, seed = check_count("bootstrap", bootstrap, low=0), check_seed("seed", seed)
    kernel_tol, max_samples, max_iter = _check_solver(kernel_tol, max_samples, max_iter)
    scale, M, background = _noise_options(noise, photons_per_unit, speckle_cells, background,
                                          float(np.max(measured.values)))
    kernel, mats, params = _kernel_and_params(geometry, measured, (parts, free, bounds,
                                                                   initial), waveforms, samples)
    ladder = Ladder(kernel, kernel_tol, max_samples)
    opts = _Options(noise, scale, M, background, max_iter)
    x = np.clip([float(getattr(mats[p.part], p.name)) for p in params],
                [p.low for p in params], [p.high for p in params])
    sigma_of = _noise_sigma(measured, opts, len(params))
    ladder.settle(_materials(mats, params, x), sigma_of)
    while True:
        model = _irls.Model(_problem(ladder.used, measured, mats, params, opts))
        x, m, iterations = _irls.solve(model, model.problem.data, x)
        if ladder.settle(_materials(mats, params, x), sigma_of,
                         functools.partial(kernel_shift, model, (x, m))):
            break
    ladder.warn_if_coarse()
    return _result(model, (x, m, iterations), ladder, (bootstrap, seed))


def _check_solver(kernel_tol, max_samples, max_iter):
    """The solver's options checked, before the kernel is traced."""
    return ((None if kernel_tol is None
             else check_real("kernel_tol", kernel_tol, low=MIN_KERNEL_TOL)),
            check_count("max_samples", max_samples, high=MAX_KERNEL_SAMPLES),
            check_count("max_iter", max_iter))


def _result(model, solved, ladder, boot):
    """The CoatingFit of a solved problem, with its covariance and identifiability."""
    problem, (x, m, iterations) = model.problem, solved
    kernel, params = ladder.used, problem.params
    J = model.jacobian(x)
    V = _irls.variance(m, problem.noise, problem.M)
    fit = _misfit(problem, m, V, J)
    full = problem.fixed_all.copy()
    full[problem.rows] = m
    names = tuple(f"{kernel.parts[p.part]}.{p.name}" for p in params)
    found = _uncertainty(fit.fisher, x, params, lambda i: names[i])
    covariance = found.covariance
    bias = _bias.first_order(model.values, x, J,
                             1.0 / V if fit.sigma2 is None else np.full(V.size, 1.0 / fit.sigma2),
                             found.generalised, np.isfinite(np.diag(covariance)))
    if ladder.step is not None:              # the last shift, at this x and kernel
        covariance = with_kernel_error(covariance, ladder.step)
    stderr, corr = _correlation(covariance)
    ident = {names[i]: v for i, v in enumerate(found.reasons)}
    combos = tuple((describe(c, names), float(c @ x), s) for c, s in found.combinations)
    boots = (_irls.bootstrap(model, m, x, count=boot[0], seed=boot[1], sigma2=fit.sigma2)
             if boot[0] else None)
    _warn_undetermined(ident, combos)
    res = ladder.info()
    scale = problem.scale
    return CoatingFit(names, x, stderr, covariance, corr,
                      tuple(_materials(problem.mats, params, x)), ident,
                      problem.noise if problem.M is None else
                      f"negative binomial (M = {problem.M:g})", fit.misfit, fit.dof,
                      iterations, (full / scale).reshape(kernel.shape), boots,
                      {"photons_per_unit": scale if problem.noise == "poisson" else None,
                       "positive": tuple(bool(p.low >= 0.0) for p in params),
                       "bounds": (problem.low, problem.high),
                       "radiometry": kernel.radiometry, "source": kernel.source,
                       "combination_coefficients": tuple(c for c, _ in found.combinations),
                       "covariance": "inverse Fisher information of the user's parameters "
                                     f"(null directions: eigenvalue ≤ {NULL_REL:g} of the "
                                     "largest of the unit-diagonal Fisher matrix)"
                                     + (", plus s sᵀ, s the parameters' shift from the "
                                        "kernel's N to 2N (its estimated error)"
                                        if ladder.active else ""), **res},
                      combinations=combos, kernel_error=res["kernel_error"],
                      samples=res["samples"], bias=bias, _likelihood=functools.partial(
                          _profile.intervals, model, x, m, fit.sigma2))


def _warn_undetermined(ident, combos):
    bad = {n: why for n, why in ident.items() if why is not True}
    if not bad:
        return
    text = "the data cannot determine " + "; ".join(f"{n} ({why})" for n, why in bad.items())
    if combos:
        text += ("; they determine " + ", ".join(f"{c} = {v:.5g} ± {s:.3g}"
                                                 for c, v, s in combos)
                 + ": fix all but one of each combination's parameters (free=) or add views "
                   "that separate them")
    warnings.warn(text, IdentifiabilityWarning, stacklevel=user_stacklevel())


def _noise_sigma(measured, opts, n):
    """The function kernel → each bin's noise σ (data units) at given coatings' model."""
    y = np.asarray(measured.values, float).ravel()

    def sigma_of(kernel, mats):
        model = kernel.predict(mats).ravel()
        if opts.noise == "poisson":
            counts = model * opts.scale + opts.background
            return np.sqrt(_irls.variance(counts, opts.noise, opts.M)) / opts.scale
        rss = float(np.sum((y - model) ** 2))
        return max(math.sqrt(rss / max(1, y.size - n)), 1e-12 * float(np.abs(y).max(
            initial=1.0)))
    return sigma_of


def _check_measured(measured, noise):
    """(``noise`` checked, whether ``measured`` are waveforms); data a fit cannot use
    refused: not a Sinogram or Waveforms, nothing returned, or negative counts."""
    waveforms = isinstance(measured, Waveforms)
    if not waveforms:
        check_sinogram("measured", measured)
    values = measured.values
    noise = check_choice("noise", noise, NOISE_MODELS)
    if not np.any(values > 0):
        raise ParameterError("measured has no positive value: nothing returned, so there is "
                             "nothing to fit (check the data's sign and units)")
    if noise == "poisson" and np.any(values < 0):
        raise ParameterError(f"noise='poisson' counts events, which are >= 0; measured has "
                             f"{int(np.count_nonzero(values < 0))} negative values (smallest "
                             f"{float(values.min()):.4g}): subtract no background, or use "
                             "noise='gaussian'")
    return noise, waveforms


def _kernel_and_params(geometry, measured, choice, waveforms, samples):
    """(the kernel, each part's coating, the free parameters): the parts, free names and
    bounds of ``choice`` = (parts, free, bounds, initial) checked before a Scene or Hits
    is traced, a kernel's views, bins and radiometry checked against ``measured``."""
    given = _geometry_parts(geometry, measured, waveforms=waveforms)
    mats, params = _resolve_params(given, *choice)
    kernel = (given if isinstance(given, CoatingKernel)
              else _traced_kernel(geometry, measured, samples=samples))
    return kernel, mats, params


def _geometry_parts(geometry, measured, *, waveforms):
    """The geometry's kernel, checked against ``measured`` (its views, bins and
    radiometry); or the parts of a Scene or Hits (:class:`PartList`), before anything is
    traced (Hits' views and bins checked)."""
    if waveforms and not (isinstance(geometry, CoatingKernel)
                          and geometry.source.endswith("waveforms")):
        raise ParameterError("measured waveforms need the geometry as a waveform kernel: "
                             "coating_kernel(...).received(sample_rate, pulse=...)")
    if isinstance(geometry, CoatingKernel):
        _check_agreement(geometry, measured, waveforms, "the kernel")
        return geometry
    if isinstance(geometry, Hits):
        lad = geometry.ladar
        _check_agreement(_Views((lad.n_views, lad.bin_edges.size - 1), lad.angles_deg,
                                lad.bin_edges, lad.view_vectors, None), measured, False,
                         "the hits' ladar")
    elif not isinstance(geometry, Scene):
        raise ParameterError(f"geometry must be a CoatingKernel, a Scene or Hits; got "
                             f"{type(geometry).__name__}")
    names, materials = parts_of(geometry)
    return PartList(names, materials, scene_aliases(geometry, names))


class _Views(NamedTuple):
    """What a kernel's data must share with it (:func:`_check_agreement`)."""

    shape: tuple
    angles_deg: np.ndarray
    bin_edges: np.ndarray
    view_vectors: np.ndarray | None
    radiometry: str | None


#: The largest difference of a bin edge between the data and the kernel taken as none, in
#: units of the kernel's narrowest bin (view angles: ANGLE_TOL_DEG degrees, modulo 360).
EDGE_TOL = 1e-6


def _check_agreement(views, measured, waveforms, whose):
    """Refuse ``measured`` unless its shape, views (angles modulo 360°, and the view
    vectors where both have them), bin edges (a waveform's time edges) and radiometry
    (where it says) are those of ``views`` (a kernel, or Hits' ladar), named ``whose``."""
    if measured.values.shape != tuple(views.shape):
        raise ParameterError(f"measured has shape {measured.values.shape}; the geometry's "
                             f"views and bins give {tuple(views.shape)}")
    angles = np.asarray(measured.angles_deg, float)
    turn = (angles - views.angles_deg + 180.0) % 360.0 - 180.0
    _refuse_where("angles_deg", np.abs(turn) > ANGLE_TOL_DEG, angles, views.angles_deg, whose)
    name, edges = ("time_edges", measured.time_edges) if waveforms else ("bin_edges",
                                                                          measured.bin_edges)
    width = float(np.min(np.diff(views.bin_edges)))
    _refuse_where(name, np.abs(edges - views.bin_edges) > EDGE_TOL * width, edges,
                  views.bin_edges, whose)
    mine = np.asarray(measured.view_vectors, float)
    if views.view_vectors is not None and mine.shape == views.view_vectors.shape:
        off = np.max(np.abs(mine - views.view_vectors), axis=1) > np.deg2rad(ANGLE_TOL_DEG)
        _refuse_where("view_vectors", off, mine, views.view_vectors, whose)
    if None not in (measured.radiometry, views.radiometry) and \
            measured.radiometry != views.radiometry:
        raise ParameterError(f"measured has radiometry {measured.radiometry!r}, {whose}'s is "
                             f"{views.radiometry!r}: make the kernel with coating_kernel(..., "
                             f"radiometry={measured.radiometry!r}), or fit data of "
                             f"radiometry {views.radiometry!r}")


def _refuse_where(name, differ, mine, theirs, whose):
    """A ParameterError naming ``name``, the first entry where ``differ`` and both values."""
    if not np.any(differ):
        return
    i = int(np.argmax(differ))
    raise ParameterError(f"measured.{name} differ from {whose}'s in {int(np.sum(differ))} of "
                         f"{len(differ)} entries: entry {i} is {np.round(mine[i], 10)} in "
                         f"measured, {np.round(theirs[i], 10)} in {whose} (measured "
                         f"{short(np.asarray(mine))}; {whose} {short(np.asarray(theirs))}): "
                         "fit the kernel made for the data's ladar (coating_kernel(scene, "
                         "ladar)), or the Scene itself")


def _traced_kernel(geometry, measured, *, samples):
    """The coating kernel of a Scene (on the measured views and bins) or of Hits."""
    if isinstance(geometry, Scene):
        if samples is None and not geometry.is_mesh:
            samples = 2048
        views = (dict(angles_deg=measured.angles_deg) if measured.planar
                 else dict(angles_deg=None, view_vectors=measured.view_vectors))
        return coating_kernel(geometry, Ladar(bin_edges=measured.bin_edges, **views),
                              radiometry=measured.radiometry or "paper", samples=samples)
    return coating_kernel(geometry, radiometry=measured.radiometry or "paper")


def _noise_options(noise, photons_per_unit, speckle_cells, background, peak):
    """(counts per unit, speckle cells or None, background), checked for ``noise``."""
    if noise == "poisson":
        if photons_per_unit is None:
            raise ParameterError("noise='poisson' needs photons_per_unit (counts per unit "
                                 "of the measured values)")
        scale = _irls.check_scale(photons_per_unit, peak)
        M = None if speckle_cells is None else check_real("speckle_cells", speckle_cells,
                                                          low=1.0)
        background = check_real("background", background, low=0.0, high=_irls.MAX_COUNTS)
        return scale, M, background
    if speckle_cells is not None or background:
        raise ParameterError("speckle_cells and background belong to noise='poisson'")
    return 1.0, None, background


@dataclass(frozen=True)
class _Options:
    noise: str
    scale: float
    M: float | None
    background: float
    max_iter: int


def _problem(kernel, measured, mats, params, opts):
    """The fit restricted to the rows a fitted part reaches (only those depend on the
    parameters), the fixed parts' model added in."""
    data = measured.values.ravel() * opts.scale
    fixed_parts = sorted({i for i in range(len(mats))} - {p.part for p in params})
    fixed = np.zeros(data.size)
    for p in fixed_parts:
        fixed += kernel.matrices[p] @ _table(mats[p])
    fixed = fixed * opts.scale + (opts.background if opts.noise == "poisson" else 0.0)
    low = np.array([p.low for p in params])
    high = np.array([p.high for p in params])
    fitted_parts = sorted({q.part for q in params})
    rows = np.flatnonzero(sum(np.diff(kernel.matrices[p].indptr) for p in fitted_parts))
    K = {p: kernel.matrices[p][rows] for p in fitted_parts}
    return _irls.Problem(K, tuple(mats), tuple(params), tuple(fitted_parts), rows,
                         data[rows], fixed[rows], data, fixed, opts.scale, opts.noise,
                         opts.M, low, high, opts.max_iter)
