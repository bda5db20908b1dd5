"""Sandford-Robertson BRDF: closed forms, limits, independent quadrature, extremes."""

from __future__ import annotations

import dataclasses
import math
import warnings

import mpmath
import numpy as np
import pytest
from _quadrature import half_vector_integral
from scipy import integrate

import meshladar as ml
from meshladar.brdf import (
    E_MIN,
    diffuse_normalization,
    diffuse_shape,
    glint_lobe,
    specular_normalization,
)
from meshladar.errors import EnergyConservationWarning, ParameterError
from meshladar.materials import ALUMINUM, DARK_GRAY

# Tolerances, each with its reason.
#: G against a 50-digit reference: the issue's bound; the closed form loses ≤ 2 bits, the
#: series is summed to 1e-23, so a few ulp (~1e-15) is what is actually reached.
G_RTOL = 1e-12
#: H and the hemispherical reflectances against graded Gauss-Legendre in half-vector
#: coordinates (scipy quad outside, epsrel 1e-12): the kink of α_max at grazing incidence
#: costs ~1e-11 at e = 1e-4.
QUAD_RTOL = 1e-9
#: Algebraic identities evaluated in float64 (a handful of roundings).
ULP_RTOL = 1e-13

BS_EXTREME = (0.0, 1e-12, 0.5, 1.0 - 1e-12, 1.0)
ES_EXTREME = (1e-4, 0.007, 0.17, 1.0)
THETAS_EXTREME = (0.0, 1e-9, math.pi / 4, math.pi / 2 - 1e-9, math.pi / 2)
THETAS = np.array([0.0, 1e-9, 1e-4, 0.01, 0.1, 0.5, 1.0, 1.3, 1.5, 1.57, math.pi / 2 - 1e-9,
                   math.pi / 2])


def _G_mp(b):
    """G(b) at 50 digits from the closed form A3 (no cancellation at that precision)."""
    with mpmath.workdps(50):
        b = mpmath.mpf(b)
        if b == 0:
            return mpmath.mpf(1)
        if b == 1:
            return mpmath.mpf(1) / 2
        c = 1 - b * b
        return (1 + b * b / c * mpmath.log(b * b)) / c


def _sr(rho_d=0.02, epsilon=0.3, b=0.1, e=0.17, lobes="both"):
    return ml.SandfordRobertson(rho_d=rho_d, epsilon=epsilon, b=b, e=e, lobes=lobes)


# ---------------------------------------------------------------------------- G(b), g(θ)

def test_G_exact_endpoints():
    assert diffuse_normalization(0.0) == 1.0
    assert diffuse_normalization(1.0) == 0.5


@pytest.mark.parametrize("b", [0.0, 1e-300, 1e-12, 1e-6, 0.01, 0.1, 0.3, 0.5,
                               math.sqrt(0.5) - 1e-9, math.sqrt(0.5), math.sqrt(0.5) + 1e-9,
                               0.8, 0.9, 0.99, 0.999999, 1 - 1e-9, 1 - 1e-12, 1 - 2**-52, 1.0])
def test_G_matches_high_precision(b):
    # b = sqrt(1/2) is the switch between closed form and series (c = 1 - b² = 1/2).
    ref = _G_mp(b)
    assert abs(diffuse_normalization(b) - float(ref)) <= G_RTOL * float(ref)


def test_G_closed_form_is_bit_for_bit_scipy_xlogy():
    """Where G(b) takes its closed form (c = 1 − b² ≥ 1/2), it is bit for bit the form
    computed with scipy.special.xlogy for s ln s (what meshladar used before it dropped
    scipy.special from its import), over 20,000 b and at b = 0."""
    from scipy.special import xlogy

    b = np.concatenate([[0.0], np.linspace(1e-6, math.sqrt(0.5), 20000)])
    c = (1.0 - b) * (1.0 + b)
    b, c = b[c >= 0.5], c[c >= 0.5]                 # the closed form's domain
    s = b * b
    np.testing.assert_array_equal(diffuse_normalization(b), (c + xlogy(s, s)) / (c * c))


