"""meshladar's packet cast against a native C loop (packets.c) on the same Embree library,
scene and rays, in interleaved rounds: the issue-14 ratios "packet cast / native
rtcIntersectW loop", over rows of consecutive rays and over tiles of the ray grid.

    python benchmarks/native/native.py --include EMBREE_INCLUDE_DIR [--rounds 5]

EMBREE_INCLUDE_DIR holds ``embree4/rtcore*.h`` of Embree v4.4.0 (the version the embreex
wheel ships; ``include/embree4`` of the v4.4.0 tag, plus an ``rtcore_config.h`` made from
``kernels/rtcore_config.h.in`` with the release's CMake defaults: version 4.4.0, one
instance level, instance arrays on, min-width off). Needs gcc.

Each view's rays are a grid, row-major in rows of ``columns`` rays (``ray_grid``), cast
from the grid along the view's direction. The loops timed, each over every view:

* ``C, width W`` (1, 4, 8, 16): packets of W consecutive rays (rows of the grid);
* ``C tiles TH x TW, width W``: packets that are tiles of the grid, 4 x 4 rays at width
  16, 2 x 4 at 8, 2 x 2 at 4, row-major over tiles, the tiles cut by the grid's right or
  bottom edge packed into the first lanes and the rest masked; each ray's primID and tfar
  are written at its own index, as meshladar's cast writes them;
* ``meshladar, width W`` (the device's native width), with and without barycentrics:
  ``PacketGeometry.cast_grid`` in scan order (``columns=0``);
* ``meshladar tiles, width W``: ``cast_grid(..., columns=columns)``, the same tiles.

Prints the triangles, views, rays and the native width, then per loop its Mrays/s and
two ratios, its speed over the C row loop's and over the C tile loop's at the native
width; then the goal line, meshladar's tile cast over the C tile loop at the native width
(the issue asks for >= 0.90); then the checks: every loop found the same number of hits,
and the C tile loop and meshladar's tile cast at the native width the same primID for
every ray (the same packets through the same library). The exit status is 1 when a check
fails.
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

#: (rows, columns) of a tile per packet width, as meshladar's tile_shape.
TILES = {4: (2, 2), 8: (2, 4), 16: (4, 4)}


def _library():
    import embreex

    root = os.path.dirname(os.path.dirname(embreex.__file__))
    (lib,) = glob.glob(os.path.join(root, "embreex.libs", "libembree4*.so*"))
    return lib


def _build(include, out, name="packets"):
    """Compile ``name``.c of this folder against the embreex wheel's Embree library (its
    headers in ``include``) into ``out``; returns the executable's path."""
    lib = _library()
    exe = os.path.join(out, name)
    subprocess.run(["gcc", "-O2", "-march=native", "-std=c11", "-D_POSIX_C_SOURCE=200809L",
                    "-Wall", "-I", include,
                    os.path.join(os.path.dirname(os.path.abspath(__file__)), f"{name}.c"),
                    lib, f"-Wl,-rpath,{os.path.dirname(lib)}", "-lpthread", "-lm", "-o", exe],
                   check=True)
    return exe


def _views(geo, n_views, rays_per_view):
    """Per view: its grid's origins (n, 3) float32 in unit coordinates, the direction
    (3,) float32 and the grid's row length."""
    from meshladar.meshes import fibonacci_sphere
    from meshladar.raytrace.grid import ray_grid

    spacing = 1.0 / math.sqrt(rays_per_view)
    views = []
    for w in fibonacci_sphere(n_views):
        grid = ray_grid(geo, w, "3d", spacing, 0.0, None)
        views.append((np.ascontiguousarray(grid.origins / geo.scale, dtype=np.float32),
                      np.ascontiguousarray(-w, dtype=np.float32), grid.columns))
    return views


def _write_inputs(tmp, unit, faces, views):
    """MESH.bin and RAYS.bin for packets.c (formats in its header comment)."""
    mesh = os.path.join(tmp, "mesh.bin")
    with open(mesh, "wb") as fh:
        fh.write(np.array([len(unit), len(faces)], np.int64).tobytes())
        fh.write(np.vstack([unit, np.zeros((1, 3), np.float32)]).tobytes())
        fh.write(np.ascontiguousarray(faces, np.uint32).tobytes())
    rays = os.path.join(tmp, "rays.bin")
    with open(rays, "wb") as fh:
        fh.write(np.array([len(views)], np.int64).tobytes())
        for o, d, cols in views:
            fh.write(np.array([len(o), cols], np.int64).tobytes() + d.tobytes() + o.tobytes())
    return mesh, rays


