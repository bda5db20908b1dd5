"""Small helpers the models share: angles to (cos θ, |sin θ|) pairs, from an angle or from a
direction and a normal; a division that fills where the denominator is 0; scalar in, scalar
out; and the [0, 1] check of a reflectance-like parameter.

Conventions (angles, horizon, units) are :mod:`meshladar.brdf.base`'s.
"""

from __future__ import annotations

import numpy as np

from .._validate import check_real, finite_array


def _safe_divide(num, den, fill):
    """num / den where den > 0, ``fill`` where den == 0, without a numpy warning."""
    num, den = np.broadcast_arrays(np.asarray(num, np.float64), np.asarray(den, np.float64))
    out = np.full(num.shape, fill, dtype=np.float64)
    np.divide(num, den, out=out, where=den > 0)
    return out


def _cos_sin(theta, name):
    t = finite_array(name, theta)
    return np.cos(t), np.abs(np.sin(t))


def _cos_sin_vec(w, n):
    """cos and sin of the angle between unit vectors, sin from the cross product (accurate
    near 0 where sqrt(1 − cos²) is not)."""
    return (np.einsum("...k,...k->...", w, n), np.linalg.norm(np.cross(w, n), axis=-1))


def _out(value, *inputs):
    """Scalar in, scalar out: a Python float when every input was 0-d."""
    if all(np.ndim(x) == 0 for x in inputs):
        return float(value)
    return value


def _unit_interval(name, value):
    return check_real(name, value, low=0.0, high=1.0)
