"""View directions spread evenly over the sphere (the golden-angle lattice)."""

from __future__ import annotations

import math

import numpy as np

from .._validate import check_count, check_size

__all__ = ["fibonacci_sphere"]


def fibonacci_sphere(n, *, hemisphere=False):
    """n view vectors spread evenly over the sphere (or the upper hemisphere z ≥ 0), by the
    golden-angle (Fibonacci) lattice: each covers ~4π/n sr."""
    n = check_count("n", n)
    # the lattice's few temporaries of n × 3 floats
    check_size("n", n, 8 * 3 * 4, f"{n} directions", "ask for fewer")
    k = np.arange(n) + 0.5
    z = 1 - k / n if hemisphere else 1 - 2 * k / n
    r = np.sqrt(np.maximum(1 - z * z, 0.0))
    phi = math.pi * (3 - math.sqrt(5)) * k
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], -1)
