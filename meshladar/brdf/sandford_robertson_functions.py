"""The Sandford-Robertson model's functions (Jin & Levine 2009, Appendix A), on which
:class:`~meshladar.brdf.SandfordRobertson` is built: the diffuse shape g (A2) and its
normalisation G (A3), the glint lobe h (A6) and its normalisation H (A9).

Each is here twice: as a private kernel on (cos, sin) pairs, vectorised and numerically
stable at every extreme, which the coating evaluates; and as a public function of angles in
radians that checks its arguments. The equations are in
:mod:`meshladar.brdf.sandford_robertson`'s introduction, the conventions (angles, horizon,
units) in :mod:`meshladar.brdf.base`'s. The public functions are also importable from
:mod:`meshladar.brdf.sandford_robertson` and :mod:`meshladar.brdf`.
"""

from __future__ import annotations

import math

import numpy as np

from .._validate import check_real, finite_array
from ..errors import ParameterError
from ..precision import E_MIN
from ._shared import _cos_sin, _out, _safe_divide

__all__ = ["diffuse_shape", "diffuse_normalization", "glint_lobe", "specular_normalization"]


#: Below this value of c = 1 − b², G(b) is summed as its Taylor series in c (A3 cancels
#: catastrophically as b → 1); above, the closed form loses at most ~2 bits.
_G_SERIES_BELOW = 0.5
#: Terms of that series: the tail after 64 terms is < 0.5**64 / (65·66) ≈ 1e-23 of G ≥ 1/2.
_G_SERIES_TERMS = 64


# --------------------------------------------------------------------------------------
# The model's functions, vectorised, on (cos, sin) pairs: private kernels first.
# --------------------------------------------------------------------------------------

def _g(cos_t, sin_t, b):
    """Diffuse shape g (A2) as cos²θ / (cos²θ + b² sin²θ), scaled by hypot against under-
    and overflow. g = 1 where both terms vanish (b = 0 at θ = π/2), the b → 0 limit."""
    den = np.hypot(cos_t, b * sin_t)
    return _safe_divide(cos_t, den, 1.0) ** 2


def _s_log_s(s):
    """s ln s element by element, 0 at s = 0, for s ≥ 0: the C library's log of each
    element, so bit for bit what ``scipy.special.xlogy(s, s)`` gives (numpy's vectorised
    log differs from it in the last bit for a few inputs in a thousand), without importing
    scipy.special at ``import meshladar`` (a sixth of a second) for one function. A loop in
    Python: for the coatings' b, a few values at a time."""
    s = np.asarray(s, dtype=np.float64)
    out = [x * math.log(x) if x > 0 else 0.0 for x in s.ravel().tolist()]
    return np.array(out, dtype=np.float64).reshape(s.shape)


def _G(b):
    """Diffuse normalisation G(b) (A3), stable on all of [0, 1].

    With c = 1 − b² (formed as (1 − b)(1 + b), exact near b = 1) and s = b²,
    G = (c + s ln s) / c² = Σ_k c^k / ((k + 1)(k + 2)). The closed form is used for
    c ≥ 1/2 (s ln s = 0 at s = 0, _s_log_s), the series for c < 1/2.
    """
    b = np.asarray(b, dtype=np.float64)
    c = (1.0 - b) * (1.0 + b)
    s = b * b
    series = np.zeros_like(c)
    for k in range(_G_SERIES_TERMS - 1, -1, -1):
        series = series * c + 1.0 / ((k + 1) * (k + 2))
    c_safe = np.where(c >= _G_SERIES_BELOW, c, 1.0)
    closed = (c_safe + _s_log_s(s)) / (c_safe * c_safe)
    return np.where(c >= _G_SERIES_BELOW, closed, series)


def _H_scaled(cos_t, e):
    """2e²·H(θ): the specular normalisation (A9) times 2e², always in [e, 2].

    H(θ) = (1/2e²) [(1 − e²) cos θ + (2e² + (1 − e²)² cos²θ) / sqrt(4e² + (1 − e²)² cos²θ)]
    """
    k = (1.0 - e) * (1.0 + e)
    kc = k * cos_t
    return kc + (2.0 * e * e + kc * kc) / np.hypot(2.0 * e, kc)


def _glint_over_H(cos_a, sin_a, cos_t, e):
    """h(α) / H(θ) in one scaled expression: 2e² / ((e² cos²α + sin²α)² · 2e²H(θ))."""
    d = np.hypot(e * cos_a, sin_a) ** 2
    return 2.0 * e * e / (d * d * _H_scaled(cos_t, e))


# --------------------------------------------------------------------------------------
# Public functions of the model (angles in radians).
# --------------------------------------------------------------------------------------

def diffuse_shape(theta, b):
    """Diffuse lobe shape g(θ) = 1 / (1 + b² tan²θ) (paper Eq. A2).

    Parameters
    ----------
    theta : array_like, radians
        Polar angle from the normal. Only cos θ and |sin θ| enter.
    b : float in [0, 1]
        Grazing-angle reflectivity. b = 0 gives g ≡ 1 (Lambertian), also at θ = π/2.

    Returns
    -------
    g : ndarray or float, in [0, 1]
        The shape of ``theta``; a Python float for a scalar ``theta``.

    Raises
    ------
    ParameterError
        When ``b`` is not a real number in [0, 1] or ``theta`` is not finite.

    References
    ----------
    Jin & Levine (2009), Eq. A2.
    Sandford & Robertson (1985).
    """
    b = check_real("b", b, low=0.0, high=1.0)
    c, s = _cos_sin(theta, "theta")
    return _out(_g(np.abs(c), s, b), theta)


