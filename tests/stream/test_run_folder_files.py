"""A run folder opens only its own regular files: a link is never followed, a FIFO never
waited on, a user's file never removed, a chunk of NaN named and recomputed (issue 29)."""

from __future__ import annotations

import os
import threading

import numpy as np
import pytest

from meshladar.errors import MeshladarWarning
from meshladar.io import save_result
from meshladar.runs import RunFolder, RunFolderError, chunk_digest

JOB = {"kind": "test"}

#: A failsafe only: the checks refuse before opening, so a pass never waits; without them
#: a FIFO blocks forever and this bound turns the hang into a failure.
HANG_FAILSAFE_S = 120


def _in_thread(call):
    """Run ``call`` in a thread; the exception it raised, or a failure if it hangs."""
    out = {}

    def run():
        try:
            call()
        except BaseException as exc:         # noqa: BLE001 - handed back to the test
            out["exc"] = exc

    t = threading.Thread(target=run, daemon=True)
    t.start()
    t.join(HANG_FAILSAFE_S)
    assert not t.is_alive(), "hung on a FIFO"
    return out.get("exc")


def test_a_lock_link_is_refused_and_its_target_untouched(tmp_path):
    target = tmp_path / "notes.txt"
    target.write_text("my notes")
    run = tmp_path / "run"
    run.mkdir()
    (run / ".lock").symlink_to(target)
    with pytest.raises(RunFolderError, match=r"\.lock: a symbolic link where the run folder"):
        RunFolder(run, JOB, 2)
    assert target.read_text() == "my notes"


@pytest.mark.parametrize("name", ["manifest.json", "chunk_00001.npz", ".lock"])
def test_a_fifo_is_refused_at_once(tmp_path, name):
    os.mkfifo(tmp_path / name)
    exc = _in_thread(lambda: RunFolder(tmp_path, JOB, 2))
    assert isinstance(exc, RunFolderError) and f"{name}: a FIFO" in str(exc)


@pytest.mark.parametrize("name", ["manifest.json", "chunk_00000.npz"])
def test_a_linked_manifest_or_chunk_is_refused(tmp_path, name):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.write_text("{}")
    run = tmp_path / "run"
    run.mkdir()
    (run / name).symlink_to(elsewhere)
    with pytest.raises(RunFolderError, match="a symbolic link"):
        RunFolder(run, JOB, 2)
    assert elsewhere.read_text() == "{}"


def test_users_files_that_look_like_temporaries_are_kept(tmp_path):
    names = [".tmp-123-notes.txt", f".tmp-{os.getpid()}-x", ".meshladar-tmp-notes",
             ".meshladar-tmp-12-abc.npz", "tmp-1-abcdefghx"]
    for n in names:
        (tmp_path / n).write_text("mine")
    ours = tmp_path / ".meshladar-tmp-99999-abcdefghchunk_00000.npz"
    ours.write_bytes(b"partial")
    with RunFolder(tmp_path, JOB, 2) as folder:
        folder.save(0, {"values": np.ones(3)})
    assert not ours.exists()
    assert all((tmp_path / n).read_text() == "mine" for n in names)


def test_a_chunk_of_nan_is_named_and_recomputed(tmp_path):
    with RunFolder(tmp_path, JOB, 2) as folder:
        with pytest.raises(RunFolderError, match=r"chunk 1 computed non-finite values in "
                                                 r"'values'; not kept"):
            folder.save(1, {"values": np.array([1.0, np.nan])})
        assert not (tmp_path / "chunk_00001.npz").exists()
        # a chunk whose checksum matches its NaN (written by an older version, or by hand)
        bad = {"values": np.array([np.inf, 1.0])}
        save_result(folder._file(0), bad, {"job": folder.digest, "chunk": 0,
                                           "sha256": chunk_digest(bad)})
        with pytest.warns(MeshladarWarning, match=r"chunk 0 holds non-finite values in "
                                                  r"'values'; recomputing it"):
            assert folder.load(0) is None
        folder.save(0, {"values": np.array([2.0, 1.0])})
        np.testing.assert_array_equal(folder.load(0)["values"], [2.0, 1.0])
