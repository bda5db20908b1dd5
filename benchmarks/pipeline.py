"""The mesh engine's paths against raw embreex on the same rays, one thread, in interleaved
rounds, timed in CPU seconds (robust to a loaded machine): raw embreex, the packet cast in
rows of the packet width and in square tiles of the grid, and the whole run from rays to
bins (flat normals on a regular and a stratified grid, the stratified one's first hits
drawn into a depth buffer instead of cast (the "raster" backend), smooth normals, footprint
bins, and a bistatic receiver 60° off the first view, the same for every view, in received power:
under the paper's radiometry faces edge-on to the receiver would warn; and a sensor at a
standoff of 100 radii, whose perspective grid's rays are counted for it).

    python benchmarks/pipeline.py [--subdivisions 6] [--views 4] [--rounds 3]

Prints Mrays per CPU-second and each path's ratio to raw embreex, with the packet width.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

import numpy as np


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--subdivisions", type=int, default=6)       # 81,920 triangles
    ap.add_argument("--views", type=int, default=4)
    ap.add_argument("--rays-per-view", type=int, default=1_000_000)
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args(argv)

    from meshladar import materials
    from meshladar.forward.mesh import simulate_mesh
    from meshladar.ladar import Ladar
    from meshladar.meshes import fibonacci_sphere
    from meshladar.raytrace import embree4
    from meshladar.raytrace.embree import Geometry, embree_scene
    from meshladar.raytrace.grid import ray_grid
    from meshladar.sensor import Sensor
    from meshladar.studies.timing import icosphere_scene, interleaved_times

    scene = icosphere_scene(args.subdivisions, materials.DARK_GRAY)
    spacing = 1.0 / math.sqrt(args.rays_per_view)
    vecs = fibonacci_sphere(args.views)
    ladar = Ladar(None, np.linspace(-0.6, 0.6, 513), view_vectors=vecs)
    geo = Geometry(scene, "flat")
    raw, packets = embree_scene(geo, "embreex"), embree_scene(geo, "packets")
    grids = [(ray_grid(geo, w, "3d", spacing, 0.0, None),
              np.ascontiguousarray((-w)[None, :], dtype=np.float32)) for w in vecs]
    n = sum(len(g.origins) for g, _ in grids)

    def cast(engine, tiles):
        def run():
            for g, d in grids:
                engine.run(g.origins, d, output=1, columns=g.columns if tiles else 0)
        return run

    def pipeline(**options):
        options = {"backend": "packets"} | options
        return lambda: simulate_mesh(scene, ladar, mode="3d", ray_spacing=spacing, jobs=1,
                                     **options).info["rays"]

    fns = {"raw embreex cast": cast(raw, False),
           "packet cast, rows": cast(packets, False),
           "packet cast, tiles": cast(packets, True),
           "rays to bins, flat, regular grid": pipeline(sampling="regular"),
           "rays to bins, flat, stratified": pipeline(sampling="stratified"),
           "rays to bins, stratified, drawn": pipeline(sampling="stratified",
                                                       backend="raster"),
           "rays to bins, smooth normals": pipeline(normals="smooth"),
           "rays to bins, smooth normals, drawn": pipeline(normals="smooth",
                                                           backend="raster"),
           "rays to bins, footprint bins": pipeline(footprint=True),
           "rays to bins, bistatic (60 deg off)": pipeline(receiver=_off_axis(vecs[0]),
                                                           radiometry="power"),
           "rays to bins, sensor at 100 radii": pipeline(sensor=Sensor(standoff=50.0),
                                                         radiometry="power")}
    rays = {k: fn() or n for k, fn in fns.items()}   # warm-up: compile, build, cache
    times = interleaved_times(fns, repeats=args.rounds, clock=time.process_time,
                              warm_up=False)
    t = {k: statistics.median(v) for k, v in times.items()}
    ref = t["raw embreex cast"]
    print(f"{len(geo.faces)} triangles, {n} rays, packet width {embree4.library().width}, "
          f"median of {args.rounds} interleaved rounds, one thread, Mrays per CPU-second")
    for k in fns:                         # per ray: a sensor's perspective grid has its own
        rate = rays[k] / t[k]
        print(f"  {k:34s} {rate / 1e6:7.2f}   {rate / (n / ref):.2f}x raw embreex")


def _off_axis(w, degrees=60.0):
    """A unit vector ``degrees`` from w (turned about an axis perpendicular to it)."""
    axis = np.cross(w, [0.0, 0.0, 1.0] if abs(w[2]) < 0.9 else [1.0, 0.0, 0.0])
    axis /= np.linalg.norm(axis)
    a = math.radians(degrees)
    return w * math.cos(a) + np.cross(axis, w) * math.sin(a)


if __name__ == "__main__":
    main()
