"""The coating fit's solver: the linear-in-tables model of the fitted rows, the noise
model's variance, and iteratively reweighted least squares (the score equations
Σ (d − m)/V(m) ∂m/∂p = 0 are the maximum-likelihood ones for V(m) = m and
V(m) = m + m²/M)."""

from __future__ import annotations

import functools
import math
import warnings
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from .._validate import check_real, short
from ..errors import EnergyConservationWarning, ParameterError
from ._identify import deviance, unit_deviance
from ._params import _jacobian, _materials
from ._tables import _table


#: The most counts in the brightest bin a count fit takes: 10¹⁵ photoelectrons (a relative
#: Poisson σ of 3e-8) is beyond any detector; far beyond, the likelihood's products
#: overflow. (The least is one count: below it there is no signal to fit.)
MAX_COUNTS = 1e15


def check_scale(photons_per_unit, peak):
    """``photons_per_unit`` checked: positive, and the brightest bin (``peak`` in data units)
    between 1 and MAX_COUNTS counts."""
    scale = check_real("photons_per_unit", photons_per_unit, low=0.0, low_open=True)
    if not 1.0 <= scale * peak <= MAX_COUNTS:
        raise ParameterError(f"photons_per_unit: {short(photons_per_unit)} per unit makes the "
                             f"brightest bin {scale * peak:.3g} counts; a count fit takes 1 to "
                             f"{MAX_COUNTS:.0e} there (fewer is no signal, more overflows its "
                             "arithmetic): give the counts per unit of the values")
    return scale


@dataclass(frozen=True, eq=False)
class Problem:
    """A fit's data and fixed parts, restricted to the rows a fitted part reaches.

    ``K`` maps each fitted part to its kernel matrix on those rows; ``data`` and ``fixed``
    are the counts (or values) and the fixed parts' model there, ``y_all`` and
    ``fixed_all`` the same on every row; ``noise`` is "gaussian" or "poisson", ``M`` the
    speckle cells (None: Poisson)."""

    K: dict
    mats: tuple
    params: tuple
    fitted_parts: tuple
    rows: np.ndarray
    data: np.ndarray
    fixed: np.ndarray
    y_all: np.ndarray
    fixed_all: np.ndarray
    scale: float
    noise: str
    M: float | None
    low: np.ndarray
    high: np.ndarray
    max_iter: int


class Model:
    """The model values and Jacobian of a :class:`Problem` at parameters x; the last few
    tables are kept, as the solver asks for the model and its Jacobian at one point."""

    def __init__(self, problem):
        self.problem = problem
        self._cache = {}

    def tables(self, x):
        """Each fitted part's table at x (None outside the model's valid set)."""
        pr = self.problem
        key = tuple(np.asarray(x, float))
        if key not in self._cache:
            try:
                with warnings.catch_warnings():
                    # the solver's trial points may leave energy conservation (allowed,
                    # as the paper's Sec. 4.A); the user hears of the estimate only
                    warnings.simplefilter("ignore", EnergyConservationWarning)
                    ms = _materials(pr.mats, pr.params, x)
                    self._cache[key] = {p: _table(ms[p]) for p in pr.fitted_parts}
            except ParameterError:
                self._cache[key] = None
            if len(self._cache) > 8:
                self._cache.pop(next(iter(self._cache)))
        return self._cache[key]

    def values(self, x):
        """The model on the fitted rows (None outside the valid set)."""
        pr = self.problem
        t = self.tables(x)
        if t is None:
            return None
        m = pr.fixed.copy()
        for p in pr.fitted_parts:
            m += (pr.K[p] @ t[p]) * pr.scale
        return m

    def jacobian(self, x):
        pr = self.problem
        return _jacobian(pr.K, pr.mats, pr.params, x, self.tables(x), pr.scale,
                         pr.data.size)


def variance(m, noise, M):
    """The noise model's variance of counts with mean ``m`` (ones for Gaussian)."""
    if noise == "gaussian":
        return np.ones_like(m)
    v = np.maximum(m, 0.0) + (0.0 if M is None else np.maximum(m, 0.0) ** 2 / M)
    return np.maximum(v, 1e-3 * max(1.0, float(np.median(v[v > 0])) if (v > 0).any()
                                      else 1.0))


def _residual(model, y, sw, z):
    mz = model.values(z)
    if mz is None:                           # outside the model's valid set
        return np.full(y.size, 1e6 * (np.abs(y).max() + 1.0)) * sw
    return (mz - y) * sw


def _weighted_jacobian(model, sw, z):
    return model.jacobian(z) * sw[:, None]