def test_G_dense_grid_and_quadrature():
    bs = np.concatenate([np.linspace(0, 1, 1001), 1 - np.geomspace(1e-15, 1e-1, 60),
                         np.geomspace(1e-15, 1e-1, 60)])
    got = diffuse_normalization(bs)
    ref = np.array([float(_G_mp(b)) for b in bs])
    assert np.max(np.abs(got / ref - 1)) < G_RTOL
    # and the definition itself (A3): G = 2 ∫ g(θ) cos θ sin θ dθ, by mpmath quadrature
    for b in (0.05, 0.5, 0.95):
        with mpmath.workdps(30):
            q = 2 * mpmath.quad(lambda t: mpmath.cos(t) ** 3 * mpmath.sin(t)
                                / (mpmath.cos(t) ** 2 + b * b * mpmath.sin(t) ** 2),
                                [0, mpmath.pi / 2])
        assert abs(diffuse_normalization(b) / float(q) - 1) < G_RTOL
    # G decreases monotonically from 1 to 1/2, also across the branch switch
    assert np.all(np.diff(diffuse_normalization(np.linspace(0, 1, 20001))) <= 0)


def test_diffuse_shape_forms_and_limits():
    theta = np.linspace(0, math.pi / 2 - 1e-3, 200)
    for b in (0.1, 0.5, 0.99):
        # A2 as printed: 1/(1 + b² tan²θ)
        np.testing.assert_allclose(diffuse_shape(theta, b), 1 / (1 + b**2 * np.tan(theta) ** 2),
                                   rtol=ULP_RTOL)
    assert np.all(diffuse_shape(THETAS, 0.0) == 1.0)       # Lambertian, also at π/2
    assert diffuse_shape(math.pi / 2, 0.5) < 1e-31          # grazing: g → 0 for b > 0
    # b → 0 meets the b = 0 branch (away from the exact grazing direction)
    np.testing.assert_allclose(diffuse_shape(theta, 1e-300), 1.0, rtol=0, atol=0)


# ---------------------------------------------------------------------------- h(α), H(θ)

@pytest.mark.parametrize("e", [1e-4, 0.007, 0.17, 0.5, 1.0])
@pytest.mark.parametrize("theta", [0.0, 1e-9, 0.3, 0.8, 1.2, 1.5, math.pi / 2 - 1e-9,
                                   math.pi / 2])
def test_H_closed_form_equals_hemispherical_integral(e, theta):
    q = half_vector_integral(theta, e, lambda w_r, a: glint_lobe(a, e)) / (4 * math.pi)
    assert specular_normalization(theta, e) == pytest.approx(q, rel=QUAD_RTOL)


@pytest.mark.parametrize("e", ES_EXTREME)
def test_H_special_values(e):
    assert specular_normalization(0.0, e) == pytest.approx(1 / (e * e * (1 + e * e)),
                                                           rel=ULP_RTOL)
    # cos(fl(π/2)) = 6.1e-17 ≠ 0: H(π/2) = 1/(2e) plus its first-order term (1 − e²)c/(2e²)
    c = math.cos(math.pi / 2)
    assert specular_normalization(math.pi / 2, e) == pytest.approx(
        1 / (2 * e) + (1 - e * e) * c / (2 * e * e), rel=ULP_RTOL)
    assert glint_lobe(0.0, e) == pytest.approx(e**-4, rel=ULP_RTOL)
    assert glint_lobe(math.pi / 2, e) == pytest.approx(1.0, rel=ULP_RTOL)


def test_e_one_is_flat_lobe():
    theta = np.linspace(0, math.pi / 2, 50)
    np.testing.assert_allclose(glint_lobe(theta, 1.0), 1.0, rtol=ULP_RTOL)
    np.testing.assert_allclose(specular_normalization(theta, 1.0), 0.5, rtol=ULP_RTOL)


@pytest.mark.parametrize("e", [0.007, 0.17, 0.6])
def test_glint_lobe_is_trowbridge_reitz(e):
    alpha = np.linspace(0, math.pi / 2 - 1e-6, 400)
    ggx = e**2 / (math.pi * np.cos(alpha) ** 4 * (e**2 + np.tan(alpha) ** 2) ** 2)
    np.testing.assert_allclose(e**2 * glint_lobe(alpha, e) / math.pi, ggx, rtol=1e-10)
    # GGX is a normalised microfacet distribution: ∫ D(m) cos α dω_m = 1
    val, _ = integrate.quad(lambda a: e**2 * glint_lobe(a, e) / math.pi * math.cos(a)
                            * math.sin(a) * 2 * math.pi, 0, math.pi / 2,
                            points=[e, 10 * e], epsabs=0, epsrel=1e-12, limit=200)
    assert val == pytest.approx(1.0, rel=QUAD_RTOL)


