"""The total-variation pieces of :func:`meshladar.reconstruct.iterative.tv_fista`: forward
differences, their adjoint, and the TV proximal map."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["MAX_TV", "gradient", "tv_prox"]


def gradient(x):
    """Forward differences (zero at the far edges)."""
    gx = np.zeros_like(x)
    gy = np.zeros_like(x)
    gx[:, :-1] = x[:, 1:] - x[:, :-1]
    gy[:-1, :] = x[1:, :] - x[:-1, :]
    return gx, gy


def _div(px, py):
    """The negative adjoint of gradient."""
    d = np.zeros_like(px)
    d[:, 0] += px[:, 0]
    d[:, 1:] += px[:, 1:] - px[:, :-1]
    d[:, -1] -= px[:, -1]
    d[0, :] += py[0, :]
    d[1:, :] += py[1:, :] - py[:-1, :]
    d[-1, :] -= py[-1, :]
    return d


#: The largest ``tv`` taken: relative to the image's level, 100 already flattens any image.
MAX_TV = 100.0


def tv_prox(z, mu, nonneg, mask, n_inner=20, dual=None):
    """argmin_x ½‖x − z‖² + μ TV(x) over x ≥ 0 (``nonneg``) and the mask: Beck and
    Teboulle's fast gradient projection on the dual (isotropic TV). Returns (x, dual)."""
    def project(v):
        v = v * mask
        return np.maximum(v, 0.0) if nonneg else v

    px, py = (np.zeros_like(z), np.zeros_like(z)) if dual is None else dual
    if mu == 0.0:                                      # tv=0: no regularisation, FISTA alone
        return project(z), (px, py)
    rx, ry = px, py
    t = 1.0
    for _ in range(n_inner):
        x = project(z + mu * _div(rx, ry))
        gx, gy = gradient(x)
        qx, qy = rx + gx / (8.0 * mu), ry + gy / (8.0 * mu)
        norm = np.maximum(1.0, np.hypot(qx, qy))
        qx, qy = qx / norm, qy / norm
        t_new = 0.5 * (1.0 + math.sqrt(1.0 + 4.0 * t * t))
        rx = qx + (t - 1.0) / t_new * (qx - px)
        ry = qy + (t - 1.0) / t_new * (qy - py)
        px, py, t = qx, qy, t_new
    return project(z + mu * _div(px, py)), (px, py)
