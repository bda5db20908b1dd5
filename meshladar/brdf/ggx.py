"""A rough conductor with the GGX (Trowbridge-Reitz) microfacet distribution, as Mitsuba 3's
``roughconductor``."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._validate import check_name, check_real
from ._shared import _unit_interval
from .base import BRDF

__all__ = ["GGX"]


@dataclass(frozen=True)
class GGX(BRDF, builtin=True):
    """A rough conductor with the GGX (Trowbridge-Reitz) microfacet distribution and
    separable Smith shadowing, as Mitsuba 3's ``roughconductor`` (``distribution="ggx"``)::

        F = R D(h) G1(w_i) G1(w_r) / (4 cos θi cos θr)
        D = α² / (π (α² cos²θh + sin²θh)²)
        G1(w) = 2 cos θ / (cos θ + sqrt(cos²θ + α² sin²θ))

    ===========  =====  ============  ==================================================
    name         unit   valid range   meaning
    ===========  =====  ============  ==================================================
    alpha        1      [1e-4, 1]     roughness α of D (Mitsuba's ``alpha``)
    reflectance  1      [0, 1]        constant Fresnel factor R (default 1)
    name         -      any str       a label for tables and reprs; not in equality
    ===========  =====  ============  ==================================================

    ``alpha`` in [1e-4, 1] is the roughness (Mitsuba's ``alpha``); ``reflectance`` R in
    [0, 1] the Fresnel factor, taken constant (Mitsuba's ``specular_reflectance`` with a
    perfect conductor; 1 by default). Monostatic, θh = θ and
    F cos θ = R D(θ) cos θ / (cos θ + sqrt(cos²θ + α² sin²θ))², finite up to θ = π/2.

    Parameters
    ----------
    alpha : float
        Roughness α of the distribution D, in [1e-4, 1].
    reflectance : float, default 1.0
        Constant Fresnel factor R, in [0, 1].
    name : str or None, keyword-only, default None
        A label for tables and reprs; not part of equality.

    Raises
    ------
    ParameterError
        When ``alpha`` or ``reflectance`` is not a finite real in its range, or ``name`` is
        neither a str nor None.

    References
    ----------
    Walter et al. (2007): the GGX distribution D, its Smith shadowing G1 and the microfacet
    BRDF F above.
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
        """F(θ; −θ)·cos θ = R D(θ) cos θ / (cos θ + sqrt(cos²θ + α² sin²θ))² in 1/sr.

        Monostatic: θi = θr = θh = θ. Finite up to θ = π/2, where it is 0.

        Parameters
        ----------
        cos_theta : array_like
            cos θ of the monostatic incidence angle θ; values < 0 are clamped to 0.
        sin_theta : array_like
            sin θ ≥ 0, broadcasting with ``cos_theta``.

        Returns
        -------
        ndarray
            F·cos θ in 1/sr, float64, of the inputs' broadcast shape.

        References
        ----------
        Walter et al. (2007).
        """
        c = np.maximum(np.asarray(cos_theta, np.float64), 0.0)
        s = np.asarray(sin_theta, np.float64)
        return self.reflectance * self._D(c, s) * c * self._g1_over_2c(c, s) ** 2

    def bistatic(self, cos_i, sin_i, cos_r, sin_r, cos_h, sin_h):
        """F(w_i, w_r)·cos θr = R D(θh) cos θr · G1(w_i)/(2 cos θi) · G1(w_r)/(2 cos θr) in
        1/sr; 0 where cos θi < 0 or cos θr < 0. cos θh is clamped at 0.

        Parameters
        ----------
        cos_i, sin_i : array_like
            Cosine and sine (≥ 0) of θi, the polar angle of the direction to the source.
        cos_r, sin_r : array_like
            Cosine and sine (≥ 0) of θr, the polar angle of the direction to the receiver.
        cos_h, sin_h : array_like
            Cosine and sine (≥ 0) of θh, the polar angle of the half vector. All six
            broadcast together.

        Returns
        -------
        ndarray
            F·cos θr in 1/sr, float64, of the inputs' broadcast shape.

        References
        ----------
        Walter et al. (2007).
        """
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

    def lobe_width(self):
        """α: D falls to a quarter of its peak at sin θ = α/sqrt(1 − α²) ≈ α.

        Returns
        -------
        float
            ``alpha``, read as radians of the monostatic incidence angle θ.
        """
        return self.alpha
