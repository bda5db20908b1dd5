"""Benchmarks of ``meshladar bench`` on the inverse side: FBP against scikit-image's
``iradon``, SIRT and SART against its ``iradon_sart``, 3-D reflective tomography (the
profiles and their Radon inversion) and a two-coating fit against re-weighing.

The functions are re-exported by :mod:`meshladar.studies.bench`, whose report prints them.
"""

from __future__ import annotations

import dataclasses
import statistics
import time
import warnings

import numba
import numpy as np

from .. import forward, materials
from .. import phantoms as _phantoms
from ..brdf import SandfordRobertson
from ..errors import MeshladarWarning
from ..fit import coating_kernel, fit_coatings
from ..forward import simulate
from ..forward.mesh import trace
from ..ladar import Ladar
from ..meshes import fibonacci_sphere, sphere
from ..reconstruct import fbp
from ..reconstruct.iterative import sart, sirt
from ..reconstruct.volumes import fbp3d as radon3d
from ..scene import Scene
from ..sinogram import Sinogram
from ..weighing import weigh
from .timing import icosphere_scene as _icosphere_scene
from .timing import interleaved, interleaved_times

__all__ = ["bench_fbp", "bench_tomography3d", "bench_sirt", "bench_fit"]


def bench_fbp(*, n_bins=1024, size=1024, repeats=5, filter="ramp"):
    """FBP of a 360 × n_bins sinogram to size² against ``skimage.transform.iradon``, on one
    thread, in CPU seconds, in interleaved rounds.

    Both run in this process on the same data (the mixed disk pair's exact sinogram), with
    the same filter and linear interpolation, on the same grid (unit bins centred on
    k − n/2, pixel centres on scikit-image's grid, views 180° − φ). numba runs on one
    thread while timing (its setting is restored after), as scikit-image does; each round
    calls ours then theirs (after one warm-up round), timed by ``time.process_time`` so
    that other work on a shared machine counts against neither, and the speed-up is the
    median of the rounds' ratios.

    Parameters
    ----------
    n_bins : int, keyword-only
        Range bins of width 2 / ``n_bins`` (default 1024), bin k centred on
        (k − ``n_bins``/2) × 2 / ``n_bins``.
    size : int, keyword-only
        Pixels per side of both images (default 1024); ours has half-width 1 about
        (−w/2, −w/2), w the bin width, to match scikit-image's pixel grid.
    repeats : int, keyword-only
        Timed rounds after one warm-up round (default 5); at least 1.
    filter : str, keyword-only
        The filter both use (default ``"ramp"``): a name both :func:`meshladar.fbp` and
        scikit-image's ``iradon`` accept.

    Returns
    -------
    dict
        ``ours_s`` and ``skimage_s``: median CPU seconds of a call, one thread;
        ``speedup``: the median over rounds of skimage's time over ours; ``mpix_views``
        and ``skimage_mpix_views``: millions of pixel-views (size² × 360) per CPU second
        of each at its median; ``max_diff_rel``: the largest absolute difference of the
        two images over scikit-image's largest absolute value; ``shape``: the sinogram's
        (360, ``n_bins``); ``size``; ``rounds``: ``repeats``.

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
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        t = interleaved_times({"ours": ours, "theirs": theirs}, repeats=repeats,
                              clock=time.process_time)
    finally:
        numba.set_num_threads(threads)
    a, b = ours().values, theirs()
    ours_s, theirs_s = statistics.median(t["ours"]), statistics.median(t["theirs"])
    pixel_views = 360.0 * size * size
    return {"ours_s": ours_s, "skimage_s": theirs_s,
            "speedup": statistics.median([y / x for x, y in zip(t["ours"], t["theirs"])]),
            "mpix_views": pixel_views / ours_s / 1e6,
            "skimage_mpix_views": pixel_views / theirs_s / 1e6,
            "max_diff_rel": float(np.max(np.abs(a - b)) / np.max(np.abs(b))),
            "shape": (360, n_bins), "size": size, "rounds": repeats}


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
