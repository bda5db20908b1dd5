"""The exact references of :mod:`meshladar.studies.peer`, which need no renderer at all:
:func:`sphere_power_profile`, the closed form for a Lambertian sphere, and
:func:`convex_power_profile`, the exact bin integrals of a convex (or otherwise unoccluded)
faceted Lambertian mesh. Both are importable from the peer module.
"""

from __future__ import annotations

import numpy as np

__all__ = ["sphere_power_profile", "convex_power_profile"]


def sphere_power_profile(bin_edges, radius, reflectance, top):
    """Closed form for a Lambertian sphere under unit irradiance, seen monostatically.

    A point at depth d = r − top below the sphere's nearest point has cos θ = 1 − d/R; the
    band [d, d + dd] has area 2πR dd, so the received-power density is
    (ρ/π) cos²θ 2πR = 2ρR (1 − d/R)² for 0 ≤ d ≤ R (total 2ρR²/3), and a bin
    [d0, d1] holds (2ρR²/3) [(1 − d0/R)³ − (1 − d1/R)³].

    Parameters
    ----------
    bin_edges : (n_bins + 1,) array_like
        Range edges, increasing, scene units (r = −p·w, growing away from the sensor).
    radius : float
        R, scene units.
    reflectance : float
        ρ, the Lambertian reflectance (F = ρ/π).
    top : float
        The range of the sphere's nearest point (its centre's range − R).

    Returns
    -------
    (n_bins,) numpy.ndarray of float64
        Received power per bin; 0 for bins wholly before ``top`` or beyond ``top + R``
        (the far half is not seen).
    """
    e = np.asarray(bin_edges, dtype=np.float64)
    R = float(radius)
    d0 = np.clip(e[:-1] - top, 0.0, R) / R
    d1 = np.clip(e[1:] - top, 0.0, R) / R
    return 2.0 * reflectance * R * R / 3.0 * ((1.0 - d0) ** 3 - (1.0 - d1) ** 3)


def _triangular_cdf(x, a, c, b):
    """CDF at x (…, k) of the triangular distribution (a ≤ c ≤ b per row): a linear
    function's values over a uniform triangle."""
    x = np.asarray(x)
    a, c, b = a[:, None], c[:, None], b[:, None]
    span = b - a
    left = np.where((c - a) > 0, (x - a) ** 2 / np.where(span * (c - a) > 0, span * (c - a), 1.0),
                    0.0)
    right = 1.0 - np.where((b - c) > 0,
                           (b - x) ** 2 / np.where(span * (b - c) > 0, span * (b - c), 1.0),
                           0.0)
    out = np.where(x <= c, left, right)
    out = np.where(x <= a, 0.0, np.where(x >= b, 1.0, out))
    return out


def convex_power_profile(vertices, faces, view, bin_edges, reflectance=0.5):
    """Exact received-power profile of a convex Lambertian mesh (or any mesh whose front
    faces neither shadow nor hide one another), flat facets, monostatic, irradiance 1.

    Each face facing w contributes (ρ/π) cos²θ × area, spread over range as the triangular
    distribution of r = −p·w over the triangle (min, mode, max at its vertices' ranges):
    no sampling, so the error of either tool on the same mesh is measured exactly.

    Parameters
    ----------
    vertices : (n, 3) array_like of float
        The mesh's vertices, scene units.
    faces : (m, 3) array_like of int
        Vertex indices; a face faces w when its normal by the right-hand rule (counter-
        clockwise winding seen from outside) has a positive component along w. Others
        return nothing.
    view : (3,) array_like
        w, from the scene toward the sensor (normalised here).
    bin_edges : (n_bins + 1,) array_like
        Range edges r = −p·w, increasing, scene units; a face's power outside them is not
        counted.
    reflectance : float
        ρ, the Lambertian reflectance (default 0.5).

    Returns
    -------
    (n_bins,) numpy.ndarray of float64
        Received power per bin, ``radiometry="power"`` units under unit irradiance.
    """
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    w = np.asarray(view, dtype=np.float64).reshape(3)
    w = w / np.linalg.norm(w)
    e = np.asarray(bin_edges, dtype=np.float64)
    tri = v[f]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area2 = np.linalg.norm(n, axis=1)
    cos = (n @ w) / np.where(area2 > 0, area2, 1.0)
    front = cos > 0
    weight = reflectance / np.pi * cos[front] ** 2 * 0.5 * area2[front]
    r = np.sort(-(tri[front] @ w), axis=1)
    out = np.zeros(len(e) - 1)
    for lo in range(0, len(r), 20000):                    # bounded memory
        rr = r[lo:lo + 20000]
        cdf = _triangular_cdf(e[None, :], rr[:, 0], rr[:, 1], rr[:, 2])
        out += weight[lo:lo + 20000] @ np.diff(cdf, axis=1)
    return out
