"""The "raster" backend: a dense orthographic view's first hits drawn into a depth buffer
over its ray grid (meshladar.weighing._raster_kernels) instead of traced, checked against
Embree's traced hits on the same float32 rays (closed, open, concave and intersecting
bodies), against the packet backend's sinograms, and against a closed form."""

from __future__ import annotations

import numpy as np
import pytest

import meshladar as ml
from meshladar.materials import ALUMINUM
from meshladar.raytrace import embree4
from meshladar.raytrace.embree import embree_scene, geometry
from meshladar.raytrace.grid import grid_plan, ray_grid
from meshladar.sensor import Sensor
from meshladar.weighing._raster_kernels import zbuffer

pytestmark = pytest.mark.skipif(not embree4.available(),
                                reason="the packet backend does not load here")
trimesh = pytest.importorskip("trimesh")

#: Rays whose drawn face is not Embree's: only those within float32 round-off of an edge
#: (a silhouette's, or one shared by two faces), at most this fraction of a view's hits
#: (measured: 10 in 785,000 on a stratified 82k sphere).
EDGE_RAYS = 1e-4
#: Where both find a face turned at least 0.05 toward the view (|n·w|), the drawn distance
#: L − height against Embree's float32 one, as a fraction of the scene's radius (a float32
#: origin's round-off along a face seen nearly edge-on moves the hit along the ray by
#: that round-off / |n·w|; the bins recompute distances in float64 from the face's plane).
DISTANCE_TOL = 1e-5
#: A sinogram's bins against the packet backend's: the few edge rays move one ray's
#: weight each (sum over the bins, as a fraction of the total).
BINS_TOL = 1e-3


def _scenes():
    box = trimesh.creation.box((1.0, 0.8, 0.6))
    box.update_faces(np.abs(box.face_normals[:, 2] - 1.0) > 1e-9)     # no lid: open
    box.remove_unreferenced_vertices()
    a = trimesh.creation.icosphere(subdivisions=4, radius=0.5)
    b = trimesh.creation.icosphere(subdivisions=4, radius=0.4)
    b.apply_translation((0.45, 0.1, -0.05))                           # the two intersect
    ring = trimesh.creation.annulus(0.3, 0.6, 0.25)                    # concave, closed
    ring.apply_translation((2.0, 1.0, 0.5))
    flipped = trimesh.creation.icosphere(subdivisions=3, radius=0.3)
    flipped.invert()                                                   # inward normals
    flipped.apply_translation((-1.0, 0.5, 0.0))
    return {"open box": [box], "intersecting spheres": [a, b],
            "ring and open box": [ring, box], "inverted sphere": [flipped]}


@pytest.fixture
def drawn_views(monkeypatch):
    """How many views (or bands of a view's rows) the raster drew in the test."""
    from meshladar.weighing import fused
    count = [0]
    draw = fused.draw_bin_grid

    def counting(*args, **kwargs):
        count[0] += 1
        return draw(*args, **kwargs)

    monkeypatch.setattr(fused, "draw_bin_grid", counting)
    return count


def _scene(meshes):
    parts = [ml.meshes.MeshPart(m.vertices, m.faces, np.zeros(len(m.faces), np.int64), f"p{i}")
             for i, m in enumerate(meshes)]
    return ml.Scene.from_parts(parts, [ALUMINUM])


