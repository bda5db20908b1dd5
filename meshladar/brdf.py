"""BRDFs: the protocol every forward model accepts, and the Sandford-Robertson (SR) model,
exact and numerically stable at every extreme.

The protocol (:class:`BRDF`): a coating defines ``projected(cos_theta, sin_theta)``, its
monostatic weight F(θ; −θ)·cos θ, and inherits ``monostatic``; a bistatic receiver needs
``bistatic`` as well. Built in: :class:`SandfordRobertson`, :class:`Lambertian`,
:class:`Phong`, :class:`GGX` (Mitsuba's rough conductor) and :class:`Tabulated` (measured).

The SR model (Jin & Levine 2009, Appendix A) splits reflection into a diffuse lobe
(Eqs. A1-A4) and a specular glint lobe (Eqs. A5-A10), tied together by energy
conservation (Eqs. 3, A7, A8)::

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
α = θ.

Conventions
-----------
* Angles are polar angles from the outward surface normal, in radians. Directions point
  away from the surface (toward the source, toward the receiver).
* Every function here depends on an angle only through its cosine and the magnitude of its
  sine: it is even and 2π-periodic in θ. Where a direction is below the horizon
  (cos θ < 0) the BRDF is exactly 0. At the horizon itself (cos θ = 0, reachable with
  direction vectors) F is evaluated as at θ = fl(π/2), whose cosine is 6.1e-17, so it stays
  finite; the projected weight F·cos θr is continuous up to and including θr = π/2.
* BRDF values are in 1/sr.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from scipy.special import xlogy

from ._validate import (check_choice, check_flag, check_name, check_real, finite_array,
                        unit_vectors)
from .errors import EnergyConservationWarning, ModelError, ParameterError
from .precision import COS_HORIZON as _COS_HORIZON
from .precision import E_MIN
from .precision import ENERGY_SLACK as _ENERGY_SLACK

__all__ = [
    "BRDF",
    "SandfordRobertson",
    "Lambertian",
    "Phong",
    "GGX",
    "Tabulated",
    "diffuse_shape",
    "diffuse_normalization",
    "glint_lobe",
    "specular_normalization",
    "LOBES",
    "E_MIN",
]

#: The lobe selections a :class:`SandfordRobertson` accepts.
LOBES = ("both", "diffuse", "specular")



#: Below this value of c = 1 − b², G(b) is summed as its Taylor series in c (A3 cancels
#: catastrophically as b → 1); above, the closed form loses at most ~2 bits.
_G_SERIES_BELOW = 0.5
#: Terms of that series: the tail after 64 terms is < 0.5**64 / (65·66) ≈ 1e-23 of G ≥ 1/2.
_G_SERIES_TERMS = 64



# --------------------------------------------------------------------------------------
# The model's functions, vectorised, on (cos, sin) pairs: private kernels first.
# --------------------------------------------------------------------------------------

def _safe_divide(num, den, fill):
    """num / den where den > 0, ``fill`` where den == 0, without a numpy warning."""
    num, den = np.broadcast_arrays(np.asarray(num, np.float64), np.asarray(den, np.float64))
    out = np.full(num.shape, fill, dtype=np.float64)
    np.divide(num, den, out=out, where=den > 0)
    return out


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

def _cos_sin(theta, name):
    t = finite_array(name, theta)
    return np.cos(t), np.abs(np.sin(t))


def _out(value, *inputs):
    """Scalar in, scalar out: a Python float when every input was 0-d."""
    if all(np.ndim(x) == 0 for x in inputs):
        return float(value)
    return value


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
        Glint angle: polar angle of the half vector.
    e : float in [E_MIN, 1]
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
        Incidence angle θi; only cos θ enters, clipped at 0 below the horizon.
    e : float in [E_MIN, 1]
    """
    e = check_real("e", e, low=E_MIN, high=1.0)
    c, _ = _cos_sin(theta, "theta")
    return _out(_H_scaled(np.maximum(c, 0.0), e) / (2.0 * e * e), theta)


