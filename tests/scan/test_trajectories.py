"""Trajectories (waypoints and CSV files): refused where they do not cover the pattern's
pulses, read in GPS time with ``time_offset``, and their files' faults named by line."""

from __future__ import annotations

import json

import numpy as np
import pytest

from meshladar.errors import ParameterError
from meshladar.scan import Platform, ScanPattern, oscillating, read_las, scan, write_las

from _scan_scenes import plate, scene, sensor

GPS = "time,x,y,z,roll,pitch,yaw\n345000,0,0,300,0,90,0\n345010,600,0,300,0,90,0\n"


def _nadir(duration=1.0):
    return oscillating(5.0, scan_hz=5, pulse_rate=20, duration=duration)


def _ground():
    """A plate in z = 0 facing up (the test plate turned), 2 km across."""
    mesh = plate(0.0, half=1000.0)
    mesh.apply_transform([[0, 0, 1, 0], [0, 1, 0, 0], [-1, 0, 0, 0], [0, 0, 0, 1]])
    return scene(mesh)


@pytest.mark.parametrize("rows", [GPS, GPS + "345020,1200,0,300,0,90,0\n"])
def test_a_gps_time_trajectory_is_refused_naming_both_time_spans(tmp_path, rows):
    """Two rows at GPS time 345000 s were a constant velocity extrapolated to x = −2e7 m;
    three held the first pose: both are refused before any ray is cast, the message
    naming the pulses' span (0 to 0.95 s) and the trajectory's."""
    (tmp_path / "t.csv").write_text(rows)
    platform = Platform.from_csv(tmp_path / "t.csv")
    last = "345010" if rows == GPS else "345020"
    with pytest.raises(ParameterError, match=rf"from 0 s to 0\.95 s, .* from 345000 s to "
                                             rf"{last} s.*time_offset"):
        scan(_ground(), _nadir(), platform, sensor())
    waypoints = Platform.waypoints([0.5, 1.0, 2.0], np.zeros((3, 3)), np.zeros((3, 3)))
    with pytest.raises(ParameterError, match=r"from 0 s to 1 s, .* from 0\.5 s to 2 s"):
        waypoints.check_covers([0.0, 1.0])
    waypoints.check_covers([0.5, 2.0])                      # its ends are covered


def test_time_offset_reads_a_gps_time_trajectory_from_its_start(tmp_path):
    """time_offset=345000: the file's 345000 s is the pattern's 0; the platform flies 60 m/s
    along x at 300 m, nadir, so each point lies at x = 60 t under it (to 1 mm)."""
    (tmp_path / "t.csv").write_text(GPS)
    platform = Platform.from_csv(tmp_path / "t.csv", time_offset=345000.0)
    np.testing.assert_array_equal(platform.times, [0.0, 10.0])
    cloud = scan(_ground(), _nadir(), platform, sensor())
    assert len(cloud) == 20
    np.testing.assert_allclose(cloud.points["x"], 60.0 * cloud.points["emission_time"],
                               atol=1e-3)
    np.testing.assert_allclose(cloud.points["z"], 0.0, atol=1e-3)
    assert cloud.info["platform"]["time_origin_s"] == 345000.0


def test_a_las_file_keeps_the_trajectorys_gps_time(tmp_path):
    """A scan from a trajectory in GPS time writes LAS GPS times of 345000 s plus each
    pulse's emission time (the pattern's clock, kept exactly in its own field); one from
    a static platform writes the emission times; a file read and written again keeps its
    GPS times (to 1 ns)."""
    laspy = pytest.importorskip("laspy")
    (tmp_path / "t.csv").write_text(GPS)
    platform = Platform.from_csv(tmp_path / "t.csv", time_offset=345000.0)
    at_rest = Platform.static((0, 0, 300), attitude_deg=(0, 90, 0))    # looking down
    for where, origin in ((platform, 345000.0), (at_rest, 0.0)):
        cloud = scan(_ground(), _nadir(), where, sensor())
        assert len(cloud) == len(_nadir())                   # one return a pulse
        write_las(tmp_path / "p.las", cloud)
        las = laspy.read(tmp_path / "p.las")
        np.testing.assert_array_equal(np.asarray(las.gps_time),
                                      origin + cloud.points["emission_time"])
        back = read_las(tmp_path / "p.las")
        np.testing.assert_array_equal(back.points["emission_time"],
                                      cloud.points["emission_time"])
        write_las(tmp_path / "q.las", back)                        # read, written again
        np.testing.assert_allclose(np.asarray(laspy.read(tmp_path / "q.las").gps_time),
                                   np.asarray(las.gps_time), rtol=0, atol=1e-9)


