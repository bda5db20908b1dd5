"""
Coatings compared: what a ladar sees of each BRDF
=================================================

A monostatic ladar sees each surface element at one angle, the incidence θ, and receives
its projected BRDF F(θ; −θ) cos θ (the paper's Eq. 8). The left panel draws it for four
coatings: the paper's dark gray and aluminium (Sandford–Robertson), a Lambertian surface
and a glossy GGX one. The right panel is what that does to one disk's range profile: the
Lambertian disk returns the same at every range bin it spans, a glossy coating favours
the bins near the ladar (small θ), and the aluminium's glint returns almost only from the
disk's nearest point.
"""

import matplotlib.pyplot as plt
import numpy as np

import meshladar as ml
from meshladar.materials import ALUMINUM, DARK_GRAY

coatings = {"dark gray (SR)": DARK_GRAY, "aluminium (SR)": ALUMINUM,
            "Lambertian, ρ = 0.5": ml.brdf.Lambertian(0.5), "GGX, α = 0.2": ml.brdf.GGX(alpha=0.2)}
theta = np.deg2rad(np.linspace(0.0, 89.0, 400))
ladar = ml.Ladar(angles_deg=[0.0], bin_edges=np.linspace(-1.05, 0.05, 111))

fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), layout="constrained")
for name, coating in coatings.items():
    axes[0].semilogy(np.rad2deg(theta), coating.monostatic(theta) * np.cos(theta), label=name)
    profile = ml.simulate(ml.Scene([ml.Disk((0.0, 0.0), 1.0, coating)]), ladar).values[0]
    centres = 0.5 * (ladar.bin_edges[1:] + ladar.bin_edges[:-1])
    axes[1].semilogy(centres, np.maximum(profile / profile.max(), 1e-6), label=name)
axes[0].set(xlabel="incidence θ [deg]", ylabel="F(θ; −θ) cos θ [1/sr]",
            title="what a monostatic ladar sees")
axes[1].set(xlabel="range r (the nearest point is at −1)", ylabel="relative return",
            title="a unit disk's range profile", ylim=(1e-6, 2))
axes[0].legend(fontsize="small")
plt.show()
