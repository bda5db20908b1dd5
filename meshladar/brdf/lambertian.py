"""The Lambertian coating: F = albedo/π in every direction."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._validate import check_name
from .base import BRDF, _unit_interval
from .sandford_robertson import KernelRow

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
        return KernelRow(self.albedo, 0.0, 0.0, 1.0, 1.0, 1.0, 0.0)
