"""The tables a coating kernel weighs: each coating's projected monostatic weight
F(θ; −θ) cos θ on :data:`GRID` incidence angles in [0, π/2].

The angles are θ = (π/2) u² for u evenly spaced on [0, 1] (:data:`GRID` points): a glint
lives at small θ (F peaks at normal incidence), where the spacing is finest: √(2π θ)/(GRID
− 1) near θ, 2.4e-6 rad at θ = 2.4e-4 (a hundred samples across a glint that narrow, 20
across one of 1e-5 rad), rising to π/(GRID − 1) = 1.9e-4 rad at the horizon. An even grid of 1.9e-4 rad
put 1.3 samples across a 2.4e-4 rad glint, whose kernel then erred by 0.57 σ at 10⁴
photoelectrons however finely the boundaries were cut (the kernel's N-to-2N check could not
see it), and a fit of the paper's pair settled there.

A kernel's matrices act on these tables (:mod:`.kernels`), and the fit's model, Jacobian
and view design evaluate them (:mod:`._params`, :mod:`._irls`, :mod:`.design`).
"""

from __future__ import annotations

import math

import numpy as np

from ..brdf import projected_weight

#: θ samples of the tables on [0, π/2], at θ = (π/2) u², u evenly spaced (:func:`grid_position`).
GRID = 16385
_THETA = 0.5 * math.pi * np.linspace(0.0, 1.0, GRID) ** 2


def grid_position(theta, grid=GRID):
    """The fractional index of each angle ``theta`` (radians, clipped to [0, π/2]) on a
    table of ``grid`` points at θ = (π/2) u²: (grid − 1) √(θ / (π/2))."""
    return np.sqrt(np.clip(theta, 0.0, 0.5 * math.pi) / (0.5 * math.pi)) * (grid - 1)


def _table(material):
    """The projected weight F(θ; −θ) cos θ on the θ grid (1/sr; finite up to the horizon,
    where F itself is not)."""
    return np.asarray(projected_weight(material, np.cos(_THETA), np.sin(_THETA)), dtype=float)
