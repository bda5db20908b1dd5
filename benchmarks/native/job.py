"""The whole mesh job against its physical limit on this machine: ``meshladar bench``'s
streaming run (360 views × 1e6 rays of the 81,920-triangle sphere, the default pipeline:
stratified rays, flat normals, SR, binned per chunk) on two threads, against the same
views' regular ray grids (the same extents and number of rays) cast in tile packets by a
plain C loop on two threads (limit.c) on the same Embree library, with nothing weighed or
binned: the issue-31 ratio "job / bare C tile cast" (goal ≥ 0.70).

    python benchmarks/native/job.py --include EMBREE_INCLUDE_DIR [--rounds 2] [--threads 2]

EMBREE_INCLUDE_DIR as for native.py (``embree4/rtcore*.h`` of Embree v4.4.0 with its
``rtcore_config.h``). Needs gcc. Both sides are timed in wall seconds (the job inside
its own fresh process, imports excluded, as ``bench_streaming`` reports it), in
interleaved rounds, best of each; run it on an otherwise idle machine.
"""

from __future__ import annotations

import argparse
import math
import os
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from native import _build  # noqa: E402  (compiles a C file of this folder)


def _inputs(tmp, views, rays_per_view, subdivisions):
    """MESH.bin and PLANS.bin for limit.c (formats in its header comment): the streaming
    run's sphere at unit size and each view's regular grid plan (grid_plan, no offsets)."""
    from meshladar import materials
    from meshladar.meshes import fibonacci_sphere
    from meshladar.raytrace.embree import Geometry
    from meshladar.raytrace.grid import grid_plan
    from meshladar.studies.timing import icosphere_scene

    scene = icosphere_scene(subdivisions, materials.DARK_GRAY)
    geo = Geometry(scene, "flat")
    vectors = fibonacci_sphere(views)
    geo.for_views(scene, views)
    unit = np.ascontiguousarray(geo.shifted / geo.scale, dtype=np.float32)
    mesh = os.path.join(tmp, "mesh.bin")
    with open(mesh, "wb") as fh:
        fh.write(np.array([len(unit), len(geo.faces32)], np.int64).tobytes())
        fh.write(np.vstack([unit, np.zeros((1, 3), np.float32)]).tobytes())
        fh.write(np.ascontiguousarray(geo.faces32, np.uint32).tobytes())
    plans, rays = os.path.join(tmp, "plans.bin"), 0
    spacing = 1.0 / math.sqrt(rays_per_view)
    with open(plans, "wb") as fh:
        fh.write(np.array([views], np.int64).tobytes()
                 + np.float32(1.0 / geo.scale).tobytes())
        for w in vectors:
            p = grid_plan(geo, w, "3d", spacing, 0.0, None)
            rays += p.s.size * p.t.size
            head = np.concatenate([-w, p.u, p.v, p.L * w]).astype(np.float32)
            fh.write(np.array([p.s.size, p.t.size], np.int64).tobytes() + head.tobytes()
                     + p.s.astype(np.float32).tobytes() + p.t.astype(np.float32).tobytes())
    return mesh, plans, rays, len(geo.faces32)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--include", required=True)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--views", type=int, default=360)
    ap.add_argument("--rays-per-view", type=int, default=1_000_000)
    ap.add_argument("--subdivisions", type=int, default=6)       # 81,920 triangles
    args = ap.parse_args(argv)

    from meshladar.raytrace import embree4
    from meshladar.studies.bench_mesh import bench_streaming

    width = embree4.library().width
    c_best, job_best, job_rays = math.inf, math.inf, 0
    with tempfile.TemporaryDirectory() as tmp:
        exe = _build(args.include, tmp, "limit")
        mesh, plans, rays, faces = _inputs(tmp, args.views, args.rays_per_view,
                                           args.subdivisions)
        for _ in range(args.rounds):
            out = subprocess.run([exe, mesh, plans, str(width), str(args.threads), "1"],
                                 capture_output=True, text=True, check=True).stdout.split()
            c_best, c_hits = min(c_best, float(out[2])), int(out[4])
            assert int(out[5]) == rays
            st = bench_streaming(views=args.views, rays_per_view=args.rays_per_view,
                                 subdivisions=args.subdivisions, jobs=args.threads)
            job_best, job_rays = min(job_best, st["seconds"]), st["rays"]
    print(f"{faces} triangles, {args.views} views, {rays:,} rays a pass (the job's "
          f"stratified grids: {job_rays:,}); native width {width}; {args.threads} threads; "
          f"best of {args.rounds} interleaved rounds, wall seconds")
    print(f"  C tile cast (limit):   {c_best:7.2f} s  {rays / c_best / 1e6:7.2f} Mrays/s  "
          f"hits {c_hits:,}")
    print(f"  meshladar job:         {job_best:7.2f} s  {job_rays / job_best / 1e6:7.2f} "
          f"Mrays/s")
    print(f"  job / limit: {(job_rays / job_best) / (rays / c_best):.3f} (goal >= 0.70)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
