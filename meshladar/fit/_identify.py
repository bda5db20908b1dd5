"""Identifiability of a coating fit: the covariance from the Fisher information in the
user's own parameters, its near-null directions (the combinations the data cannot
separate), and which parameters the data cannot determine.

The Fisher matrix F (of the user's parameters, whatever their bounds) is scaled to unit
diagonal, S = D F D with D = diag(F)^(-1/2), and eigen-decomposed. An eigenvalue below
:data:`NULL_REL` times the largest marks a near-null direction: along it the parameters move
together without changing the data (for a unit-diagonal S, the direction's σ is more than
1/sqrt(NULL_REL) ≈ 30,000 times the σ each parameter would have alone). The parameters with
a share of such a direction are undetermined (σ = inf); the combinations orthogonal to the
null directions are determined, and are named with their σ from the generalised inverse
D S⁺ D restricted to the other directions.

A ridge is nearly null: parameters correlated beyond :data:`RIDGE_CORR` (a narrow glint's
ε and e, of which the data see mostly one combination at 10⁴ photoelectrons) are each
loosely determined and their estimates skewed along it, while the combination across the
ridge is well measured: it is named with its σ among the combinations too.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

#: Relative eigenvalue threshold of the unit-diagonal Fisher matrix below which a direction
#: counts as null (finite-difference Jacobians leave ~1e-14 on exact degeneracies).
NULL_REL = 1e-9
#: A parameter takes part in a null direction when its (scaled) component exceeds this.
_SHARE = 0.05
#: Also undetermined: a σ beyond half the bounds' width, a non-negative or unbounded
#: parameter's σ beyond half its value (its 95 % interval spans more than a factor 7), or a
#: correlation beyond _CORR_LIMIT with another while either of the two is loose: σ beyond
#: _LOOSE of its value (non-negative or unbounded) or of its bounds' width (signed).
_REL_LIMIT = 0.5
_CORR_LIMIT = 0.995
_LOOSE = 0.25
#: A parameter whose effect on the data over its range is below this share of the largest
#: one's does not act on the data.
_DEAD = 1e-14
#: The scale of that effect for an unbounded parameter whose value is below it.
_UNIT = 1.0
#: A ridge: parameters correlated beyond this (in absolute value) are each loosely
#: determined along it, and the fit names the combination across it that the data measure
#: (:func:`_ridges`), with the eigenvectors of their unit-diagonal covariance whose
#: variance is at most RIDGE_REL of the largest (σ at most a tenth of the ridge's).
RIDGE_CORR = 0.99
RIDGE_REL = 0.01


class Identified(NamedTuple):
    """Covariance (inf on the diagonal of a parameter the data do not act on or that takes
    part in a null direction, NaN beside it; weakly determined ones keep their finite σ),
    per-parameter True or the reason, the determined combinations as (coefficients, σ)
    pairs, and the generalised inverse D S⁺ D over the parameters the data act on (NaN on
    the others' rows and columns), null directions included."""

    covariance: np.ndarray
    reasons: list
    combinations: list
    generalised: np.ndarray


def _scales(params, x, floor=1e-12):
    """Each parameter's range: its bounds' width, or (unbounded) its value, at least
    ``floor``."""
    return np.array([p.high - p.low if math.isfinite(p.high - p.low) else
                     max(abs(v), floor) for p, v in zip(params, x)])


def _uncertainty(fisher, x, params, label):
    """Identified from the Fisher matrix ``fisher`` (user parameters) at ``x``; ``label(i)``
    names parameter i."""
    n = len(params)
    fisher = 0.5 * (fisher + fisher.T)
    width = _scales(params, x)
    # the data's dependence over the range; an unbounded parameter at 0 on a unit scale
    # (its value's scale would make any effect vanish)
    effect = np.diag(fisher) * _scales(params, x, floor=_UNIT) ** 2
    reasons = [True] * n
    top = float(effect.max(initial=0.0))
    for i in range(n):
        if not effect[i] > _DEAD * max(top, 1e-300):
            reasons[i] = "the data do not depend on it"
    live = [i for i in range(n) if reasons[i] is True]
    cov = np.full((n, n), np.nan)
    combinations = []
    involved = np.zeros(len(live), bool)
    if live:
        d = 1.0 / np.sqrt(np.diag(fisher)[live])
        lam, vec = np.linalg.eigh(fisher[np.ix_(live, live)] * np.outer(d, d))
        null = lam <= NULL_REL * lam[-1]
        inv = (vec[:, ~null] / lam[~null]) @ vec[:, ~null].T
        sub = inv * np.outer(d, d)                         # D S⁺ D, user units
        cov[np.ix_(live, live)] = sub
        if null.any():
            involved = np.any(np.abs(vec[:, null]) > _SHARE, axis=1)
            combinations = _combinations(vec[:, null] * d[:, None], involved, sub)
            names = " and ".join(label(live[a]) for a in np.flatnonzero(involved))
            for a in np.flatnonzero(involved):
                reasons[live[a]] = f"the data determine only a combination of {names}"
        _loose_ones(reasons, live, involved, (sub, width, x), (params, label))
        combinations += _ridges(sub, involved)
        combinations = [(_widened(c, live, n), s) for c, s in combinations]
    generalised = cov.copy()
    unknown = [i for i in range(n) if i not in live]
    unknown += [i for a, i in enumerate(live) if involved[a]]
    for i in unknown:
        cov[i, :] = cov[:, i] = np.nan
        cov[i, i] = math.inf
    return Identified(cov, reasons, combinations, generalised)


def _combinations(null_user, involved, sub):
    """Determined combinations: an orthonormal basis of the involved parameters' space
    less the null directions (in user units), each scaled to a largest coefficient of 1,
    with its σ from the generalised inverse ``sub``."""
    idx = np.flatnonzero(involved)
    N = null_user[idx]                                     # (p, m)
    q, _ = np.linalg.qr(N, mode="complete")
    basis = q[:, np.linalg.matrix_rank(N):]
    out = []
    for c in basis.T:
        c = c / c[np.argmax(np.abs(c))]
        full = np.zeros(len(involved))
        full[idx] = c
        out.append((full, math.sqrt(max(float(full @ sub @ full), 0.0))))
    return out


def _ridges(sub, involved):
    """The best-determined combinations along ridges: groups of parameters (outside the
    null directions) linked by correlations beyond :data:`RIDGE_CORR`; in each group's
    unit-diagonal covariance, the eigenvectors whose variance is at most
    :data:`RIDGE_REL` of the largest, in user units (scaled to a largest coefficient of
    1), with their σ from ``sub``. Along such a ridge the parameters are each loosely
    determined and their estimates skewed, while these combinations stay well measured."""
    sd = np.sqrt(np.maximum(np.diag(sub), 0.0))
    ok = (sd > 0) & ~involved
    safe = np.where(ok, sd, 1.0)
    linked = (np.abs(sub / np.outer(safe, safe)) > RIDGE_CORR) & np.outer(ok, ok)
    group = np.arange(len(sd))
    for a, b in zip(*np.nonzero(np.triu(linked, 1))):          # union of linked pairs
        group[group == group[b]] = group[a]
    out = []
    for g in np.unique(group):
        idx = np.flatnonzero(group == g)
        if len(idx) < 2:
            continue
        block = sub[np.ix_(idx, idx)] / np.outer(sd[idx], sd[idx])
        lam, vec = np.linalg.eigh(block)
        for k in np.flatnonzero(lam <= RIDGE_REL * lam[-1]):
            c = vec[:, k] / sd[idx]
            full = np.zeros(len(sd))
            full[idx] = c / c[np.argmax(np.abs(c))]
            out.append((full, math.sqrt(max(float(full @ sub @ full), 0.0))))
    return out


def _widened(coefficients, live, n):
    """A combination's coefficients over the live parameters, over all ``n``."""
    full = np.zeros(n)
    full[live] = coefficients
    return full


def _loose_ones(reasons, live, involved, at, named):
    """Mark, among the determined live parameters, those whose σ exceeds half their range
    (or, non-negative or unbounded, half their value), and both of a pair that trade off
    beyond _CORR_LIMIT where either is loose (σ beyond _LOOSE of its value, or of its
    bounds' width where it may be negative): the loose one's skew carries along the ridge
    to the other, however small the other's σ."""
    sub, width, x = at
    params, label = named
    sd = np.sqrt(np.maximum(np.diag(sub), 0.0))
    # a σ is weighed against the value where the parameter is non-negative or unbounded,
    # else against its bounds' width
    by_value = [params[i].low >= 0.0 or not math.isfinite(width[i]) for i in live]
    for a, i in enumerate(live):
        bounded = math.isfinite(params[i].high - params[i].low)
        if not involved[a] and bounded and sd[a] > _REL_LIMIT * width[i]:
            reasons[i] = f"its uncertainty ({sd[a]:.3g}) exceeds half its range"
        elif not involved[a] and by_value[a] and sd[a] > _REL_LIMIT * abs(x[i]):
            reasons[i] = (f"its uncertainty ({sd[a]:.3g}) exceeds half its value "
                          f"({x[i]:.3g})")
    safe = np.where(sd > 0, sd, 1.0)
    corr = sub / np.outer(safe, safe)
    loose = [sd[a] > _LOOSE * max(abs(x[i]) if by_value[a] else width[i], 1e-12)
             for a, i in enumerate(live)]
    for a, i in enumerate(live):
        for b, j in enumerate(live):
            # a pair on a ridge with a loose member: both estimates move along it together
            if (i < j and not (involved[a] or involved[b]) and abs(corr[a, b]) > _CORR_LIMIT
                    and (loose[a] or loose[b])):
                for k, other in ((i, j), (j, i)):
                    if reasons[k] is True:
                        reasons[k] = (f"it trades off with {label(other)} (correlation "
                                      f"{corr[a, b]:+.4f})")


def describe(coefficients, labels):
    """'a + 0.5·b − c' from coefficients and labels (zeros left out)."""
    terms = []
    for c, name in zip(coefficients, labels):
        if c == 0:
            continue
        mag = abs(c)
        body = name if abs(mag - 1.0) < 1e-9 else f"{mag:.4g}·{name}"
        terms.append(("−" if c < 0 else "+", body))
    if not terms:
        return "0"
    text = ("−" if terms[0][0] == "−" else "") + terms[0][1]
    return text + "".join(f" {s} {b}" for s, b in terms[1:])


class Misfit(NamedTuple):
    """The misfit at the estimate and the Fisher information it implies."""

    misfit: float
    dof: int
    fisher: np.ndarray
    sigma2: float


def unit_deviance(y, m, M=None):
    """Each bin's count deviance of counts ``y`` against means ``m``: 2 [y ln(y/m) − (y − m)]
    for Poisson and 2 [y ln(y/m) − (y + M) ln((y + M)/(m + M))] for the negative binomial
    of M cells (y ln y = 0 at y = 0; means floored at 1e-300; never below 0)."""
    y = np.asarray(y, float)
    m = np.maximum(np.asarray(m, float), 1e-300)
    pos = y > 0
    ylog = np.zeros_like(y)
    ylog[pos] = y[pos] * np.log(y[pos] / m[pos])
    if M is None:
        return np.maximum(2.0 * (ylog - (y - m)), 0.0)
    return np.maximum(2.0 * (ylog - (y + M) * np.log((y + M) / (m + M))), 0.0)


def deviance(y, m, M=None):
    """The count deviance of counts ``y`` against means ``m``: twice the log-likelihood
    ratio of the saturated model, the sum of :func:`unit_deviance`."""
    return float(np.sum(unit_deviance(y, m, M)))


def _misfit(problem, m, V, J):
    """χ² (Gaussian, σ² from the residuals) or the count deviance, its degrees of freedom
    and the Fisher information at the estimate (model values ``m``, variances ``V``,
    Jacobian ``J`` on the fitted rows)."""
    data, fixed = problem.data, problem.fixed
    y_all, fixed_all = problem.y_all, problem.fixed_all
    n = len(problem.params)
    if problem.noise == "gaussian":
        # σ² from every bin: those no fitted part reaches hold noise (about the fixed
        # parts) too
        outside = float(np.sum((y_all - fixed_all) ** 2)) - float(np.sum((data - fixed) ** 2))
        rss = float(np.sum((data - m) ** 2)) + max(outside, 0.0)
        dof = max(1, y_all.size - n)
        # exact data: σ at rounding of the data's scale, not 0
        sigma2 = max(rss / dof, (1e-12 * float(np.abs(y_all).max(initial=1.0))) ** 2)
        misfit = rss / sigma2
        fisher = (J.T @ J) / sigma2
    else:
        sigma2 = None
        dof = max(1, data.size - n)
        misfit = deviance(data, m, problem.M)
        fisher = J.T @ (J / V[:, None])
    return Misfit(misfit, dof, fisher, sigma2)


def _correlation(cov):
    """(standard errors, correlation matrix) of a covariance (NaN where undetermined)."""
    diag = np.diag(cov)
    stderr = np.sqrt(np.where(np.isfinite(diag), np.maximum(diag, 0.0), np.inf))
    d = np.where((stderr > 0) & np.isfinite(stderr), stderr, np.nan)
    with np.errstate(invalid="ignore"):
        return stderr, cov / np.outer(d, d)
