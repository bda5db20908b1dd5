"""The mesh engine: Embree first hits, weights and bins against closed forms and the exact
analytic profiles; trace once and re-weigh; mesh checks; precision far away and tiny."""

from __future__ import annotations

import math
import warnings
from types import SimpleNamespace

import numpy as np
import pytest
import trimesh
from scipy import integrate

import meshladar as ml
from meshladar import meshes as mlmesh
from meshladar.errors import (GeometryError, LobeSamplingWarning, MeshladarWarning,
                              ParameterError)
from meshladar.forward.mesh import first_hits
from meshladar.weighing.faces import check_edge_on_receiver
from meshladar.materials import ALUMINUM, DARK_GRAY, lambertian

from conftest import PAIR  # noqa: E402  (the shared disk pair)


def _rel(a, b):
    return np.linalg.norm(a - b) / np.linalg.norm(b)


def _sphere_scene(material, radius=0.5, subdivisions=5, center=(0.0, 0.0, 0.0)):
    part = mlmesh.sphere(center, radius, 0, subdivisions=subdivisions)
    return ml.Scene._from_parts([part], [material])


@pytest.mark.parametrize("material", [lambertian(0.6), DARK_GRAY], ids=["lambertian", "gray"])
def test_sphere_3d_range_profile(material):
    # rings at polar angle θ about the view axis: dA = 2πR² sin θ dθ at range r_c − R cos θ,
    # so P[k] = 2πR² ∫ F(θ) cos θ sin θ dθ over the θ of bin k
    R = 0.5
    scene = _sphere_scene(material, R)
    edges = np.linspace(-R, R, 33)
    views = ml.meshes.fibonacci_sphere(3)
    ladar = ml.Ladar(None, edges, view_vectors=views)
    sino = ml.simulate(scene, ladar, model="mesh", normals="exact", rays_per_bin=12,
                       footprint=True)
    expected = np.zeros(32)
    for k in range(32):
        lo, hi = max(edges[k], -R), min(edges[k + 1], 0.0)
        if hi <= lo:
            continue
        t0, t1 = math.acos(-lo / R), math.acos(-hi / R)       # r = −R cos θ: t0 < t1
        expected[k], _ = integrate.quad(lambda t: 2 * math.pi * R * R * material.monostatic(
            t, projected=True) * math.sin(t), t0, t1, epsrel=1e-12)
    for row in sino.values:
        # first return: the nearest bin is the top at r = −R; nothing beyond the equator's
        # bin (the facets straddling the equator reach slightly past r = 0)
        assert row[0] > 0 and np.all(row[17:] == 0)
        # bins to 3% where the sphere returns more than 5% of the maximum, away from the rim
        # (θ < 75°): there the gray coating's F grows like 1/cos θ and point samples of that
        # integrable singularity converge slowly (documented in meshladar.raytrace)
        core = (expected > 0.05 * expected.max()) & (np.arange(32) < 13)
        np.testing.assert_allclose(row[core], expected[core], rtol=0.03)
        if material.is_lambertian:                  # no rim singularity: the total to 0.5%
            assert row.sum() == pytest.approx(expected.sum(), rel=5e-3)


def test_first_return_range_of_an_offset_sphere():
    c = np.array([0.3, -0.2, 0.1])
    scene = _sphere_scene(lambertian(), 0.25, 4, center=c)
    views = ml.meshes.fibonacci_sphere(5)
    hits = ml.trace(scene, ml.Ladar(None, np.linspace(-2, 2, 401), view_vectors=views),
                    ray_spacing=0.005)
    for i, w in enumerate(views):
        r = hits.range[hits.view == i]
        # the nearest point is r = −c·w − R (to the facet sag R(1 − cos(edge angle)))
        assert r.min() == pytest.approx(-(c @ w) - 0.25, abs=2e-3)


