"""The executors a streaming run's chunks go to (:mod:`meshladar.stream`): the choice
between this thread, a pool of threads or of worker processes, and a user's executor; the
worker processes' set-up and their prompt stop when a run is interrupted; the submission of
chunks to an executor, with the payload scattered once to a Dask cluster's workers and a
chunk whose worker was lost sent again; and the Dask executor itself.

:mod:`meshladar.stream` re-exports the public names (``meshladar.stream.choose_executor``,
``meshladar.stream.dask_executor``, ...), where they are documented.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from concurrent.futures import (CancelledError, ProcessPoolExecutor, ThreadPoolExecutor,
                                as_completed)

import numpy as np

from ._dask import connect
from ._validate import check_count, check_real
from .errors import ParameterError

__all__ = ["check_jobs", "choose_executor", "in_worker", "dask_executor", "thread_pool",
           "HEAP_THRESHOLDS", "MAX_JOBS_PER_CORE", "THREADS_FROM", "PARALLEL_FROM"]

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
        return thread_pool(min(jobs, max(1, n_chunks))), True
    return ProcessPoolExecutor(max_workers=int(jobs), initializer=_worker_init), True


#: glibc malloc's thresholds once a run starts threads: blocks above 32 MiB are mapped
#: from the system, and a heap's free top beyond 64 MiB is given back (M_MMAP_THRESHOLD,
#: M_TRIM_THRESHOLD). These are the largest values glibc's own dynamic thresholds reach
#: (DEFAULT_MMAP_THRESHOLD_MAX and twice it), which a process's main heap soon has; the
#: heaps of threads kept giving their pages back and faulting them in again, chunk after
#: chunk: a scan's chunks on two threads took 8,000 page faults and ran 1.3x one thread,
#: 1.85x with these (``meshladar.studies.bench_scan``). A process keeps up to 64 MiB free
#: per heap (one per thread) after a run.
HEAP_THRESHOLDS = {"mmap": 32 << 20, "trim": 64 << 20}
_HEAP_SET = []
#: Environment variables with which a user sets glibc malloc's thresholds: then left alone.
_MALLOC_ENV = ("MALLOC_MMAP_THRESHOLD_", "MALLOC_TRIM_THRESHOLD_", "MALLOC_TOP_PAD_",
               "MALLOC_MMAP_MAX_")


def thread_pool(workers):
    """A pool of ``workers`` threads for a run's compiled loops (which release the GIL),
    with the heap thresholds set (:data:`HEAP_THRESHOLDS`), its threads all started
    before it is returned: every thread pool of meshladar's runs is made here.

    ``ThreadPoolExecutor`` starts a thread per task while none is idle, ``submit`` waiting
    until it runs, which needs the GIL: started so, a scan's second thread waited behind
    the first chunk's Python and the first chunk behind it (two threads 1.46-1.52× one in
    ``bench_scan(rounds=7)``; 1.74-1.80× with the threads started here, at a barrier).

    Parameters
    ----------
    workers : int
        Threads.

    Returns
    -------
    concurrent.futures.ThreadPoolExecutor
        The pool (the caller shuts it down).

    Raises
    ------
    RuntimeError
        When a thread cannot be started (the threads already started end).
    """
    _steady_heap()
    workers = max(1, int(workers))
    pool = ThreadPoolExecutor(max_workers=workers)
    met = threading.Barrier(workers, timeout=_START_BOUND)
    try:
        for f in [pool.submit(met.wait) for _ in range(workers)]:
            f.result()
    except BaseException:                # no thread, or interrupted: free those waiting
        met.abort()
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    return pool


#: Seconds a new pool's threads may take to meet (:func:`thread_pool`; they meet in
#: microseconds): only a pool that started fewer threads than tasks (not CPython's) would
#: wait so long, and it then fails with BrokenBarrierError instead of waiting for ever.
_START_BOUND = 60.0


def _steady_heap():
    """Set :data:`HEAP_THRESHOLDS` once per process, under glibc only, unless the process
    was started with malloc's thresholds set (:data:`_MALLOC_ENV`, or GLIBC_TUNABLES naming
    glibc.malloc): glibc reads them at start only, so the environment it started with is
    what counts (Dask's nanny puts MALLOC_TRIM_THRESHOLD_ in os.environ for its workers,
    which changes nothing in this process)."""
    if _HEAP_SET:
        return
    _HEAP_SET.append(True)
    try:
        glibc = os.confstr("CS_GNU_LIBC_VERSION") or ""
    except (AttributeError, ValueError, OSError):
        glibc = ""
    start = _starting_environment()
    if (not glibc.startswith("glibc") or any(k in start for k in _MALLOC_ENV)
            or "glibc.malloc" in start.get("GLIBC_TUNABLES", "")):
        return
    import ctypes

    mallopt = ctypes.CDLL(None).mallopt
    mallopt(-3, HEAP_THRESHOLDS["mmap"])                   # M_MMAP_THRESHOLD
    mallopt(-1, HEAP_THRESHOLDS["trim"])                   # M_TRIM_THRESHOLD


def _starting_environment():
    """The environment this process started with (Linux: /proc/self/environ, which later
    changes to os.environ do not touch); os.environ where it cannot be read."""
    try:
        with open("/proc/self/environ", "rb") as f:
            pairs = f.read().split(b"\0")
    except OSError:
        return dict(os.environ)
    return dict(p.decode("utf-8", "replace").partition("=")[::2] for p in pairs if p)


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
    results = getattr(ex, "_result_queue", None)
    wakeup = getattr(ex, "_executor_manager_thread_wakeup", None)
    ex.shutdown(wait=False, cancel_futures=True)
    # this process's ends of the pool's pipes are closed while every worker still holds its
    # own, so none of them is closed twice: the manager closes the task pipe's read end
    # itself once it sees a worker gone (and two threads closing one descriptor race). The
    # feeder thread may be blocked writing a task no worker will read: nobody joins it (the
    # queue is abandoned), and with the workers gone its write fails (cpython gh-94777). The
    # manager may be reading the rest of a result a worker was sending when it ended: with
    # the workers gone this process's write end was the last, and the read meets the end.
    if queue is not None:
        queue.cancel_join_thread()
        queue._reader.close()
    if results is not None:
        results._writer.close()
    for p in list(processes.values()):
        if p.is_alive():
            p.terminate()
    for p in list(processes.values()):
        p.join(_STOP_GRACE_S)              # one caught mid-start may not take SIGTERM yet:
        if p.is_alive():                   # then SIGKILL, so the stop always completes
            p.kill()
            p.join()
    # and the manager woken to notice the dead workers
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


def _on_executor(ex, tasks, todo, keep):
    """Run the chunks ``todo`` on ``ex``, ``keep(k, result)`` as each completes (one pass
    of ``as_completed`` a round of submissions: linear in the chunks)."""
    shared = _scatter(ex, tasks.payload)
    futures = {ex.submit(tasks.fn, shared, tasks.chunks[k], *tasks.args): k for k in todo}
    retries = {}
    while futures:
        again = {}
        for f in as_completed(futures):
            k = futures.pop(f)                        # (as_completed holds its own set)
            try:
                keep(k, f.result())
            except CancelledError:
                # a lost worker took the shared payload: resend with it, a few times
                retries[k] = retries.get(k, 0) + 1
                if retries[k] > _MAX_RETRIES:
                    raise
                again[ex.submit(tasks.fn, tasks.payload, tasks.chunks[k], *tasks.args)] = k
        futures = again


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
        cluster, sec = _local_cluster(LocalCluster, workers, threads_per_worker)
        client = Client(cluster, security=sec)
    else:
        client = _scheduler_client(Client, address, timeout, security)
    try:
        yield client.get_executor(pure=False)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def _local_cluster(cluster_class, workers, threads_per_worker):
    """A ``distributed.LocalCluster`` (``cluster_class``) of ``workers`` processes on
    127.0.0.1, secured with TLS and temporary credentials and serving no HTTP pages; and
    those credentials, which only this process holds (its client needs them)."""
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
        cluster = cluster_class(n_workers=workers, threads_per_worker=threads_per_worker,
                                processes=True, host="127.0.0.1", dashboard_address=None,
                                security=sec, protocol="tls://")
    return cluster, sec


def _scheduler_client(client_class, address, timeout, security):
    """A ``distributed.Client`` (``client_class``) of the existing scheduler at ``address``,
    once the address is checked (a ``scheme://host`` of :data:`_SCHEMES`); ParameterError
    when nothing answers there as a Dask scheduler within ``timeout`` seconds."""
    scheme = address.split("://", 1)[0] if isinstance(address, str) else None
    if scheme not in _SCHEMES or "://" not in address or not address.split("://", 1)[1]:
        raise ParameterError(f"scheduler must be an address such as tcp://host:8786 "
                             f"(schemes {', '.join(_SCHEMES)}); got {address!r}")
    try:
        return connect(client_class, address, timeout, security)
    except Exception as exc:   # noqa: BLE001 - whatever answers that is not a scheduler
        # (an HTTP server's reply read as a message length asks for exabytes: MemoryError;
        # a server that accepts and says nothing: our own deadline's TimeoutError)
        raise ParameterError(f"scheduler: no Dask scheduler answered at {address!r} "
                             f"within {timeout:g} s ({type(exc).__name__}: "
                             f"{str(exc).splitlines()[0][:120] if str(exc) else ''})") \
            from exc
