"""Benchmarks: medians of several runs in one process (``meshladar bench``).

Speed is measured here, never in timed tests. Each case is run ``repeats`` times after one
warm-up run, and the median, minimum and maximum wall times are reported (FBP against
scikit-image: one thread, CPU seconds, interleaved rounds). This module
holds the forward models' cases and :func:`report`, the lines ``meshladar bench`` prints.
The mesh engine's cases are in :mod:`.bench_mesh`, the timing helpers in :mod:`.timing`;
the cases of the inverse side (FBP, SIRT and SART, 3-D tomography, the coating fit) are
in the private ``_bench_inverse`` beside this module, and importable from here.
"""

from __future__ import annotations

import functools
import math
import statistics

import numpy as np

from .. import forward, materials
from .. import phantoms as _phantoms
from ..forward import simulate
from ..ladar import Ladar
from ..sensor import Sensor
from ..waveforms import GaussianPulse, receive
from . import peer
from ._bench_inverse import bench_fbp, bench_fit, bench_sirt, bench_tomography3d
from .bench_gpu import bench_gpu, gpu_lines  # noqa: F401
from .bench_bounces import bench_bounces
from .peer_bounces import bench_second_bounce
from .bench_scan import bench_scan
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

def report(*, repeats=5, full=False, gpu=False):
    """The benchmark report, line by line (what ``meshladar bench`` prints): each model and
    FBP timed against its peer in the same process; ``full`` adds streaming and Dask;
    ``gpu`` gives the GPU line alone (:func:`meshladar.studies.bench_gpu.bench_gpu`).

    The lines, in order: the analytic model (:func:`bench_analytic`), FBP against
    scikit-image (:func:`bench_fbp`: one thread, CPU seconds, interleaved rounds; skipped
    with a line when scikit-image is not installed), the mesh engine
    (:mod:`meshladar.studies.bench_mesh`), received power and waveforms
    (:func:`bench_sensor`), SIRT and SART (:func:`bench_sirt`), a two-coating fit, the
    imaging ladar (:func:`scan_line`), light beyond one bounce (:func:`bounce_line`), and
    3-D tomography (:func:`bench_tomography3d`); with ``full`` also Mitsuba 3 + mitransient
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
    gpu : bool, keyword-only
        Only Warp's cast against the packet backend's, on a CUDA device where there is
        one (default False).

    Yields
    ------
    str
        One line of the report, each as soon as its case is measured.
    """
    if gpu:
        yield from gpu_lines(repeats)
        return
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
        yield (f"FBP {r['shape'][0]} x {r['shape'][1]} -> {r['size']}^2, ramp, linear, one "
               f"thread, CPU s, median of {r['rounds']} interleaved rounds: meshladar "
               f"{r['ours_s']:.3f} s ({r['mpix_views']:.0f} Mpixel-views/s), skimage.iradon "
               f"{r['skimage_s']:.3f} s, speed-up {r['speedup']:.1f}x, max |difference| "
               f"{r['max_diff_rel']:.1e} of max")
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
    yield from _scene_lines()
    if full:
        yield from _full_lines()


def _scene_lines():
    """The report's lines of the imaging ladar, light beyond one bounce and 3-D tomography."""
    yield scan_line()
    yield bounce_line()
    tb = bench_tomography3d()
    yield (f"3-D tomography, {tb['faces']} triangles, {tb['views']} views, {tb['size']}^3: "
           f"profiles {tb['simulate_s']:.1f} s ({tb['rays']:,} rays, 2 threads), inversion "
           f"{tb['reconstruct_s']:.1f} s, total {tb['simulate_s'] + tb['reconstruct_s']:.1f} s")


