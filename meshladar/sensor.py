"""The sensor: what a ladar's receiver records (DESIGN.md's sensor stage).

Radiometry conventions (``radiometry=`` on every forward model and on :func:`weigh`):

``"paper"``
    The paper's Eq. 8: each bin is ∫ F(θ) cos θ dA over the visible surface whose range lies
    in it (with a beam, times the beam's relative irradiance at each point). This is what
    the paper's figures use; it is not the power a receiver collects.
``"power"``
    Received power: the reflected radiance F E cos θ_i seen over the element's projected
    area toward the receiver, ∫ F cos θ_i cos θ_r dA (monostatic ∫ F cos²θ dA), with the
    receiver's (D/R)² at a finite standoff D. One cos θ more than Eq. 8: a Lambertian
    sphere's profile is ∝ (1 − r/R)², not ∝ (1 − r/R).
"""

from __future__ import annotations

from ._validate import check_choice

__all__ = ["RADIOMETRIES"]

#: The radiometry conventions every forward model takes (module docstring).
RADIOMETRIES = ("paper", "power")


def check_radiometry(radiometry) -> bool:
    """True for received power, False for the paper's Eq. 8; a ParameterError naming the
    choices otherwise."""
    return check_choice("radiometry", radiometry, RADIOMETRIES) == "power"
