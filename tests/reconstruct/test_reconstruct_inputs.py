"""A user trial's defects in meshladar.reconstruct, each against closed forms or hand-built
data: compensate's default square (the bins' reach, as fbp's) on a scene in millimetres;
fbp's coverage warnings with repeated view angles; the iterative solvers' invariance to
the data's scale (1e-300 to 1e300); and the inputs refused with their value and shape
(fbp3d's and sirt's weights, sphere_weights' view vectors, compensate's labels)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import meshladar as ml
from meshladar.brdf import Lambertian
from meshladar.errors import MeshladarWarning, ParameterError
from meshladar.meshes import fibonacci_sphere
from meshladar.reconstruct import compensation
from meshladar.reconstruct.compensation import (compensate, first_image, needed_size,
                                                surface_weights)
from meshladar.reconstruct.fbp2d import _distinct_angles, bins_reach
from meshladar.reconstruct.iterative import cgls, sart, sirt, tv_fista
from meshladar.reconstruct.volumes import coverage_gap_deg, fbp3d, sphere_weights


def disk_sinogram(center, radius, angles_deg, edges, value=1.0):
    """Exact bin integrals of a uniform disk's Radon transform, the chord 2√(R² − s²)
    integrated over each bin (range r = −p·w, so the centre's range is −c·w)."""
    phi = np.deg2rad(np.asarray(angles_deg, dtype=float))
    rc = -(center[0] * np.cos(phi) + center[1] * np.sin(phi))
    s = np.clip((np.asarray(edges)[None, :] - rc[:, None]) / radius, -1.0, 1.0)
    prim = radius * radius * (s * np.sqrt(1.0 - s * s) + np.arcsin(s))   # ∫ chord ds
    return ml.Sinogram(value * np.diff(prim, axis=1), angles_deg=angles_deg, bin_edges=edges)


# -- 1. compensate's default square: the bins' reach ------------------------------------

#: The disk of the trial, millimetres: radius 60 at (40, -25), Lambertian albedo 0.5.
MM_CENTER, MM_RADIUS, ALBEDO = (40.0, -25.0), 60.0, 0.5
#: The compensated ring's integral against ⟨h⟩ · 2πR (measured 0.6 % low at 128 bins,
#: 128²; test_compensation's LEVEL_TOL).
LEVEL_TOL = 0.06
#: The surface pixels' distance from the true circle, in bin widths (measured: mean 0.5,
#: largest 1.2).
MEAN_OFFSET_BINS, MAX_OFFSET_BINS = 1.0, 2.0


@pytest.fixture(scope="module")
def mm_disk():
    part = ml.Scene([ml.Disk(center=MM_CENTER, radius=MM_RADIUS, material=Lambertian(ALBEDO))])
    return ml.simulate(part, ml.Ladar.covering(part, n_bins=128))


def test_compensate_defaults_to_the_bins_reach_in_any_units(mm_disk):
    """A Lambertian disk in millimetres: by default the square is the bins' reach about the
    origin (as fbp's), so the compensated ring lies on the true circle and integrates to
    ⟨h⟩ · 2πR, ⟨h⟩ = (1/π) ∫₀^{π/2} (ρ/π) cos θ dθ = ρ/π² (a 2-unit window at the origin,
    the old default, held no surface at all)."""
    sino = mm_disk
    reach = float(max(abs(sino.bin_edges[0]), abs(sino.bin_edges[-1])))
    img = compensate(sino, Lambertian(ALBEDO), size=128)
    assert img.extent == reach == bins_reach(sino)
    assert img.center == (0.0, 0.0)
    X, Y = np.meshgrid(img.x, img.y)
    r = np.hypot(X - MM_CENTER[0], Y - MM_CENTER[1])
    v = img.values
    bin_width = float(np.diff(sino.bin_edges).mean())
    ring = float(v.sum()) * (2.0 * img.extent / img.size) ** 2
    expected = ALBEDO / math.pi ** 2 * 2.0 * math.pi * MM_RADIUS
    assert abs(ring / expected - 1.0) < LEVEL_TOL
    assert abs(float(np.sum(v * r) / v.sum()) - MM_RADIUS) < MEAN_OFFSET_BINS * bin_width
    assert float(np.abs(r[v != 0] - MM_RADIUS).max()) < MAX_OFFSET_BINS * bin_width
    # the helpers share the default: first_image's square, needed_size's pixels
    assert first_image(sino, 16).extent == reach
    assert needed_size(sino) == math.ceil(2.0 * reach / (1.5 * bin_width) - 1e-9)
    assert needed_size(sino, 1.0) == math.ceil(2.0 / (1.5 * bin_width) - 1e-9)


def test_compensate_names_the_square_that_holds_no_surface(mm_disk):
    with pytest.raises(ParameterError, match=r"seen and backed by the data in the square "
                                             r"extent=1 about center=\(300\.0, 0\.0\): "
                                             r"check that it holds the scene"):
        compensate(mm_disk, Lambertian(ALBEDO), size=64, extent=1.0, center=(300.0, 0.0))


# -- 2. fbp's coverage warnings count distinct angles -----------------------------------

EDGES = np.linspace(-1.0, 1.0, 101)
#: Images from the same data, each angle's views sharing its weight: round-off only.
SAME_IMAGE_RTOL = 1e-12


def test_repeated_views_leave_the_gap_warning_on():
    """180 angles over a half circle, each taken 3 times: the gap (181°) is 181 times the
    median spacing of the distinct angles (1°), as for the angles taken once; the image is
    the once-taken one (an angle's share split among its repeats)."""
    once = np.arange(0.0, 180.0, 1.0)
    gap = r"largest gap 181° vs median spacing 1° \(of 180 distinct angles\)"
    with pytest.warns(MeshladarWarning, match=gap):
        ref = ml.fbp(disk_sinogram((0.1, 0.0), 0.5, once, EDGES), 64)
    with pytest.warns(MeshladarWarning, match=gap):
        rep = ml.fbp(disk_sinogram((0.1, 0.0), 0.5, np.repeat(once, 3), EDGES), 64)
    np.testing.assert_allclose(rep.values, ref.values, rtol=0,
                               atol=SAME_IMAGE_RTOL * np.abs(ref.values).max())


def test_repeated_views_leave_the_too_few_warning_on():
    """12 angles each taken 3 times are 12 views for the angular sampling: π · 51 bins
    across / 12 = 13 > 8 warns, as for the 12 taken once."""
    once = np.arange(0.0, 360.0, 30.0)
    with pytest.warns(MeshladarWarning, match=r"^12 views are too few for the 51 bins"):
        ml.fbp(disk_sinogram((0.1, 0.0), 0.5, once, EDGES), 64)
    with pytest.warns(MeshladarWarning, match=r"^12 distinct views \(the 36 views repeat 12 "
                                              r"angles, within 1e-06 deg\) are too few for "
                                              r"the 51 bins"):
        ml.fbp(disk_sinogram((0.1, 0.0), 0.5, np.repeat(once, 3), EDGES), 64)


def test_full_coverage_with_repeats_does_not_warn():
    """360 angles at 1°, each taken 3 times: covered, and the uniform disk of value 1
    reconstructs as from the angles once (filterwarnings = error)."""
    once = np.arange(0.0, 360.0, 1.0)
    ref = ml.fbp(disk_sinogram((0.1, 0.0), 0.5, once, EDGES), 64)
    rep = ml.fbp(disk_sinogram((0.1, 0.0), 0.5, np.repeat(once, 3), EDGES), 64)
    np.testing.assert_allclose(rep.values, ref.values, rtol=0,
                               atol=SAME_IMAGE_RTOL * np.abs(ref.values).max())
    X, Y = np.meshgrid(rep.x, rep.y)
    inside = np.hypot(X - 0.1, Y) < 0.4                   # a pixel and more from the edge
    assert np.abs(rep.values[inside] - 1.0).max() < DISK_ATOL


#: FBP of the exact disk (64², 100 bins over [−1, 1], 360 views) inside it: 1 to this
#: (measured 9.7e-4).
DISK_ATOL = 3e-3


def test_distinct_angles_within_the_stated_tolerance():
    """Angles within 1e-6° (ANGLE_TOL_DEG, mod 360°) are one; 2e-6° apart are two."""
    angles = [0.0, 5e-7, 359.9999995, 90.0, 90.0 + 2e-6, 450.0]
    distinct, index = _distinct_angles(angles)
    np.testing.assert_allclose(np.degrees(distinct), [0.0, 90.0, 90.0 + 2e-6], atol=1e-9)
    assert index.tolist() == [0, 0, 0, 1, 2, 1]


# -- 3. the iterative solvers are invariant to the data's scale ------------------------

ANGLES = np.arange(0.0, 360.0, 5.0)
EDGES48 = np.linspace(-1.0, 1.0, 48)
SOLVERS = {"sirt": (sirt, {"n_iter": 5}), "sart": (sart, {"n_iter": 2}),
           "cgls": (cgls, {"n_iter": 5}), "cgls_fbp": (cgls, {"n_iter": 5, "x0": "fbp"}),
           "tv_fista": (tv_fista, {"n_iter": 5})}
#: Powers of two from 2^-996 (1.5e-300) to 2^996 (6.7e299): the solvers divide by a power
#: of two, so they run on the same numbers and the image scales exactly.
POWERS = (-996, -565, 565, 996)
#: Decimal scales change the data's last bits: the runs agree to round-off (measured
#: ≤ 1.3e-14 of the peak at these few iterations; CGLS's later ones amplify any last-bit
#: change, at unit scale too: 1e-5 after 30).
DECIMAL_RTOL = 1e-9


def _run(name, values, **extra):
    f, kw = SOLVERS[name]
    return f(ml.Sinogram(values, angles_deg=ANGLES, bin_edges=EDGES48), 32, **kw, **extra)


@pytest.fixture(scope="module")
def exact_disk():
    return disk_sinogram((0.1, 0.2), 0.4, ANGLES, EDGES48).values


@pytest.mark.parametrize("name", sorted(SOLVERS))
def test_solvers_scale_exactly_with_the_data(name, exact_disk):
    unit = _run(name, exact_disk)
    assert unit.info["residuals"][-1] < unit.info["residuals"][0] < 1.0
    for k in POWERS:
        s = math.ldexp(1.0, k)
        got = _run(name, exact_disk * s)                       # no warning: errors here
        np.testing.assert_array_equal(got.values, unit.values * s)
        assert got.info["residuals"] == unit.info["residuals"]
        assert got.info["stopped"] == unit.info["stopped"]
        if name == "tv_fista":
            assert got.info["objective"] == unit.info["objective"]
            assert got.info["lambda"] == unit.info["lambda"] * s
    for s in (1e-300, 1e300):
        got = _run(name, exact_disk * s)
        np.testing.assert_allclose(got.values / s, unit.values, rtol=0,
                                   atol=DECIMAL_RTOL * np.abs(unit.values).max())
        np.testing.assert_allclose(got.info["residuals"], unit.info["residuals"],
                                   rtol=DECIMAL_RTOL)


@pytest.mark.parametrize("name", ["sirt", "cgls", "tv_fista"])
def test_a_dropped_bin_sets_no_scale(name, exact_disk):
    """A bin of 2^1000 with weight 0 (a dropped glint) changes nothing: the run equals the
    one with that bin at 0, without overflow."""
    weights = np.ones_like(exact_disk)
    weights[3, 20] = 0.0
    glint, dropped = exact_disk.copy(), exact_disk.copy()
    glint[3, 20], dropped[3, 20] = math.ldexp(1.0, 1000), 0.0
    got, ref = _run(name, glint, weights=weights), _run(name, dropped, weights=weights)
    np.testing.assert_array_equal(got.values, ref.values)
    assert got.info["residuals"] == ref.info["residuals"]


# -- 4. inputs refused with their value and shape ---------------------------------------

def _ball_sinogram(radius=0.5, n_views=200, n_bins=24):
    """A uniform ball's plane integrals π(a² − s²) over each bin, Fibonacci views."""
    w = fibonacci_sphere(n_views)
    edges = np.linspace(-1.0, 1.0, n_bins + 1)
    s = np.clip(edges, -radius, radius)
    prim = math.pi * (radius ** 2 * s - s ** 3 / 3.0)
    values = np.tile(np.diff(prim), (n_views, 1))
    return ml.Sinogram(values, angles_deg=np.degrees(np.arctan2(w[:, 1], w[:, 0])),
                       bin_edges=edges, view_vectors=w)


def test_fbp3d_weights_are_refused_with_value_and_shape():
    sino = _ball_sinogram()
    with pytest.raises(ParameterError, match=r"weights are all zero \(shape \(200,\)\)"):
        fbp3d(sino, size=8, weights=np.zeros(200))
    with pytest.raises(ParameterError, match=r"weights must be solid angles >= 0 .*got -1 at "
                                             r"index 7 \(of shape \(200,\)\)"):
        fbp3d(sino, size=8, weights=np.r_[np.ones(7), -1.0, np.ones(192)])
    with pytest.raises(ParameterError, match=r"weights must be 200 solid angles >= 0, shape "
                                             r"\(200,\) .*got shape \(199,\)"):
        fbp3d(sino, size=8, weights=np.ones(199))


def test_view_vectors_shape_is_checked_first():
    w = fibonacci_sphere(400)
    for f in (sphere_weights, coverage_gap_deg):
        with pytest.raises(ParameterError, match=r"view_vectors must be an \(n, 3\) array of "
                                                 r"view directions, n >= 1; got shape "
                                                 r"\(400, 2\)"):
            f(w[:, :2])
    # Fibonacci directions are equal-area: shares of 4π that sum to it
    np.testing.assert_allclose(sphere_weights(w).sum(), 4 * math.pi, rtol=1e-12)


def test_sirt_weights_name_the_offending_value():
    sino = disk_sinogram((0.1, 0.2), 0.4, ANGLES, EDGES48)
    bad = np.ones(sino.shape)
    bad[2, 5] = -0.5
    with pytest.raises(ParameterError, match=r"weights must be >= 0 \(0 drops a bin\); got "
                                             r"-0\.5 at index \(2, 5\) \(of shape \(72, 47\)\)"):
        sirt(sino, 16, weights=bad)
    with pytest.raises(ParameterError, match=r"weights must be one value >= 0 per bin, shape "
                                             r"\(72, 47\) \(n_views, n_bins\); got shape "
                                             r"\(72,\)"):
        sirt(sino, 16, weights=np.ones(72))
    with pytest.raises(ParameterError, match=r"weights are all zero \(shape \(72, 47\)\)"):
        sirt(sino, 16, weights=np.zeros(sino.shape))


@pytest.fixture
def no_work(monkeypatch):
    """compensate's first reconstruction made to fail: a refusal must come before it."""
    def work(*args, **kwargs):
        raise AssertionError("compensate started its work before refusing its input")
    monkeypatch.setattr(compensation, "first_image", work)


def test_compensate_checks_labels_whenever_given(no_work):
    sino = disk_sinogram((0.1, 0.2), 0.4, ANGLES, EDGES48)
    one = [Lambertian(0.5)]
    with pytest.raises(ParameterError, match=r"labels must be a \(64, 64\) array of indices "
                                             r"into material; got shape \(3, 3\)"):
        compensate(sino, one, labels=np.zeros((3, 3), int), size=64)
    half = np.zeros((64, 64))
    half[5, 9] = 0.5
    with pytest.raises(ParameterError, match=r"labels must be whole numbers \(indices into "
                                             r"material\); got 0\.5 at index \(5, 9\)"):
        compensate(sino, Lambertian(0.5), labels=half, size=64)
    with pytest.raises(ParameterError, match=r"several materials \(2\) need labels"):
        compensate(sino, [Lambertian(0.5), Lambertian(0.2)], size=64)
    with pytest.raises(ParameterError, match=r"extent must be in \[1e-150, 1e\+300\]; got -1"):
        compensate(sino, one, extent=-1.0, size=64)
    with pytest.raises(ParameterError, match=r"center must be a point \(x, y\); got shape"):
        compensate(sino, one, center=(0.0, 0.0, 0.0), size=64)


#: Error of h(θ)/⟨h⟩ = π cos θ (a Lambertian coating, paper radiometry) on the surface's
#: front-facing entries, unblurred (the normals are the estimate's own): ⟨h⟩ is the
#: library's quadrature over θ (measured: 1e-8 absolute).
WEIGHT_RTOL, WEIGHT_ATOL = 1e-7, 1e-7


def test_surface_weights_check_labels_on_the_surface_for_one_material():
    """An index outside [0, n) on the surface is refused with its pixel; off the surface any
    whole number is a background value (-1 here); labels of 0 on the surface weigh as no
    labels, h(θ)/⟨h⟩ = cos θ / (1/π) in front (the closed form of a Lambertian coating)."""
    sino = disk_sinogram((0.0, 0.0), 0.5, ANGLES, EDGES48)
    surf = compensation.estimate_surface(ml.fbp(sino, 32), sino, shadows=False)
    r, c = int(surf.rows[0]), int(surf.cols[0])
    with pytest.raises(ParameterError, match=r"labels on the surface must be in \[0, 1\) .*got "
                                             rf"1 at pixel \({r}, {c}\)"):
        surface_weights(surf, ANGLES, Lambertian(0.5), labels=np.ones((32, 32), int))
    background = np.full((32, 32), -1)
    background[surf.rows, surf.cols] = 0
    H = surface_weights(surf, ANGLES, Lambertian(0.5), labels=background, blur_deg=0.0)
    phi = np.deg2rad(ANGLES)
    cos_t = surf.normals[:, :1] * np.cos(phi) + surf.normals[:, 1:] * np.sin(phi)
    front = cos_t > 0
    np.testing.assert_allclose(H[front], np.pi * cos_t[front], rtol=WEIGHT_RTOL,
                               atol=WEIGHT_ATOL)
    np.testing.assert_array_equal(H, surface_weights(surf, ANGLES, Lambertian(0.5),
                                                     blur_deg=0.0))
