"""Streaming runs, the same for every forward model: chunks of views, executors (processes,
threads, Dask), retries, run folders and progress.

A forward model hands :func:`run_chunks` a per-chunk job ``fn(payload, items, *args)``: a
module-level function (so processes and Dask can pickle it), the data every chunk needs
(``payload``: a mesh's geometry, a scene's shapes), and the number of items (views, or a lone
disk's distinct profiles). It knows nothing of meshes or shapes. Chunks run here, on a pool
of ``jobs`` worker processes, or on any ``concurrent.futures`` executor (a
``ThreadPoolExecutor``, or a Dask cluster's, see :func:`dask_executor`)::

    from meshladar.stream import dask_executor
    with dask_executor("tcp://scheduler:8786") as ex:      # an existing cluster
        sino = ml.simulate(scene, ladar, model="mesh", executor=ex)
    with dask_executor(workers=2) as ex:     # a local cluster on loopback, TLS-secured
        ...

With a Dask executor the payload is scattered to every worker once (not sent with each
task); a chunk whose worker was lost is sent again, with the payload itself, up to
``_MAX_RETRIES`` times. Workers need meshladar installed in the same version.

With ``run_dir`` a run is resumable and loss-free (:mod:`meshladar.runs`): each finished
chunk is saved atomically with a checksum, and the same job run again computes only what is
missing. A progress bar (``progress=True``) is drawn on a terminal only.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from . import _executors
# the executors (their own module), re-exported here, where they always were
from ._executors import (_on_executor, _stop_workers, check_jobs, choose_executor,
                         dask_executor, in_worker)
from ._validate import check_flag
from .errors import ParameterError
from .runs import RunFolder

__all__ = ["run_chunks", "joined", "dask_executor", "Progress", "choose_executor",
           "check_jobs", "check_run_dir", "in_worker", "MAX_JOBS_PER_CORE", "THREADS_FROM",
           "PARALLEL_FROM", "HEAP_THRESHOLDS"]

# the executors' limits, documented here, where they are public
#: Worker processes allowed per core (``jobs``): more only compete for the cores.
MAX_JOBS_PER_CORE = _executors.MAX_JOBS_PER_CORE
#: Estimated work (rays) from which ``jobs=None`` starts a process per core (a process
#: pool costs 0.4-1.5 s to start: about 4e6 rays of one core's work).
PARALLEL_FROM = _executors.PARALLEL_FROM
#: The same for threads, which cost next to nothing to start: from 5e4 rays a view's rows
#: on two threads pay (a 1e5-ray view of an 82k-face sphere: 15-18 ms against 24-30 ms).
THREADS_FROM = _executors.THREADS_FROM
#: glibc malloc's thresholds a run sets when it starts threads (bytes): blocks above
#: ``mmap`` mapped from the system, a heap's free top beyond ``trim`` given back; the
#: largest values glibc's own dynamic thresholds reach. Not set where the process started
#: with malloc's thresholds in its environment (the Long runs guide).
HEAP_THRESHOLDS = _executors.HEAP_THRESHOLDS


class Progress:
    """``Progress(total, unit, enabled=True)``; ``update(n)``; ``close()``.

    Draws to stderr only when enabled and stderr is a TTY (quiet in pipes, logs and CI).

    Parameters
    ----------
    total : int
        How many items the bar counts to.
    unit : str
        The items' name in the bar (default ``"items"``).
    enabled : bool
        Whether to draw at all (default True); keyword-only. The bar is drawn only when
        this is true and ``stream`` has ``isatty()`` returning true.
    stream : file-like, optional
        Where to draw (default ``sys.stderr``); keyword-only.
    """

    def __init__(self, total, unit="items", *, enabled=True, stream=None):
        self.stream = sys.stderr if stream is None else stream
        self.enabled = bool(enabled) and hasattr(self.stream, "isatty") and self.stream.isatty()
        self.total, self.unit, self.done = int(total), unit, 0
        self.start = time.monotonic()
        self._last = 0.0

    def update(self, n=1):
        """Count ``n`` more items done and redraw the bar (at most every 0.1 s, and once
        the total is reached): done/total, the rate per second and the estimated time
        left.

        Parameters
        ----------
        n : int
            Items finished since the last update (default 1).
        """
        self.done += n
        if not self.enabled:
            return
        now = time.monotonic()
        if now - self._last < 0.1 and self.done < self.total:
            return
        self._last = now
        frac = self.done / max(self.total, 1)
        bar = "#" * int(30 * frac)
        rate = self.done / max(now - self.start, 1e-9)
        eta = (self.total - self.done) / rate if rate > 0 else 0.0
        self.stream.write(f"\r[{bar:<30}] {self.done}/{self.total} {self.unit} "
                          f"{rate:.1f}/s eta {eta:.0f}s")
        self.stream.flush()

    def close(self):
        """End the bar's line (a newline on the stream, where the bar is drawn), so that
        what is written next starts on a line of its own."""
        if self.enabled:
            self.stream.write("\n")
            self.stream.flush()


def _chunks(n, size):
    return [np.arange(i, min(i + size, n)) for i in range(0, n, size)]


def check_run_dir(run_dir):
    """``run_dir`` as a path, refused early (before any work) if it cannot be a folder.

    Parameters
    ----------
    run_dir : str or os.PathLike
        The run folder; it need not exist yet.

    Returns
    -------
    str or os.PathLike
        ``run_dir``, unchanged.

    Raises
    ------
    ParameterError
        When ``run_dir`` is not a non-empty str or os.PathLike, or names an existing
        path that is not a folder.
    """
    if not isinstance(run_dir, (str, os.PathLike)) or not os.fspath(run_dir):
        raise ParameterError(f"run_dir must be a folder path; got {run_dir!r}")
    if os.path.exists(run_dir) and not os.path.isdir(run_dir):
        raise ParameterError(f"run_dir must be a folder; {os.fspath(run_dir)!r} is a file")
    return run_dir


def run_chunks(fn, payload, n_items, *, chunk_size, args=(), jobs=None, executor=None,
               progress=False, unit="views", work=0.0, run_dir=None, job=None, arrays=None,
               threads=False):
    """Run ``fn(payload, items, *args)`` over chunks of ``range(n_items)``.

    Parameters
    ----------
    fn : callable
        The per-chunk job, a module-level function; ``items`` is an int array of the
        chunk's item indices.
    payload : object
        What every chunk needs, sent to each worker once where the executor allows.
    n_items, chunk_size : int
        Items in all and per chunk.
    args : tuple
        Further arguments of every call (sent with each task).
    jobs : int, optional
        Workers (threads or processes); default 1, or one per core (at most one per chunk)
        once ``work`` reaches :data:`THREADS_FROM` (threads) or :data:`PARALLEL_FROM` rays.
    executor : concurrent.futures.Executor, optional
        Any executor; overrides ``jobs``.
    progress : bool
        A progress bar over the items, on a terminal only.
    unit : str
        The items' name in the bar (default "views").
    work : float
        Estimated work (rays) for the default ``jobs``.
    threads : bool
        Whether ``fn`` releases the GIL, so that ``jobs`` are threads sharing the payload
        (no pickling, no per-process rebuild) rather than processes.
    run_dir : path, optional
        A run folder for resumable runs; needs ``job`` and ``arrays``.
    job : dict
        Everything that determines the result (its digest names the folder's job).
    arrays : dict
        ``{name: trailing shape}`` of the arrays each chunk returns as a dict, each with
        one row per item: ``{"values": (n_bins,)}``.

    Returns
    -------
    list
        Each chunk's result, in chunk order.

    Raises
    ------
    ParameterError
        When ``progress`` is not a bool, ``run_dir``, ``jobs`` or ``executor`` is refused
        (:func:`check_run_dir`, :func:`choose_executor`), or a chunk's arrays cannot be
        saved.
    RunFolderError
        When the run folder is in use, holds another job, or a chunk computes non-finite
        values (:class:`~meshladar.runs.RunFolder`).
    """
    check_flag("progress", progress)
    if run_dir is not None:
        check_run_dir(run_dir)
    chunks = _chunks(int(n_items), int(chunk_size))
    ex, own = choose_executor(jobs, executor, work, len(chunks), threads=threads)
    bar = Progress(n_items, unit, enabled=progress)
    results = [None] * len(chunks)
    folder = None
    try:
        if run_dir is not None:
            folder = RunFolder(run_dir, dict(job, views_per_chunk=int(chunk_size)), len(chunks))
            _resume(folder, chunks, arrays, results, bar)
        _run_missing(ex, _Tasks(fn, payload, chunks, args), results, folder, bar)
    except BaseException:
        if own:                          # interrupted or failed: drop the queued chunks and
            _stop_workers(ex)            # stop the workers at once, not after their chunks
            own = False
        raise
    finally:
        _close(bar, folder, ex if own else None)
    return results


def _run_missing(ex, tasks, results, folder, bar):
    """Compute the chunks ``results`` still lacks: in this thread (``ex`` None, or nothing
    to do) or on ``ex``; each is kept in ``results`` and the run folder (if any) and counted
    on the bar as it completes."""
    def keep(k, res):
        results[k] = res
        if folder is not None:
            folder.save(k, res)
        bar.update(len(tasks.chunks[k]))

    todo = [k for k in range(len(tasks.chunks)) if results[k] is None]
    if ex is None or not todo:
        for k in todo:
            keep(k, tasks.fn(tasks.payload, tasks.chunks[k], *tasks.args))
    else:
        _on_executor(ex, tasks, todo, keep)


def _close(bar, folder, pool):
    """End a run: the progress bar, the run folder (if any), then the pool the run started
    (``pool``: None when the executor is the user's, or the workers were stopped already)."""
    bar.close()
    if folder is not None:
        folder.close()
    if pool is not None:
        pool.shutdown()


def _resume(folder, chunks, arrays, results, bar):
    """Fill ``results`` with the chunks the run folder already holds (verified)."""
    for k, items in enumerate(chunks):
        saved = folder.load(k, {name: (len(items),) + tuple(shape)
                                for name, shape in arrays.items()})
        if saved is not None:
            results[k] = saved
            bar.update(len(items))


class _Tasks(NamedTuple):
    """What every chunk's task is made of: ``fn(payload, chunks[k], *args)``."""

    fn: Callable
    payload: object
    chunks: list
    args: tuple


def joined(results, name):
    """One array of all chunks' ``name`` rows (each chunk's result a dict of arrays).

    Parameters
    ----------
    results : sequence of dict
        Each chunk's result (:func:`run_chunks`), in chunk order.
    name : str
        The array to join.

    Returns
    -------
    numpy.ndarray
        The chunks' ``name`` arrays concatenated along their first axis (one row per
        item).
    """
    return np.concatenate([np.asarray(r[name]) for r in results])
