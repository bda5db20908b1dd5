"""A user trial's command-line defects about outputs, inputs and stops: every output path
(and output folder, and file written beside an output) is checked before any work, naming
its flag; no output lies in the run folder; a file that is not an .npz result says so; two
outputs that are one file are called outputs; the help's one-liners and simulate's summary
say what is true; an interrupted study says how to resume, and SIGTERM exits 143."""

from __future__ import annotations

import os
import signal
import subprocess
import sys

import numpy as np
import pytest

import meshladar as ml
import meshladar.studies
from meshladar import plotting
from meshladar.cli import COMMANDS, main
from meshladar.cli import lrcs as cli_lrcs
from meshladar.cli import reconstruct as cli_reconstruct
from meshladar.cli import scan as cli_scan
from meshladar.cli import simulate as cli_simulate
from meshladar.cli.checks import check_output, check_place
from meshladar.errors import ParameterError
from meshladar.io import ResultFileError, load_result, load_sinogram, save_sinogram
from meshladar.meshes import fibonacci_sphere


def _work(*args, **kwargs):
    pytest.fail("the work started before the bad output was refused")


@pytest.fixture
def no_work(monkeypatch):
    """Every command's work fails the test if it is reached."""
    for module, name in ((cli_simulate, "simulate"), (cli_lrcs, "lrcs"),
                         (cli_reconstruct, "receive"), (cli_reconstruct, "fbp"),
                         (cli_reconstruct, "fbp3d"), (plotting, "viz"),
                         (cli_scan.scanning, "scan"), (meshladar.studies, "faceting_study")):
        monkeypatch.setattr(module, name, _work)


def _sinogram(path, sphere=False):
    """A small saved sinogram: 8 views about z, or 50 over the sphere."""
    if sphere:
        w = fibonacci_sphere(50)
        sino = ml.Sinogram(np.ones((50, 16)), angles_deg=np.degrees(np.arctan2(w[:, 1],
                                                                                w[:, 0])),
                           bin_edges=np.linspace(-1.0, 1.0, 17), view_vectors=w)
    else:
        sino = ml.Sinogram(np.ones((8, 16)), angles_deg=np.arange(8) * 45.0,
                           bin_edges=np.linspace(-1.0, 1.0, 17))
    save_sinogram(path, sino)
    return path


def _run(capsys, argv):
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


_FLASH = "flash rows=2 columns=2 ifov_deg=0.1"
_PLACE = "static position=-5,0,0"

#: A command whose output (or output folder) lies under the file f.txt: (argv, its flag).
UNDER_A_FILE = [
    (["simulate", "disk", "--views", "4", "-o", "f.txt/x.npz"], "-o", "f.txt/x.npz"),
    (["simulate", "disk", "--views", "4", "-o", "x.npz", "--run-dir", "f.txt/run"],
     "--run-dir", "f.txt/run"),
    (["lrcs", "disk", "--views", "2", "-o", "f.txt/s.csv"], "-o", "f.txt/s.csv"),
    (["receive", "s.npz", "--sample-rate", "2e9", "-o", "f.txt/w.npz"], "-o", "f.txt/w.npz"),
    (["receive", "s.npz", "--sample-rate", "2e9", "-o", "w.npz", "--plot", "f.txt/w.png"],
     "--plot", "f.txt/w.png"),
    (["reconstruct", "s.npz", "-o", "f.txt/r.png"], "-o", "f.txt/r.png"),
    (["paper", "f.txt/figs", "--size", "8"], "outdir", "f.txt/figs"),
    (["study", "faceting", "f.txt/st", "--quiet"], "outdir", "f.txt/st"),
    (["view", "disk", "--screenshot", "f.txt/v.png"], "--screenshot", "f.txt/v.png"),
    (["scan", "disk", "--pattern", _FLASH, "--platform", _PLACE, "-o", "f.txt/p.h5"], "-o",
     "f.txt/p.h5"),
    (["scan", "disk", "--pattern", _FLASH, "--platform", _PLACE, "-o", "p.h5",
      "--waveforms", "f.txt/w.h5"], "--waveforms", "f.txt/w.h5"),
]


