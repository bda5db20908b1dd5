"""The rules a :class:`~meshladar.brdf.SandfordRobertson` coating's parameters follow,
checked when it is made: each parameter in its range, the lobe selection one of
:data:`LOBES`, and energy conservation (Eqs. 3 and A8): an error when the specular lobe
would need a negative specular reflectivity ρs, a warning for a diffuse-only coating that
reflects more light than it receives.
"""

from __future__ import annotations

import warnings

from .._validate import check_choice, check_name, check_real
from ..errors import EnergyConservationWarning, ParameterError, user_stacklevel
from ..precision import E_MIN
from ..precision import ENERGY_SLACK as _ENERGY_SLACK

#: The lobe selections a :class:`SandfordRobertson` accepts.
LOBES = ("both", "diffuse", "specular")

#: The numeric parameters with their valid ranges, in the order they are checked.
_RANGES = (("rho_d", 0.0, 1.0), ("epsilon", 0.0, 1.0), ("b", 0.0, 1.0), ("e", E_MIN, 1.0))


def _checked_parameters(coating):
    """{name: float} of the coating's numeric parameters, each checked to be a finite real
    in its range, then its ``lobes`` and ``name`` checked: a ParameterError at the first
    that is not."""
    values = {param: check_real(param, getattr(coating, param), low=low, high=high)
              for param, low, high in _RANGES}
    check_choice("lobes", coating.lobes, LOBES)
    check_name(coating.name)
    return values


def _check_energy(coating):
    """A ParameterError when the coating includes the specular lobe and rho_d + epsilon
    exceeds G(b), so that ρs(0) < 0 (A8); an EnergyConservationWarning when it is
    diffuse-only and reflects more than it receives at normal incidence. Called from the
    coating's ``__post_init__``: the warning points at the line that made the coating."""
    G = coating.G
    if coating.has_specular:
        total = coating.rho_d + coating.epsilon
        if total > G * (1.0 + _ENERGY_SLACK):
            raise ParameterError(
                f"coating is not energy-conserving: rho_d + epsilon = {total:.6g} exceeds "
                f"G(b) = {G:.6g} (b = {coating.b:g}) by {total - G:.3g}, so the specular "
                f"reflectivity rho_s(0) = 1 - (rho_d + epsilon)/G(b) = {1 - total / G:.3g} "
                "< 0; lower rho_d or epsilon, or use lobes='diffuse'")
    peak = coating.rho_d / G
    if coating.lobes == "diffuse" and peak > 1.0 * (1.0 + _ENERGY_SLACK):
        warnings.warn(
            f"diffuse-only coating is not energy-conserving: it reflects up to "
            f"rho_d/G(b) = {peak:.4g} of the incident light at normal incidence "
            f"(rho_d = {coating.rho_d:g}, b = {coating.b:g}); allowed, as in the paper's "
            "Sec. 4.A", EnergyConservationWarning, stacklevel=user_stacklevel())
