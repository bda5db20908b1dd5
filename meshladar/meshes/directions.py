"""View directions spread evenly over the sphere (the golden-angle lattice)."""

from __future__ import annotations

import math

import numpy as np

from .._validate import check_count, check_size

__all__ = ["fibonacci_sphere"]


def fibonacci_sphere(n, *, hemisphere=False):
    """n view vectors spread evenly over the sphere (or the upper hemisphere z ≥ 0), by the
    golden-angle (Fibonacci) lattice: each covers ~4π/n sr (~2π/n sr on the hemisphere).

    Point k (k = 0 … n − 1) has z = 1 − (2k + 1)/n (hemisphere: z = 1 − (k + 1/2)/n, so
    0 < z < 1) and azimuth φ = π(3 − √5)(k + 1/2) from the +x axis toward +y.

    Parameters
    ----------
    n : int
        Number of directions, ≥ 1.
    hemisphere : bool, keyword-only, default False
        Spread the points over the upper hemisphere only (read by truth value).

    Returns
    -------
    (n, 3) ndarray of float64
        Unit vectors, the first nearest +z.

    Raises
    ------
    ParameterError
        When ``n`` is not an integer ≥ 1, or the lattice's arrays (96 bytes a point) would
        need more than 4 GiB.
    """
    n = check_count("n", n)
    # the lattice's few temporaries of n × 3 floats
    check_size("n", n, 8 * 3 * 4, f"{n} directions", "ask for fewer")
    k = np.arange(n) + 0.5
    z = 1 - k / n if hemisphere else 1 - 2 * k / n
    r = np.sqrt(np.maximum(1 - z * z, 0.0))
    phi = math.pi * (3 - math.sqrt(5)) * k
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], -1)