def test_tilted_plate_cos_theta_everywhere():
    beta = math.radians(35.0)
    plate = trimesh.Trimesh(vertices=[[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]],
                            faces=[[0, 1, 2], [0, 2, 3]])
    rot = trimesh.transformations.rotation_matrix(beta, [1, 0, 0])
    scene = ml.Scene.from_mesh(plate, DARK_GRAY, transform=rot)
    assert scene.report["watertight"] == [False]                  # open meshes are allowed
    hits = ml.trace(scene, ml.Ladar(None, np.linspace(-3, 3, 61), view_vectors=[[0, 0, 1]]),
                    ray_spacing=0.05)
    assert hits.size > 100
    np.testing.assert_allclose(hits.cos_theta, math.cos(beta), rtol=1e-12)
    np.testing.assert_allclose(hits.sin_theta, math.sin(beta), rtol=1e-12)
    # seen from behind, a plate is two-sided by default and blocks silently with "ignore"
    behind = ml.Ladar(None, np.linspace(-3, 3, 61), view_vectors=[[0, 0, -1]])
    two = ml.simulate(scene, behind, model="mesh", ray_spacing=0.05)
    with pytest.warns(ml.errors.MeshladarWarning, match=r"all zeros.*back of a face"):
        ign = ml.simulate(scene, behind, model="mesh", ray_spacing=0.05, back_faces="ignore")
    assert two.info["back_face_hits"][0] == hits.size and two.total()[0] > 0
    assert ign.total()[0] == 0.0


@pytest.mark.slow
def test_slice_mode_converges_to_the_analytic_profiles():
    ladar = ml.Ladar.paper(angles_deg=np.arange(0.0, 360.0, 20.0))
    exact = ml.simulate(PAIR, ladar)
    errors = [_rel(ml.simulate(PAIR.tessellate(n), ladar, model="mesh", normals="smooth",
                               rays_per_bin=r).values, exact.values)
              for n, r in ((64, 2), (256, 4), (1024, 8))]
    # measured 0.37, 0.0004, 0.0002: falls with segments and rays
    assert errors[0] > errors[1] >= errors[2] and errors[2] < 2e-3
    # flat facets miss aluminium's e = 0.007 glint until facets are finer than ~e, and
    # the faceting check says so where they are not (256 sides: steps of 0.0245 rad
    # against 2e = 0.014), and only there
    with pytest.warns(LobeSamplingWarning, match=r"^part 'small': with flat normals .*"
                                                 r"step by 0\.0245 rad"):
        coarse = ml.simulate(PAIR.tessellate(256), ladar, model="mesh", normals="flat")
    with warnings.catch_warnings():
        warnings.simplefilter("error", LobeSamplingWarning)
        fine = ml.simulate(PAIR.tessellate(4096), ladar, model="mesh", normals="flat")
    assert _rel(coarse.values, exact.values) > 0.3 and _rel(fine.values, exact.values) < 0.05


def test_exact_and_smooth_normals_beat_flat_for_a_glossy_coating():
    ladar = ml.Ladar.paper(angles_deg=np.arange(0.0, 360.0, 30.0))
    exact = ml.simulate(PAIR, ladar)
    mesh = PAIR.tessellate(512)
    err = {n: _rel(ml.simulate(mesh, ladar, model="mesh", normals=n).values, exact.values)
           for n in ("flat", "smooth", "exact")}
    assert err["smooth"] < 0.1 * err["flat"] and err["exact"] < 0.1 * err["flat"]


@pytest.mark.slow
def test_footprint_beats_point_sampling_at_equal_rays():
    scene = ml.phantoms.scene("disk", lambertian(1.0))
    ladar = ml.Ladar.paper(angles_deg=[0.0, 33.0])
    exact = ml.simulate(scene, ladar)
    mesh = scene.tessellate(4096)
    for rpb in (1, 4):
        point = ml.simulate(mesh, ladar, model="mesh", normals="exact", rays_per_bin=rpb)
        foot = ml.simulate(mesh, ladar, model="mesh", normals="exact", rays_per_bin=rpb,
                           footprint=True)
        assert _rel(foot.values, exact.values) < 0.9 * _rel(point.values, exact.values)
        np.testing.assert_allclose(foot.total(), point.total(), rtol=1e-9)   # weights kept


def test_shadow_gap_of_the_multi_material_pair():
    # footprints cover the near-silhouette bins, which point samples skip (dr/ds → ∞ there)
    sino = ml.simulate(PAIR.tessellate(1024), ml.Ladar.paper(angles_deg=[0.0]), model="mesh",
                       normals="exact", footprint=True)
    edges = sino.bin_edges
    margin = 2 * 0.003125
    gap = (edges[:-1] >= -0.4 + margin) & (edges[1:] <= 0.3 - math.sqrt(0.07) - margin)
    assert gap.sum() > 100 and np.all(sino.values[0][gap] == 0.0)
    lit = (edges[1:] <= -0.45) & (edges[:-1] >= -0.7 + margin)
    assert np.all(sino.values[0][lit] > 0)


