"""``meshladar scan`` end to end: a room's STL scanned by a moving spinning head, its LAS
and HDF5 files read back, its points on the room's walls (closed-form distances)."""

from __future__ import annotations

import re

import numpy as np
import pytest
import trimesh

from meshladar.cli import main
from meshladar.scan import read_hdf5, read_las, read_npz

HALF = np.array([20.0, 20.0, 6.0])


def test_a_moving_spinning_head_writes_a_las_of_points_on_the_walls(tmp_path, capsys):
    trimesh.creation.box(2 * HALF).export(tmp_path / "room.stl")
    argv = ["scan", str(tmp_path / "room.stl"), "--material", "aluminum",
            "--pattern", "rotating elevations_deg=-15:15:16 rotation_hz=10 pulse_rate=1e5 "
                         "duration=0.05",
            "--platform", "moving position=-5,0,0 velocity=10,0,0",
            "-o", str(tmp_path / "p.las"), "--waveforms", str(tmp_path / "w.h5")]
    assert main(argv) == 0
    out = capsys.readouterr()
    assert "5000 returns from 5000 pulses" in out.out
    cloud = read_las(tmp_path / "p.las")
    assert len(cloud) == 5000
    # every point on a wall: its largest |coordinate| / half size is 1 (LAS scale 1e-4)
    ratio = np.max(np.abs(cloud.xyz) / HALF, axis=1)
    np.testing.assert_allclose(ratio, 1.0, atol=0.01 / 6.0)
    waves = read_hdf5(tmp_path / "w.h5")
    assert sum(len(block) for block in waves.waveforms) == 5000
    np.testing.assert_array_equal(waves.points["pulse_id"], cloud.points["pulse_id"])


def test_a_trajectory_file_drives_the_platform(tmp_path):
    trimesh.creation.box(2 * HALF).export(tmp_path / "room.stl")
    (tmp_path / "t.csv").write_text("time,x,y,z,roll,pitch,yaw\n0,0,0,0,0,90,0\n1,10,0,0,0,90,0\n")
    argv = ["scan", str(tmp_path / "room.stl"), "--quiet",
            "--pattern", "oscillating half_angle_deg=10 scan_hz=2 pulse_rate=100 duration=1",
            "--platform", str(tmp_path / "t.csv"), "-o", str(tmp_path / "p.h5")]
    assert main(argv) == 0
    cloud = read_hdf5(tmp_path / "p.h5")
    np.testing.assert_allclose(cloud.points["z"], -6.0, atol=1e-3)       # the floor
    # nadir pitch: the mirror sweeps across track (world y), x follows the platform
    np.testing.assert_allclose(cloud.points["x"], 10 * cloud.points["emission_time"], atol=1e-3)
    np.testing.assert_allclose(cloud.points["y"],
                               6 * np.tan(np.radians(cloud.points["scan_angle"])), atol=1e-3)


def test_view_draws_a_scans_points_over_the_room(tmp_path):
    """``meshladar view room.stl --points p.las --screenshot``: the PNG holds coloured
    points (the test renders off screen; skipped where rendering cannot start)."""
    import subprocess
    import sys

    from _rendering import _SMOKE

    if subprocess.run([sys.executable, "-c", _SMOKE], capture_output=True).returncode:
        pytest.skip("off-screen rendering does not work here")
    from matplotlib.image import imread

    trimesh.creation.box(2 * HALF).export(tmp_path / "room.stl")
    assert main(["scan", str(tmp_path / "room.stl"), "--quiet", "--pattern",
                 "rotating elevations_deg=-15:15:8 rotation_hz=10 pulse_rate=4e4 duration=0.1",
                 "--platform", "static position=0,0,0", "-o", str(tmp_path / "p.las")]) == 0
    assert main(["view", str(tmp_path / "room.stl"), "--points", str(tmp_path / "p.las"),
                 "--color-by", "range", "--screenshot", str(tmp_path / "v.png"),
                 "--size", "400x300", "--quiet"]) == 0
    img = imread(tmp_path / "v.png")[..., :3]
    assert img.shape[:2] == (300, 400)
    spread = img.max(axis=2) - img.min(axis=2)          # coloured, not grey or white
    assert (spread > 0.15).sum() > 300


