"""A run folder opens only its own regular files: a link is never followed, a FIFO never
waited on, a user's file never removed, a chunk of NaN named and recomputed (issue 29); a
user's own file under a run folder's name (``manifest.json``, ``chunk_*.npz``, ``.lock``)
refused before any work and never overwritten, meshladar's own damaged files rewritten."""

from __future__ import annotations

import json
import os
import threading

import numpy as np
import pytest

from meshladar.errors import MeshladarWarning, ParameterError
from meshladar.io import save_result
from meshladar.runs import ForeignFileError, RunFolder, RunFolderError, chunk_digest
from meshladar.stream import joined, run_chunks

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


# ------------------------------------- someone else's file under a run folder's name (defect)

def _user_npz(path):
    np.savez(path, mine=np.arange(4.0))


def _user_result(path):
    save_result(path, {"values": np.ones(3)}, {"note": "a result of the user's"})


#: Files a user made under a run folder's names; each must stop a run before any work.
USERS_FILES = {
    "a JSON object of another program": ("manifest.json", b'{"mine": 1}\n'),
    "a text manifest": ("manifest.json", b"my notes, not JSON\n"),
    "an empty JSON object": ("manifest.json", b"{}"),
    "a user's npz": ("chunk_00000.npz", _user_npz),
    "a user's text": ("chunk_00000.npz", b"plain text of mine\n"),
    "a meshladar result that is no chunk": ("chunk_00001.npz", _user_result),
    "another program's lock": (".lock", b"locked by my editor\n"),
}


def _counting():
    """A per-chunk job that records each call, and the list of calls."""
    calls = []

    def fn(payload, items):
        calls.append(items.tolist())
        return {"values": items.astype(float)[:, None] * payload}

    return fn, calls


def _run(folder, fn, job=None):
    return run_chunks(fn, 2.0, 6, chunk_size=3, run_dir=folder, job=job or {"kind": "count"},
                      arrays={"values": (1,)})


def _put(path, content):
    if callable(content):
        content(path)
    else:
        path.write_bytes(content)
    return path.read_bytes()


@pytest.mark.parametrize("case", sorted(USERS_FILES))
def test_a_users_file_under_a_run_folders_name_is_refused_before_any_work(tmp_path, case):
    name, content = USERS_FILES[case]
    mine = tmp_path / name
    before = _put(mine, content)
    (tmp_path / "notes.txt").write_text("notes")
    fn, calls = _counting()
    with pytest.raises(ParameterError) as exc:
        _run(tmp_path, fn)
    assert isinstance(exc.value, RunFolderError)
    msg = str(exc.value)
    assert str(mine) in msg and "\n" not in msg
    assert "choose an empty or new folder" in msg and f"move {name} out of {tmp_path}" in msg
    assert mine.read_bytes() == before and calls == []
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted({name, "notes.txt", ".lock"})
    assert (tmp_path / "notes.txt").read_text() == "notes"


@pytest.mark.parametrize("name, content", [("manifest.json", b'{"mine": 1}'),
                                           ("chunk_00001.npz", _user_npz)])
def test_someone_elses_file_is_refused_even_beside_this_jobs_chunks(tmp_path, name, content):
    fn, calls = _counting()
    _run(tmp_path, fn)
    (tmp_path / "chunk_00001.npz").unlink()
    ours = (tmp_path / "chunk_00000.npz").read_bytes()
    before = _put(tmp_path / name, content)
    calls.clear()
    with pytest.raises(ForeignFileError, match=name.replace(".", r"\.") + ": not a meshladar"):
        _run(tmp_path, fn)
    assert (tmp_path / name).read_bytes() == before and calls == []
    assert (tmp_path / "chunk_00000.npz").read_bytes() == ours


def test_meshladars_own_damaged_files_are_rewritten_and_other_files_left_alone(tmp_path):
    fn, calls = _counting()
    (tmp_path / "notes.txt").write_text("notes")
    first = joined(_run(tmp_path, fn), "values")
    assert len(calls) == 2
    # a truncated manifest (not JSON) beside this job's chunks: meshladar's own, damaged:
    # rewritten, the chunks reused
    manifest = tmp_path / "manifest.json"
    manifest.write_bytes(manifest.read_bytes()[:40])
    calls.clear()
    np.testing.assert_array_equal(joined(_run(tmp_path, fn), "values"), first)
    assert calls == [] and json.loads(manifest.read_text())["digest"]
    # a chunk that no longer reads, in this job's folder: recomputed, alone
    (tmp_path / "chunk_00001.npz").write_bytes(b"garbage")
    np.testing.assert_array_equal(joined(_run(tmp_path, fn), "values"), first)
    assert calls == [[3, 4, 5]]
    assert (tmp_path / "notes.txt").read_text() == "notes"


def test_an_unreadable_manifest_alone_is_refused_not_guessed(tmp_path):
    # the same truncated manifest with no chunk of this job beside it: whose it is cannot be
    # told, so it is kept and the folder refused
    fn, calls = _counting()
    _run(tmp_path, fn)
    for chunk in tmp_path.glob("chunk_*.npz"):
        chunk.unlink()
    manifest = tmp_path / "manifest.json"
    manifest.write_bytes(manifest.read_bytes()[:40])
    before, calls[:] = manifest.read_bytes(), []
    with pytest.raises(ForeignFileError, match="no chunk of this job beside it"):
        _run(tmp_path, fn)
    assert manifest.read_bytes() == before and calls == []