#: Re-weighing cached hits (numpy's SR model, norms by hypot) against the compiled loop
#: (its SR kernel's norms are square roots of sums of squares): the same hits, weights
#: equal to ~1e-15 relative, asserted to this.
REWEIGH_RTOL = 1e-12


def test_reweighing_cached_hits_equals_a_fresh_simulate():
    ladar = ml.Ladar.paper(angles_deg=np.arange(0.0, 360.0, 45.0))
    mesh = PAIR.tessellate(256)
    hits = ml.trace(mesh, ladar, normals="smooth")
    fresh = ml.simulate(mesh, ladar, model="mesh", normals="smooth").values
    np.testing.assert_allclose(ml.weigh(hits).values, fresh, rtol=REWEIGH_RTOL,
                               atol=REWEIGH_RTOL * np.abs(fresh).max())
    assert np.abs(fresh).max() > 0
    swapped = ml.phantoms.scene("disk_pair", large=ALUMINUM, small=DARK_GRAY).tessellate(256)
    np.testing.assert_allclose(ml.weigh(hits, [ALUMINUM, DARK_GRAY]).values,
                               ml.simulate(swapped, ladar, model="mesh",
                                           normals="smooth").values, rtol=1e-12, atol=0)
    with pytest.raises(ParameterError, match=r"materials must give 2 coatings"):
        ml.weigh(hits, [ALUMINUM])


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # faceted on purpose
def test_glb_with_two_parts_and_two_materials(tmp_path):
    sc = trimesh.Scene()
    sc.add_geometry(trimesh.creation.box(extents=(0.4, 0.4, 0.4)), node_name="box",
                    transform=trimesh.transformations.translation_matrix([-0.5, 0, 0]))
    sc.add_geometry(trimesh.creation.icosphere(subdivisions=3, radius=0.2), node_name="ball",
                    transform=trimesh.transformations.translation_matrix([0.5, 0, 0]))
    path = tmp_path / "parts.glb"
    sc.export(path)
    scene = ml.Scene.from_mesh(path, materials={"box": DARK_GRAY, "ball": ALUMINUM})
    assert len(scene.parts) == 2 and set(scene.materials) == {DARK_GRAY, ALUMINUM}
    assert all(scene.report["watertight"]) and scene.report["degenerate_faces"] == 0
    # seen from +y both parts are fully lit and apart: each returns its own coating's power
    ladar = ml.Ladar([90.0], np.linspace(-0.6, 0.6, 121))
    both = ml.simulate(scene, ladar, model="mesh", mode="3d", rays_per_bin=4)
    alone = [ml.simulate(ml.Scene.from_mesh(path, materials={"box": DARK_GRAY,
                                                             "ball": ALUMINUM})
                         if False else scene, ladar, model="mesh", mode="3d",
                         rays_per_bin=4)]
    np.testing.assert_allclose(both.values, alone[0].values)
    box_top = both.values[0][(both.bin_centers > -0.21) & (both.bin_centers < -0.19)].sum()
    # the box's top face (0.4 × 0.4 at normal incidence, r = −0.2): F(0)·area
    assert box_top == pytest.approx(DARK_GRAY.monostatic(0.0) * 0.16, rel=0.02)
    with pytest.raises(ParameterError, match=r"no part named 'cube'"):
        ml.Scene.from_mesh(path, materials={"cube": DARK_GRAY})
    with pytest.raises(ParameterError, match=r"part 'ball' has no material"):
        ml.Scene.from_mesh(path, materials={"box": DARK_GRAY})


