"""
The speed/accuracy knob: ask for a tolerance
============================================

A mesh model's error comes from faceting (segments), from sampling (rays per bin) and from
the normals. ``simulate(..., tol=...)`` refines both until successive runs, extrapolated with
their measured convergence order, estimate the error at or below the tolerance. On the
paper's disk pair (dark gray beside aluminium, 36 views) the left panel is the true error
of each run against the exact analytic profiles, over the rays it cast; the right panel
puts the chosen run's profile of one view over the exact one.
"""

import matplotlib.pyplot as plt
import numpy as np

import meshladar as ml
from meshladar.materials import ALUMINUM, DARK_GRAY

scene = ml.phantoms.scene("disk_pair", large=DARK_GRAY, small=ALUMINUM)
ladar = ml.Ladar.paper(angles_deg=np.arange(0.0, 360.0, 10.0))
exact = ml.simulate(scene, ladar)                     # the analytic model: exact bins

fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), layout="constrained")
for tol, marker in ((1e-2, "o"), (1e-3, "s")):
    sino = ml.simulate(scene, ladar, model="mesh", tol=tol)
    runs = sino.info["refinement"]
    rays = [r["rays"] for r in runs]
    estimate = [r.get("error_estimate", np.nan) for r in runs]
    axes[0].loglog(rays, estimate, marker + "-", label=f"tol = {tol:g}: estimates")
    axes[0].axhline(tol, color="0.6", lw=0.8)
    error = np.linalg.norm(sino.values - exact.values) / np.linalg.norm(exact.values)
    axes[0].loglog(rays[-1], error, marker, color="k", mfc="none", ms=10)
centres = 0.5 * (ladar.bin_edges[1:] + ladar.bin_edges[:-1])
axes[1].semilogy(centres, np.maximum(exact.values[0], 1e-8), "k", label="exact (analytic)")
axes[1].semilogy(centres, np.maximum(sino.values[0], 1e-8), "--", label=f"mesh, tol = {tol:g}")
axes[0].set(xlabel="rays cast", ylabel="relative L2 error",
            title="estimates per run; circled: the chosen run's true error")
axes[1].set(xlabel="range", ylabel="return", title="view 0", ylim=(1e-6, None))
axes[0].legend(fontsize="small")
axes[1].legend(fontsize="small")
plt.show()
