"""Mesh-engine benchmarks of ``meshladar bench``: throughput against raw embreex on the
same rays, the compiled loop against per-hit arrays, one view end to end, scene builds,
streaming and Dask."""

from __future__ import annotations

import json
import math
import statistics
import subprocess
import sys
import time
import time as _time

import numpy as np

from .. import materials
from ..ladar import Ladar
from ..meshes import fibonacci_sphere
from ..forward.mesh import simulate_mesh, trace
from ..raytrace import embree4
from ..raytrace.embree import Geometry, embree_scene
from ..raytrace.grid import ray_grid
from ..stream import dask_executor
from ..weighing import weigh
from .timing import icosphere_scene as _icosphere_scene
from .timing import interleaved

__all__ = ["bench_mesh", "bench_fused", "bench_single_view", "bench_streaming",
           "bench_dask"]


def bench_mesh(*, repeats=3, subdivisions=6, rays_per_view=1_000_000, views=16, build=True):
    """Mesh engine throughput against raw embreex on the same rays, and its build cost,
    timed in rounds (:func:`interleaved`), one process, the same rays. Returns a dict:
    ``raw_mrays`` (embreex's run() alone), ``packet_mrays`` (the packet backend's cast),
    ``pipeline_mrays`` (rays → hits → weights → bins, packets, one thread, regular grid),
    ``embreex_pipeline_mrays`` (the same through embreex), ``stratified_mrays``,
    ``raster_mrays`` (stratified, drawn: "raster", the default), ``two_thread_mrays``
    (packets, 2 threads), their ratios, ``packet_width``, and the build of a 1.3M-triangle
    mesh: embreex's upload and BVH (``upload_s``, ``bvh_s``) against the packet backend's
    shared-buffer scene (``packet_build_s``), unless ``build`` is False.

    The target: a dark gray icosphere of radius 0.5 (:func:`.timing.icosphere_scene`),
    ``views`` Fibonacci directions, 512 range bins over [−0.6, 0.6], ``mode="3d"``.

    Parameters
    ----------
    repeats : int, keyword-only
        Timed rounds after one warm-up round (default 3).
    subdivisions : int, keyword-only
        Icosphere subdivisions (default 6: 81,920 faces).
    rays_per_view : int, keyword-only
        Rays per view: the ray spacing is 1 / sqrt(``rays_per_view``) across the sphere's
        1 × 1 projected square (default 10⁶).
    views : int, keyword-only
        Fibonacci view directions (default 16).
    build : bool, keyword-only
        Also time the scene builds of an 8-subdivision icosphere (default True).

    Returns
    -------
    dict
        ``faces``, ``rays``, ``views``, ``packet_width``, the ``*_mrays`` (from median
        times), the ratios ``packet_over_raw``, ``pipeline_over_raw``,
        ``stratified_over_regular``, ``raster_over_raw``, ``raster_two_over_one``,
        ``two_over_one``, ``two_over_raw`` (of times: > 1 when the first named is faster);
        with ``build``, ``build_faces``, the build times ``upload_s``, ``bvh_s``,
        ``packet_build_s`` (s) and the ratios ``build_over_bvh`` (embreex's upload and BVH
        over its BVH) and ``packet_build_over_bvh``.
    """
    scene = _icosphere_scene(subdivisions, materials.DARK_GRAY)
    spacing = 1.0 / math.sqrt(rays_per_view)          # the sphere's 1 × 1 projected square
    vecs = fibonacci_sphere(views)
    ladar = Ladar(None, np.linspace(-0.6, 0.6, 513), view_vectors=vecs)
    geo = Geometry(scene, "flat")
    emb = embree_scene(geo, "embreex")
    pk = embree_scene(geo, "packets")
    grids = [ray_grid(geo, w, "3d", spacing, 0.0, None)[0] for w in vecs]
    dirs = [np.ascontiguousarray((-w)[None, :], dtype=np.float32) for w in vecs]
    n_rays = sum(len(o) for o in grids)

    def cast(engine):                # the same rays, one call per view
        def run():
            for o, d in zip(grids, dirs):
                engine.run(o, d, output=1)
        return run

    def pipeline(backend, jobs=1, sampling="regular"):
        return lambda: simulate_mesh(scene, ladar, mode="3d", ray_spacing=spacing, jobs=jobs,
                                     sampling=sampling, backend=backend)

    t = interleaved({"raw": cast(emb), "packet": cast(pk), "pipe": pipeline("packets"),
                     "pipe_embreex": pipeline("embreex"),
                     "stratified": pipeline("packets", sampling="stratified"),
                     "drawn": pipeline("raster", sampling="stratified"),
                     "drawn_two": pipeline("raster", jobs=2, sampling="stratified"),
                     "two": pipeline("packets", jobs=2)}, repeats=repeats)
    build = _build_split(8) if build else {}
    m = {k: n_rays / v / 1e6 for k, v in t.items()}
    return {"faces": len(geo.faces), "rays": n_rays, "views": views,
            "packet_width": embree4.library().width,
            "raw_mrays": m["raw"], "packet_mrays": m["packet"],
            "packet_over_raw": t["raw"] / t["packet"],
            "pipeline_mrays": m["pipe"], "pipeline_over_raw": t["raw"] / t["pipe"],
            "embreex_pipeline_mrays": m["pipe_embreex"],
            "stratified_mrays": m["stratified"],
            "stratified_over_regular": t["pipe"] / t["stratified"],
            "raster_mrays": m["drawn"], "raster_over_raw": t["raw"] / t["drawn"],
            "raster_two_over_one": t["drawn"] / t["drawn_two"],
            "two_thread_mrays": m["two"], "two_over_one": t["pipe"] / t["two"],
            "two_over_raw": t["raw"] / t["two"], **build}


