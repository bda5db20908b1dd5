"""Executors for the mesh engine's chunks of views: local processes or a Dask cluster.

Any ``concurrent.futures.Executor`` works (``simulate(..., executor=ex)``). For Dask::

    from meshladar.parallel import dask_executor
    with dask_executor("tcp://scheduler:8786") as ex:      # an existing cluster
        sino = ml.simulate(scene, ladar, model="mesh", executor=ex)
    with dask_executor(workers=2) as ex:                    # a local cluster on loopback
        ...

With a Dask executor the mesh is scattered to every worker once (not sent with each task),
and each worker builds its Embree scene once per mesh (cached by content hash). Workers
need meshladar (and so numpy, scipy, trimesh, embreex, numba) installed in the same version.
"""

from __future__ import annotations

import contextlib

__all__ = ["dask_executor"]


@contextlib.contextmanager
def dask_executor(address=None, *, workers=2, threads_per_worker=1):
    """A ``concurrent.futures`` executor on a Dask cluster, closed on exit.

    Parameters
    ----------
    address : str, optional
        The scheduler of an existing cluster (``tcp://host:8786``). Without it a
        ``distributed.LocalCluster`` of ``workers`` processes is started on 127.0.0.1.
    workers, threads_per_worker : int
        The local cluster's size (embreex holds the GIL while casting: one thread each).
    """
    try:
        from distributed import Client, LocalCluster
    except ImportError as exc:
        raise ImportError("Dask execution needs distributed: pip install 'meshladar[dask]'") \
            from exc
    cluster = None
    if address is None:
        cluster = LocalCluster(n_workers=int(workers), threads_per_worker=int(threads_per_worker),
                               processes=True, host="127.0.0.1", dashboard_address=None)
        client = Client(cluster)
    else:
        client = Client(address)
    try:
        yield client.get_executor(pure=False)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
