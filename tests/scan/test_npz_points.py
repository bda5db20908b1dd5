"""Point clouds in numpy's .npz archive (meshladar.scan.npz): exact round trips of a real
scan (records, waveform blocks, an info with inf and nan), the formats' table and each
writer refusing the others' extensions, foreign files refused by the reader, and the
command line writing and reading .npz points where laspy and h5py are missing."""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest

from meshladar import io as results
from meshladar.errors import ParameterError
from meshladar.scan import (GeigerMode, Platform, PointCloud, flash, read_npz, rotating, scan,
                            write_hdf5, write_las, write_npz)
from meshladar.scan.formats import points_format
from meshladar.scan.points import POINT_DTYPE

from _scan_scenes import plate, scene, sensor


def _equal_clouds(a, b):
    assert a.points.dtype == b.points.dtype == POINT_DTYPE
    for name in POINT_DTYPE.names:        # field by field, NaN where NaN (bits compared)
        np.testing.assert_array_equal(a.points[name], b.points[name], strict=True)
    assert (a.waveforms is None) == (b.waveforms is None)
    if a.waveforms is not None:
        assert len(a.waveforms) == len(b.waveforms) >= 1
        for x, y, s, t in zip(a.waveforms, b.waveforms, a.starts, b.starts):
            np.testing.assert_array_equal(x, y, strict=True)
            np.testing.assert_array_equal(s, t, strict=True)


def test_a_scan_with_waveforms_reads_back_exactly(tmp_path):
    """A rotating head's scan of a plate, waveforms kept in several blocks: every field of
    every return, every sample and start, and the info, bit for bit."""
    pattern = rotating(np.linspace(-5, 5, 4), rotation_hz=50, pulse_rate=2e4, duration=0.01)
    cloud = scan(scene(plate(30.0)), pattern, Platform.static((0, 0, 0)), sensor(),
                 keep_waveforms=True, chunk_pulses=64)
    assert len(cloud) > 0 and len(cloud.waveforms) >= 3
    write_npz(tmp_path / "p.npz", cloud)
    back = read_npz(tmp_path / "p.npz")
    _equal_clouds(cloud, back)
    assert back.info == cloud.info
    assert back.waveform(70)[1] == cloud.waveform(70)[1]


def test_an_infinite_dead_time_and_nans_in_the_info_read_back(tmp_path):
    geiger = sensor(pulse_energy=1e-12, geiger=GeigerMode(shots=10))
    cloud = scan(scene(plate(50.0)), flash(2, 2, ifov_deg=0.1), Platform.static((0, 0, 0)),
                 geiger)
    cloud = PointCloud(cloud.points, dict(cloud.info, extra=[-math.inf, math.nan]))
    path = tmp_path / "g.npz"
    write_npz(path, cloud)
    arrays, meta = results.load_result(path)                 # the archive as numpy sees it
    assert meta["kind"] == "points" and meta["units"]["range"] == "m"
    assert meta["info"]["sensor"]["geiger"]["dead_time_s"] == "inf"
    back = read_npz(path)
    assert back.info["sensor"]["geiger"]["dead_time_s"] == math.inf
    assert back.info["extra"][0] == -math.inf and math.isnan(back.info["extra"][1])
    _equal_clouds(cloud, back)


def test_the_formats_table_and_each_writer_refusing_the_others_extensions(tmp_path):
    cloud = PointCloud(np.zeros(2, POINT_DTYPE))
    assert points_format("a.NPZ") == points_format("b.npz") == "NPZ"
    for write, name, named in ((write_npz, "x.las", "a LAS file; write_las"),
                               (write_npz, "x.h5", "an HDF5 file; write_hdf5"),
                               (write_las, "x.npz", "an NPZ file; write_npz"),
                               (write_hdf5, "x.npz", "an NPZ file; write_npz")):
        with pytest.raises(ParameterError, match=rf"path: .*{name}' names {named} writes "
                                                 "that format"):
            write(tmp_path / name, cloud)
    with pytest.raises(ParameterError, match="cloud must be a PointCloud; got ndarray"):
        write_npz(tmp_path / "x.npz", cloud.points)
    assert not any(tmp_path.iterdir())


