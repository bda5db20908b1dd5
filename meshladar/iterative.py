"""Deprecated alias of meshladar.reconstruct.iterative (one release).

The solvers live in :mod:`meshladar.reconstruct.iterative`, the projectors in
:mod:`meshladar.reconstruct.operators`.
"""

from __future__ import annotations

from ._deprecated import warn_moved
from .reconstruct.iterative import (METHODS, PROJECTORS, LinearProjector, RangeProjector, cgls,
                                    glint_weights, sart, sirt, tv_fista)

warn_moved("iterative", "reconstruct.iterative")

__all__ = ["RangeProjector", "LinearProjector", "sirt", "sart", "cgls", "tv_fista",
           "glint_weights", "METHODS", "PROJECTORS"]