# --------------------------------------------------------------------------------------
# The material.
# --------------------------------------------------------------------------------------

class BRDF:
    """The BRDF protocol: what a coating must give for every forward model to use it.

    A subclass defines :meth:`projected`, the monostatic weight F(θ; −θ)·cos θ of the
    paper's Eq. 8 on arrays of (cos θ, sin θ) with cos θ ≥ 0 (0 below the horizon, finite
    up to and including θ = π/2). Everything else derives from it: :meth:`monostatic` for
    users, :meth:`value` (F itself) for the mesh engine. A bistatic receiver needs
    :meth:`bistatic` too. ``kernel_params`` (a row for the compiled SR kernel) and
    ``angular_scales`` (the narrowest features, for the analytic model's quadrature) are
    optional speed and accuracy hints.

    Examples
    --------
    >>> import numpy as np, meshladar as ml
    >>> class Matte(ml.brdf.BRDF):
    ...     def projected(self, cos_theta, sin_theta):
    ...         return 0.3 / np.pi * np.maximum(cos_theta, 0.0)
    >>> round(Matte().monostatic(0.0), 4)
    0.0955
    """

    #: Row of the compiled SR kernel's material table, or None (the engine then calls
    #: :meth:`value` on arrays: slower, same result).
    kernel_params = None

    #: (near normal, near grazing): the angular widths, in radians, of the fastest
    #: variation of F·cos θ near θ = 0 and θ = π/2, or None where it is smooth. The analytic
    #: model grades its quadrature panels to them.
    angular_scales = (None, None)

    name = None

    def projected(self, cos_theta, sin_theta):
        """F(θ; −θ)·cos θ in 1/sr for arrays cos θ ≥ 0 and sin θ = sqrt(1 − cos²θ) ≥ 0."""
        raise ModelError(f"{type(self).__name__} must define projected(cos_theta, "
                         "sin_theta), the monostatic F·cos θ (meshladar.brdf.BRDF)")

    def value(self, cos_theta, sin_theta):
        """F(θ; −θ) in 1/sr: the projected weight over cos θ (cos(fl(π/2)) at the horizon),
        0 below it."""
        c = np.asarray(cos_theta, np.float64)
        p = projected_weight(self, np.maximum(c, 0.0), sin_theta)
        return np.where(c >= 0, p / np.maximum(c, _COS_HORIZON), 0.0)

    def bistatic(self, cos_i, sin_i, cos_r, sin_r, cos_h, sin_h):
        """F(w_i, w_r)·cos θr in 1/sr from the cosines and sines of θi, θr and the half
        vector's polar angle; 0 below either horizon. Optional."""
        raise ModelError(f"{type(self).__name__} has no bistatic evaluation: define "
                         "bistatic() to use it with a bistatic receiver")

    def bistatic_value(self, cos_i, sin_i, cos_r, sin_r, cos_h, sin_h):
        """F(w_i, w_r) in 1/sr (the bistatic weight over cos θr)."""
        p = self.bistatic(cos_i, sin_i, cos_r, sin_r, cos_h, sin_h)
        return np.where((cos_i >= 0) & (cos_r >= 0), p / np.maximum(cos_r, _COS_HORIZON), 0.0)

    def monostatic(self, theta, *, projected=False):
        """F(θ; −θ) (or F·cos θ with ``projected=True``) for incidence angles θ in radians,
        0 below the horizon; a float for a scalar θ."""
        c, s = _cos_sin(theta, "theta")
        check_flag("projected", projected)
        out = projected_weight(self, np.maximum(c, 0.0), s) if projected else self.value(c, s)
        return _out(np.where(c >= 0, out, 0.0), theta)

    def evaluate(self, incident, reflected, normal=(0.0, 0.0, 1.0), *, projected=False):
        """F(w_i, w_r) for arbitrary (bistatic) directions, in 1/sr.

        Parameters
        ----------
        incident : (..., 3) array_like
            Direction from the surface toward the source; need not be unit length.
        reflected : (..., 3) array_like
            Direction from the surface toward the receiver.
        normal : (..., 3) array_like, default +z
            Outward surface normal. All three broadcast together.
        projected : bool, keyword-only
            Return F·cos θr, finite up to and including θr = π/2.

        Returns
        -------
        (...) ndarray
            0 where either direction is below the horizon.
        """
        check_flag("projected", projected)
        w_i = unit_vectors("incident", incident)
        w_r = unit_vectors("reflected", reflected)
        n = unit_vectors("normal", normal)
        try:
            np.broadcast_shapes(w_i.shape, w_r.shape, n.shape)
        except ValueError:
            raise ParameterError(f"incident, reflected and normal must broadcast together; got "
                                 f"shapes {w_i.shape}, {w_r.shape}, {n.shape}") from None
        cos_i, sin_i = _cos_sin_vec(w_i, n)
        cos_r, sin_r = _cos_sin_vec(w_r, n)
        half = w_i + w_r
        norm = np.linalg.norm(half, axis=-1)
        # Opposite directions (both on the horizon): α = π/2
        cos_a = _safe_divide(np.einsum("...k,...k->...", half, n), norm, 0.0)
        sin_a = _safe_divide(np.linalg.norm(np.cross(half, n), axis=-1), norm, 1.0)
        return self._evaluate_cs(cos_i, sin_i, cos_r, sin_r, cos_a, sin_a, projected)

    def _evaluate_cs(self, cos_i, sin_i, cos_r, sin_r, cos_a, sin_a, projected):
        if projected:
            visible = (cos_i >= 0) & (cos_r >= 0)
            return np.where(visible, self.bistatic(cos_i, sin_i, cos_r, sin_r, cos_a, sin_a),
                            0.0)
        return self.bistatic_value(cos_i, sin_i, cos_r, sin_r, cos_a, sin_a)

    def evaluate_angles(self, theta_i, theta_r, delta_phi=0.0, *, projected=False):
        """F for polar angles θi, θr and relative azimuth Δφ = φr − φi, in 1/sr.

        Δφ = 0 with θr = θi is the monostatic geometry; Δφ = π with θr = θi is the mirror
        (Snell) direction. Angles in radians, broadcast together.
        """
        ti = finite_array("theta_i", theta_i)
        tr = finite_array("theta_r", theta_r)
        dp = finite_array("delta_phi", delta_phi)
        zero = np.zeros(np.broadcast(ti, tr, dp).shape)
        w_i = np.stack([np.sin(ti) + zero, zero, np.cos(ti) + zero], axis=-1)
        w_r = np.stack([np.sin(tr) * np.cos(dp) + zero, np.sin(tr) * np.sin(dp) + zero,
                        np.cos(tr) + zero], axis=-1)
        return _out(self.evaluate(w_i, w_r, projected=projected), theta_i, theta_r, delta_phi)

    def describe(self) -> dict:
        """A JSON-serialisable description: the model's name and its parameters."""
        import dataclasses

        params = ({f.name: getattr(self, f.name) for f in dataclasses.fields(self)
                   if f.name != "name"} if dataclasses.is_dataclass(self) else {})
        return {"model": type(self).__name__, "name": self.name,
                **{k: v.tolist() if isinstance(v, np.ndarray) else v
                   for k, v in params.items()}}