@pytest.mark.filterwarnings("ignore::meshladar.errors.MeshladarWarning")   # inverted
@pytest.mark.parametrize("name", list(_scenes()))
def test_drawn_first_hits_are_embrees_but_within_round_off_of_an_edge(name):
    scene = _scene(_scenes()[name])
    geo = geometry(scene, "flat")
    emb = embree_scene(geo, "packets")
    f32 = np.float32
    for k, w in enumerate(ml.meshes.fibonacci_sphere(5)):
        sp = geo.radius / 300
        plan = grid_plan(geo, w, "3d", sp, 0.0, np.random.default_rng(k))
        rays = ray_grid(geo, w, "3d", sp, 0.0, np.random.default_rng(k))
        got = emb.run(rays.origins, (-w)[None, :], columns=rays.columns)
        u32, v32 = plan.u.astype(f32), plan.v.astype(f32)
        proj = geo.shifted @ np.array([u32, v32, w], np.float64).T
        prim = np.empty(len(rays.origins), np.int32)
        height = np.empty(len(rays.origins))
        zbuffer(np.ascontiguousarray(proj), geo.faces32, geo.face_normals @ w, geo.closed,
                plan.s.astype(f32), plan.t.astype(f32), plan.offsets, f32(sp), prim, height)
        traced = np.asarray(got["primID"])
        hits = int((traced >= 0).sum())
        assert hits > 10_000
        assert (prim != traced).sum() <= EDGE_RAYS * hits + 2, (name, k)
        both = (prim == traced) & (prim >= 0)
        both[both] = np.abs(geo.face_normals[prim[both]] @ w) >= 0.05
        drawn = plan.L - height[both]
        np.testing.assert_allclose(drawn, np.asarray(got["tfar"])[both], rtol=0,
                                   atol=DISTANCE_TOL * geo.radius)


VARIANTS = {
    "stratified": {},
    "regular": {"sampling": "regular", "seed": None},
    "footprint": {"footprint": True},
    "power, back faces ignored": {"radiometry": "power", "back_faces": "ignore"},
    "one view on two threads": {"jobs": 2},
    "smooth normals": {"normals": "smooth"},
    "smooth normals, footprint": {"normals": "smooth", "footprint": True},
}


@pytest.mark.filterwarnings("ignore::meshladar.errors.MeshladarWarning")   # inverted
@pytest.mark.parametrize("variant", list(VARIANTS))
def test_drawn_sinograms_are_the_packet_backends_but_at_edge_rays(variant, drawn_views):
    scene = _scene(_scenes()["ring and open box"] + _scenes()["intersecting spheres"])
    options = dict(mode="3d", rays_per_bin=6, seed=3) | VARIANTS[variant]
    views = 1 if variant.startswith("one view") else 6
    ladar = ml.Ladar(None, np.linspace(-3, 3, 121),
                     view_vectors=ml.meshes.fibonacci_sphere(views) if views > 1 else
                     [[0.3, 0.4, np.sqrt(0.75)]])
    packets = ml.simulate(scene, ladar, model="mesh", backend="packets", **options)
    drawn = ml.simulate(scene, ladar, model="mesh", backend="raster", **options)
    assert drawn.info["backend"] == "raster" and drawn.info["rays"] == packets.info["rays"]
    assert drawn_views[0] >= views
    assert drawn.info["rays"] > 50_000 * views
    a, b = packets.values, drawn.values
    assert np.abs(a - b).sum() <= BINS_TOL * np.abs(a).sum(), np.abs(a - b).sum() / a.sum()
    assert drawn.info["back_face_hits"] == packets.info["back_face_hits"] or \
        abs(np.sum(drawn.info["back_face_hits"]) - np.sum(packets.info["back_face_hits"])) \
        <= EDGE_RAYS * drawn.info["rays"]


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")   # facets
@pytest.mark.parametrize("options", [{"receiver": [0.6, 0.0, 0.8], "radiometry": "power"},
                                     {"sensor": Sensor(standoff=40.0), "radiometry": "power"},
                                     {"mode": "slice"}],
                         ids=["bistatic", "sensor", "slice"])
def test_views_the_raster_does_not_draw_are_cast_as_the_packet_backend_casts_them(
        options, drawn_views):
    scene = _scene(_scenes()["intersecting spheres"])
    ladar = ml.Ladar(angles_deg=[0.0, 70.0], bin_edges=np.linspace(-1, 1, 41))
    kw = dict(mode="3d", rays_per_bin=8) | options
    packets = ml.simulate(scene, ladar, model="mesh", backend="packets", **kw)
    drawn = ml.simulate(scene, ladar, model="mesh", backend="raster", **kw)
    np.testing.assert_array_equal(drawn.values, packets.values)
    assert drawn_views[0] == 0


