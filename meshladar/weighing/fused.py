"""The fused path of the packet backend: one view from ray grid to bins in one compiled
loop (:func:`._fused_kernels.cast_bin_grid`), with the weights and bins a
:class:`~meshladar.forward.mesh` job prepared for it."""

from __future__ import annotations

import numpy as np

from ..raytrace.embree4_ctypes import RTC_RAY_QUERY_FLAG_COHERENT
from ._fused_kernels import cast_bin_grid as kernel

__all__ = ["cast_bin_grid"]


def cast_bin_grid(emb, plan, direction, spacing, bins, receiver=None):
    """Cast, weigh and bin one view of the packet scene ``emb``
    (:class:`meshladar.raytrace.embree.EmbreeScene` whose backend is fused): ``plan`` is
    :func:`meshladar.raytrace.grid.grid_plan`'s :class:`~meshladar.raytrace.grid.GridPlan`,
    ``bins`` the weigh-and-bin arguments (:class:`~meshladar.forward.job.FlatBins`,
    flat for the compiled loop); ``receiver`` (direction, lift) makes the view bistatic.
    Returns (back-face hits, rays cast)."""
    s, t, du, dv, u, v, L = plan.s, plan.t, plan.du, plan.dv, plan.u, plan.v, plan.L
    sc = emb.scene.scene
    lib = sc.lib
    empty = np.empty((0, 0), np.float32)
    w = np.asarray(direction, dtype=np.float64)
    return kernel(
        lib.intersect[lib.width], sc.live(), lib.width,
        RTC_RAY_QUERY_FLAG_COHERENT, s.astype(np.float32), t.astype(np.float32),
        empty if du is None else du, empty if dv is None else dv, np.float32(spacing),
        u.astype(np.float32), v.astype(np.float32), (L * w).astype(np.float32),
        (-w).astype(np.float32)[None, :], np.float32(emb.inverse), float(emb.scale), *bins,
        lib.occluded[lib.width],
        np.empty(0) if receiver is None else np.asarray(receiver[0], np.float64),
        0.0 if receiver is None else float(receiver[1]))
