"""``meshladar scan`` end to end: a room's STL scanned by a moving spinning head, its LAS
and HDF5 files read back, its points on the room's walls (closed-form distances)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from meshladar.cli import main
from meshladar.scan import read_hdf5, read_las

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
