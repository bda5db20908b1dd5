"""Long scans: threads give the same points as one thread, and a scan stopped midway and
run again from its run folder computes only the chunks it lacked and gives the same
points as a scan never stopped (synchronised on the chunks, not on time)."""

from __future__ import annotations

import numpy as np
import pytest

from meshladar.noise import Noise
from meshladar.scan import Platform, ScanBeam, rotating, scan
from meshladar.scan import files as scan_files
from meshladar.scan import run as scan_run

from _scan_scenes import plate, scene, sensor


def _setup():
    sc = scene(plate(30.0, half=40.0))
    pat = rotating(np.linspace(-10, 10, 8), rotation_hz=2, pulse_rate=4e4, duration=0.05)
    sen = sensor(noise=Noise(background_rate=2e7), beam=ScanBeam(1e-3, sub_rays=8),
                 samples=128)
    return sc, pat, Platform.static((0.0, 0.0, 0.0)), sen


def test_threads_give_the_points_of_one_thread():
    sc, pat, plat, sen = _setup()
    one = scan(sc, pat, plat, sen, jobs=1, chunk_pulses=300, seed=4)
    two = scan(sc, pat, plat, sen, jobs=2, chunk_pulses=300, seed=4)
    assert len(one) > 500
    assert one.points.tobytes() == two.points.tobytes()


def test_a_stopped_scan_resumes_from_its_run_folder_with_identical_points(tmp_path,
                                                                         monkeypatch):
    sc, pat, plat, sen = _setup()
    fresh = scan(sc, pat, plat, sen, chunk_pulses=300, seed=4, keep_waveforms=True)
    real = scan_run._chunk
    calls = []

    def stop_at_third(job, sl, seed):
        calls.append(sl.start)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(job, sl, seed)

    monkeypatch.setattr(scan_run, "_chunk", stop_at_third)
    with pytest.raises(KeyboardInterrupt):
        scan(sc, pat, plat, sen, jobs=1, chunk_pulses=300, seed=4, keep_waveforms=True,
             run_dir=tmp_path / "run")
    calls.clear()
    monkeypatch.setattr(scan_run, "_chunk", lambda job, sl, seed: (calls.append(sl.start),
                                                                  real(job, sl, seed))[1])
    resumed = scan(sc, pat, plat, sen, jobs=1, chunk_pulses=300, seed=4, keep_waveforms=True,
                   run_dir=tmp_path / "run")
    assert len(calls) == -(-len(pat) // 300) - 2          # the two saved chunks not redone
    assert resumed.points.tobytes() == fresh.points.tobytes()
    for a, b in zip(resumed.waveforms, fresh.waveforms):
        assert np.array_equal(a, b)


def test_waveforms_stream_to_a_file_block_by_block_with_the_points(tmp_path):
    """``waveforms_file``: the records go to disk as chunks finish (threads, any order)
    and read back equal to those kept in memory, with the points and parameters."""
    from meshladar.scan import read_hdf5

    sc, pat, plat, sen = _setup()
    kept = scan(sc, pat, plat, sen, chunk_pulses=300, seed=4, keep_waveforms=True)
    streamed = scan(sc, pat, plat, sen, chunk_pulses=300, seed=4, jobs=2,
                    waveforms_file=tmp_path / "w.h5")
    assert streamed.waveforms is None
    back = read_hdf5(tmp_path / "w.h5")
    assert back.points.tobytes() == kept.points.tobytes() == streamed.points.tobytes()
    assert len(back.waveforms) == len(kept.waveforms)
    for a, b in zip(back.waveforms + back.starts, kept.waveforms + kept.starts):
        assert np.array_equal(a, b)
    assert [p.name for p in tmp_path.iterdir()] == ["w.h5"]        # no partial file left


def test_a_failed_streaming_scan_leaves_no_file(tmp_path, monkeypatch):
    sc, pat, plat, sen = _setup()
    real = scan_run._chunk

    def fail_second(job, sl, seed, calls=[]):
        calls.append(1)
        if len(calls) == 2:
            raise RuntimeError("boom")
        return real(job, sl, seed)

    monkeypatch.setattr(scan_run, "_chunk", fail_second)
    with pytest.raises(RuntimeError, match="boom"):
        scan(sc, pat, plat, sen, chunk_pulses=300, jobs=1, waveforms_file=tmp_path / "w.h5")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("step", ["_write_points", "replace"])
def test_a_waveform_file_that_cannot_be_finished_leaves_no_temporary(step, tmp_path,
                                                                   monkeypatch):
    """A scan whose waveform file fails at the end (writing the points, or moving the
    file into place: the name taken by a folder meanwhile) raises, and leaves neither the
    file nor its temporary."""
    sc, pat, plat, sen = _setup()

    def fails(*args):
        raise OSError("disk full")

    if step == "replace":
        monkeypatch.setattr(scan_files.os, "replace", fails)
    else:
        monkeypatch.setattr(scan_files, step, fails)
    with pytest.raises(OSError, match="disk full"):
        scan(sc, pat, plat, sen, chunk_pulses=300, jobs=1, waveforms_file=tmp_path / "w.h5")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_a_dask_cluster_gives_the_points_of_one_thread():
    """Chunks sent to a local Dask cluster (two workers, TLS) come back as one thread's."""
    pytest.importorskip("distributed")
    from meshladar.stream import dask_executor

    sc, pat, plat, sen = _setup()
    one = scan(sc, pat, plat, sen, jobs=1, chunk_pulses=300, seed=4)
    with dask_executor(workers=2) as ex:
        far = scan(sc, pat, plat, sen, chunk_pulses=300, seed=4, executor=ex)
    assert len(one) > 500 and one.points.tobytes() == far.points.tobytes()


def test_a_run_folder_of_another_format_is_refused_naming_it(tmp_path, monkeypatch):
    """A run folder kept by an earlier version's scan (another JOB_FORMAT: what a chunk
    computes changed) is refused, the message naming ``format``, not only the other keys
    that moved with it."""
    from meshladar.runs import RunFolderError
    from meshladar.scan import _streaming

    sc, pat, plat, sen = _setup()
    monkeypatch.setattr(_streaming, "JOB_FORMAT", 1)
    scan(sc, pat, plat, sen, jobs=1, chunk_pulses=300, run_dir=tmp_path / "run")
    monkeypatch.setattr(_streaming, "JOB_FORMAT", 2)
    with pytest.raises(RunFolderError, match=r"differs in format"):
        scan(sc, pat, plat, sen, jobs=1, chunk_pulses=300, run_dir=tmp_path / "run")
