"""Parallel rays' start distance: it does not change a projection (the whole line is
walked), and a start far enough to lose the rays' sideways position is refused."""

from __future__ import annotations

import numpy as np
import pytest

from meshladar.errors import ParameterError
from meshladar.forward.siddon import MAX_START_DISTANCE, PixelGrid, parallel_rays, project

#: Projections from starts 0 and 1e4 away agree to the start's rounding carried through the
#: traversal (measured 1.0e-9 of the largest value at 1e4; it grows about linearly with the
#: distance, which is why MAX_START_DISTANCE bounds it)
START_TOL = 5e-9


def _disk_image(grid):
    x0, y0 = grid.origin
    x = x0 + (np.arange(grid.nx) + 0.5) * grid.pixel_size
    y = y0 + (np.arange(grid.ny) + 0.5) * grid.pixel_size
    return (np.hypot(*np.meshgrid(x, y)) < 0.6).astype(float)


def test_the_start_does_not_change_the_projection():
    grid = PixelGrid.square(64, 1.0)
    image = _disk_image(grid)
    s = np.linspace(-0.9, 0.9, 37)
    near = project(image, grid, parallel_rays([0.0, 33.0], s, distance=0.0))
    far = project(image, grid, parallel_rays([0.0, 33.0], s, distance=1e4))
    assert np.abs(near).max() > 0.5
    np.testing.assert_allclose(far, near, rtol=0, atol=START_TOL * np.abs(near).max())


@pytest.mark.parametrize("distance", [1e12, 1e16, MAX_START_DISTANCE * 2.0])
def test_a_start_too_far_for_the_rays_position_is_refused(distance):
    # at 1e12 a start's rounding moved rays sideways by 6e-3 of the signal, silently
    with pytest.raises(ParameterError, match=r"distance must be in \[0, 1e\+06\]"):
        parallel_rays([0.0], np.linspace(-1.0, 1.0, 5), distance=distance)


def test_the_limit_scales_with_the_positions_reach():
    s = np.linspace(-1e3, 1e3, 5)                  # a scene in millimetres
    parallel_rays([0.0], s, distance=5e8)          # within 1e6 × 1e3
    with pytest.raises(ParameterError, match="distance"):
        parallel_rays([0.0], s, distance=2e9)
