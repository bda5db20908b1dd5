"""Distributed execution: identical results on every executor, and surviving a lost worker."""

from __future__ import annotations

import os
import signal
import threading
import time
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor

import numpy as np
import pytest

import meshladar as ml
from meshladar.materials import ALUMINUM, DARK_GRAY

pytest.importorskip("distributed")
from meshladar.parallel import dask_executor  # noqa: E402

PAIR = ml.Scene([ml.Disk((-0.3, 0.0), 0.4, DARK_GRAY), ml.Disk((0.4, 0.0), 0.3, ALUMINUM)])


@pytest.fixture(scope="module")
def job():
    mesh = PAIR.tessellate(512)
    ladar = ml.Ladar.paper(angles_deg=np.arange(0.0, 360.0, 5.0))
    return mesh, ladar, ml.simulate(mesh, ladar, model="mesh", normals="smooth", jobs=1)


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
        np.testing.assert_array_equal(ml.weigh(hits).values, serial.values)


def test_a_killed_worker_does_not_change_the_answer(job):
    mesh, _, _ = job
    ladar = ml.Ladar.paper(angles_deg=np.arange(0.0, 360.0, 1.0))
    serial = ml.simulate(mesh, ladar, model="mesh", rays_per_bin=64, jobs=1)
    with dask_executor(workers=2) as ex:
        client = ex._client
        pids = list(client.run(os.getpid).values())
        killed = []

        def kill_one():
            time.sleep(0.5)
            os.kill(pids[0], signal.SIGKILL)
            killed.append(time.monotonic())

        t = threading.Thread(target=kill_one)
        t.start()
        got = ml.simulate(mesh, ladar, model="mesh", rays_per_bin=64, executor=ex)
        finished = time.monotonic()
        t.join()
    assert killed and killed[0] < finished                    # the worker died mid-run
    np.testing.assert_array_equal(got.values, serial.values)
