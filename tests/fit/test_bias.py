"""The first-order (Cox-Snell) bias of a maximum-likelihood estimate (meshladar.fit._bias)
against closed forms: Poisson counts whose mean is c_i/θ (the estimate Σc/Σy, its bias θ/N
to order 1/N, N = Σ c_i/θ), Gaussian data about a·exp(θ) (the estimate log(ȳ/a), its bias
the delta method's −σ²/(2 n a² exp(2θ))), a mean linear in its parameters (no bias) and the
same in log α (the delta method's −Var(α̂)/(2α²)), an undetermined parameter, a model
valid on one side of the estimate only; against Cox and Snell's sum written out with
analytic derivatives and expectations over the data's distribution (three correlated
parameters with a full Hessian, for Poisson, negative binomial and Gaussian data; a
parameter beside a null direction); a curvature that changes within the steps (NaN); a
fit's own field on a linear and a nonlinear coating parameter; and the report's line of
notable biases, on a user's coating whose estimate is the log of a Poisson mean."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy import stats

import meshladar as ml
from meshladar.brdf import BRDF, Lambertian, SandfordRobertson
from meshladar.fit import NOTED_BIAS, fit_coatings
from meshladar.fit._bias import first_order
from meshladar.ladar import Ladar
from meshladar.scene import Scene
from meshladar.shapes import Disk

#: Relative tolerance of a second difference at STEP = 0.1 σ on smooth closed forms
#: (its truncation error is ~(0.1 σ)² of the fourth derivative; round-off far below).
REL = 1e-3


def _fisher_parts(J, w):
    F = J.T @ (w[:, None] * J)
    return np.linalg.inv(F)


def test_the_reciprocal_of_a_poisson_rate():
    """μ_i = c_i/θ: J = −c/θ², H = 2c/θ³, W = θ/c, F = N/θ², so b = θ/N exactly at first
    order (E[Σc/Y] with Y ~ Poisson(N) is θ (1 + 1/N + ...))."""
    c = np.array([40.0, 25.0, 10.0, 5.0])
    theta = np.array([0.5])
    values = lambda x: c / x[0] if x[0] > 0 else None
    m = values(theta)
    J = (-c / theta[0] ** 2)[:, None]
    w = 1.0 / m
    b = first_order(values, theta, J, w, _fisher_parts(J, w))
    n = m.sum()
    assert b[0] == pytest.approx(theta[0] / n, rel=REL)


def test_the_exponential_mean_of_gaussian_data():
    """Gaussian data of σ² about m_i = a exp(θ) (one parameter, rows alike): the MLE is
    log(ȳ/a), whose bias to first order is −σ²/(2 n a² exp(2θ)) (the delta method's second
    term for the logarithm); the formula gives the same."""
    a, sigma2, theta, n = 3.0, 0.04, 0.2, 12
    values = lambda x: np.full(n, a * np.exp(x[0]))
    J = np.full((n, 1), a * np.exp(theta))
    w = np.full(n, 1.0 / sigma2)
    b = first_order(values, np.array([theta]), J, w, _fisher_parts(J, w))
    assert b[0] == pytest.approx(-sigma2 / (2 * n * a * a * np.exp(2 * theta)), rel=REL)


def test_two_parameters_with_a_correlation():
    """Poisson data of mean μ_i = α t_i + β t_i² (no curvature): no bias; the same rates in
    parameters (log α, β): the bias of log α̂ is the delta method's −Var(α̂)/(2α²)
    (E[log α̂] ≈ log α − Var(α̂)/(2α²), α̂ unbiased to this order), β's none."""
    t = np.linspace(0.5, 2.0, 9)
    alpha, beta = 30.0, 12.0
    lin = lambda x: x[0] * t + x[1] * t * t
    J = np.c_[t, t * t]
    w = 1.0 / lin([alpha, beta])
    C = _fisher_parts(J, w)
    b = first_order(lin, np.array([alpha, beta]), J, w, C)
    assert np.abs(b).max() < 1e-9 * alpha
    logged = lambda x: np.exp(x[0]) * t + x[1] * t * t
    Jl = np.c_[alpha * t, t * t]
    Cl = _fisher_parts(Jl, w)
    bl = first_order(logged, np.array([np.log(alpha), beta]), Jl, w, Cl)
    assert bl[0] == pytest.approx(-0.5 * C[0, 0] / alpha ** 2, rel=REL)
    assert abs(bl[1]) < 1e-6 * np.sqrt(C[1, 1])