def _meshladar(pk, views, barycentrics, tiles):
    """Seconds for meshladar's cast of every view (in tiles of its grid, or in scan order),
    then, outside the timing, the hits' count, the sum of their primIDs and every ray's
    primID (every view's in turn)."""
    t0 = time.perf_counter()
    for o, d, cols in views:
        pk.cast_grid(o, d, barycentrics=barycentrics, columns=cols if tiles else 0)
    t = time.perf_counter() - t0
    prim = np.concatenate([pk.cast_grid(o, d, columns=cols if tiles else 0)[0]
                           for o, d, cols in views])
    hit = prim >= 0
    return t, int(hit.sum()), int(prim[hit].astype(np.int64).sum()), prim


def _rounds(exe, mesh, rays, pk, views, rounds, tmp):
    """Interleaved rounds of every loop: the best seconds and the (hits, primID sum) per
    loop, the C tile loop's and meshladar's tile cast's primIDs at the native width."""
    width = pk.lib.width
    c_prims = os.path.join(tmp, "prims.bin")
    loops = [(f"C, width {w}", w, "rows") for w in (1, 4, 8, 16)]
    loops += [(f"C tiles {th} x {tw}, width {w}", w, "tiles") for w, (th, tw) in TILES.items()]
    best, sums = {}, {}
    for _ in range(rounds):
        for key, w, mode in loops:
            cmd = [exe, mesh, rays, str(w), "1", mode]
            cmd += [c_prims] if mode == "tiles" and w == width else []
            out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout.split()
            best[key] = min(best.get(key, np.inf), float(out[1]))
            sums[key] = (int(out[3]), int(out[4]))
        for bary, tiles in ((False, False), (True, False), (False, True)):
            key = (f"meshladar{' tiles' if tiles else ''}, width {width}"
                   + (", with u, v" if bary else ""))
            t, h, p, prim = _meshladar(pk, views, bary, tiles)
            best[key] = min(best.get(key, np.inf), t)
            sums[key] = (h, p)
            if tiles:
                ml_prim = prim
    return best, sums, np.fromfile(c_prims, np.int32), ml_prim


def _report(best, sums, width, c_prim, ml_prim):
    """Prints every loop's Mrays/s and ratios, the goal ratio and the checks; True when
    the checks pass."""
    n_rays = len(c_prim)
    th, tw = TILES[width]
    rows, tiles = best[f"C, width {width}"], best[f"C tiles {th} x {tw}, width {width}"]
    for key, t in best.items():
        print(f"  {key:<34} {n_rays / t / 1e6:7.2f} Mrays/s   {rows / t:5.2f} x C rows   "
              f"{tiles / t:5.2f} x C tiles   hits {sums[key][0]}")
    print(f"  meshladar tiles / C tiles at width {width}: "
          f"{tiles / best[f'meshladar tiles, width {width}']:.3f} (goal >= 0.90)")
    same = len({s[0] for s in sums.values()}) == 1
    differ = int(np.count_nonzero(c_prim != ml_prim))
    print("  same hit count in every loop: " + ("yes" if same else "NO"))
    print(f"  same primID for every ray, C tiles and meshladar tiles at width {width}: "
          + ("yes" if differ == 0 else f"NO ({differ} rays differ)"))
    return same and differ == 0


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
    from meshladar.raytrace import embree4
    from meshladar.raytrace.embree import Geometry

    scene = _icosphere_scene(args.subdivisions, materials.DARK_GRAY)
    geo = Geometry(scene, "flat")
    unit = np.ascontiguousarray(geo.shifted / geo.scale, dtype=np.float32)
    views = _views(geo, args.views, args.rays_per_view)
    pk = embree4.PacketGeometry(unit, geo.faces32)
    width = pk.lib.width

    with tempfile.TemporaryDirectory() as tmp:
        exe = _build(args.include, tmp)
        mesh, rays = _write_inputs(tmp, unit, geo.faces32, views)
        best, sums, c_prim, ml_prim = _rounds(exe, mesh, rays, pk, views, args.rounds, tmp)
    print(f"{len(geo.faces32)} triangles, {len(views)} views, {len(c_prim)} rays; native "
          f"width {width}; best of {args.rounds} interleaved rounds; ratios over the C row "
          f"and tile loops at width {width}")
    return 0 if _report(best, sums, width, c_prim, ml_prim) else 1


if __name__ == "__main__":
    sys.exit(main())