#: The built-in models, whose outputs are trusted; a user's are checked (shape, finite, ≥ 0).
_TRUSTED: set = set()


def projected_weight(m, cos_theta, sin_theta):
    """``m.projected(cos θ, sin θ)`` as a float64 array of the inputs' shape, checked for a
    user's model: finite and non-negative, else a ParameterError naming the class."""
    cos_theta = np.maximum(cos_theta, 0.0)             # the protocol's domain: cos θ >= 0
    out = m.projected(cos_theta, sin_theta)
    if type(m) in _TRUSTED:
        return out
    shape = np.broadcast(np.asarray(cos_theta), np.asarray(sin_theta)).shape
    try:
        out = np.broadcast_to(np.asarray(out, dtype=np.float64), shape)
    except (TypeError, ValueError):
        raise ParameterError(f"{type(m).__name__}.projected must return real numbers of the "
                             f"inputs' shape {shape}; got {type(out).__name__} of shape "
                             f"{np.shape(out)}") from None
    bad = ~np.isfinite(out) | (out < 0)
    if bad.any():
        k = np.flatnonzero(bad.ravel())[0]
        raise ParameterError(f"{type(m).__name__}.projected must be finite and non-negative; "
                             f"got {float(out.ravel()[k]):.6g} at cos theta = "
                             f"{float(np.broadcast_to(cos_theta, shape).ravel()[k]):.6g}")
    return out


