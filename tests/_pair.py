"""Fig. 10(a)'s gray/aluminium pair measured at a photon level: the analytic model's exact
profiles plus seeded Poisson counts, and the pair's coating kernel at 2048 samples."""

from __future__ import annotations

import numpy as np

import meshladar as ml
from meshladar import materials
from meshladar.fit import coating_kernel
from meshladar.ladar import Ladar
from meshladar.studies import paper

LAD = Ladar(np.arange(0.0, 360.0, 6.0), Ladar.centered(64, 1.6 / 64).bin_edges)


def pair_counts(seed, level=1e4):
    """(scene, kernel, measured Sinogram, counts per unit): ``level`` photoelectrons in the
    brightest bin, Poisson counts of seed ``seed``."""
    scene = paper._pair(materials.DARK_GRAY, materials.ALUMINUM)
    exact = ml.simulate(scene, LAD, model="analytic").values
    k = level / exact.max()
    y = np.random.default_rng(seed).poisson(exact * k) / k
    measured = ml.Sinogram(y, angles_deg=LAD.angles_deg, bin_edges=LAD.bin_edges,
                           info={"radiometry": "paper"})
    return scene, coating_kernel(scene, LAD, samples=2048), measured, k
