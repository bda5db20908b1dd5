"""The benchmark of light beyond one bounce (``meshladar bench``'s bounce line): second-
bounce paths per second on an 81 920-triangle hemispherical bowl (non-convex), one and
two threads, the packet backend against embreex on the same (incoherent) bounce rays,
interleaved; and a convex scene's ``bounces="auto"`` against ``bounces=1``."""

from __future__ import annotations

import time

import numpy as np

from ..brdf import Lambertian
from ..forward import simulate
from ..forward.bounces import higher_orders
from ..ladar import Ladar
from ..meshes import MeshPart, icosphere, sphere
from ..scene import Scene

__all__ = ["bench_bounces"]


def _bowl(subdivisions):
    v, f = icosphere(subdivisions)
    keep = v[f].mean(axis=1)[:, 2] < -0.5            # a cap of a quarter of the sphere
    return Scene.from_parts([MeshPart(v, f[keep], 0, "bowl")], [Lambertian(0.6)])


def _timed(fn, clock=time.perf_counter):
    t = clock()
    out = fn()
    return clock() - t, out


def bench_bounces(*, subdivisions=7, views=4, samples=1 << 17, rounds=3):
    """Second-bounce paths per second and the convex scene's cost of ``"auto"``.

    Parameters
    ----------
    subdivisions : int
        The bowl's icosphere level (7: a cap of 81 920 triangles, z < −R/2).
    views : int
        Views per run.
    samples : int
        Paths per view.
    rounds : int
        Interleaved rounds; medians reported.

    Returns
    -------
    dict
        ``faces``, ``paths`` (per run), ``one_thread`` and ``two_threads`` (paths per
        second, wall clock), ``packets_over_embreex`` (one thread), ``auto_over_one``
        (a convex 81 920-face sphere's ``bounces="auto"`` time over ``bounces=1``).
    """
    bowl = _bowl(subdivisions)
    angles = np.linspace(0.0, 60.0, views)
    w = np.stack([np.sin(np.radians(angles)), np.zeros(views), np.cos(np.radians(angles))], 1)
    lad = Ladar(None, view_vectors=w, bin_edges=np.linspace(-3.0, 3.0, 65))
    runs = {"one": [], "two": [], "embreex": []}
    for _ in range(rounds):
        for key, kw in (("one", {}), ("two", {"jobs": 2}), ("embreex", {"backend": "embreex"})):
            runs[key].append(_timed(lambda: higher_orders(
                bowl, lad, bounces=2, ray_spacing=4e-3, samples=samples, seed=0, **kw))[0])
    t = {k: float(np.median(v)) for k, v in runs.items()}
    ball = Scene.from_parts([sphere((0, 0, 0), 1.0, 0, subdivisions=6)], [Lambertian(0.6)])
    auto, one = [], []
    for _ in range(rounds):
        for out, b in ((one, 1), (auto, "auto")):
            out.append(_timed(lambda: simulate(ball, lad, model="mesh", radiometry="power",
                                               bounces=b))[0])
    paths = views * samples
    return {"faces": len(bowl.parts[0].faces), "paths": paths,
            "one_thread": paths / t["one"], "two_threads": paths / t["two"],
            "packets_over_embreex": t["embreex"] / t["one"],
            "auto_over_one": float(np.median(auto) / np.median(one))}
