"""
The paper's pair: glints hide the diffuse disk, the log brings it back
======================================================================

Jin & Levine's Fig. 10: a large dark-gray disk beside a small aluminium one. The aluminium's
glint (its specular lobe is 0.007 wide) outshines everything in the sinogram, so filtered
backprojection of the radiance shows the small disk and a faint ring; backprojecting the
logarithm of the radiance brings the gray disk back.
"""

import matplotlib.pyplot as plt
import numpy as np

import meshladar as ml
from meshladar.materials import ALUMINUM, DARK_GRAY


def _square(img):
    """The image's square as matplotlib's extent (left, right, bottom, top)."""
    (cx, cy), e = img.center, img.extent
    return (cx - e, cx + e, cy - e, cy + e)


scene = ml.phantoms.scene("disk_pair", large=DARK_GRAY, small=ALUMINUM)
ladar = ml.Ladar.paper()                      # 360 views, 512 bins over [-0.8, 0.8]
sino = ml.simulate(scene, ladar)              # exact profiles (the analytic model)
plain = ml.fbp(sino, size=256)
logged = ml.fbp(ml.log_radiance(sino), size=256)

fig, axes = plt.subplots(1, 3, figsize=(11, 3.6), layout="constrained")
axes[0].imshow(np.log10(np.maximum(sino.values, 1e-6)), aspect="auto", cmap="magma",
               extent=(sino.bin_edges[0], sino.bin_edges[-1], 360, 0))
axes[0].set(title="log10 sinogram", xlabel="range", ylabel="view angle [deg]")
for ax, img, title in ((axes[1], plain, "FBP of the radiance"),
                       (axes[2], logged, "FBP of log radiance")):
    top = np.percentile(np.abs(img.values), 99.5)
    ax.imshow(img.values, cmap="gray", vmin=-top, vmax=top, origin="lower",
              extent=_square(img))
    ax.set(title=title, xlabel="x", ylabel="y")
plt.show()
