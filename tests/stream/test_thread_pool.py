"""meshladar's thread pools (:func:`meshladar._executors.thread_pool`) start all their threads
before they are returned, so that no chunk waits behind a thread starting; a pool that
cannot start them all releases those it started. Synchronised on the threads themselves
(barriers and joins), no timing."""

from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor

import pytest

from meshladar._executors import thread_pool


@pytest.mark.parametrize("workers", [1, 2, 5])
def test_every_thread_runs_before_the_pool_is_returned(workers):
    before = set(threading.enumerate())
    pool = thread_pool(workers)
    try:
        started = set(threading.enumerate()) - before
        assert len(started) == workers
        # all of them serve tasks: as many tasks meeting at a barrier complete
        met = threading.Barrier(workers)
        assert sorted(pool.map(lambda _: met.wait(), range(workers))) == list(range(workers))
    finally:
        pool.shutdown()
    assert not any(t.is_alive() for t in started)


def test_a_pool_that_cannot_start_its_threads_frees_those_it_started(monkeypatch):
    before = set(threading.enumerate())
    submit = ThreadPoolExecutor.submit
    calls = []

    def failing(self, fn, *args, **kwargs):
        calls.append(fn)
        if len(calls) == 3:
            raise RuntimeError("can't start new thread")
        return submit(self, fn, *args, **kwargs)

    monkeypatch.setattr(ThreadPoolExecutor, "submit", failing)
    with pytest.raises(RuntimeError, match="can't start new thread"):
        thread_pool(4)
    for t in set(threading.enumerate()) - before:   # released from the barrier: they end
        t.join()
    assert set(threading.enumerate()) <= before
