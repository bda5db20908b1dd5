"""Circles and ellipses among the surface points of a first reconstruction, for
:func:`~meshladar.fit.shapes.find_shapes`: circles found by RANSAC (three points define a
circle; of those whose points go round at least :data:`MIN_ARC` of it and that overlap no
circle already found, the one with the most points within ``tol`` wins), groups of points connected
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

#: A circle RANSAC keeps has points in at least this share of its ARC_SECTORS equal
#: sectors: a shape's boundary reconstructed from views all round shows most of its circle,
#: while a circle through pieces of two shapes' boundaries holds a few arcs of its own.
MIN_ARC = 0.5
ARC_SECTORS = 36


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
    found, circles = [], []
    while left.size >= min_points and len(found) < max_shapes:
        p = points[left]
        best, most = None, min_points - 1
        for _ in range(400):
            q = _circle_through(p[rng.choice(p.shape[0], 3, replace=False)])
            if q is None:
                continue
            inl = np.abs(np.hypot(p[:, 0] - q[0], p[:, 1] - q[1]) - q[2]) < tol
            if inl.sum() > most and _kept(p[inl], q, circles):
                best, most = inl, int(inl.sum())
        if best is None:
            break
        q, _, _ = _circle_lsq(p[best])                       # refine, then re-collect
        inl = np.abs(np.hypot(p[:, 0] - q[0], p[:, 1] - q[1]) - q[2]) < tol
        found.append(left[inl])
        circles.append(q)
        left = left[~inl]
    return found


def _circle_through(abc):
    """(x, y, r) of the circle through three points, None when they are in a line."""
    (ax, ay), (bx, by), (cx_, cy_) = abc
    d = 2 * (ax * (by - cy_) + bx * (cy_ - ay) + cx_ * (ay - by))
    if abs(d) < 1e-12:
        return None
    ux = ((ax * ax + ay * ay) * (by - cy_) + (bx * bx + by * by) * (cy_ - ay)
          + (cx_ * cx_ + cy_ * cy_) * (ay - by)) / d
    uy = ((ax * ax + ay * ay) * (cx_ - bx) + (bx * bx + by * by) * (ax - cx_)
          + (cx_ * cx_ + cy_ * cy_) * (bx - ax)) / d
    return ux, uy, math.hypot(ax - ux, ay - uy)


def _kept(p, q, circles):
    """Whether the circle ``q`` with its points ``p`` goes round MIN_ARC of itself and
    overlaps none of ``circles`` (shapes in a scene do not overlap)."""
    sector = np.floor((np.arctan2(p[:, 1] - q[1], p[:, 0] - q[0]) + math.pi)
                      * (ARC_SECTORS / (2 * math.pi))).astype(np.int64) % ARC_SECTORS
    if np.unique(sector).size < MIN_ARC * ARC_SECTORS:
        return False
    return all(math.hypot(q[0] - c[0], q[1] - c[1]) >= q[2] + c[2] for c in circles)