def test_far_from_origin_and_tiny_scenes_keep_their_accuracy():
    ladar = ml.Ladar.paper(angles_deg=[0.0, 70.0, 200.0])
    base_mesh = PAIR.tessellate(512)
    base = ml.simulate(base_mesh, ladar, model="mesh", normals="smooth")
    part_v = [p.vertices for p in base_mesh.parts]
    w = ladar.view_vectors
    # translated by 1e4 × the scene's size: same profile on shifted bin edges
    d = np.array([1.4e4, -0.9e4, 0.3e4])
    far = ml.Scene._from_parts([mlmesh.MeshPart(v + d, p.faces, p.material, p.name)
                                for v, p in zip(part_v, base_mesh.parts)], base_mesh.materials)
    for i in range(3):
        lad = ml.Ladar([ladar.angles_deg[i]], ladar.bin_edges - d @ w[i])
        got = ml.simulate(far, lad, model="mesh", normals="smooth", mode="slice", z0=d[2])
        # float32 relative to the scene's own size: the same rays up to last-bit rounding of
        # the shifted vertices (measured ≤ 2e-11 absolute). Naive float32 coordinates at
        # 1.4e4 would misplace every hit by ~1e-3, a third of a bin.
        np.testing.assert_allclose(got.values[0], base.values[i], rtol=1e-5,
                                   atol=1e-6 * base.values.max())
        assert got.total()[0] == pytest.approx(base.total()[i], rel=1e-6)
    # scaled by 1e-3: lengths (and per-unit-height values) scale by 1e-3
    s = 1e-3
    tiny = ml.Scene._from_parts([mlmesh.MeshPart(v * s, p.faces, p.material, p.name)
                                 for v, p in zip(part_v, base_mesh.parts)], base_mesh.materials)
    got = ml.simulate(tiny, ml.Ladar(ladar.angles_deg, ladar.bin_edges * s), model="mesh",
                      normals="smooth", mode="slice", ray_spacing=s * 0.003125 / 8)
    # (float32 rounds the scaled coordinates differently: a ray sitting on a bin edge may
    # change sides, moving ~1e-5 of a bin; measured 1.4e-5)
    np.testing.assert_allclose(got.values, base.values * s, rtol=1e-4,
                               atol=1e-6 * s * base.values.max())


def test_first_hits_ranges_are_float64_accurate():
    """A tilted plate's top face at z = h, 30 units off the origin (size 2), seen
    obliquely: every first hit lies on the plane and its range is the closed form
    r = (a_z − h)/w_z from the hit ray's transverse position a = p − (p·w)w (exact: the
    float32 origin as cast), to 1e-12 of the scene's size; Embree's float32 distances
    alone are off by ~1e-7 (measured 1.4e-7)."""
    h, d = 0.1, np.array([30.0, -20.0, 10.0])
    plate = trimesh.creation.box(extents=(2.0, 1.5, 0.2))
    plate.apply_translation(d)
    scene = ml.Scene.from_mesh(plate, material=lambertian(0.5))
    w = np.array([0.3, -0.2, 0.9])
    w /= np.linalg.norm(w)
    p, face, r = first_hits(scene, w, ray_spacing=0.01)
    top = np.abs(plate.face_normals[face] @ [0.0, 0.0, 1.0]) > 0.99
    assert top.sum() > 10_000 and p.dtype == r.dtype == np.float64
    p, r = p[top], r[top]
    size = 2.0
    z_top = d[2] + h
    assert np.max(np.abs(p[:, 2] - z_top)) < 1e-12 * size
    a = p - (p @ w)[:, None] * w
    np.testing.assert_allclose(r, (a[:, 2] - z_top) / w[2], rtol=0, atol=1e-12 * size)
    np.testing.assert_allclose(r, -(p @ w), rtol=0, atol=1e-12 * size)


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # faceted on purpose
def test_jobs_and_jitter_are_reproducible():
    ladar = ml.Ladar.paper(angles_deg=np.arange(0.0, 360.0, 30.0))
    mesh = PAIR.tessellate(256)
    one = ml.simulate(mesh, ladar, model="mesh", jobs=1)
    two = ml.simulate(mesh, ladar, model="mesh", jobs=2)
    np.testing.assert_array_equal(one.values, two.values)
    a = ml.simulate(mesh, ladar, model="mesh", seed=5)
    b = ml.simulate(mesh, ladar, model="mesh", seed=5)
    c = ml.simulate(mesh, ladar, model="mesh", seed=6)
    np.testing.assert_array_equal(a.values, b.values)
    assert not np.array_equal(a.values, c.values)
    # jittered and regular grids estimate the same totals; with a Lambertian coating every
    # ray carries ρd/π·δs, so the totals differ by at most the rays at the two silhouettes
    lamb = ml.phantoms.scene("disk_pair", lambertian(0.5)).tessellate(256)
    jit = ml.simulate(lamb, ladar, model="mesh", seed=5)
    reg = ml.simulate(lamb, ladar, model="mesh")
    spacing = reg.info["ray_spacing"]
    np.testing.assert_allclose(jit.total(), reg.total(), atol=4 * spacing * 0.5 / math.pi)