#: A Lambertian icosphere of 82k flat faces against the smooth sphere's closed form:
#: faceting and sampling (measured 9.3e-4 of the largest bin, drawn or traced alike).
SPHERE_TOL = 3e-3


def test_a_drawn_lambertian_sphere_is_the_textbook_profile(drawn_views):
    """The cap at depth r below the top of a Lambertian sphere of radius R holds, in
    received power, 2 (ρ/π) π R² ∫ cos²a sin a da: a bin (2/3) ρ R² [c³] with
    c = 1 − r/R; under the paper's radiometry ρ R² [c²] (one factor of cos fewer)."""
    R, rho = 1.0, 1.0
    scene = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=6, radius=R),
                               material=ml.brdf.Lambertian(rho))
    ladar = ml.Ladar(angles_deg=[0.0, 40.0], bin_edges=np.linspace(-R, 0.0, 21))
    c = -ladar.bin_edges / R
    for radiometry, n in (("power", 3), ("paper", 2)):
        sino = ml.simulate(scene, ladar, model="mesh", radiometry=radiometry,
                           rays_per_bin=40, backend="raster")
        exact = 2 * rho / n * R * R * (c[:-1] ** n - c[1:] ** n)
        assert np.abs(sino.values - exact).max() < SPHERE_TOL * exact.max(), radiometry
    assert drawn_views[0] == 4


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")   # facets
def test_a_view_bigger_than_one_buffer_is_drawn_in_blocks_of_rows_with_the_same_bins(
        monkeypatch):
    """DRAWN_RAYS bounds a view's depth buffer: a view drawn in blocks of a few rows each
    (its rows binned in the same order) gives the one-buffer bins exactly."""
    from meshladar.weighing import fused
    scene = _scene(_scenes()["ring and open box"])
    ladar = ml.Ladar(angles_deg=[10.0, 100.0], bin_edges=np.linspace(-3, 3, 61))
    kw = dict(model="mesh", mode="3d", ray_spacing=0.006, backend="raster")
    whole = ml.simulate(scene, ladar, **kw)
    monkeypatch.setattr(fused, "DRAWN_RAYS", 5_000)
    blocks = ml.simulate(scene, ladar, **kw)
    assert whole.info["rays"] > 20 * 5_000
    np.testing.assert_array_equal(blocks.values, whole.values)


def test_grids_sparser_than_their_faces_are_cast_not_drawn(drawn_views):
    """A view of fewer than DRAWN_RAYS_PER_FACE rays on the face a ray hits is cast (its
    faces would cost more to draw than its rays to cast): the packet backend's numbers
    exactly."""
    scene = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=5, radius=1.0),
                               material=ml.brdf.Lambertian(0.5))
    ladar = ml.Ladar(angles_deg=[0.0, 50.0], bin_edges=np.linspace(-1, 1, 11))
    kw = dict(model="mesh", mode="3d", ray_spacing=0.05)
    drawn = ml.simulate(scene, ladar, backend="raster", **kw)
    assert drawn.info["rays"] < 2 * 20 * 4 ** 5
    np.testing.assert_array_equal(drawn.values,
                                  ml.simulate(scene, ladar, backend="packets", **kw).values)
    assert drawn_views[0] == 0


