"""The pixel model (the paper's method): converges toward the exact profiles."""

from __future__ import annotations

import math

import numpy as np
import pytest

import meshladar as ml
from meshladar.materials import DARK_GRAY, lambertian
from meshladar.forward.pixel import rasterize
from meshladar.forward.siddon import PixelGrid

PAPER = ml.Ladar.paper()


def _pair(big, small):
    return ml.phantoms.scene("disk_pair", large=big, small=small)


def test_rasterized_boundary_and_normals():
    scene = ml.Scene([ml.Disk((0.1, 0.0), 0.5, DARK_GRAY)])
    grid = PixelGrid.square(200, 1.0)
    owner, normal = rasterize(scene, grid)
    X, Y = np.meshgrid(grid.x, grid.y)
    r = np.hypot(X - 0.1, Y)
    on = owner == 0
    # pixels whose centre is inside; the filled area is the disk's to O(perimeter·pixel);
    # normals point radially outward
    np.testing.assert_array_equal(on, r < 0.5)
    assert on.sum() * grid.pixel_size**2 == pytest.approx(math.pi * 0.25, rel=grid.pixel_size)
    radial = np.stack([(X - 0.1)[on], Y[on]], -1) / np.maximum(r[on], 1e-300)[:, None]
    ok = r[on] > 0
    np.testing.assert_allclose(np.einsum("ij,ij->i", normal[on][ok], radial[ok]), 1.0,
                               rtol=1e-12)


def test_lambertian_disk_total():
    A, rho_d, pix = 0.8, 0.7, 0.005
    sino = ml.simulate(ml.Scene([ml.Disk((0, 0), A, lambertian(rho_d))]),
                       ml.Ladar.paper(angles_deg=[0.0, 17.0, 45.0]), model="pixel",
                       pixel_size=pix)
    # every ray that meets the rasterised disk deposits (ρd/π)·δs: the projected width
    # 2A ± a pixel at each side
    np.testing.assert_allclose(sino.total(), 2 * A * rho_d / math.pi,
                               rtol=2 * pix / (2 * A))
    assert sino.model == "pixel" and sino.info["pixel_size"] == pix


def test_converges_toward_the_analytic_profiles():
    scene = _pair(DARK_GRAY, DARK_GRAY)
    lad = ml.Ladar.paper(angles_deg=[30.0, 60.0, 90.0, 150.0])
    exact = ml.simulate(scene, lad)
    errors = []
    for pix in (0.01, 0.005, 0.0025):
        px = ml.simulate(scene, lad, model="pixel", pixel_size=pix)
        errors.append(np.linalg.norm(px.values - exact.values) / np.linalg.norm(exact.values))
        last = px
    # pixelation error falls with the pixel size (measured 1.06, 0.46, 0.28)
    assert errors[0] > errors[1] > errors[2]
    # and the returned power per view is right to a few per cent (measured ≤ 3%)
    np.testing.assert_allclose(last.total(), exact.total(), rtol=0.05)


def test_shadow_gap_is_dark():
    px = ml.simulate(_pair(DARK_GRAY, DARK_GRAY), ml.Ladar.paper(angles_deg=[0.0]),
                     model="pixel", pixel_size=0.0025)
    edges = px.bin_edges
    margin = 2 * 0.0025
    gap = (edges[:-1] >= -0.4 + margin) & (edges[1:] <= 0.3 - math.sqrt(0.07) - margin)
    assert gap.sum() > 100 and np.all(px.values[0][gap] == 0.0)


def test_bad_options():
    scene = _pair(DARK_GRAY, DARK_GRAY)
    with pytest.raises(ml.errors.ParameterError, match=r"pixel_size must be in \(0, inf\)"):
        ml.simulate(scene, PAPER, model="pixel", pixel_size=0.0)
    with pytest.raises(ml.errors.ParameterError, match=r"model 'pixel' takes options "
                                                        r"\('pixel_size', 'ray_spacing', "
                                                        r"'radiometry', 'jobs', "
                                                        r"'executor', 'progress', 'run_dir'\)"):
        ml.simulate(scene, PAPER, model="pixel", tol=0.1)