def test_mesh_checks_and_bad_input(tmp_path):
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3], [1, 1, 2]])   # last: degenerate
    scene = ml.Scene._from_parts([mlmesh.MeshPart(v, f, 0)], [DARK_GRAY])
    assert scene.report["degenerate_faces"] == 1 and scene.report["faces"] == 4
    assert scene.report["watertight"] == [True] and scene.report["inverted"] == [False]
    with pytest.warns(ml.errors.MeshladarWarning, match=r"1 closed body with inverted"):
        inverted = ml.Scene._from_parts([mlmesh.MeshPart(v, f[:4, ::-1], 0)], [DARK_GRAY])
    assert inverted.report["inverted"] == [True]
    # back_faces="ignore" then blanks the part: an all-zero sinogram says why
    lad = ml.Ladar(None, np.linspace(-2, 2, 41), view_vectors=[[1.0, 1.0, 1.0]])
    with pytest.warns(ml.errors.MeshladarWarning, match=r"all zeros.*inverted"):
        blank = ml.simulate(inverted, lad, model="mesh", back_faces="ignore", ray_spacing=0.02)
    assert blank.total()[0] == 0.0
    assert ml.simulate(inverted, lad, model="mesh", ray_spacing=0.02).total()[0] > 0
    bad = v.copy()
    bad[2, 1] = np.nan
    with pytest.raises(GeometryError, match=r"vertices must be finite; got \[0.0, nan, 0.0\] "
                                            r"at vertex 2"):
        mlmesh.MeshPart(bad, f, 0)
    with pytest.raises(GeometryError, match=r"faces index vertices 0..3; got 0..7"):
        mlmesh.MeshPart(v, [[0, 1, 7]], 0)
    with pytest.raises(GeometryError, match=r"nope.stl: no such mesh file"):
        ml.Scene.from_mesh(tmp_path / "nope.stl", DARK_GRAY)
    junk = tmp_path / "junk.stl"
    junk.write_bytes(b"\x00" * 10)
    with pytest.raises(GeometryError, match=r"junk.stl"):
        ml.Scene.from_mesh(junk, DARK_GRAY)
    lad = ml.Ladar.paper(angles_deg=[0.0])
    with pytest.raises(ParameterError, match=r"normals='exact' needs parts tessellated"):
        ml.simulate(scene, lad, model="mesh", normals="exact")
    with pytest.raises(ParameterError, match=r"mode='slice' needs views about the z axis"):
        ml.simulate(scene, ml.Ladar(None, [0, 1], view_vectors=[[0, 0, 1]]), model="mesh",
                    mode="slice")
    with pytest.raises(ParameterError, match=r"normals must be one of \('flat', 'smooth', "
                                             r"'exact'\); got 'phong'"):
        ml.simulate(scene, lad, model="mesh", normals="phong")
    with pytest.raises(ParameterError, match=r"give ray_spacing or rays_per_bin, not both"):
        ml.simulate(scene, lad, model="mesh", ray_spacing=0.1, rays_per_bin=2)
    with pytest.raises(ParameterError, match=r"jobs must be an integer >= 1; got 0"):
        ml.simulate(scene, lad, model="mesh", jobs=0)
    with pytest.raises(ParameterError, match=r"needs analytic shapes"):
        ml.simulate(scene, lad)


def test_analytic_scene_is_tessellated_for_the_mesh_model():
    lad = ml.Ladar.paper(angles_deg=[10.0, 100.0])
    auto = ml.simulate(PAIR, lad, model="mesh", normals="exact")
    manual = ml.simulate(PAIR.tessellate(1024), lad, model="mesh", normals="exact")
    np.testing.assert_array_equal(auto.values, manual.values)


