"""The Sandford-Robertson (SR) model (Jin & Levine 2009, Appendix A): its functions and the
:class:`SandfordRobertson` coating, exact and numerically stable at every extreme.

SR splits reflection into a diffuse lobe (Eqs. A1-A4) and a specular glint lobe
(Eqs. A5-A10), tied together by energy conservation (Eqs. 3, A7, A8)::

    F(θi, θr) = F_d + F_s
    F_d = ρd g(θi) g(θr) / (π G(b)²)                          (A1)
    F_s = ρs(θi) h(α) / (4π H(θi) cos θr)                     (A5)
    g(θ) = 1 / (1 + b² tan²θ) = cos²θ / (cos²θ + b² sin²θ)    (A2)
    G(b) = [1 + b² ln(b²) / (1 − b²)] / (1 − b²)              (A3)
    h(α) = 1 / (e² cos²α + sin²α)²                            (A6)
    ρs(θ) = 1 − (ε + ρd) g(θ) / G(b)                          (A8)
    ε(θ)  = ε g(θ) / G(b)                                     (A7)

α is the glint angle: the polar angle of the half vector that bisects the directions to
the source and to the receiver. For the collocated (monostatic) ladar, θr = θi = θ and
α = θ. Conventions (angles, horizon, units) are :mod:`meshladar.brdf.base`'s.

Its compiled twin, ``meshladar.brdf._sandford_robertson_kernel.sr_monostatic``, takes
the coating's :attr:`SandfordRobertson.kernel_params` (a :class:`KernelRow`) and evaluates
the same expressions in the same order.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from functools import cached_property
from typing import NamedTuple

import numpy as np
from scipy.special import xlogy

from .._validate import check_choice, check_flag, check_name, check_real, finite_array
from ..errors import EnergyConservationWarning, ParameterError
from ..precision import COS_HORIZON as _COS_HORIZON
from ..precision import E_MIN
from ..precision import ENERGY_SLACK as _ENERGY_SLACK
from .base import BRDF, _cos_sin, _out, _safe_divide

__all__ = ["SandfordRobertson", "KernelRow", "diffuse_shape", "diffuse_normalization",
           "glint_lobe", "specular_normalization", "LOBES", "E_MIN"]

#: The lobe selections a :class:`SandfordRobertson` accepts.
LOBES = ("both", "diffuse", "specular")

#: Below this value of c = 1 − b², G(b) is summed as its Taylor series in c (A3 cancels
#: catastrophically as b → 1); above, the closed form loses at most ~2 bits.
_G_SERIES_BELOW = 0.5
#: Terms of that series: the tail after 64 terms is < 0.5**64 / (65·66) ≈ 1e-23 of G ≥ 1/2.
_G_SERIES_TERMS = 64


class KernelRow(NamedTuple):
    """One coating's row of the compiled SR kernel's material table (the flat arguments of
    the compiled ``sr_monostatic`` after cos θ, sin θ).

    Attributes
    ----------
    rho_d : float
        Diffuse spectral reflectivity ρd (A1).
    epsilon : float
        Spectral emissivity ε (A7).
    b : float
        Grazing-angle reflectivity (A2).
    e : float
        Glint eccentricity (A6).
    G : float
        Diffuse normalisation G(b) (A3).
    has_diffuse : float
        1.0 when the diffuse lobe is summed, else 0.0.
    has_specular : float
        1.0 when the specular (glint) lobe is summed, else 0.0.
    """

    rho_d: float
    epsilon: float
    b: float
    e: float
    G: float
    has_diffuse: float
    has_specular: float


# --------------------------------------------------------------------------------------
# The model's functions, vectorised, on (cos, sin) pairs: private kernels first.
# --------------------------------------------------------------------------------------

def _g(cos_t, sin_t, b):
    """Diffuse shape g (A2) as cos²θ / (cos²θ + b² sin²θ), scaled by hypot against under-
    and overflow. g = 1 where both terms vanish (b = 0 at θ = π/2), the b → 0 limit."""
    den = np.hypot(cos_t, b * sin_t)
    return _safe_divide(cos_t, den, 1.0) ** 2


def _G(b):
    """Diffuse normalisation G(b) (A3), stable on all of [0, 1].

    With c = 1 − b² (formed as (1 − b)(1 + b), exact near b = 1) and s = b²,
    G = (c + s ln s) / c² = Σ_k c^k / ((k + 1)(k + 2)). The closed form is used for
    c ≥ 1/2 (s ln s handled at s = 0 by xlogy), the series for c < 1/2.
    """
    b = np.asarray(b, dtype=np.float64)
    c = (1.0 - b) * (1.0 + b)
    s = b * b
    series = np.zeros_like(c)
    for k in range(_G_SERIES_TERMS - 1, -1, -1):
        series = series * c + 1.0 / ((k + 1) * (k + 2))
    c_safe = np.where(c >= _G_SERIES_BELOW, c, 1.0)
    closed = (c_safe + xlogy(s, s)) / (c_safe * c_safe)
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


@dataclass(frozen=True)
class SandfordRobertson(BRDF, builtin=True):
    r"""Sandford-Robertson BRDF of a coating (paper Eqs. 1-4, A1-A10).

    ========  =====  ============  ======================================================  =====
    name      unit   valid range   meaning                                                 eq.
    ========  =====  ============  ======================================================  =====
    rho_d     1      [0, 1]        diffuse spectral reflectivity ρd                        A1
    epsilon   1      [0, 1]        spectral emissivity ε (hemispherical, normal-weighted)  A7
    b         1      [0, 1]        grazing-angle reflectivity: diffuse lobe narrowness     A2
    e         1      [1e-12, 1]    glint eccentricity: specular lobe width (rad, ~e)       A6
    lobes     -      both |        which lobes F sums; "diffuse" alone is the paper's      4
                     diffuse |     Figs 5-7, "specular" alone with rho_d = epsilon = 0
                     specular      (ρs ≡ 1) its Fig. 8
    name      -      any str       a label for tables and reprs; not part of equality       -
    ========  =====  ============  ======================================================  =====

    Energy conservation (Eq. 3) gives the specular reflectivity
    ρs(θ) = 1 − (ε + ρd) g(θ)/G(b) (A8). When the specular lobe is included it must be
    non-negative at every θ, i.e. ``rho_d + epsilon <= G(b)``; otherwise construction
    raises :class:`~meshladar.errors.ParameterError`. A diffuse-only coating with
    ρd > G(b) (the paper's ρd = 1, b = 0.99 surface reflects up to 1/G ≈ 1.99 of the
    incident light at normal incidence) is allowed with an
    :class:`~meshladar.errors.EnergyConservationWarning`.

    The glint lobe h(α) is the Trowbridge-Reitz (GGX) distribution with roughness e.

    Parameters
    ----------
    rho_d : float
        Diffuse spectral reflectivity ρd, in [0, 1] (A1).
    epsilon : float
        Spectral emissivity ε, in [0, 1] (A7).
    b : float
        Grazing-angle reflectivity, in [0, 1] (A2): 0 is a Lambertian diffuse lobe, larger
        values a narrower one.
    e : float
        Glint eccentricity, in [E_MIN, 1] = [1e-12, 1] (A6): small values are mirror-like,
        1 a flat lobe (h ≡ 1).
    lobes : {"both", "diffuse", "specular"}, keyword-only, default "both"
        Which lobes F sums (Eq. 4). With "specular" the diffuse term is left out but ρd
        still enters ρs (A8).
    name : str or None, keyword-only, default None
        A label for tables and reprs; not part of equality.

    Raises
    ------
    ParameterError
        When ``rho_d``, ``epsilon``, ``b`` or ``e`` is not a finite real in its range,
        ``lobes`` is not one of :data:`LOBES`, ``name`` is neither a str nor None, or the
        specular lobe is included and rho_d + epsilon > G(b)·(1 + 1e-12).

    Warns
    -----
    EnergyConservationWarning
        When ``lobes="diffuse"`` and rho_d / G(b) > 1 + 1e-12.

    References
    ----------
    Jin & Levine (2009), Eqs. 1-4, 8 and A1-A10.
    Sandford & Robertson (1985), the original BRDF.

    Examples
    --------
    >>> import numpy as np, meshladar as ml
    >>> m = ml.SandfordRobertson(rho_d=0.047, epsilon=0.53, b=0.1, e=0.007)
    >>> round(float(m.monostatic(0.0)), 1)      # the aluminium glint at normal incidence
    651.1
    >>> float(m.monostatic(np.pi / 2, projected=True)) > 0   # F·cos θ finite at grazing
    True
    """

    rho_d: float
    epsilon: float
    b: float
    e: float
    lobes: str = field(default="both", kw_only=True)
    name: str | None = field(default=None, kw_only=True, compare=False)

    def __post_init__(self):
        for param, low, high in (("rho_d", 0.0, 1.0), ("epsilon", 0.0, 1.0),
                                 ("b", 0.0, 1.0), ("e", E_MIN, 1.0)):
            object.__setattr__(self, param, check_real(param, getattr(self, param),
                                                       low=low, high=high))
        check_choice("lobes", self.lobes, LOBES)
        check_name(self.name)
        G = self.G
        if self.has_specular:
            total = self.rho_d + self.epsilon
            if total > G * (1.0 + _ENERGY_SLACK):
                raise ParameterError(
                    f"coating is not energy-conserving: rho_d + epsilon = {total:.6g} exceeds "
                    f"G(b) = {G:.6g} (b = {self.b:g}) by {total - G:.3g}, so the specular "
                    f"reflectivity rho_s(0) = 1 - (rho_d + epsilon)/G(b) = {1 - total / G:.3g} "
                    "< 0; lower rho_d or epsilon, or use lobes='diffuse'")
        peak = self.rho_d / G
        if self.lobes == "diffuse" and peak > 1.0 * (1.0 + _ENERGY_SLACK):
            warnings.warn(
                f"diffuse-only coating is not energy-conserving: it reflects up to "
                f"rho_d/G(b) = {peak:.4g} of the incident light at normal incidence "
                f"(rho_d = {self.rho_d:g}, b = {self.b:g}); allowed, as in the paper's Sec. 4.A",
                EnergyConservationWarning, stacklevel=3)

    # -- derived constants --------------------------------------------------------------
    @cached_property
    def G(self) -> float:
        """Diffuse normalisation G(b) (A3)."""
        return float(_G(self.b))

    @property
    def has_diffuse(self) -> bool:
        """True when F includes the diffuse lobe (and ρd > 0)."""
        return self.lobes != "specular" and self.rho_d > 0.0

    @property
    def has_specular(self) -> bool:
        """True when F includes the specular (glint) lobe."""
        return self.lobes != "diffuse"

    @property
    def is_lambertian(self) -> bool:
        """True when F is the constant ρd/π: no specular lobe and b = 0."""
        return not self.has_specular and self.b == 0.0

    # -- directional quantities (A4, A7, A8) --------------------------------------------
    def diffuse_reflectance(self, theta):
        """Directional diffuse reflectance ρd g(θ)/G(b) (A4), 0 for lobes='specular'.

        Parameters
        ----------
        theta : array_like, radians
            Incidence angle from the outward normal; must be finite. Only cos θ and |sin θ|
            enter; the result is 0 where cos θ < 0 (below the horizon).

        Returns
        -------
        ndarray or float
            Dimensionless, the shape of ``theta``; a Python float for a scalar ``theta``.

        Raises
        ------
        ParameterError
            When ``theta`` is not finite real numbers.

        References
        ----------
        Jin & Levine (2009), Eq. A4.
        """
        c, s = _cos_sin(theta, "theta")
        scale = self.rho_d / self.G if self.lobes != "specular" else 0.0
        return _out(np.where(c >= 0, scale * _g(np.abs(c), s, self.b), 0.0), theta)

    def emissivity(self, theta):
        """Directional emissivity ε g(θ)/G(b) (A7).

        It does not depend on ``lobes``.

        Parameters
        ----------
        theta : array_like, radians
            Incidence angle from the outward normal; must be finite. Only cos θ and |sin θ|
            enter; the result is 0 where cos θ < 0 (below the horizon).

        Returns
        -------
        ndarray or float
            Dimensionless, the shape of ``theta``; a Python float for a scalar ``theta``.

        Raises
        ------
        ParameterError
            When ``theta`` is not finite real numbers.

        References
        ----------
        Jin & Levine (2009), Eq. A7.
        """
        c, s = _cos_sin(theta, "theta")
        return _out(np.where(c >= 0, self.epsilon / self.G * _g(np.abs(c), s, self.b), 0.0),
                    theta)

    def specular_reflectance(self, theta):
        """Directional specular reflectivity ρs(θ) = 1 − (ε + ρd) g(θ)/G(b) (A8).

        Clipped at 0 (it is ≥ 0 for every coating that includes the specular lobe);
        0 for lobes='diffuse'.

        Parameters
        ----------
        theta : array_like, radians
            Incidence angle from the outward normal; must be finite. Only cos θ and |sin θ|
            enter; the result is 0 where cos θ < 0 (below the horizon).

        Returns
        -------
        ndarray or float
            Dimensionless, in [0, 1], the shape of ``theta``; a Python float for a scalar
            ``theta``.

        Raises
        ------
        ParameterError
            When ``theta`` is not finite real numbers.

        References
        ----------
        Jin & Levine (2009), Eq. A8.
        """
        c, s = _cos_sin(theta, "theta")
        rs = self._rho_s(np.abs(c), s) if self.has_specular else np.zeros_like(c)
        return _out(np.where(c >= 0, rs, 0.0), theta)

    def _rho_s(self, cos_i, sin_i):
        return np.maximum(1.0 - (self.epsilon + self.rho_d) / self.G * _g(cos_i, sin_i, self.b),
                          0.0)

    # -- evaluation ---------------------------------------------------------------------
    def _core(self, cos_i, sin_i, cos_r, sin_r, cos_a, sin_a, projected):
        """F (or F·cos θr) from cosines and sines of θi, θr and α; 0 below either horizon."""
        visible = (cos_i >= 0) & (cos_r >= 0)
        ci = np.maximum(cos_i, 0.0)
        cr = np.maximum(cos_r, 0.0)
        out = np.zeros(np.broadcast(ci, cr, cos_a).shape)
        g_i = _g(ci, sin_i, self.b)
        if self.has_diffuse:
            f_d = self.rho_d / (math.pi * self.G ** 2) * g_i * _g(cr, sin_r, self.b)   # A1
            out = out + (f_d * cr if projected else f_d)
        if self.has_specular:
            rho_s = self._rho_s(ci, sin_i)                                             # A8
            f_s_cos = rho_s * _glint_over_H(cos_a, sin_a, ci, self.e) / (4.0 * math.pi)  # A5·cos θr
            out = out + (f_s_cos if projected else f_s_cos / np.maximum(cr, _COS_HORIZON))
        return np.where(visible, out, 0.0)

    def projected(self, cos_theta, sin_theta):
        """F(θ; −θ)·cos θ, the weight of the paper's Eq. 8: the specular term's 1/cos θ (A5)
        cancels exactly, so this is finite up to and including θ = π/2, where it equals
        ρs(π/2) e/(2π) for the glint lobe.

        Monostatic: θr = θi = θ and the glint angle α = θ.

        Parameters
        ----------
        cos_theta : array_like
            cos θ of the monostatic incidence angle θ; the result is 0 where it is < 0.
        sin_theta : array_like
            sin θ ≥ 0, broadcasting with ``cos_theta``.

        Returns
        -------
        ndarray
            F(θ; −θ)·cos θ in 1/sr, float64, of the inputs' broadcast shape.

        References
        ----------
        Jin & Levine (2009), Eqs. 8, A1, A5 and A8.
        """
        return self._core(cos_theta, sin_theta, cos_theta, sin_theta, cos_theta, sin_theta,
                          True)

    def value(self, cos_theta, sin_theta):
        """F(θ; −θ) in 1/sr, evaluated directly (not as :meth:`projected` over cos θ): the
        specular term's 1/cos θr (A5) is taken as 1/max(cos θ, cos(fl(π/2))).

        Monostatic: θr = θi = θ and the glint angle α = θ.

        Parameters
        ----------
        cos_theta : array_like
            cos θ of the monostatic incidence angle θ; the result is 0 where it is < 0.
        sin_theta : array_like
            sin θ ≥ 0, broadcasting with ``cos_theta``.

        Returns
        -------
        ndarray
            F(θ; −θ) in 1/sr, float64, of the inputs' broadcast shape.

        References
        ----------
        Jin & Levine (2009), Eqs. 4, A1, A5 and A8.
        """
        return self._core(cos_theta, sin_theta, cos_theta, sin_theta, cos_theta, sin_theta,
                          False)

    def bistatic(self, cos_i, sin_i, cos_r, sin_r, cos_h, sin_h):
        """F(w_i, w_r)·cos θr in 1/sr; 0 where cos θi < 0 or cos θr < 0. The specular
        term's 1/cos θr (A5) cancels, so it is finite at θr = π/2.

        Parameters
        ----------
        cos_i, sin_i : array_like
            Cosine and sine (≥ 0) of θi, the polar angle of the direction to the source.
        cos_r, sin_r : array_like
            Cosine and sine (≥ 0) of θr, the polar angle of the direction to the receiver.
        cos_h, sin_h : array_like
            Cosine and sine of the glint angle α, the half vector's polar angle. All six
            broadcast together.

        Returns
        -------
        ndarray
            F·cos θr in 1/sr, float64, of the inputs' broadcast shape.

        References
        ----------
        Jin & Levine (2009), Eqs. A1, A5 and A8.
        """
        return self._core(cos_i, sin_i, cos_r, sin_r, cos_h, sin_h, True)

    def bistatic_value(self, cos_i, sin_i, cos_r, sin_r, cos_h, sin_h):
        """F(w_i, w_r) in 1/sr; 0 where cos θi < 0 or cos θr < 0. The specular term's
        1/cos θr (A5) is taken as 1/max(cos θr, cos(fl(π/2))).

        Parameters
        ----------
        cos_i, sin_i : array_like
            Cosine and sine (≥ 0) of θi, the polar angle of the direction to the source.
        cos_r, sin_r : array_like
            Cosine and sine (≥ 0) of θr, the polar angle of the direction to the receiver.
        cos_h, sin_h : array_like
            Cosine and sine of the glint angle α, the half vector's polar angle. All six
            broadcast together.

        Returns
        -------
        ndarray
            F in 1/sr, float64, of the inputs' broadcast shape.

        References
        ----------
        Jin & Levine (2009), Eqs. 4, A1, A5 and A8.
        """
        return self._core(cos_i, sin_i, cos_r, sin_r, cos_h, sin_h, False)

    def _evaluate_cs(self, cos_i, sin_i, cos_r, sin_r, cos_a, sin_a, projected):
        return self._core(cos_i, sin_i, cos_r, sin_r, cos_a, sin_a, projected)

    @property
    def kernel_params(self):
        """(rho_d, epsilon, b, e, G, has_diffuse, has_specular): the compiled kernel's row
        (:class:`KernelRow`)."""
        return KernelRow(self.rho_d, self.epsilon, self.b, self.e, self.G,
                         float(self.has_diffuse), float(self.has_specular))

    @property
    def angular_scales(self):
        return (self.e if self.has_specular else None,
                min([x for x in ((self.b if self.has_diffuse and self.b > 0 else None),
                                 (2.0 * self.e if self.has_specular else None))
                     if x is not None], default=None))

    def lobe_width(self):
        """e, the glint lobe's roughness (a GGX lobe: a quarter of its peak at θ ≈ e); None
        without the specular lobe.

        Returns
        -------
        float or None
            ``e`` (read as radians of θ) when ``lobes`` is "both" or "specular", else None.
        """
        return self.e if self.has_specular else None

    def monostatic(self, theta, *, projected=False):
        """F(θ; −θ): the BRDF for a collocated transmitter and receiver, in 1/sr.

        The receiver direction equals the source direction, so θr = θi = θ and the glint
        angle α = θ.

        Parameters
        ----------
        theta : array_like, radians
            Incidence angle from the outward normal. F depends on θ through cos θ and
            |sin θ| only; it is 0 where cos θ < 0 (below the horizon). Must be finite.
        projected : bool, keyword-only
            Return F(θ)·cos θ, the weight of the paper's Eq. 8. The specular term's
            1/cos θ (A5) cancels exactly, so this is finite and continuous up to and
            including θ = π/2, where it equals ρs(π/2) e/(2π) for the glint lobe.

        Returns
        -------
        ndarray or float
            Same shape as ``theta``; a float for scalar input.

        Raises
        ------
        ParameterError
            When ``theta`` is not finite real numbers or ``projected`` is not a bool.

        References
        ----------
        Jin & Levine (2009), Eqs. 4, 8, A1, A5 and A8.
        """
        c, s = _cos_sin(theta, "theta")
        return _out(self._core(c, s, c, s, c, s, check_flag("projected", projected)), theta)

