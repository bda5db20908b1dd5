"""
The 3-D viewer: what the ladar sees of a scene
==============================================

``meshladar.viz.viewer.show_scene`` draws a scene with pyvista, off screen here: the
paper's pair seen from 20° above its plane, first hits coloured by their range bin over the
returns, the shadowed side of the large disk and the faces turned away in flat colours,
the beam's ray grid and the iso-range planes. On a desktop the same call opens a window
you can turn; ``meshladar view`` is the command line's door to it.
"""

import matplotlib.pyplot as plt

import meshladar as ml
from meshladar.materials import ALUMINUM, DARK_GRAY
from meshladar.viz import viewer

scene = ml.phantoms.scene("disk_pair", large=DARK_GRAY, small=ALUMINUM)
ladar = ml.Ladar.paper(angles_deg=[0.0])
shown = viewer.show_scene(scene, ladar=ladar, view_angle_deg=20.0, off_screen=True,
                          window_size=(900, 640))

fig, ax = plt.subplots(figsize=(9, 6.4), layout="constrained")
ax.imshow(shown.image)
ax.set_axis_off()
plt.show()
