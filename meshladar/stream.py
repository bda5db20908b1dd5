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

import contextlib
import os
import signal
import sys
import time
from collections.abc import Callable
from concurrent.futures import (CancelledError, ProcessPoolExecutor, ThreadPoolExecutor,
                                as_completed)
from typing import NamedTuple

import numpy as np

from ._validate import check_count, check_flag, check_real
from .errors import ParameterError
from ._dask import connect
from .runs import RunFolder

__all__ = ["run_chunks", "joined", "dask_executor", "Progress", "choose_executor",
           "check_jobs", "check_run_dir", "in_worker", "MAX_JOBS_PER_CORE", "THREADS_FROM", "PARALLEL_FROM"]

#: Worker processes allowed per core (``jobs``): more only compete for the cores.
MAX_JOBS_PER_CORE = 4
#: Resubmissions of a chunk whose task was cancelled (a worker lost with its data).
_MAX_RETRIES = 3
#: Estimated work (rays) from which ``jobs=None`` starts a process per core (a process
#: pool costs 0.4-1.5 s to start: about 4e6 rays of one core's work).
PARALLEL_FROM = 4e6
#: The same for threads, which cost next to nothing to start: from 5e4 rays a view's rows
#: on two threads pay (a 1e5-ray view of an 82k-face sphere: 15-18 ms against 24-30 ms).
THREADS_FROM = 5e4



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
        if self.enabled:
            self.stream.write("\n")
            self.stream.flush()


def _chunks(n, size):
    return [np.arange(i, min(i + size, n)) for i in range(0, n, size)]


def check_jobs(jobs):
    """``jobs`` checked (None, or 1 to MAX_JOBS_PER_CORE per core): a caller checks it with
    its other options, before any work or warning.

    Parameters
    ----------
    jobs : int or None
        Worker count: None (the caller's default), or an integer in
        [1, :data:`MAX_JOBS_PER_CORE` × the machine's cores].

    Returns
    -------
    int or None
        ``jobs``, unchanged.

    Raises
    ------
    ParameterError
        When ``jobs`` is not None and not an integer ≥ 1 (bools refused), or is more than
        :data:`MAX_JOBS_PER_CORE` per core.
    """
    if jobs is None:
        return None
    cores = os.cpu_count() or 1
    if isinstance(jobs, bool) or not isinstance(jobs, (int, np.integer)) or jobs < 1:
        raise ParameterError(f"jobs must be an integer >= 1; got {jobs!r}")
    if jobs > MAX_JOBS_PER_CORE * cores:
        raise ParameterError(f"jobs must be at most {MAX_JOBS_PER_CORE * cores} "
                             f"({MAX_JOBS_PER_CORE} per core on this {cores}-core machine: "
                             f"more workers only compete for the cores); got {jobs}")
    return jobs


def choose_executor(jobs, executor, work, n_chunks, *, threads=False):
    """The executor to use, and whether it is this call's own (to shut down): the user's;
    else a pool of ``jobs`` threads (a job whose compiled loop releases the GIL, as the mesh
    engine's casts do) or worker processes (one that holds it: the analytic and pixel
    models' numpy); else none. By default a pool is started only when the work (rays) pays
    for it, with at most one worker per chunk: a single view never starts one.

    Parameters
    ----------
    jobs : int or None
        Workers; None: 1 below the work threshold (:data:`THREADS_FROM` for threads,
        :data:`PARALLEL_FROM` for processes), else one per core, at most ``n_chunks``.
    executor : concurrent.futures.Executor or None
        The user's executor: used as given, ``jobs`` ignored.
    work : float
        Estimated work (rays), for the default ``jobs``.
    n_chunks : int
        Number of chunks: the most workers the default starts.
    threads : bool
        A thread pool rather than worker processes (default False). Keyword-only.

    Returns
    -------
    executor : concurrent.futures.Executor or None
        The executor, or None to run the chunks in this thread (one job).
    own : bool
        True when the pool was started here (the caller shuts it down).

    Raises
    ------
    ParameterError
        When ``executor`` has no callable ``submit``, or ``jobs`` is refused by
        :func:`check_jobs`.
    """
    if executor is not None:
        if not callable(getattr(executor, "submit", None)):
            raise ParameterError(f"executor must be a concurrent.futures.Executor (with "
                                 f"submit); got {type(executor).__name__}")
        return executor, False
    cores = os.cpu_count() or 1
    if jobs is None:
        start = THREADS_FROM if threads else PARALLEL_FROM
        jobs = 1 if work < start else max(1, min(cores, n_chunks))
    check_jobs(jobs)
    if jobs == 1:
        return None, False
    if threads:
        return ThreadPoolExecutor(max_workers=int(jobs)), True
    return ProcessPoolExecutor(max_workers=int(jobs), initializer=_worker_init), True