def test_a_parameter_without_sigma_gets_no_bias():
    """A parameter the covariance does not determine (inf on its diagonal) gets NaN; the
    others their bias as if it were fixed."""
    c = np.array([40.0, 25.0, 10.0])
    values = lambda x: c / x[0]
    J = np.c_[-c / 0.25, np.zeros(3)]
    w = 0.5 / c
    C = np.array([[0.5 ** 3 / c.sum(), np.nan], [np.nan, np.inf]])
    b = first_order(values, np.array([0.5, 1.0]), J, w, C)
    assert np.isnan(b[1]) and b[0] == pytest.approx(0.5 / (c.sum() / 0.5), rel=REL)


def test_a_model_invalid_on_one_side_takes_the_other():
    """Where the step below the estimate leaves the valid set, the one-sided second
    difference gives the reciprocal's bias to its first-order accuracy."""
    c = np.array([40.0, 25.0])
    theta = 0.5
    values = lambda x: c / x[0] if x[0] >= theta else None
    J = (-c / theta ** 2)[:, None]
    w = theta / c
    b = first_order(values, np.array([theta]), J, w, _fisher_parts(J, w))
    n = c.sum() / theta
    assert b[0] == pytest.approx(theta / n, rel=0.05)


#: A mean linear in the parameter leaves a second difference of round-off only: at 10⁵
#: counts and steps of 0.1 σ, ~1e-16 · 10⁵ / (0.1 σ)² in d, far below this share of σ.
LINEAR_TOL = 1e-6


def test_a_fit_linear_in_its_parameter_has_no_bias():
    """A Lambertian disk's albedo scales the data, so its Poisson estimate Σy/Σa is
    unbiased exactly: ``fit.bias`` is 0 to round-off and ``fit.corrected`` the estimate;
    a glinting SR coating's width e, which the data depend on nonlinearly, gets a finite,
    nonzero bias below its σ (10⁵ photoelectrons)."""
    lad = Ladar(np.arange(0.0, 360.0, 10.0), Ladar.centered(48, 1.4 / 48).bin_edges)
    for brdf in (Lambertian(0.3), SandfordRobertson(0.1, 0.4, 0.2, 0.02)):
        scene = Scene([Disk((0.0, 0.0), 0.5, brdf, name="disk")])
        exact = ml.simulate(scene, lad, model="analytic").values
        k = 1e5 / exact.max()
        y = np.random.default_rng(3).poisson(exact * k) / k
        measured = ml.Sinogram(y, angles_deg=lad.angles_deg, bin_edges=lad.bin_edges,
                               info={"radiometry": "paper"})
        fit = fit_coatings(scene, measured, noise="poisson", photons_per_unit=k)
        if isinstance(brdf, Lambertian):
            assert abs(fit.bias[0]) < LINEAR_TOL * fit.stderr[0]
            assert fit.corrected[0] == pytest.approx(fit.estimate[0], abs=LINEAR_TOL
                                                     * fit.stderr[0])
        else:
            i = fit.names.index("disk.e")
            assert 0.0 < abs(fit.bias[i]) < fit.stderr[i]
            assert fit.corrected[i] == fit.estimate[i] - fit.bias[i]


