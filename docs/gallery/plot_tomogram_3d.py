"""
A 3-D tomogram from views over the sphere
=========================================

Range profiles from views spread over the sphere are plane integrals of the surface's
return, and ``fbp3d`` inverts them with the 3-D formula. A Lambertian ball seen from 600
Fibonacci directions comes back as a shell at its radius; three slices through the volume
show it.
"""

import matplotlib.pyplot as plt
import numpy as np
import trimesh

import meshladar as ml
from meshladar.meshes import fibonacci_sphere
from meshladar.reconstruct.volumes import fbp3d

trimesh.creation.icosphere(subdivisions=4, radius=0.5).export("ball.stl")
part = ml.Scene.from_mesh("ball.stl", material=ml.brdf.Lambertian(0.5))
ladar = ml.Ladar(None, np.linspace(-0.8, 0.8, 65), view_vectors=fibonacci_sphere(600))
volume = fbp3d(ml.simulate(part, ladar, model="mesh", radiometry="power"), size=64,
               smooth=1.5)
v = volume.values                     # v[k, i, j] at (x[j], y[i], z[k])
mid = [n // 2 for n in v.shape]
cuts = {"z = 0": (v[mid[0]], volume.x, volume.y), "y = 0": (v[:, mid[1]], volume.x, volume.z),
        "x = 0": (v[:, :, mid[2]], volume.y, volume.z)}
fig, axes = plt.subplots(1, 3, figsize=(11, 3.6), layout="constrained")
top = np.abs(v).max()
for ax, (title, (cut, a, b)) in zip(axes, cuts.items()):
    ax.imshow(cut, cmap="gray", vmin=-top, vmax=top, origin="lower",
              extent=(a[0], a[-1], b[0], b[-1]))
    ax.set(title=title)
plt.show()
