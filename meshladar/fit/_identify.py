"""Identifiability of a coating fit: the covariance from the Fisher information, and which
parameters the data cannot determine (no effect on the data, an uncertainty beyond their
range, or a near-perfect correlation with another)."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

#: A parameter is called undetermined when its standard error exceeds this share of its
#: bounds' width (or of its value where unbounded), or when it is correlated beyond
#: _CORR_LIMIT with another and its standard error exceeds _LOOSE of its value.
_REL_LIMIT = 0.5
_CORR_LIMIT = 0.995
_LOOSE = 0.25


def _uncertainty(fisher, x, params, kernel):
    """(covariance, per-parameter True or the reason it is undetermined)."""
    n = len(params)
    width = np.array([p.high - p.low if math.isfinite(p.high - p.low) else
                      max(abs(v), 1e-12) for p, v in zip(params, x)])
    scaled = fisher * np.outer(width, width)
    reasons = [True] * n
    diag = np.diag(scaled)
    top = float(diag.max(initial=0.0))
    for i in range(n):
        if diag[i] <= 1e-14 * max(top, 1e-300):
            reasons[i] = "the data do not depend on it"
    live = [i for i in range(n) if reasons[i] is True]
    cov = np.full((n, n), 0.0)
    for i in range(n):
        if reasons[i] is not True:
            cov[i, i] = math.inf
    if live:
        sub = scaled[np.ix_(live, live)]
        try:
            inv = np.linalg.inv(sub)
            if not np.all(np.isfinite(inv)):
                raise np.linalg.LinAlgError
        except np.linalg.LinAlgError:
            inv = np.linalg.pinv(sub)
        cov[np.ix_(live, live)] = inv / np.outer(width[live], width[live])
        sd = np.sqrt(np.maximum(np.diag(inv), 0.0))
        for a, i in enumerate(live):
            if sd[a] > _REL_LIMIT:
                reasons[i] = (f"its uncertainty ({sd[a] * width[i]:.3g}) exceeds half its "
                              f"range")
        corr = inv / np.outer(np.where(sd > 0, sd, 1), np.where(sd > 0, sd, 1))
        loose = {i: sd[a] * width[i] > _LOOSE * max(abs(x[i]), 1e-12)
                 for a, i in enumerate(live)}
        for a, i in enumerate(live):
            for b_, j in enumerate(live):
                if i < j and abs(corr[a, b_]) > _CORR_LIMIT:
                    for k, other in ((i, j), (j, i)):
                        if reasons[k] is True and loose[k]:
                            reasons[k] = (f"it trades off with "
                                          f"{kernel.parts[params[other].part]}."
                                          f"{params[other].name} (correlation "
                                          f"{corr[a, b_]:+.4f})")
    return cov, reasons


class Misfit(NamedTuple):
    """The misfit at the estimate and the Fisher information it implies."""

    misfit: float
    dof: int
    fisher: np.ndarray
    sigma2: float


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
        misfit = float(np.sum((data - m) ** 2 / V))
        fisher = J.T @ (J / V[:, None])
    return Misfit(misfit, dof, fisher, sigma2)


def _correlation(cov):
    """(standard errors, correlation matrix) of a covariance (NaN where undetermined)."""
    stderr = np.sqrt(np.maximum(np.diag(cov), 0.0))
    d = np.where((stderr > 0) & np.isfinite(stderr), stderr, 1.0)
    return stderr, np.where(np.isfinite(cov), cov, np.nan) / np.outer(d, d)