def scan_line():
    """The report's imaging-ladar line (:func:`meshladar.studies.bench_scan.bench_scan`).

    Returns
    -------
    str
        The line.
    """
    sb = bench_scan()
    return (f"scan, rotating 32 channels at 3e5 pulses/s x 16 sub-rays, {sb['faces']} "
            f"triangles, {sb['sub_rays']:,} sub-rays, CPU s: bare packet cast "
            f"{sb['packet_mrays']:.1f} Msubrays/s, scan (cast + waveforms + returns + truth) "
            f"{sb['scan_mrays']:.2f} Msubrays/s ({sb['scan_over_cast']:.2f} of the cast), "
            f"discrete returns {sb['discrete_mrays']:.2f} Msubrays/s "
            f"({sb['discrete_over_cast']:.2f}), two threads {sb['two_over_one']:.2f}x one "
            f"(the bare cast {sb['cast_two_over_one']:.2f}x); "
            f"flash 128 x 128, 512 samples: "
            f"{sb['flash_fps']:.1f} frames/s")


def bounce_line():
    """The report's line of light beyond one bounce
    (:func:`meshladar.studies.bench_bounces.bench_bounces`).

    Returns
    -------
    str
        The line.
    """
    b = bench_bounces()
    return (f"bounces, {b['faces']}-triangle bowl, second bounce, {b['paths']:,} paths: "
            f"{b['one_thread'] / 1e6:.2f} Mpaths/s one thread, {b['two_threads'] / 1e6:.2f} "
            f"two ({b['two_threads'] / b['one_thread']:.2f}x); packet backend "
            f"{b['packets_over_embreex']:.2f}x embreex on the bounce rays; a convex sphere's "
            f"bounces='auto' {b['auto_over_one']:.2f}x bounces=1")


def _full_lines():
    """The report's lines of ``full``: the peer renderer, streaming and Dask."""
    pt = peer.bench_time_to_accuracy()
    if not pt["mitransient"]:
        yield f"Mitsuba 3 + mitransient: skipped ({peer.available(reason=True)[1][:200]})"
    else:
        for target, tools in pt["time_to"].items():
            yield (f"time to {target:g} relative L2, Lambertian {pt['faces']}-face sphere, "
                   f"received power: meshladar {tools.get('meshladar') or float('nan'):.2f} s, "
                   f"mitransient {tools.get('mitransient') or float('nan'):.2f} s")
        sb = bench_second_bounce()
        yield (f"time to a 1e-3 relative standard error of the second bounce, Lambertian "
               f"bowl (2,560 faces): meshladar {sb['meshladar_s']:.2f} s, mitransient "
               f"{sb['mitransient_s']:.2f} s (errors at the budget "
               f"{sb['meshladar_error']:.1e} and {sb['mitransient_error']:.1e})")
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
    yield (f"  pipeline, raster, stratified       {m['raster_mrays']:7.2f} Mrays/s "
           f"({m['raster_over_raw']:.2f}x raw embreex; 2 threads "
           f"{m['raster_two_over_one']:.2f}x one)")
    yield (f"  pipeline, packets, 2 threads       {m['two_thread_mrays']:7.2f} Mrays/s "
           f"({m['two_over_one']:.2f}x one, {m['two_over_raw']:.2f}x raw embreex)")
    for sub in (3, 8):                                 # 1.3k and 1.3M triangles
        o = bench_mesh(repeats=2, subdivisions=sub, views=4, build=False)
        yield (f"  {o['faces']:>8} triangles, 4 views: raw embreex {o['raw_mrays']:5.2f}, "
               f"packet cast {o['packet_mrays']:5.2f} ({o['packet_over_raw']:.2f}x), "
               f"pipeline {o['pipeline_mrays']:5.2f} ({o['pipeline_over_raw']:.2f}x), "
               f"2 threads {o['two_thread_mrays']:5.2f} Mrays/s")
    sp = bench_mesh(repeats=2, views=2000, rays_per_view=1296, build=False)
    yield (f"  many small views, {sp['views']} views x {sp['rays'] // sp['views']} rays: raw "
           f"embreex {sp['raw_mrays']:5.2f}, pipeline {sp['pipeline_mrays']:5.2f} "
           f"({sp['pipeline_over_raw']:.2f}x), stratified {sp['stratified_mrays']:5.2f}, "
           f"2 threads {sp['two_thread_mrays']:5.2f} Mrays/s")
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