def test_fibonacci_sphere():
    v = ml.meshes.fibonacci_sphere(500)
    np.testing.assert_allclose(np.linalg.norm(v, axis=1), 1.0, rtol=1e-12)
    assert np.all(np.abs(v.mean(axis=0)) < 0.01)
    assert np.all(ml.meshes.fibonacci_sphere(50, hemisphere=True)[:, 2] >= 0)


@pytest.mark.slow
def test_bistatic_receiver():
    mesh = PAIR.tessellate(512)
    ladar = ml.Ladar.paper(angles_deg=[20.0, 140.0])
    mono = ml.simulate(mesh, ladar, model="mesh", normals="smooth")
    # a receiver collocated with the ladar is the monostatic case (its occlusion rays leave
    # from first hits, which see the ladar by construction)
    same = ml.simulate(mesh, ladar, model="mesh", normals="smooth",
                       receiver=ladar.view_vectors)
    np.testing.assert_allclose(same.values, mono.values, rtol=1e-9, atol=1e-15)
    # a plate at normal incidence, receiver 30° off in x-z: every ray weighs the bistatic
    # F(w, w_r) · δA⊥, and range is half the two-way path, −p·(w + w_r)/2
    plate = trimesh.Trimesh(vertices=[[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]],
                            faces=[[0, 1, 2], [0, 2, 3]])
    scene = ml.Scene.from_mesh(plate, ALUMINUM)
    b = math.radians(30.0)
    w_r = np.array([math.sin(b), 0.0, math.cos(b)])
    lad = ml.Ladar(None, np.linspace(-1.5, 1.5, 301), view_vectors=[[0, 0, 1]])
    sino = ml.simulate(scene, lad, model="mesh", ray_spacing=0.02, receiver=w_r)
    f = ALUMINUM.evaluate([0, 0, 1], w_r)
    assert sino.total()[0] == pytest.approx(f * 4.0, rel=1e-9)
    centers = sino.bin_centers[sino.values[0] > 0]
    half = math.sin(b) / 2                       # −x·sin(30°)/2 for x ∈ [−1, 1]
    assert centers.min() == pytest.approx(-half, abs=0.02) and centers.max() == \
        pytest.approx(half, abs=0.02)
    # a blocker between the plate and the receiver shadows part of the return
    wall = trimesh.creation.box(extents=(0.2, 2.4, 0.2))
    wall.apply_translation([0.8, 0.0, 1.0])      # over x ∈ [0.7, 0.9], toward +x+z
    both = ml.Scene.from_meshes([(plate, ALUMINUM), (wall, DARK_GRAY)])
    shadowed = ml.trace(both, lad, ray_spacing=0.02, receiver=w_r)
    on_plate = np.abs(shadowed.range + 0.0) < 1.0          # plate hits vs the wall's tops
    blocked = shadowed.bistatic[:, 0] < 0
    assert blocked.sum() > 0 and (blocked & on_plate).sum() == blocked.sum()
    with pytest.raises(ParameterError, match="footprint binning is monostatic only"):
        ml.simulate(scene, lad, model="mesh", receiver=w_r, footprint=True)
    with pytest.raises(ParameterError, match=r"receiver must be a direction"):
        ml.simulate(scene, lad, model="mesh", receiver=[1.0, 0.0])


def test_several_meshes_with_transforms():
    ball = trimesh.creation.icosphere(subdivisions=3, radius=0.2)
    shift = trimesh.transformations.translation_matrix
    scene = ml.Scene.from_meshes([(ball, DARK_GRAY, shift([-0.5, 0, 0])),
                                  (ball, ALUMINUM, shift([0.5, 0, 0]))])
    assert len(scene.parts) == 2 and len(scene.materials) == 2
    b = scene.bounds()
    np.testing.assert_allclose(b[:, 0], [-0.7, 0.7], atol=1e-12)
    # from +y both balls are lit and apart: the returns split by x at their own ranges
    hits = ml.trace(scene, ml.Ladar([90.0], np.linspace(-0.5, 0.5, 101)), mode="3d",
                    ray_spacing=0.01)
    assert set(np.unique(hits.material)) == {0, 1}


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # faceted on purpose
@pytest.mark.parametrize("back_faces", ["two-sided", "ignore"])
def test_fused_flat_path_equals_trace_and_weigh(back_faces):
    # simulate's compiled monostatic flat-normal loop against the numpy path of weigh()
    mats = [DARK_GRAY, ALUMINUM, ml.SandfordRobertson(0.02, 0.3, 1 - 1e-12, 1e-4),
            ml.materials.glint(0.05), lambertian(0.3)]
    for m in mats:
        scene = ml.phantoms.scene("disk_pair", large=m, small=ALUMINUM)
        mesh = scene.tessellate(300)
        ladar = ml.Ladar.paper(angles_deg=[0.0, 77.0, 201.0])
        fast = ml.simulate(mesh, ladar, model="mesh", back_faces=back_faces)
        slow = ml.weigh(ml.trace(mesh, ladar, back_faces=back_faces))
        np.testing.assert_allclose(fast.values, slow.values, rtol=1e-12, atol=1e-300)
        assert fast.info["back_face_hits"] == slow.info["back_face_hits"]


