"""Magnitudes at float64's ends, refused by name where they would overflow or underflow
inside (found by the command line's flag fuzzing once numpy's warnings raised inside
meshladar were no longer filtered out as meshladar's own)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import meshladar as ml
from meshladar.errors import ParameterError
from meshladar.forward.mesh import first_hits
from meshladar.sensor import MIN_WAIST, GaussianBeam


@pytest.mark.parametrize("waist", [5e-324, 1e-320, 1e-200, MIN_WAIST / 2])
def test_a_waist_whose_square_underflows_is_refused(waist):
    # exp(−2ρ²/waist²) divided by zero for a subnormal waist
    with pytest.raises(ParameterError, match=r"waist must be in \[1e-12, 1e\+09\]"):
        GaussianBeam(waist=waist)
    assert GaussianBeam(waist=MIN_WAIST).waist == MIN_WAIST


def test_covering_bins_whose_edges_overflow_are_refused():
    # 16 bins of 1e308 overflowed to inf edges; one bin of 1e300 still fits
    disk = ml.phantoms.scene("disk")
    with pytest.raises(ParameterError, match=r"bin_width must be in \[1e-200, 9\.987\d*e\+306\]"):
        ml.Ladar.covering(disk, n_bins=16, bin_width=1e308, angles_deg=[0.0])
    for n, w in ((16, 1e306), (None, 1e300)):
        edges = ml.Ladar.covering(disk, n_bins=n, bin_width=w, angles_deg=[0.0]).bin_edges
        assert np.all(np.isfinite(edges))


@pytest.mark.parametrize("z0", [1e308, -1e300, 1e31])
def test_a_slice_height_beyond_the_scenes_range_is_refused(z0):
    # 1e308 overflowed the rays' float32 coordinates inside the trace
    ball = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=1),
                              material=ml.materials.DARK_GRAY)
    ladar = ml.Ladar.covering(ball, n_bins=8, angles_deg=[0.0])
    with pytest.raises(ParameterError, match=r"z0 must be in \[-1e\+30, 1e\+30\]"):
        ml.simulate(ball, ladar, model="mesh", mode="slice", z0=z0)


@pytest.mark.parametrize("spacing", [3.05e38, 6.8e38, 1e31])
def test_a_ray_spacing_beyond_the_scenes_range_is_refused(spacing):
    # 3e38 overflowed the rays' float32 coordinates in the grid (found by the functions'
    # fuzzing through resolve); the largest taken, 1e30, traces with finite coordinates
    ball = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=1),
                              material=ml.materials.DARK_GRAY)
    ladar = ml.Ladar.covering(ball, n_bins=8, angles_deg=[0.0])
    with pytest.raises(ParameterError, match=r"ray_spacing must be in \[1e-150, 1e\+30\]"):
        ml.simulate(ball, ladar, model="mesh", ray_spacing=spacing)
    with pytest.raises(ParameterError, match=r"ray_spacing must be in \[1e-150, 1e\+30\]"):
        first_hits(ball, [0.0, 0.0, 1.0], ray_spacing=spacing)
    with np.errstate(all="raise"):
        points, _, ranges = first_hits(ball, [0.0, 0.0, 1.0], ray_spacing=1e30)
    assert np.all(np.isfinite(points)) and np.all(np.isfinite(ranges))