def test_foreign_files_are_refused_by_the_reader(tmp_path):
    sino = results.save_result(tmp_path / "s.npz", {"values": np.ones((2, 3))},
                               {"kind": "sinogram"})
    assert sino is None
    with pytest.raises(ParameterError, match=r"is not a meshladar point cloud \(its kind: "
                                             r"'sinogram'\)"):
        read_npz(tmp_path / "s.npz")
    (tmp_path / "m.stl").write_bytes(b"solid x\nendsolid x\n")
    with pytest.raises(ParameterError, match=r"path: .*m\.stl"):
        read_npz(tmp_path / "m.stl")
    with pytest.raises(ParameterError, match="no such file"):
        read_npz(tmp_path / "none.npz")
    results.save_result(tmp_path / "o.npz", {"points": np.zeros(3)}, {"kind": "points"})
    with pytest.raises(ParameterError, match="its points are not meshladar's records"):
        read_npz(tmp_path / "o.npz")


def test_the_command_line_scans_to_npz_without_laspy_or_h5py(tmp_path, capsys, monkeypatch):
    """A plain install: -o points.npz scans (LAS and HDF5 are refused at once, naming the
    extra), and ``view --points`` reads the file back (its reader)."""
    from meshladar.cli import commands, main

    for module in ("laspy", "h5py"):
        monkeypatch.setitem(sys.modules, module, None)             # import fails
    ball = tmp_path / "ball.stl"
    trimesh = pytest.importorskip("trimesh")
    trimesh.creation.icosphere(3, radius=2.0).export(ball)           # the scanner inside
    argv = ["scan", str(ball), "--pattern", "rotating elevations_deg=-15:15:4 rotation_hz=50 "
            "pulse_rate=2e4 duration=0.005", "--platform", "static position=0,0,0",
            "--quiet", "-o"]
    assert main(argv + [str(tmp_path / "p.las")]) == 2
    assert "needs laspy, which is not installed" in capsys.readouterr().err
    assert main(argv + [str(tmp_path / "p.npz")]) == 0
    cloud = commands._read_points(str(tmp_path / "p.npz"))
    assert len(cloud) > 0
    np.testing.assert_allclose(np.linalg.norm(cloud.xyz, axis=1), 2.0, atol=0.02)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ball.stl", "p.npz"]


def test_empty_blocks_numpy_info_and_damaged_archives(tmp_path):
    """A block of no pulse is not stored (its key was the next block's, which replaced
    it); numpy numbers and arrays in the info are written as JSON's; an archive whose
    blocks lack their starts, whose starts are of another length, whose records are not
    one row a return, or which holds a member of another name is refused as damaged."""
    blocks = (np.zeros((2, 5)), np.zeros((0, 7)), np.ones((1, 9)))
    starts = (np.zeros(2), np.zeros(0), np.ones(1))
    info = {"gain": np.float32(1.5), "n": np.int64(3), "axis": np.arange(3.0), "t": (1, 2)}
    write_npz(tmp_path / "e.npz", PointCloud(np.zeros(0, POINT_DTYPE), info, blocks, starts))
    back = read_npz(tmp_path / "e.npz")
    assert [w.shape for w in back.waveforms] == [(2, 5), (1, 9)]
    assert back.waveform(2)[1] == 1.0                  # pulse 2: the third block's first
    assert back.info == {"gain": 1.5, "n": 3, "axis": [0.0, 1.0, 2.0], "t": [1, 2]}
    with pytest.raises(ParameterError, match="cloud.info must hold what JSON can"):
        write_npz(tmp_path / "o.npz", PointCloud(np.zeros(0, POINT_DTYPE), {"x": object()}))
    arrays, meta = results.load_result(tmp_path / "e.npz")
    for name, change in (("no starts", lambda a: a.pop("starts_000000000002")),
                         ("short starts", lambda a: a.update(starts_000000000002=np.ones(2))),
                         ("2-D points", lambda a: a.update(points=np.zeros((2, 2),
                                                                           POINT_DTYPE))),
                         ("stray member", lambda a: a.update(block_10=np.ones((1, 3))))):
        damaged = {k: v for k, v in arrays.items()}
        change(damaged)
        results.save_result(tmp_path / "d.npz", damaged, meta)
        with pytest.raises(ParameterError, match=r"is damaged|not meshladar's records"):
            read_npz(tmp_path / "d.npz")
