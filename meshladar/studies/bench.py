"""Benchmarks: medians of several runs in one process (``meshladar bench``).

Speed is measured here, never in timed tests. Each case is run ``repeats`` times after one
warm-up run, and the median, minimum and maximum wall times are reported. The mesh
engine's cases are in :mod:`.bench_mesh`, the timing helpers in :mod:`.timing`.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import statistics
import time
import warnings

import numpy as np

from .. import forward, materials
from .. import phantoms as _phantoms
from ..brdf import SandfordRobertson
from ..errors import MeshladarWarning
from ..fit import coating_kernel, fit_coatings
from ..forward import simulate
from ..reconstruct.iterative import sart, sirt
from ..ladar import Ladar
from ..meshes import fibonacci_sphere, sphere
from ..forward.mesh import trace
from ..waveforms import GaussianPulse, receive
from ..reconstruct import fbp
from ..scene import Scene
from ..sensor import Sensor
from ..sinogram import Sinogram
from ..reconstruct.volumes import fbp3d as radon3d
from ..weighing import weigh
from . import peer
from .bench_mesh import (bench_dask, bench_fused,  # noqa: F401
                         bench_mesh, bench_single_view, bench_streaming)
from .timing import icosphere_scene as _icosphere_scene
from .timing import interleaved, time_call

__all__ = ["time_call", "bench_analytic", "bench_fbp", "bench_mesh", "bench_sensor",
           "bench_tomography3d", "bench_sirt", "bench_streaming", "bench_dask", "report"]


def bench_analytic(*, repeats=5):
    """The paper's analytic sinograms (360 views × 512 bins of A/256): one row per case.

    Returns a list of dicts with ``case``, ``median_s``, ``min_s``, ``max_s``.

    The six cases: the disk pair with each of the four combinations of dark gray and
    aluminium, the ellipse of semi-axes 0.6 and 0.3 in aluminium and the disk of radius
    A = 0.8 in aluminium, each
    simulated with the analytic model on :meth:`meshladar.ladar.Ladar.paper`'s ladar.

    Parameters
    ----------
    repeats : int, keyword-only
        Timed runs per case after one warm-up run (default 5); at least 1, as
        ``statistics.median`` of no times fails.

    Returns
    -------
    list of dict
        One per case: ``case`` (str), and the ``median_s``, ``min_s`` and ``max_s`` of its
        wall times, in seconds.
    """
    gray, al = materials.DARK_GRAY, materials.ALUMINUM
    ladar = Ladar.paper()

    pair = functools.partial(_phantoms.scene, "disk_pair")
    cases = {
        "disk pair, gray + gray": pair(large=gray, small=gray),
        "disk pair, aluminium + aluminium": pair(large=al, small=al),
        "disk pair, gray + aluminium": pair(large=gray, small=al),
        "disk pair, aluminium + gray": pair(large=al, small=gray),
        "ellipse A=0.6 B=0.3, aluminium": _phantoms.scene("ellipse", al),
        "disk A=0.8, aluminium (one profile)": _phantoms.scene("disk", al),
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

    Parameters
    ----------
    n_bins : int, keyword-only
        Range bins of width 2 / ``n_bins`` (default 1024), bin k centred on
        (k − ``n_bins``/2) × 2 / ``n_bins``.
    size : int, keyword-only
        Pixels per side of both images (default 1024); ours has half-width 1 about
        (−w/2, −w/2), w the bin width, to match scikit-image's pixel grid.
    repeats : int, keyword-only
        Timed runs of each after one warm-up run (default 3).
    filter : str, keyword-only
        The filter both use (default ``"ramp"``): a name both :func:`meshladar.fbp` and
        scikit-image's ``iradon`` accept.

    Returns
    -------
    dict
        ``ours_s`` and ``skimage_s``: median wall times in seconds; ``speedup``:
        ``skimage_s / ours_s``; ``max_diff_rel``: the largest absolute difference of the
        two images over scikit-image's largest absolute value; ``shape``: the sinogram's
        (360, ``n_bins``); ``size``.

    Raises
    ------
    ImportError
        When scikit-image is not installed (the ``bench`` extra).
    """
    try:
        from skimage.transform import iradon
    except ImportError as exc:
        raise ImportError("the FBP benchmark compares against scikit-image: "
                          "pip install 'meshladar[bench]'") from exc

    scene = _phantoms.scene("disk_pair", large=materials.DARK_GRAY, small=materials.ALUMINUM)
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


