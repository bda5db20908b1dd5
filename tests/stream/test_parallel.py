"""Distributed execution: identical results on every executor, and surviving a lost worker."""

from __future__ import annotations

import os
import signal
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor

import numpy as np
import pytest

import meshladar as ml

pytest.importorskip("distributed")
from meshladar.stream import dask_executor  # noqa: E402

from conftest import PAIR  # noqa: E402  (the shared disk pair)


@pytest.fixture(scope="module")
def job():
    mesh = PAIR.tessellate(512)
    ladar = ml.Ladar.paper(angles_deg=np.arange(0.0, 360.0, 5.0))
    return mesh, ladar, ml.simulate(mesh, ladar, model="mesh", normals="smooth", jobs=1)


@pytest.mark.slow
def test_identical_results_on_every_executor(job):
    mesh, ladar, serial = job
    # each chunk of views is computed by the same code whatever runs it, and chunks write
    # disjoint rows: bitwise identical
    with ThreadPoolExecutor(2) as ex:
        np.testing.assert_array_equal(
            ml.simulate(mesh, ladar, model="mesh", normals="smooth", executor=ex).values,
            serial.values)
    with ProcessPoolExecutor(2) as ex:
        np.testing.assert_array_equal(
            ml.simulate(mesh, ladar, model="mesh", normals="smooth", executor=ex).values,
            serial.values)
    with dask_executor(workers=2) as ex:
        np.testing.assert_array_equal(
            ml.simulate(mesh, ladar, model="mesh", normals="smooth", executor=ex).values,
            serial.values)
        hits = ml.trace(mesh, ladar, normals="smooth", executor=ex)
        # re-weighed by numpy's SR model (norms by hypot), the compiled loop's kernel takes
        # square roots of sums of squares: equal to ~1e-15 relative
        np.testing.assert_allclose(ml.weigh(hits).values, serial.values, rtol=1e-12,
                                   atol=1e-12 * np.abs(serial.values).max())


@pytest.mark.slow
@pytest.mark.parametrize("model", ["analytic", "pixel"])
def test_every_model_runs_on_every_executor(model):
    # the stream is shared by the forward models: chunks of views on threads, processes and
    # Dask give the serial numbers bit for bit
    ladar = ml.Ladar.paper(angles_deg=np.arange(0.0, 360.0, 4.0))
    serial = ml.simulate(PAIR, ladar, model=model)
    with ThreadPoolExecutor(2) as ex:
        np.testing.assert_array_equal(ml.simulate(PAIR, ladar, model=model, executor=ex).values,
                                      serial.values)
    np.testing.assert_array_equal(ml.simulate(PAIR, ladar, model=model, jobs=2).values,
                                  serial.values)
    with dask_executor(workers=2) as ex:
        np.testing.assert_array_equal(ml.simulate(PAIR, ladar, model=model, executor=ex).values,
                                      serial.values)


@pytest.mark.slow
def test_a_killed_worker_does_not_change_the_answer(job):
    mesh, _, _ = job
    ladar = ml.Ladar.paper(angles_deg=np.arange(0.0, 360.0, 1.0))
    serial = ml.simulate(mesh, ladar, model="mesh", rays_per_bin=64, jobs=1)
    with dask_executor(workers=2) as ex:
        client = ex._client
        pids = list(client.run(os.getpid).values())
        pending_at_kill = []

        class KillAfterFirstChunk:
            """The Dask executor, killing a worker the moment the first chunk is done
            (an event, not a delay): the others are still queued or running then."""

            _client = client

            def __init__(self):
                self.futures = []

            def submit(self, *args, **kwargs):
                f = ex.submit(*args, **kwargs)
                if not self.futures:
                    f.add_done_callback(self._kill)
                self.futures.append(f)
                return f

            def _kill(self, _):
                pending_at_kill.append(sum(not f.done() for f in self.futures))
                os.kill(pids[0], signal.SIGKILL)

        got = ml.simulate(mesh, ladar, model="mesh", rays_per_bin=64,
                          executor=KillAfterFirstChunk())
    # 45 chunks of 8 views: most were still to do when the worker died
    assert pending_at_kill and pending_at_kill[0] > 0
    np.testing.assert_array_equal(got.values, serial.values)


@pytest.mark.slow
def test_a_worker_lost_while_the_mesh_is_scattered_is_retried(job):
    from distributed.comm.core import CommClosedError

    mesh, ladar, serial = job
    with dask_executor(workers=2) as ex:
        calls = []

        class FlakyClient:
            """The client whose first scatter fails as a lost worker makes it fail."""

            def scatter(self, *args, **kwargs):
                calls.append(1)
                if len(calls) == 1:
                    raise CommClosedError("in <TCP (closed) ...>: Stream is closed")
                return ex._client.scatter(*args, **kwargs)

        class Flaky:
            _client = FlakyClient()
            submit = staticmethod(ex.submit)

        got = ml.simulate(mesh, ladar, model="mesh", normals="smooth", executor=Flaky())
    assert len(calls) == 2                                    # failed once, then scattered
    np.testing.assert_array_equal(got.values, serial.values)


