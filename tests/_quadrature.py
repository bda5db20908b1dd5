"""Independent quadrature over the hemisphere of reflected directions, for the BRDF tests.

Narrow glint lobes (e down to 1e-4) are resolved by integrating in half-vector
coordinates: the reflected direction w_r is the mirror of w_i about the half vector m, and
dω_r = 4 (w_i·m) dω_m. In polar coordinates (α, φ) of m about the normal, the glint lobe
depends on α alone and peaks at α = 0, so a graded Gauss-Legendre mesh in α with panels at
multiples of e resolves it. The admissible half vectors (w_r above the surface) are
α ≤ α_max(φ) = (atan2(sin θi cos φ, cos θi) + π/2) / 2, from
2 (w_i·m) cos α − cos θi = cos θi cos 2α + sin θi cos φ sin 2α ≥ 0.
Nothing here uses the closed forms under test.
"""

from __future__ import annotations

import numpy as np
from scipy import integrate

_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(24)


def _alpha_panels(alpha_max, e):
    """Panel edges on [0, alpha_max], graded geometrically (ratio ~2) from e/64 to π/2."""
    n = int(np.ceil(np.log2((np.pi / 2) / (e / 64.0)))) + 1
    inner = np.geomspace(e / 64.0, np.pi / 2, n)
    edges = np.concatenate([[0.0], inner[inner < alpha_max], [alpha_max]])
    return edges


def _gauss(edges):
    a, b = edges[:-1, None], edges[1:, None]
    x = 0.5 * (b - a) * _GL_NODES + 0.5 * (a + b)
    w = 0.5 * (b - a) * _GL_WEIGHTS
    return x.ravel(), w.ravel()


def half_vector_integral(theta_i, e, weight, *, epsrel=1e-12):
    """∫ weight(w_r) dω_r over the upper hemisphere, in half-vector coordinates.

    ``weight`` maps reflected directions (n, 3) and half-vector polar angles (n,) to values.
    The lobe scale ``e`` sets the α grading.
    """
    w_i = np.array([np.sin(theta_i), 0.0, np.cos(theta_i)])

    def over_alpha(phi):
        alpha_max = 0.5 * (np.arctan2(np.sin(theta_i) * np.cos(phi), np.cos(theta_i)) + np.pi / 2)
        if alpha_max <= 0.0:
            return 0.0
        alpha, w = _gauss(_alpha_panels(alpha_max, e))
        m = np.stack([np.sin(alpha) * np.cos(phi), np.sin(alpha) * np.sin(phi), np.cos(alpha)], -1)
        dot = m @ w_i
        w_r = 2.0 * dot[:, None] * m - w_i
        jac = 4.0 * dot * np.sin(alpha)
        return float(np.sum(w * jac * weight(w_r, alpha)))

    # The integrand is even in φ. As θi → π/2, α_max(φ) steps from π/2 to 0 across
    # cos φ ≈ 0 over a width ~cot θi: break the φ range there.
    width = max(np.cos(theta_i) / max(np.sin(theta_i), 1e-300), 1e-300)
    points = np.pi / 2 + width * np.array([-100.0, -10.0, -1.0, 0.0, 1.0, 10.0, 100.0])
    points = points[(points > 0) & (points < np.pi)]
    value, _ = integrate.quad(over_alpha, 0.0, np.pi, points=points, epsabs=0.0,
                              epsrel=epsrel, limit=200)
    return 2.0 * value
