"""The tables a coating kernel weighs: each coating's projected monostatic weight
F(θ; −θ) cos θ on :data:`GRID` incidence angles in [0, π/2].

A kernel's matrices act on these tables (:mod:`.kernels`), and the fit's model, Jacobian
and view design evaluate them (:mod:`._params`, :mod:`._irls`, :mod:`.design`).
"""

from __future__ import annotations

import math

import numpy as np

from ..brdf import projected_weight

#: θ samples of the tables on [0, π/2].
GRID = 8193
_THETA = np.linspace(0.0, 0.5 * math.pi, GRID)


def _table(material):
    """The projected weight F(θ; −θ) cos θ on the θ grid (1/sr; finite up to the horizon,
    where F itself is not)."""
    return np.asarray(projected_weight(material, np.cos(_THETA), np.sin(_THETA)), dtype=float)
