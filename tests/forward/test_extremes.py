"""The numerical-stability matrix: extreme coatings, grazing facets, extreme scales, bin
counts and view counts. No NaN or inf anywhere, no numpy warnings (warnings are errors in
this suite), and the values that have closed forms keep them."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

import meshladar as ml
from meshladar.materials import ALUMINUM, DARK_GRAY, glint

EXTREME_COATINGS = {
    "b=1e-12": lambda: ml.SandfordRobertson(0.02, 0.3, 1e-12, 0.17),
    "b=1-1e-12": lambda: ml.SandfordRobertson(0.02, 0.3, 1 - 1e-12, 0.17),
    "b=1": lambda: ml.SandfordRobertson(0.02, 0.3, 1.0, 0.17),
    "e=1e-4": lambda: ml.SandfordRobertson(0.02, 0.3, 0.1, 1e-4),
    "glint e=1e-4": lambda: glint(1e-4),
}


def _pair(m):
    return ml.phantoms.scene("disk_pair", large=m, small=ALUMINUM)


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # coarse on purpose
@pytest.mark.filterwarnings("ignore:.* views are too few")   # few views on purpose: speed
@pytest.mark.parametrize("name", list(EXTREME_COATINGS))
def test_extreme_coatings_in_every_model(name):
    scene = _pair(EXTREME_COATINGS[name]())
    ladar = ml.Ladar.paper(angles_deg=[0.0, 45.0, 200.0])
    for model, opts in (("analytic", {}), ("mesh", {"normals": "exact"}),
                        ("mesh", {"footprint": True}), ("pixel", {"pixel_size": 0.005})):
        sino = ml.simulate(scene, ladar, model=model, **opts)
        assert np.all(np.isfinite(sino.values)) and np.all(sino.values >= 0), (model, opts)
    image = ml.fbp(ml.simulate(scene, ml.Ladar.paper(angles_deg=np.arange(0.0, 360.0, 5.0))),
                   size=64)
    assert np.all(np.isfinite(image.values))


def test_grazing_facets():
    # a plate seen within 1e-6 rad of its own plane: cos θ ~ 1e-6, F·δA⊥ stays finite
    plate = trimesh.Trimesh(vertices=[[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]],
                            faces=[[0, 1, 2], [0, 2, 3]])
    for m in (DARK_GRAY, ALUMINUM, glint(1e-4)):
        scene = ml.Scene.from_mesh(plate, m)
        for tilt in (1e-3, 1e-6):
            w = [math.cos(tilt), 0.0, math.sin(tilt)]           # nearly in the plate's plane
            lad = ml.Ladar(None, np.linspace(-2, 2, 41), view_vectors=[w])
            hits = ml.trace(scene, lad, mode="3d", ray_spacing=1e-4)
            if hits.size:
                np.testing.assert_allclose(hits.cos_theta, math.sin(tilt), rtol=1e-6)
            sino = ml.weigh(hits)
            assert np.all(np.isfinite(sino.values))
            if tilt == 1e-3:
                # projected area 2·2·sin(tilt), ~20 rays across it: every ray weighs F(θ)δA⊥
                expected = m.monostatic(math.pi / 2 - tilt) * 4 * math.sin(tilt)
                assert sino.total()[0] == pytest.approx(expected, rel=0.06)


@pytest.mark.filterwarnings("ignore:.* views are too few")   # few views on purpose: speed
@pytest.mark.parametrize("scale", [1e-3, 1e4])
def test_extreme_scales(scale):
    # lengths scale, bin integrals (per unit height) scale with them, F does not
    base = _pair(DARK_GRAY)
    big = ml.Scene([ml.Disk((-0.3 * scale, 0.0), 0.4 * scale, DARK_GRAY),
                    ml.Disk((0.4 * scale, 0.0), 0.3 * scale, ALUMINUM)])
    lad = ml.Ladar.paper(angles_deg=[10.0, 100.0])
    lad_s = ml.Ladar(lad.angles_deg, lad.bin_edges * scale)
    ref = ml.simulate(base, lad)
    got = ml.simulate(big, lad_s)
    np.testing.assert_allclose(got.values, ref.values * scale, rtol=1e-9,
                               atol=1e-12 * scale * ref.values.max())
    mesh = ml.simulate(big, lad_s, model="mesh", normals="exact")
    mref = ml.simulate(base, lad, model="mesh", normals="exact")
    # float32 rounds the scaled geometry differently, so single rays near silhouettes may
    # change bins; totals and the sinogram as a whole agree
    np.testing.assert_allclose(mesh.total(), mref.total() * scale, rtol=1e-3)
    # (aluminium's glint is sampled by a handful of rays at 8 per bin: a ray that moves
    # changes the glint bins by ~1e-3 of the sinogram; measured 1.9e-3)
    assert np.linalg.norm(mesh.values - mref.values * scale) <= 5e-3 * np.linalg.norm(
        mref.values * scale)
    image = ml.fbp(got, size=32, extent=scale)
    assert np.all(np.isfinite(image.values))


@pytest.mark.parametrize("scale", [1e-25, 1e-15, 1e-9, 1e9, 1e15, 1e25])
def test_meshes_at_any_scale_give_the_same_profile(scale):
    # Embree alone misses a 1e-16 or 1e14 sphere outright; the engine traces a unit-size copy
    # (a power-of-two scale, exact in float32), so the profile scales exactly as area does.
    # A power-of-two scale factor keeps every float32 origin and vertex the same bits.
    sphere = trimesh.creation.icosphere(subdivisions=2, radius=0.5)
    base = ml.Scene.from_mesh(sphere, material=DARK_GRAY)
    s = 2.0 ** round(math.log2(scale))
    big = ml.Scene.from_mesh(trimesh.Trimesh(sphere.vertices * s, sphere.faces, process=False),
                             material=DARK_GRAY)
    lad = ml.Ladar.covering(base, n_bins=32, angles_deg=[0.0, 60.0])
    lad_s = ml.Ladar(lad.angles_deg, lad.bin_edges * s)
    ref = ml.simulate(base, lad, model="mesh", ray_spacing=0.02)
    got = ml.simulate(big, lad_s, model="mesh", ray_spacing=0.02 * s)
    assert np.all(np.isfinite(got.values))
    # the same rays on the same float32 geometry: equal to float64 round-off of the scale
    np.testing.assert_allclose(got.values, ref.values * s * s, rtol=1e-12)


@pytest.mark.parametrize("radius", [1e-35, 1e35])
def test_mesh_sizes_beyond_the_engine_are_refused(radius):
    unit = trimesh.creation.icosphere(subdivisions=1)
    sphere = trimesh.Trimesh(unit.vertices * radius, unit.faces, process=False)
    scene = ml.Scene.from_mesh(sphere, material=DARK_GRAY)
    lad = ml.Ladar(np.array([0.0]), np.linspace(-2 * radius, 2 * radius, 9))
    with pytest.raises(ml.errors.ParameterError, match=r"bounding radius is .* the mesh engine "
                                                       r"traces sizes in \[1e-30, 1e\+30\]"):
        ml.simulate(scene, lad, model="mesh")


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # faceted on purpose
def test_a_mesh_far_from_the_origin_for_its_size_warns():
    sphere = trimesh.creation.icosphere(subdivisions=1, radius=1e-3)
    sphere.apply_translation([1e7, 0.0, 0.0])
    scene = ml.Scene.from_mesh(sphere, material=DARK_GRAY)
    lad = ml.Ladar.covering(scene, n_bins=16, angles_deg=[0.0])
    with pytest.warns(ml.errors.MeshladarWarning, match=r"lies 1e\+07 from the origin"):
        ml.simulate(scene, lad, model="mesh")


@pytest.mark.filterwarnings("ignore:.* views are too few")   # few views on purpose: speed
@pytest.mark.parametrize("n_bins", [1, 8192])
def test_extreme_bin_counts(n_bins):
    scene = _pair(DARK_GRAY)
    lad = ml.Ladar.centered(n_bins, 1.6 / n_bins, angles_deg=[0.0, 33.0, 250.0])
    exact = ml.simulate(scene, lad)
    # the total per view does not depend on the binning
    ref = ml.simulate(scene, ml.Ladar.paper(angles_deg=[0.0, 33.0, 250.0]))
    np.testing.assert_allclose(exact.total(), ref.total(), rtol=1e-11)
    # the ray density is the user's choice, not the bins': the same rays either way
    mesh = ml.simulate(scene, lad, model="mesh", normals="exact", ray_spacing=4e-4)
    assert np.all(np.isfinite(mesh.values))
    np.testing.assert_allclose(mesh.total(), ref.total(), rtol=0.02)
    few = ml.simulate(scene, ml.Ladar.centered(n_bins, 1.6 / n_bins,
                                               angles_deg=np.arange(0.0, 360.0, 30.0)))
    if n_bins == 1:                    # one bin: finite, and said to have no resolution
        with pytest.warns(ml.errors.MeshladarWarning, match="one range bin"):
            image = ml.fbp(few, size=16)
    else:
        image = ml.fbp(few, size=16)
    assert np.all(np.isfinite(image.values))


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # coarse on purpose
@pytest.mark.parametrize("n_views", [1, pytest.param(3600, marks=pytest.mark.slow)])
def test_extreme_view_counts(n_views):
    scene = _pair(ALUMINUM)
    angles = np.arange(n_views) * (360.0 / n_views)
    lad = ml.Ladar.paper(angles_deg=angles)
    sino = ml.simulate(scene, lad)
    assert sino.shape == (n_views, 512) and np.all(np.isfinite(sino.values))
    mesh = ml.simulate(scene, lad, model="mesh", rays_per_bin=1, normals="exact")
    assert np.all(np.isfinite(mesh.values))
    if n_views == 1:
        with pytest.warns(ml.errors.MeshladarWarning, match="one view does not cover"):
            image = ml.fbp(sino, size=32)          # a single view: a smeared backprojection
    else:
        image = ml.fbp(sino, size=128)
        # 3600 views remove most of the angular aliasing that 360 views leave around the
        # bright rings: less ripple outside the scene
        coarse = ml.fbp(ml.simulate(scene, ml.Ladar.paper()), size=128)
        X, Y = np.meshgrid(image.x, image.y)
        outside = np.hypot(X, Y) > 0.75
        assert image.values[outside].std() < 0.5 * coarse.values[outside].std()
    assert np.all(np.isfinite(image.values))
