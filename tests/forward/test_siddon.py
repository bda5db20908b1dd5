"""Siddon projector: exact lengths, adjointness, agreement with the exact Radon transform."""

from __future__ import annotations

import math

import numpy as np
import pytest

from meshladar.errors import ParameterError
from meshladar.forward.siddon import ParallelProjector, PixelGrid, Rays, backproject, project


def _square_chord(phi, s, half):
    """Length of the line s·u + t·w inside [−half, half]² (by slab clipping)."""
    c, sn = math.cos(phi), math.sin(phi)
    lo, hi = -math.inf, math.inf
    for pu, pw in ((-sn * s, c), (c * s, sn)):
        if abs(pw) < 1e-15:
            if not -half <= pu <= half:
                return 0.0
            continue
        a, b = (-half - pu) / pw, (half - pu) / pw
        lo, hi = max(lo, min(a, b)), min(hi, max(a, b))
    return max(hi - lo, 0.0)


@pytest.mark.parametrize("size", [1, 7, 64])
def test_lengths_sum_to_the_chord_through_the_grid(size):
    grid = PixelGrid.square(size, 1.0)
    angles = np.array([0.0, 17.0, 45.0, 90.0, 133.0, 180.0, 270.0, 301.0])
    pos = np.linspace(-1.5, 1.5, 60)          # no ray exactly on the grid's outer edges
    A = ParallelProjector(grid, angles, pos)
    got = A @ np.ones(grid.shape)
    ref = np.array([[_square_chord(math.radians(a), s, 1.0) for s in pos] for a in angles])
    np.testing.assert_allclose(got, ref, rtol=1e-12, atol=1e-12)


def test_adjoint():
    # ⟨Ax, y⟩ = ⟨x, Aᵀy⟩: both sides sum the same products length·x·y in another order
    rng = np.random.default_rng(2009)
    grid = PixelGrid(40, 30, 0.05, (-1.0, -0.7))
    A = ParallelProjector(grid, rng.uniform(0, 360, 37), np.linspace(-1.2, 1.2, 53))
    x = rng.normal(size=grid.shape)
    y = rng.normal(size=(37, 53))
    lhs = np.sum((A @ x) * y)
    rhs = np.sum(x * (A.T @ y))
    assert abs(lhs - rhs) <= 1e-10 * abs(lhs)


def test_uniform_disk_projections_match_exact_radon():
    grid = PixelGrid.square(400, 1.0)
    h = grid.pixel_size
    X, Y = np.meshgrid(grid.x, grid.y)
    c, R = np.array([0.2, -0.1]), 0.5
    disk = ((X - c[0]) ** 2 + (Y - c[1]) ** 2 < R**2).astype(float)
    angles = [0.0, 33.0, 90.0, 151.0]
    pos = np.linspace(-0.9, 0.9, 721)
    proj = ParallelProjector(grid, angles, pos) @ disk
    for i, a in enumerate(angles):
        u = np.array([-math.sin(math.radians(a)), math.cos(math.radians(a))])
        q = pos - c @ u
        exact = 2 * np.sqrt(np.clip(R**2 - q**2, 0, None))
        inner = np.abs(q) < R - 2 * h
        # pixelation: each chord end is off by ≤ √2 h along the boundary normal, i.e. by
        # √2 h R / sqrt(R² − q²) along the ray
        bound = 2 * math.sqrt(2) * h * R / np.sqrt(R**2 - q[inner] ** 2)
        assert np.all(np.abs(proj[i][inner] - exact[inner]) <= bound)
        # mass: ∫ p ds equals the pixelated disk's area (to the ds quadrature)
        ds = pos[1] - pos[0]
        assert proj[i].sum() * ds == pytest.approx(disk.sum() * h * h, rel=2e-3)


def test_rays_missing_the_grid_and_axis_aligned_rays():
    grid = PixelGrid(4, 4, 1.0, (0.0, 0.0))
    img = np.arange(16.0).reshape(4, 4)
    rays = Rays([10.0, 10.0, 0.5, 10.0], [10.0, 1.5, 10.0, 4.0], [-1, -1, 0, -1], [0, 0, -1, 0])
    out = project(img, grid, rays)
    assert out[0] == 0.0                                   # misses
    assert out[1] == pytest.approx(img[1].sum())           # along row 1 (y ∈ [1, 2))
    assert out[2] == pytest.approx(img[:, 0].sum())        # down column 0
    assert out[3] == 0.0                                   # on the grid's top edge, outside
    back = backproject(np.array([0.0, 1.0, 0.0, 0.0]), grid, rays)
    np.testing.assert_allclose(back[1], 1.0)
    assert back.sum() == pytest.approx(4.0)


def test_bad_inputs():
    with pytest.raises(ParameterError, match=r"nx must be an integer >= 1; got 0"):
        PixelGrid(0, 3, 1.0, (0, 0))
    with pytest.raises(ParameterError, match=r"pixel_size must be in \(0, inf\)"):
        PixelGrid(2, 3, 0.0, (0, 0))
    grid = PixelGrid(2, 2, 1.0, (0, 0))
    rays = Rays([0.0], [0.0], [1.0], [0.0])
    with pytest.raises(ParameterError, match=r"image must have the grid's shape \(2, 2\)"):
        project(np.ones((3, 2)), grid, rays)
    with pytest.raises(ParameterError, match=r"ray directions \(dx, dy\) must be non-zero"):
        Rays([0.0], [0.0], [0.0], [0.0])
    with pytest.raises(ParameterError, match=r"values must have one entry per ray \(1\)"):
        backproject(np.ones(2), grid, rays)