def check_brdf(name, value):
    """``value`` if it follows the BRDF protocol, else a ParameterError naming ``name``."""
    if not isinstance(value, BRDF):
        raise ParameterError(f"{name} must be a meshladar.brdf.BRDF (SandfordRobertson, "
                             f"Lambertian, Phong, GGX, Tabulated or a subclass); got "
                             f"{type(value).__name__}")
    if type(value).projected is BRDF.projected:
        raise ModelError(f"{name}: {type(value).__name__} must define projected(cos_theta, "
                         "sin_theta), the monostatic F·cos θ (meshladar.brdf.BRDF)")
    return value


@dataclass(frozen=True)
class SandfordRobertson(BRDF):
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

    Examples
    --------
    >>> import numpy as np, meshladar as ml
    >>> m = ml.SandfordRobertson(rho_d=0.047, epsilon=0.53, b=0.1, e=0.007)
    >>> round(m.monostatic(0.0), 1)             # the aluminium glint at normal incidence
    651.0
    >>> float(m.monostatic(np.pi / 2, projected=True)) > 0   # F·cos θ finite at grazing
    True

    References
    ----------
    Jin & Levine, Appl. Opt. 48 (2009), Eqs. (1)-(4), (8), (A1)-(A10).
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
        """Directional diffuse reflectance ρd g(θ)/G(b) (A4), 0 for lobes='specular'."""
        c, s = _cos_sin(theta, "theta")
        scale = self.rho_d / self.G if self.lobes != "specular" else 0.0
        return _out(np.where(c >= 0, scale * _g(np.abs(c), s, self.b), 0.0), theta)

    def emissivity(self, theta):
        """Directional emissivity ε g(θ)/G(b) (A7)."""
        c, s = _cos_sin(theta, "theta")
        return _out(np.where(c >= 0, self.epsilon / self.G * _g(np.abs(c), s, self.b), 0.0),
                    theta)

    def specular_reflectance(self, theta):
        """Directional specular reflectivity ρs(θ) = 1 − (ε + ρd) g(θ)/G(b) (A8).

        Clipped at 0 (it is ≥ 0 for every coating that includes the specular lobe);
        0 for lobes='diffuse'.
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
        ρs(π/2) e/(2π) for the glint lobe."""
        return self._core(cos_theta, sin_theta, cos_theta, sin_theta, cos_theta, sin_theta,
                          True)

    def value(self, cos_theta, sin_theta):
        return self._core(cos_theta, sin_theta, cos_theta, sin_theta, cos_theta, sin_theta,
                          False)

    def bistatic(self, cos_i, sin_i, cos_r, sin_r, cos_h, sin_h):
        return self._core(cos_i, sin_i, cos_r, sin_r, cos_h, sin_h, True)

    def bistatic_value(self, cos_i, sin_i, cos_r, sin_r, cos_h, sin_h):
        return self._core(cos_i, sin_i, cos_r, sin_r, cos_h, sin_h, False)

    def _evaluate_cs(self, cos_i, sin_i, cos_r, sin_r, cos_a, sin_a, projected):
        return self._core(cos_i, sin_i, cos_r, sin_r, cos_a, sin_a, projected)

    @property
    def kernel_params(self):
        """(rho_d, epsilon, b, e, G, has_diffuse, has_specular): the compiled kernel's row."""
        return (self.rho_d, self.epsilon, self.b, self.e, self.G, float(self.has_diffuse),
                float(self.has_specular))

    @property
    def angular_scales(self):
        return (self.e if self.has_specular else None,
                min([x for x in ((self.b if self.has_diffuse and self.b > 0 else None),
                                 (2.0 * self.e if self.has_specular else None))
                     if x is not None], default=None))

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
        """
        c, s = _cos_sin(theta, "theta")
        return _out(self._core(c, s, c, s, c, s, check_flag("projected", projected)), theta)


_TRUSTED.add(SandfordRobertson)


def _cos_sin_vec(w, n):
    """cos and sin of the angle between unit vectors, sin from the cross product (accurate
    near 0 where sqrt(1 − cos²) is not)."""
    return (np.einsum("...k,...k->...", w, n), np.linalg.norm(np.cross(w, n), axis=-1))


# --------------------------------------------------------------------------------------
# More models on the protocol: Lambertian, Phong, GGX, tabulated.
# --------------------------------------------------------------------------------------

def _unit_interval(name, value):
    return check_real(name, value, low=0.0, high=1.0)


@dataclass(frozen=True)
class Lambertian(BRDF):
    """A perfectly diffuse coating: F = albedo/π in every direction.

    ``albedo`` in [0, 1] is the hemispherical reflectance (∫ F cos θr dω = albedo).
    Equal to ``SandfordRobertson(albedo, 0, 0, 1, lobes="diffuse")``, and traced by the
    same compiled kernel.
    """

    albedo: float
    name: str | None = field(default=None, kw_only=True, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "albedo", _unit_interval("albedo", self.albedo))
        check_name(self.name)

    def projected(self, cos_theta, sin_theta):
        return self.albedo / math.pi * np.maximum(np.asarray(cos_theta, np.float64), 0.0)

    def value(self, cos_theta, sin_theta):
        c = np.asarray(cos_theta, np.float64)
        return np.where(c >= 0, self.albedo / math.pi, 0.0)

    def bistatic(self, cos_i, sin_i, cos_r, sin_r, cos_h, sin_h):
        return np.where((cos_i >= 0) & (cos_r >= 0),
                        self.albedo / math.pi * np.maximum(cos_r, 0.0), 0.0)

    @property
    def kernel_params(self):
        # SR with b = 0 (g ≡ 1, G = 1), diffuse only: F = rho_d / π
        return (self.albedo, 0.0, 0.0, 1.0, 1.0, 1.0, 0.0)


@dataclass(frozen=True)
class Phong(BRDF):
    """The energy-normalised modified Phong BRDF (Lafortune & Willems 1994), the Phong
    family that lidar simulators such as HELIOS++ and classic graphics use::

        F = kd/π + ks (n + 2)/(2π) cos^n ψ

    with ψ the angle between the mirror direction of the source and the receiver (0 where
    ψ > 90°). Monostatic, ψ = 2θ. ``kd + ks <= 1`` conserves energy; at normal incidence
    the specular lobe reflects exactly ks. ``exponent`` n ≥ 0 (n = 0: a second diffuse
    term; n = 1000: a lobe about 2.5° wide).
    """

    kd: float
    ks: float
    exponent: float
    name: str | None = field(default=None, kw_only=True, compare=False)

    def __post_init__(self):
        check_name(self.name)
        object.__setattr__(self, "kd", _unit_interval("kd", self.kd))
        object.__setattr__(self, "ks", _unit_interval("ks", self.ks))
        object.__setattr__(self, "exponent", check_real("exponent", self.exponent, low=0.0,
                                                        high=1e6))
        if self.kd + self.ks > 1.0 + _ENERGY_SLACK:
            raise ParameterError(f"kd + ks must be at most 1 (energy conservation); got "
                                 f"kd + ks = {self.kd + self.ks:.6g}")

    def _lobe(self, cos_psi):
        n = self.exponent
        c = np.asarray(cos_psi, np.float64)
        lobe = np.zeros(c.shape)
        np.power(c, n, out=lobe, where=c > 0)                    # 0 beyond ψ = 90°
        return self.ks * (n + 2.0) / (2.0 * math.pi) * lobe

    def projected(self, cos_theta, sin_theta):
        c = np.maximum(np.asarray(cos_theta, np.float64), 0.0)
        s = np.asarray(sin_theta, np.float64)
        cos_2t = (c - s) * (c + s)                              # cos 2θ, exact near 45°
        return (self.kd / math.pi + self._lobe(cos_2t)) * c

    def bistatic(self, cos_i, sin_i, cos_r, sin_r, cos_h, sin_h):
        ch = np.asarray(cos_h, np.float64)
        ci = np.asarray(cos_i, np.float64)
        cr = np.asarray(cos_r, np.float64)
        # mirror m = 2(n·w_i)n − w_i;  m·w_r = 2 cos θi cos θr − w_i·w_r, and
        # w_i·w_r = 2 cos²β − 1 with β the half angle: |w_i + w_r| = 2 cos β and
        # n·(w_i + w_r) = cos θi + cos θr = 2 cos β cos θh, so cos β = (ci + cr)/(2 ch)
        cb = np.where(ch > 0, (ci + cr) / (2.0 * np.where(ch > 0, ch, 1.0)), 0.0)
        cos_psi = 2.0 * ci * cr - (2.0 * cb * cb - 1.0)
        visible = (ci >= 0) & (cr >= 0)
        return np.where(visible, (self.kd / math.pi + self._lobe(cos_psi)) * np.maximum(cr, 0),
                        0.0)

    @property
    def angular_scales(self):
        # the monostatic lobe cos^n(2θ) falls to 1/e at 2θ ≈ sqrt(2/n)
        return (0.5 * math.sqrt(2.0 / self.exponent) if self.exponent > 0 else None, None)


@dataclass(frozen=True)
class GGX(BRDF):
    """A rough conductor with the GGX (Trowbridge-Reitz) microfacet distribution and
    separable Smith shadowing, as Mitsuba 3's ``roughconductor`` (``distribution="ggx"``)::

        F = R D(h) G1(w_i) G1(w_r) / (4 cos θi cos θr)
        D = α² / (π (α² cos²θh + sin²θh)²)
        G1(w) = 2 cos θ / (cos θ + sqrt(cos²θ + α² sin²θ))

    ``alpha`` in [1e-4, 1] is the roughness (Mitsuba's ``alpha``); ``reflectance`` R in
    [0, 1] the Fresnel factor, taken constant (Mitsuba's ``specular_reflectance`` with a
    perfect conductor; 1 by default). Monostatic, θh = θ and
    F cos θ = R D(θ) cos θ / (cos θ + sqrt(cos²θ + α² sin²θ))², finite up to θ = π/2.
    """

    alpha: float
    reflectance: float = 1.0
    name: str | None = field(default=None, kw_only=True, compare=False)

    def __post_init__(self):
        check_name(self.name)
        object.__setattr__(self, "alpha", check_real("alpha", self.alpha, low=1e-4, high=1.0))
        object.__setattr__(self, "reflectance",
                           _unit_interval("reflectance", self.reflectance))

    def _D(self, ch, sh):
        a = self.alpha
        d = np.hypot(a * ch, sh) ** 2
        return a * a / (math.pi * d * d)

    def _g1_over_2c(self, c, s):
        """G1 / (2 cos θ) = 1 / (cos θ + sqrt(cos²θ + α² sin²θ)), finite at cos θ = 0."""
        return 1.0 / (c + np.hypot(c, self.alpha * s))

    def projected(self, cos_theta, sin_theta):
        c = np.maximum(np.asarray(cos_theta, np.float64), 0.0)
        s = np.asarray(sin_theta, np.float64)
        return self.reflectance * self._D(c, s) * c * self._g1_over_2c(c, s) ** 2

    def bistatic(self, cos_i, sin_i, cos_r, sin_r, cos_h, sin_h):
        ci = np.maximum(np.asarray(cos_i, np.float64), 0.0)
        cr = np.maximum(np.asarray(cos_r, np.float64), 0.0)
        ch = np.maximum(np.asarray(cos_h, np.float64), 0.0)
        # F cos θr = R D G1(i) G1(r) / (4 cos θi) = R D cos θr · g(i) · g(r), g = G1/(2 cos)
        out = (self.reflectance * self._D(ch, np.asarray(sin_h, np.float64)) * cr
               * self._g1_over_2c(ci, np.asarray(sin_i, np.float64))
               * self._g1_over_2c(cr, np.asarray(sin_r, np.float64)))
        return np.where((np.asarray(cos_i) >= 0) & (np.asarray(cos_r) >= 0), out, 0.0)

    @property
    def angular_scales(self):
        return (self.alpha, None)


@dataclass(frozen=True, eq=False)
class Tabulated(BRDF):
    """A measured monostatic BRDF: F(θ) sampled at angles ``theta_deg``.

    ``theta_deg`` must increase strictly from 0 to 90 (degrees); ``values`` are F in 1/sr
    (or, with ``projected=True``, F·cos θ: give that form when F grows toward grazing
    incidence, as glossy coatings' does). Between samples F·cos θ is interpolated linearly
    in θ. Monostatic only.
    """

    theta_deg: np.ndarray
    values: np.ndarray
    projected_values: bool = field(default=False, kw_only=True)
    name: str | None = field(default=None, kw_only=True, compare=False)

    def __post_init__(self):
        check_name(self.name)
        check_flag("projected_values", self.projected_values)
        t = np.array(finite_array("theta_deg", self.theta_deg))          # copies: the user's
        v = np.array(finite_array("values", self.values))                # arrays stay theirs
        if t.ndim != 1 or t.size < 2:
            raise ParameterError(f"theta_deg must be a 1-D array of at least 2 angles; got "
                                 f"shape {t.shape}")
        if v.shape != t.shape:
            raise ParameterError(f"values must have theta_deg's shape {t.shape}; got {v.shape}")
        if t[0] != 0.0 or t[-1] != 90.0 or np.any(np.diff(t) <= 0):
            raise ParameterError(f"theta_deg must increase strictly from 0 to 90 degrees; got "
                                 f"{t[0]:g} ... {t[-1]:g}" + (" (not increasing)" if
                                                             np.any(np.diff(t) <= 0) else ""))
        if np.any(v < 0):
            k = int(np.argmax(v < 0))
            raise ParameterError(f"values must be non-negative; got {v[k]:g} at "
                                 f"{t[k]:g} degrees")
        weight = v.copy() if self.projected_values else v * np.cos(np.deg2rad(t))
        if not self.projected_values:
            weight[-1] = 0.0                                    # F cos θ at exactly 90°
        for k, a in (("theta_deg", t), ("values", v), ("_weight", weight)):
            a = np.array(a, dtype=np.float64)
            a.flags.writeable = False
            object.__setattr__(self, k, a)

    def __eq__(self, other):
        return (type(other) is Tabulated and np.array_equal(self.theta_deg, other.theta_deg)
                and np.array_equal(self._weight, other._weight))

    __hash__ = None

    def projected(self, cos_theta, sin_theta):
        c = np.maximum(np.asarray(cos_theta, np.float64), 0.0)
        theta = np.degrees(np.arctan2(np.asarray(sin_theta, np.float64), c))
        return np.interp(theta, self.theta_deg, self._weight)

    @property
    def angular_scales(self):
        step = float(np.min(np.diff(np.deg2rad(self.theta_deg))))
        return (step, step)

    def describe(self) -> dict:
        return {"model": "Tabulated", "name": self.name, "theta_deg": self.theta_deg.tolist(),
                "values": self.values.tolist(), "projected_values": self.projected_values}


_TRUSTED.update({Lambertian, Phong, GGX, Tabulated})
