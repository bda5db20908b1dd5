"""Deprecated alias of meshladar.reconstruct.volumes (one release).

3-D reflective tomography now lives in :mod:`meshladar.reconstruct.volumes` (``radon3d`` is
:func:`~meshladar.reconstruct.volumes.fbp3d`, ``fbp_stack`` is
:func:`~meshladar.reconstruct.volumes.fbp_slices`) and the :class:`Volume` record in
:mod:`meshladar.images`. Importing this module warns (DeprecationWarning) with the new
home; its ``radon3d`` and ``fbp_stack`` are the new functions.
"""

from __future__ import annotations

from ._deprecated import warn_moved
from .images import Volume
from .reconstruct.volumes import (MAX_GAP_DEG, coverage_gap_deg, fbp3d, fbp_slices,
                                  sphere_weights)

warn_moved("volume", "reconstruct.volumes (fbp3d, fbp_slices; Volume in meshladar.images)")

#: Old name of :func:`meshladar.reconstruct.volumes.fbp3d`.
radon3d = fbp3d
#: Old name of :func:`meshladar.reconstruct.volumes.fbp_slices`.
fbp_stack = fbp_slices

__all__ = ["Volume", "radon3d", "fbp_stack", "fbp3d", "fbp_slices", "sphere_weights",
           "coverage_gap_deg", "MAX_GAP_DEG"]
