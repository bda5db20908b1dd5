"""Circles and ellipses among the surface points of a first reconstruction, for
:func:`~meshladar.fit.shapes.find_shapes`: circles found by RANSAC (three points define a
circle; the one with the most points within ``tol`` wins), groups of points connected
within a reach, and each set of points fitted by geometric least squares (a circle from
Kåsa's algebraic start, an ellipse from Fitzgibbon's direct fit) with the covariance of its
parameters from the residuals.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import least_squares
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ..errors import ParameterError


def _circle_lsq(p):
    """Geometric least-squares circle (centre, radius, covariance of (cx, cy, r))."""
    x, y = p[:, 0], p[:, 1]
    A = np.stack([x, y, np.ones_like(x)], axis=1)            # Kåsa's algebraic start
    c = np.linalg.lstsq(A, x * x + y * y, rcond=None)[0]
    cx, cy = 0.5 * c[0], 0.5 * c[1]
    r = math.sqrt(max(c[2] + cx * cx + cy * cy, 1e-300))
    sol = least_squares(lambda q: np.hypot(x - q[0], y - q[1]) - q[2], [cx, cy, r])
    dof = max(1, p.shape[0] - 3)
    s2 = float(np.sum(sol.fun ** 2)) / dof
    cov = s2 * np.linalg.pinv(sol.jac.T @ sol.jac)
    return sol.x, cov, float(math.sqrt(s2))


def _ellipse_lsq(p):
    """(centre, semi-axes, angle_deg, covariance of the five, rms): Fitzgibbon's direct fit
    refined by geometric least squares on the distance to the ellipse (sampled)."""
    x, y = p[:, 0] - p[:, 0].mean(), p[:, 1] - p[:, 1].mean()
    D = np.stack([x * x, x * y, y * y, x, y, np.ones_like(x)], axis=1)
    S = D.T @ D
    C = np.zeros((6, 6))
    C[0, 2] = C[2, 0] = 2.0
    C[1, 1] = -1.0
    try:
        w, v = np.linalg.eig(np.linalg.solve(S, C))
    except np.linalg.LinAlgError:
        raise ParameterError("the surface points do not determine an ellipse") from None
    a = np.real(v[:, np.argmax(np.real(w))])
    A_, B_, C_, D_, E_, F_ = a
    den = B_ * B_ - 4 * A_ * C_
    x0 = (2 * C_ * D_ - B_ * E_) / den
    y0 = (2 * A_ * E_ - B_ * D_) / den
    theta = 0.5 * math.atan2(-B_, C_ - A_)
    num = 2 * (A_ * E_ * E_ + C_ * D_ * D_ - B_ * D_ * E_ + den * F_)
    root = math.hypot(A_ - C_, B_)
    ax1 = math.sqrt(abs(num * ((A_ + C_) + root))) / abs(den)
    ax2 = math.sqrt(abs(num * ((A_ + C_) - root))) / abs(den)
    start = [x0 + p[:, 0].mean(), y0 + p[:, 1].mean(), ax1, ax2, theta]

    def resid(q):
        cx, cy, a1, a2, t = q
        c, s = math.cos(t), math.sin(t)
        u = (p[:, 0] - cx) * c + (p[:, 1] - cy) * s
        v_ = -(p[:, 0] - cx) * s + (p[:, 1] - cy) * c
        ang = np.arctan2(v_ / a2, u / a1)                   # nearest by eccentric angle
        return np.hypot(u - a1 * np.cos(ang), v_ - a2 * np.sin(ang))

    sol = least_squares(resid, start)
    dof = max(1, p.shape[0] - 5)
    s2 = float(np.sum(sol.fun ** 2)) / dof
    cov = s2 * np.linalg.pinv(sol.jac.T @ sol.jac)
    return sol.x, cov, float(math.sqrt(s2))


def _components(points, reach, min_points):
    """Index arrays of the connected groups of points (neighbours within ``reach``) with at
    least ``min_points`` points."""

    pairs = cKDTree(points).query_pairs(reach, output_type="ndarray")
    n = points.shape[0]
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    _, label = connected_components(graph, directed=False)
    return [np.flatnonzero(label == k) for k in np.unique(label)
            if np.count_nonzero(label == k) >= min_points]


def _ransac_circles(points, tol, min_points, max_shapes, seed):
    rng = np.random.default_rng(seed)
    left = np.arange(points.shape[0])
    found = []
    while left.size >= min_points and len(found) < max_shapes:
        p = points[left]
        best = None
        for _ in range(400):
            i, j, k = rng.choice(p.shape[0], 3, replace=False)
            (ax, ay), (bx, by), (cx_, cy_) = p[i], p[j], p[k]
            d = 2 * (ax * (by - cy_) + bx * (cy_ - ay) + cx_ * (ay - by))
            if abs(d) < 1e-12:
                continue
            ux = ((ax * ax + ay * ay) * (by - cy_) + (bx * bx + by * by) * (cy_ - ay)
                  + (cx_ * cx_ + cy_ * cy_) * (ay - by)) / d
            uy = ((ax * ax + ay * ay) * (cx_ - bx) + (bx * bx + by * by) * (ax - cx_)
                  + (cx_ * cx_ + cy_ * cy_) * (bx - ax)) / d
            r = math.hypot(ax - ux, ay - uy)
            inl = np.abs(np.hypot(p[:, 0] - ux, p[:, 1] - uy) - r) < tol
            if best is None or inl.sum() > best.sum():
                best = inl
        if best is None or best.sum() < min_points:
            break
        q, _, _ = _circle_lsq(p[best])                       # refine, then re-collect
        inl = np.abs(np.hypot(p[:, 0] - q[0], p[:, 1] - q[1]) - q[2]) < tol
        found.append(left[inl])
        left = left[~inl]
    return found
