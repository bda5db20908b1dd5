"""Light beyond one bounce against Mitsuba 3 + mitransient: the total received power of
each order of bounces (meshladar's ``radiometry="power"``) from renders at increasing
``max_depth`` with one seed, whose differences are each order's estimate.

Only totals are compared: mitransient's directional emitter counts a constant length for
the light's leg to the first surface, so its path lengths of orders beyond the first are
not the plane wave's (meshladar bins each path at half its true optical path), while the
power each order carries is the same.
"""

from __future__ import annotations

import time

import numpy as np

from ..brdf import Lambertian
from ..forward import simulate
from ..ladar import Ladar
from ..meshes import MeshPart, icosphere
from ..scene import Scene
from .peer import _mitsuba, _uniform_width
from ._mitsuba_scene import _checked, _frame, _opl_mapping, _samples, _target, _transient_scene

__all__ = ["mitransient_orders", "bench_second_bounce"]


def mitransient_orders(vertices, faces, view, *, bsdf, bounces=2, spp=256, film=(128, 128),
                       seed=0, sampler="independent"):
    """Total received power of orders 1..``bounces`` rendered by mitransient (module
    docstring): one render per ``max_depth`` = order + 1, same seed and sampler, so that
    each difference is that order's own estimate.

    Parameters
    ----------
    vertices, faces : (n, 3) float, (m, 3) int
        The mesh (two-sided).
    view : (3,) array_like
        w, from the scene toward the sensor and the emitter's source (collocated).
    bsdf : dict
        A Mitsuba BSDF dictionary (``{"type": "diffuse", ...}``, ``roughconductor``, …).
    bounces : int
        The highest order.
    spp : int
        Samples per pixel.
    film : (nx, ny)
        Pixels, square, covering the mesh's bounding sphere.
    seed : int
        The sampler's seed (the same for every depth).
    sampler : str
        Mitsuba sampler plugin.

    Returns
    -------
    (bounces,) numpy.ndarray
        Each order's total, ∫ F cos θi cos θr dA and its higher-order analogues, in
        meshladar's units (per unit irradiance).
    """
    v, f, w, _ = _checked(vertices, faces, view, [0.0, 1.0])
    nx, ny = int(film[0]), int(film[1])
    spp = _samples(spp, sampler)
    mi, dr = _mitsuba()
    mesh = _target(mi, v, f, bsdf, True)
    fr = _frame(mi, v, w, nx, ny)
    reach = 2.0 * (bounces + 2) * fr.rad
    edges = np.array([-(-(fr.origin @ w)) - reach, -(fr.origin @ w) + reach])
    edges = np.array([float(-(fr.origin @ w)) - reach, float(-(fr.origin @ w)) + 2 * reach])
    mapping = _opl_mapping(mi, mesh, w, fr, edges, _uniform_width(edges))
    totals = []
    for depth in range(2, bounces + 2):
        scene = _transient_scene(mi, mesh, w, fr, {
            "sampler": {"type": sampler, "sample_count": spp, "seed": int(seed)},
            "film": {"type": "transient_hdr_film", "width": nx, "height": ny,
                     "temporal_bins": 1, "bin_width_opl": mapping["bin_width_opl"],
                     "start_opl": max(mapping["start_opl"], 0.0),
                     "rfilter": {"type": "box"}}}, max_depth=depth)
        _, transient = mi.render(scene, spp=spp, seed=int(seed))
        totals.append(float(np.array(transient, dtype=np.float64)[..., 0].sum())
                      * (2.0 * fr.h / nx) ** 2)
        dr.sync_thread()
    return np.diff(np.r_[0.0, totals])


def bench_second_bounce(*, target=1e-3, rounds=4, spp=64, samples=1 << 17, seed=0):
    """Seconds to a relative standard error ``target`` of the second order's total on a
    Lambertian hemispherical bowl (a 5 120-face icosphere's lower half, seen 17° off its
    axis), meshladar against mitransient, interleaved; each tool's error measured at one
    budget and its time scaled by (error / target)² (Monte Carlo: error ∝ 1/√time).

    meshladar's error is its own standard error estimate; mitransient's the spread of its
    second order over ``rounds`` seeds (renders at ``max_depth`` 2 and 3).

    Parameters
    ----------
    target : float
        The relative standard error to reach.
    rounds : int
        Interleaved rounds (mitransient seeds), at least 2.
    spp : int
        mitransient's samples per pixel (128 × 128 pixels).
    samples : int
        meshladar's paths per run.
    seed : int
        The first seed.

    Returns
    -------
    dict
        ``meshladar_s``, ``mitransient_s`` (seconds to ``target``), ``meshladar_error``,
        ``mitransient_error`` (at the budget), ``order2`` (meshladar's mean total).
    """
    v, f = icosphere(4)
    f = f[v[f].mean(axis=1)[:, 2] < 0]
    w = np.array([0.3, 0.1, 1.0]) / np.linalg.norm([0.3, 0.1, 1.0])
    scene = Scene.from_parts([MeshPart(v, f, 0, "bowl")], [Lambertian(0.6)])
    ladar = Ladar(None, view_vectors=w[None], bin_edges=np.linspace(-4.0, 4.0, 9))
    bsdf = {"type": "diffuse", "reflectance": {"type": "uniform", "value": 0.6}}
    ours, theirs = [], []
    for k in range(rounds):
        t = time.perf_counter()
        sino = simulate(scene, ladar, model="mesh", radiometry="power", bounces=2,
                        bounce_samples=samples, ray_spacing=4e-3, seed=seed + k)
        ours.append((time.perf_counter() - t, sino.info["order_totals"][1],
                     sino.info["order_stderr"][1]))
        t = time.perf_counter()
        o = mitransient_orders(v, f, w, bsdf=bsdf, bounces=2, spp=spp, seed=seed + k)
        theirs.append((time.perf_counter() - t, o[1]))
    ot, ov, oe = (np.array(c) for c in zip(*ours))
    tt, tv = (np.array(c) for c in zip(*theirs))
    ours_err, their_err = float(np.mean(oe / ov)), float(np.std(tv, ddof=1) / np.mean(tv))
    return {"meshladar_s": float(np.median(ot)) * (ours_err / target) ** 2,
            "mitransient_s": float(np.median(tt)) * (their_err / target) ** 2,
            "meshladar_error": ours_err, "mitransient_error": their_err,
            "order2": float(np.mean(ov))}
