"""Reconstruction: images and volumes from sinograms.

* :mod:`~meshladar.reconstruct.fbp2d` — filtered backprojection of views about the z axis
  (:func:`fbp`) and its resampling, with its filters in
  :mod:`~meshladar.reconstruct.filters` and the paper's log/clip preprocessing in
  :mod:`~meshladar.reconstruct.radiance`;
* :mod:`~meshladar.reconstruct.volumes` — 3-D inversion over the sphere of views
  (:func:`~meshladar.reconstruct.volumes.fbp3d`) and stacked slices
  (:func:`~meshladar.reconstruct.volumes.fbp_slices`);
* :mod:`~meshladar.reconstruct.operators` — the projectors as scipy ``LinearOperator``\\ s;
* :mod:`~meshladar.reconstruct.iterative` — SIRT, SART, CGLS and TV-FISTA on them;
* :mod:`~meshladar.reconstruct.surface` and :mod:`~meshladar.reconstruct.compensation` —
  surface estimation and BRDF/shadow-compensated reconstruction.

This package face imports the 2-D FBP (numba with its compiled loop); the other
modules load when imported.
"""

from __future__ import annotations

from ..images import Image
from .fbp2d import (FILTERS, INTERPOLATIONS, LOG_FLOOR, PAPER_CLIP, bins_reach, clip_radiance,
                    default_extent, fbp, fourier_filter, log_radiance, noise_floor, quiet_fbp,
                    resample_uniform)

__all__ = ["Image", "fbp", "bins_reach", "default_extent", "fourier_filter", "log_radiance", "clip_radiance", "resample_uniform",
           "noise_floor", "quiet_fbp", "FILTERS", "INTERPOLATIONS", "LOG_FLOOR", "PAPER_CLIP"]
