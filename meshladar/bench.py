"""Benchmarks: medians of several runs in one process (``meshladar bench``).

Speed is measured here, never in timed tests. Each case is run ``repeats`` times after one
warm-up run, and the median, minimum and maximum wall times are reported.
"""

from __future__ import annotations

import statistics
import time

__all__ = ["time_call", "bench_analytic", "bench_fbp", "bench_mesh", "bench_sensor",
           "bench_tomography3d", "bench_sirt", "bench_streaming", "bench_dask", "report"]


def time_call(fn, *, repeats=5):
    """Wall times (s) of ``repeats`` calls of ``fn()`` after one warm-up call."""
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return times


def bench_analytic(*, repeats=5):
    """The paper's analytic sinograms (360 views × 512 bins of A/256): one row per case.

    Returns a list of dicts with ``case``, ``median_s``, ``min_s``, ``max_s``.
    """
    from . import forward, materials
    from .ladar import Ladar
    from .scene import Scene
    from .shapes import Disk, Ellipse

    gray, al = materials.DARK_GRAY, materials.ALUMINUM
    ladar = Ladar.paper()

    def pair(big, small):
        from . import phantoms

        return phantoms.scene("disk_pair", large=big, small=small)

    cases = {
        "disk pair, gray + gray": pair(gray, gray),
        "disk pair, aluminium + aluminium": pair(al, al),
        "disk pair, gray + aluminium": pair(gray, al),
        "disk pair, aluminium + gray": pair(al, gray),
        "ellipse A=0.6 B=0.3, aluminium": Scene([Ellipse((0.0, 0.0), (0.6, 0.3), 0.0, al)]),
        "disk A=0.8, aluminium (one profile)": Scene([Disk((0.0, 0.0), 0.8, al)]),
    }
    rows = []
    for name, scene in cases.items():
        t = time_call(lambda s=scene: forward.simulate(s, ladar), repeats=repeats)
        rows.append({"case": name, "median_s": statistics.median(t), "min_s": min(t),
                     "max_s": max(t)})
    return rows


def bench_fbp(*, n_bins=1024, size=1024, repeats=3, filter="ramp"):
    """FBP of a 360 × n_bins sinogram to size² against ``skimage.transform.iradon``.

    Both run in this process on the same data (the mixed disk pair's exact sinogram), with
    the same filter and linear interpolation, on the same grid (unit bins centred on
    k − n/2, pixel centres on scikit-image's grid, views 180° − φ). Returns a dict with both
    medians, their ratio and the largest difference relative to the image maximum.
    """
    import numpy as np

    try:
        from skimage.transform import iradon
    except ImportError as exc:
        raise ImportError("the FBP benchmark compares against scikit-image: "
                          "pip install 'meshladar[bench]'") from exc
    from . import forward, materials
    from .ladar import Ladar
    from . import phantoms
    from .reconstruct import fbp

    scene = phantoms.scene("disk_pair", large=materials.DARK_GRAY, small=materials.ALUMINUM)
    bw = 2.0 / n_bins
    ladar = Ladar(np.arange(360.0), (np.arange(n_bins + 1) - n_bins / 2 - 0.5) * bw)
    sino = forward.simulate(scene, ladar)
    ours = lambda: fbp(sino, size=size, extent=1.0, center=(-0.5 * bw, -0.5 * bw),  # noqa
                       filter=filter)
    theirs = lambda: iradon((sino.values / bw**2).T, theta=180.0 - sino.angles_deg,  # noqa
                            filter_name=filter, interpolation="linear", circle=False,
                            output_size=size)
    t_ours = time_call(ours, repeats=repeats)
    t_theirs = time_call(theirs, repeats=repeats)
    a, b = ours().values, theirs()
    return {"ours_s": statistics.median(t_ours), "skimage_s": statistics.median(t_theirs),
            "speedup": statistics.median(t_theirs) / statistics.median(t_ours),
            "max_diff_rel": float(np.max(np.abs(a - b)) / np.max(np.abs(b))),
            "shape": (360, n_bins), "size": size}


def _icosphere_scene(subdivisions, material):
    from .mesh import sphere
    from .scene import Scene

    return Scene.from_parts([sphere((0.0, 0.0, 0.0), 0.5, 0, subdivisions=subdivisions)],
                             [material])


