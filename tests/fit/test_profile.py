"""Profile-likelihood intervals of coating fits (``CoatingFit.interval(method="profile")``)
against closed forms: a model linear in its one parameter under Poisson counts (the
likelihood-ratio interval of a scaled total, solved here by scipy), and a model linear in
two parameters under Gaussian noise (the profile interval is then exactly estimate ∓ z σ);
an end stops at the parameter's bound."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.stats import norm

import meshladar as ml
from meshladar.brdf import SandfordRobertson
from meshladar.errors import ParameterError
from meshladar.fit import coating_kernel, fit_coatings
from meshladar.ladar import Ladar
from meshladar.scene import Scene
from meshladar.shapes import Disk

LAD = Ladar(np.arange(0.0, 360.0, 12.0), Ladar.centered(48, 1.6 / 48).bin_edges)
#: The ends are found on the signed root √Δ to 1 % of z (_profile.ROOT_TOL); where the root
#: is linear in the coordinate searched that is 1 % of the half-width, asserted at 2 %.
END_TOL = 0.02
Z95 = float(norm.ppf(0.975))


def _diffuse(rho, centre=(0.1, 0.0), radius=0.5, name="disk"):
    return Disk(centre, radius, SandfordRobertson(rho, 0.0, 0.5, 1.0, lobes="diffuse"),
                name=name)


def _sinogram(values):
    return ml.Sinogram(values, angles_deg=LAD.angles_deg, bin_edges=LAD.bin_edges,
                       info={"radiometry": "paper"})


def _poisson_fit(peak, **kw):
    scene = Scene([_diffuse(0.4)])
    kernel = coating_kernel(scene, LAD, samples=1024)
    exact = ml.simulate(scene, LAD, model="analytic").values
    k = peak / exact.max()
    counts = np.random.default_rng(3).poisson(exact * k)
    fit = fit_coatings(kernel, _sinogram(counts / k), free=["rho_d"], noise="poisson",
                       photons_per_unit=k, kernel_tol=None, **kw)
    return fit, kernel, counts, k


def test_one_parameter_poisson_interval_is_the_likelihood_ratio_closed_form():
    """m = ρ a (a diffuse coating's model is linear in ρd): the deviance's rise is
    2 [N ln(ρ̂/ρ) − A (ρ̂ − ρ)] with N the total counts and A the total of a, ρ̂ = N / A;
    its z² crossings are the interval. At 30 photoelectrons in the brightest bin it is
    skewed (upper arm longer), which the profile follows."""
    fit, kernel, counts, k = _poisson_fit(30.0)
    a = kernel.predict([dataclasses.replace(kernel.materials[0], rho_d=0.5)]) * k / 0.5
    N, A = float(counts.sum()), float(a.sum())
    rho = N / A
    assert abs(fit.estimate[0] - rho) < 0.01 * fit.stderr[0]    # the solver settles to 1 % σ

    def rise(r):
        return 2.0 * (N * np.log(rho / r) - A * (rho - r)) - Z95 ** 2

    want = (brentq(rise, rho * 1e-3, rho), brentq(rise, rho, rho * 10.0))
    lo, hi = fit.interval(0.95, method="profile")
    half = (want[1] - want[0]) / 2.0
    assert abs(lo[0] - want[0]) < END_TOL * half and abs(hi[0] - want[1]) < END_TOL * half
    assert want[1] - rho > rho - want[0]                 # the skew the profile follows


def test_two_parameter_gaussian_profile_is_estimate_plus_minus_z_sigma():
    """Two diffuse disks side by side across the line of sight, seen over 8° (their
    profiles share bins: ρd correlation −0.53), both ρd free, Gaussian noise: the model is
    linear, the misfit quadratic, so the profile interval (the other ρd refitted) is
    exactly estimate ∓ z σ, σ from the Fisher information. Holding the other at its
    estimate instead would give an interval 0.85 times as wide."""
    lad = Ladar(np.arange(0.0, 8.0, 0.5), LAD.bin_edges)
    scene = Scene([_diffuse(0.4, (0.0, 0.3), 0.25, "a"), _diffuse(0.2, (0.0, -0.3), 0.25, "b")])
    exact = ml.simulate(scene, lad, model="analytic").values
    noisy = exact + np.random.default_rng(5).normal(0.0, 0.02 * exact.max(), exact.shape)
    measured = ml.Sinogram(noisy, angles_deg=lad.angles_deg, bin_edges=lad.bin_edges,
                           info={"radiometry": "paper"})
    fit = fit_coatings(coating_kernel(scene, lad, samples=1024), measured, free=["rho_d"],
                       kernel_tol=None)
    assert fit.correlation[0, 1] < -0.5                  # the nuisance matters
    only = fit.interval(0.95, method="profile", parameters=["b.rho_d"])
    assert np.array_equal(only[0][0], fit.interval(0.95)[0][0])         # a's stays normal
    lo, hi = fit.interval(0.95, method="profile")
    z_sigma = Z95 * fit.stderr
    np.testing.assert_allclose(lo, fit.estimate - z_sigma, atol=END_TOL * z_sigma.min())
    np.testing.assert_allclose(hi, fit.estimate + z_sigma, atol=END_TOL * z_sigma.min())


def test_an_end_stops_at_the_parameters_bound_and_each_level_is_computed_once():
    """A bound inside the likelihood interval is the end; the same level asked again is
    the stored answer (no refits)."""
    free, *_ = _poisson_fit(30.0)
    top = float(free.estimate[0] + 0.3 * (free.interval(0.95, "profile")[1][0]
                                          - free.estimate[0]))
    fit, *_ = _poisson_fit(30.0, bounds={"rho_d": (0.0, top)})
    lo, hi = fit.interval(0.95, method="profile")
    assert hi[0] == top and lo[0] == pytest.approx(free.interval(0.95, "profile")[0][0],
                                                   rel=1e-3)
    again = fit.interval(0.95, method="profile")
    assert again[0] is not lo and np.array_equal(again[0], lo)
    assert list(fit._profiled) == [(0.95, 0)]


def test_profile_needs_the_fits_likelihood_and_a_known_method():
    fit, *_ = _poisson_fit(1000.0)
    with pytest.raises(ParameterError, match="method.*'normal', 'profile'"):
        fit.interval(method="wald")
    with pytest.raises(ParameterError, match="'disk.e' is not a fitted parameter; the fit "
                                             "has disk.rho_d"):
        fit.interval(method="profile", parameters=["disk.e"])
    with pytest.raises(ParameterError, match="parameters must be a list"):
        fit.interval(method="profile", parameters=3)
    bare = dataclasses.replace(fit, _likelihood=None)
    with pytest.raises(ParameterError, match="needs the fit's likelihood"):
        bare.interval(method="profile")
