"""meshladar's thread pools (:func:`meshladar._executors.thread_pool`) start all their
threads before they are returned, so that no chunk waits behind a thread starting; a pool
that cannot start them all, or is interrupted while they start, releases those it started.
Synchronised on the threads themselves (barriers and joins); the bounds on those waits
(:data:`HANG`) only turn a hang into a failure."""

from __future__ import annotations

import threading

import pytest

from meshladar import _executors
from meshladar._executors import thread_pool

#: Seconds after which a wait that should end at once counts as hung.
HANG = 60.0


@pytest.mark.parametrize("workers", [1, 2, 5])
def test_every_thread_runs_before_the_pool_is_returned(workers):
    before = set(threading.enumerate())
    pool = thread_pool(workers)
    try:
        started = set(threading.enumerate()) - before
        assert len(started) == workers
        # all of them serve tasks: as many tasks meeting at a barrier complete
        met = threading.Barrier(workers, timeout=HANG)
        assert sorted(pool.map(lambda _: met.wait(), range(workers))) == list(range(workers))
    finally:
        pool.shutdown()
    assert not any(t.is_alive() for t in started)


def _ended(before):
    """Whether every thread started since ``before`` ends (joined, within :data:`HANG`)."""
    for t in set(threading.enumerate()) - before:
        t.join(HANG)
    return set(threading.enumerate()) <= before


@pytest.mark.parametrize("fails", ["start", "interrupt"])
def test_a_pool_that_cannot_start_its_threads_frees_those_it_started(monkeypatch, fails):
    """The third thread fails to start (its task already queued, as when the system has
    no thread to give), or Ctrl-C arrives while it starts: the two started end."""
    before = set(threading.enumerate())
    start, calls = threading.Thread.start, []
    error = RuntimeError("can't start new thread") if fails == "start" else KeyboardInterrupt

    def failing(self):
        calls.append(self)
        if len(calls) == 3:
            raise error
        start(self)

    monkeypatch.setattr(threading.Thread, "start", failing)
    monkeypatch.setattr(_executors, "_START_BOUND", None)   # they must be freed, not time out
    with pytest.raises(type(error) if fails == "start" else KeyboardInterrupt):
        thread_pool(4)
    monkeypatch.undo()
    assert len(calls) == 3
    assert _ended(before)
