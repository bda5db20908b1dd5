"""Light beyond one bounce against Mitsuba 3 + mitransient: the range profile of each order
of bounces (meshladar's ``radiometry="power"``) from renders at increasing ``max_depth``
with one seed, whose differences are each order's estimate.

The light is a point source D = :data:`LIGHT_DISTANCE` bounding radii away along w, of
intensity D² (unit irradiance at the scene): mitransient's directional emitter counts a
constant length for the light's leg to the first surface, so its path lengths beyond the
first order are not a plane wave's, while a distant point's leg |x₁ − S| ≈ D − x₁·w is.
Its departures from a plane wave (the leg's curvature, the irradiance's 1/R² across the
target) are first order in 1/D: a second render at D/2, with the same seed, extrapolates
them away (2 p(D) − p(D/2)).
The orthographic sensor's leg is −x_k·w from its near plane, so each path's optical path
is a constant plus twice meshladar's range, half the optical path.
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
from ._mitsuba_scene import (_checked, _frame, _opl_mapping, _samples, _target,
                             _transient_scene)

__all__ = ["LIGHT_DISTANCE", "mitransient_profiles", "mitransient_orders",
           "bench_second_bounce"]


#: The point light's distance in bounding radii: its light leg departs from a plane wave's
#: by ρ²/(2D) ≤ 1e-3 radii and its irradiance by 2ρ/D ≤ 4e-3, both first order in 1/D and
#: extrapolated away from a second render at D/2; float32 path lengths at that distance
#: keep ~3e-5 radii (measured, order 1 of the dihedral against meshladar: relative L2 over
#: the bins 2.5e-4 at 500, 6.6e-4 at 1000, 1.8e-3 at 2000 radii).
LIGHT_DISTANCE = 500.0


def mitransient_profiles(vertices, faces, view, bin_edges, *, bsdf, bounces=2, spp=256,
                         film=(128, 128), seed=0, sampler="independent"):
    """Range profiles of orders 1..``bounces`` rendered by mitransient (module docstring):
    one render per ``max_depth`` = order + 1, same seed and sampler, so that each
    difference is that order's own estimate.

    Parameters
    ----------
    vertices, faces : (n, 3) float, (m, 3) int
        The mesh (two-sided).
    view : (3,) array_like
        w, from the scene toward the sensor and the light (collocated).
    bin_edges : (k + 1,) array_like
        Evenly spaced range edges, meshladar's convention (r = −p·w; half the optical
        path of a path of several bounces).
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
    (bounces, k) numpy.ndarray
        Each order's bin integrals of received power per unit irradiance (meshladar's
        ``radiometry="power"``).
    """
    v, f, w, edges = _checked(vertices, faces, view, bin_edges)
    mi, _ = _mitsuba()
    mesh = _target(mi, v, f, bsdf, True)
    plan = (bounces, _samples(spp, sampler), (int(film[0]), int(film[1])), int(seed), sampler)
    near, far = (_rendered(mi, mesh, (v, w, edges), plan, LIGHT_DISTANCE * k) for k in (0.5, 1))
    return 2.0 * far - near                     # Richardson's extrapolation in 1/D


def _rendered(mi, mesh, target, plan, distance):
    """The orders' profiles with the point light ``distance`` bounding radii away."""
    v, w, edges = target
    bounces, spp, (nx, ny), seed, sampler = plan
    width = _uniform_width(edges)
    dr = _mitsuba()[1]
    fr = _frame(mi, v, w, nx, ny)
    D = distance * fr.rad
    centre = fr.origin - fr.dist * w
    # optical path = |x₁ − S| + L + (−x_k·w − r_near) ≈ D + c·w − r_near + 2r
    offset = D + float(centre @ w) - float(-(fr.origin @ w) + fr.near)
    totals = [np.zeros(len(edges) - 1)]
    for depth in range(2, bounces + 2):
        scene = mi.load_dict({
            "type": "scene",
            "integrator": {"type": "transient_path", "max_depth": depth},
            "emitter": {"type": "point", "position": (centre + D * w).tolist(),
                        "intensity": {"type": "uniform", "value": D * D}},
            "target": mesh,
            "sensor": {"type": "orthographic", "to_world": fr.to_world, "near_clip": fr.near,
                       "far_clip": fr.dist + 2.0 * fr.rad + fr.near,
                       "sampler": {"type": sampler, "sample_count": spp, "seed": seed},
                       "film": {"type": "transient_hdr_film", "width": nx, "height": ny,
                                "temporal_bins": len(edges) - 1,
                                "bin_width_opl": 2.0 * width,
                                "start_opl": offset + 2.0 * float(edges[0]),
                                "rfilter": {"type": "box"}}}})
        _, transient = mi.render(scene, spp=spp, seed=seed)
        totals.append(np.array(transient, dtype=np.float64)[..., 0].sum(axis=(0, 1))
                      * (2.0 * fr.h / nx) ** 2)
        dr.sync_thread()
    return np.diff(np.vstack(totals), axis=0)


def mitransient_orders(vertices, faces, view, *, bsdf, bounces=2, spp=256, film=(128, 128),
                       seed=0, sampler="independent"):
    """Total received power of orders 1..``bounces`` rendered by mitransient, one render
    per ``max_depth`` = order + 1 with its directional emitter (whose constant light leg
    leaves totals exact: one bin holds every path), the same seed and sampler, so that
    each difference is that order's own estimate. The cheapest way mitransient has to a
    total, which :func:`bench_second_bounce` times.

    Parameters
    ----------
    vertices, faces : (n, 3) float, (m, 3) int
        The mesh (two-sided).
    view : (3,) array_like
        w, from the scene toward the sensor and the light (collocated).
    bsdf : dict
        A Mitsuba BSDF dictionary.
    bounces : int
        The highest order.
    spp : int
        Samples per pixel.
    film : (nx, ny)
        Pixels.
    seed : int
        The sampler's seed.
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