_OSC = "oscillating half_angle_deg=10 scan_hz=20 pulse_rate=1000 duration=0.1"


def _room(tmp_path):
    trimesh.creation.box(2 * HALF).export(tmp_path / "room.stl")
    return str(tmp_path / "room.stl")


def test_a_waypoints_platform_takes_flat_lists_a_word_and_the_mount(tmp_path):
    """positions and attitudes_deg flat (three values a waypoint), interpolation=spline,
    mount_offset and boresight_deg: 60 m/s along x, nadir; the sensor 1 m ahead on the body
    (pitch 90°: body z is world +x, so mount_offset=0,0,1 puts it 1 m ahead); every point
    on the floor at x = 60 t + 1."""
    argv = ["scan", _room(tmp_path), "--quiet", "--pattern", _OSC, "--platform",
            "waypoints times=0,0.05,0.1 positions=0,0,0,3,0,0,6,0,0 "
            "attitudes_deg=0,90,0,0,90,0,0,90,0 interpolation=spline mount_offset=0,0,1 "
            "boresight_deg=0,0,0", "-o", str(tmp_path / "p.h5")]
    assert main(argv) == 0
    cloud = read_hdf5(tmp_path / "p.h5")
    platform = cloud.info["platform"]
    assert platform["positions"] == [[0, 0, 0], [3, 0, 0], [6, 0, 0]]
    assert platform["interpolation"] == "spline" and platform["mount_offset"] == [0, 0, 1]
    assert len(cloud) == 100
    np.testing.assert_allclose(cloud.points["z"], -6.0, atol=1e-3)
    np.testing.assert_allclose(cloud.points["x"], 60 * cloud.points["emission_time"] + 1.0,
                               atol=1e-3)


@pytest.mark.parametrize("platform, message", [
    ("waypoints times=0,0.1 positions=0,0,0,3,0,0,1 attitudes_deg=0,90,0,0,90,0",
     "--platform: positions takes three values a waypoint.*a multiple of 3; got 7"),
    ("static position=0,0,0 mount_offset=1,2", "--platform: mount_offset must have shape"),
    ("static position=0,0,0 position=1,0,0", "--platform: position is given twice"),
    ("waypoints times=0,0.1 positions=0,0,0,1,0,0 attitudes_deg=0,0,0,0,0,0 "
     "interpolation=cubic", "--platform: interpolation must be one of"),
    ("waypoints times=0,0.05 positions=0,0,0,1,0,0 attitudes_deg=0,0,0,0,0,0",
     r"--platform: the pattern's pulses leave from 0 s to 0\.099 s, outside .* 0 s to "
     r"0\.05 s")])
def test_a_bad_platform_spec_is_refused_by_flag_before_scanning(tmp_path, capsys,
                                                                monkeypatch, platform,
                                                                message):
    import meshladar.cli.scan as cli_scan
    monkeypatch.setattr(cli_scan.scanning, "scan", lambda *a, **k: pytest.fail("scanned"))
    argv = ["scan", _room(tmp_path), "--quiet", "--pattern", _OSC, "--platform", platform,
            "-o", str(tmp_path / "p.las")]
    assert main(argv) == 2
    assert re.search(message, capsys.readouterr().err)


