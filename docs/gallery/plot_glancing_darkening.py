"""
Glancing incidence darkens the boundary
=======================================

The paper's first finding (Figs 6 and 8): a Lambertian disk reconstructs flat, with a clean
ring at its boundary, but a coating that reflects less at glancing incidence darkens the
inside of the reconstructed boundary, like beam hardening in x-ray CT with the opposite
sign. A diffuse lobe (b = 0.99) darkens a wide band; a glint (e = 0.007) a deep, narrow one.
The right panel is each image's mean over circles, near the boundary.
"""

import warnings

import matplotlib.pyplot as plt
import numpy as np

import meshladar as ml
from meshladar.errors import EnergyConservationWarning

with warnings.catch_warnings():
    # the paper's rho_d = 1, b = 0.99 surface reflects up to 1.99 of what it receives at
    # normal incidence: knowingly not energy-conserving (Sec. 4.A), as in the paper
    warnings.simplefilter("ignore", EnergyConservationWarning)
    b099 = ml.SandfordRobertson(1.0, 0.0, 0.99, 1.0, lobes="diffuse")
coatings = {"Lambertian": ml.materials.lambertian(rho_d=1.0),
            "diffuse, b = 0.99": b099,
            "glint, e = 0.007": ml.materials.glint(e=0.007)}
ladar = ml.Ladar.paper()                      # 360 views, bins A/256 over the disk A = 0.8
radii = np.linspace(0.7, 0.84, 141)

fig, axes = plt.subplots(1, 4, figsize=(13, 3.3), layout="constrained",
                         gridspec_kw={"width_ratios": [1, 1, 1, 1.4]})
for ax, (name, coating) in zip(axes, coatings.items()):
    image = ml.fbp(ml.simulate(ml.phantoms.scene("disk", coating), ladar), size=256)
    top = np.percentile(np.abs(image.values), 99.5)
    e = image.extent
    ax.imshow(image.values, cmap="gray", vmin=-0.2 * top, vmax=0.2 * top, origin="lower",
              extent=(-e, e, -e, e))
    ax.set(title=name, xticks=[], yticks=[])
    profile = image.radial_profile(radii)
    axes[3].plot(radii, profile / profile.max(), label=name)
axes[3].set(xlabel="radius (the disk's is 0.8)", ylabel="radial mean / the ring's peak",
            ylim=(-0.7, 1.05))
axes[3].legend(fontsize="small")
plt.show()