def test_a_sheet_of_two_faces_back_to_back_shows_the_face_turned_toward_the_view(
        drawn_views):
    """A plate modelled twice, once each way round (a 'double-sided' sheet), with back
    faces ignored: every drawn ray takes the face turned toward the ladar, so the sheet
    returns what the plate alone returns, seen from either side (Embree takes either of
    two coincident faces)."""
    quad = np.array([[0, 1, 2], [0, 2, 3]])
    v = np.array([[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]])
    lam = ml.brdf.Lambertian(0.5)
    sheet = ml.Scene.from_parts([ml.meshes.MeshPart(v, np.vstack([quad, quad[:, ::-1]]),
                                                    np.zeros(4, np.int64), "sheet")], [lam])
    for up in (1.0, -1.0):
        plate = ml.Scene.from_parts([ml.meshes.MeshPart(
            v, quad if up > 0 else quad[:, ::-1], np.zeros(2, np.int64), "plate")], [lam])
        ladar = ml.Ladar(None, np.linspace(-2, 2, 21),
                         view_vectors=[[0.3, 0.2, up * 0.9], [-0.5, 0.1, up * 0.8]])
        kw = dict(model="mesh", mode="3d", ray_spacing=0.004, back_faces="ignore")
        drawn = ml.simulate(sheet, ladar, backend="raster", **kw)
        alone = ml.simulate(plate, ladar, backend="packets", **kw)
        assert alone.total().min() > 0
        np.testing.assert_allclose(drawn.values, alone.values, rtol=1e-12, atol=1e-15)
    assert drawn_views[0] == 4


def _rod(length, segment=0.00413, half_width=0.002):
    """A closed square rod along x, its rings ``segment`` apart: faces of a few cells each,
    far from the origin at its ends (the float32 coordinates coarse against a cell)."""
    n = int(round(length / segment))
    xs = -length / 2 + np.arange(n + 1) * segment
    ring = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * half_width
    v = np.array([[x, y, z] for x in xs for y, z in ring])
    f = []
    for k in range(n):
        a, b = 4 * k, 4 * (k + 1)
        for j in range(4):
            f += [[a + j, a + (j + 1) % 4, b + (j + 1) % 4], [a + j, b + (j + 1) % 4, b + j]]
    e = 4 * n
    f += [[0, 2, 1], [0, 3, 2], [e, e + 1, e + 2], [e, e + 2, e + 3]]
    mesh = trimesh.Trimesh(v, np.array(f), process=False)
    if mesh.volume < 0:
        mesh.invert()
    return mesh


@pytest.mark.parametrize("length, spacing", [(20.0, 5e-4), (200.0, 1e-3)])
def test_no_ray_inside_a_closed_rods_outline_falls_through(length, spacing):
    """Every ray more than a twentieth of a cell inside a closed rod's outline meets it:
    faces sharing an edge test a ray on it with the same edge function (one of them, or
    both, takes it: watertight), and the cells a face may cover are found from the
    float32 centres themselves, up to 10⁵ cells from the grid's first (a float32 centre
    drifts by a fraction of a cell there)."""
    from meshladar.raytrace.grid import stratified_offsets
    scene = _scene([_rod(length)])
    geo = geometry(scene, "flat")
    assert geo.closed.all()
    w = np.array([0.0, 0.3, 1.0]) / np.hypot(0.3, 1.0)
    plan = grid_plan(geo, w, "3d", spacing, 0.0, np.random.default_rng(0))
    f32 = np.float32
    vertices = embree_scene(geo, "raster").raster[0] * geo.scale
    axes = np.array([plan.u.astype(f32), plan.v.astype(f32), w], np.float64)
    proj = np.stack([vertices @ a for a in axes], axis=1)
    n = plan.s.size * plan.t.size
    prim, height = np.empty(n, np.int32), np.empty(n)
    zbuffer(proj, geo.faces32, geo.face_normals @ w, geo.closed, plan.s.astype(f32),
            plan.t.astype(f32), plan.offsets, f32(spacing), prim, height)
    du, dv = stratified_offsets(plan.offsets)
    inside = np.ones(du.shape, bool)
    for d, centres, axis in ((du, plan.s[:, None], axes[0]), (dv, plan.t[None, :], axes[1])):
        x = d * f32(spacing) + centres.astype(f32)         # the rays' S, T
        ends = geo.shifted @ axis
        inside &= np.minimum(x - ends.min(), ends.max() - x) > 0.05 * spacing
    assert inside.sum() > 100_000
    assert (prim.reshape(inside.shape)[inside] < 0).sum() == 0