def test_a_gps_time_trajectory_file_takes_its_time_offset(tmp_path, capsys):
    """'FILE.csv time_offset=345000': the file's 345000 s is the pattern's 0 (60 m/s along
    x); without it the file is refused, naming --platform and both time spans."""
    (tmp_path / "t.csv").write_text("time,x,y,z,roll,pitch,yaw\n345000,0,0,0,0,90,0\n"
                                    "345010,600,0,0,0,90,0\n")
    base = ["scan", _room(tmp_path), "--quiet", "--pattern", _OSC, "-o",
            str(tmp_path / "p.h5"), "--platform"]
    assert main(base + [str(tmp_path / "t.csv")]) == 2
    assert re.search(r"--platform: the pattern's pulses leave from 0 s to 0\.099 s, outside "
                     r"the platform's waypoints, from 345000 s to 345010 s",
                     capsys.readouterr().err)
    assert main(base + [f"{tmp_path / 't.csv'} time_offset=345000 boresight_deg=0,0,0"]) == 0
    cloud = read_hdf5(tmp_path / "p.h5")
    np.testing.assert_allclose(cloud.points["x"], 60 * cloud.points["emission_time"],
                               atol=1e-3)
    # a file name with a space: the name runs to its .csv, its keys follow
    (tmp_path / "my flight.csv").write_text((tmp_path / "t.csv").read_text())
    assert main(base + [f"{tmp_path / 'my flight.csv'} time_offset=345000"]) == 0
    np.testing.assert_array_equal(read_hdf5(tmp_path / "p.h5").points["x"], cloud.points["x"])
    assert main(base + [str(tmp_path / "my flight.csv")]) == 2       # no offset: refused
    assert "outside the platform's waypoints" in capsys.readouterr().err
    # a folder whose name holds ".csv " itself: a whole existing name is taken as it is
    (tmp_path / "run.csv files").mkdir()
    (tmp_path / "run.csv files" / "t.csv").write_text("time,x,y,z,roll,pitch,yaw\n"
                                                       "0,0,0,0,0,90,0\n1,60,0,0,0,90,0\n")
    assert main(base + [str(tmp_path / "run.csv files" / "t.csv")]) == 0


@pytest.mark.parametrize("extra, message", [
    (["--max-returns", "16"], r"--max-returns must be an integer in \[1, 15\]; got 16"),
    (["--geiger-shots", "10", "--discrete"],
     "--discrete makes no waveform records: --geiger-shots does not apply"),
    (["--discrete", "--waveforms", "w.h5"], "--discrete .* --waveforms does not apply"),
    (["--noise", "--geiger-shots", "10"],                          # (a user's trial)
     "--noise does not apply with --geiger-shots: .* always drawn"),
    (["--pattern", "flash rows=2 columns=2 ifov_deg=0.1 frame_rate=inf frames=2"],
     r"--pattern: frame_rate must be finite and in \(0, 1e\+12\]; got inf"),
    (["--platform", "static position=0,0,0 attitude_deg=0,1e308,0"],
     r"--platform: attitude_deg must be angles within ±1e\+09 degrees .*got 1e\+308"),
    (["--tol", "1e-9"], "--tol 1e-09 needs more than 4096 sub-rays"),
    (["--pattern", "rotating elevations_deg=0 rotation_hz=10 pulse_rate=1e3 duration=0.02 "
                   "duration=0.01"], "--pattern: duration is given twice"),
    (["--pattern", "raster azimuth_deg=0 elevation_deg=0 pulse_rate=1 bidirectional=maybe"],
     "--pattern: bidirectional='maybe' must be true or false"),
    (["-o", "./same.h5", "--waveforms", "same.h5"], "are the same file"),
    (["-o", "real.h5", "--waveforms", "link.h5"], "are the same file"),
])
def test_sensor_and_output_flags_are_refused_by_their_names(tmp_path, capsys, monkeypatch,
                                                            extra, message):
    """The API's names come back as the flags (max_returns, echoes='waveform'); a key given
    twice is refused; -o and --waveforms are compared as real paths (link.h5 links to
    real.h5, which does not exist yet); all before scanning."""
    import meshladar.cli.scan as cli_scan
    monkeypatch.setattr(cli_scan.scanning, "scan", lambda *a, **k: pytest.fail("scanned"))
    monkeypatch.chdir(tmp_path)
    (tmp_path / "link.h5").symlink_to(tmp_path / "real.h5")
    argv = ["scan", _room(tmp_path), "--quiet", "--pattern", _OSC, "--platform",
            "static position=0,0,0", "-o", "p.las"]
    assert main(argv + extra) == 2
    assert re.search(message, capsys.readouterr().err)


