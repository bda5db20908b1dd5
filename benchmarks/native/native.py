"""meshladar's packet cast against a native C loop (packets.c) on the same Embree library,
scene and rays, in interleaved rounds: the issue-14 ratio "packet cast / native
rtcIntersectW loop".

    python benchmarks/native/native.py --include EMBREE_INCLUDE_DIR [--rounds 5]

EMBREE_INCLUDE_DIR holds ``embree4/rtcore*.h`` of Embree v4.4.0 (the version the embreex
wheel ships; ``include/embree4`` of the v4.4.0 tag, plus an ``rtcore_config.h`` made from
``kernels/rtcore_config.h.in`` with the release's CMake defaults: version 4.4.0, one
instance level, instance arrays on, min-width off). Needs gcc. Prints Mrays/s for the C
loop at widths 1, 4, 8 and 16 and for meshladar's cast (the device's native width, with
and without barycentrics), their ratios, and checks that every loop found the same hits.
"""

from __future__ import annotations

import argparse
import glob
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np


def _library():
    import embreex

    root = os.path.dirname(os.path.dirname(embreex.__file__))
    (lib,) = glob.glob(os.path.join(root, "embreex.libs", "libembree4*.so*"))
    return lib


def _build(include, out):
    lib = _library()
    exe = os.path.join(out, "packets")
    subprocess.run(["gcc", "-O2", "-march=native", "-std=c11", "-D_POSIX_C_SOURCE=200809L",
                    "-Wall", "-I", include,
                    os.path.join(os.path.dirname(os.path.abspath(__file__)), "packets.c"),
                    lib, f"-Wl,-rpath,{os.path.dirname(lib)}", "-lm", "-o", exe], check=True)
    return exe


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--include", required=True)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--subdivisions", type=int, default=6)       # 81,920 triangles
    ap.add_argument("--views", type=int, default=16)
    ap.add_argument("--rays-per-view", type=int, default=1_000_000)
    args = ap.parse_args(argv)

    from meshladar import materials
    from meshladar.studies.bench import _icosphere_scene
    from meshladar.meshes import fibonacci_sphere
    from meshladar.raytrace import embree4
    from meshladar.raytrace.embree import Geometry
    from meshladar.raytrace.grid import ray_grid

    scene = _icosphere_scene(args.subdivisions, materials.DARK_GRAY)
    geo = Geometry(scene, "flat")
    unit = np.ascontiguousarray(geo.shifted / geo.scale, dtype=np.float32)
    spacing = 1.0 / math.sqrt(args.rays_per_view)
    vecs = fibonacci_sphere(args.views)
    grids = [np.ascontiguousarray(ray_grid(geo, w, "3d", spacing, 0.0, None)[0] / geo.scale,
                                  dtype=np.float32) for w in vecs]
    dirs = [np.ascontiguousarray(-w, dtype=np.float32) for w in vecs]
    n_rays = sum(len(g) for g in grids)
    pk = embree4.PacketGeometry(unit, geo.faces32)
    width = pk.lib.width

    with tempfile.TemporaryDirectory() as tmp:
        exe = _build(args.include, tmp)
        mesh = os.path.join(tmp, "mesh.bin")
        with open(mesh, "wb") as fh:
            fh.write(np.array([len(unit), len(geo.faces32)], np.int64).tobytes())
            fh.write(np.vstack([unit, np.zeros((1, 3), np.float32)]).tobytes())
            fh.write(np.ascontiguousarray(geo.faces32, np.uint32).tobytes())
        rays = os.path.join(tmp, "rays.bin")
        with open(rays, "wb") as fh:
            fh.write(np.array([len(grids)], np.int64).tobytes())
            for o, d in zip(grids, dirs):
                fh.write(np.array([len(o)], np.int64).tobytes() + d.tobytes() + o.tobytes())

        def python(barycentrics):
            hits = prims = 0
            t0 = time.perf_counter()
            for o, d in zip(grids, dirs):
                res = pk.cast_grid(o, d, barycentrics=barycentrics)
                prim = res[0]
            t = time.perf_counter() - t0
            for o, d in zip(grids, dirs):                # the checksum, outside the timing
                prim = pk.cast_grid(o, d)[0]
                hit = prim >= 0
                hits += int(hit.sum())
                prims += int(prim[hit].astype(np.int64).sum())
            return t, hits, prims

        best, sums = {}, {}
        for _ in range(args.rounds):
            for w in (1, 4, 8, 16):
                out = subprocess.run([exe, mesh, rays, str(w), "1"], capture_output=True,
                                     text=True, check=True).stdout.split()
                key = f"C, width {w}"
                best[key] = min(best.get(key, np.inf), float(out[1]))
                sums[key] = (int(out[3]), int(out[4]))
            for bary in (False, True):
                key = f"meshladar, width {width}" + (", with u, v" if bary else "")
                t, h, p = python(bary)
                best[key] = min(best.get(key, np.inf), t)
                sums[key] = (h, p)
    print(f"{len(geo.faces32)} triangles, {len(grids)} views, {n_rays} rays; native width "
          f"{width}; best of {args.rounds} interleaved rounds")
    native = best[f"C, width {width}"]
    for key, t in best.items():
        print(f"  {key:<34} {n_rays / t / 1e6:7.2f} Mrays/s   {native / t:5.2f} x the C loop "
              f"at width {width}   hits {sums[key][0]}")
    same = len({s[0] for s in sums.values()}) == 1
    print("  same hit count in every loop: " + ("yes" if same else "NO"))
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
