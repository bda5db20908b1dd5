"""BRDFs: the protocol every forward model accepts (:class:`BRDF`, in :mod:`.base`; the
registry of built-in models in :mod:`.registry`, the compiled kernel's material table in
:mod:`.kernel_table`) and the built-in models, one file each: :class:`SandfordRobertson`
(Jin & Levine 2009, Appendix A, with its functions in :mod:`.sandford_robertson_functions`
and its compiled twin beside it), :class:`Lambertian`, :class:`Phong`, :class:`GGX`
(Mitsuba's rough conductor) and :class:`Tabulated` (measured).

The protocol: a coating defines ``projected(cos_theta, sin_theta)``, its monostatic weight
F(θ; −θ)·cos θ, and inherits ``monostatic``; a bistatic receiver needs ``bistatic`` as
well. Built-in models register themselves in :data:`MODELS` when their class is defined.
Conventions (angles from the outward normal in radians, exactly 0 below the horizon, 1/sr)
are stated in :mod:`meshladar.brdf.base`.
"""

from __future__ import annotations

# in this order, which is the order the models register in (MODELS, messages)
from .base import MODELS, BRDF, check_brdf, is_builtin, material_table, projected_weight  # isort: skip
from .sandford_robertson import (E_MIN, LOBES, KernelRow, SandfordRobertson,  # isort: skip
                                 diffuse_normalization, diffuse_shape, glint_lobe,
                                 specular_normalization)
from .lambertian import Lambertian  # isort: skip
from .phong import Phong  # isort: skip
from .ggx import GGX  # isort: skip
from .tabulated import Tabulated  # isort: skip

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
    "MODELS",
    "KernelRow",
    "is_builtin",
    "projected_weight",
    "material_table",
    "check_brdf",
]
