"""The energy-normalised modified Phong BRDF (Lafortune & Willems 1994)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._validate import check_name, check_real
from ..errors import ParameterError
from ..precision import ENERGY_SLACK as _ENERGY_SLACK
from ._shared import _unit_interval
from .base import BRDF

__all__ = ["Phong"]


@dataclass(frozen=True)
class Phong(BRDF, builtin=True):
    """The energy-normalised modified Phong BRDF (Lafortune & Willems 1994), the Phong
    family that lidar simulators such as HELIOS++ and classic graphics use::

        F = kd/π + ks (n + 2)/(2π) cos^n ψ

    ========  =====  ============  ==============================================
    name      unit   valid range   meaning
    ========  =====  ============  ==============================================
    kd        1      [0, 1]        diffuse reflectance (F_d = kd/π)
    ks        1      [0, 1]        specular reflectance at normal incidence;
                                   kd + ks <= 1 (energy conservation)
    exponent  1      [0, 1e6]      Phong exponent n: lobe width ~ sqrt(2/n) rad
    name      -      any str       a label for tables and reprs; not in equality
    ========  =====  ============  ==============================================

    with ψ the angle between the mirror direction of the source and the receiver (the lobe
    term is 0 where ψ ≥ 90°, i.e. cos ψ ≤ 0). Monostatic, ψ = 2θ. ``kd + ks <= 1``
    conserves energy; at normal incidence the specular lobe reflects exactly ks.
    ``exponent`` n ≥ 0 (n = 0: a constant ks/π, but only within ψ < 90° of the mirror
    direction, so monostatic only for θ < 45°; n = 1000: a lobe about 2.5° wide).

    Parameters
    ----------
    kd : float
        Diffuse reflectance, in [0, 1].
    ks : float
        Specular reflectance at normal incidence, in [0, 1]; kd + ks must be at most
        1 + 1e-12.
    exponent : float
        Phong exponent n, in [0, 1e6].
    name : str or None, keyword-only, default None
        A label for tables and reprs; not part of equality.

    Raises
    ------
    ParameterError
        When ``kd``, ``ks`` or ``exponent`` is not a finite real in its range,
        kd + ks > 1 + 1e-12, or ``name`` is neither a str nor None.

    References
    ----------
    Lafortune & Willems (1994): the energy-normalised modified Phong BRDF, with the
    (n + 2)/(2π) normalisation used here.
    Phong (1975): the cos^n ψ specular lobe.
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
        """F(θ; −θ)·cos θ = (kd/π + ks (n + 2)/(2π) cos^n 2θ)·cos θ in 1/sr, the lobe term
        0 where cos 2θ ≤ 0.

        Parameters
        ----------
        cos_theta : array_like
            cos θ of the monostatic incidence angle θ; values < 0 are clamped to 0.
        sin_theta : array_like
            sin θ ≥ 0, broadcasting with ``cos_theta``; cos 2θ is formed as
            (cos θ − sin θ)(cos θ + sin θ).

        Returns
        -------
        ndarray
            F·cos θ in 1/sr, float64, of the inputs' broadcast shape.

        References
        ----------
        Lafortune & Willems (1994).
        """
        c = np.maximum(np.asarray(cos_theta, np.float64), 0.0)
        s = np.asarray(sin_theta, np.float64)
        cos_2t = (c - s) * (c + s)                              # cos 2θ, exact near 45°
        return (self.kd / math.pi + self._lobe(cos_2t)) * c

    def bistatic(self, cos_i, sin_i, cos_r, sin_r, cos_h, sin_h):
        """F(w_i, w_r)·cos θr = (kd/π + ks (n + 2)/(2π) cos^n ψ)·cos θr in 1/sr; 0 where
        cos θi < 0 or cos θr < 0, the lobe term 0 where cos ψ ≤ 0.

        cos ψ = 2 cos θi cos θr − (2 cos²β − 1), with cos β = (cos θi + cos θr)/(2 cos θh)
        the cosine of half the angle between the two directions (taken as 0 where
        cos θh ≤ 0).

        Parameters
        ----------
        cos_i : array_like
            Cosine of θi, the polar angle of the direction to the source.
        sin_i : array_like
            Not used.
        cos_r : array_like
            Cosine of θr, the polar angle of the direction to the receiver.
        sin_r : array_like
            Not used.
        cos_h : array_like
            Cosine of θh, the polar angle of the half vector.
        sin_h : array_like
            Not used. The three cosines broadcast together.

        Returns
        -------
        ndarray
            F·cos θr in 1/sr, float64, of the cosines' broadcast shape.

        References
        ----------
        Lafortune & Willems (1994).
        """
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

    def lobe_width(self):
        """θ where the monostatic lobe cos^n(2θ) falls to a quarter: arccos(4^(−1/n))/2
        (≈ sqrt(ln 4 / 2n) = 0.83/√n for large n); None without a lobe (ks = 0 or n = 0).

        Returns
        -------
        float or None
            The half-width in radians of the monostatic incidence angle θ, or None.
        """
        if self.ks == 0 or self.exponent == 0:
            return None
        return 0.5 * math.acos(4.0 ** (-1.0 / self.exponent))

    @property
    def angular_scales(self):
        # the monostatic lobe cos^n(2θ) falls to 1/e at 2θ ≈ sqrt(2/n)
        return (0.5 * math.sqrt(2.0 / self.exponent) if self.exponent > 0 else None, None)