def interleaved(fns, *, repeats=3):
    """Median wall time (s) of each of ``fns`` (a dict of name → callable), run in rounds
    (one call of each per round, after one warm-up round) so that a shared machine's load
    falls on all of them alike."""
    for fn in fns.values():
        fn()
    times = {k: [] for k in fns}
    for _ in range(repeats):
        for k, fn in fns.items():
            t0 = time.perf_counter()
            fn()
            times[k].append(time.perf_counter() - t0)
    return {k: statistics.median(v) for k, v in times.items()}


def bench_mesh(*, repeats=3, subdivisions=6, rays_per_view=1_000_000, views=16, build=True):
    """Mesh engine throughput against raw embreex on the same rays, and its build cost.

    Everything is timed in rounds (:func:`interleaved`) in one process on the same rays.
    Returns a dict: ``raw_mrays`` (embreex's run() alone), ``packet_mrays`` (the packet
    backend's cast alone), ``pipeline_mrays`` (rays → hits → weights → bins, packets, one
    thread, regular grid), ``embreex_pipeline_mrays`` (the same through embreex),
    ``stratified_mrays``, ``two_thread_mrays`` (packets, 2 threads), their ratios,
    ``packet_width``, and the build of a 1.3M-triangle mesh: embreex's upload and BVH
    (``upload_s``, ``bvh_s``) against the packet backend's shared-buffer scene
    (``packet_build_s``), unless ``build`` is False.
    """
    import math

    import numpy as np

    from . import materials
    from .ladar import Ladar
    from .mesh import fibonacci_sphere
    from .raytrace import embree4
    from .raytrace.embree import _embree_scene, _Geometry
    from .raytrace.grid import _ray_grid
    from .raytrace.model import simulate_mesh

    scene = _icosphere_scene(subdivisions, materials.DARK_GRAY)
    spacing = 1.0 / math.sqrt(rays_per_view)          # the sphere's 1 × 1 projected square
    vecs = fibonacci_sphere(views)
    ladar = Ladar(None, np.linspace(-0.6, 0.6, 513), view_vectors=vecs)
    geo = _Geometry(scene, "flat")
    emb = _embree_scene(geo, "embreex")
    pk = _embree_scene(geo, "packets")
    grids = [_ray_grid(geo, w, "3d", spacing, 0.0, None)[0] for w in vecs]
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
            "two_thread_mrays": m["two"], "two_over_one": t["pipe"] / t["two"],
            "two_over_raw": t["raw"] / t["two"], **build}


def bench_fused(*, repeats=2, subdivisions=6, rays_per_view=1_000_000, views=4):
    """The cases the compiled loop took over from per-hit arrays, against the per-hit path
    (``trace`` + ``weigh``, the same packets cast), on the same rays in interleaved rounds,
    one thread: footprint binning, and a bistatic receiver 60° off the ladar (aluminium
    82k-face sphere; flat normals). Returns Mrays/s and the ratios."""
    import math

    import numpy as np

    from . import materials
    from .ladar import Ladar
    from .mesh import fibonacci_sphere
    from .raytrace.model import simulate_mesh, trace
    from .weighing import weigh

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
    options (rows on threads from 5e4 rays) and one thread: medians of ``calls`` calls."""
    import math

    import numpy as np

    from . import materials
    from .ladar import Ladar
    from .raytrace.model import simulate_mesh

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
    import time as _time

    import numpy as np

    from .mesh import _icosphere
    from .raytrace import embree4

    v, f = _icosphere(subdivisions)
    from embreex import rtcore_scene
    from embreex.mesh_construction import TriangleMesh

    v32, f32 = np.ascontiguousarray(v, np.float32), np.ascontiguousarray(f, np.int32)
    sc = rtcore_scene.EmbreeScene(robust=True)
    t0 = _time.perf_counter()
    TriangleMesh(sc, v32, f32)
    t1 = _time.perf_counter()
    sc.run(np.array([[0, 0, 5]], np.float32), np.array([[0, 0, -1]], np.float32))
    t2 = _time.perf_counter()
    embree4.Scene(v32, f32, robust=True).release()
    t3 = _time.perf_counter()
    return {"build_faces": len(f), "upload_s": t1 - t0, "bvh_s": t2 - t1,
            "build_over_bvh": (t2 - t0) / (t2 - t1), "packet_build_s": t3 - t2,
            "packet_build_over_bvh": (t3 - t2) / (t2 - t1)}


def bench_streaming(*, views=360, rays_per_view=1_000_000, subdivisions=6, jobs=2):
    """The streaming run of the issue: ``views`` views × ~1e6 rays of an 82k-triangle
    sphere, binned per chunk. Runs in a fresh subprocess and reports its wall time and the
    peak RSS of it and its workers (ru_maxrss of the largest process)."""
    import json
    import subprocess
    import sys

    code = f"""