# ---------------------------------------------------------------------------- energy

@pytest.mark.parametrize("m", [DARK_GRAY, ALUMINUM, ml.SandfordRobertson(0.1, 0.2, 0.9, 1e-4),
                               ml.SandfordRobertson(0.0, 0.5, 1.0, 1.0)],
                         ids=["dark_gray", "aluminum", "b0.9_e1e-4", "b1_e1"])
def test_energy_conservation_pointwise(m):
    # ρd(θ) + ρs(θ) + ε(θ) = 1 (Eq. 3 with A4, A7, A8)
    total = m.diffuse_reflectance(THETAS) + m.specular_reflectance(THETAS) + m.emissivity(THETAS)
    np.testing.assert_allclose(total, 1.0, rtol=ULP_RTOL)


@pytest.mark.parametrize("m", [DARK_GRAY, ALUMINUM, ml.materials.glint(1e-4)],
                         ids=["dark_gray", "aluminum", "glint_e1e-4"])
# Directions are built as vectors here; at θi = π/2 − δ the mirror half vector w_i + w_r is
# ~2δ long and its rounding (1e-16 absolute) blurs α by ~1e-16/δ, which a 1e-4 lobe feels
# at δ = 1e-6 (2e-9 relative): grazing stops at θ = 1.57 (δ = 8e-4). The closed-form H is
# checked at θ = π/2 − 1e-9 and π/2 with exact α above.
@pytest.mark.parametrize("theta", [0.0, 0.4, 1.0, 1.45, 1.57])
def test_hemispherical_integrals_equal_directional_reflectances(m, theta):
    w_i = np.array([math.sin(theta), 0.0, math.cos(theta)])
    spec = dataclasses.replace(m, lobes="specular")
    q_s = half_vector_integral(
        theta, m.e, lambda w_r, a: spec.evaluate(w_i, w_r, projected=True))
    assert q_s == pytest.approx(m.specular_reflectance(theta), rel=QUAD_RTOL)
    if m.rho_d > 0:
        diff = dataclasses.replace(m, lobes="diffuse")
        # the diffuse lobe is azimuth-independent: ∫ F_d cos θr dω = 2π ∫ F_d cos sin dθr
        q_d, _ = integrate.quad(lambda tr: 2 * math.pi * diff.evaluate_angles(theta, tr, 0.0)
                                * math.cos(tr) * math.sin(tr), 0, math.pi / 2,
                                epsabs=0, epsrel=1e-13)
        assert q_d == pytest.approx(m.diffuse_reflectance(theta), rel=QUAD_RTOL)
        # the full lobe plus emission is all the incident light (Eq. 3)
        assert q_s + q_d + m.emissivity(theta) == pytest.approx(1.0, rel=QUAD_RTOL)


def test_diffuse_reciprocity():
    rng = np.random.default_rng(20091)
    v = rng.normal(size=(2, 500, 3))
    v[..., 2] = np.abs(v[..., 2])
    for b in (0.0, 0.1, 0.99, 1.0):
        m = ml.SandfordRobertson(0.4, 0.0, b, 1.0, lobes="diffuse")
        np.testing.assert_allclose(m.evaluate(v[0], v[1]), m.evaluate(v[1], v[0]), rtol=ULP_RTOL)


def test_b_zero_is_lambertian():
    m = ml.materials.lambertian(0.6)
    assert m.is_lambertian
    np.testing.assert_allclose(m.monostatic(THETAS), 0.6 / math.pi, rtol=ULP_RTOL)
    tr = np.linspace(0, math.pi / 2, 37)
    np.testing.assert_allclose(m.evaluate_angles(0.7, tr, 2.0), 0.6 / math.pi, rtol=ULP_RTOL)
    # b → 0 meets b = 0
    tiny = ml.SandfordRobertson(0.6, 0.0, 1e-12, 1.0, lobes="diffuse")
    theta = np.linspace(0, math.pi / 2 - 1e-3, 100)
    np.testing.assert_allclose(tiny.monostatic(theta), 0.6 / math.pi, rtol=ULP_RTOL)


# ---------------------------------------------------------------------------- monostatic