#: True in a worker process of this module's pools (see :func:`in_worker`).
_IN_WORKER = False


def in_worker() -> bool:
    """Whether this process is a worker forked by :func:`run_chunks`' own pool. A job runs
    its compiled kernels serially there: the workers already share the cores, and a child
    forked after an OpenMP kernel ran in its parent aborts when it starts one itself.

    Returns
    -------
    bool
        True in a worker process of this module's process pools, else False.
    """
    return _IN_WORKER


def _worker_init():
    """In a worker process: die with the parent (Linux), so a killed run leaves no
    workers behind; elsewhere a no-op."""
    global _IN_WORKER
    _IN_WORKER = True

    if sys.platform.startswith("linux"):
        import ctypes

        try:
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(1, int(signal.SIGKILL))           # PR_SET_PDEATHSIG
        except (OSError, AttributeError):
            pass
    signal.signal(signal.SIGINT, signal.SIG_IGN)        # the parent handles Ctrl-C
    # and SIGTERM: a worker told to stop just ends (the parent's handler, inherited by the
    # fork, would raise KeyboardInterrupt in the worker and print its traceback)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


#: Seconds a terminated worker has to exit before it is killed.
_STOP_GRACE_S = 5.0


def _stop_workers(ex):
    """Shut our own pool down without waiting, and end its worker processes now (SIGTERM,
    which a worker takes as an order to exit, then wait for them), so an interrupted run
    stops within moments and leaves no process; a thread pool's running chunks cannot be
    stopped and finish."""
    # the pool's internals, read before shutdown() drops its references to them
    processes = dict(getattr(ex, "_processes", None) or {})
    queue = getattr(ex, "_call_queue", None)
    wakeup = getattr(ex, "_executor_manager_thread_wakeup", None)
    ex.shutdown(wait=False, cancel_futures=True)
    for p in list(processes.values()):
        if p.is_alive():
            p.terminate()
    for p in list(processes.values()):
        p.join(_STOP_GRACE_S)              # one caught mid-start may not take SIGTERM yet:
        if p.is_alive():                   # then SIGKILL, so the stop always completes
            p.kill()
            p.join()
    # the pool's feeder thread may be blocked writing a task no worker will read, and the
    # interpreter's exit joins it: nobody joins it (the queue is abandoned), its read end is
    # closed as the pool itself does when broken (cpython gh-94777), and its manager woken
    # to notice the dead workers
    if queue is not None:
        queue.cancel_join_thread()
        queue._reader.close()
    if wakeup is not None:
        try:
            wakeup.wakeup()
        except OSError:
            pass


def _scatter(ex, payload):
    """On a Dask executor, the payload shipped once to every worker (a future standing for
    it); elsewhere the payload itself. A worker lost while it is being scattered is retried
    like a lost chunk; if scattering keeps failing, every task carries the payload."""
    scatter = getattr(getattr(ex, "_client", None), "scatter", None)
    if scatter is None:
        return payload
    for _ in range(_MAX_RETRIES):
        try:
            return scatter(payload, broadcast=True, hash=False)
        except (OSError, TimeoutError, CancelledError):   # distributed's CommClosedError is
            continue                                      # an OSError
    return payload


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

        def keep(k, res):
            results[k] = res
            if folder is not None:
                folder.save(k, res)
            bar.update(len(chunks[k]))

        todo = [k for k in range(len(chunks)) if results[k] is None]
        if ex is None or not todo:
            for k in todo:
                keep(k, fn(payload, chunks[k], *args))
        else:
            _on_executor(ex, _Tasks(fn, payload, chunks, args), todo, keep)
    except BaseException:
        if own:                          # interrupted or failed: drop the queued chunks and
            _stop_workers(ex)            # stop the workers at once, not after their chunks
            own = False
        raise
    finally:
        bar.close()
        if folder is not None:
            folder.close()
        if own:
            ex.shutdown()
    return results


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


def _on_executor(ex, tasks, todo, keep):
    """Run the chunks ``todo`` on ``ex``, ``keep(k, result)`` as each completes."""
    shared = _scatter(ex, tasks.payload)
    futures = {ex.submit(tasks.fn, shared, tasks.chunks[k], *tasks.args): k for k in todo}
    retries = {}
    while futures:
        for f in as_completed(list(futures)):
            k = futures.pop(f)
            try:
                keep(k, f.result())
            except CancelledError:
                # a lost worker took the scattered payload (or the task) with it: send the
                # chunk again with the payload itself, a bounded number of times
                retries[k] = retries.get(k, 0) + 1
                if retries[k] > _MAX_RETRIES:
                    raise
                futures[ex.submit(tasks.fn, tasks.payload, tasks.chunks[k], *tasks.args)] = k
            break


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


