"""The fused loops' scratch buffers (meshladar.weighing._scratch): kept per thread and
reused from view to view, so a loop must read no slot it has not written for the same
band. Buffers filled with junk (NaN, huge and negative numbers, True flags, the packet
workspace included) give the sinograms of new buffers bit for bit, and those agree with
embreex's per-hit path, which uses none of them."""

import importlib
import pkgutil
import threading

import numba
import numpy as np
import pytest
import trimesh
from numba.core.dispatcher import Dispatcher

import meshladar as ml
import meshladar.weighing
from meshladar.materials import ALUMINUM, DARK_GRAY
from meshladar.weighing import _scratch
from meshladar.weighing._compiled import njit_loop

#: The fused loop against the per-hit path (their summation orders differ).
SAME_RTOL = 1e-12

KINDS = {
    "flat": dict(),
    "footprint": dict(footprint=True),
    "smooth": dict(normals="smooth"),
    "bistatic": dict(receiver=(0.3, 0.5, 0.81), radiometry="power"),
    "sensor": dict(sensor=ml.sensor.Sensor(standoff=20.0), radiometry="power"),
}


def _poison(tree, rng):
    """Junk in every array of a scratch tuple (nested), in place."""
    if isinstance(tree, tuple):
        for item in tree:
            _poison(item, rng)
    elif isinstance(tree, np.ndarray):
        if tree.dtype == np.bool_:
            tree[...] = True
        elif tree.dtype.kind == "f":
            tree[...] = np.where(rng.random(tree.shape) < 0.5, np.nan, -3e38)
        else:
            tree[...] = rng.integers(-2**31, 2**31 - 1, tree.shape).astype(tree.dtype)


def _box(center, extents, material):
    b = trimesh.creation.box(extents)
    b.apply_translation(center)
    return ml.meshes.MeshPart(np.asarray(b.vertices), np.asarray(b.faces), material,
                              name="box")


def _run(scene, ladar, options, backend="packets"):
    return ml.simulate(scene, ladar, model="mesh", backend=backend, rays_per_bin=3, jobs=1,
                       **options)


@pytest.fixture(autouse=True)
def _own_buffers():
    """Each test starts with new buffers and leaves the thread's as they were."""
    held = getattr(_scratch._HELD, "buffers", None)
    _scratch._HELD.buffers = {}
    yield
    if held is None:
        del _scratch._HELD.buffers
    else:
        _scratch._HELD.buffers = held


@pytest.mark.parametrize("kind", list(KINDS))
def test_junk_in_reused_buffers_changes_no_bit(kind, monkeypatch):
    scene = ml.Scene.from_parts(
        [ml.meshes.sphere((0.1, -0.2, 0.3), 0.5, 0, subdivisions=3),
         _box((2.5, 0.0, 0.0), (0.2, 0.4, 0.3), 1)], [DARK_GRAY, ALUMINUM])
    ladar = ml.Ladar.covering(scene, n_bins=48, view_vectors=ml.meshes.fibonacci_sphere(4))
    options = KINDS[kind]
    fresh = _run(scene, ladar, options)
    assert _scratch._HELD.buffers, "the fused loop took no buffers from the scratch"
    rng = np.random.default_rng(5)
    poisoned = []

    def junk_scratch(*args):
        buffers = _scratch.scratch(*args)
        _poison(buffers, rng)                           # junk before every view
        poisoned.append(args)
        return buffers

    from meshladar.weighing import fused, sensor_view
    monkeypatch.setattr(fused, "scratch", junk_scratch)
    monkeypatch.setattr(sensor_view, "scratch", junk_scratch)
    again = _run(scene, ladar, options)
    assert len(poisoned) == 4                           # every view's buffers
    np.testing.assert_array_equal(again.values, fresh.values)
    ref = _run(scene, ladar, options, backend="embreex")
    assert fresh.values.max() > 0
    np.testing.assert_allclose(fresh.values, ref.values, rtol=SAME_RTOL,
                               atol=SAME_RTOL * ref.values.max())


def test_buffers_grow_for_longer_rows_are_reused_and_are_per_thread():
    small = _scratch.scratch("flat", 16, 10)
    assert small[1][3][0].size == 4 * 10                        # a 4-row tile's band
    big = _scratch.scratch("flat", 16, 100)
    assert big[1][3][0].size == 4 * 100 and big is not small
    assert _scratch.scratch("flat", 16, 50) is big              # shorter rows: reused
    grown = _scratch.scratch("flat", 16, 101)                    # grows by a quarter
    assert grown[1][3][0].size == 500
    assert _scratch.scratch("smooth", 16, 50)[1][3][3].size == 200   # barycentrics
    assert _scratch.scratch("flat", 8, 50)[1][3][0].size == 100      # 2 × 4 tiles
    other = []
    t = threading.Thread(target=lambda: other.append(_scratch.scratch("flat", 16, 50)))
    t.start()
    t.join()
    assert other[0] is not _scratch.scratch("flat", 16, 50)
    ws = grown[0]
    assert ws[3] % 64 == 0 and ws[2].ctypes.data == ws[3]       # 64-aligned workspace


@pytest.mark.parametrize("width", [4, 8])
@pytest.mark.parametrize("kind", ["flat", "bistatic", "sensor"])
def test_narrower_packets_take_buffers_of_their_own_tiles(kind, width, monkeypatch):
    """At packet widths 8 and 4 (tiles of 2 rows: the CPUs without AVX-512) the fused
    loops' buffers hold their bands, and the sinograms agree with the per-hit path's."""
    from meshladar.raytrace import embree4

    scene = ml.Scene.from_parts([ml.meshes.sphere((0.1, -0.2, 0.3), 0.5, 0, subdivisions=3)],
                                [DARK_GRAY])
    ladar = ml.Ladar.covering(scene, n_bins=48, view_vectors=ml.meshes.fibonacci_sphere(3))
    lib = embree4.library()
    assert lib.native[width]
    monkeypatch.setattr(lib, "width", width)
    narrow = _run(scene, ladar, KINDS[kind])
    assert {w for kind_, w in _scratch._HELD.buffers} == {width}
    ref = _run(scene, ladar, KINDS[kind], backend="embreex")
    assert narrow.values.max() > 0
    np.testing.assert_allclose(narrow.values, ref.values, rtol=SAME_RTOL,
                               atol=SAME_RTOL * ref.values.max())


@njit_loop()
def _allocates(n):                                        # pragma: no cover - compiled
    return np.empty(n).sum()


def test_a_weigh_loop_cannot_allocate():
    """The loops are compiled without numba's runtime (meshladar.weighing._compiled):
    one that allocated fails to compile instead."""
    with pytest.raises(numba.core.errors.TypingError):
        _allocates(3)


def test_every_weigh_loop_is_compiled_without_the_runtime():
    """Every compiled function defined in the weigh stage's modules but the one that makes
    its own buffer (footprint_rows)."""
    modules = [importlib.import_module(f"meshladar.weighing.{m.name}")
               for m in pkgutil.iter_modules(meshladar.weighing.__path__)]
    loops = {f"{m.__name__}.{k}": v.targetoptions.get("_nrt", True)
             for m in modules for k, v in vars(m).items() if isinstance(v, Dispatcher)
             and v.py_func.__module__ == m.__name__}
    assert loops.pop("meshladar.weighing._kernels.footprint_rows") is True
    assert len(loops) >= 25 and not any(loops.values()), loops