@pytest.mark.parametrize("argv, flag, path", UNDER_A_FILE,
                         ids=[f"{a[0]}{f}" for a, f, _ in UNDER_A_FILE])
def test_an_output_under_a_file_is_refused_by_its_flag_before_the_work(
        argv, flag, path, tmp_path, monkeypatch, capsys, no_work):
    """`simulate cone.stl ... -o cone.stl/x.npz` computed, then said "'cone.stl/x.npz'
    File exists"; `paper cone.stl/figs` ran 5.5 s, then said "Not a directory"."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "f.txt").write_text("a file")
    _sinogram(tmp_path / "s.npz")
    before = sorted(os.listdir(tmp_path))
    code, out, err = _run(capsys, argv)
    above = os.path.join(os.getcwd(), "f.txt")
    assert (code, out) == (2, "")
    assert err == f"meshladar: error: {flag}: cannot write {path!r}: {above!r} is a file, " \
                  "not a folder\n"
    assert sorted(os.listdir(tmp_path)) == before


def test_an_output_in_a_folder_without_write_permission_is_refused(tmp_path, monkeypatch,
                                                                  capsys, no_work):
    """(Run as root, the folder's permission is stood in for by os.access.)"""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "ro").mkdir()
    locked = os.path.join(os.getcwd(), "ro")
    access = os.access
    monkeypatch.setattr(os, "access", lambda p, mode, **kw: False if os.fspath(p) == locked
                        else access(p, mode, **kw))
    code, _, err = _run(capsys, ["simulate", "disk", "--views", "4", "-o", "ro/x.npz"])
    assert code == 2
    assert err == ("meshladar: error: -o: cannot write 'ro/x.npz': no permission to write in "
                   f"the folder {locked!r}\n")


@pytest.mark.parametrize("argv", [
    ["simulate", "disk", "--views", "4", "-o", "ro/x.npz"],
    ["scan", "box.stl", "--pattern", "raster azimuth_deg=0 elevation_deg=0 pulse_rate=1",
     "--platform", "static position=-5,0,0", "-o", "ro/x.las"]])
def test_a_folder_that_takes_no_file_is_refused_before_the_work(tmp_path, monkeypatch, capsys,
                                                                 no_work, argv):
    """Permission bits that say yes to a folder that takes no file (root on /sys, a
    read-only mount: a user's scan ran 4 s and then failed "Permission denied" without
    naming -o): a temporary is tried, and the refusal names the flag before the work."""
    import errno
    import tempfile
    import trimesh

    monkeypatch.chdir(tmp_path)
    trimesh.creation.box().export(tmp_path / "box.stl")
    (tmp_path / "ro").mkdir()
    locked = os.path.join(os.getcwd(), "ro")
    mkstemp = tempfile.mkstemp

    def refuse(*args, dir=None, **kw):
        if os.fspath(dir) == locked:
            raise OSError(errno.EROFS, "Read-only file system")
        return mkstemp(*args, dir=dir, **kw)

    monkeypatch.setattr(tempfile, "mkstemp", refuse)
    code, _, err = _run(capsys, argv)
    assert code == 2
    assert err == (f"meshladar: error: -o: cannot write {argv[-1]!r}: the folder {locked!r} "
                   "takes no new file (Read-only file system)\n")
    assert os.listdir(locked) == []


@pytest.mark.parametrize("argv", [
    ["simulate", "disk", "--views", "4", "-o", "brk/x.npz"],
    ["scan", "box.stl", "--pattern", "raster azimuth_deg=0 elevation_deg=0 pulse_rate=1",
     "--platform", "static position=-5,0,0", "-o", "brk/x.las"]])
def test_an_output_under_a_link_to_nothing_is_refused_naming_the_link(tmp_path, monkeypatch,
                                                                      capsys, no_work, argv):
    """A review: -o under a dangling link passed the checks (its parent takes files) and
    scan failed after loading the scene with "File exists", naming no flag."""
    import trimesh

    monkeypatch.chdir(tmp_path)
    trimesh.creation.box().export(tmp_path / "box.stl")
    os.symlink(tmp_path / "gone", tmp_path / "brk")
    code, _, err = _run(capsys, argv)
    assert code == 2
    assert err == (f"meshladar: error: -o: cannot write {argv[-1]!r}: "
                   f"{str(tmp_path / 'brk')!r} is a link to {str(tmp_path / 'gone')!r}, which "
                   "does not exist\n")


def test_the_folder_probe_is_named_as_a_temporary_and_removed(tmp_path, monkeypatch):
    """The probe a check makes is one of meshladar's temporaries by name (a kill between
    making and removing it leaves one the next write in that folder removes)."""
    from meshladar._atomic_write import temporary_writer

    removed = []
    remove = os.remove
    monkeypatch.setattr(os, "remove", lambda p: (removed.append(p), remove(p)))
    check_place(str(tmp_path / "x.npz"), "-o")
    (probe,) = removed
    assert temporary_writer(os.path.basename(probe)) == os.getpid()
    assert os.listdir(tmp_path) == []


def test_missing_folders_above_an_output_are_accepted(tmp_path):
    # the writers create them: only the nearest existing path above must be a folder
    check_place(str(tmp_path / "new" / "sub" / "x.npz"), "-o")
    check_place(str(tmp_path / "new" / "figs"), "outdir", folder=True)


@pytest.mark.parametrize("sphere, suffix, what", [(False, ".image.npz", "image data"),
                                                  (True, ".volume.npz", "volume")])
def test_a_folder_where_reconstruct_writes_its_values_is_refused_before_the_work(
        sphere, suffix, what, tmp_path, monkeypatch, capsys, no_work):
    """`mkdir out.image.npz; reconstruct cone.npz -o out.png` ran FBP, wrote out.png, then
    failed naming no flag (and the 3-D inversion's out.volume.npz alike)."""
    monkeypatch.chdir(tmp_path)
    _sinogram(tmp_path / "s.npz", sphere=sphere)
    (tmp_path / f"out{suffix}").mkdir()
    code, _, err = _run(capsys, ["reconstruct", "s.npz", "-o", "out.png", "--size", "8"])
    assert code == 2
    assert err == (f"meshladar: error: -o 'out.png' would write the {what} to "
                   f"'out{suffix}', which is a folder: choose another output name (or move "
                   "the folder)\n")
    assert not (tmp_path / "out.png").exists()


@pytest.mark.parametrize("output", ["run/chunk_00000.npz", "run/manifest.npz",
                                    "run/sub/x.npz", "link/x.npz"])
def test_no_output_lies_in_the_run_folder(output, tmp_path, monkeypatch, capsys, no_work):
    """`simulate ... -o run/chunk_00000.npz --run-dir run` replaced the run's own chunk
    (a later resume read the result as a chunk). Any path in the run folder, at any depth
    and through a link, is refused."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "run").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "run")
    chunk = tmp_path / "run" / "chunk_00000.npz"
    chunk.write_bytes(b"the run's own chunk")
    code, _, err = _run(capsys, ["simulate", "disk", "--views", "4", "-o", output,
                                 "--run-dir", "run"])
    assert code == 2
    assert err == (f"meshladar: error: -o {output!r} is in the run folder --run-dir 'run', "
                   "which holds the run's own files (manifest.json, chunk_*.npz): write the "
                   "result outside it\n")
    assert chunk.read_bytes() == b"the run's own chunk"


def test_an_output_beside_the_run_folder_is_accepted(tmp_path):
    (tmp_path / "run").mkdir()
    for name in ("runner.npz", "run.npz"):          # a name that begins as the folder's
        check_output(str(tmp_path / name), (".npz",), [], run_dir=str(tmp_path / "run"))
    folder = str(tmp_path / "r.npz")                 # -o naming the run folder itself
    with pytest.raises(ParameterError, match=f"^-o {folder!r} is the input {folder!r}"):
        check_output(folder, (".npz",), [folder], run_dir=folder)


def _binary_stl(path):
    path.write_bytes(bytes(80) + (1).to_bytes(4, "little") + bytes(50))


NOT_NPZ = [
    ("m.stl", lambda p: p.write_bytes(b"solid cube\nfacet normal 0 0 1\n"),
     "it looks like an ASCII STL mesh"),
    ("b.stl", _binary_stl, "it looks like a binary STL mesh"),
    ("m.ply", lambda p: p.write_bytes(b"ply\nformat ascii 1.0\nend_header\n"),
     "it looks like a PLY mesh"),
    ("p.las", lambda p: p.write_bytes(b"LASF" + bytes(300)), "it looks like a LAS point cloud"),
    ("w.h5", lambda p: p.write_bytes(b"\x89HDF\r\n\x1a\n" + bytes(100)),
     "it looks like an HDF5 file"),
    ("a.npy", lambda p: np.save(p, np.zeros(3)), "it looks like a bare .npy array"),
    ("t.npz", lambda p: p.write_bytes(b"hello\n"), "its first bytes are not a zip archive's"),
    ("e.npz", lambda p: p.write_bytes(b""), "an empty file"),
]


@pytest.mark.parametrize("name, write, what", NOT_NPZ, ids=[n for n, _, _ in NOT_NPZ])
def test_a_file_that_is_not_an_npz_is_called_so(name, write, what, tmp_path):
    """reconstruct and receive of an .stl, .ply, .las or .h5 printed numpy's advice about
    pickled data and allow_pickle."""
    path = tmp_path / name
    write(path)
    with pytest.raises(ResultFileError) as info:
        load_result(path)
    assert str(info.value) == (f"{path}: not a readable result file: not an .npz archive "
                               f"({what}); give an .npz file that meshladar wrote")


@pytest.mark.parametrize("argv", [["reconstruct", "m.stl", "-o", "r.png"],
                                  ["receive", "m.stl", "--sample-rate", "2e9", "-o", "w.npz"]])
def test_reconstruct_and_receive_say_a_mesh_is_not_a_result(argv, tmp_path, monkeypatch,
                                                            capsys):
    monkeypatch.chdir(tmp_path)
    NOT_NPZ[0][1](tmp_path / "m.stl")
    code, _, err = _run(capsys, argv)
    assert code == 2
    assert err == ("meshladar: error: m.stl: not a readable result file: not an .npz archive "
                   "(it looks like an ASCII STL mesh); give an .npz file that meshladar "
                   "wrote\n")


def test_two_outputs_that_are_one_file_are_called_outputs(tmp_path, monkeypatch, capsys,
                                                          no_work):
    """`receive ... -o spw4.npz --plot spw4.npz` said --plot was "the input"."""
    monkeypatch.chdir(tmp_path)
    _sinogram(tmp_path / "s.npz")
    code, _, err = _run(capsys, ["receive", "s.npz", "--sample-rate", "2e9", "-o", "w.npz",
                                 "--plot", "w.npz"])
    assert code == 2
    assert err == ("meshladar: error: --plot 'w.npz' and -o 'w.npz' are the same file: give "
                   "each output its own\n")


def test_the_help_says_what_reconstruct_and_study_do(capsys):
    with pytest.raises(SystemExit) as done:
        main(["--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert done.value.code == 0
    assert ("reconstruct invert a saved sinogram (FBP about z, or 3-D over the sphere) into "
            "a figure (PNG, PDF, SVG, JPEG, TIFF) and its values (.npz)") in text
    assert "study run a study (faceting, tomography3d or reconstruction) into a folder" in text
    assert "into a PNG" not in text and "faceting-vs-analytic" not in text


def test_simulates_summary_says_the_total_return_is_a_mean_over_views(tmp_path, capsys):
    out = tmp_path / "d.npz"
    code, text, _ = _run(capsys, ["simulate", "disk", "--views", "4", "-o", out])
    sino, _ = load_sinogram(out)
    assert code == 0 and sino.total().size == 4
    assert text.endswith(f"; paper radiometry; mean total return per view "
                         f"{sino.total().mean():.6g}; wrote {out}\n")


#: A child that runs the command line with a study's work held: it says "started" once the
#: work has begun, then waits for a signal.
_HELD_STUDY = """
import signal, sys
import meshladar.studies.paper
from meshladar.cli import main


def held(*args, **kwargs):
    print("started", flush=True)
    while True:
        signal.pause()


meshladar.studies.faceting_study = held
meshladar.studies.paper.run_3d = held
sys.exit(main(sys.argv[1:]))
"""


@pytest.mark.parametrize("kind, hint", [
    ("faceting", "; finished study points are kept in {run}: run the same command again to "
                 "resume"),
    ("tomography3d", "; the tomography3d study keeps no finished part: running it again "
                     "starts over")])
@pytest.mark.parametrize("sig, status", [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_an_interrupted_study_says_what_is_kept_and_sigterm_exits_143(kind, hint, sig,
                                                                      status, tmp_path):
    """An interrupted study printed only "meshladar: interrupted"; SIGTERM exited 130
    (SIGINT's status). The signal is sent once the child says its work has started."""
    outdir = tmp_path / "st"
    child = subprocess.Popen([sys.executable, "-c", _HELD_STUDY, "study", kind, str(outdir),
                              "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             text=True)
    try:
        assert child.stdout.readline() == "started\n"
        child.send_signal(sig)
        _, err = child.communicate(timeout=120)
    finally:
        if child.poll() is None:
            child.kill()
            child.communicate()
    assert child.returncode == status
    assert err == "meshladar: interrupted" + hint.format(run=outdir / "run") + "\n"


#: A child whose run folder's first chunk is saved, then held until a signal.
_HELD_RUN = """
import signal, sys
from meshladar import runs
from meshladar.cli import main

save = runs.RunFolder.save


def held(self, i, arrays):
    save(self, i, arrays)
    print("saved", flush=True)
    while True:
        signal.pause()


runs.RunFolder.save = held
sys.exit(main(sys.argv[1:]))
"""


def test_sigterm_during_a_run_exits_143_with_the_resume_hint(tmp_path):
    run = tmp_path / "run"
    child = subprocess.Popen([sys.executable, "-c", _HELD_RUN, "simulate", "disk_pair",
                              "--views", "64", "--jobs", "1", "--run-dir", str(run), "-o",
                              str(tmp_path / "r.npz"), "--quiet"], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
    try:
        assert child.stdout.readline() == "saved\n"
        child.send_signal(signal.SIGTERM)
        _, err = child.communicate(timeout=120)
    finally:
        if child.poll() is None:
            child.kill()
            child.communicate()
    assert child.returncode == 143
    assert err == (f"meshladar: interrupted; finished chunks are kept in {run}: run the same "
                   "command again to resume\n")
    assert list(run.glob("chunk_*.npz")) and not (tmp_path / "r.npz").exists()


#: The entry point, SIGTERMed while it imports the command line (deterministic: the import
#: hook sends the signal to its own process).
_TERMINATED_IMPORT = """
import os, signal, sys
class Terminate:
    def find_spec(self, name, path=None, target=None):
        if name == "meshladar.cli.commands":
            os.kill(os.getpid(), signal.SIGTERM)
        return None
sys.meta_path.insert(0, Terminate())
from meshladar.__main__ import run
sys.exit(run(["materials"]))
"""


def test_sigterm_while_the_command_line_imports_exits_143():
    done = subprocess.run([sys.executable, "-c", _TERMINATED_IMPORT], capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 143
    assert done.stderr == "meshladar: interrupted\n"


def test_every_command_is_in_the_table():
    # the outputs' cases above cover every command that writes a file or a folder
    writers = {argv[0] for argv, _, _ in UNDER_A_FILE}
    assert writers == set(COMMANDS) - {"demo", "materials", "bench"}
