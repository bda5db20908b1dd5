"""The records' own checks (meshladar.Sinogram, meshladar.Image) and log_radiance at the
ends of float64: contradictions and nonsense refused with the argument named, before any
result exists; no NaN or inf from a valid floor."""

import math

import numpy as np
import pytest

import meshladar as ml
from meshladar.errors import ParameterError

ANGLES = np.arange(0.0, 360.0, 10.0)
EDGES = np.linspace(-1.0, 1.0, 33)


def _vectors(angles_deg):
    phi = np.deg2rad(angles_deg)
    return np.stack([np.cos(phi), np.sin(phi), 0 * phi], axis=1)


def test_a_sinogram_refuses_angles_that_contradict_its_view_vectors():
    """fbp reads the angles, fbp3d and the fits the vectors: a pair that disagrees (every
    vector 90° from its angle) is refused as Ladar refuses it; the same views agree."""
    values = np.ones((ANGLES.size, 32))
    with pytest.raises(ParameterError, match=r"angles_deg and view_vectors disagree: view 0 "
                                             r"has angle 0 deg but vector .*\(azimuth 90 deg\)"):
        ml.Sinogram(values, angles_deg=ANGLES, bin_edges=EDGES,
                    view_vectors=_vectors(ANGLES + 90.0))
    with pytest.raises(ParameterError, match="disagree"):
        ml.Ladar(ANGLES, EDGES, view_vectors=_vectors(ANGLES + 90.0))
    same = ml.Sinogram(values, angles_deg=ANGLES - 360.0, bin_edges=EDGES,
                       view_vectors=_vectors(ANGLES))
    np.testing.assert_allclose(same.view_vectors, _vectors(ANGLES), atol=1e-15)
    up = ml.Sinogram(values[:1], angles_deg=[123.0], bin_edges=EDGES,
                     view_vectors=[[0.0, 0.0, 1.0]])         # along z: any angle
    assert up.view_vectors[0, 2] == 1.0


def test_a_sinogram_of_3d_views_takes_their_azimuths():
    """angles_deg is optional with view_vectors: it is their azimuths (as for Ladar), so
    a hemisphere of views needs no made-up angles; with neither, the error says so."""
    vec = ml.meshes.fibonacci_sphere(5)
    sino = ml.Sinogram(np.ones((5, 32)), bin_edges=EDGES, view_vectors=vec)
    np.testing.assert_allclose(sino.angles_deg, np.degrees(np.arctan2(vec[:, 1], vec[:, 0])),
                               atol=1e-12)
    with pytest.raises(ParameterError, match="give angles_deg or view_vectors; got neither"):
        ml.Sinogram(np.ones((5, 32)), bin_edges=EDGES)
    with pytest.raises(ParameterError, match=r"view_vectors must have shape \(n_views, 3\); "
                                             r"got \(5, 2\)"):
        ml.Sinogram(np.ones((5, 32)), bin_edges=EDGES, view_vectors=vec[:, :2])


def test_a_sinogram_of_none_says_so():
    with pytest.raises(ParameterError, match="values must be an array of real numbers; "
                                             "got None"):
        ml.Sinogram(None, angles_deg=ANGLES, bin_edges=EDGES)


@pytest.mark.parametrize("kwargs, message", [
    (dict(values=np.zeros((3, 4)), extent=1.0), r"square \(size, size\) array; got shape "
                                                r"\(3, 4\)"),
    (dict(values=np.zeros((0, 0)), extent=1.0), r"got shape \(0, 0\)"),
    (dict(values=np.zeros((4, 4)), extent=-1.0), r"extent must be in \(0, inf\); got -1.0"),
    (dict(values=np.zeros((4, 4)), extent=0.0), r"extent must be in \(0, inf\); got 0.0"),
    (dict(values=np.zeros((4, 4)), extent=math.inf), "extent must be finite"),
    (dict(values=np.zeros((4, 4)), extent=1.0, center=(0.0, 1.0, 2.0)),
     r"center must be two numbers"),
    (dict(values=np.full((4, 4), np.nan), extent=1.0), "values must be finite"),
])
def test_an_image_refuses_what_is_not_a_square_grid(kwargs, message):
    with pytest.raises(ParameterError, match=message):
        ml.Image(**kwargs)


def test_an_image_grid_is_what_its_docstring_says():
    """Pixel centres c + (−extent + (k + ½) 2 extent / size), increasing, positive size."""
    image = ml.Image(np.zeros((4, 4)), 2, (10, -3))
    assert image.pixel_size == 1.0
    np.testing.assert_array_equal(image.x, [8.5, 9.5, 10.5, 11.5])
    np.testing.assert_array_equal(image.y, [-4.5, -3.5, -2.5, -1.5])


#: A bin's log-ratio to the floor, ln(v / (floor · max)), holds to this relative error even
#: where floor · max is subnormal (a subnormal keeps fewer digits) .
LOG_RTOL = 1e-9


@pytest.mark.parametrize("floor", [1e-6, 1e-300, 1e-308, 5e-309, 1e-320])
@pytest.mark.parametrize("peak", [1.0, 1e-300, 1e300])
def test_log_radiance_is_finite_and_exact_at_any_floor(floor, peak):
    """log(max(v, m) / m), m = floor × max: finite and ≥ 0 for every floor in (0, 1] and
    any maximum, equal to ln(v / max) − ln(floor) above the floor and 0 at or below it
    (empty bins included), with no warning."""
    v = peak * np.array([[1.0, 0.5, 0.0, 1e-3]])
    sino = ml.Sinogram(v, angles_deg=[0.0], bin_edges=np.arange(5.0))
    out = ml.log_radiance(sino, floor=floor).values[0]
    expected = [math.log(r) - math.log(floor) if r > floor else 0.0
                for r in (1.0, 0.5, 0.0, 1e-3)]
    assert np.all(np.isfinite(out)) and np.all(out >= 0)
    np.testing.assert_allclose(out, expected, rtol=LOG_RTOL, atol=0)
