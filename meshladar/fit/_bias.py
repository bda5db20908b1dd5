"""The first-order bias of a coating fit's maximum-likelihood estimate (Cox and Snell).

For independent data whose distribution is a one-parameter exponential family in its mean
m_i(θ) (Gaussian with known σ², Poisson, negative binomial of known M), with weights
w_i = 1/Var(y_i) and Fisher information F = Jᵀ W J, the estimate's bias to order 1/F is

    b = −½ C Jᵀ W d,    d_i = tr(C H_i),    C = F⁻¹,

H_i the Hessian of m_i in the parameters: the terms in the variance function's derivative
cancel, so the bias comes from the curvature of the model alone (for Gaussian noise this is
Box's nonlinear-regression bias). tr(C H_i) is summed over C's principal axes, each a
central second difference of the model (one-sided where a step leaves the coatings' valid
set), at steps of STEP and 2 STEP of the axis's σ: where the two biases differ by more than
AGREE σ the expansion does not hold and the bias is NaN. Undetermined parameters (a null
direction of the Fisher matrix) take part through the generalised inverse, as a
reparametrisation to the determined combinations would. The estimate less b, θ̂ − b(θ̂),
is the bias-corrected estimate.

References
----------
D. R. Cox and E. J. Snell, "A general definition of residuals", J. R. Stat. Soc. B 30,
248-275 (1968); M. J. Box, "Bias in nonlinear estimation", J. R. Stat. Soc. B 33, 171-201
(1971); G. M. Cordeiro and P. McCullagh, "Bias correction in generalized linear models",
J. R. Stat. Soc. B 53, 629-643 (1991).
"""

from __future__ import annotations

import numpy as np

__all__ = ["first_order"]

#: The second differences' step along each principal axis of C, in that axis's σ.
STEP = 0.1
#: The bias is computed at steps of STEP and 2 STEP; where they differ by more than this
#: share of σ, the model's curvature changes within a few tenths of σ, the expansion the
#: bias comes from does not hold, and the bias is NaN.
AGREE = 0.05
#: Steps tried (each a tenth of the last) before an axis whose neighbourhood is outside the
#: coatings' valid set on both sides leaves the bias unknown.
TRIES = 3


def first_order(values, x, J, w, generalised, determined=None):
    """The first-order bias b of the estimate ``x``: NaN on a parameter not ``determined``,
    and wherever the model cannot be evaluated around ``x`` or steps of STEP and 2 STEP
    disagree by more than AGREE σ.

    Parameters
    ----------
    values : callable
        The model's values at parameters (None where the coatings are invalid).
    x : (n,) array
        The estimate.
    J : (rows, n) array
        The model's Jacobian at ``x``.
    w : (rows,) array
        The inverse variance of each datum.
    generalised : (n, n) array
        The inverse Fisher information, or its generalised inverse over the parameters the
        data act on (NaN on the others), null directions included: a determined
        parameter's bias holds the undetermined ones free along the determined
        combinations, as a reparametrisation to those combinations would.
    determined : (n,) bool array, optional
        The parameters whose bias is wanted (default: those with a finite diagonal).

    Returns
    -------
    (n,) array
    """
    n = x.size
    live = np.flatnonzero(np.isfinite(np.diag(generalised)))
    wanted = np.zeros(n, bool)
    wanted[live] = True
    if determined is not None:
        wanted &= np.asarray(determined, bool)
    bias = np.full(n, np.nan)
    if not wanted.any():
        return bias
    C = generalised[np.ix_(live, live)]
    sd = np.sqrt(np.maximum(np.diag(C), 1e-300))
    lam, vec = np.linalg.eigh(C / np.outer(sd, sd))
    axes = []
    for k in np.flatnonzero(lam > 0.0):
        axis = np.zeros(n)
        axis[live] = sd * vec[:, k]
        axes.append((lam[k], axis))
    m0 = values(x)
    fine, coarse = (_traces(values, x, m0, axes, step) for step in (STEP, 2 * STEP))
    if fine is None or coarse is None:
        return bias
    b = -0.5 * C @ (J[:, live].T @ (w[:, None] * np.vstack([fine, coarse]).T))
    bias[live] = np.where(np.abs(b[:, 0] - b[:, 1]) <= AGREE * sd, b[:, 0], np.nan)
    bias[~wanted] = np.nan
    return bias


def _traces(values, x, m0, axes, step):
    """d_i = tr(C H_i), C = Σ λ a aᵀ over its principal ``axes`` (λ, a), from second
    differences at ``step`` of each axis's σ (None where an axis cannot be evaluated)."""
    d = np.zeros_like(m0)
    for lam, axis in axes:
        curve = _second_difference(values, x, m0, axis, step * np.sqrt(lam))
        if curve is None:
            return None
        d += lam * curve
    return d


def _second_difference(values, x, m0, axis, h):
    """The model's second derivative along ``axis`` at ``x`` (steps ``h``): central, or
    one-sided where one side is invalid; None where no step of TRIES makes one."""
    for _ in range(TRIES):
        up, down = values(x + h * axis), values(x - h * axis)
        if up is not None and down is not None:
            return (up - 2.0 * m0 + down) / (h * h)
        side = 1.0 if up is not None else -1.0
        first = up if up is not None else down
        second = values(x + 2.0 * side * h * axis) if first is not None else None
        if second is not None:
            return (second - 2.0 * first + m0) / (h * h)
        h *= 0.1
    return None
