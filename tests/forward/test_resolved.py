"""Returns resolved in cross-range, elevation and Doppler (meshladar.forward.resolved): closed forms
and conservation."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

import meshladar as ml
from meshladar.materials import ALUMINUM, lambertian
from meshladar.forward.resolved import resolve
from meshladar.motion import Motion

trimesh = pytest.importorskip("trimesh")

#: an 82k-face sphere with smooth normals, 8 rays per range bin: faceting and sampling
#: error of a Doppler bin (measured 4.4e-4 of the largest, Eq. 8; 1.1e-4 under power)
SPHERE_BIN_TOL = 2e-3
#: the same rays binned two ways: their sums differ by rounding only
SUM_RTOL = 1e-12


@pytest.fixture(scope="module")
def sphere():
    return ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=6, radius=1.0),
                              material=lambertian(0.5))


@pytest.mark.parametrize("radiometry", ["paper", "power"])
def test_rotating_lambertian_sphere_doppler_profile(sphere, radiometry):
    """A sphere turning at ω about z, seen from x: f_D = 2 (Ω × p)·w / λ = −2ω y / λ, so the
    Doppler profile is the cross-range profile of the projected disk: (ρ/π) 2 sqrt(R² − y²)
    per unit y under Eq. 8, and (ρ/π) π (R² − y²) / (2R) under received power (the disk's
    ∫ cos θ dz)."""
    R, rho, om, lam = 1.0, 0.5, 0.1, 1e-6
    ladar = ml.Ladar(angles_deg=[0.0], bin_edges=np.linspace(-1.0, 0.0, 65))
    fe = np.linspace(-2.02 * om * R / lam, 2.02 * om * R / lam, 41)
    motion = Motion(omega=(0.0, 0.0, om), wavelength=lam)
    ret = resolve(sphere, ladar, [("doppler", fe)], motion=motion, radiometry=radiometry,
                  normals="smooth", rays_per_bin=8)
    y = np.clip(-fe * lam / (2 * om), -R, R)
    if radiometry == "paper":
        prim = rho / math.pi * (y * np.sqrt(R * R - y * y) + R * R * np.arcsin(y / R))
    else:
        prim = rho / (2 * R) * (R * R * y - y ** 3 / 3)
    exact = -np.diff(prim)
    assert np.abs(ret.values[0] - exact).max() < SPHERE_BIN_TOL * exact.max()
    # the same rays as the range sinogram, traced: the same total ("auto" draws the
    # sinogram's first hits, which differ at rays within round-off of an edge)
    sino = ml.simulate(sphere, ladar, model="mesh", radiometry=radiometry, normals="smooth",
                       rays_per_bin=8, backend="packets")
    np.testing.assert_allclose(ret.total(), sino.total(), rtol=SUM_RTOL)
    assert ret.info["radiometry"] == radiometry and ret.units == ("Hz",)


def test_doppler_of_a_translation_is_one_line():
    """A target translating at V toward the ladar: every point at f_D = 2 V·w / λ."""
    scene = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=3),
                               material=lambertian(0.5))
    ladar = ml.Ladar(angles_deg=[30.0], bin_edges=np.linspace(-1.0, 0.0, 33))
    w = ladar.view_vectors[0]
    V, lam = np.array([3.0, -1.0, 2.0]), 1.55e-6
    f0 = 2 * float(V @ w) / lam
    fe = f0 + np.array([-1.0, -1e-3, 1e-3, 1.0]) * 1e3
    ret = resolve(scene, ladar, {"doppler": fe}, motion=Motion(velocity=V, wavelength=lam))
    assert ret.values[0, 0] == 0 and ret.values[0, 2] == 0 and ret.values[0, 1] > 0


def test_turntable_doppler_sign():
    """A small sphere at +y on a turntable turning counter-clockwise (Ω = +ω z), seen from
    +x: Ω × p = −ω y0 x, away from the ladar, so every return has f_D ≈ −2 ω y0 / λ < 0."""
    om, y0, lam = 0.5, 2.0, 1e-6
    ball = trimesh.creation.icosphere(subdivisions=3, radius=0.05)
    ball.apply_translation((0.0, y0, 0.0))
    scene = ml.Scene.from_mesh(ball, material=lambertian(0.5))
    ladar = ml.Ladar(angles_deg=[0.0], bin_edges=np.linspace(-0.1, 0.1, 9))
    f0 = -2 * om * y0 / lam
    fe = np.linspace(-1.5 * abs(f0), 1.5 * abs(f0), 31)
    ret = resolve(scene, ladar, [("doppler", fe)], motion=Motion(omega=(0.0, 0.0, om),
                                                                 wavelength=lam))
    prof = ret.values[0]
    centre = np.sum(prof * ret.centers("doppler")) / prof.sum()
    # the ball spans ±0.05 in x... its points' Doppler is −2ω(y)/λ, y within 0.05 of y0
    assert abs(centre - f0) < 0.05 * abs(f0)
    assert prof[ret.centers("doppler") > 0].sum() == 0


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # faceted on purpose
def test_range_gated_image_stack():
    """Three coordinates at once: cross-range × elevation × range; its marginals are the
    two-coordinate images and the range profile."""
    scene = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=3),
                               material=ALUMINUM)
    ladar = ml.Ladar.covering(scene, n_bins=8, angles_deg=[0.0, 50.0])
    e = np.linspace(-1.1, 1.1, 12)
    stack = resolve(scene, ladar, [("cross_range", e), ("elevation", e),
                                   ("range", ladar.bin_edges)])
    assert stack.values.shape == (2, 11, 11, 8)
    image = resolve(scene, ladar, [("cross_range", e), ("elevation", e)])
    np.testing.assert_allclose(stack.values.sum(axis=3), image.values, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(stack.marginal("range"),
                               resolve(scene, ladar, [("range", ladar.bin_edges)]).values,
                               rtol=1e-12, atol=1e-15)


def test_plate_angle_angle_image_is_its_projected_shape():
    """A Lambertian square plate turned 30° about z, seen from x: its image in (cross-range,
    elevation) is the projected rectangle (cos 30° × 1 by 1) times F·(cell area), exactly 0
    outside it, and its total is F × the projected area."""
    half, rho = 0.5, 0.7
    plate = trimesh.Trimesh([[0, -half, -half], [0, half, -half], [0, half, half],
                             [0, -half, half]], [[0, 1, 2], [0, 2, 3]], process=False)
    turn = trimesh.transformations.rotation_matrix(math.radians(30.0), [0, 0, 1])
    scene = ml.Scene.from_mesh(plate, material=lambertian(rho), transform=turn)
    ladar = ml.Ladar(angles_deg=[0.0], bin_edges=np.linspace(-0.5, 0.5, 11))
    e = np.linspace(-0.6, 0.6, 25)                  # cells of 0.05, 20 rays across each
    ret = resolve(scene, ladar, [("cross_range", e), ("elevation", e)],
                  ray_spacing=0.05 / 20)
    img = ret.values[0]
    F = rho / math.pi
    hu = half * math.cos(math.radians(30.0))        # projected half-width along u (= −y)
    c = 0.5 * (e[1:] + e[:-1])
    inside_u = np.abs(c) + 0.025 < hu
    inside_v = np.abs(c) + 0.025 < half
    outside_u = np.abs(c) - 0.025 > hu
    outside_v = np.abs(c) - 0.025 > half
    cell = 0.05 * 0.05
    interior = img[np.ix_(inside_u, inside_v)]
    # stratified rays: a cell of 20 x 20 rays holds 400 ± ~20 of them (rows at its edges)
    np.testing.assert_allclose(interior, F * cell, rtol=0.08)
    assert np.all(img[outside_u, :] == 0) and np.all(img[:, outside_v] == 0)
    np.testing.assert_allclose(img.sum(), F * (2 * hu) * (2 * half), rtol=2e-3)


def test_rotating_cylinder_range_doppler():
    """A Lambertian cylinder (radius R, height H) turning about its axis z, seen from x: the
    side's point at angle φ has range −R cos φ and Doppler −2ωR sin φ/λ, so every return
    lies on that ellipse of the range-Doppler plane, and, with F cos θ dA = (ρ/π) H dy, its
    Doppler marginal is uniform: (ρ/π) H Δy per bin."""
    R, H, rho, om, lam = 0.5, 1.0, 0.6, 0.2, 1e-6
    cyl = trimesh.creation.cylinder(radius=R, height=H, sections=512)
    scene = ml.Scene.from_mesh(cyl, material=lambertian(rho))
    ladar = ml.Ladar(angles_deg=[0.0], bin_edges=np.linspace(-R, 0.0, 41))
    fmax = 2 * om * R / lam
    fe = np.linspace(-fmax, fmax, 21)
    ret = resolve(scene, ladar, [("range", ladar.bin_edges), ("doppler", fe)],
                  motion=Motion(omega=(0.0, 0.0, om), wavelength=lam), rays_per_bin=8)
    img = ret.values[0]
    rc, fc = ret.centers("range"), ret.centers("doppler")
    # distance of each cell from the ellipse (r/R)² + (f/fmax)² = 1, in cells
    dr, df = np.diff(ladar.bin_edges)[0], np.diff(fe)[0]
    rr, ff = np.meshgrid(rc, fc, indexing="ij")
    t = np.arctan2(-ff / fmax, -rr / R)            # φ of the nearest point, roughly
    near = (np.abs(rr + R * np.cos(t)) <= 1.5 * dr) | (np.abs(ff + fmax * np.sin(t))
                                                      <= 1.5 * df)
    assert img[~near].sum() <= 1e-12 * img.sum()
    dy = (fe[1] - fe[0]) * lam / (2 * om)
    np.testing.assert_allclose(ret.marginal("doppler")[0], rho / math.pi * H * dy, rtol=0.02)


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # faceted on purpose
def test_each_view_total_is_the_same_whatever_it_is_binned_by():
    scene = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=4),
                               material=ALUMINUM)
    ladar = ml.Ladar.covering(scene, n_bins=32, view_vectors=ml.meshes.fibonacci_sphere(5))
    wide = np.linspace(-1.2, 1.2, 17)
    # one engine throughout: "auto" draws a range-only run's first hits ("raster") and
    # traces the others', which differ at rays within round-off of an edge
    by = [resolve(scene, ladar, [("range", ladar.bin_edges)], backend="packets"),
          resolve(scene, ladar, [("cross_range", wide)], backend="packets"),
          resolve(scene, ladar, [("elevation", wide), ("range", ladar.bin_edges)],
                  backend="packets"),
          resolve(scene, ladar, [("doppler", np.linspace(-1e6, 1e6, 9))],
                  motion=Motion(omega=(0.1, 0.2, 0.3)), backend="packets")]
    for ret in by[1:]:
        np.testing.assert_allclose(ret.total(), by[0].total(), rtol=SUM_RTOL)
    np.testing.assert_allclose(by[2].marginal("range"), by[0].values, rtol=1e-12,
                               atol=1e-15)
    sino = ml.simulate(scene, ladar, model="mesh", normals="flat", backend="embreex")
    np.testing.assert_allclose(by[0].values, sino.values, rtol=1e-12, atol=1e-15)
    assert by[0].sinogram().shape == sino.shape


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # faceted on purpose
def test_resolved_runs_stream_on_threads_and_resume(tmp_path):
    scene = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=3),
                               material=ALUMINUM)
    ladar = ml.Ladar.covering(scene, n_bins=16, angles_deg=np.arange(0.0, 360.0, 20.0))
    axes = [("cross_range", np.linspace(-1.1, 1.1, 12)), ("range", ladar.bin_edges)]
    one = resolve(scene, ladar, axes, jobs=1)
    two = resolve(scene, ladar, axes, jobs=2)
    np.testing.assert_array_equal(one.values, two.values)
    run = tmp_path / "run"
    first = resolve(scene, ladar, axes, run_dir=run)
    again = resolve(scene, ladar, axes, run_dir=run)
    np.testing.assert_array_equal(first.values, one.values)
    np.testing.assert_array_equal(again.values, one.values)


def test_resolved_noise_realisations():
    scene = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=3),
                               material=lambertian(0.5))
    ladar = ml.Ladar.covering(scene, n_bins=16, angles_deg=[0.0])
    ret = resolve(scene, ladar, [("cross_range", np.linspace(-1, 1, 9))]).scaled(1e3)
    from meshladar.noise import Noise

    with pytest.raises(ml.errors.ParameterError, match="dwell"):
        ret.realise(Noise(background_rate=1e6), 2, seed=1)
    draws = ret.realise(Noise(speckle_cells=2.0), 4000, seed=1)
    assert draws.shape == (4000,) + ret.values.shape
    # the mean of the draws converges to the image (Poisson + speckle, 4000 draws)
    sd = np.sqrt(ret.values + ret.values ** 2 / 2.0) / math.sqrt(4000)
    live = ret.values > 0
    assert np.all(np.abs(draws.mean(0) - ret.values)[live] < 5 * sd[live])


@pytest.mark.parametrize("axes, motion, match", [
    ([("speed", [0.0, 1.0])], None, "axis name must be one of"),
    ([("doppler", [0.0, 1.0])], None, "needs motion"),
    ([("range", [0.0, 1.0]), ("range", [0.0, 1.0])], None, "different coordinates"),
    ([("range", [1.0, 0.0])], None, "strictly increasing"),
    ([], None, "one to three"),
    ([("range", [0, 1]), ("doppler", [0, 1]), ("elevation", [0, 1]),
      ("cross_range", [0, 1])], Motion(), "one to three"),
    ([("range", [0.0, 1.0])], "spin", "motion must be"),
])
def test_resolve_checks_its_axes(axes, motion, match):
    scene = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=1),
                               material=lambertian(0.5))
    ladar = ml.Ladar.covering(scene, n_bins=8, angles_deg=[0.0])
    with pytest.raises(ml.errors.ParameterError, match=match):
        resolve(scene, ladar, axes, motion=motion)


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # faceted on purpose
def test_returns_figures(tmp_path):
    pytest.importorskip("matplotlib")
    from meshladar.viz import resolved as figures

    scene = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=3),
                               material=ALUMINUM)
    ladar = ml.Ladar.covering(scene, n_bins=16, angles_deg=[0.0, 90.0])
    rd = resolve(scene, ladar, [("range", ladar.bin_edges),
                                ("doppler", np.linspace(-3e5, 3e5, 17))],
                 motion=Motion(omega=(0.0, 0.0, 0.1)))
    one = resolve(scene, ladar, [("cross_range", np.linspace(-1.1, 1.1, 23))])
    for ret, log in ((rd, True), (one, False)):
        path = figures.draw(ret, tmp_path / "f.png", log=log)
        assert os.path.getsize(path) > 5_000
    with pytest.raises(ml.errors.ParameterError, match="views"):
        figures.draw(rd, tmp_path / "g.png", views=[5])


def test_resolved_returns_with_a_sensor():
    """A sensor at a standoff: the range marginal is simulate's with the same sensor; the
    link budget's photoelectrons carry over; a far sensor's range–Doppler image approaches
    the parallel-ray one (first order in size / standoff)."""
    scene = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=4),
                               material=lambertian(0.5))
    ladar = ml.Ladar.covering(scene, n_bins=24, angles_deg=[0.0, 60.0])
    motion = Motion(omega=(0.0, 0.0, 0.2), velocity=(0.5, 0.0, 0.0))
    fe = np.linspace(-1.5e6, 1.5e6, 25)
    axes = [("range", ladar.bin_edges), ("doppler", fe)]
    sensor = ml.sensor.Sensor(standoff=50.0, pulse_energy=1e-3, aperture_diameter=0.1,
                              beam=ml.sensor.FloodBeam(radius=2.0))
    ret = resolve(scene, ladar, axes, motion=motion, radiometry="power", sensor=sensor)
    sino = ml.simulate(scene, ladar, model="mesh", radiometry="power", sensor=sensor,
                       backend="embreex")
    np.testing.assert_allclose(ret.marginal("range"), sino.values, rtol=1e-9,
                               atol=1e-12 * sino.values.max())
    assert ret.info["units"] == "photoelectrons"
    with pytest.raises(ml.errors.ParameterError, match="radiometry='power'"):
        resolve(scene, ladar, axes, motion=motion, sensor=sensor)
    errors = []
    ref = resolve(scene, ladar, axes, motion=motion, radiometry="power").values
    for D in (200.0, 800.0):
        far = resolve(scene, ladar, axes, motion=motion, radiometry="power",
                      sensor=ml.sensor.Sensor(standoff=D)).values
        errors.append(np.linalg.norm(far - ref) / np.linalg.norm(ref))
    assert errors[1] < 0.5 * errors[0] and errors[1] < 0.02, errors


def test_doppler_bins_that_miss_every_return_say_so():
    """issue 29: Doppler or range bins missing every return gave an empty Returns without a
    word (simulate warns in the same case): the warning names each axis's bins."""
    scene = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=3),
                               material=lambertian(0.5))
    ladar = ml.Ladar(angles_deg=[30.0], bin_edges=np.linspace(-1.0, 0.0, 33))
    V, lam = np.array([3.0, -1.0, 2.0]), 1.55e-6
    f0 = 2 * float(V @ ladar.view_vectors[0]) / lam
    far = f0 + np.array([1e6, 2e6])                  # 1 MHz and more from every return
    with pytest.warns(ml.errors.MeshladarWarning,
                      match=r"^the returns are all zeros: \d+ rays hit the target but every "
                            r"return fell outside the cells: doppler bins \["):
        ret = resolve(scene, ladar, {"doppler": far}, motion=Motion(velocity=V, wavelength=lam))
    assert not np.any(ret.values)