def bench_sensor(*, subdivisions=6, rays_per_view=1_000_000, views=4, repeats=2):
    """Received power of an aluminium icosphere: the ladar at infinity (the compiled loop)
    against a sensor at a standoff of 100 radii (50 scene units) (perspective rays, weighed
    and binned by the compiled loop of the ``sensor`` stage: flat normals, a compiled SR
    coating), interleaved; and the waveforms of 360 views (receive).

    Both received-power runs use the mesh model on one thread, 512 bins covering the
    sphere (radius 0.5) and ``views`` views at 0°, 1°, ...; the waveforms are those of a
    360-view, 512-bin received-power sinogram (``rays_per_bin=1``) sampled at 20 GHz with
    a Gaussian pulse of 0.1 ns FWHM.

    Parameters
    ----------
    subdivisions : int, keyword-only
        Icosphere subdivisions (default 6: 81,920 faces).
    rays_per_view : int, keyword-only
        Rays per view: the ray spacing is 1 / sqrt(``rays_per_view``) across the sphere's
        1 × 1 projected square (default 10⁶).
    views : int, keyword-only
        Views of the two received-power runs (default 4).
    repeats : int, keyword-only
        Timed rounds after one warm-up round (default 2).

    Returns
    -------
    dict
        ``faces``; ``rays``: rays cast by the run at infinity, over all its views;
        ``far_mrays`` and ``near_mrays``: millions of rays per second of the two runs
        (median times); ``receive_s``: the median wall time of ``receive`` in seconds;
        ``receive_shape``: the sinogram's (n_views, n_bins) it sampled.
    """
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
    Radon inversion onto size³ voxels (``size`` a side); wall times of each (after a warm-up).

    The bins: ``size`` of them over ranges [−0.55, 0.55]; the cube: half-width 0.55. Each
    stage is timed once, after one run of each (the inversion at 8³, to compile it);
    meshladar's warnings are silenced while timing (the volume is not looked at, so the
    inversion's warning that the views are too few does not apply).

    Parameters
    ----------
    views : int, keyword-only
        Fibonacci view directions over the sphere (default 200).
    size : int, keyword-only
        Voxels per side, and range bins (default 128).
    subdivisions : int, keyword-only
        Icosphere subdivisions (default 6: 81,920 faces).
    jobs : int, keyword-only
        Threads of the mesh model (default 2).

    Returns
    -------
    dict
        ``faces``, ``views``, ``size``, ``rays`` (rays cast, all views), and the wall
        times in seconds ``simulate_s`` and ``reconstruct_s``.
    """
    scene = _icosphere_scene(subdivisions, materials.DARK_GRAY)
    ladar = Ladar(None, np.linspace(-0.55, 0.55, size + 1),
                  view_vectors=fibonacci_sphere(views))
    sino = simulate(scene, ladar, model="mesh", radiometry="power", jobs=jobs)
    with warnings.catch_warnings():
        # a timing: the volume is not looked at, so fbp3d's warning that 200 views are too
        # few for a sharp one does not apply
        warnings.simplefilter("ignore", MeshladarWarning)
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
    calls, times ``iterations``).

    The data: the exact bin integrals of a uniform disk of radius 0.4 centred at
    (0.1, 0), ``size`` bins over [−1, 1]. SIRT uses the linear projector, SART its
    default (``"auto"``: linear, as the bins are uniform) and its default groups, one per
    36 views (10 for 360). Each of ours is timed once after a compiling run at 16².

    Parameters
    ----------
    size : int, keyword-only
        Range bins, and pixels per side of the image over [−1, 1]² (default 512).
    n_views : int, keyword-only
        Views evenly spaced over 360° (default 360).
    iterations : int, keyword-only
        Sweeps of each method (default 50).
    skimage_iterations : int, keyword-only
        ``iradon_sart`` calls timed to estimate its time per sweep (default 2).

    Returns
    -------
    dict
        ``ours_s`` (SIRT) and ``sart_s``: wall times in seconds of ``iterations`` sweeps;
        ``skimage_s``: scikit-image's estimated time for as many sweeps, or None when
        scikit-image is not installed (the dict then holds only ``ours_s``, ``sart_s``,
        ``skimage_s`` and ``iterations``); ``iterations``, ``size``, ``views``.
    """
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
    FBP timed against its peer in the same process; ``full`` adds streaming and Dask.

    The lines, in order: the analytic model (:func:`bench_analytic`), FBP against
    scikit-image (:func:`bench_fbp`; skipped with a line when it is not installed), the
    mesh engine (:mod:`meshladar.studies.bench_mesh`), received power and waveforms
    (:func:`bench_sensor`), SIRT and SART (:func:`bench_sirt`), a two-coating fit, and 3-D
    tomography (:func:`bench_tomography3d`); with ``full`` also Mitsuba 3 + mitransient
    (:func:`meshladar.studies.peer.bench_time_to_accuracy`), streaming
    (:func:`bench_streaming`) and Dask (:func:`bench_dask`; skipped with a line when Dask
    is not installed).

    Parameters
    ----------
    repeats : int, keyword-only
        Timed runs per case after one warm-up (default 5), for the analytic model, FBP
        and the mesh engine's main case; the other cases use their own defaults.
    full : bool, keyword-only
        Add the peer renderer, the streaming run and the Dask run (default False).

    Yields
    ------
    str
        One line of the report, each as soon as its case is measured.
    """
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
    yield from _mesh_lines(repeats)
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


def _mesh_lines(repeats):
    """The report's mesh-engine lines (:mod:`.bench_mesh`)."""
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
