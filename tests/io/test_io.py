"""Saved results: atomic writes, no pickle, clear errors."""

from __future__ import annotations

import numpy as np
import pytest

import meshladar
from meshladar.io import ResultFileError, load_result, save_result, write_text_atomic


def test_round_trip(tmp_path):
    p = tmp_path / "sub" / "r.npz"
    save_result(p, {"a": np.arange(3.0), "b": np.eye(2)}, {"seed": 3, "model": "analytic"})
    arrays, meta = load_result(p)
    np.testing.assert_array_equal(arrays["a"], np.arange(3.0))
    assert meta == {"seed": 3, "model": "analytic", "meshladar_version": meshladar.__version__}
    assert [f.name for f in p.parent.iterdir()] == ["r.npz"]       # no temporary left over


def test_failed_write_keeps_the_old_file(tmp_path):
    p = tmp_path / "r.npz"
    save_result(p, {"a": np.zeros(2)}, {"v": 1})
    with pytest.raises(meshladar.errors.ParameterError, match="meta must be JSON-serialisable"):
        save_result(p, {"a": np.zeros(2)}, {"v": object()})        # not JSON: the save fails
    arrays, meta = load_result(p)
    assert meta["v"] == 1 and [f.name for f in tmp_path.iterdir()] == ["r.npz"]


def test_errors(tmp_path):
    with pytest.raises(ResultFileError, match="no such result file"):
        load_result(tmp_path / "missing.npz")
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not a zip")
    with pytest.raises(ResultFileError, match="not a readable result file"):
        load_result(bad)
    plain = tmp_path / "plain.npz"
    np.savez(plain, a=np.zeros(1))
    with pytest.raises(ResultFileError, match="not a meshladar result"):
        load_result(plain)
    obj = tmp_path / "obj.npz"
    np.savez(obj, __meta__=np.array("{}"), a=np.array([{"x": 1}], dtype=object))
    with pytest.raises(ResultFileError, match="not a readable result file"):
        load_result(obj)                                           # pickled data refused


def test_write_text_atomic(tmp_path):
    p = tmp_path / "t.txt"
    write_text_atomic(p, "héllo")
    assert p.read_text(encoding="utf-8") == "héllo"


