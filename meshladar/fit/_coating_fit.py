"""The result record of :func:`~meshladar.fit.coatings.fit_coatings`: the estimates with
their covariance and identifiability, shown as a summary or a report, and their intervals
(normal, or from the profile likelihood of :mod:`._profile`).

:class:`CoatingFit` is importable from :mod:`meshladar.fit.coatings` and :mod:`meshladar.fit`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.special import ndtri

from .._summary import table as _html_table
from .._summary import text as _text
from .._validate import check_choice, check_real
from ..errors import ParameterError
from . import _profile

__all__ = ["CoatingFit", "NOTED_BIAS"]

#: The report names a parameter whose first-order bias reaches this share of its σ (a
#: tenth: a 95 % interval off by that covers 94.9 % of the truths, not 95 %).
NOTED_BIAS = 0.1


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
        The combinations the data do determine, as (text, value, σ): of undetermined
        parameters, the directions of the Fisher matrix orthogonal to its near-null ones
        (e.g. ("disk.rho_d + disk.epsilon", 0.5, 0.0027)); and across a ridge, parameters
        correlated beyond 0.99, the best-measured one (e.g. the paper's aluminium at 10⁴
        photoelectrons, ("0.01805·small.epsilon + small.e", 0.01663, 8.2e-05): each of
        ε and e loose and skewed, the combination unbiased). Their coefficients over
        ``names`` are ``info["combination_coefficients"]``, in the same order.
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
    bias : (n,) array or None
        The estimate's first-order bias (Cox and Snell), from the model's curvature and
        the Fisher information at the estimate; NaN where σ is not finite and where the
        expansion does not hold (second differences at 0.1 and 0.2 σ give biases more
        than 0.05 σ apart). ``corrected`` is the estimate less it.
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
    bias: np.ndarray | None = None
    _likelihood: object = field(default=None, repr=False, compare=False)
    _profiled: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def undetermined(self):
        """The names the data cannot determine."""
        return tuple(n for n in self.names if self.identifiable[n] is not True)

    @property
    def corrected(self):
        """The estimate less its first-order bias (``bias``), kept within the search's
        bounds; the estimate itself where the bias is unknown."""
        if self.bias is None:
            return self.estimate.copy()
        return self._within_bounds(self.estimate - np.where(np.isfinite(self.bias),
                                                            self.bias, 0.0))

    def _within_bounds(self, values):
        """``values`` (one per parameter) clipped to the search's bounds
        (``info["bounds"]``, where the fit records them)."""
        bounds = self.info.get("bounds")
        return values if bounds is None else np.clip(values, bounds[0], bounds[1])

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
                *((("first-order bias", self._skewed()),) if self._skewed() else ()),
                ("misfit", f"{self.deviance:.4g} on {self.dof} dof"),
                ("kernel error", self._kernel_line()))

    def __repr__(self) -> str:
        return _text("CoatingFit", *self._summary())

    def _repr_html_(self) -> str:
        return _html_table("CoatingFit", *self._summary())

    def interval(self, level=0.95, method="normal", parameters=None):
        """(low, high) arrays of the ``level`` intervals.

        ``method="normal"`` (z the normal quantile): a parameter whose valid range starts
        at 0 or above (``info["positive"]``: every built-in coating's parameter, as its
        bounds) has a positive estimate,
        and a finite σ gets its interval on the log scale, estimate · exp(∓ z σ /
        estimate) (the delta method's σ of the logarithm): it stays positive and follows
        the right skew of a width's estimates (the glinting disk's b at 10³ photons covers
        0.93 of the truths, against 0.88 for estimate ∓ z σ; the same at 10⁴, on 100
        seeded trials each); any other gets estimate ∓ z σ. Either end stops at the
        search's bound (``info["bounds"]``): a narrow glint's ε of 0.80 ± 0.17 gets
        [0.53, 1], not [0.53, 1.21] (tested).

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
        z = float(ndtri(0.5 + 0.5 * level))
        low, high = (self._within_bounds(v) for v in _profile.normal(
            self.estimate, self.stderr, self.info.get("positive"), z))
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
            beyond 0.9, the determined combinations, the parameters whose first-order
            bias (``bias``) reaches :data:`NOTED_BIAS` of their σ, and the kernel's error.
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
        skewed = self._skewed()
        if skewed:
            out.append(f"  first-order bias: {skewed} (fit.corrected subtracts it)")
        out.append(f"  kernel error: {self._kernel_line()}")
        return out

    def _skewed(self):
        """'name +0.31 σ, …' for the parameters whose first-order bias reaches
        :data:`NOTED_BIAS` of their σ ('' where none does, or the bias is unknown)."""
        if self.bias is None:
            return ""
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            z = self.bias / self.stderr
        return ", ".join(f"{n} {v:+.2f} σ" for n, v in zip(self.names, z)
                         if np.isfinite(v) and abs(v) >= NOTED_BIAS)
