"""Scan patterns and platforms against their definitions: angles, rates and poses written
out by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from meshladar.errors import ParameterError
from meshladar.scan import (Platform, ScanPattern, flash, oscillating, raster, risley,
                            rotating)


def _az_el(d):
    return np.degrees(np.arctan2(d[:, 1], d[:, 0])), np.degrees(np.arcsin(d[:, 2]))


def test_a_rotating_head_fires_its_channels_in_turn_as_it_turns():
    el = np.linspace(-15, 15, 32)
    pat = rotating(el, rotation_hz=10, pulse_rate=3.2e5, duration=0.1)
    assert len(pat) == 32_000
    az, elev = _az_el(pat.directions)
    k = np.arange(len(pat))
    np.testing.assert_allclose(elev, el[k % 32], atol=1e-12)
    np.testing.assert_array_equal(pat.channels, k % 32)
    expect = (360.0 * 10 * k / 3.2e5 + 180.0) % 360.0 - 180.0
    np.testing.assert_allclose(np.cos(np.radians(az - expect)), 1.0, atol=1e-12)


def test_a_raster_sweeps_rows_and_a_bidirectional_one_returns():
    pat = raster([-10, 0, 10], [5, -5], pulse_rate=100, bidirectional=True)
    az, el = _az_el(pat.directions)
    np.testing.assert_allclose(az, [-10, 0, 10, 10, 0, -10], atol=1e-12)
    np.testing.assert_allclose(el, [5, 5, 5, -5, -5, -5], atol=1e-12)
    np.testing.assert_allclose(pat.times, np.arange(6) / 100)


def test_an_oscillating_mirror_makes_a_triangle_wave():
    pat = oscillating(20.0, scan_hz=1.0, pulse_rate=8.0, duration=1.0)
    az, el = _az_el(pat.directions)
    np.testing.assert_allclose(az, [0, 10, 20, 10, 0, -10, -20, -10], atol=1e-9)
    np.testing.assert_allclose(el, 0.0, atol=1e-12)


def test_a_risley_pair_stays_within_the_sum_of_its_wedges_and_closes_its_rose():
    pat = risley(5.0, prism_hz=(100.0, -70.0), pulse_rate=1e5, duration=0.1)
    off = np.degrees(np.arccos(np.clip(pat.directions[:, 0], -1, 1)))
    assert off.max() <= 10.0 + 1e-9 and off.max() > 9.9
    # both wedges back at their start after 0.1 s (10 and −7 turns)
    np.testing.assert_allclose(pat.directions[0], pat.directions[-1], atol=2e-2)


def test_a_flash_array_looks_through_evenly_spaced_pixels_top_left_first():
    pat = flash(3, 4, ifov_deg=0.5, frames=2, frame_rate=10)
    p = math.tan(math.radians(0.5))
    d = pat.directions / pat.directions[:, :1]
    np.testing.assert_allclose(d[0], [1, 1.5 * p, 1.0 * p])          # row 0, column 0
    np.testing.assert_allclose(d[11], [1, -1.5 * p, -1.0 * p])       # row 2, column 3
    np.testing.assert_array_equal(pat.channels, np.tile(np.arange(12), 2))
    np.testing.assert_allclose(pat.times, np.repeat([0.0, 0.1], 12))
    assert pat.is_flash and pat.shape == (3, 4)


@pytest.mark.parametrize("make, name", [
    (lambda: ScanPattern([0.0, -1.0], [[1, 0, 0], [1, 0, 0]]), "times"),
    (lambda: ScanPattern([0.0], [[0, 0, 0]]), "directions"),
    (lambda: ScanPattern([0.0], [[1, 0, 0], [1, 0, 0]]), "directions"),
    (lambda: rotating([0.0], rotation_hz=0, pulse_rate=1, duration=1), "rotation_hz"),
    (lambda: rotating([0.0], rotation_hz=1, pulse_rate=1e12, duration=1e6), "pulses"),
    (lambda: oscillating(90.0, scan_hz=1, pulse_rate=1, duration=1), "half_angle_deg"),
    (lambda: risley(50.0, prism_hz=(1, 2), pulse_rate=1, duration=1), "deviation_deg"),
    (lambda: risley(5.0, prism_hz=(1, 0), pulse_rate=1, duration=1), "prism_hz"),
    (lambda: flash(0, 4, ifov_deg=1), "rows"),
    (lambda: raster([], [0.0], pulse_rate=1), "azimuth_deg"),
])
def test_bad_patterns_are_refused_by_name(make, name):
    with pytest.raises(ParameterError, match=name):
        make()


def test_a_static_platform_holds_its_pose_and_pitch_90_looks_straight_down():
    plat = Platform.static((1.0, 2.0, 30.0), (0.0, 90.0, 0.0))
    origin, rot = plat.sensor_poses([0.0, 5.0])
    np.testing.assert_allclose(origin, [[1, 2, 30]] * 2)
    np.testing.assert_allclose(rot[0] @ [1, 0, 0], [0, 0, -1], atol=1e-12)


def test_yaw_turns_the_boresight_left_and_the_mount_offset_rides_with_the_body():
    plat = Platform.static((0, 0, 0), (0.0, 0.0, 90.0), mount_offset=(1.0, 0.0, 0.5),
                           boresight_deg=(0.0, 0.0, -90.0))
    origin, rot = plat.sensor_poses([0.0])
    np.testing.assert_allclose(origin[0], [0, 1, 0.5], atol=1e-12)      # body x is world y
    np.testing.assert_allclose(rot[0] @ [1, 0, 0], [1, 0, 0], atol=1e-12)   # turned back


def test_waypoints_interpolate_positions_and_slerp_attitudes():
    plat = Platform.waypoints([0.0, 2.0, 4.0], [[0, 0, 0], [2, 0, 0], [2, 2, 0]],
                              [[0, 0, 0], [0, 0, 90], [0, 0, 90]])
    origin, rot = plat.sensor_poses([1.0, 3.0, 9.0])
    np.testing.assert_allclose(origin, [[1, 0, 0], [2, 1, 0], [2, 2, 0]], atol=1e-12)
    c = math.cos(math.radians(45))
    np.testing.assert_allclose(rot[0] @ [1, 0, 0], [c, c, 0], atol=1e-12)   # halfway: 45°
    spline = Platform.waypoints([0, 1, 2, 3], [[0, 0, 0], [1, 1, 0], [2, 4, 0], [3, 9, 0]],
                                np.zeros((4, 3)), interpolation="spline")
    assert spline.sensor_poses([1.0])[0][0] == pytest.approx([1, 1, 0])


def test_a_moving_platform_extrapolates_its_constant_velocity():
    origin, _ = Platform.moving((0, 0, 5), (3.0, -1.0, 0.0)).sensor_poses([-1.0, 2.5])
    np.testing.assert_allclose(origin, [[-3, 1, 5], [7.5, -2.5, 5]], atol=1e-12)


def test_a_trajectory_file_reads_as_its_waypoints(tmp_path):
    path = tmp_path / "traj.csv"
    path.write_text("time,x,y,z,roll,pitch,yaw\n0,0,0,100,0,90,0\n10,50,0,100,0,90,0\n")
    origin, rot = Platform.from_csv(path).sensor_poses([5.0])
    np.testing.assert_allclose(origin[0], [25, 0, 100])
    np.testing.assert_allclose(rot[0] @ [1, 0, 0], [0, 0, -1], atol=1e-12)
    bad = tmp_path / "bad.csv"
    bad.write_text("t,x,y,z\n0,0,0,0\n")
    with pytest.raises(ParameterError, match="header"):
        Platform.from_csv(bad)
    with pytest.raises(ParameterError, match="path"):
        Platform.from_csv(tmp_path / "missing.csv")