@pytest.mark.parametrize("m", [DARK_GRAY, ALUMINUM], ids=["dark_gray", "aluminum"])
def test_monostatic_closed_form_at_normal_incidence(m):
    G = float(_G_mp(m.b))
    rho_s0 = 1 - (m.epsilon + m.rho_d) / G
    expected = m.rho_d / (math.pi * G**2) + rho_s0 * (1 + m.e**2) / (4 * math.pi * m.e**2)
    assert m.monostatic(0.0) == pytest.approx(expected, rel=ULP_RTOL)


def test_paper_coating_magnitudes():
    # DESIGN.md: aluminium's F is about 650 sr⁻¹ at normal incidence, 0.04 five degrees off
    assert ALUMINUM.monostatic(0.0) == pytest.approx(651.1, rel=1e-3)
    assert ALUMINUM.monostatic(math.radians(5)) == pytest.approx(0.043, rel=0.05)
    assert glint_lobe(0.0, 0.007) == pytest.approx(4.165e8, rel=1e-3)   # 1/e⁴ ≈ 4e8


@pytest.mark.parametrize("m", [DARK_GRAY, ALUMINUM], ids=["dark_gray", "aluminum"])
def test_monostatic_agrees_with_bistatic_forms(m):
    theta = np.linspace(0, math.pi / 2, 91)
    mono = m.monostatic(theta)
    np.testing.assert_allclose(m.evaluate_angles(theta, theta, 0.0), mono, rtol=ULP_RTOL)
    w = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], -1)
    np.testing.assert_allclose(m.evaluate(w, w), mono, rtol=ULP_RTOL)
    np.testing.assert_allclose(m.monostatic(theta, projected=True),
                               mono * np.cos(theta), rtol=ULP_RTOL)
    # explicit A1 + A5 with θr = θi = α = θ
    g = 1 / (1 + m.b**2 * np.tan(theta[:-1]) ** 2)
    G = m.G
    rho_s = 1 - (m.epsilon + m.rho_d) * g / G
    c = np.cos(theta[:-1])
    H = ((1 - m.e**2) * c + (2 * m.e**2 + (1 - m.e**2) ** 2 * c**2)
         / np.sqrt(4 * m.e**2 + (1 - m.e**2) ** 2 * c**2)) / (2 * m.e**2)
    h = 1 / (m.e**2 * c**2 + np.sin(theta[:-1]) ** 2) ** 2
    F = m.rho_d * g * g / (math.pi * G**2) + rho_s * h / (4 * math.pi * H * c)
    np.testing.assert_allclose(mono[:-1], F, rtol=1e-12)


@pytest.mark.parametrize("e", ES_EXTREME)
def test_projected_glint_finite_and_continuous_at_grazing(e):
    m = ml.materials.glint(e)
    limit = e / (2 * math.pi)              # ρs(π/2) h(π/2) / (4π H(π/2)) with H = 1/(2e)
    assert m.monostatic(math.pi / 2, projected=True) == pytest.approx(limit, rel=ULP_RTOL)
    near = m.monostatic(math.pi / 2 - np.geomspace(1e-3, 1e-12, 10), projected=True)
    # approaches the limit linearly in the distance to grazing (slope bounded by ~1/e)
    assert np.all(np.abs(near / limit - 1) <= 4 * np.geomspace(1e-3, 1e-12, 10) / e)
    # a direction exactly in the surface (cos θr = 0) gives the same limit: no jump
    w_i = np.array([1.0, 0.0, 0.0])
    assert m.evaluate(w_i, w_i, projected=True) == pytest.approx(limit, rel=ULP_RTOL)
    assert np.isfinite(m.evaluate(w_i, w_i))


def test_below_horizon_is_zero():
    for m in (DARK_GRAY, ALUMINUM, ml.materials.lambertian()):
        theta = np.array([math.pi / 2 + 1e-12, 2.0, math.pi, -2.0, 4.0])
        assert np.all(m.monostatic(theta) == 0.0)
        assert np.all(m.monostatic(theta, projected=True) == 0.0)
        assert m.evaluate_angles(0.3, 1.8, 0.0) == 0.0
        assert m.evaluate_angles(1.8, 0.3, 0.0) == 0.0
        assert m.evaluate([0, 0, -1], [0, 0, 1]) == 0.0
    # F depends on θ through cos θ and |sin θ|: even and 2π-periodic
    t = np.linspace(0, 1.5, 20)
    np.testing.assert_array_equal(ALUMINUM.monostatic(-t), ALUMINUM.monostatic(t))
    np.testing.assert_allclose(ALUMINUM.monostatic(t + 2 * math.pi), ALUMINUM.monostatic(t),
                               rtol=1e-9)


