"""Deprecated alias of meshladar.fit (one release): coating kernels, fits and view design
now live in :mod:`meshladar.fit.kernels`, :mod:`meshladar.fit.coatings` and
:mod:`meshladar.fit.design`."""

from ._deprecated import warn_moved
from .fit import (NOISE_MODELS, SR_BOUNDS, CoatingFit, CoatingKernel, IdentifiabilityWarning,
                  ViewDesign, coating_kernel, design_views, fit_coatings)
from .fit.kernels import GRID  # noqa: F401

warn_moved("fitting", "fit")

__all__ = ["CoatingKernel", "coating_kernel", "fit_coatings", "CoatingFit",
           "IdentifiabilityWarning", "design_views", "ViewDesign", "NOISE_MODELS",
           "SR_BOUNDS"]
