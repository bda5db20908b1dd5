"""The energy-normalised modified Phong BRDF (Lafortune & Willems 1994)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._validate import check_name, check_real
from ..errors import ParameterError
from ..precision import ENERGY_SLACK as _ENERGY_SLACK
from .base import BRDF, _unit_interval

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

    def lobe_width(self):
        """θ where the monostatic lobe cos^n(2θ) falls to a quarter: arccos(4^(−1/n))/2
        (≈ sqrt(ln 4 / 2n) = 0.83/√n for large n); None without a lobe (ks = 0 or n = 0)."""
        if self.ks == 0 or self.exponent == 0:
            return None
        return 0.5 * math.acos(4.0 ** (-1.0 / self.exponent))

    @property
    def angular_scales(self):
        # the monostatic lobe cos^n(2θ) falls to 1/e at 2θ ≈ sqrt(2/n)
        return (0.5 * math.sqrt(2.0 / self.exponent) if self.exponent > 0 else None, None)