def test_file_formats_and_per_face_materials(tmp_path):
    box = trimesh.creation.box(extents=(0.5, 0.5, 0.5))
    ladar = ml.Ladar([90.0], np.linspace(-0.5, 0.5, 101))
    ref = ml.simulate(ml.Scene.from_mesh(box, DARK_GRAY), ladar, model="mesh", mode="3d",
                      rays_per_bin=2)
    for ext in ("stl", "obj", "ply", "off"):
        path = tmp_path / f"box.{ext}"
        box.export(path)
        got = ml.simulate(ml.Scene.from_mesh(path, DARK_GRAY), ladar, model="mesh", mode="3d",
                          rays_per_bin=2)
        np.testing.assert_allclose(got.values, ref.values, rtol=1e-6, atol=1e-12)
    # per-face materials: the +y face (seen from φ = 90°) aluminium, the rest gray
    ids = (box.face_normals[:, 1] > 0.5).astype(int)
    scene = ml.Scene.from_mesh(box, materials=[DARK_GRAY, ALUMINUM], face_materials=ids)
    hits = ml.trace(scene, ladar, mode="3d", rays_per_bin=2)
    assert np.all(hits.material == 1)                    # only the +y face is seen
    sino = ml.weigh(hits)
    assert sino.total()[0] == pytest.approx(ALUMINUM.monostatic(0.0) * 0.25, rel=0.02)
    with pytest.raises(ParameterError, match=r"face_materials must be \(12,\) integers"):
        ml.Scene.from_mesh(box, materials=[DARK_GRAY], face_materials=[0, 1])


def test_sphere_part_via_public_api_and_progress_is_quiet_off_a_terminal(capsys):
    scene = ml.Scene.from_parts([ml.meshes.sphere((0, 0, 0), 0.5, 0, subdivisions=3)],
                                [lambertian(1.0)])
    sino = ml.simulate(scene, ml.Ladar.paper(angles_deg=[0.0, 90.0]), model="mesh",
                       progress=True)
    assert capsys.readouterr().err == ""                 # not a TTY: no bar
    # a mesh is a 3-D target by default: the whole sphere's return, ρd/π × its projected
    # area πR² (the 1280-face icosphere's silhouette is 0.5% inside the sphere's)
    assert sino.info["mode"] == "3d"
    np.testing.assert_allclose(sino.total(), 0.5**2, rtol=0.01)


def test_alternating_meshes_reuse_their_embree_scenes():
    from meshladar.raytrace.embree import _EMBREE_CACHE_SIZE, embree_scene, Geometry

    scenes = [ml.Scene.from_parts([ml.meshes.sphere((0, 0, 0), 0.5 + 0.1 * k, 0, subdivisions=1)],
                                  [DARK_GRAY]) for k in range(_EMBREE_CACHE_SIZE + 1)]
    geos = [Geometry(s, "flat") for s in scenes]
    first = [embree_scene(g) for g in geos[:2]]
    assert [embree_scene(g) for g in geos[:2] * 2] == first * 2     # built once each
    for g in geos[2:]:                                # past the bound: the oldest goes
        embree_scene(g)
    assert embree_scene(geos[1]) is first[1] and embree_scene(geos[0]) is not first[0]