def test_specular_peaks_in_the_mirror_direction():
    theta_i = 0.6
    tr = np.linspace(0.0, math.pi / 2, 2001)
    # F itself grows like 1/cos θr toward grazing reflection; the lobe is seen in F·cos θr
    f = ALUMINUM.evaluate_angles(theta_i, tr, math.pi, projected=True)
    assert abs(tr[np.argmax(f)] - theta_i) <= tr[1] - tr[0]
    # mirror direction: α = 0, F_s = ρs h(0) / (4π H cos θr) + F_d
    peak = (ALUMINUM.specular_reflectance(theta_i) * ALUMINUM.e**-4
            / (4 * math.pi * specular_normalization(theta_i, ALUMINUM.e) * math.cos(theta_i)))
    f_d = ALUMINUM.rho_d * diffuse_shape(theta_i, 0.1) ** 2 / (math.pi * ALUMINUM.G**2)
    assert ALUMINUM.evaluate_angles(theta_i, theta_i, math.pi) == pytest.approx(peak + f_d,
                                                                                rel=ULP_RTOL)


# ---------------------------------------------------------------------------- extremes

def _extreme_materials():
    for b in BS_EXTREME:
        for e in ES_EXTREME:
            yield ml.SandfordRobertson(0.02, 0.3, b, e)                  # both (0.32 ≤ G ≥ 1/2)
            yield ml.SandfordRobertson(0.0, 0.0, b, e, lobes="specular")
        yield ml.SandfordRobertson(0.4, 0.0, b, 1.0, lobes="diffuse")


def test_extremes_grid_finite_nonnegative_without_warnings():
    theta = np.array(THETAS_EXTREME)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with np.errstate(over="raise", divide="raise", invalid="raise"):
            for m in _extreme_materials():
                for projected in (False, True):
                    f = m.monostatic(theta, projected=projected)
                    assert np.all(np.isfinite(f)) and np.all(f >= 0), m
                # continuity of F·cos θ up to and including π/2, on a ladder of steps down
                # to float spacing. Near grazing |d(F cos θ)/dθ| ≤ 10 sr⁻¹ plus the diffuse
                # shape's transition, |dg/dθ| ≤ 0.65/b, which is steep but continuous.
                ladder = np.append(math.pi / 2 - np.geomspace(1e-3, 1e-15, 13), math.pi / 2)
                fc = m.monostatic(ladder, projected=True)
                lipschitz = 10.0 * (1.0 + (1.0 / m.b if m.b > 0 else 0.0))
                assert np.all(np.abs(np.diff(fc)) <= lipschitz * np.diff(ladder) + 1e-15), m
                # bistatic directions exactly at the horizon stay finite
                w = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
                assert np.all(np.isfinite(m.evaluate(w[:, None], w[None, :])))


def test_scalar_in_scalar_out_and_shapes():
    assert isinstance(DARK_GRAY.monostatic(0.2), float)
    assert isinstance(DARK_GRAY.monostatic(np.float64(0.2)), float)
    assert isinstance(DARK_GRAY.monostatic(np.array(0.2)), float)
    assert isinstance(DARK_GRAY.evaluate_angles(0.2, 0.3, 1.0), float)
    assert DARK_GRAY.monostatic(np.zeros((3, 4))).shape == (3, 4)
    assert DARK_GRAY.evaluate_angles(np.zeros((5, 1)), np.zeros(4)).shape == (5, 4)
    assert DARK_GRAY.monostatic(np.array([])).shape == (0,)


# ---------------------------------------------------------------------------- validation

