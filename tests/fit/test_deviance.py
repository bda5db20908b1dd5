"""The count fits' misfit is the deviance (twice the log-likelihood ratio against the
saturated model), checked against scipy's own probability mass functions; before, the
Poisson fit reported Pearson's X² under that name."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

import meshladar as ml
from meshladar.fit import fit_coatings
from meshladar.fit._identify import deviance

#: Agreement of two sums of ~100 log-probabilities.
TOL = 1e-9


def _counts():
    rng = np.random.default_rng(7)
    m = rng.uniform(0.05, 40.0, 100)
    return rng.poisson(m).astype(float), m


def test_poisson_deviance_is_twice_the_log_likelihood_ratio():
    y, m = _counts()
    expected = 2.0 * np.sum(stats.poisson.logpmf(y, y) - stats.poisson.logpmf(y, m))
    assert deviance(y, m) == pytest.approx(expected, rel=TOL)


def test_negative_binomial_deviance_is_twice_the_log_likelihood_ratio():
    y, m = _counts()
    M = 3.0                           # variance m + m²/M: scipy's nbinom(n=M, p=M/(M+m))
    logpmf = lambda mean: stats.nbinom.logpmf(y, M, M / (M + mean))  # noqa: E731
    assert deviance(y, m, M) == pytest.approx(2.0 * np.sum(logpmf(y) - logpmf(m)), rel=TOL)


def test_a_poisson_fit_reports_the_deviance_of_its_prediction():
    """The fit's misfit is the deviance of its own predicted counts (not X²)."""
    disk = ml.Disk((0.0, 0.0), 0.5, ml.brdf.SandfordRobertson(0.3, 0.0, 0.4, 1.0,
                                                                lobes="diffuse"), name="d")
    ladar = ml.Ladar(np.arange(0.0, 360.0, 30.0), ml.Ladar.centered(32, 1.4 / 32).bin_edges)
    exact = ml.simulate(ml.Scene([disk]), ladar, model="analytic")
    k = 200.0 / exact.values.max()
    y = np.random.default_rng(1).poisson(exact.values * k)
    measured = ml.Sinogram(y / k, angles_deg=ladar.angles_deg, bin_edges=ladar.bin_edges,
                           info={"radiometry": "paper"})
    fit = fit_coatings(ml.Scene([disk]), measured, noise="poisson", photons_per_unit=k)
    mu = fit.predicted * k
    reached = mu > 0
    expected = 2.0 * np.sum(stats.poisson.logpmf(y[reached], y[reached])
                            - stats.poisson.logpmf(y[reached], mu[reached]))
    assert fit.deviance == pytest.approx(expected, rel=1e-6)
    pearson = float(np.sum((y[reached] - mu[reached]) ** 2 / mu[reached]))
    assert abs(fit.deviance - pearson) > 1e-3 * pearson
