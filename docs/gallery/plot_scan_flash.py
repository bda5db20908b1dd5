"""
A flash frame and a spinning head's range errors
================================================

A 64 × 64 flash array 2.5 m above the floor of a room looks at an aluminium crate before a
dark gray wall: its range image shows the crate's face nearer than the wall, its intensity
image (log scale) the aluminium's glint where the crate's face is square to the sensor. A
spinning 32-channel head in the same room gives a point cloud whose every return carries
its truth: the histogram of measured minus true range is the receiver's sub-sample timing
error, a fraction of a millimetre against a 7.5 cm sample (2 GS/s).
"""

import matplotlib.pyplot as plt
import numpy as np
import trimesh

import meshladar as ml
from meshladar import scan as sc

room = trimesh.creation.box((40.0, 40.0, 12.0))
crate = trimesh.creation.box((2.0, 6.0, 3.0))
crate.apply_translation((8.0, 1.0, -4.5))
scene = ml.Scene.from_meshes([(room, ml.materials.DARK_GRAY), (crate, ml.materials.ALUMINUM)])

flash = sc.flash(64, 64, ifov_deg=0.25)
camera = sc.Platform.static((-12.0, 0.0, -3.5))
frame = sc.scan(scene, flash, camera,
                sc.ScanSensor(pulse_energy=1e-3, aperture_diameter=0.05, sample_rate=2e9))

head = sc.rotating(np.linspace(-15, 15, 32), rotation_hz=10, pulse_rate=3e5, duration=0.1)
cloud = sc.scan(scene, head, sc.Platform.moving((0.0, 0.0, 0.0), (10.0, 0.0, 0.0)),
                sc.ScanSensor(pulse_energy=1e-7, aperture_diameter=0.05, sample_rate=2e9,
                              beam=sc.ScanBeam(5e-4, sub_rays=16)))
print(f"{len(cloud)} returns from {len(head)} pulses; range error RMS "
      f"{1e3 * np.sqrt(np.nanmean(cloud.range_error ** 2)):.2f} mm")

fig, axes = plt.subplots(1, 3, figsize=(11, 3.4), layout="constrained")
im = axes[0].imshow(frame.image("range"), cmap="viridis")
fig.colorbar(im, ax=axes[0], label="range [m]")
im = axes[1].imshow(np.log10(frame.image("intensity")), cmap="magma")
fig.colorbar(im, ax=axes[1], label="log10 photoelectrons")
for ax, title in zip(axes[:2], ("flash frame: range", "flash frame: intensity")):
    ax.set(title=title, xticks=[], yticks=[])
axes[2].hist(1e3 * cloud.range_error, bins=60)
axes[2].set(title="spinning head: measured - true range", xlabel="mm", ylabel="returns")
plt.show()