def test_a_trajectory_of_one_row_is_refused(tmp_path):
    """One pose covers no span of time: the file is refused, naming it and pointing to a
    platform at rest (the pulses of a forgotten GPS offset were scanned from it)."""
    (tmp_path / "one.csv").write_text("time,x,y,z,roll,pitch,yaw\n345000,0,0,300,0,90,0\n")
    with pytest.raises(ParameterError, match=r"one\.csv: a trajectory needs 2 or more rows .*"
                                             r"got 1 .*Platform\.static"):
        Platform.from_csv(tmp_path / "one.csv")


@pytest.mark.parametrize("kw, match", [
    (dict(position=(0, 0)), r"position must have shape \(3,\); got \(2,\)"),
    (dict(position=(0, 0, 1), attitude_deg=(0, 90)), r"attitude_deg must have shape \(3,\)")])
def test_a_static_platform_names_its_own_arguments(kw, match):
    with pytest.raises(ParameterError, match=match):
        Platform.static(**kw)


def test_static_and_constant_velocity_platforms_cover_every_time():
    """A pattern of 3 s from a static platform and a moving one (its waypoints at 0 and
    1 s): no refusal, the moving one extrapolated (x = 10 t); a 2-waypoint trajectory of
    the same poses does not extrapolate: refused."""
    pattern = ScanPattern(np.array([0.0, 3.0]), [[0.0, 0.0, -1.0]] * 2)
    still = scan(_ground(), pattern, Platform.static((0, 0, 50)), sensor())
    np.testing.assert_allclose(still.points["x"], 0.0, atol=1e-9)
    moving = scan(_ground(), pattern, Platform.moving((0, 0, 50), (10, 0, 0)), sensor())
    np.testing.assert_allclose(moving.points["x"], [0.0, 30.0], atol=1e-9)
    assert moving.info["platform"]["extrapolate"] is True
    two = Platform.waypoints([0.0, 1.0], [[0, 0, 50], [10, 0, 50]], np.zeros((2, 3)))
    assert two.extrapolate is False
    with pytest.raises(ParameterError, match="from 0 s to 3 s, outside .* 0 s to 1 s"):
        scan(_ground(), pattern, two, sensor())


@pytest.mark.parametrize("kw, match", [
    (dict(extrapolate="yes"), "extrapolate must be True or False"),
    (dict(extrapolate=True, times=[0, 1, 2]), "2 waypoints interpolated linearly; got 3")])
def test_extrapolate_is_only_a_constant_velocity(kw, match):
    times = kw.pop("times", [0.0, 1.0])
    with pytest.raises(ParameterError, match=match):
        Platform(times, np.zeros((len(times), 3)), np.zeros((len(times), 3)), **kw)


def test_a_trajectory_file_with_a_byte_order_mark_reads(tmp_path):
    """Excel's UTF-8 CSV starts with a byte-order mark: the header still matches."""
    path = tmp_path / "bom.csv"
    path.write_bytes("\ufefftime,x,y,z,roll,pitch,yaw\n0,0,0,300,0,90,0\n1,4,0,300,0,90,0\n"
                     .encode("utf-8"))
    platform = Platform.from_csv(path)
    np.testing.assert_array_equal(platform.times, [0.0, 1.0])
    np.testing.assert_allclose(platform.sensor_poses([0.5])[0], [[2.0, 0.0, 300.0]])


@pytest.mark.parametrize("row, match", [
    ("1,1,0,300,0,90", r"line 3: a row holds 7 values \(time,x,y,z,roll,pitch,yaw\); got 6"),
    ("1,1,0,300,0,90,0,5", "line 3: a row holds 7 values .*got 8"),
    ("1,1,0,abc,0,90,0", "line 3: every value must be a number"),
    ("1,nan,0,300,0,90,0", r"t\.csv, line 3: x is nan; every value must be a finite number"),
    ("1,1,0,300,0,inf,0", r"line 3: pitch is inf; every value must be a finite number"),
    ("0,1,0,300,0,90,0", r"t\.csv, line 3: time 0\.0 does not follow line 2's 0\.0; the "
                         "times must increase"),
    ("-0.00005,1,0,300,0,90,0", r"line 3: time -5e-05 does not follow line 2's 0\.0")])
def test_a_bad_row_is_named_by_its_line(tmp_path, row, match):
    path = tmp_path / "t.csv"
    path.write_text(f"time,x,y,z,roll,pitch,yaw\n0,0,0,300,0,90,0\n{row}\n")
    with pytest.raises(ParameterError, match=match):
        Platform.from_csv(path)


def test_the_platform_description_is_json():
    described = Platform.moving((0, 0, 1), (1, 0, 0)).describe()
    assert json.loads(json.dumps(described))["extrapolate"] is True
