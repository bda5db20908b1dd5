"""The GPU line of ``meshladar bench --gpu``: Warp's ray queries (a CUDA device where there
is one, else its CPU kernels) against the packet backend on the same rays."""

from __future__ import annotations

import math

import numpy as np

from .. import materials
from ..meshes import fibonacci_sphere
from ..raytrace import embree4
from ..raytrace.backends import backend
from ..raytrace.embree import Geometry, embree_scene
from ..forward.mesh import simulate_mesh
from ..ladar import Ladar
from ..raytrace.grid import ray_grid
from .timing import icosphere_scene, interleaved

__all__ = ["bench_gpu"]


def bench_gpu(*, repeats=3, subdivisions=6, rays_per_view=1_000_000, views=4):
    """First hits cast by Warp against the packet backend, on the same rays in interleaved
    rounds: ``views`` Fibonacci views of a dark gray icosphere, each a grid of about
    ``rays_per_view`` rays (the packet backend in tiles, its fastest), cast through each
    backend's ``run`` (for Warp, the copies to and from the device included).

    The device is "warp" (a CUDA device) when it loads, else "warp-cpu" (its kernels on
    the CPU, one thread: a measurement of the same code path, not of a GPU).

    Parameters
    ----------
    repeats : int, keyword-only
        Timed rounds after one warm-up round (default 3).
    subdivisions : int, keyword-only
        Icosphere subdivisions (default 6: 81,920 faces).
    rays_per_view : int, keyword-only
        Rays per view (default 10⁶).
    views : int, keyword-only
        Fibonacci view directions (default 4).

    Returns
    -------
    dict
        ``backend`` ("warp" or "warp-cpu"), ``where`` (the device, as its ``available()``
        says), ``faces``, ``rays`` (all views), ``packet_width``, ``packets_mrays`` and
        ``warp_mrays`` (millions of rays a second, from median times), ``warp_over_packets``
        (> 1 when Warp is faster) and ``same_face`` (the fraction of rays whose first hit,
        or miss, is the same in both); the same for the whole run from rays to bins (flat
        normals, 512 bins: Warp's one kernel against the fused loop, one thread),
        ``packets_bins_mrays``, ``warp_bins_mrays`` and ``bins_warp_over_packets``; or,
        when Warp is not installed, ``skipped`` (why).
    """
    ok, where = backend("warp").available()
    name = "warp" if ok else "warp-cpu"
    if not ok:
        ok, where = backend(name).available()
        if not ok:
            return {"skipped": where}
    scene = icosphere_scene(subdivisions, materials.DARK_GRAY)
    geo = Geometry(scene, "flat")
    scenes = {"packets": embree_scene(geo, "packets"), name: embree_scene(geo, name)}
    spacing = 1.0 / math.sqrt(rays_per_view)
    grids = [(ray_grid(geo, w, "3d", spacing, 0.0, None),
              np.ascontiguousarray((-w)[None, :], dtype=np.float32))
             for w in fibonacci_sphere(views)]
    hits = {}

    def cast(key):
        def run():
            hits[key] = [scenes[key].run(g.origins, d, output=1, columns=g.columns)["primID"]
                         for g, d in grids]
        return run

    def pipeline(key):                 # rays to bins: Warp's one kernel, the fused loop
        ladar = Ladar(None, np.linspace(-0.6, 0.6, 513), view_vectors=fibonacci_sphere(views))
        return lambda: simulate_mesh(scene, ladar, mode="3d", ray_spacing=spacing, jobs=1,
                                     sampling="regular", backend=key)

    t = interleaved({**{k: cast(k) for k in scenes},
                     **{f"{k} bins": pipeline(k) for k in scenes}}, repeats=repeats)
    n = sum(len(g.origins) for g, _ in grids)
    same = sum(int(np.sum(a == b)) for a, b in zip(hits["packets"], hits[name]))
    return {"backend": name, "where": where, "faces": len(geo.faces), "rays": n,
            "packet_width": embree4.library().width,
            "packets_mrays": n / t["packets"] / 1e6, "warp_mrays": n / t[name] / 1e6,
            "warp_over_packets": t["packets"] / t[name], "same_face": same / n,
            "packets_bins_mrays": n / t["packets bins"] / 1e6,
            "warp_bins_mrays": n / t[f"{name} bins"] / 1e6,
            "bins_warp_over_packets": t["packets bins"] / t[f"{name} bins"]}


def gpu_lines(repeats):
    """The lines of ``meshladar bench --gpu`` (:func:`bench_gpu`)."""
    g = bench_gpu(repeats=repeats)
    if "skipped" in g:
        yield f"GPU (Warp) vs packets: skipped ({g['skipped']})"
        return
    yield (f"first hits, {g['faces']} triangles, {g['rays']:,} rays: {g['backend']} "
           f"({g['where']}) {g['warp_mrays']:.2f} Mrays/s, packets "
           f"({g['packet_width']}-wide tiles, 1 thread) {g['packets_mrays']:.2f} Mrays/s: "
           f"{g['warp_over_packets']:.2f}x; the same face on {g['same_face']:.6f} of rays")
    yield (f"  rays to bins (flat normals, 512 bins): {g['backend']} "
           f"{g['warp_bins_mrays']:.2f} Mrays/s, packets (fused loop) "
           f"{g['packets_bins_mrays']:.2f} Mrays/s: {g['bins_warp_over_packets']:.2f}x")
    if g["backend"] == "warp-cpu":
        yield ("  (no CUDA device here: Warp's kernels ran on the CPU; on a GPU machine "
               "this line times backend='warp')")
