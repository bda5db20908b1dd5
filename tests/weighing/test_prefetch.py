"""The weigh loops' prefetch (meshladar/weighing/_prefetch.py) changes no number: with it
compiled in for every mesh (PREFETCH_FROM = 0, in a subprocess with its own numba cache:
the loops read the constant when they compile), the packet backend's fused loops still
give the sinograms of embreex's per-hit path, whose weights and bins are numpy's."""

import json
import os
import subprocess
import sys

import pytest

#: The fused loops against the per-hit path (their summation orders differ).
SAME_RTOL = 1e-12

_SCRIPT = r"""
import json, sys
import numpy as np
import meshladar.weighing._prefetch as P
P.PREFETCH_FROM = 0                          # before any loop compiles: prefetch everywhere
import meshladar as ml
from meshladar.materials import ALUMINUM, DARK_GRAY
from meshladar.sensor import Sensor

parts = [ml.meshes.sphere((0.1, -0.2, 0.3), 0.5, 0, subdivisions=3),
         ml.meshes.sphere((0.6, 0.4, 0.1), 0.2, 1, subdivisions=2)]
scene = ml.Scene.from_parts(parts, [DARK_GRAY, ALUMINUM])
ladar = ml.Ladar.covering(scene, n_bins=48, view_vectors=ml.meshes.fibonacci_sphere(4))
cases = {"flat": {}, "footprint": {"footprint": True}, "smooth": {"normals": "smooth"},
         "bistatic": {"receiver": (0.3, 0.5, 0.81), "radiometry": "power"},
         "sensor": {"sensor": Sensor(standoff=20.0), "radiometry": "power"}}
out = {"ahead": int(P.ahead(np.zeros((2, 3)))), "cases": {}}
for name, options in cases.items():
    a = ml.simulate(scene, ladar, model="mesh", backend="embreex", rays_per_bin=3, **options)
    b = ml.simulate(scene, ladar, model="mesh", backend="packets", rays_per_bin=3, **options)
    scale = float(np.abs(a.values).max())
    out["cases"][name] = [scale, float(np.abs(b.values - a.values).max() / scale),
                          float((np.abs(b.values - a.values)
                                 / np.maximum(np.abs(a.values), 1e-300)).max()),
                          a.info["backend"], b.info["backend"]]
print(json.dumps(out))
"""


@pytest.mark.slow
def test_the_fused_loops_with_their_prefetch_give_the_per_hit_numbers(tmp_path):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    run = subprocess.run([sys.executable, "-c", _SCRIPT], env=env, capture_output=True,
                         text=True, check=False)
    assert run.returncode == 0, run.stderr[-3000:]
    got = json.loads(run.stdout.strip().splitlines()[-1])
    assert got["ahead"] == 32                        # the prefetch was compiled in
    assert sorted(got["cases"]) == ["bistatic", "flat", "footprint", "sensor", "smooth"]
    for name, (scale, abs_err, _, backend_a, backend_b) in got["cases"].items():
        assert (backend_a, backend_b) == ("embreex", "packets"), name
        assert scale > 0, name
        assert abs_err <= SAME_RTOL, (name, abs_err)