def test_the_local_cluster_is_tls_secured_and_refuses_strangers():
    from urllib.error import HTTPError
    from urllib.request import urlopen

    from distributed import Client

    with dask_executor(workers=1) as ex:
        address = ex._client.scheduler.address
        assert address.startswith("tls://127.0.0.1:")
        assert ex.submit(sum, [1, 2]).result() == 3
        # another local user without the temporary credentials cannot connect
        with pytest.raises((TypeError, OSError, TimeoutError)):
            Client(address, timeout=5)
        # nor read the cluster over plain HTTP: no dashboard, no info or metrics pages
        # (issue 29: the scheduler served them on 127.0.0.1:8787 and each worker on a port)
        info = ex._client.scheduler_info()
        ports = [info["services"]["dashboard"]] + [
            w["services"]["dashboard"] for w in info["workers"].values()
            if "dashboard" in w.get("services", {})]
        assert len(ports) == 2
        for port in ports:
            for page in ("info/main/workers.html", "metrics", "json/counts.json", "health"):
                with pytest.raises(HTTPError, match="404"):
                    urlopen(f"http://127.0.0.1:{port}/{page}", timeout=30)


@pytest.mark.parametrize("options, message", [
    ({"workers": 0}, r"workers must be an integer >= 1; got 0"),
    ({"workers": 1.5}, r"workers must be an integer >= 1; got 1.5"),
    ({"workers": 10**6}, r"workers: 1000000 local workers of 1 thread\(s\) is more than"),
    ({"timeout": 0}, r"timeout must be in \(0, 3600\]; got 0.0"),
    ({"threads_per_worker": -1}, r"threads_per_worker must be an integer >= 1"),
])
def test_cluster_sizes_are_checked_before_starting(options, message):
    """``workers=0`` hung waiting for a worker; 64 workers started on 2 cores."""
    with pytest.raises(ml.errors.ParameterError, match=message):
        with dask_executor(**options):
            pass


def _listener(reply):
    """A local server that is not a Dask scheduler: it answers like a web server, or
    accepts connections and never says a word. Returns its address and a function that
    stops it: the serving thread is woken by one last connection, joined, and every
    socket closed (no thread left blocked in accept on a closed socket, no socket left
    for the garbage collector)."""
    import socket
    import threading

    sock = socket.socket()
    sock.bind(("127.0.0.1", 0))
    sock.listen()
    held, stopping = [], threading.Event()

    def serve():
        while True:
            conn, _ = sock.accept()
            held.append(conn)
            if stopping.is_set():
                return
            if reply:
                conn.sendall(b"HTTP/1.0 200 OK\r\nContent-Length: 5\r\n\r\nhello")

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()

    def stop():
        stopping.set()
        with socket.create_connection(sock.getsockname()):
            thread.join()
        for conn in held:
            conn.close()
        sock.close()

    return f"tcp://127.0.0.1:{sock.getsockname()[1]}", stop


@pytest.mark.parametrize("reply", [True, False], ids=["web-server", "silent"])
def test_something_that_is_not_a_scheduler_is_refused(reply):
    """issue 29: a web server's reply was read as a message length (a MemoryError
    traceback); a silent server hung the client for minutes despite ``timeout``."""
    address, stop = _listener(reply)
    try:
        with pytest.raises(ml.errors.ParameterError,
                           match=f"^scheduler: no Dask scheduler answered at '{address}'"):
            with dask_executor(address, timeout=1):
                pass
    finally:
        stop()


@pytest.mark.parametrize("address, message", [
    ("not an address", "scheduler must be an address such as tcp://host:8786"),
    ("udp://127.0.0.1:8786", "scheduler must be an address"),
    ("tcp://", "scheduler must be an address"),
    pytest.param("tcp://127.0.0.1:1", "no Dask scheduler answered at 'tcp://127.0.0.1:1'",
                 marks=pytest.mark.slow),         # waits out the connection timeout
])
def test_a_bad_scheduler_is_one_clear_error(address, message, tmp_path, capsys):
    with pytest.raises(ml.errors.ParameterError, match=message):
        with dask_executor(address, timeout=2):
            pass
    from meshladar.cli import main

    code = main(["simulate", "disk", "--model", "mesh", "--views", "2", "--scheduler", address,
                 "-o", str(tmp_path / "x.npz")])
    err = capsys.readouterr().err
    assert code == 2 and message in err and err.count("\n") == 1