def _cox_snell(mu, jac, hess, third, theta, noise):
    """Cox and Snell's bias Σ I^{sr} I^{tu} (κ_{rt,u} + ½ κ_{rtu}) written out, each κ an
    expectation summed over the data's distribution (Poisson, negative binomial of
    ``noise`` cells, or Gaussian of variance 0.5) with the model's analytic derivatives:
    no use of the simplified form under test."""
    m, J, H, T = mu(theta), jac(theta), hess(theta), third(theta)
    n = theta.size
    info, k2, k3 = np.zeros((n, n)), np.zeros((n, n, n)), np.zeros((n, n, n))
    for i in range(m.size):
        if noise == "gaussian":
            ys = np.linspace(m[i] - 12.0, m[i] + 12.0, 4001)
            p = stats.norm.pdf(ys, m[i], np.sqrt(0.5))
            l1, l2, l3 = (ys - m[i]) / 0.5, np.full(ys.size, -2.0), np.zeros(ys.size)
        else:
            ys = np.arange(0.0, 2000.0)
            if noise is None:
                p = stats.poisson.pmf(ys, m[i])
                l1, l2, l3 = ys / m[i] - 1, -ys / m[i] ** 2, 2 * ys / m[i] ** 3
            else:
                M = noise
                p = stats.nbinom.pmf(ys, M, M / (M + m[i]))
                l1 = ys / m[i] - (ys + M) / (m[i] + M)
                l2 = -ys / m[i] ** 2 + (ys + M) / (m[i] + M) ** 2
                l3 = 2 * ys / m[i] ** 3 - 2 * (ys + M) / (m[i] + M) ** 3
        p = p / p.sum()
        j, h, t3 = J[i], H[i], T[i]
        u1 = l1[:, None] * j
        u2 = l2[:, None, None] * np.outer(j, j) + l1[:, None, None] * h
        sym = (np.einsum("ru,t->rtu", h, j) + np.einsum("r,tu->rtu", j, h)
               + np.einsum("rt,u->rtu", h, j))
        u3 = (l3[:, None, None, None] * np.einsum("r,t,u->rtu", j, j, j)
              + l2[:, None, None, None] * sym + l1[:, None, None, None] * t3)
        info += np.einsum("y,yr,yt->rt", p, u1, u1)
        k2 += np.einsum("y,yrt,yu->rtu", p, u2, u1)
        k3 += np.einsum("y,yrtu->rtu", p, u3)
    inv = np.linalg.inv(info)
    return np.einsum("sr,tu,rtu->s", inv, inv, k2 + 0.5 * k3)


#: The written-out expectations' own error (the Gaussian's sum over 4001 points, the
#: counts' truncated at 2000) against the second differences' truncation at 0.1 σ.
EXACT_REL = 2e-3


@pytest.mark.parametrize("noise", [None, 3.0, "gaussian"])
def test_three_correlated_parameters_with_cross_curvature(noise):
    """μ_i = c_i + exp(X_i θ), three correlated parameters whose Hessian is full: the bias
    equals Cox and Snell's written out (_cox_snell) for Poisson, negative binomial (M = 3)
    and Gaussian data."""
    t = np.linspace(-1.0, 1.0, 15)
    X = np.c_[np.ones_like(t), t, t * t]
    c = 2.0 + 3.0 * t ** 2
    theta = np.array([np.log(12.0), 0.8, -0.6])
    mu = lambda th: c + np.exp(X @ th)
    jac = lambda th: np.exp(X @ th)[:, None] * X
    hess = lambda th: np.exp(X @ th)[:, None, None] * X[:, :, None] * X[:, None, :]
    third = lambda th: hess(th)[..., None] * X[:, None, None, :]
    m = mu(theta)
    w = (np.full(m.size, 2.0) if noise == "gaussian"
         else 1.0 / (m + (0.0 if noise is None else m * m / noise)))
    J = jac(theta)
    b = first_order(mu, theta, J, w, _fisher_parts(J, w))
    exact = _cox_snell(mu, jac, hess, third, theta, noise)
    assert np.allclose(b, exact, rtol=EXACT_REL, atol=0.0), (b, exact)


def test_beside_a_null_direction_the_combination_is_free():
    """μ = 20 exp(θ0 + θ1 + θ2 t): the data see θ0 + θ1 only. With the generalised inverse
    (as the fit passes it) θ2's bias is that of the model in (s = θ0 + θ1, θ2) written out;
    θ0 and θ1 get none (not determined)."""
    t = np.linspace(0.2, 2.0, 12)
    x = np.array([0.1, 0.2, -0.7])
    mu = lambda z: 20.0 * np.exp(z[0] + z[1] + z[2] * t)
    m = mu(x)
    w = 1.0 / m
    J = m[:, None] * np.c_[np.ones_like(t), np.ones_like(t), t]
    generalised = np.linalg.pinv(J.T @ (w[:, None] * J))
    b = first_order(mu, x, J, w, generalised, determined=[False, False, True])
    A = np.c_[np.ones_like(t), t]
    mu2 = lambda z: 20.0 * np.exp(A @ z)
    jac2 = lambda z: mu2(z)[:, None] * A
    hess2 = lambda z: jac2(z)[:, :, None] * A[:, None, :]
    third2 = lambda z: hess2(z)[..., None] * A[:, None, None, :]
    exact = _cox_snell(mu2, jac2, hess2, third2, np.array([0.3, -0.7]), None)
    assert np.isnan(b[:2]).all()
    assert b[2] == pytest.approx(exact[1], rel=EXACT_REL)


