"""Profile-likelihood intervals of a coating fit (``CoatingFit.interval(method="profile")``).

A parameter's interval at level L is the set of its values v whose profile misfit, the
misfit with the parameter held at v and every other free parameter refitted, exceeds the
fit's own by at most z², z the normal quantile of L (Wilks' theorem: the likelihood-ratio
interval; Pawitan, *In All Likelihood*, 2001, Sec. 3.4 and 9.7). For counts the misfit is
the deviance, for least squares RSS / σ², σ² the fit's own. Where the likelihood is
quadratic it equals the normal interval estimate ∓ z σ; where it is not (a narrow glint at
a few thousand photoelectrons, its ε and e on a curved ridge) it follows the likelihood,
as the normal interval cannot. The kernel is the fit's own (its estimated error, ≤ 0.1 σ,
is not added).

Each end is found on the signed root r(v) = √Δ(v), nearly linear in v (in ln v for a
parameter ≥ 0): from the normal interval's end, a secant from the estimate brackets it,
and Brent's method closes in until r is within ROOT_TOL of z; each refit starts from the
last. An end that does not reach z² before the parameter's bound is the bound; values
outside the coatings' valid set count as far outside the interval.
"""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
from scipy.optimize import brentq

from ..errors import EnergyConservationWarning, ParameterError
from . import _irls
from ._identify import deviance
from ._params import _materials

#: An end is accepted when its signed root is within this fraction of z.
ROOT_TOL = 0.01
#: A profile refit's relative tolerance (ftol and xtol of its solves, _irls.solve; the fit
#: itself uses 1e-8): on the pair of coatings at 10⁴ photoelectrons the ends agree with
#: 1e-8's to five digits, far inside ROOT_TOL, at 15 % fewer evaluations.
REFIT_TOL = 1e-6
#: The most profile refits per end.
MAX_REFITS = 12


def normal(estimate, stderr, positive, z):
    """(low, high) of the normal intervals: on the log scale for a positive estimate of a
    parameter ≥ 0 (``positive``) with a finite σ, estimate ∓ z σ otherwise."""
    est, sd = np.asarray(estimate, float), np.asarray(stderr, float)
    log = (np.asarray(np.zeros(est.size, bool) if positive is None else positive, bool)
           & (est > 0) & np.isfinite(sd))
    r = np.where(log, sd, 0.0) / np.where(log, est, 1.0)
    # a σ hundreds of times its estimate (a weakly determined glint width) takes the top
    # to inf and the bottom to 0: the interval is unbounded above, not a warning
    with np.errstate(over="ignore", under="ignore"):
        return (np.where(log, est * np.exp(-z * r), est - z * sd),
                np.where(log, est * np.exp(z * r), est + z * sd))


def chosen(names, parameters):
    """The indices of ``parameters`` (names of ``names``; None: all), checked."""
    if parameters is None:
        return list(range(len(names)))
    if isinstance(parameters, str):
        parameters = [parameters]
    if not isinstance(parameters, (list, tuple)):
        raise ParameterError(f"parameters must be a list of the fit's names; got "
                             f"{type(parameters).__name__}")
    out = []
    for p in parameters:
        if p not in names:
            raise ParameterError(f"parameters: {p!r} is not a fitted parameter; the fit has "
                                 f"{', '.join(names)}")
        out.append(names.index(p))
    return out


def misfit(problem, m, sigma2):
    """The fit's misfit at model values ``m``: the count deviance, or RSS / σ²."""
    if problem.noise == "gaussian":
        return float(np.sum((problem.data - m) ** 2)) / sigma2
    return deviance(problem.data, m, problem.M)


class Profile:
    """The profile misfit of one parameter of a solved fit (``model`` at ``x``)."""

    def __init__(self, model, x, base, sigma2, i):
        self.model, self.i, self.sigma2, self.base = model, i, sigma2, base
        self.x = np.asarray(x, float)
        self.starts = {self.x[i]: np.delete(self.x, i)}   # v → the others refitted there

    def delta(self, v):
        """The misfit's rise with parameter i held at v (inf outside the valid set)."""
        pr = self.model.problem
        near = min(self.starts, key=lambda w: abs(w - v))   # the nearest refit starts it
        x = self.x.copy()
        x[self.i] = v
        x[np.arange(x.size) != self.i] = self.starts[near]
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", EnergyConservationWarning)
                mats = _materials(pr.mats, pr.params, x)
        except ParameterError:
            return math.inf
        held = dataclasses.replace(
            pr, mats=tuple(mats), params=pr.params[:self.i] + pr.params[self.i + 1:],
            low=np.delete(pr.low, self.i), high=np.delete(pr.high, self.i))
        if not held.params:                       # one free parameter: nothing to refit
            m = _irls.Model(held).values(np.zeros(0))
        else:
            start = np.clip(self.starts[near], held.low, held.high)
            self.starts[v], m, _ = _irls.solve(_irls.Model(held), held.data, start, REFIT_TOL)
        if m is None:
            return math.inf
        return max(misfit(held, m, self.sigma2) - self.base, 0.0)


