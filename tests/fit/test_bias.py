"""The first-order (Cox-Snell) bias of a maximum-likelihood estimate (meshladar.fit._bias)
against closed forms: Poisson counts whose mean is c_i/θ (the estimate Σc/Σy, its bias θ/N
to order 1/N, N = Σ c_i/θ), Gaussian data about a·exp(θ) (the estimate log(ȳ/a), its bias
the delta method's −σ²/(2 n a² exp(2θ))), a mean linear in its parameters (no bias) and the
same in log α (the delta method's −Var(α̂)/(2α²)), an undetermined parameter, and a model
valid on one side of the estimate only."""

from __future__ import annotations

import numpy as np
import pytest

import meshladar as ml
from meshladar.brdf import Lambertian, SandfordRobertson
from meshladar.fit import fit_coatings
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