def bench_fused(*, repeats=2, subdivisions=6, rays_per_view=1_000_000, views=4):
    """The cases the compiled loop took over from per-hit arrays, against the per-hit path
    (``trace`` + ``weigh``, the same packets cast), on the same rays in interleaved rounds,
    one thread: footprint binning, and a bistatic receiver 60° off the ladar (aluminium
    82k-face sphere; flat normals). Returns Mrays/s and the ratios.

    Each view's receiver direction is 0.5 w + (√3/2) u, u the unit horizontal vector
    w × z; the views are ``views`` Fibonacci directions with 512 range bins over
    [−0.6, 0.6], traced in ``mode="3d"`` with the packet backend.

    Parameters
    ----------
    repeats : int, keyword-only
        Timed rounds after one warm-up round (default 2).
    subdivisions : int, keyword-only
        Icosphere subdivisions (default 6: 81,920 faces).
    rays_per_view : int, keyword-only
        Rays per view: the ray spacing is 1 / sqrt(``rays_per_view``) (default 10⁶).
    views : int, keyword-only
        Fibonacci view directions (default 4).

    Returns
    -------
    dict
        ``faces`` (20 × 4^``subdivisions``), ``rays`` (all views), the throughputs in
        millions of rays per second ``footprint_mrays``, ``footprint_hits_mrays``,
        ``bistatic_mrays``, ``bistatic_hits_mrays`` and ``point_mrays`` (median times),
        and ``footprint_speedup`` and ``bistatic_speedup``: the per-hit path's time over
        the compiled loop's.
    """
    scene = _icosphere_scene(subdivisions, materials.ALUMINUM)
    spacing = 1.0 / math.sqrt(rays_per_view)
    ladar = Ladar(None, np.linspace(-0.6, 0.6, 513), view_vectors=fibonacci_sphere(views))
    w = ladar.view_vectors
    # a receiver 60° from each view, about the view's own horizontal axis
    side = np.cross(w, [0.0, 0.0, 1.0])
    side /= np.maximum(np.linalg.norm(side, axis=1, keepdims=True), 1e-12)
    receiver = 0.5 * w + (math.sqrt(3) / 2) * side
    run = {"mode": "3d", "ray_spacing": spacing, "jobs": 1, "backend": "packets"}

    t = interleaved({
        "footprint": lambda: simulate_mesh(scene, ladar, footprint=True, **run),
        "footprint_hits": lambda: weigh(trace(scene, ladar, **run), footprint=True),
        "bistatic": lambda: simulate_mesh(scene, ladar, receiver=receiver, **run),
        "bistatic_hits": lambda: weigh(trace(scene, ladar, receiver=receiver, **run)),
        "point": lambda: simulate_mesh(scene, ladar, **run)}, repeats=repeats)
    rays = simulate_mesh(scene, ladar, **run).info["rays"]
    n = float(np.sum(rays))
    m = {k: n / v / 1e6 for k, v in t.items()}
    return {"faces": 20 * 4 ** subdivisions, "rays": int(n), **{f"{k}_mrays": v
                                                              for k, v in m.items()},
            "footprint_speedup": t["footprint_hits"] / t["footprint"],
            "bistatic_speedup": t["bistatic_hits"] / t["bistatic"]}


