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
the coating's :attr:`SandfordRobertson.kernel_params` (a :class:`KernelRow`, from
:mod:`meshladar.brdf.kernel_table`) and evaluates the same expressions, rearranged to one
square root instead of three (from cos θ and sin²θ; equal to 1e-13).
The functions g, G, h and H are in :mod:`meshladar.brdf.sandford_robertson_functions`, the
rules the parameters follow in ``_sandford_robertson_checks``; the public names of both are
importable from here as well.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .._validate import check_flag
from ..precision import COS_HORIZON as _COS_HORIZON
from ..precision import E_MIN
from ._sandford_robertson_checks import LOBES, _check_energy, _checked_parameters
from ._shared import _cos_sin, _out
from .base import BRDF
from .kernel_table import KernelRow
from .sandford_robertson_functions import (_G, _g, _glint_over_H, diffuse_normalization,
                                           diffuse_shape, glint_lobe, specular_normalization)

__all__ = ["SandfordRobertson", "KernelRow", "diffuse_shape", "diffuse_normalization",
           "glint_lobe", "specular_normalization", "LOBES", "E_MIN"]


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
        for param, value in _checked_parameters(self).items():
            object.__setattr__(self, param, value)
        _check_energy(self)

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
