"""
Your own mesh: two parts, two coatings, a sinogram and its reconstruction
=========================================================================

Any triangle mesh works (STL, OBJ, PLY, glTF...). Here two STL files are made on the spot
with trimesh — a dark-gray cylinder and a glossy sphere beside it (a GGX coating, roughness
0.2) — and loaded as one scene, each part with its own coating. The mesh model traces them with Embree from 90 views
about the z axis; the bins cover the ranges the scene spans. Reflection tomography of the
log radiance then shows both parts.
"""

import matplotlib.pyplot as plt
import numpy as np
import trimesh

import meshladar as ml
from meshladar.materials import DARK_GRAY


def _square(img):
    """The image's square as matplotlib's extent (left, right, bottom, top)."""
    (cx, cy), e = img.center, img.extent
    return (cx - e, cx + e, cy - e, cy + e)


trimesh.creation.cylinder(radius=0.35, height=0.5, sections=128).export("body.stl")
trimesh.creation.icosphere(subdivisions=4, radius=0.15).apply_translation(
    (0.55, 0.0, 0.0)).export("dome.stl")

scene = ml.Scene.from_meshes([("body.stl", DARK_GRAY), ("dome.stl", ml.brdf.GGX(alpha=0.2))])
ladar = ml.Ladar.covering(scene, n_bins=256, angles_deg=np.arange(0.0, 360.0, 4.0))
sino = ml.simulate(scene, ladar, model="mesh", normals="smooth")
image = ml.fbp(ml.log_radiance(sino), size=256)

fig, axes = plt.subplots(1, 2, figsize=(9, 3.8), layout="constrained")
axes[0].imshow(np.log10(np.maximum(sino.values, 1e-8)), aspect="auto", cmap="magma",
               extent=(sino.bin_edges[0], sino.bin_edges[-1], 360, 0))
axes[0].set(title="log10 sinogram (mesh model)", xlabel="range", ylabel="view angle [deg]")
top = np.percentile(np.abs(image.values), 99.5)
axes[1].imshow(image.values, cmap="gray", vmin=-top, vmax=top, origin="lower",
               extent=_square(image))
axes[1].set(title="FBP of log radiance", xlabel="x", ylabel="y")
plt.show()
