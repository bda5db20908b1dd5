"""Executors for the mesh engine's chunks of views: local processes or a Dask cluster.

Any ``concurrent.futures.Executor`` works (``simulate(..., executor=ex)``). For Dask::

    from meshladar.parallel import dask_executor
    with dask_executor("tcp://scheduler:8786") as ex:      # an existing cluster
        sino = ml.simulate(scene, ladar, model="mesh", executor=ex)
    with dask_executor(workers=2) as ex:     # a local cluster on loopback, TLS-secured
        ...

With a Dask executor the mesh is scattered to every worker once (not sent with each task),
and each worker builds its Embree scene once per mesh (cached by content hash). Workers
need meshladar (and so numpy, scipy, trimesh, embreex, numba) installed in the same version.
"""

from __future__ import annotations

import contextlib

__all__ = ["dask_executor"]


#: Address schemes of a Dask scheduler.
_SCHEMES = ("tcp", "tls", "ucx", "ws", "wss")


@contextlib.contextmanager
def dask_executor(address=None, *, workers=2, threads_per_worker=1, timeout=10.0,
                  security=None):
    """A ``concurrent.futures`` executor on a Dask cluster, closed on exit.

    Parameters
    ----------
    address : str, optional
        The scheduler of an existing cluster (``tcp://host:8786``, ``tls://...``). Without it
        a ``distributed.LocalCluster`` of ``workers`` processes is started on 127.0.0.1,
        secured with TLS and temporary credentials (``Security.temporary()``): Dask moves
        pickles, so an open local cluster would let any user of a shared host who connects
        during the run execute code as you. Only this process holds the credentials.
    workers, threads_per_worker : int
        The local cluster's size (embreex holds the GIL while casting: one thread each).
    timeout : float
        Seconds to wait for an existing scheduler to answer.
    security : distributed.security.Security, optional
        Credentials for an existing TLS cluster.

    An existing scheduler is trusted completely: whoever controls it, or can connect to an
    unsecured one, can run code in this process. Connect only to clusters you control, with
    TLS (``tls://`` and ``security=``) on a shared network.
    """
    try:
        from distributed import Client, LocalCluster
    except ImportError as exc:
        raise ImportError("Dask execution needs distributed: pip install 'meshladar[dask]'") \
            from exc
    from .errors import ParameterError

    cluster = None
    if address is None:
        try:
            from distributed.security import Security

            sec = Security.temporary()
        except ImportError as exc:
            raise ImportError("a local Dask cluster is secured with TLS, which needs "
                              "cryptography: pip install 'meshladar[dask]'") from exc
        cluster = LocalCluster(n_workers=int(workers), threads_per_worker=int(threads_per_worker),
                               processes=True, host="127.0.0.1", dashboard_address=None,
                               security=sec, protocol="tls://")
        client = Client(cluster, security=sec)
    else:
        scheme = address.split("://", 1)[0] if isinstance(address, str) else None
        if scheme not in _SCHEMES or "://" not in address or not address.split("://", 1)[1]:
            raise ParameterError(f"scheduler must be an address such as tcp://host:8786 "
                                 f"(schemes {', '.join(_SCHEMES)}); got {address!r}")
        try:
            client = Client(address, timeout=timeout, security=security)
        except (OSError, TimeoutError, ValueError, TypeError) as exc:
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