def bench_single_view(*, subdivisions=6, rays=100_000, calls=30):
    """End-to-end time of one view of ``rays`` rays on a cached mesh (82k faces), default
    options (rows on threads from :data:`meshladar.stream.THREADS_FROM`, 5e4 rays) and one
    thread: medians of ``calls`` calls.

    The view: direction (0.3, −0.4, 0.866) of a dark gray icosphere of radius 0.5, 512
    range bins over [−0.6, 0.6]; each setting runs once untimed first.

    Parameters
    ----------
    subdivisions : int, keyword-only
        Icosphere subdivisions (default 6: 81,920 faces).
    rays : int, keyword-only
        Rays of the view: the ray spacing is 1 / sqrt(``rays``) (default 10⁵).
    calls : int, keyword-only
        Timed calls of each setting (default 30).

    Returns
    -------
    dict
        ``rays``: the rays cast per call; ``default_ms`` and ``one_thread_ms``: the median
        wall times in milliseconds.
    """
    scene = _icosphere_scene(subdivisions, materials.DARK_GRAY)
    ladar = Ladar(None, np.linspace(-0.6, 0.6, 513), view_vectors=[[0.3, -0.4, 0.866]])
    spacing = 1.0 / math.sqrt(rays)
    out = {}
    for name, jobs in (("default", None), ("one_thread", 1)):
        simulate_mesh(scene, ladar, ray_spacing=spacing, jobs=jobs)
        ts = []
        for _ in range(calls):
            t0 = time.perf_counter()
            sino = simulate_mesh(scene, ladar, ray_spacing=spacing, jobs=jobs)
            ts.append(time.perf_counter() - t0)
        out[f"{name}_ms"] = 1e3 * statistics.median(ts)
    return {"rays": int(sino.info["rays"]), **out}


def _build_split(subdivisions):
    """Scene builds of an icosphere (8 subdivisions: 1.3M triangles): embreex's upload loop
    against its BVH build (commit on the first query), and the packet backend's scene
    (shared numpy buffers, then the same robust BVH build)."""
    import trimesh

    ico = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    v, f = np.asarray(ico.vertices, dtype=np.float64), np.asarray(ico.faces)
    from embreex import rtcore_scene
    from embreex.mesh_construction import TriangleMesh

    v32, f32 = np.ascontiguousarray(v, np.float32), np.ascontiguousarray(f, np.int32)
    sc = rtcore_scene.EmbreeScene(robust=True)
    t0 = _time.perf_counter()
    TriangleMesh(sc, v32, f32)
    t1 = _time.perf_counter()
    sc.run(np.array([[0, 0, 5]], np.float32), np.array([[0, 0, -1]], np.float32))
    t2 = _time.perf_counter()
    embree4.PacketGeometry(v32, f32, robust=True).release()
    t3 = _time.perf_counter()
    return {"build_faces": len(f), "upload_s": t1 - t0, "bvh_s": t2 - t1,
            "build_over_bvh": (t2 - t0) / (t2 - t1), "packet_build_s": t3 - t2,
            "packet_build_over_bvh": (t3 - t2) / (t2 - t1)}