@pytest.mark.parametrize("kwargs, match", [
    (dict(rho_d=-0.1), r"rho_d must be in \[0, 1\]; got -0.1"),
    (dict(rho_d=1.5), r"rho_d must be in \[0, 1\]; got 1.5"),
    (dict(epsilon=2.0), r"epsilon must be in \[0, 1\]; got 2.0"),
    (dict(b=1.3), r"b must be in \[0, 1\]; got 1.3"),
    (dict(b=-1e-9), r"b must be in \[0, 1\]"),
    (dict(e=0.0), r"e must be in \[1e-12, 1\]; got 0.0"),
    (dict(e=1.01), r"e must be in \[1e-12, 1\]; got 1.01"),
    (dict(rho_d=float("nan")), r"rho_d must be finite"),
    (dict(b=float("inf")), r"b must be finite"),
    (dict(e=float("-inf")), r"e must be finite"),
    (dict(rho_d="0.1"), r"rho_d must be a real number; got '0.1'"),
    (dict(b=True), r"b must be a real number; got True"),
    (dict(lobes="glint"), r"lobes must be one of \('both', 'diffuse', 'specular'\); got 'glint'"),
    (dict(rho_d=0.5, epsilon=0.6), r"not energy-conserving: rho_d \+ epsilon = 1.1 exceeds "
                                   r"G\(b\) = 0.963114 \(b = 0.1\) by 0.137"),
    (dict(rho_d=0.0, epsilon=0.99, b=0.1, lobes="specular"), r"not energy-conserving"),
])
def test_bad_parameters_raise_clear_errors(kwargs, match):
    params = dict(rho_d=0.03, epsilon=0.5, b=0.1, e=0.17) | kwargs
    with pytest.raises(ParameterError, match=match):
        ml.SandfordRobertson(**params)


def test_errors_are_value_errors():
    with pytest.raises(ValueError):
        ml.SandfordRobertson(2.0, 0.0, 0.0, 1.0)


def test_paper_diffuse_surface_warns_but_builds():
    with pytest.warns(EnergyConservationWarning, match=r"up to rho_d/G\(b\) = 1.9"):
        m = ml.SandfordRobertson(rho_d=1.0, epsilon=0.0, b=0.99, e=1.0, lobes="diffuse")
    assert m.diffuse_reflectance(0.0) == pytest.approx(1 / m.G, rel=ULP_RTOL)
    assert 1.98 < 1 / m.G < 2.0
    # the Lambertian ρd = 1 surface is exactly energy-conserving: no warning (errors here)
    ml.SandfordRobertson(rho_d=1.0, epsilon=0.0, b=0.0, e=1.0, lobes="diffuse")


def test_energy_boundary_is_allowed():
    m = ml.SandfordRobertson(rho_d=0.2, epsilon=diffuse_normalization(0.3) - 0.2, b=0.3, e=0.1)
    assert m.specular_reflectance(0.0) == pytest.approx(0.0, abs=1e-15)
    assert m.specular_reflectance(0.0) >= 0.0


@pytest.mark.parametrize("bad", [float("nan"), [0.1, float("inf")], "x"])
def test_bad_theta_raises(bad):
    with pytest.raises(ParameterError, match="theta must be"):
        DARK_GRAY.monostatic(bad)


def test_bad_vectors_raise():
    with pytest.raises(ParameterError, match=r"incident must be non-zero"):
        DARK_GRAY.evaluate([0, 0, 0], [0, 0, 1])
    with pytest.raises(ParameterError, match=r"reflected must have shape \(\.\.\., 3\)"):
        DARK_GRAY.evaluate([0, 0, 1], [0, 1])
    with pytest.raises(ParameterError, match=r"normal must be finite"):
        DARK_GRAY.evaluate([0, 0, 1], [0, 0, 1], [0, float("nan"), 1])


def test_value_type():
    m = ml.SandfordRobertson(rho_d=0.032, epsilon=0.877, b=0.1, e=0.17)
    with pytest.raises(dataclasses.FrozenInstanceError):
        m.b = 0.2
    assert m == DARK_GRAY                       # the name is a label, not part of equality
    assert hash(m) == hash(DARK_GRAY)
    text = repr(DARK_GRAY)
    for part in ("rho_d=0.032", "epsilon=0.877", "b=0.1", "e=0.17", "lobes='both'"):
        assert part in text
    assert E_MIN == 1e-12


# ------------------------------------------------------------------ the BRDF protocol

from meshladar.brdf import BRDF, GGX, Lambertian, Phong, Tabulated  # noqa: E402

#: 2-D quadrature of smooth lobes over the hemisphere: scipy's dblquad reaches ~1e-12;
#: this bound leaves room for the sharpest lobe (Phong n = 1000)
ALBEDO_TOL = 1e-7

MODELS = {
    "lambertian": Lambertian(0.3),
    "phong n=50": Phong(0.2, 0.7, 50),
    "phong n=0": Phong(0.1, 0.4, 0),
    "ggx 0.2": GGX(0.2),
    "ggx 1e-4 R=0.9": GGX(1e-4, 0.9),
    "tabulated": Tabulated([0.0, 30.0, 60.0, 90.0], [0.3, 0.2, 0.1, 0.05]),
    "sr aluminum": ALUMINUM,
}