def diffuse_normalization(b):
    """G(b) = (1/π) ∫ g(θ) cos θ dω over the hemisphere (paper Eq. A3).

    Evaluated as (c + b² ln b²)/c² with c = 1 − b² for c ≥ 1/2 and as the series
    Σ c^k/((k+1)(k+2)) for c < 1/2, so that it is accurate to a few ulp on all of [0, 1]:
    G(0) = 1 and G(1) = 1/2 exactly.

    Parameters
    ----------
    b : array_like in [0, 1]

    Returns
    -------
    G : ndarray or float, in [1/2, 1]
        The shape of ``b``; a Python float for a scalar ``b``.

    Raises
    ------
    ParameterError
        When ``b`` is not finite real numbers, or any element is outside [0, 1].

    References
    ----------
    Jin & Levine (2009), Eq. A3.
    Sandford & Robertson (1985).
    """
    arr = finite_array("b", b)
    if np.any((arr < 0) | (arr > 1)):
        bad = float(arr[(arr < 0) | (arr > 1)].ravel()[0])
        raise ParameterError(f"b must be in [0, 1]; got {bad!r}")
    return _out(_G(arr), b)


def glint_lobe(alpha, e):
    """Glint lobe h(α) = 1 / (e² cos²α + sin²α)² (paper Eq. A6).

    This is, up to normalisation, the Trowbridge-Reitz (GGX) microfacet distribution with
    roughness e: D(α) = e² / (π cos⁴α (e² + tan²α)²) = e² h(α) / π. It peaks at
    h(0) = 1/e⁴ and equals 1 at α = π/2 for every e.

    Parameters
    ----------
    alpha : array_like, radians
        Glint angle: polar angle of the half vector. Must be finite; only cos α and |sin α|
        enter.
    e : float in [E_MIN, 1]
        Glint eccentricity (specularity parameter), a scalar; E_MIN = 1e-12.

    Returns
    -------
    h : ndarray or float, in [1, 1/e⁴]
        The shape of ``alpha``; a Python float for a scalar ``alpha``.

    Raises
    ------
    ParameterError
        When ``e`` is not a real number in [E_MIN, 1] or ``alpha`` is not finite.

    References
    ----------
    Jin & Levine (2009), Eq. A6.
    Sandford & Robertson (1985).
    """
    e = check_real("e", e, low=E_MIN, high=1.0)
    c, s = _cos_sin(alpha, "alpha")
    return _out(1.0 / np.hypot(e * c, s) ** 4, alpha)


def specular_normalization(theta, e):
    """H(θi) = (1/4π) ∫ h(α) dω_r over the hemisphere of reflected directions (Eq. A9).

    The paper's Eq. A10 prints the closed form inside a stray integral; H is defined by the
    consistency condition A9, ρs(θi) = ∫ F_s cos θr dω_r, which with F_s from A5 gives
    H(θi) = (1/4π) ∫ h(α) dω_r. Its closed form is

        H(θ) = 1/(2e²) [(1 − e²) cos θ + (2e² + (1 − e²)² cos²θ) / sqrt(4e² + (1 − e²)² cos²θ)].

    Derivation: change variables from the reflected direction to the half vector m,
    dω_r = 4 (w_i·m) dω_m, so H = (1/π) ∫ h(α_m) (w_i·m) dω_m over the half vectors whose
    reflection stays above the surface. With u = cos²α_m, h depends on α_m alone, the
    azimuthal integral of w_i·m over the admissible cap reduces to elementary terms, and the
    remaining integral of the rational function 1/(e² + (1 − e²)(1 − u))² gives the form
    above. Checks: H(0) = 1/(e²(1 + e²)), H(π/2) = 1/(2e), and H ≡ 1/2 at e = 1 (h ≡ 1,
    H = 2π/4π). The test suite verifies it against independent quadrature down to e = 1e-4.

    Parameters
    ----------
    theta : array_like, radians
        Incidence angle θi; only cos θ enters, clipped at 0 below the horizon. Must be
        finite.
    e : float in [E_MIN, 1]
        Glint eccentricity (specularity parameter), a scalar; E_MIN = 1e-12.

    Returns
    -------
    H : ndarray or float
        The closed form above, from 1/(e²(1 + e²)) at θ = 0 to 1/(2e) at θ = π/2 (and
        below the horizon); the shape of ``theta``, a Python float for a scalar ``theta``.

    Raises
    ------
    ParameterError
        When ``e`` is not a real number in [E_MIN, 1] or ``theta`` is not finite.

    References
    ----------
    Jin & Levine (2009), Eqs. A9 and A10.
    Sandford & Robertson (1985).
    """
    e = check_real("e", e, low=E_MIN, high=1.0)
    c, _ = _cos_sin(theta, "theta")
    return _out(_H_scaled(np.maximum(c, 0.0), e) / (2.0 * e * e), theta)
