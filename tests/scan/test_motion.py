"""Moving parts and platforms: motion blur and Doppler against closed forms."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import meshladar as ml
from meshladar.errors import ParameterError
from meshladar.motion import Motion
from meshladar.scan import Platform, ScanPattern, scan

from _scan_scenes import plate, scene, sensor

R0, V, LAMBDA = 100.0, 20.0, 1.064e-6


def _along_x(n, dt=1e-3):
    return ScanPattern(np.arange(n) * dt, np.tile([1.0, 0.0, 0.0], (n, 1)))


def test_a_part_closing_on_the_sensor_blurs_its_range_and_shifts_by_2v_over_lambda():
    """A plate coming at 20 m/s: pulse k at t_k ranges R0 − v t_k (the scene frozen at
    each emission: light-time moves it 13 µm), and every echo is shifted 2v/λ = 37.6 MHz
    (to 1e-6); a wall behind it, static, keeps its range and no shift."""
    wall = plate(R0 + 50.0, half=50.0)
    sc = scene(plate(R0, half=5.0), wall)
    pc = scan(sc, _along_x(20), Platform.static((0, 0, 0)), sensor(),
              motions={0: Motion(velocity=(-V, 0.0, 0.0))})
    pts = pc.points
    np.testing.assert_allclose(pts["range"], R0 - V * pts["emission_time"], atol=2e-3)
    np.testing.assert_allclose(pts["true_range"], R0 - V * pts["emission_time"], rtol=1e-12)
    np.testing.assert_allclose(pts["doppler"], 2 * V / LAMBDA, rtol=1e-6)
    assert np.all(pts["true_part"] == 0)
    behind = scan(sc, ScanPattern([0.0], [[1.0, 0.08, 0.0]]), Platform.static((0, 0, 0)),
                  sensor(), motions={0: Motion(velocity=(-V, 0.0, 0.0))})
    assert behind.points["true_part"][0] == 1 and behind.points["doppler"][0] == 0.0


def test_the_shift_is_at_the_sensors_wavelength_and_another_motions_is_warned_of():
    """A user's trial: a Motion's wavelength set to another than the sensor's was ignored
    without a word (the shift is the sensor's: 2v/λ at 1.55 µm) and recorded as the
    motion's. Now warned; a Motion left at its default is not (a review: every 1.55 µm
    user would be), and the scan records the sensor's either way."""
    sc = scene(plate(R0, half=5.0))
    sen = sensor(wavelength=1.55e-6)
    with pytest.warns(ml.errors.MeshladarWarning, match=r"motions\[0\] has wavelength "
                                                        r"9\.05e-07 m; .* 1\.55e-06 m"):
        pc = scan(sc, _along_x(3), Platform.static((0, 0, 0)), sen,
                  motions={0: Motion(velocity=(-V, 0.0, 0.0), wavelength=905e-9)})
    np.testing.assert_allclose(pc.points["doppler"], 2 * V / 1.55e-6, rtol=1e-6)
    assert pc.info["motions"]["0"]["wavelength_m"] == 1.55e-6
    quiet = scan(sc, _along_x(3), Platform.static((0, 0, 0)), sen,       # (no warning:
                 motions={0: Motion(velocity=(-V, 0.0, 0.0))})           # filterwarnings)
    assert quiet.info["motions"]["0"]["wavelength_m"] == 1.55e-6


def test_a_platform_closing_on_a_static_plate_sees_the_same_shift():
    pc = scan(scene(plate(R0)), _along_x(10), Platform.moving((0, 0, 0), (V, 0, 0)),
              sensor())
    np.testing.assert_allclose(pc.points["doppler"], 2 * V / LAMBDA, rtol=1e-6)
    np.testing.assert_allclose(pc.points["true_range"], R0 - V * pc.points["emission_time"],
                               rtol=1e-12)


def test_a_turntable_shifts_each_point_by_its_own_velocity_toward_the_sensor():
    """A cylinder turning about z at 50 rad/s, seen from 100 m along −x at heights across
    it: each echo's shift is 2 (Ω × p)·u / λ at its own true point p (u toward the
    sensor), to 1e-5 (the footprint's one ray), and grows linearly across the axis."""
    drum = trimesh.creation.cylinder(radius=1.0, height=2.0, sections=512)
    sc = ml.Scene.from_meshes([(drum, ml.brdf.Lambertian(0.5))])
    ys = np.linspace(-0.8, 0.8, 9)
    pat = ScanPattern(np.zeros(9), np.stack([np.full(9, R0), ys, np.zeros(9)], 1))
    omega = np.array([0.0, 0.0, 50.0])
    pc = scan(sc, pat, Platform.static((-R0, 0.0, 0.0)), sensor(),
              motions={0: Motion(omega=tuple(omega))})
    p = pc.true_xyz
    u = np.array([-R0, 0.0, 0.0]) - p
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    expect = 2 * np.einsum("ij,ij->i", np.cross(omega, p), u) / LAMBDA
    np.testing.assert_allclose(pc.points["doppler"], expect, rtol=1e-5)
    assert np.all(np.diff(pc.points["doppler"]) > 0)


@pytest.mark.parametrize("motions, name", [({5: Motion()}, "motions"),
                                           ({"nope": Motion()}, "motions"),
                                           ({0: (1, 0, 0)}, "motions"),
                                           ([Motion()], "motions")])
def test_bad_motions_are_refused_by_name(motions, name):
    with pytest.raises(ParameterError, match=name):
        scan(scene(plate(R0)), _along_x(1), Platform.static((0, 0, 0)), sensor(),
             motions=motions)


@pytest.mark.parametrize("interpolation", ["linear", "spline"])
def test_doppler_at_the_waypoints_first_and_last_times_is_the_paths_own(interpolation):
    """A platform flying along x toward a wall R0 ahead, by waypoints at 0, 0.05, 0.1 s:
    the shift is 2 v_x(t)/λ with v the path's derivative (linear: each leg's slope; spline:
    scipy's natural spline's derivative), at the first and last times too, where the pose
    is held beyond the path (a central difference there halved it), to 1e-6."""
    from scipy.interpolate import CubicSpline

    times = np.array([0.0, 0.05, 0.1])
    x = np.array([0.0, 0.5, 1.5])
    path = Platform.waypoints(times, np.c_[x, np.zeros(3), np.zeros(3)], np.zeros((3, 3)),
                              interpolation=interpolation)
    t = np.array([0.0, 0.02, 0.08, 0.1])
    pc = scan(scene(plate(R0, half=50.0)), ScanPattern(t, np.tile([1.0, 0.0, 0.0], (4, 1))),
              path, sensor())
    v = (np.array([10.0, 10.0, 20.0, 20.0]) if interpolation == "linear"
         else CubicSpline(times, x, bc_type="natural")(t, 1))
    assert len(pc.points) == 4
    np.testing.assert_allclose(pc.points["doppler"], 2 * v / LAMBDA, rtol=1e-6)
