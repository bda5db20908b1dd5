"""The coating kernel's θ tables (meshladar.fit._tables): the projected monostatic weight on
θ = (π/2) u², interpolated (cubic in u), against the BRDF evaluated at each angle; and a
narrow glint's kernel against the analytic model's exact profiles."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import meshladar as ml
from meshladar import materials
from meshladar.brdf import SandfordRobertson, projected_weight
from meshladar.fit import GRID, coating_kernel
from meshladar.fit._sampling import interp_matrix
from meshladar.fit._tables import _table, grid_position
from meshladar.ladar import Ladar
from meshladar.scene import Scene
from meshladar.studies import paper

#: The interpolated table's largest error, relative to its peak, at any angle.
TABLE_RTOL = 1e-4


@pytest.mark.parametrize("e", [1e-5, 2.4e-4, 1e-3, 0.007, 0.3])
def test_a_glints_table_interpolates_to_its_brdf(e):
    """An SR coating's table (cubic in u) at 20,000 random angles, half of them within 5 e
    of normal incidence where the glint is, equals the BRDF's projected weight evaluated
    there to TABLE_RTOL of the peak, for glints from 1e-5 to 0.3 rad wide (an even grid
    of 8193 angles put 1.3 samples across 2.4e-4 rad)."""
    coating = SandfordRobertson(0.05, 0.5, 0.1, e)
    rng = np.random.default_rng(0)
    theta = np.concatenate([rng.uniform(0.0, min(5.0 * e, 0.5 * np.pi), 10_000),
                            rng.uniform(0.0, 0.5 * np.pi, 10_000)])
    M = interp_matrix(np.arange(theta.size), theta, np.ones(theta.size), theta.size, GRID,
                      cubic=True)
    got = M @ _table(coating)
    want = projected_weight(coating, np.cos(theta), np.sin(theta))
    assert np.max(np.abs(got - want)) <= TABLE_RTOL * want.max()


def test_the_grid_is_quadratic_and_its_positions_invert_it():
    """θ_k = (π/2) (k / (GRID − 1))²: grid_position gives back k at every grid angle, and
    the spacing at θ is √(2πθ)/(GRID − 1) to first order."""
    from meshladar.fit._tables import _THETA

    k = np.arange(GRID)
    np.testing.assert_allclose(_THETA, 0.5 * np.pi * (k / (GRID - 1)) ** 2, rtol=1e-15)
    np.testing.assert_allclose(grid_position(_THETA), k, atol=1e-9)
    i = GRID // 100
    np.testing.assert_allclose(_THETA[i + 1] - _THETA[i],
                               np.sqrt(2 * np.pi * _THETA[i]) / (GRID - 1), rtol=0.01)


#: The pair's kernel against the exact profiles, in noise σ at 10⁴ photoelectrons in the
#: brightest bin (the fit's kernel tolerance is 0.1 σ).
KERNEL_SIGMA_TOL = 0.05


@pytest.mark.slow
def test_a_narrow_glints_kernel_converges_to_the_exact_profiles():
    """Fig. 10(a)'s pair with the aluminium's glint narrowed to e = 2.4e-4 (ε 0.9, where
    fits at 10⁴ photoelectrons had settled): the kernel at 65536 pieces per boundary is
    within KERNEL_SIGMA_TOL of the analytic model's exact profiles in every bin, in noise σ
    at 10⁴ photoelectrons (the even 8193-angle grid left 0.57 σ at any number of pieces)."""
    lad = Ladar(np.arange(0.0, 360.0, 6.0), Ladar.centered(64, 1.6 / 64).bin_edges)
    scene = paper._pair(materials.DARK_GRAY, materials.ALUMINUM)
    k = 1e4 / ml.simulate(scene, lad, model="analytic").values.max()
    kernel = coating_kernel(scene, lad, samples=65536)
    i = kernel.part_index("small")
    mats = [s.material for s in scene.shapes]
    mats[i] = dataclasses.replace(mats[i], e=2.4e-4, epsilon=0.9)
    narrow = Scene([dataclasses.replace(s, material=m) for s, m in zip(scene.shapes, mats)])
    exact = ml.simulate(narrow, lad, model="analytic").values
    sigma = np.sqrt(np.maximum(exact * k, 1.0)) / k
    assert np.max(np.abs(kernel.predict(mats) - exact) / sigma) <= KERNEL_SIGMA_TOL
