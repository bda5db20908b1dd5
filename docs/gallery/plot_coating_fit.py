"""
Fitting a coating, with its intervals
=====================================

With the geometry known, a coating's BRDF parameters can be fitted to measured returns.
Here the paper's pair is "measured" with Poisson noise at 10⁴ photoelectrons in the
brightest bin, and ``fit_coatings`` fits the aluminium disk's ε and e (the glint's
strength and width), the gray disk's coating known. The panels show each parameter's 95 %
interval from the normal approximation and from the profile likelihood, against the truth.
At this photon level the likelihood of a glint's strength and width is not quite
quadratic: over seeded trials the profile intervals cover the truth as often as they say,
the normal ones less often (the guide's page on coatings has the numbers).
"""

import matplotlib.pyplot as plt
import numpy as np

import meshladar as ml
from meshladar.fit import coating_kernel, fit_coatings
from meshladar.materials import ALUMINUM, DARK_GRAY

scene = ml.phantoms.scene("disk_pair", large=DARK_GRAY, small=ALUMINUM)
ladar = ml.Ladar(angles_deg=np.arange(0.0, 360.0, 5.0), bin_edges=np.linspace(-0.8, 0.8, 65))
exact = ml.simulate(scene, ladar)
k = 1e4 / exact.values.max()
measured = ml.Sinogram(np.random.default_rng(1).poisson(k * exact.values) / k,
                       angles_deg=ladar.angles_deg, bin_edges=ladar.bin_edges)
fit = fit_coatings(coating_kernel(scene, ladar), measured, noise="poisson",
                   photons_per_unit=k, free={"small": ["epsilon", "e"]})
print("\n".join(fit.report()))

ends = {method: fit.interval(0.95, method=method) for method in ("normal", "profile")}
fig, axes = plt.subplots(1, 2, figsize=(9, 3.2), layout="constrained")
for ax, name, true in zip(axes, ("small.epsilon", "small.e"), (ALUMINUM.epsilon, ALUMINUM.e)):
    i = fit.names.index(name)
    for y, (method, (low, high)) in enumerate(ends.items()):
        ax.plot([low[i], high[i]], [y, y], lw=4, label=f"{method} 95 %")
    ax.axvline(true, color="k", ls="--", label="truth")
    ax.set(title=name, yticks=[], ylim=(-1, 2))
axes[0].legend(fontsize="small")
plt.show()