def test_missing_output_folders_are_made_as_for_every_command(tmp_path, capsys):
    """-o and --waveforms into folders that do not exist yet: made (the command-line
    guide's rule; scan refused them), after every check: a file standing where a folder
    should be is refused naming the flag, and nothing is made."""
    trimesh.creation.box(2 * HALF).export(tmp_path / "room.stl")
    argv = ["scan", str(tmp_path / "room.stl"), "--quiet",
            "--pattern", "raster azimuth_deg=-1:1:3 elevation_deg=-1:1:3 pulse_rate=1e5",
            "--platform", "static position=0,0,0"]
    assert main(argv + ["-o", str(tmp_path / "a" / "b" / "p.las"),
                        "--waveforms", str(tmp_path / "c" / "w.h5")]) == 0
    assert len(read_las(tmp_path / "a" / "b" / "p.las")) == 9
    assert len(read_hdf5(tmp_path / "c" / "w.h5").points) == 9
    assert main(argv + ["-o", str(tmp_path / "room.stl" / "p.las")]) == 2
    assert capsys.readouterr().err.startswith("meshladar: error: -o: ")
    assert main(argv + ["-o", str(tmp_path / "d" / "p.las"), "--sample-rate", "1e6"]) == 2
    assert not (tmp_path / "d").exists()


def test_a_run_folder_resumes_a_scan_from_the_command_line(tmp_path, capsys, monkeypatch):
    """A user's trial: scan had no --run-dir (resuming was the API's alone). The same
    command run again over a finished folder computes no chunk and writes the same
    points; --run-dir with --waveforms is refused before any work."""
    import meshladar.scan.run as scan_run

    argv = ["scan", _room(tmp_path), "--quiet", "--pattern", _OSC, "--platform",
            "static position=0,0,0", "--noise", "--background-rate", "1e7",
            "--run-dir", str(tmp_path / "run")]
    assert main(argv + ["-o", str(tmp_path / "a.npz")]) == 0
    assert (tmp_path / "run" / "manifest.json").exists()
    monkeypatch.setattr(scan_run, "_chunk", lambda *a: pytest.fail("a chunk recomputed"))
    assert main(argv + ["-o", str(tmp_path / "b.npz")]) == 0
    a, b = np.load(tmp_path / "a.npz"), np.load(tmp_path / "b.npz")
    assert np.array_equal(a["points"], b["points"]) and len(a["points"]) > 0
    assert main(argv + ["-o", str(tmp_path / "c.npz"), "--waveforms", "w.h5"]) == 2
    assert "give one of them" in capsys.readouterr().err


def test_the_geiger_arrays_and_detectors_settings_are_flags(tmp_path, capsys):
    """A user's trial: the dead time, the detection efficiency and the false-alarm
    probability were the API's alone. They are flags, recorded in the file's parameters;
    the Geiger array's need --geiger-shots, and a false alarm out of (0, 0.5] is refused
    by its flag, each before any work."""
    base = ["scan", _room(tmp_path), "--quiet", "--pattern", "flash rows=2 columns=2 "
            "ifov_deg=0.1", "--platform", "static position=0,0,0", "--pulse-energy", "1e-12"]
    assert main(base + ["-o", str(tmp_path / "g.npz"), "--geiger-shots", "10", "--dead-time",
                        "1e-8", "--detection-efficiency", "0.5", "--false-alarm",
                        "1e-4"]) == 0
    sensor = read_npz(tmp_path / "g.npz").info["sensor"]
    assert sensor["geiger"] == {"shots": 10, "dead_time_s": 1e-8, "detection_efficiency": 0.5}
    assert sensor["detector"]["false_alarm"] == 1e-4
    for extra, message in ((["--dead-time", "1e-8"], "--dead-time sets a Geiger-mode "
                                                      "array's pixels: give --geiger-shots"),
                           (["--false-alarm", "0.7"], r"--false-alarm must be in \(0, 0\.5\]")):
        assert main(base + ["-o", str(tmp_path / "x.npz")] + extra) == 2
        assert re.search(message, capsys.readouterr().err)
        assert not (tmp_path / "x.npz").exists()
