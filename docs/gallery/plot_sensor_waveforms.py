"""
A sensor at 2 km: received photoelectrons, waveforms and noise
==============================================================

A part traced from a finite standoff with a Gaussian beam and a link budget comes out in
photoelectrons per range bin. ``receive`` turns each view's bins into a digitiser's samples
(a 1 ns pulse, a 0.5 ns receiver response, 5 GS/s), and ``Waveforms.realise`` draws noisy
records from a receiver model: speckle, Poisson photoelectrons with background and dark
counts, an avalanche gain with excess noise, and 12-bit quantisation. The band is the
middle 90 % of 200 draws.
"""

import matplotlib.pyplot as plt
import numpy as np
import trimesh

import meshladar as ml
from meshladar.noise import Noise
from meshladar.sensor import GaussianBeam, Sensor
from meshladar.waveforms import GaussianPulse, receive

trimesh.creation.icosphere(subdivisions=3, radius=0.5).export("ball.stl")
part = ml.Scene.from_mesh("ball.stl", material=ml.materials.DARK_GRAY)
ladar = ml.Ladar.covering(part, n_bins=64, angles_deg=[0.0])
sensor = Sensor(standoff=2000.0, beam=GaussianBeam(waist=0.01, divergence=2e-4),
                pulse_energy=1e-4, aperture_diameter=0.1)
sino = ml.simulate(part, ladar, model="mesh", radiometry="power", sensor=sensor)
waves = receive(sino, sample_rate=5e9, pulse=GaussianPulse(fwhm=1e-9),
                response=GaussianPulse(fwhm=0.5e-9))
noise = Noise(speckle_cells=4, background_rate=2e8, dark_rate=1e7, excess_noise_factor=2.5,
              gain=10, bits=12, full_scale=2e5)
draws = waves.realise(noise, 200, seed=0)

t = 0.5 * (waves.time_edges[1:] + waves.time_edges[:-1]) * 1e9
low, high = np.percentile(draws[:, 0] / noise.gain, [5, 95], axis=0)
fig, ax = plt.subplots(figsize=(7, 3.6), layout="constrained")
ax.fill_between(t, low, high, alpha=0.3, label="noisy records ÷ gain, 5–95 %")
ax.plot(t, waves.values[0], "k", label="expected signal")
ax.set(xlabel="two-way time [ns]", ylabel="photoelectrons per sample",
       title=f"{sino.info['units']} at {sensor.standoff:.0f} m")
ax.legend()
plt.show()