def test_truncated_and_pickled_sinogram_results_are_rejected(tmp_path):
    import meshladar as ml
    from meshladar.io import load_sinogram, save_sinogram

    sino = ml.simulate(ml.Scene([ml.Disk((0, 0), 0.5, ml.materials.DARK_GRAY)]),
                       ml.Ladar.paper(angles_deg=[0.0, 90.0]))
    p = tmp_path / "s.npz"
    save_sinogram(p, sino, scene=None, params={"n": np.int64(3)})
    back, meta = load_sinogram(p)
    np.testing.assert_array_equal(back.values, sino.values)
    assert meta["params"] == {"n": 3}
    data = p.read_bytes()
    (tmp_path / "cut.npz").write_bytes(data[: len(data) // 2])
    with pytest.raises(ResultFileError, match="cut.npz: not a readable result file"):
        load_sinogram(tmp_path / "cut.npz")
    # a pickle-bearing array is never unpickled (allow_pickle=False)
    evil = tmp_path / "evil.npz"
    np.savez(evil, __meta__=np.array('{"kind": "sinogram"}'),
             values=np.array([object()], dtype=object))
    with pytest.raises(ResultFileError, match="evil.npz: not a readable result file"):
        load_sinogram(evil)


def test_temporaries_of_a_killed_writer_are_removed_by_the_next_write(tmp_path):
    import subprocess
    import sys

    from meshladar import _atomic_write

    # a pid that has ended (a finished child), and this process's own (alive)
    child = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                           capture_output=True, text=True, check=True)
    dead = int(child.stdout)
    stale = tmp_path / f".meshladar-tmp-{dead}-abc12_xyout.npz"
    stale.write_bytes(b"x" * 1000)                        # what a SIGKILL mid-write leaves
    live = tmp_path / f".meshladar-tmp-{1}-def456ghother.npz"   # pid 1 is alive: kept
    live.write_bytes(b"y")
    users = _near_miss_names(dead)
    for name in users:
        (tmp_path / name).write_text("a user's notes")
    _atomic_write._SWEPT.discard(str(tmp_path))
    save_result(tmp_path / "out.npz", {"a": np.zeros(3)}, {})
    assert not stale.exists() and live.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([live.name, "out.npz", *users])
    assert all((tmp_path / name).read_text() == "a user's notes" for name in users)


def _near_miss_names(dead_pid):
    """Users' own file names that look like temporaries (issue 29: ``.tmp-<pid>-notes.txt``
    was deleted by the next write in its folder)."""
    return [f".tmp-{dead_pid}-notes.txt", f".tmp-{dead_pid}-abc123out.npz", ".tmp-notes",
            f".meshladar-tmp-{dead_pid}-short", f".meshladar-tmp-{dead_pid}-ABCDEFGHx.npz",
            ".meshladar-tmp-notes.txt", f"meshladar-tmp-{dead_pid}-abcdefghx.npz",
            f".meshladar-tmp-{dead_pid}-abcdefgh", f"x.meshladar-tmp-{dead_pid}-abcdefghy"]


def test_a_link_named_like_a_temporary_is_not_followed_or_removed(tmp_path):
    from meshladar import _atomic_write

    target = tmp_path / "keep.txt"
    target.write_text("precious")
    link = tmp_path / ".meshladar-tmp-999999999-abcdefghx.npz"
    link.symlink_to(target)
    _atomic_write._SWEPT.discard(str(tmp_path))
    save_result(tmp_path / "out.npz", {"a": np.zeros(3)}, {})
    assert link.is_symlink() and target.read_text() == "precious"


def test_a_failed_write_names_the_users_file_not_the_temporary(tmp_path):
    import errno

    from meshladar.io import write_atomic

    def full_disk(fh):
        raise OSError(errno.ENOSPC, "No space left on device")

    target = tmp_path / "out.bin"
    with pytest.raises(OSError) as exc:
        write_atomic(target, full_disk)
    assert exc.value.errno == errno.ENOSPC and exc.value.filename == str(target)
    assert list(tmp_path.iterdir()) == []                 # no temporary left behind
    # a path through a file (not a folder): the error names what the user gave
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(OSError) as exc:
        write_atomic(blocker / "out.bin", lambda fh: fh.write(b"1"))
    assert exc.value.filename == str(blocker / "out.bin")


def test_cli_output_through_a_file_is_one_line_naming_it(tmp_path, capsys):
    from meshladar.cli import main

    (tmp_path / "file").write_text("x")
    out = tmp_path / "file" / "d.npz"
    assert main(["simulate", "disk", "--views", "4", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and repr(str(out)) in err and ".tmp-" not in err


def test_an_interrupt_inside_a_writer_stays_an_interrupt(tmp_path):
    """Ctrl-C while numpy writes a zip member: zipfile's close then raises ValueError in
    its cleanup; the write must still end as KeyboardInterrupt (a clean stop, a resume
    hint), leave no temporary and not the half-written file."""
    from meshladar.io import write_atomic

    def writer(fh):
        try:
            fh.write(b"partial")
            raise KeyboardInterrupt
        finally:
            raise ValueError("Can't close the ZIP file while there is an open writing handle")

    target = tmp_path / "r.npz"
    with pytest.raises(KeyboardInterrupt):
        write_atomic(target, writer)
    assert not target.exists() and list(tmp_path.iterdir()) == []


def test_result_files_are_sized_before_reading(tmp_path, monkeypatch):
    """A result file is checked for its arrays' declared sizes before any is read: a header
    claiming more than its member holds, or members unpacking past the cap, are refused
    (issue 29: a 2 GB file of junk was read whole); a FIFO is refused before opening."""
    import io as stdio
    import os
    import zipfile

    import meshladar._validate as validate
    from meshladar.io import ResultFileError, load_result

    path = tmp_path / "r.npz"
    save_result(path, {"a": np.zeros(1000)}, {})
    assert load_result(path)[0]["a"].shape == (1000,)
    monkeypatch.setattr(validate, "MAX_ARRAY_BYTES", 4000)       # 8000 bytes of data
    with pytest.raises(ResultFileError, match=r"would unpack to .* GiB, more than the"):
        load_result(path)
    monkeypatch.undo()
    # a crafted header: shape (2**40,) over 8 bytes of data
    header = stdio.BytesIO()
    np.lib.format.write_array_header_1_0(header, {"descr": "<f8", "fortran_order": False,
                                                  "shape": (2**40,)})
    crafted = tmp_path / "crafted.npz"
    with zipfile.ZipFile(crafted, "w") as z:
        z.writestr("values.npy", b"\x93NUMPY\x01\x00" + header.getvalue()[8:] + b"\0" * 8)
        z.writestr("__meta__.npy", b"")
    with pytest.raises(ResultFileError, match=r"values\.npy declares 8796093022208 bytes"):
        load_result(crafted)
    fifo = tmp_path / "fifo.npz"
    os.mkfifo(fifo)
    with pytest.raises(ResultFileError, match="not a regular file"):
        load_result(fifo)


def test_an_interrupt_during_a_write_waits_for_the_whole_file(tmp_path):
    """Ctrl-C while numpy writes a result (the CI's Ctrl-C test once landed inside the zip
    writer, and the half-closed ZipFile complained when collected): the file is finished and
    renamed into place first, then the interrupt is delivered; nothing is left unraisable
    (pytest turns an unraisable exception into an error here)."""
    import gc
    import signal

    from meshladar.io import write_atomic

    def writer(fh):
        signal.raise_signal(signal.SIGINT)               # Ctrl-C as the writer starts
        np.savez_compressed(fh, a=np.arange(1000))

    target = tmp_path / "r.npz"
    with pytest.raises(KeyboardInterrupt):
        write_atomic(target, writer)
    gc.collect()
    with np.load(target) as done:
        np.testing.assert_array_equal(done["a"], np.arange(1000))
    assert [p.name for p in tmp_path.iterdir()] == ["r.npz"]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_a_second_interrupt_stops_a_write_at_once(tmp_path):
    """A write that does not finish can still be stopped: the second Ctrl-C is delivered
    where it lands, the temporary is removed and the target never appears."""
    import signal

    from meshladar.io import write_atomic

    reached = []

    def writer(fh):
        fh.write(b"partial")
        signal.raise_signal(signal.SIGINT)
        signal.raise_signal(signal.SIGINT)
        reached.append("after")

    target = tmp_path / "r.npz"
    with pytest.raises(KeyboardInterrupt):
        write_atomic(target, writer)
    assert reached == [] and list(tmp_path.iterdir()) == []
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_an_old_3d_sinogram_with_made_up_angles_still_loads(tmp_path):
    """Files from before angles_deg became optional beside view_vectors could hold zeros
    for the angles of 3-D views; such a file loads with its views' azimuths and a warning
    naming it (the views, values and bins as stored)."""
    vec = meshladar.meshes.fibonacci_sphere(6)
    arrays = {"values": np.arange(48.0).reshape(6, 8), "angles_deg": np.zeros(6),
              "bin_edges": np.linspace(-1.0, 1.0, 9), "view_vectors": vec}
    path = tmp_path / "old.npz"
    save_result(path, arrays, {"kind": "sinogram", "model": "mesh", "info": {}})
    with pytest.warns(meshladar.errors.MeshladarWarning, match=r"old\.npz: its angles_deg "
                                                        r"contradict its view_vectors"):
        sino, _ = meshladar.io.load_sinogram(path)
    np.testing.assert_allclose(sino.angles_deg, np.degrees(np.arctan2(vec[:, 1], vec[:, 0])),
                               atol=1e-12)
    np.testing.assert_array_equal(sino.values, arrays["values"])
    np.testing.assert_allclose(sino.view_vectors, vec, atol=1e-15)
