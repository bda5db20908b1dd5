"""Resumable, loss-free runs: kill, interrupt, corrupt, resume."""

from __future__ import annotations

import os
import signal
import subprocess
import sys

import numpy as np
import pytest

import meshladar as ml
from meshladar.materials import ALUMINUM
from meshladar.runs import RunFolderError

from conftest import PAIR  # noqa: E402  (the shared disk pair)


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # faceted on purpose
def test_resume_reuses_verified_chunks_and_recomputes_corrupt_ones(tmp_path):
    mesh = PAIR.tessellate(256)
    ladar = ml.Ladar.paper(angles_deg=np.arange(0.0, 360.0, 10.0))     # 36 views: 5 chunks
    ref = ml.simulate(mesh, ladar, model="mesh")
    run = tmp_path / "run"
    first = ml.simulate(mesh, ladar, model="mesh", run_dir=run)
    np.testing.assert_array_equal(first.values, ref.values)
    chunks = sorted(p.name for p in run.glob("chunk_*.npz"))
    assert len(chunks) == 5 and (run / "manifest.json").is_file()
    # corrupt one chunk, delete another: both are recomputed, the rest reused
    (run / chunks[1]).write_bytes(b"garbage")
    os.remove(run / chunks[3])
    mtimes = {c: (run / c).stat().st_mtime_ns for c in (chunks[0], chunks[2], chunks[4])}
    again = ml.simulate(mesh, ladar, model="mesh", run_dir=run)
    np.testing.assert_array_equal(again.values, ref.values)
    assert all((run / c).stat().st_mtime_ns == t for c, t in mtimes.items())
    # a chunk whose numbers were altered fails its checksum and is recomputed too
    from meshladar.io import load_result, save_result

    arrays, meta = load_result(run / chunks[2])
    arrays["values"] = arrays["values"] * 2
    save_result(run / chunks[2], arrays, {k: v for k, v in meta.items()
                                          if k != "meshladar_version"})
    np.testing.assert_array_equal(ml.simulate(mesh, ladar, model="mesh", run_dir=run).values,
                                  ref.values)


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # faceted on purpose
def test_a_different_job_is_refused(tmp_path):
    mesh = PAIR.tessellate(128)
    ladar = ml.Ladar.paper(angles_deg=np.arange(0.0, 360.0, 30.0))
    ml.simulate(mesh, ladar, model="mesh", run_dir=tmp_path)
    with pytest.raises(RunFolderError, match=r"holds a different job \(differs in "
                                             r"ray_spacing\)"):
        ml.simulate(mesh, ladar, model="mesh", run_dir=tmp_path, rays_per_bin=4)
    with pytest.raises(RunFolderError, match="different job"):
        ml.simulate(PAIR.tessellate(256), ladar, model="mesh", run_dir=tmp_path)


_JOB = """
import sys, numpy as np, meshladar as ml
from meshladar.materials import DARK_GRAY, ALUMINUM
pair = ml.phantoms.scene("disk_pair", large=DARK_GRAY, small=ALUMINUM)
ladar = ml.Ladar.paper(angles_deg=np.arange(0.0, 360.0, 0.5))
s = ml.simulate(pair.tessellate(512), ladar, model="mesh", rays_per_bin=16,
                run_dir=sys.argv[1], jobs=1)
np.save(sys.argv[2], s.values)
"""


