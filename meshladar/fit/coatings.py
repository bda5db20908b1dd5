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
identifiability in :mod:`._identify`.
"""

from __future__ import annotations

import functools
import math
import warnings
from dataclasses import dataclass, field

import numpy as np
from scipy.stats import norm

from .._summary import table as _html_table
from .._summary import text as _text
from .._validate import check_choice, check_count, check_real, check_seed, check_sinogram
from ..errors import MeshladarWarning, ParameterError
from ..ladar import Ladar
from ..waveforms import Waveforms
from ..scene import Scene
from . import _irls, _profile
from ._identify import NULL_REL, _correlation, _misfit, _uncertainty, describe
from ._params import _materials, _resolve_params
from ._resolution import (KERNEL_TOL, MAX_SAMPLES, MIN_KERNEL_TOL, KernelErrorWarning, Ladder,
                          kernel_shift, with_kernel_error)
from .kernels import MAX_KERNEL_SAMPLES, CoatingKernel, _table, coating_kernel

__all__ = ["fit_coatings", "CoatingFit", "IdentifiabilityWarning", "KernelErrorWarning",
           "NOISE_MODELS", "KERNEL_TOL"]

#: Noise models of :func:`fit_coatings`.
NOISE_MODELS = ("gaussian", "poisson")


class IdentifiabilityWarning(MeshladarWarning):
    """A fitted parameter that the data cannot determine."""


@dataclass(frozen=True, eq=False)
class CoatingFit:
    """The result of :func:`fit_coatings`.

    Attributes
    ----------
    names : tuple of str
        "part.parameter" of each free parameter.
    estimate, stderr : (n,) arrays
        σ is inf for a parameter the data do not act on or that only a combination
        determines (a weakly determined one, named in ``identifiable``, keeps its σ).
    covariance, correlation : (n, n) arrays
        From the Fisher information of the user's parameters at the estimate (inf on an
        undetermined parameter's diagonal, NaN beside it), plus the kernel's estimated
        error as a systematic term s sᵀ, s the parameters' shift from the kernel's N to 2N
        (where it was estimated; ≤ 0.5 % of σ when the shift is within ``kernel_tol``).
    materials : tuple of BRDF
        Every part's coating with the estimates in.
    identifiable : dict
        name → True, or the reason the data cannot determine it.
    undetermined : tuple of str
        The names the data cannot determine.
    combinations : tuple of (str, float, float)
        The combinations of undetermined parameters that the data do determine (the
        directions of the Fisher matrix orthogonal to its near-null ones), as (text,
        value, σ): e.g. ("disk.rho_d + disk.epsilon", 0.5, 0.0027).
    kernel_error : float or None
        The kernel's error: the largest change of the model at the estimate over the bins
        from N to 2N pieces per boundary (or rays per bin width of a mesh traced from its
        Scene), in units of each bin's noise σ (the fit used 2N; None: not estimated, see
        ``info["kernel_error_note"]``).
        ``info["kernel_shift"]``: the largest shift of a parameter, in its σ, that this
        change causes; N doubles until both are at most ``kernel_tol``.
    samples : float or None
        Pieces per boundary (analytic) or rays per bin width (a mesh traced from its
        Scene) of the kernel used.
    noise, deviance, dof, iterations, predicted
        The noise model, the misfit (χ² for Gaussian; for counts the deviance, twice the
        log-likelihood ratio against the saturated model), degrees of freedom, solver
        iterations, the fitted sinogram values.
    bootstrap : (n_boot, n) array or None
        Parametric-bootstrap estimates.
    """

    names: tuple
    estimate: np.ndarray
    stderr: np.ndarray
    covariance: np.ndarray
    correlation: np.ndarray
    materials: tuple
    identifiable: dict
    noise: str
    deviance: float
    dof: int
    iterations: int
    predicted: np.ndarray
    bootstrap: np.ndarray | None = None
    info: dict = field(default_factory=dict)
    combinations: tuple = ()
    kernel_error: float | None = None
    samples: int | None = None
    _likelihood: object = field(default=None, repr=False, compare=False)
    _profiled: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def undetermined(self):
        """The names the data cannot determine."""
        return tuple(n for n in self.names if self.identifiable[n] is not True)

    def _kernel_line(self):
        if self.kernel_error is None:
            return "not estimated"
        unit = ("rays per bin width" if self.info.get("source") == "mesh"
                else "samples per boundary")
        return f"{self.kernel_error:.2g} σ ({self.samples:g} {unit})"

    def _summary(self):
        return (("noise", self.noise),
                *((n, f"{v:.5g} ± {e:.3g}" + ("" if self.identifiable[n] is True
                                               else " (undetermined)"))
                  for n, v, e in zip(self.names, self.estimate, self.stderr)),
                *((c, f"{v:.5g} ± {e:.3g} (determined)") for c, v, e in self.combinations),
                ("misfit", f"{self.deviance:.4g} on {self.dof} dof"),
                ("kernel error", self._kernel_line()))

    def __repr__(self) -> str:
        return _text("CoatingFit", *self._summary())

    def _repr_html_(self) -> str:
        return _html_table("CoatingFit", *self._summary())

    def interval(self, level=0.95, method="normal", parameters=None):
        """(low, high) arrays of the ``level`` intervals.

        ``method="normal"`` (z the normal quantile): a parameter whose valid range starts
        at 0 or above (``info["positive"]``: every SR parameter) has a positive estimate,
        and a finite σ gets its interval on the log scale, estimate · exp(∓ z σ /
        estimate) (the delta method's σ of the logarithm): it stays positive and follows
        the right skew of a width's estimates (the glinting disk's b at 10³ photons covers
        0.93 of the truths, against 0.88 for estimate ∓ z σ; the same at 10⁴, on 100
        seeded trials each); any other gets estimate ∓ z σ.

        ``method="profile"``: the likelihood-ratio interval, the values whose profile
        misfit (the others refitted) rises at most z² (:mod:`._profile`): right where the
        likelihood is far from quadratic (a narrow glint's ε and e at 10⁴ photoelectrons),
        at the cost of a few refits per end (seconds each for a pair of coatings); an end
        stops at the parameter's bound. ``parameters`` (names; default all) limits the
        profiling to those, the others keep their normal interval, as does an
        undetermined parameter. Each end is computed once.

        Parameters
        ----------
        level : float
            The intervals' coverage, in (0, 1) (default 0.95).
        method : {"normal", "profile"}
            The normal approximation (default) or the profile likelihood.
        parameters : list of str, optional
            ``method="profile"``: the names (of ``names``) to profile (default all).

        Returns
        -------
        low, high : (n,) arrays
            The ends, in the parameters' own units, in the order of ``names``.

        Raises
        ------
        ParameterError
            On a level outside (0, 1), an unknown method or parameter name, or
            ``method="profile"`` on a CoatingFit not made by :func:`fit_coatings`.

        References
        ----------
        Y. Pawitan, *In All Likelihood*, Oxford University Press (2001), Sec. 3.4 and 9.7
        (likelihood-ratio and profile-likelihood intervals).
        """
        level = check_real("level", level, low=0.0, high=1.0, low_open=True, high_open=True)
        method = check_choice("method", method, ("normal", "profile"))
        z = float(norm.ppf(0.5 + 0.5 * level))
        low, high = _profile.normal(self.estimate, self.stderr, self.info.get("positive"), z)
        if method == "normal":
            return low, high
        if self._likelihood is None:
            raise ParameterError("method='profile' needs the fit's likelihood, which this "
                                 "CoatingFit does not carry (it was not made by fit_coatings)")
        chosen = [i for i in _profile.chosen(self.names, parameters)
                  if np.isfinite(self.stderr[i])]
        todo = [i for i in chosen if (level, i) not in self._profiled]
        if todo:
            plow, phigh = self._likelihood(self.stderr, z, todo)
            self._profiled.update({(level, i): (plow[i], phigh[i]) for i in todo})
        for i in chosen:
            low[i], high[i] = self._profiled[(level, i)]
        return low, high

    def report(self):
        """The fit as text lines: each parameter ± σ, its 95 % interval, and whether the
        data determine it.

        Returns
        -------
        list of str
            The lines: a header (noise model, misfit, iterations), one line per parameter
            (estimate, σ, normal 95 % interval, NOT DETERMINED and why), correlations
            beyond 0.9, the determined combinations, and the kernel's error.
        """
        lo, hi = self.interval()
        out = [f"  coating fit ({self.noise}; misfit {self.deviance:.4g} on {self.dof} "
               f"degrees of freedom, {self.iterations} iterations)",
               f"  {'parameter':<26} {'estimate':>11} {'± σ':>10} {'95 % interval':>24}"]
        for i, n in enumerate(self.names):
            ok = self.identifiable[n]
            note = "" if ok is True else f"  NOT DETERMINED: {ok}"
            out.append(f"  {n:<26} {self.estimate[i]:11.5g} {self.stderr[i]:10.3g} "
                       f"[{lo[i]:10.5g}, {hi[i]:10.5g}]{note}")
        strong = [(self.names[i], self.names[j], self.correlation[i, j])
                  for i in range(len(self.names)) for j in range(i + 1, len(self.names))
                  if np.isfinite(self.correlation[i, j]) and abs(self.correlation[i, j]) > 0.9]
        for a, b, r in strong:
            out.append(f"  correlation {a} ~ {b}: {r:+.3f}")
        for c, v, e in self.combinations:
            out.append(f"  determined: {c} = {v:.5g} ± {e:.3g}")
        out.append(f"  kernel error: {self._kernel_line()}")
        return out

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
        user's own Hits is used as it is, its error not estimated.
    measured : Sinogram or Waveforms
        The data (its ``info["radiometry"]`` picks the radiometry for a Scene); waveforms
        need a waveform kernel (:meth:`CoatingKernel.received`).
    parts : sequence, optional
        Parts (names or indices) whose coatings are fitted (default all); the others keep
        their coatings.
    free : sequence or dict, optional
        Parameter names to fit (dataclass fields of each part's BRDF; default all four SR
        parameters, or ρd and b of a diffuse-only SR coating, or every float field of
        another BRDF); a dict gives them per part.
    bounds : dict, optional
        "part.param", "index.param" or "param" → (low, high) (default SR's valid ranges,
        others unbounded): they limit the search only, not σ.
    initial : dict, optional
        part → BRDF to start from (default the geometry's own coatings).
    noise : {"gaussian", "poisson"}
        Least squares with σ from the residuals, or photoelectron counts: Poisson, or with
        ``speckle_cells`` M the negative binomial of M speckle cells per bin.
    photons_per_unit : float
        Counts per unit of ``measured.values`` (required for ``"poisson"``).
    background : float
        Known mean background counts per bin (``"poisson"``), not subtracted from the data.
    bootstrap, seed : int
        Parametric-bootstrap refits (0: none) from the fitted model, and their seed.
    samples : float
        Pieces per boundary an analytic Scene's kernel starts from (default 2048); rays per
        bin width a mesh Scene's starts from (default trace's).
    kernel_tol : float or None
        The kernel's error allowed, in σ (default 0.1, at least 1e-6): N doubles until the
        model's change from N to 2N (a mesh traced again at half the spacing) is at most
        this in each bin and in each parameter's shift (a mesh: the shift alone,
        :mod:`._resolution`); the fit uses 2N. None: no check.
    max_samples : int
        The most N (default 2^16; a mesh stops at 2^23 rays too); above it a
        :class:`KernelErrorWarning` gives the error and the N that would do.
    max_iter : int
        Most outer (reweighting) iterations.

    Returns
    -------
    CoatingFit
        Warns :class:`IdentifiabilityWarning` naming any parameter the data cannot
        determine and the combinations they do.
    """
    waveforms = isinstance(measured, Waveforms)
    if not waveforms:
        check_sinogram("measured", measured)
    noise = _check_measured(measured.values, noise)
    bootstrap, seed = check_count("bootstrap", bootstrap, low=0), check_seed("seed", seed)
    kernel_tol, max_samples, max_iter = _check_solver(kernel_tol, max_samples, max_iter)
    scale, M, background = _noise_options(noise, photons_per_unit, speckle_cells, background,
                                          float(np.max(measured.values)))
    kernel = _kernel_for(geometry, measured, waveforms=waveforms, samples=samples)
    ladder = Ladder(kernel, kernel_tol, max_samples)
    mats, params = _resolve_params(kernel, parts, free, bounds, initial)
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
                       "radiometry": kernel.radiometry, "source": kernel.source,
                       "covariance": "inverse Fisher information of the user's parameters "
                                     f"(null directions: eigenvalue ≤ {NULL_REL:g} of the "
                                     "largest of the unit-diagonal Fisher matrix)"
                                     + (", plus s sᵀ, s the parameters' shift from the "
                                        "kernel's N to 2N (its estimated error)"
                                        if ladder.active else ""), **res},
                      combinations=combos, kernel_error=res["kernel_error"],
                      samples=res["samples"], _likelihood=functools.partial(
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
    warnings.warn(text, IdentifiabilityWarning, stacklevel=3)


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


def _check_measured(values, noise):
    """``noise`` checked, and data a fit cannot use refused: nothing returned, or negative
    counts."""
    noise = check_choice("noise", noise, NOISE_MODELS)
    if not np.any(values > 0):
        raise ParameterError("measured has no positive value: nothing returned, so there is "
                             "nothing to fit (check the data's sign and units)")
    if noise == "poisson" and np.any(values < 0):
        raise ParameterError(f"noise='poisson' counts events, which are >= 0; measured has "
                             f"{int(np.count_nonzero(values < 0))} negative values (smallest "
                             f"{float(values.min()):.4g}): subtract no background, or use "
                             "noise='gaussian'")
    return noise


def _kernel_for(geometry, measured, *, waveforms, samples):
    """The coating kernel of ``geometry`` on the measured views and bins, checked."""
    if waveforms and not (isinstance(geometry, CoatingKernel)
                          and geometry.source.endswith("waveforms")):
        raise ParameterError("measured waveforms need the geometry as a waveform kernel: "
                             "coating_kernel(...).received(sample_rate, pulse=...)")
    if isinstance(geometry, CoatingKernel):
        kernel = geometry
    elif isinstance(geometry, Scene):
        if samples is None and not geometry.is_mesh:
            samples = 2048
        views = (dict(angles_deg=measured.angles_deg) if measured.planar
                 else dict(angles_deg=None, view_vectors=measured.view_vectors))
        kernel = coating_kernel(geometry, Ladar(bin_edges=measured.bin_edges, **views),
                                radiometry=measured.radiometry or "paper",
                                samples=samples)
    else:
        kernel = coating_kernel(geometry, radiometry=measured.radiometry or "paper")
    if measured.values.shape != kernel.shape:
        raise ParameterError(f"measured has shape {measured.values.shape}; the geometry's "
                             f"views and bins give {kernel.shape}")
    return kernel


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