def test_a_curvature_that_changes_within_the_steps_gives_no_bias():
    """μ_i = a_i (1 + θ) + K (θ − θ̂)⁴: the second difference is 2 K h² at h and 8 K h² at
    2h, so with K large the two steps disagree beyond AGREE σ and the bias is NaN; with
    K = 0 it is 0."""
    a = np.array([30.0, 20.0, 10.0])
    x = np.array([0.5])
    for K, finite in ((0.0, True), (1e9, False)):
        mu = lambda z, K=K: a * (1.0 + z[0]) + K * (z[0] - x[0]) ** 4
        J = a[:, None]
        w = 1.0 / mu(x)
        b = first_order(mu, x, J, w, _fisher_parts(J, w))
        assert np.isfinite(b[0]) == finite
        if finite:
            assert abs(b[0]) < 1e-9


@dataclasses.dataclass(frozen=True)
class _LogLambert(BRDF):
    """A user's model: a Lambertian coating of albedo exp(log_albedo)."""

    log_albedo: float

    def projected(self, cos_theta, sin_theta):
        return math.exp(self.log_albedo) * np.maximum(cos_theta, 0.0) / math.pi


@dataclasses.dataclass(frozen=True)
class _MinusLogLambert(BRDF):
    """The same with albedo exp(−minus_log_albedo): its estimate's bias has the other sign."""

    minus_log_albedo: float

    def projected(self, cos_theta, sin_theta):
        return math.exp(-self.minus_log_albedo) * np.maximum(cos_theta, 0.0) / math.pi


@pytest.mark.parametrize("coating, sign", [(_LogLambert(math.log(0.5)), -1),
                                           (_MinusLogLambert(-math.log(0.5)), 1)])
@pytest.mark.parametrize("total, listed", [(16, True), (400, False)])
def test_the_report_names_a_bias_from_a_tenth_of_sigma(coating, sign, total, listed):
    """A user's coating of albedo exp(±θ) under Poisson counts: the estimate matches the
    counts' total N, so its σ is 1/√N and its first-order bias, that of ∓ the log of a
    Poisson mean, ∓1/(2N): ∓1/(2√N) σ (closed form). With about 16 counts in all that is
    about ∓0.125 σ, and the report names it (seed 5: 15 counts, −0.13 σ for exp(θ), the
    coatings guide's example); with about 400, ∓0.025 σ, below NOTED_BIAS, it names
    none."""
    lad = Ladar(np.arange(0.0, 360.0, 10.0), Ladar.centered(48, 1.4 / 48).bin_edges)
    scene = Scene([Disk((0.0, 0.0), 0.5, coating, name="disk")])
    exact = ml.simulate(scene, lad, model="analytic").values
    k = total / exact.sum()
    y = np.random.default_rng(5).poisson(exact * k)
    measured = ml.Sinogram(y / k, angles_deg=lad.angles_deg, bin_edges=lad.bin_edges,
                           info={"radiometry": "paper"})
    name, = (f.name for f in dataclasses.fields(coating))
    fit = fit_coatings(scene, measured, noise="poisson", photons_per_unit=k,
                       bounds={name: (-10.0, 10.0)})
    n = y.sum()
    assert fit.stderr[0] == pytest.approx(1.0 / math.sqrt(n), rel=REL)
    assert fit.bias[0] / fit.stderr[0] == pytest.approx(sign * 0.5 / math.sqrt(n), rel=REL)
    line = [s for s in fit.report() if "first-order bias" in s]
    assert (0.5 / math.sqrt(n) >= NOTED_BIAS) == listed
    if listed:                                     # the coatings guide's example, and its sign
        assert n == 15 and line == [f"  first-order bias: disk.{name} {'-+'[sign > 0]}0.13 σ "
                                    "(fit.corrected subtracts it)"]
        assert f"first-order bias='disk.{name} {'-+'[sign > 0]}0.13 σ'" in repr(fit)
        assert f"disk.{name} {'-+'[sign > 0]}0.13 σ" in fit._repr_html_()
    else:
        assert line == []
        assert "first-order bias" not in repr(fit) + fit._repr_html_()
