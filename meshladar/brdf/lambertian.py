"""The Lambertian coating: F = albedo/π in every direction."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._validate import check_name
from ._shared import _unit_interval
from .base import BRDF
from .kernel_table import KernelRow

__all__ = ["Lambertian"]


@dataclass(frozen=True)
class Lambertian(BRDF, builtin=True):
    """A perfectly diffuse coating: F = albedo/π in every direction.

    ========  =====  ============  ==============================================  =====
    name      unit   valid range   meaning                                         eq.
    ========  =====  ============  ==============================================  =====
    albedo    1      [0, 1]        hemispherical reflectance ∫ F cos θr dω         A1
    name      -      any str       a label for tables and reprs; not in equality   -
    ========  =====  ============  ==============================================  =====

    ``albedo`` in [0, 1] is the hemispherical reflectance (∫ F cos θr dω = albedo).
    Equal to ``SandfordRobertson(albedo, 0, 0, 1, lobes="diffuse")``, and traced by the
    same compiled kernel.

    Parameters
    ----------
    albedo : float
        Hemispherical reflectance, in [0, 1].
    name : str or None, keyword-only, default None
        A label for tables and reprs; not part of equality.

    Raises
    ------
    ParameterError
        When ``albedo`` is not a finite real in [0, 1], or ``name`` is neither a str nor
        None.

    References
    ----------
    Jin & Levine (2009), Eq. A1 with b = 0 (g ≡ 1, G = 1): F_d = ρd/π.
    """

    albedo: float
    name: str | None = field(default=None, kw_only=True, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "albedo", _unit_interval("albedo", self.albedo))
        check_name(self.name)

    def projected(self, cos_theta, sin_theta):
        """F(θ; −θ)·cos θ = (albedo/π) max(cos θ, 0) in 1/sr.

        Parameters
        ----------
        cos_theta : array_like
            cos θ of the monostatic incidence angle θ; values < 0 are clamped to 0.
        sin_theta : array_like
            Not used.

        Returns
        -------
        ndarray
            F·cos θ in 1/sr, float64, of the shape of ``cos_theta``.
        """
        return self.albedo / math.pi * np.maximum(np.asarray(cos_theta, np.float64), 0.0)

    def value(self, cos_theta, sin_theta):
        """F(θ; −θ) = albedo/π in 1/sr where cos θ ≥ 0, 0 below the horizon.

        Parameters
        ----------
        cos_theta : array_like
            cos θ of the monostatic incidence angle θ.
        sin_theta : array_like
            Not used.

        Returns
        -------
        ndarray
            F in 1/sr, float64, of the shape of ``cos_theta``.
        """
        c = np.asarray(cos_theta, np.float64)
        return np.where(c >= 0, self.albedo / math.pi, 0.0)

    def bistatic(self, cos_i, sin_i, cos_r, sin_r, cos_h, sin_h):
        """F(w_i, w_r)·cos θr = (albedo/π) cos θr in 1/sr; 0 where cos θi < 0 or cos θr < 0.

        Parameters
        ----------
        cos_i : array_like
            Cosine of θi, the polar angle of the direction to the source.
        sin_i : array_like
            Not used.
        cos_r : array_like
            Cosine of θr, the polar angle of the direction to the receiver; broadcasts with
            ``cos_i``.
        sin_r, cos_h, sin_h : array_like
            Not used.

        Returns
        -------
        ndarray
            F·cos θr in 1/sr, of the broadcast shape of ``cos_i`` and ``cos_r``.
        """
        return np.where((cos_i >= 0) & (cos_r >= 0),
                        self.albedo / math.pi * np.maximum(cos_r, 0.0), 0.0)

    def bistatic_value(self, cos_i, sin_i, cos_r, sin_r, cos_h, sin_h):
        """F(w_i, w_r) = albedo/π in 1/sr where cos θi ≥ 0 and cos θr ≥ 0, 0 below either
        horizon (the constant itself, also at θr = π/2, as :meth:`value` monostatic).

        Parameters
        ----------
        cos_i : array_like
            Cosine of θi, the polar angle of the direction to the source.
        sin_i : array_like
            Not used.
        cos_r : array_like
            Cosine of θr, the polar angle of the direction to the receiver; broadcasts with
            ``cos_i``.
        sin_r, cos_h, sin_h : array_like
            Not used.

        Returns
        -------
        ndarray
            F in 1/sr, of the broadcast shape of ``cos_i`` and ``cos_r``.
        """
        return np.where((np.asarray(cos_i) >= 0) & (np.asarray(cos_r) >= 0),
                        self.albedo / math.pi, 0.0)

    @property
    def kernel_params(self):
        # SR with b = 0 (g ≡ 1, G = 1), diffuse only: F = rho_d / π
        return KernelRow(self.albedo, 0.0, 0.0, 1.0, 1.0, 1.0, 0.0)