def _start(run, out):
    return subprocess.Popen([sys.executable, "-c", _JOB, str(run), str(out)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)


def _finish(proc, timeout=600):
    """Wait, close the pipes, return (exit code, stderr)."""
    _, err = proc.communicate(timeout=timeout)
    return proc.returncode, err


def _wait_for_chunks(run, n, proc):
    """Until n chunk files exist (an event), failing at once if the run ends first; no
    deadline, so a loaded machine only makes it slower."""
    while len(list(run.glob("chunk_*.npz"))) < n:
        try:
            proc.wait(timeout=0.05)
        except subprocess.TimeoutExpired:
            continue
        raise AssertionError(_finish(proc)[1])


@pytest.mark.slow
def test_sigkill_mid_run_then_resume_gives_the_uninterrupted_result(tmp_path):
    run = tmp_path / "run"
    proc = _start(run, tmp_path / "a.npy")
    _wait_for_chunks(run, 5, proc)
    proc.send_signal(signal.SIGKILL)
    _finish(proc)
    done = len(list(run.glob("chunk_*.npz")))
    assert 5 <= done < 90                                       # 720 views: 90 chunks
    # a write cut short leaves at most a temporary, never a half-written chunk file
    from meshladar.runs import RunFolder

    for f in run.glob("chunk_*.npz"):
        from meshladar.io import load_result

        load_result(f)                                           # every final file reads
    code, err = _finish(_start(run, tmp_path / "b.npy"))
    assert code == 0, err
    assert not list(run.glob(".meshladar-tmp-*"))                # resume cleans temporaries
    del RunFolder
    code, err = _finish(_start(tmp_path / "fresh", tmp_path / "c.npy"))
    assert code == 0, err
    np.testing.assert_array_equal(np.load(tmp_path / "b.npy"), np.load(tmp_path / "c.npy"))


@pytest.mark.slow
def test_ctrl_c_stops_cleanly_and_says_how_to_resume(tmp_path):
    out = tmp_path / "r.npz"
    run = tmp_path / "run"
    cmd = [sys.executable, "-m", "meshladar", "simulate", "disk_pair", "--model", "mesh",
           "--segments", "512", "--views", "720", "--rays-per-bin", "16", "--jobs", "1",
           "--run-dir", str(run), "-o", str(out), "--quiet"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    _wait_for_chunks(run, 3, proc)
    proc.send_signal(signal.SIGINT)
    code, err = _finish(proc, timeout=60)
    assert code == 130, err
    assert "interrupted" in err and "run the same command again to resume" in err
    assert "Traceback" not in err and not out.exists()
    kept = len(list(run.glob("chunk_*.npz")))
    assert kept >= 3
    assert subprocess.run(cmd, capture_output=True, timeout=600).returncode == 0
    assert out.exists()


@pytest.mark.parametrize("model, options", [("analytic", {}), ("pixel", {"pixel_size": 0.02})])
def test_every_model_resumes_from_its_run_folder(model, options, tmp_path):
    # the stream is shared: the analytic and pixel models resume exactly as the mesh model
    ladar = ml.Ladar.paper(angles_deg=np.arange(0.0, 360.0, 3.0))        # 120 views
    ref = ml.simulate(PAIR, ladar, model=model, **options)
    run = tmp_path / "run"
    first = ml.simulate(PAIR, ladar, model=model, run_dir=run, **options)
    np.testing.assert_array_equal(first.values, ref.values)
    chunks = sorted(p.name for p in run.glob("chunk_*.npz"))
    assert len(chunks) >= 2
    (run / chunks[0]).write_bytes(b"garbage")
    kept = {c: (run / c).stat().st_mtime_ns for c in chunks[1:]}
    again = ml.simulate(PAIR, ladar, model=model, run_dir=run, **options)
    np.testing.assert_array_equal(again.values, ref.values)
    assert all((run / c).stat().st_mtime_ns == t for c, t in kept.items())
    # another coating is another job: refused, never mixed
    other = ml.phantoms.scene("disk_pair", large=ALUMINUM, small=ALUMINUM)
    with pytest.raises(RunFolderError, match="different job"):
        ml.simulate(other, ladar, model=model, run_dir=run, **options)


def test_a_lone_disk_resumes_its_distinct_profiles(tmp_path):
    # a centred disk is one profile whatever the views: the run folder holds that one
    disk = ml.phantoms.scene("disk", ALUMINUM)
    ladar = ml.Ladar.paper(angles_deg=np.arange(0.0, 360.0, 1.0))
    sino = ml.simulate(disk, ladar, run_dir=tmp_path)
    assert len(list(tmp_path.glob("chunk_*.npz"))) == 1
    np.testing.assert_array_equal(sino.values, ml.simulate(disk, ladar).values)
    np.testing.assert_array_equal(ml.simulate(disk, ladar, run_dir=tmp_path).values,
                                  sino.values)


@pytest.mark.parametrize("name, content", [("manifest.json", b'{"mine": 1}\n'),
                                           ("chunk_00000.npz", b"my own notes\n")])
def test_run_dir_never_overwrites_a_users_file(tmp_path, capsys, name, content):
    # a folder of the user's holding a file under a run folder's name: simulate and the
    # command line refuse it before any chunk, and the file is left byte for byte
    from meshladar.cli import main
    from meshladar.errors import ParameterError

    mine = tmp_path / "project" / name
    mine.parent.mkdir()
    mine.write_bytes(content)
    ladar = ml.Ladar.paper(angles_deg=np.arange(0.0, 360.0, 30.0))
    with pytest.raises(ParameterError, match=r"project/" + name.replace(".", r"\.") +
                       r": not a meshladar .*choose an empty or new folder"):
        ml.simulate(PAIR, ladar, model="analytic", run_dir=mine.parent)
    out = tmp_path / "s.npz"
    assert main(["simulate", "disk_pair", "--model", "analytic", "--views", "12", "--run-dir",
                 str(mine.parent), "-o", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(mine) in err and "Traceback" not in err
    assert mine.read_bytes() == content and not out.exists()
    assert sorted(p.name for p in mine.parent.iterdir()) == sorted({name, ".lock"})