def _albedo_at_normal_incidence(m):
    from scipy import integrate

    val, _ = integrate.quad(lambda t: 2 * np.pi * math.sin(t)
                            * m.evaluate_angles(0.0, t, 0.0, projected=True), 0.0,
                            math.pi / 2, limit=400, epsabs=1e-13, epsrel=1e-12)
    return val


@pytest.mark.parametrize("name", list(MODELS))
def test_every_model_is_finite_continuous_and_zero_below_the_horizon(name):
    m = MODELS[name]
    theta = np.concatenate([np.linspace(0.0, math.pi / 2, 2001), [math.pi / 2]])
    with np.errstate(over="raise", divide="raise", invalid="raise"):
        p = m.monostatic(theta, projected=True)
        f = m.monostatic(theta)
    assert np.all(np.isfinite(p)) and np.all(p >= 0) and np.all(np.isfinite(f))
    assert m.monostatic(math.pi / 2 + 1e-9) == 0.0 and m.monostatic(math.pi) == 0.0
    # F cos θ continuous up to and including π/2: the value there is the limit from below
    near = m.monostatic(math.pi / 2 - 1e-9, projected=True)
    assert abs(p[-1] - near) <= 1e-6 * np.max(p)
    # F = projected / cos θ where cos θ > 0
    np.testing.assert_allclose(f[:-2] * np.cos(theta[:-2]), p[:-2], rtol=1e-12, atol=1e-300)


@pytest.mark.parametrize("name", [n for n in MODELS if n != "tabulated"])
def test_the_bistatic_evaluation_at_coincident_directions_is_the_monostatic(name):
    m = MODELS[name]
    theta = np.linspace(0.0, math.pi / 2 - 1e-3, 97)
    w = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], -1)
    np.testing.assert_allclose(m.evaluate(w, w, projected=True),
                               m.monostatic(theta, projected=True), rtol=1e-11, atol=1e-15)


@pytest.mark.parametrize("m, albedo", [
    (Lambertian(0.3), 0.3),
    (Phong(0.2, 0.7, 0), 0.9), (Phong(0.2, 0.7, 1), 0.9), (Phong(0.0, 0.7, 50), 0.7),
    (Phong(0.1, 0.9, 1000), 1.0),
])
def test_hemispherical_albedo_at_normal_incidence_is_the_closed_form(m, albedo):
    # Lambertian: albedo; normalised Phong: kd + ks exactly at normal incidence
    assert _albedo_at_normal_incidence(m) == pytest.approx(albedo, rel=ALBEDO_TOL)


@pytest.mark.parametrize("alpha", [0.05, 0.2, 0.5, 1.0])
def test_ggx_against_its_closed_forms(alpha):
    from scipy import integrate

    m = GGX(alpha)
    # D is a normalised distribution of microfacet normals: ∫ D cos θh dω = 1
    D = lambda t: m._D(np.cos(t), np.sin(t))                          # noqa: E731
    norm, _ = integrate.quad(lambda t: 2 * np.pi * D(t) * np.cos(t) * np.sin(t), 0,
                             math.pi / 2, limit=400, epsrel=1e-12)
    assert norm == pytest.approx(1.0, rel=1e-9)
    # F(0) = D(0) G1(0)² / 4 = 1 / (4π α²)
    assert m.monostatic(0.0) == pytest.approx(1.0 / (4 * math.pi * alpha**2), rel=1e-13)
    # albedo at normal incidence through the half vector (θr = 2θh, dω_r = 4 cos θh dω_h):
    # ∫ D(θh) G1(2θh) cos θh dω_h, an independent 1-D integral of the textbook G1
    g1 = lambda t: 2 / (1 + np.sqrt(1 + alpha**2 * np.tan(t) ** 2))   # noqa: E731
    ref, _ = integrate.quad(lambda t: 2 * np.pi * D(t) * g1(2 * t) * np.cos(t) * np.sin(t),
                            0, math.pi / 4, limit=400, epsrel=1e-12)
    assert _albedo_at_normal_incidence(m) == pytest.approx(ref, rel=ALBEDO_TOL)
    # reciprocity: F(w_i, w_r) = F(w_r, w_i)
    rng = np.random.default_rng(3)
    a, b = rng.normal(size=(2, 50, 3))
    a[:, 2], b[:, 2] = np.abs(a[:, 2]), np.abs(b[:, 2])
    np.testing.assert_allclose(m.evaluate(a, b), m.evaluate(b, a), rtol=1e-12)


