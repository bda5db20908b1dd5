"""
Doppler of a spinning target
============================

A target turning at Ω about its centre shifts each point's return by
f_D = 2 (Ω × p)·w / λ, so one view's returns spread over Doppler as well as range.
``resolve`` bins the hits of a mesh by any one to three coordinates: here range and Doppler
for a cylinder turning at 0.1 rad/s about z, seen by a 1.55 µm ladar from the side. The
range–Doppler image of a turning cylinder is an ellipse's arc (near points move across the
line of sight, the limbs along it). A point at φ from the line of sight shifts by
f_max sin φ and returns as cos²φ (the received-power radiometry: both cosines), so the
Doppler marginal is a semicircle, √(1 − (f/f_max)²) (the paper's radiometry, one cosine
fewer, would make it flat), f_max = 2 Ω R / λ = 64.5 kHz.
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
f_max = 2 * 0.1 * 0.5 / 1.55e-6
centre, inside = 0.5 * (f[1:] + f[:-1]), slice(8, 62)       # |f| < 0.83 f_max
semicircle = np.sqrt(np.clip(1 - (centre / f_max) ** 2, 0.0, None))
assert round(f_max / 1e3, 1) == 64.5
assert np.allclose(marginal[0][inside] / marginal[0][35], semicircle[inside], atol=0.03)
axes[1].stairs(marginal[0], f / 1e3)
axes[1].set(xlabel="Doppler [kHz]", ylabel="return", title="Doppler profile")
plt.show()