def bench_streaming(*, views=360, rays_per_view=1_000_000, subdivisions=6, jobs=2):
    """The streaming run of the issue: ``views`` views × ~1e6 rays of an 82k-triangle
    sphere, binned per chunk. Runs in a fresh subprocess and reports its wall time and the
    peak RSS of it and its workers (ru_maxrss of the largest process).

    The run: the mesh model in ``mode="3d"`` on a dark gray icosphere of radius 0.5 from
    ``views`` Fibonacci directions, 1024 range bins over [−0.6, 0.6].

    Parameters
    ----------
    views : int, keyword-only
        Fibonacci view directions (default 360).
    rays_per_view : int, keyword-only
        Rays per view: the ray spacing is 1 / sqrt(``rays_per_view``) (default 10⁶).
    subdivisions : int, keyword-only
        Icosphere subdivisions (default 6: 81,920 faces).
    jobs : int, keyword-only
        Threads of the run (default 2).

    Returns
    -------
    dict
        ``seconds``: the run's wall time; ``rays``: rays cast; ``peak_rss_mb``: the peak
        resident memory in MiB (ru_maxrss / 1024, as Linux reports it in KiB);
        ``mrays``: millions of rays per second.

    Raises
    ------
    subprocess.CalledProcessError
        When the subprocess fails.
    """
    code = f"""
import json, math, resource, time
import numpy as np
from meshladar import materials
from meshladar.studies.timing import icosphere_scene as _icosphere_scene
from meshladar.ladar import Ladar
from meshladar.meshes import fibonacci_sphere
from meshladar.forward.mesh import simulate_mesh
scene = _icosphere_scene({subdivisions}, materials.DARK_GRAY)
ladar = Ladar(None, np.linspace(-0.6, 0.6, 1025), view_vectors=fibonacci_sphere({views}))
t = time.perf_counter()
sino = simulate_mesh(scene, ladar, mode="3d", ray_spacing=1.0 / math.sqrt({rays_per_view}),
                     jobs={jobs})
dt = time.perf_counter() - t
rss = max(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss,
          resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss) / 1024.0
print(json.dumps({{"seconds": dt, "rays": sino.info["rays"], "peak_rss_mb": rss}}))
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    res = json.loads(out.stdout.strip().splitlines()[-1])
    res["mrays"] = res["rays"] / res["seconds"] / 1e6
    return res


def bench_dask(*, views=360, rays_per_view=1_000_000, subdivisions=6, workers=2):
    """The streaming mesh run on a local Dask cluster of ``workers`` processes against the
    same run serially, in this process; and the per-task overhead (mean wall time of a no-op
    task through the executor). Returns a dict of seconds and the speed-up.

    The run: the mesh model in ``mode="3d"`` on a dark gray icosphere of radius 0.5 from
    ``views`` Fibonacci directions, 1024 range bins over [−0.6, 0.6]; serially with
    ``jobs=1``, then on the cluster's executor. The overhead is the mean of 200 no-op
    tasks submitted together, after one that waits for the workers.

    Parameters
    ----------
    views : int, keyword-only
        Fibonacci view directions (default 360).
    rays_per_view : int, keyword-only
        Rays per view: the ray spacing is 1 / sqrt(``rays_per_view``) (default 10⁶).
    subdivisions : int, keyword-only
        Icosphere subdivisions (default 6: 81,920 faces).
    workers : int, keyword-only
        Processes of the local Dask cluster (default 2).

    Returns
    -------
    dict
        ``views``; ``rays`` (the serial run's); ``serial_s`` and ``dask_s``: wall times in
        seconds; ``speedup``: ``serial_s / dask_s``; ``task_overhead_s``: seconds per
        no-op task; ``identical``: whether the two sinograms are equal to the bit.

    Raises
    ------
    ImportError
        When Dask's ``distributed`` (or ``cryptography``, for the cluster's TLS) is not
        installed (:func:`meshladar.stream.dask_executor`).
    ParameterError
        When ``workers`` is more processes per core than
        :func:`meshladar.stream.dask_executor` starts.
    """
    scene = _icosphere_scene(subdivisions, materials.DARK_GRAY)
    ladar = Ladar(None, np.linspace(-0.6, 0.6, 1025), view_vectors=fibonacci_sphere(views))
    spacing = 1.0 / math.sqrt(rays_per_view)
    t0 = _time.perf_counter()
    serial = simulate_mesh(scene, ladar, mode="3d", ray_spacing=spacing, jobs=1)
    t_serial = _time.perf_counter() - t0
    with dask_executor(workers=workers) as ex:
        ex.submit(int, 0).result()                           # workers up
        t0 = _time.perf_counter()
        futures = [ex.submit(int, k) for k in range(200)]
        [f.result() for f in futures]
        overhead = (_time.perf_counter() - t0) / 200
        t0 = _time.perf_counter()
        dist = simulate_mesh(scene, ladar, mode="3d", ray_spacing=spacing, executor=ex)
        t_dask = _time.perf_counter() - t0
    same = bool(np.array_equal(serial.values, dist.values))
    return {"views": views, "rays": serial.info["rays"], "serial_s": t_serial,
            "dask_s": t_dask, "speedup": t_serial / t_dask, "task_overhead_s": overhead,
            "identical": same}
