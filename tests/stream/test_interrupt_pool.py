"""An interrupted run stops its process pool at once: the workers computing chunks are ended,
not waited for, and none is left behind (issue 29: SIGTERM or Ctrl-C with process workers
waited 10-30 s for the running chunks, or printed a worker's KeyboardInterrupt traceback)."""

from __future__ import annotations

import os
import signal

import numpy as np
import pytest

from meshladar.stream import run_chunks


def _chunk(folder, items):
    """Chunk 0 interrupts the run (SIGTERM to the parent) once chunk 1 is running; chunk 1
    never finishes by itself: only being stopped ends it."""
    k = int(items[0])
    ready = os.path.join(folder, "ready")          # a FIFO: opening it blocks until both ends
    if k == 0:
        with open(ready, "rb") as fh:              # the event: chunk 1 has written its pid
            fh.read(1)
        os.kill(os.getppid(), signal.SIGTERM)
        return {"values": np.zeros((1, 1))}
    with open(os.path.join(folder, "pid1"), "w") as fh:
        fh.write(str(os.getpid()))
    with open(ready, "wb") as fh:
        fh.write(b"1")
    while True:
        signal.pause()


def _interrupt(signum, frame):
    raise KeyboardInterrupt


@pytest.mark.skipif(not hasattr(signal, "pause"), reason="POSIX signals")
def test_an_interrupt_ends_the_workers_computing_chunks(tmp_path):
    os.mkfifo(tmp_path / "ready")
    previous = signal.signal(signal.SIGTERM, _interrupt)     # as the command line does
    try:
        with pytest.raises(KeyboardInterrupt):
            run_chunks(_chunk, str(tmp_path), 2, chunk_size=1, jobs=2)
    finally:
        signal.signal(signal.SIGTERM, previous)
    pid = int((tmp_path / "pid1").read_text())
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return                                               # ended (and reaped): passed
    os.kill(pid, signal.SIGKILL)                             # don't leave it to the suite
    pytest.fail("the worker computing chunk 1 outlived the interrupted run")