def test_hits_are_a_frozen_record_of_named_arrays():
    sphere = ml.Scene.from_parts([ml.meshes.sphere((0, 0, 0), 0.5, 0, subdivisions=2)],
                                 [DARK_GRAY])
    lad = ml.Ladar(np.array([0.0, 90.0]), np.linspace(-0.6, 0.6, 9))
    hits = ml.trace(sphere, lad)
    k = hits.size
    assert k > 0 and hits.spread.shape == (k, 4) and hits.rays.shape == (2,)
    for name in ("view", "range", "cos_theta", "sin_theta", "material", "spread", "rays"):
        with pytest.raises(ValueError, match="read-only"):
            getattr(hits, name)[0] = 0
    import dataclasses

    with pytest.raises(ParameterError, match=r"Hits.spread must have shape \(\d+, 4\); got"):
        dataclasses.replace(hits, spread=np.zeros((k, 2)))


def test_a_views_hits_are_a_frozen_record_too():
    # the record a worker returns for one view: named fields, shapes checked, read-only
    from meshladar.hits import ViewHits

    k = 5
    h = ViewHits(np.zeros(k), np.ones(k), np.zeros(k), np.zeros(k, np.int32), np.zeros((k, 4)),
                 rays=10, back_face_hits=0)
    assert h.bistatic is None and h.rays == 10
    with pytest.raises(ValueError, match="read-only"):
        h.range[0] = 1.0
    with pytest.raises(ParameterError, match=r"ViewHits.curve must have shape \(5, 4\); "
                                             r"got \(5, 3\)"):
        ViewHits(np.zeros(k), np.ones(k), np.zeros(k), np.zeros(k, np.int32),
                 np.zeros((k, 4)), 10, 0, curve=np.zeros((k, 3)))


@pytest.mark.parametrize("backend", ["packets", "embreex"])
def test_a_receiver_edge_on_to_a_lit_face_is_said_under_eq8(backend):
    """A cube seen along x with the receiver along y: its +x face is lit and exactly edge-on
    to the receiver. Under Eq. 8 (radiometry='paper') the bistatic weight is F, whose
    specular term grows as 1/cos θr: that face outweighs everything by ~1e16, which is
    said; received power (F·cos θr) is finite and silent."""
    cube = trimesh.creation.box(extents=(0.5, 0.5, 0.5))
    scene = ml.Scene.from_mesh(cube, ALUMINUM)
    lad = ml.Ladar(None, np.linspace(-0.6, 0.6, 65), view_vectors=[[1.0, 0.0, 0.0]])
    with pytest.warns(MeshladarWarning, match="edge-on to the receiver"):
        paper = ml.simulate(scene, lad, model="mesh", receiver=(0.0, 1.0, 0.0),
                            backend=backend)
    power = ml.simulate(scene, lad, model="mesh", receiver=(0.0, 1.0, 0.0),
                        radiometry="power", backend=backend)
    assert paper.values.max() > 1e12 * power.values.max() > 0


@pytest.mark.parametrize("normal, ignore_back, warns", [
    ((1.0, 0.0, 0.0), False, True),          # a lit face exactly edge-on to the receiver
    ((1.0, 0.0, 0.0), True, True),
    ((-1.0, 0.0, 0.0), False, True),         # a back face, two-sided: turned, edge-on
    ((-1.0, 0.0, 0.0), True, False),         # an ignored back face is never weighed
    ((0.0, 1.0, 0.0), False, False),         # edge-on to the ladar: not lit
    ((1.0, -1e-7, 0.0), False, False),       # the receiver below the face's horizon
    ((1.0, 5e-7, 0.0), False, True),         # cos θr = 5e-7 < 1e-6
    ((1.0, 2e-6, 0.0), False, False),        # cos θr = 2e-6: not edge-on
])
def test_the_fused_loops_edge_on_check_finds_the_faces_the_per_hit_path_would(
        normal, ignore_back, warns):
    """The compiled pass over the faces (built-in coatings weighed at their first hit)
    warns for exactly the faces toward the ladar (w = x) with 0 ≤ cos θr < 1e-6 for the
    receiver along y: closed-form cosines of single unit normals."""
    n = np.array([normal], dtype=np.float64)
    geo = SimpleNamespace(face_normals=n / np.linalg.norm(n))
    w, w_r = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        check_edge_on_receiver(geo, w, w_r, ignore_back)
    assert any("edge-on to the receiver" in str(x.message) for x in seen) == warns