def _coordinates(low, value):
    """(to, back): the coordinate the end is sought in, ln v for a parameter ≥ 0."""
    if low >= 0.0 and value > 0.0:
        return math.log, math.exp
    return float, float


#: A parameter ≥ 0 whose low end is not reached above e^-LOG_DEPTH times its estimate has
#: the bound 0 as its low end.
LOG_DEPTH = 50.0
#: The most a step from the estimate grows, per refit, while no end is bracketed.
MAX_GROWTH = 8.0


class _Found(Exception):
    """An end within ROOT_TOL: stops Brent's search early."""


#: The first step from the estimate, on the log scale, is at most this (a normal σ many
#: times its estimate would put it decades away, where each refit is slow).
MAX_FIRST_LOG_STEP = math.log(4.0)


def end(profile, value, sd, z, side, limit):
    """One end (side −1: low, +1: high) of the interval of parameter ``profile.i``, from
    its estimate ``value`` and normal σ ``sd``; ``limit`` is its bound on that side."""
    to, back = _coordinates(profile.model.problem.low[profile.i], value)
    u0 = to(value)
    if to is math.log and limit <= 0.0:
        ulim = u0 - LOG_DEPTH
    else:
        ulim = to(limit) if np.isfinite(limit) else side * math.inf
    seen = {u0: -z}                                   # the estimate: no rise

    def excess(u):                     # the signed root less z (inf: invalid), each u once
        if u not in seen:
            seen[u] = math.sqrt(profile.delta(back(u))) - z
            if abs(seen[u]) <= ROOT_TOL * z:
                raise _Found(u)
        return seen[u]

    step = min(z * sd / value, MAX_FIRST_LOG_STEP) if to is math.log else z * sd
    try:
        inside, outside = _bracket(excess, u0, u0 + side * step, ulim, z)
        if outside is None:
            return limit if inside == ulim else back(inside)
        brentq(excess, *sorted((inside, outside)), xtol=1e-12, maxiter=MAX_REFITS)
    except _Found as found:
        return back(found.args[0])
    except RuntimeError:                             # not settled: the outer point
        pass
    return back(outside)


def _bracket(excess, u0, u, ulim, z):
    """(last u inside, first u outside): from the first trial ``u``, a secant from the
    estimate ``u0`` through the last point inside (the signed root is linear there for a
    quadratic likelihood), grown 1.5 to MAX_GROWTH times; a trial outside the coatings'
    valid set halves the step back. No u outside (None): the bound ``ulim`` is inside, or
    the valid set ends first (the last u inside is then the end)."""
    side, inside, edge = math.copysign(1.0, u - u0), u0, ulim
    for _ in range(MAX_REFITS):
        if side * (u - edge) >= 0:
            u = edge
        f = excess(u)
        if math.isinf(f):                             # the valid set ends nearer
            edge, u = u, 0.5 * (inside + u)
            continue
        if f > 0:
            return inside, u
        inside, r = u, f + z
        if u == ulim:
            break
        u = u0 + (u - u0) * min(max(z / r if r > 0 else MAX_GROWTH, 1.5), MAX_GROWTH)
    return inside, None


def intervals(model, x, m, sigma2, stderr, z, which):
    """(low, high): the profile-likelihood ends of the parameters ``which`` (indices) of
    the fit ``model`` solved at ``x`` (model values ``m``, least squares' σ² or None),
    from their normal σ ``stderr`` at the quantile ``z``; NaN for the others."""
    pr = model.problem
    base = misfit(pr, m, sigma2)
    low, high = np.full(len(x), np.nan), np.full(len(x), np.nan)
    for i in which:
        low[i], high[i] = (end(Profile(model, x, base, sigma2, i), float(x[i]),
                               float(stderr[i]), z, side, float(limit))
                           for side, limit in ((-1, pr.low[i]), (1, pr.high[i])))
    return low, high
