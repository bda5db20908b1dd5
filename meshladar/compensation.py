"""Deprecated alias of meshladar.reconstruct.compensation (one release).

Surface estimation lives in :mod:`meshladar.reconstruct.surface`, the surface projector in
:mod:`meshladar.reconstruct.operators`, the compensated solve in
:mod:`meshladar.reconstruct.compensation`.
"""

from __future__ import annotations

from ._deprecated import warn_moved
from .reconstruct.compensation import (SOLVERS, Surface, SurfaceProjector, compensate,
                                       estimate_surface, first_image, surface_weights)

warn_moved("compensation", "reconstruct.compensation")

__all__ = ["Surface", "estimate_surface", "surface_weights", "SurfaceProjector", "compensate",
           "first_image", "SOLVERS"]