def solve(model, y, x_start, tol=1e-8):
    """The maximum-likelihood fit from ``x_start`` to data ``y``: (x, model values, solver
    evaluations); ``tol`` is each least-squares solve's relative tolerance (ftol and xtol).

    Least squares for Gaussian noise. Counts: IRLS first, which stops when the
    reweighting moves no parameter by 1 % of its σ (:func:`_settled`), or when a reweighted
    solve raises the deviance (:data:`RISE_TOL`: IRLS can cycle between two points, a
    glint's width and specular share trading places at 10⁴ photoelectrons), keeping the
    best point seen; then the deviance itself is minimised from there (:func:`_polish`), so
    the estimate is the likelihood's optimum even where IRLS stalled short of it."""
    pr = model.problem
    x = x_start.copy()
    iterations = 0
    m = model.values(x)
    if m is None:
        raise ParameterError("the starting coatings are invalid (initial=)")
    best = None
    for _ in range(pr.max_iter):
        V = variance(m, pr.noise, pr.M)
        sw = 1.0 / np.sqrt(V)
        sol = least_squares(functools.partial(_residual, model, y, sw), x,
                            jac=functools.partial(_weighted_jacobian, model, sw),
                            bounds=(pr.low, pr.high), x_scale="jac", method="trf",
                            ftol=tol, xtol=tol, max_nfev=200)
        iterations += sol.nfev
        dx = np.abs(sol.x - x)
        x = sol.x
        m = model.values(x)
        if pr.noise == "gaussian":
            return x, m, iterations
        dev = deviance(y, m, pr.M)
        if best is not None and dev > best[0] + RISE_TOL * max(abs(best[0]), 1.0):
            break                                  # a cycle: polish the best point seen
        if best is None or dev < best[0]:
            best = (dev, x, m)
        if _settled(sol.jac, dx, x, len(pr.params)):
            break
    return _polish(model, y, best, tol, iterations)


def _polish(model, y, best, tol, iterations):
    """The count deviance minimised from IRLS's best point (dev, x, m) by least squares on
    the deviance residuals sign(y − m) √d (Σ r² is the deviance): (x, m, evaluations), the
    start kept unless the deviance falls."""
    pr = model.problem
    sol = least_squares(functools.partial(_deviance_residual, model, y), best[1],
                        jac=functools.partial(_deviance_jacobian, model, y),
                        bounds=(pr.low, pr.high), x_scale="jac", method="trf",
                        ftol=tol, xtol=tol, max_nfev=200)
    m = model.values(sol.x)
    if m is None or deviance(y, m, pr.M) >= best[0]:
        return best[1], best[2], iterations + sol.nfev
    return sol.x, m, iterations + sol.nfev


def _deviance_residual(model, y, z):
    m = model.values(z)
    if m is None:                           # outside the model's valid set
        return np.full(y.size, 1e6 * (np.sqrt(np.abs(y).max()) + 1.0))
    return np.sign(y - m) * np.sqrt(unit_deviance(y, m, model.problem.M))


def _deviance_jacobian(model, y, z):
    """∂r/∂x = (m − y) / (V r) · ∂m/∂x (d'(m) = 2 (m − y)/V for both count models), whose
    limit where y = m is −1/√V."""
    pr = model.problem
    m = model.values(z)
    if m is None:
        return np.zeros((y.size, len(pr.params)))
    m = np.maximum(m, 1e-300)
    V = m + (0.0 if pr.M is None else m * m / pr.M)
    r = np.sign(y - m) * np.sqrt(unit_deviance(y, m, pr.M))
    near = np.abs(r) < 1e-6
    g = np.where(near, -1.0 / np.sqrt(V), (m - y) / (V * np.where(near, 1.0, r)))
    return model.jacobian(z) * g[:, None]


#: A reweighted solve whose count deviance exceeds the best so far by more than this
#: fraction of it stops the iteration (round-off near the optimum is ~1e-15 of it).
RISE_TOL = 1e-9


def _settled(Jw, dx, x, n):
    """Converged when the reweighting moves no parameter by 1 % of its σ."""
    try:
        sd = np.sqrt(np.abs(np.diag(np.linalg.pinv(Jw.T @ Jw))))
    except np.linalg.LinAlgError:
        sd = np.full(n, np.inf)
    return bool(np.all(dx <= 0.01 * sd + 1e-12 * np.abs(x)))


def bootstrap(model, m, x, *, count, seed, sigma2):
    """Parametric-bootstrap refits: (count, n) estimates from data drawn from the fitted
    model values ``m`` (Gaussian with σ², Poisson, or negative binomial)."""
    pr = model.problem
    rng = np.random.default_rng(seed)
    boots = np.empty((count, len(pr.params)))
    for b in range(count):
        if pr.noise == "gaussian":
            y = m + rng.normal(0.0, math.sqrt(sigma2), m.size)
        elif pr.M is None:
            y = rng.poisson(np.maximum(m, 0.0)).astype(float)
        else:
            y = rng.poisson(rng.gamma(pr.M, np.maximum(m, 0.0) / pr.M)).astype(float)
        boots[b] = solve(model, y, x)[0]
    return boots
