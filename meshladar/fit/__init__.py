"""Coatings and shapes from ladar data, the geometry traced once.

* :mod:`.kernels`: :class:`CoatingKernel` and :func:`coating_kernel` (analytic shapes or
  mesh :class:`~meshladar.hits.Hits`).
* :mod:`.coatings`: :func:`fit_coatings` (least squares, Poisson or speckle likelihood by
  IRLS; covariance and identifiability).
* :mod:`.design`: :class:`ViewDesign`, :func:`design_views`.
* :mod:`.shapes`: disks and ellipses found in a reconstruction (:func:`find_shapes`,
  :func:`fit_scene`).
"""

from __future__ import annotations

from ._params import SR_BOUNDS
from .coatings import (KERNEL_TOL, NOISE_MODELS, NOTED_BIAS, CoatingFit,
                       IdentifiabilityWarning, KernelErrorWarning, fit_coatings)
from .design import ViewDesign, design_views
from .kernels import GRID, CoatingKernel, coating_kernel
from .shapes import SceneFit, find_shapes, fit_scene

__all__ = ["CoatingKernel", "coating_kernel", "fit_coatings", "CoatingFit",
           "IdentifiabilityWarning", "KernelErrorWarning", "KERNEL_TOL", "NOTED_BIAS",
           "design_views", "ViewDesign", "NOISE_MODELS",
           "SR_BOUNDS", "GRID", "SceneFit", "find_shapes", "fit_scene"]