#: Address schemes of a Dask scheduler.
_SCHEMES = ("tcp", "tls", "ucx", "ws", "wss")
@contextlib.contextmanager
def dask_executor(address=None, *, workers=2, threads_per_worker=1, timeout=10.0,
                  security=None):
    """A ``concurrent.futures`` executor on a Dask cluster, closed on exit.

    An existing scheduler is trusted completely: whoever controls it, or can connect to an
    unsecured one, can run code in this process. Connect only to clusters you control, with
    TLS (``tls://`` and ``security=``) on a shared network.

    Parameters
    ----------
    address : str, optional
        The scheduler of an existing cluster (``tcp://host:8786``, ``tls://...``). Without it
        a ``distributed.LocalCluster`` of ``workers`` processes is started on 127.0.0.1,
        secured with TLS and temporary credentials (``Security.temporary()``): Dask moves
        pickles, so an open local cluster would let any user of a shared host who connects
        during the run execute code as you. Only this process holds the credentials.
    workers, threads_per_worker : int
        The local cluster's size: processes (the analytic and pixel models hold the GIL)
        of one thread each by default.
    timeout : float
        Seconds to wait for an existing scheduler to answer.
    security : distributed.security.Security, optional
        Credentials for an existing TLS cluster.

    Yields
    ------
    concurrent.futures.Executor
        The Dask client's executor (``Client.get_executor(pure=False)``); the client, and
        the local cluster if one was started, are closed on exit.

    Raises
    ------
    ParameterError
        When ``workers`` or ``threads_per_worker`` is not an integer ≥ 1, ``timeout`` is
        not in (0, 3600], a local cluster would have more than :data:`MAX_JOBS_PER_CORE`
        threads per core, ``address`` is not a ``scheme://host`` address with a scheme of
        tcp, tls, ucx, ws or wss, or no scheduler answers there within ``timeout``.
    ImportError
        When ``distributed`` (or, for a local cluster, ``cryptography``) is not installed.
    """
    workers = check_count("workers", workers)
    threads_per_worker = check_count("threads_per_worker", threads_per_worker)
    timeout = check_real("timeout", timeout, low=0.0, low_open=True, high=3600.0)
    cores = os.cpu_count() or 1
    if address is None and workers * threads_per_worker > MAX_JOBS_PER_CORE * cores:
        raise ParameterError(f"workers: {workers} local workers of {threads_per_worker} "
                             f"thread(s) is more than {MAX_JOBS_PER_CORE} per core on this "
                             f"{cores}-core machine (they only compete for the cores); give "
                             f"at most {MAX_JOBS_PER_CORE * cores // threads_per_worker}")
    try:
        from distributed import Client, LocalCluster
    except ImportError as exc:
        raise ImportError("Dask execution needs distributed: pip install 'meshladar[dask]'") \
            from exc
    cluster = None
    if address is None:
        try:
            from distributed.security import Security

            sec = Security.temporary()
        except ImportError as exc:
            raise ImportError("a local Dask cluster is secured with TLS, which needs "
                              "cryptography: pip install 'meshladar[dask]'") from exc
        import dask

        # no dashboard: the scheduler and every worker still open an HTTP port, which
        # serves plain, unauthenticated pages (task info, metrics) to any local user
        # unless their routes are emptied
        with dask.config.set({"distributed.scheduler.http.routes": [],
                              "distributed.worker.http.routes": []}):
            cluster = LocalCluster(n_workers=workers, threads_per_worker=threads_per_worker,
                                   processes=True, host="127.0.0.1", dashboard_address=None,
                                   security=sec, protocol="tls://")
        client = Client(cluster, security=sec)
    else:
        scheme = address.split("://", 1)[0] if isinstance(address, str) else None
        if scheme not in _SCHEMES or "://" not in address or not address.split("://", 1)[1]:
            raise ParameterError(f"scheduler must be an address such as tcp://host:8786 "
                                 f"(schemes {', '.join(_SCHEMES)}); got {address!r}")
        try:
            client = connect(Client, address, timeout, security)
        except Exception as exc:   # noqa: BLE001 - whatever answers that is not a scheduler
            # (an HTTP server's reply read as a message length asks for exabytes: MemoryError;
            # a server that accepts and says nothing: our own deadline's TimeoutError)
            raise ParameterError(f"scheduler: no Dask scheduler answered at {address!r} "
                                 f"within {timeout:g} s ({type(exc).__name__}: "
                                 f"{str(exc).splitlines()[0][:120] if str(exc) else ''})") \
                from exc
    try:
        yield client.get_executor(pure=False)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