def test_phong_monostatic_closed_form():
    m = Phong(0.2, 0.7, 50)
    theta = np.linspace(0.0, math.pi / 2, 91)
    lobe = np.where(theta < math.pi / 4, np.cos(2 * theta), 0.0) ** 50
    np.testing.assert_allclose(m.monostatic(theta), 0.2 / math.pi + 0.7 * 52 / (2 * math.pi)
                               * lobe, rtol=1e-12)
    with pytest.raises(ParameterError, match=r"kd \+ ks must be at most 1 .*; got kd \+ ks = 1.1"):
        Phong(0.5, 0.6, 10)


def test_tabulated_interpolates_a_measured_table_and_checks_it():
    # SR aluminium's F cos θ sampled every 0.01°: the table reproduces it between samples
    t = np.linspace(0.0, 90.0, 9001)
    table = Tabulated(t, ALUMINUM.monostatic(np.deg2rad(t), projected=True),
                      projected_values=True)
    mid = np.deg2rad(t[:-1] + 0.005)
    np.testing.assert_allclose(table.monostatic(mid, projected=True),
                               ALUMINUM.monostatic(mid, projected=True), rtol=2e-3)
    user = np.array([0.0, 90.0])
    Tabulated(user, [1.0, 1.0])
    assert user.flags.writeable and user.tolist() == [0.0, 90.0]        # not taken over
    for args, message in [(([0, 45], [1, 1]), r"increase strictly from 0 to 90"),
                          (([0, 90, 45], [1, 1, 1]), r"from 0 to 90 .*not increasing"),
                          (([0, 90], [1, -1]),
                           r"values must be in \[0, 1e\+12\] \(per sr: a mirror-like glint "
                           r"peaks near 1e6\); got -1 at 90"),
                          (([0, 90], [1, np.nan]), r"values must be finite"),
                          (([0, 90], [1, 1, 1]), r"values must have theta_deg's shape")]:
        with pytest.raises(ParameterError, match=message):
            Tabulated(*args)


class _UserMatte(BRDF):
    """A user's coating defining only the protocol's one required method."""

    def projected(self, cos_theta, sin_theta):
        return 0.3 / np.pi * cos_theta


@pytest.mark.parametrize("model", ["analytic", "pixel",
                                   pytest.param("mesh", marks=pytest.mark.slow)])
def test_a_users_model_works_in_every_forward_model(model):
    from meshladar.materials import lambertian

    def scene(m):
        return ml.Scene([ml.Disk((-0.3, 0.0), 0.4, m), ml.Ellipse((0.4, 0.1), (0.3, 0.15),
                                                                   30.0, m)])

    ladar = ml.Ladar.paper(angles_deg=np.arange(0.0, 360.0, 45.0))
    opts = {"pixel": {"pixel_size": 0.01}, "mesh": {}}.get(model, {})
    results = []
    for m in (_UserMatte(), Lambertian(0.3), lambertian(0.3)):
        s = scene(m) if model != "mesh" else scene(m).tessellate(256)
        results.append(ml.simulate(s, ladar, model=model, **opts).values)
    # the same function through three paths (a user's arrays, Lambertian, SR with b = 0 in
    # the compiled kernel): equal to round-off
    np.testing.assert_allclose(results[0], results[1], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(results[0], results[2], rtol=1e-12, atol=1e-15)


def test_a_users_model_returning_nonsense_is_named():
    class Broken(BRDF):
        def projected(self, cos_theta, sin_theta):
            return cos_theta - 0.5

    scene = ml.Scene([ml.Disk((0.0, 0.0), 0.5, Broken())])
    with pytest.raises(ParameterError, match=r"Broken.projected must be finite and "
                                             r"non-negative; got -[\d.e-]+ at cos theta = 0.4\d+"):
        ml.simulate(scene, ml.Ladar.paper(angles_deg=[0.0]))
    with pytest.raises(ml.errors.ModelError, match=r"Broken has no bistatic evaluation"):
        Broken().evaluate([0, 0, 1], [0, 1, 1])
