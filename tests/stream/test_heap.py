"""A threaded run keeps its threads' heaps: glibc malloc's thresholds
(:data:`meshladar.stream.HEAP_THRESHOLDS`) set when a run starts threads, unless the
process started with its own. Read as resident memory (the kernel's page count, no
timing), in a fresh process each time, since the thresholds are the process's."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

pytestmark = pytest.mark.skipif(
    not (os.confstr("CS_GNU_LIBC_VERSION") or "").startswith("glibc"),
    reason="glibc malloc's thresholds")

#: A threaded run (two threads, trivial chunks), then a thread that makes and frees a
#: 24 MiB array; prints how much more is resident, MiB, with the array and after it.
_SCRIPT = """
import os, sys, threading
import numpy as np
from meshladar.stream import run_chunks

if "late" in sys.argv:             # set after the start, as Dask's nanny does for its workers
    os.environ["MALLOC_TRIM_THRESHOLD_"] = "65536"
if "run" in sys.argv:
    run_chunks(lambda payload, items: len(items), None, 4, chunk_size=1, jobs=2, threads=True)
page = os.sysconf("SC_PAGE_SIZE") / 2 ** 20
grew = []

def resident():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * page

def work():
    before = resident()
    a = np.ones(3 << 20)
    grew.append(resident() - before)
    del a
    grew.append(resident() - before)

t = threading.Thread(target=work)
t.start()
t.join()
print(*grew)
"""


def _resident(*args, **env):
    clean = {k: v for k, v in os.environ.items()          # this process's may hold Dask's
             if not k.startswith("MALLOC_") and k != "GLIBC_TUNABLES"}
    out = subprocess.run([sys.executable, "-c", _SCRIPT, *args], capture_output=True,
                         text=True, env=dict(clean, **env), check=True).stdout
    return [float(x) for x in out.split()]


def test_a_threads_freed_memory_is_kept_for_its_next_chunk():
    """After a threaded run, a thread's freed 24 MiB stay resident, for the next chunk to
    reuse, where glibc's default (its first large block mapped afresh) gives them back,
    and the next chunk faults every page in again: a scan on two threads took 8,000 page
    faults and ran 1.3x one thread."""
    held, kept = _resident("run")
    assert held > 20 and kept > 20
    held, kept = _resident()                 # no threaded run: the default
    assert held > 20 and kept < 4


def test_thresholds_a_user_set_are_left_alone():
    """MALLOC_MMAP_THRESHOLD_ at 128 KiB: every large array is mapped afresh, and given
    back when freed, threaded run or not."""
    held, kept = _resident("run", MALLOC_MMAP_THRESHOLD_="131072")
    assert held > 20 and kept < 4


def test_thresholds_put_in_the_environment_after_the_start_change_nothing():
    """Dask's nanny puts MALLOC_TRIM_THRESHOLD_ in os.environ for the workers it spawns;
    glibc read the environment at this process's start, so the run still sets its own."""
    held, kept = _resident("late", "run")
    assert held > 20 and kept > 20
