"""Deprecated alias of meshladar.reconstruct.volumes (one release).

3-D reflective tomography now lives in :mod:`meshladar.reconstruct.volumes` (``radon3d`` is
:func:`~meshladar.reconstruct.volumes.fbp3d`, ``fbp_stack`` is
:func:`~meshladar.reconstruct.volumes.fbp_slices`) and the :class:`Volume` record in
:mod:`meshladar.images`. The old names here do not warn yet: ``radon3d`` and ``fbp_stack``
of this module are the new functions themselves until their importers (``cli.py``,
``paper.py``, ``bench.py``, ``tests/test_viewer.py``) call the new names; then they become
the warning aliases of :mod:`meshladar.reconstruct.volumes`.
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
