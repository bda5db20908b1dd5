"""
Doppler of a spinning target
============================

A target turning at Ω about its centre shifts each point's return by
f_D = 2 (Ω × p)·w / λ, so one view's returns spread over Doppler as well as range.
``resolve`` bins the hits of a mesh by any one to three coordinates: here range and Doppler
for a cylinder turning at 0.1 rad/s about z, seen by a 1.55 µm ladar from the side. The
range–Doppler image of a turning cylinder is an ellipse's arc (near points move across the
line of sight, the limbs along it), and its Doppler marginal is flat.
"""

import matplotlib.pyplot as plt
import numpy as np
import trimesh

import meshladar as ml
from meshladar.forward import resolve
from meshladar.motion import Motion

trimesh.creation.cylinder(radius=0.5, height=1.0, sections=256).export("drum.stl")
part = ml.Scene.from_mesh("drum.stl", material=ml.brdf.Lambertian(0.5))
ladar = ml.Ladar(angles_deg=[0.0], bin_edges=np.linspace(-0.55, 0.05, 61))
motion = Motion(omega=(0.0, 0.0, 0.1), wavelength=1.55e-6)
f = np.linspace(-7e4, 7e4, 71)                                  # Hz
rd = resolve(part, ladar, [("range", ladar.bin_edges), ("doppler", f)], motion=motion,
             radiometry="power")

fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), layout="constrained")
axes[0].imshow(rd.values[0].T, origin="lower", aspect="auto", cmap="magma",
               extent=(ladar.bin_edges[0], ladar.bin_edges[-1], f[0] / 1e3, f[-1] / 1e3))
axes[0].set(xlabel="range [m]", ylabel="Doppler [kHz]", title="range–Doppler image")
marginal = rd.marginal("doppler")
axes[1].stairs(marginal[0], f / 1e3)
axes[1].set(xlabel="Doppler [kHz]", ylabel="return", title="Doppler profile")
plt.show()