import json, math, resource, time
import numpy as np
from meshladar import materials
from meshladar.bench import _icosphere_scene
from meshladar.ladar import Ladar
from meshladar.mesh import fibonacci_sphere
from meshladar.raytrace import simulate_mesh
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
    task through the executor). Returns a dict of seconds and the speed-up."""
    import math
    import time as _time

    import numpy as np

    from . import materials
    from .ladar import Ladar
    from .mesh import fibonacci_sphere
    from .stream import dask_executor
    from .raytrace.model import simulate_mesh

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


def bench_sensor(*, subdivisions=6, rays_per_view=1_000_000, views=4, repeats=2):
    """Received power of an aluminium icosphere: the ladar at infinity (the compiled loop)
    against a sensor at a standoff of 100 radii (50 scene units) (perspective rays, weighed per hit in
    numpy), interleaved; and the waveforms of 360 views (receive)."""
    import math

    import numpy as np

    from . import materials
    from .forward import simulate
    from .ladar import Ladar
    from .receiver import GaussianPulse, receive
    from .sensor import Sensor

    scene = _icosphere_scene(subdivisions, materials.ALUMINUM)
    ladar = Ladar.covering(scene, n_bins=512, angles_deg=np.arange(float(views)))
    spacing = 1.0 / math.sqrt(rays_per_view)           # the sphere is 1 across
    far, near = {}, {}

    def run(sensor, out):
        def go():
            out["sino"] = simulate(scene, ladar, model="mesh", radiometry="power",
                                   sensor=sensor, ray_spacing=spacing, jobs=1)
        return go

    t = interleaved({"far": run(None, far), "near": run(Sensor(standoff=50.0), near)},
                    repeats=repeats)
    sino = simulate(scene, Ladar.covering(scene, n_bins=512), model="mesh",
                    radiometry="power", rays_per_bin=1)
    t_wave = time_call(lambda: receive(sino, sample_rate=20e9, pulse=GaussianPulse(1e-10)),
                       repeats=repeats)
    return {"faces": sum(len(p.faces) for p in scene.parts), "rays": far["sino"].info["rays"],
            "far_mrays": far["sino"].info["rays"] / t["far"] / 1e6,
            "near_mrays": near["sino"].info["rays"] / t["near"] / 1e6,
            "receive_s": float(np.median(t_wave)), "receive_shape": sino.shape}


def bench_tomography3d(*, views=200, size=128, subdivisions=6, jobs=2):
    """3-D reflective tomography of an 82k-face sphere part: the range profiles of ``views``
    Fibonacci directions (mesh model, received power, ``jobs`` threads), then their 3-D
    Radon inversion onto ``size``³ voxels; wall times of each (after a warm-up)."""
    from . import materials
    from .forward import simulate
    from .ladar import Ladar
    from .mesh import fibonacci_sphere
    from .volume import radon3d

    import numpy as np

    scene = _icosphere_scene(subdivisions, materials.DARK_GRAY)
    ladar = Ladar(None, np.linspace(-0.55, 0.55, size + 1),
                  view_vectors=fibonacci_sphere(views))
    sino = simulate(scene, ladar, model="mesh", radiometry="power", jobs=jobs)
    radon3d(sino, size=8, extent=0.55)                     # compile
    t0 = time.perf_counter()
    sino = simulate(scene, ladar, model="mesh", radiometry="power", jobs=jobs)
    t1 = time.perf_counter()
    radon3d(sino, size=size, extent=0.55)
    t2 = time.perf_counter()
    return {"faces": sum(len(p.faces) for p in scene.parts), "views": views, "size": size,
            "rays": sino.info["rays"], "simulate_s": t1 - t0, "reconstruct_s": t2 - t1}


def bench_sirt(*, size=512, n_views=360, iterations=50, skimage_iterations=2):
    """SIRT and SART (ordered subsets, 10 groups) of a 360 × 512 disk sinogram onto 512²
    (``iterations`` sweeps each, the linear projector pair) against scikit-image's
    ``iradon_sart`` on the same data (its time per sweep, from ``skimage_iterations``
    calls, times ``iterations``)."""
    import numpy as np

    from .iterative import sart, sirt
    from .sinogram import Sinogram

    edges = np.linspace(-1.0, 1.0, size + 1)
    phi = np.deg2rad(np.arange(n_views) * 360.0 / n_views)
    a, c = 0.4, np.array([0.1, 0.0])

    def prim(s):
        s = np.clip(s, -a, a)
        return s * np.sqrt(a * a - s * s) + a * a * np.arcsin(s / a)

    rc = -(c[0] * np.cos(phi) + c[1] * np.sin(phi))
    vals = prim(edges[None, 1:] - rc[:, None]) - prim(edges[None, :-1] - rc[:, None])
    sino = Sinogram(vals, angles_deg=np.degrees(phi), bin_edges=edges)
    sirt(sino, size=16, n_iter=1, projector="linear")                   # compile
    sart(sino, size=16, n_iter=1)
    t0 = time.perf_counter()
    sirt(sino, size=size, extent=1.0, n_iter=iterations, projector="linear")
    ours = time.perf_counter() - t0
    t0 = time.perf_counter()
    sart(sino, size=size, extent=1.0, n_iter=iterations)
    ours_sart = time.perf_counter() - t0
    try:
        from skimage.transform import iradon_sart
    except ImportError:
        return {"ours_s": ours, "sart_s": ours_sart, "skimage_s": None,
                "iterations": iterations}
    radon = (vals / (edges[1] - edges[0])).T.astype(np.float64)        # (positions, views)
    t0 = time.perf_counter()
    image = None
    for _ in range(skimage_iterations):
        image = iradon_sart(radon, theta=np.degrees(phi), image=image)
    per = (time.perf_counter() - t0) / skimage_iterations
    return {"ours_s": ours, "sart_s": ours_sart, "skimage_s": per * iterations,
            "iterations": iterations, "size": size, "views": n_views}


def bench_fit(*, subdivisions=6, views=36, n_bins=256, photons=1e5, repeats=3):
    """Two coatings fitted on an icosphere (20·4^6 = 81,920 faces; gray below z = 0,
    aluminium above) from 36 views spread over the sphere, Poisson counts with ``photons``
    in the brightest bin: the trace, the coating kernel, the fit (all eight SR parameters
    from a start 20-50 % off), and one re-weighing by the kernel against ``weigh`` on the
    same hits, interleaved."""
    import dataclasses

    import numpy as np

    from . import materials
    from .brdf import SandfordRobertson
    from .fitting import coating_kernel, fit_coatings
    from .ladar import Ladar
    from .mesh import fibonacci_sphere, sphere
    from .raytrace import trace
    from .scene import Scene
    from .sinogram import Sinogram
    from .weighing import weigh

    part = sphere((0.0, 0.0, 0.0), 0.5, 0, subdivisions=subdivisions)
    top = part.vertices[part.faces].mean(axis=1)[:, 2] > 0
    part = dataclasses.replace(part, material=top.astype(np.int64))
    scene = Scene.from_parts([part], [materials.DARK_GRAY, materials.ALUMINUM])
    ladar = Ladar.covering(scene, n_bins=n_bins, view_vectors=fibonacci_sphere(views))
    t0 = time.perf_counter()
    hits = trace(scene, ladar)
    t_trace = time.perf_counter() - t0
    t0 = time.perf_counter()
    kernel = coating_kernel(hits)
    t_kernel = time.perf_counter() - t0
    truth = kernel.predict()
    k = photons / float(truth.max())
    counts = np.random.default_rng(0).poisson(truth * k)
    measured = Sinogram(counts / k, angles_deg=ladar.angles_deg, bin_edges=ladar.bin_edges,
                        view_vectors=ladar.view_vectors)
    start = {0: SandfordRobertson(0.04, 0.7, 0.15, 0.25),
             1: SandfordRobertson(0.06, 0.45, 0.15, 0.01)}
    t0 = time.perf_counter()
    fit = fit_coatings(kernel, measured, noise="poisson", photons_per_unit=k, initial=start)
    t_fit = time.perf_counter() - t0
    t = interleaved({"kernel": lambda: kernel.predict(), "weigh": lambda: weigh(hits)},
                    repeats=repeats)
    true = [getattr(m, n) for m in (materials.DARK_GRAY, materials.ALUMINUM)
            for n in ("rho_d", "epsilon", "b", "e")]
    return {"faces": int(part.faces.shape[0]), "views": views, "hits": int(hits.view.size),
            "trace_s": t_trace, "kernel_s": t_kernel, "fit_s": t_fit,
            "total_s": t_trace + t_kernel + t_fit, "predict_s": t["kernel"],
            "weigh_s": t["weigh"],
            "max_z": float(np.max(np.abs((fit.estimate - true) / fit.stderr))),
            "iterations": fit.iterations}


def report(*, repeats=5, full=False):
    """The benchmark report, line by line (what ``meshladar bench`` prints): each model and
    FBP timed against its peer in the same process; ``full`` adds streaming and Dask."""
    yield (f"analytic model, 360 views x 512 bins (A/256), median of {repeats} runs after "
           "one warm-up")
    yield f"  {'case':<40} {'median [s]':>10} {'min [s]':>9} {'max [s]':>9}"
    for row in bench_analytic(repeats=repeats):
        yield (f"  {row['case']:<40} {row['median_s']:10.3f} {row['min_s']:9.3f} "
               f"{row['max_s']:9.3f}")
    try:
        r = bench_fbp(repeats=repeats)
    except ImportError as exc:
        yield f"FBP vs scikit-image: skipped ({exc})"
    else:
        yield (f"FBP {r['shape'][0]} x {r['shape'][1]} -> {r['size']}^2, ramp, linear: "
               f"meshladar {r['ours_s']:.3f} s, skimage.iradon {r['skimage_s']:.3f} s, "
               f"speed-up {r['speedup']:.1f}x, max |difference| {r['max_diff_rel']:.1e} of max")
    m = bench_mesh(repeats=repeats)
    yield (f"mesh engine, {m['faces']} triangles, {m['views']} views x "
           f"{m['rays'] // m['views']} rays (3-D grid), same rays in the same process:")
    yield f"  raw embreex cast (output=1)        {m['raw_mrays']:7.2f} Mrays/s"
    yield (f"  packet cast alone (width {m['packet_width']:2d})      {m['packet_mrays']:7.2f} "
           f"Mrays/s ({m['packet_over_raw']:.2f}x raw embreex)")
    yield (f"  pipeline, packets, 1 thread        {m['pipeline_mrays']:7.2f} Mrays/s "
           f"({m['pipeline_over_raw']:.2f}x raw embreex)")
    yield (f"  pipeline, embreex, 1 thread        {m['embreex_pipeline_mrays']:7.2f} Mrays/s")
    yield (f"  pipeline, stratified sampling      {m['stratified_mrays']:7.2f} Mrays/s "
           f"({100 * m['stratified_over_regular']:.0f}% of the regular grid's)")
    yield (f"  pipeline, packets, 2 threads       {m['two_thread_mrays']:7.2f} Mrays/s "
           f"({m['two_over_one']:.2f}x one, {m['two_over_raw']:.2f}x raw embreex)")
    for sub in (3, 8):                                 # 1.3k and 1.3M triangles
        o = bench_mesh(repeats=2, subdivisions=sub, views=4, build=False)
        yield (f"  {o['faces']:>8} triangles, 4 views: raw embreex {o['raw_mrays']:5.2f}, "
               f"packet cast {o['packet_mrays']:5.2f} ({o['packet_over_raw']:.2f}x), "
               f"pipeline {o['pipeline_mrays']:5.2f} ({o['pipeline_over_raw']:.2f}x), "
               f"2 threads {o['two_thread_mrays']:5.2f} Mrays/s")
    fu = bench_fused()
    yield (f"  compiled loop against per-hit arrays, {fu['faces']} triangles, 4 views x 1e6 "
           f"rays, 1 thread: footprint bins {fu['footprint_mrays']:.2f} against "
           f"{fu['footprint_hits_mrays']:.2f} Mrays/s ({fu['footprint_speedup']:.1f}x), "
           f"bistatic {fu['bistatic_mrays']:.2f} against {fu['bistatic_hits_mrays']:.2f} "
           f"({fu['bistatic_speedup']:.1f}x); point bins {fu['point_mrays']:.2f}")
    sv = bench_single_view()
    yield (f"  one view of {sv['rays']:,} rays on a cached mesh, end to end: "
           f"{sv['default_ms']:.1f} ms (default: its rows on threads), "
           f"{sv['one_thread_ms']:.1f} ms on one thread")
    yield (f"  build, {m['build_faces']} triangles: embreex upload {m['upload_s']:.2f} s + BVH "
           f"{m['bvh_s']:.2f} s = {m['build_over_bvh']:.1f}x the BVH; packet scene "
           f"{m['packet_build_s']:.2f} s = {m['packet_build_over_bvh']:.2f}x the BVH")
    se = bench_sensor()
    yield (f"received power, {se['faces']} triangles, {se['rays'] / 4:.3g} rays per view: at "
           f"infinity (compiled loop) {se['far_mrays']:.2f} Mrays/s, sensor at a standoff "
           f"(perspective, compiled loop) {se['near_mrays']:.2f} Mrays/s; waveforms of "
           f"{se['receive_shape'][0]} views x {se['receive_shape'][1]} bins at 20 GHz "
           f"{se['receive_s']:.3f} s")
    it = bench_sirt()
    head = f"{it['iterations']} sweeps 360 x 512 -> 512^2 (linear projector): "
    if it["skimage_s"] is None:
        yield f"{head}SIRT {it['ours_s']:.1f} s, SART (10 subsets) {it['sart_s']:.1f} s"
    else:
        yield (f"{head}SIRT {it['ours_s']:.1f} s, SART (10 subsets) {it['sart_s']:.1f} s; "
               f"skimage.iradon_sart {it['skimage_s']:.1f} s (per-sweep time x "
               f"{it['iterations']}), speed-up {it['skimage_s'] / it['ours_s']:.1f}x and "
               f"{it['skimage_s'] / it['sart_s']:.1f}x")
    fb = bench_fit()
    yield (f"coating fit, {fb['faces']} faces, {fb['views']} views ({fb['hits']:,} hits), two "
           f"SR coatings (8 parameters, Poisson): trace {fb['trace_s']:.1f} s + kernel "
           f"{fb['kernel_s']:.1f} s + fit {fb['fit_s']:.1f} s = {fb['total_s']:.1f} s "
           f"(every estimate within {fb['max_z']:.1f} sigma); one re-weighing: kernel "
           f"{fb['predict_s'] * 1e3:.0f} ms, weigh {fb['weigh_s'] * 1e3:.0f} ms "
           f"({fb['weigh_s'] / fb['predict_s']:.1f}x)")
    tb = bench_tomography3d()
    yield (f"3-D tomography, {tb['faces']} triangles, {tb['views']} views, {tb['size']}^3: "
           f"profiles {tb['simulate_s']:.1f} s ({tb['rays']:,} rays, 2 threads), inversion "
           f"{tb['reconstruct_s']:.1f} s, total {tb['simulate_s'] + tb['reconstruct_s']:.1f} s")
    if not full:
        return
    from . import peer

    pt = peer.bench_time_to_accuracy()
    if not pt["mitransient"]:
        yield f"Mitsuba 3 + mitransient: skipped ({peer.available(reason=True)[1][:200]})"
    else:
        for target, tools in pt["time_to"].items():
            yield (f"time to {target:g} relative L2, Lambertian {pt['faces']}-face sphere, "
                   f"received power: meshladar {tools.get('meshladar') or float('nan'):.2f} s, "
                   f"mitransient {tools.get('mitransient') or float('nan'):.2f} s")
    st = bench_streaming()
    yield (f"streaming 360 views x 1e6 rays, 2 threads: {st['seconds']:.1f} s, "
           f"{st['mrays']:.2f} Mrays/s, peak RSS {st['peak_rss_mb']:.0f} MB")
    try:
        d = bench_dask()
    except ImportError as exc:
        yield f"Dask: skipped ({exc})"
    else:
        yield (f"Dask, 2 local workers, {d['views']} views x 1e6 rays: {d['dask_s']:.1f} s "
               f"vs serial {d['serial_s']:.1f} s = {d['speedup']:.2f}x; per-task overhead "
               f"{1e3 * d['task_overhead_s']:.1f} ms; identical: {d['identical']}")
