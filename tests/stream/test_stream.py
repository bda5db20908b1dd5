"""The stream (chunks, executors, retries, run folders, progress) on its own: it is handed a
per-chunk job and knows nothing of meshes."""

from __future__ import annotations

import concurrent.futures
from concurrent.futures import CancelledError, Future, ThreadPoolExecutor

import numpy as np
import pytest

import meshladar._executors as executors
from meshladar.errors import ParameterError
from meshladar.runs import RunFolderError
from meshladar.stream import joined, run_chunks


def _squares(payload, items, offset):
    """A per-chunk job: rows (item² + offset, payload) for each item."""
    return {"values": np.stack([items.astype(float) ** 2 + offset,
                                np.full(items.size, float(payload))], -1)}


def test_chunks_cover_every_item_once_in_order():
    res = run_chunks(_squares, 7.0, 23, chunk_size=5, args=(1.0,))
    assert [len(r["values"]) for r in res] == [5, 5, 5, 5, 3]
    v = joined(res, "values")
    np.testing.assert_array_equal(v[:, 0], np.arange(23.0) ** 2 + 1.0)
    np.testing.assert_array_equal(v[:, 1], 7.0)


def test_threads_give_the_serial_result():
    serial = joined(run_chunks(_squares, 2.0, 50, chunk_size=4, args=(0.5,)), "values")
    with ThreadPoolExecutor(3) as ex:
        threaded = run_chunks(_squares, 2.0, 50, chunk_size=4, args=(0.5,), executor=ex)
    np.testing.assert_array_equal(joined(threaded, "values"), serial)


class _LosesFirstTry:
    """An executor whose first submission of each chunk is cancelled (a lost worker)."""

    def __init__(self):
        self.seen = {}

    def submit(self, fn, *args):
        f = Future()
        key = tuple(args[1])
        self.seen[key] = self.seen.get(key, 0) + 1
        if self.seen[key] == 1:
            f.cancel()
            f.set_running_or_notify_cancel()
        else:
            f.set_result(fn(*args))
        return f


def test_a_lost_chunk_is_sent_again():
    ex = _LosesFirstTry()
    v = joined(run_chunks(_squares, 1.0, 10, chunk_size=3, args=(0.0,), executor=ex), "values")
    np.testing.assert_array_equal(v[:, 0], np.arange(10.0) ** 2)
    assert sorted(ex.seen.values()) == [2, 2, 2, 2]          # each chunk: lost once, resent


class _Done:
    """An executor whose every submission is done at once."""

    def submit(self, fn, *args):
        f = Future()
        f.set_result(fn(*args))
        return f


@pytest.mark.parametrize("executor, handed", [(_Done, 200), (_LosesFirstTry, 400)])
def test_completions_are_waited_for_once_each(executor, handed, monkeypatch):
    """200 chunks' futures are handed to ``as_completed`` once each (and each lost one's
    resubmission once more), not again after every completion: the wait is linear in the
    chunks (it was quadratic, 50 s for 40,000 pulses in chunks of 5 on two threads)."""
    seen = []

    def counted(futures):
        seen.append(len(futures))
        return concurrent.futures.as_completed(futures)

    monkeypatch.setattr(executors, "as_completed", counted)
    v = joined(run_chunks(_squares, 1.0, 400, chunk_size=2, args=(0.0,),
                          executor=executor()), "values")
    np.testing.assert_array_equal(v[:, 0], np.arange(400.0) ** 2)
    assert sum(seen) == handed


class _AlwaysLost(_LosesFirstTry):
    def submit(self, fn, *args):
        f = Future()
        f.cancel()
        f.set_running_or_notify_cancel()
        return f


def test_a_chunk_lost_every_time_is_an_error_after_the_retries():
    with pytest.raises(CancelledError):
        run_chunks(_squares, 1.0, 4, chunk_size=2, args=(0.0,), executor=_AlwaysLost())


def test_a_run_folder_keeps_chunks_and_refuses_another_job(tmp_path):
    job = {"kind": "squares", "n": 12}
    first = joined(run_chunks(_squares, 3.0, 12, chunk_size=5, args=(0.0,), run_dir=tmp_path,
                              job=job, arrays={"values": (2,)}), "values")
    assert len(list(tmp_path.glob("chunk_*.npz"))) == 3

    def fails(payload, items, offset):
        raise AssertionError("every chunk should come from the run folder")

    again = joined(run_chunks(fails, 3.0, 12, chunk_size=5, args=(0.0,), run_dir=tmp_path,
                              job=job, arrays={"values": (2,)}), "values")
    np.testing.assert_array_equal(again, first)
    with pytest.raises(RunFolderError, match="different job"):
        run_chunks(_squares, 3.0, 12, chunk_size=5, args=(0.0,), run_dir=tmp_path,
                   job={"kind": "squares", "n": 13}, arrays={"values": (2,)})


@pytest.mark.parametrize("kwargs, match", [
    ({"jobs": 0}, "jobs must be an integer >= 1"),
    ({"jobs": 2.5}, "jobs must be an integer >= 1"),
    ({"executor": object()}, "executor must be a concurrent.futures.Executor"),
    ({"progress": "yes"}, "progress must be True or False"),
    ({"run_dir": ""}, "run_dir must be a folder path"),
])
def test_bad_streaming_options_are_refused_before_any_work(kwargs, match):
    def never(payload, items):
        raise AssertionError("no chunk may run")

    with pytest.raises(ParameterError, match=match):
        run_chunks(never, None, 4, chunk_size=2, **kwargs)
