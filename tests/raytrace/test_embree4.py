"""The packet backend (meshladar.raytrace.embree4): the Embree 4 library of the embreex
wheel through ctypes, against embreex itself, the reference."""

from __future__ import annotations

import copy
import subprocess
import sys
import warnings

from dataclasses import replace

import numpy as np
import pytest

import meshladar as ml
from meshladar.errors import MeshladarWarning, ParameterError
from meshladar.materials import ALUMINUM, DARK_GRAY
from meshladar.raytrace import embree4

from conftest import PAIR  # noqa: E402  (the shared disk pair)

#: Backends agree to float64 round-off where they report the same face: ranges are
#: recomputed in float64 from the same float32 origin and face plane.
SAME_HITS_RTOL = 1e-12


def _sphere(subdivisions=4):
    return ml.Scene.from_parts([ml.meshes.sphere((0.1, -0.2, 0.3), 0.5, 0,
                                               subdivisions=subdivisions)], [DARK_GRAY])


def test_the_library_is_embree_4_with_a_native_packet_width():
    lib = embree4.library()
    assert lib.version[0] == 4 and lib.width in (4, 8, 16) and lib.native[lib.width]
    assert embree4.available() == (True, lib.path)


@pytest.mark.parametrize("width", [4, 8, 16])
def test_the_self_test_passes_at_every_width_and_fails_a_library_that_does_not_answer(width):
    """The check library() runs once (at the native width) holds at every width, and a
    library whose packet queries leave the packet untouched (as one with other layouts
    would answer nothing where these layouts read) fails it with an OSError naming the
    width, not later in a cast; so does one whose single-ray query answers nothing."""
    lib = embree4.library()
    probe = copy.copy(lib)                      # the same library and device, another width
    probe.width = width
    embree4._self_test(probe)
    probe.intersect = {width: lambda *args: None}
    with pytest.raises(OSError, match=f"a {width}-wide packet"):
        embree4._self_test(probe)
    probe.intersect, probe.occluded = lib.intersect, {width: lambda *args: None}
    with pytest.raises(OSError, match=f"a {width}-wide packet"):
        embree4._self_test(probe)
    probe.occluded, probe.intersect1 = lib.occluded, lambda *args: None
    with pytest.raises(OSError, match=r"a single ray \(rtcIntersect1\)"):
        embree4._self_test(probe)


def _assert_same_hits(a, b):
    assert a.size == b.size > 0
    for name in ("view", "material", "rays", "back_face_hits"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    for name in ("range", "cos_theta", "sin_theta", "spread", "bistatic", "weight_factor"):
        x, y = getattr(a, name), getattr(b, name)
        if x is None:
            assert y is None
            continue
        np.testing.assert_allclose(x, y, rtol=SAME_HITS_RTOL, atol=1e-15)


@pytest.mark.parametrize("width", [4, 8, 16])
def test_tiles_of_a_grid_give_the_hits_of_its_rows(width):
    """A grid cast in tiles (columns=) finds, ray by ray, the face, distance and
    barycentrics that packets of consecutive rays find: 37 rows of 29 rays, so that the
    last tiles of each row and of the grid are partial at every width."""
    scene = _sphere(3)
    geo = ml.raytrace.embree.Geometry(scene, "flat")
    pk = ml.raytrace.embree.embree_scene(geo, "packets").scene.scene
    w = np.array([0.3, -0.5, 0.81])
    w /= np.linalg.norm(w)
    u = np.cross(w, [0.0, 0.0, 1.0])
    u /= np.linalg.norm(u)
    v = np.cross(w, u)
    s, t = np.linspace(-0.55, 0.55, 37), np.linspace(-0.55, 0.55, 29)
    o = (s[:, None, None] * u + t[None, :, None] * v + 2.0 * w).reshape(-1, 3)
    d = (-w).astype(np.float32)
    rows = pk.cast_grid(o, d, width=width, barycentrics=True)
    tiles = pk.cast_grid(o, d, width=width, barycentrics=True, columns=29)
    hit = rows.prim >= 0
    assert 0.3 < hit.mean() < 0.9                  # hits and misses, in every tile row
    np.testing.assert_array_equal(tiles.prim, rows.prim)
    np.testing.assert_array_equal(tiles.tfar, rows.tfar)
    np.testing.assert_array_equal(tiles.u[hit], rows.u[hit])
    np.testing.assert_array_equal(tiles.v[hit], rows.v[hit])
    with pytest.raises(ValueError, match="columns must be 0 or the length"):
        pk.cast_grid(o, d, columns=30)


@pytest.mark.parametrize("options", [
    {"normals": "flat"},
    {"normals": "smooth"},                          # the hits' barycentrics
    {"normals": "flat", "receiver": (0.6, 0.8, 0.0)},   # occlusion rays toward the receiver
], ids=["flat", "smooth", "bistatic"])
def test_packets_give_embreexs_hits_and_sinograms(options):
    scene = _sphere()
    ladar = ml.Ladar.covering(scene, n_bins=32, angles_deg=[0.0, 37.0, 145.0])
    a = ml.trace(scene, ladar, backend="embreex", rays_per_bin=4, **options)
    b = ml.trace(scene, ladar, backend="packets", rays_per_bin=4, **options)
    assert a.info["backend"] == "embreex" and b.info["backend"] == "packets"
    _assert_same_hits(a, b)
    sa, sb = ml.weigh(a), ml.weigh(b)
    np.testing.assert_allclose(sb.values, sa.values, rtol=SAME_HITS_RTOL,
                               atol=SAME_HITS_RTOL * np.abs(sa.values).max())


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # faceted on purpose
def test_the_streaming_paths_agree_too():
    # the fused monostatic path (flat normals, point bins) and the slice mode of a phantom
    mesh = PAIR.tessellate(256)
    ladar = ml.Ladar.paper(angles_deg=np.arange(0.0, 360.0, 15.0))
    for kwargs in ({}, {"footprint": True, "normals": "exact"}):
        a = ml.simulate(mesh, ladar, model="mesh", backend="embreex", **kwargs)
        b = ml.simulate(mesh, ladar, model="mesh", backend="packets", **kwargs)
        assert b.info["backend"] == "packets"
        np.testing.assert_allclose(b.values, a.values, rtol=SAME_HITS_RTOL,
                                   atol=SAME_HITS_RTOL * np.abs(a.values).max())
    scene = ml.Scene.from_parts([ml.meshes.sphere((0, 0, 0), 0.5, 0, subdivisions=3)],
                                [ALUMINUM])
    ladar = ml.Ladar.covering(scene, n_bins=16, view_vectors=ml.meshes.fibonacci_sphere(6))
    a = ml.simulate(scene, ladar, model="mesh", backend="embreex")
    b = ml.simulate(scene, ladar, model="mesh", backend="packets")
    np.testing.assert_allclose(b.values, a.values, rtol=SAME_HITS_RTOL,
                               atol=SAME_HITS_RTOL * np.abs(a.values).max())


def test_threads_share_one_scene_and_give_the_serial_numbers():
    scene = _sphere(3)
    ladar = ml.Ladar.covering(scene, n_bins=32, angles_deg=np.arange(0.0, 360.0, 10.0))
    one = ml.simulate(scene, ladar, model="mesh", jobs=1)
    two = ml.simulate(scene, ladar, model="mesh", jobs=2)
    np.testing.assert_array_equal(two.values, one.values)


def test_a_backend_that_cannot_load_is_said_once_and_never_changes_the_numbers(monkeypatch):
    from meshladar.raytrace import backends as engine

    scene = _sphere(2)
    ladar = ml.Ladar.covering(scene, n_bins=8, angles_deg=[0.0])
    ref = ml.simulate(scene, ladar, model="mesh", backend="embreex")
    monkeypatch.setattr(embree4, "_LIB", None)
    monkeypatch.setattr(embree4, "_LIB_ERROR", "no Embree 4 library found (test)")
    monkeypatch.setattr(engine, "_FALLBACK_SAID", False)
    with pytest.warns(MeshladarWarning, match=r"the packet backend cannot load \(no Embree 4 "
                                              r"library found \(test\)\): the mesh engine "
                                              r"casts with embreex"):
        got = ml.simulate(scene, ladar, model="mesh")
    assert got.info["backend"] == "embreex"
    np.testing.assert_array_equal(got.values, ref.values)
    with warnings.catch_warnings():
        warnings.simplefilter("error")                    # said once, not on every call
        ml.simulate(scene, ladar, model="mesh")
    with pytest.raises(ParameterError, match=r"backend='packets' cannot load here \(no "
                                             r"Embree 4 library found \(test\)\)"):
        ml.simulate(scene, ladar, model="mesh", backend="packets")


def test_an_unknown_backend_is_refused():
    scene = _sphere(1)
    with pytest.raises(ParameterError, match=r"backend must be one of \('auto', 'packets', "
                                             r"'raster', 'embreex', 'warp', 'warp-cpu'\); "
                                             r"got 'optix'"):
        ml.simulate(scene, ml.Ladar.covering(scene, n_bins=4, angles_deg=[0.0]),
                    model="mesh", backend="optix")


def test_a_wrong_library_path_is_a_reason_not_a_crash(tmp_path):
    fake = tmp_path / "libembree4.so.4"
    fake.write_bytes(b"not a shared library")
    code = ("from meshladar.raytrace import embree4; ok, why = embree4.available(); "
            "print(ok); print(why)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env={"MESHLADAR_EMBREE4": str(fake), "PATH": ""}, check=True).stdout
    ok, why = out.splitlines()[:2]
    assert ok == "False" and str(fake) in why


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # coarse on purpose
@pytest.mark.parametrize("normals", ["flat", "smooth"])
@pytest.mark.parametrize("sampling", ["regular", "stratified"])
def test_the_fused_loop_gives_the_unfused_numbers_bit_for_bit(sampling, normals, monkeypatch):
    # grid, cast, weigh and bin in one loop build the same float32 origins and bin the
    # same hits (with smooth normals, the same barycentrics) as the path through per-ray
    # arrays: equal, not merely close; the far, large sphere makes Embree's unit-size copy
    # a real rescaling
    from meshladar.raytrace.backends import REGISTRY, backend
    from meshladar.raytrace.embree import EmbreeScene

    backend("packets")                                       # registered on first use

    for centre, radius in (((0.0, 0.0, 0.0), 0.5), ((1e3, -2e3, 5e2), 37.0)):
        scene = ml.Scene.from_parts([ml.meshes.sphere(centre, radius, 0, subdivisions=4)],
                                    [ALUMINUM])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", MeshladarWarning)    # the far sphere's bins
            ladar = ml.Ladar.covering(scene, n_bins=48,
                                      view_vectors=ml.meshes.fibonacci_sphere(5))
            fused = ml.simulate(scene, ladar, model="mesh", sampling=sampling,
                                backend="packets", normals=normals)
            with monkeypatch.context() as m:
                m.setattr(EmbreeScene, "fused", property(lambda self: False))
                m.setitem(REGISTRY, "packets", replace(REGISTRY["packets"], fused=False))
                plain = ml.simulate(scene, ladar, model="mesh", sampling=sampling,
                                    backend="packets", normals=normals)
        assert fused.info["rays"] == plain.info["rays"] > 0
        np.testing.assert_array_equal(fused.values, plain.values)


@pytest.mark.parametrize("footprint", [False, True])
def test_grids_sparser_than_their_faces_are_cast_ray_by_ray_with_the_same_numbers(
        footprint, monkeypatch):
    """A grid with fewer rays than a face's area holds (Σa²/Σa over δ²: 0.3 here) is cast
    one ray at a time, a dense one (12) in coherent packets; either way gives the same
    hits, so the same sinogram. With footprint bins, a sparse grid makes each face's row
    at its first hit and a dense one every row before the cast: the same rows."""
    from meshladar.forward import fused_views
    from meshladar.raytrace import plan as plan_module
    from meshladar.raytrace.plan import plan_trace

    flags, casts = [], {f: getattr(fused_views, f) for f in ("cast_bin_grid", "cast_bin_views")}
    coherent_at = {"cast_bin_grid": 7, "cast_bin_views": 5}    # where the flag is passed

    def spying(name):                    # a view alone, or a chunk's views in one call
        def spy(*args):
            flags.append(args[coherent_at[name]])
            return casts[name](*args)
        return spy

    scene = _sphere(5)
    ladar = ml.Ladar.covering(scene, n_bins=32, view_vectors=ml.meshes.fibonacci_sphere(7))
    area = scene.parts[0].face_normals_areas()[1]
    typical = float(area @ area / area.sum())
    for per_face, coherent in ((0.3, False), (12.0, True)):
        spacing = (typical / per_face) ** 0.5
        plan = plan_trace(scene, ladar, ray_spacing=spacing, backend="packets")
        assert plan.geo.hit_face_area == pytest.approx(typical, rel=1e-12)
        assert plan.coherent is coherent
        for name in casts:
            monkeypatch.setattr(fused_views, name, spying(name))
        flags.clear()
        chosen = ml.simulate(scene, ladar, model="mesh", ray_spacing=spacing,
                             backend="packets", footprint=footprint)
        assert flags == [coherent] * 7                              # what the loop got
        monkeypatch.setattr(plan_module, "COHERENT_SCALE",
                            np.inf if coherent else 0.0)            # the other way
        other = ml.simulate(scene, ladar, model="mesh", ray_spacing=spacing,
                            backend="packets", footprint=footprint)
        assert flags[7:] == [not coherent] * 7
        monkeypatch.undo()
        assert chosen.info["rays"] == other.info["rays"] > 0
        np.testing.assert_allclose(other.values, chosen.values, rtol=SAME_HITS_RTOL,
                                   atol=SAME_HITS_RTOL * np.abs(chosen.values).max())


def test_the_coherent_flag_pays_from_fewer_rays_a_face_on_bigger_meshes():
    """3-D grids are cast coherent from COHERENT_SCALE / √faces rays on the face a ray hits
    (the break-even measured on icospheres): 0.6 rays a face is incoherent on 20k faces
    (0.6 √20480 = 86 < 128) and coherent on 82k (0.6 √81920 = 172); a slice's rows keep
    one ray a face; footprints are made before the cast from one ray a face on."""
    from meshladar.raytrace.plan import COHERENT_SCALE, plan_trace

    assert COHERENT_SCALE == 128.0
    for subdivisions, per_face, coherent in ((5, 0.6, False), (6, 0.6, True), (6, 0.4, False),
                                             (5, 0.95, True)):
        scene = _sphere(subdivisions)
        ladar = ml.Ladar.covering(scene, n_bins=8, angles_deg=[0.0])
        area = scene.parts[0].face_normals_areas()[1]
        spacing = (float(area @ area / area.sum()) / per_face) ** 0.5
        plan = plan_trace(scene, ladar, ray_spacing=spacing, backend="packets")
        assert plan.rays_per_face == pytest.approx(per_face, rel=1e-12)
        assert plan.coherent is coherent, (subdivisions, per_face)
        assert plan.dense is False
        flat = plan_trace(scene, ladar, mode="slice", ray_spacing=spacing, backend="packets")
        assert flat.coherent is flat.dense is (flat.rays_per_face >= 1.0)


@pytest.mark.parametrize("sampling", ["regular", "stratified"])
def test_one_big_view_splits_its_rows_over_threads(sampling):
    # a single view is one chunk: its rows go to threads instead, each band with its own
    # bins and weight cache, added in order (the one-thread numbers to rounding)
    scene = _sphere(4)
    ladar = ml.Ladar.covering(scene, n_bins=64, view_vectors=[[0.3, -0.4, 0.866]])
    one = ml.simulate(scene, ladar, model="mesh", jobs=1, sampling=sampling,
                      rays_per_bin=16)
    for jobs in (2, 3):
        many = ml.simulate(scene, ladar, model="mesh", jobs=jobs, sampling=sampling,
                           rays_per_bin=16)
        assert many.info["rays"] == one.info["rays"]
        assert many.info["back_face_hits"] == one.info["back_face_hits"]
        np.testing.assert_allclose(many.values, one.values, rtol=SAME_HITS_RTOL,
                                   atol=SAME_HITS_RTOL * one.values.max())
        again = ml.simulate(scene, ladar, model="mesh", jobs=jobs, sampling=sampling,
                            rays_per_bin=16)
        np.testing.assert_array_equal(again.values, many.values)     # reproducible


@pytest.mark.parametrize("backend", ["packets", "embreex"])
def test_any_coating_takes_the_fused_path_with_the_general_paths_numbers(backend):
    # coatings without a compiled kernel (Phong, GGX, a table, a user's model) have F·area
    # evaluated per face and view before the cast: the numbers of trace + weigh, per hit
    class Halfway(ml.brdf.BRDF):                     # a user's model: projected weight only
        def projected(self, cos_theta, sin_theta):
            return 0.3 * np.maximum(cos_theta, 0.0) ** 2

    coatings = [ml.brdf.Phong(0.2, 0.7, 50), ml.brdf.GGX(alpha=0.3),
                ml.brdf.Tabulated([0.0, 30.0, 60.0, 90.0], [0.3, 0.2, 0.1, 0.05]), Halfway()]
    parts = [ml.meshes.sphere((0.6 * k, 0.0, 0.0), 0.25, k, subdivisions=3) for k in range(4)]
    scene = ml.Scene.from_parts(parts, coatings)
    ladar = ml.Ladar.covering(scene, n_bins=40, view_vectors=ml.meshes.fibonacci_sphere(3))
    one_view = ml.Ladar.covering(scene, n_bins=40, view_vectors=[[0.2, 0.9, 0.3]])
    for lad, jobs in ((ladar, 1), (ladar, 2), (one_view, 2)):   # 2 jobs on one view: rows
        fused = ml.simulate(scene, lad, model="mesh", backend=backend, jobs=jobs)
        general = ml.weigh(ml.trace(scene, lad, backend=backend))
        assert fused.values.max() > 0
        np.testing.assert_allclose(fused.values, general.values, rtol=SAME_HITS_RTOL,
                                   atol=SAME_HITS_RTOL * general.values.max())


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # coarse on purpose
@pytest.mark.filterwarnings("ignore::meshladar.errors.BounceWarning")  # two glinting bodies
@pytest.mark.parametrize("back_faces", ["two-sided", "ignore"])
def test_smooth_normals_take_a_compiled_loop_with_the_general_paths_numbers(back_faces):
    # smooth normals with SR coatings are weighed and binned in one compiled loop from the
    # cast's barycentrics: the numbers of trace + weigh (per-hit arrays in numpy)
    parts = [ml.meshes.sphere((0.0, 0.0, 0.0), 0.4, 0, subdivisions=3),
             ml.meshes.sphere((0.9, 0.1, 0.0), 0.3, 1, subdivisions=2)]
    scene = ml.Scene.from_parts(parts, [ALUMINUM, DARK_GRAY])
    ladar = ml.Ladar.covering(scene, n_bins=48, view_vectors=ml.meshes.fibonacci_sphere(9))
    for backend in ("packets", "embreex"):
        fast = ml.simulate(scene, ladar, model="mesh", normals="smooth", backend=backend,
                           back_faces=back_faces)
        general = ml.weigh(ml.trace(scene, ladar, normals="smooth", backend=backend,
                                    back_faces=back_faces))
        assert fast.values.max() > 0 and fast.info["rays"] == general.info["rays"]
        assert fast.info["back_face_hits"] == general.info["back_face_hits"]
        np.testing.assert_allclose(fast.values, general.values, rtol=SAME_HITS_RTOL,
                                   atol=SAME_HITS_RTOL * general.values.max())


@pytest.mark.filterwarnings("ignore::meshladar.errors.BounceWarning")  # two glinting bodies
@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # coarse on purpose
@pytest.mark.parametrize("mode, normals", [("3d", "flat"), ("slice", "flat"),
                                           ("3d", "smooth")])
def test_footprints_take_the_fused_loop_with_the_general_paths_numbers(mode, normals,
                                                                       monkeypatch):
    # footprint binning with flat normals (any coating) or smooth ones (SR coatings), either
    # radiometry, back faces two-sided or ignored, regular or stratified rays, views on
    # threads or one view's rows, is weighed and spread in the compiled loop, from one
    # footprint row per face and view: the numbers of trace + weigh(footprint=True), and
    # the per-hit path is not taken
    from meshladar.forward import job as model

    plate = ml.meshes.MeshPart(np.array([[-0.5, -0.4, -0.3], [0.5, -0.4, 0.2], [0.5, 0.4, 0.3],
                                       [-0.5, 0.4, -0.2]]), np.array([[0, 1, 2], [0, 2, 3]]),
                             1, name="plate")                 # open: seen from both sides
    parts = [ml.meshes.sphere((0.0, 0.0, 0.0), 0.3, 0, subdivisions=3), plate]
    for coatings in ([ALUMINUM, DARK_GRAY], [ml.brdf.GGX(alpha=0.3), DARK_GRAY])[
            :1 if normals == "smooth" else 2]:
        scene = ml.Scene.from_parts(parts, coatings)
        vectors = ml.meshes.fibonacci_sphere(5) if mode == "3d" else None
        ladar = ml.Ladar.covering(scene, n_bins=40, view_vectors=vectors,
                                  angles_deg=None if vectors is not None else [0, 70, 200])
        for backend in ("packets", "embreex"):
            for options in ({}, {"back_faces": "ignore", "radiometry": "power"},
                            {"sampling": "stratified", "seed": 4, "jobs": 2}):
                general = ml.weigh(ml.trace(scene, ladar, mode=mode, backend=backend,
                                            normals=normals, rays_per_bin=3,
                                            **{k: v for k, v in
                                                               options.items()
                                                               if k != "radiometry"}),
                                   footprint=True,
                                   radiometry=options.get("radiometry", "paper"))
                with monkeypatch.context() as m:
                    m.setattr(model, "_bin_one", None)           # the per-hit path is not used
                    m.setattr(model, "QUICK_RAYS", 0)     # (small embreex runs would take it)
                    fused = ml.simulate(scene, ladar, model="mesh", mode=mode,
                                        normals=normals, backend=backend, footprint=True,
                                        rays_per_bin=3, **options)
                assert fused.values.max() > 0 and fused.info["footprint"] is True
                assert "receiver" not in fused.info                       # monostatic
                assert fused.info["back_face_hits"] == general.info["back_face_hits"]
                assert sum(general.info["back_face_hits"]) > 0
                np.testing.assert_allclose(fused.values, general.values, rtol=SAME_HITS_RTOL,
                                           atol=SAME_HITS_RTOL * general.values.max())
    one_view = ml.Ladar.covering(scene, n_bins=40, view_vectors=[[0.2, 0.9, 0.3]])
    if mode == "3d":                                   # one view's rows on two threads
        rows = ml.simulate(scene, one_view, model="mesh", footprint=True, jobs=2)
        one = ml.simulate(scene, one_view, model="mesh", footprint=True, jobs=1)
        np.testing.assert_allclose(rows.values, one.values, rtol=SAME_HITS_RTOL,
                                   atol=SAME_HITS_RTOL * one.values.max())


@pytest.mark.filterwarnings("ignore::meshladar.errors.BounceWarning")  # two glinting bodies
@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # faceted on purpose
@pytest.mark.slow
@pytest.mark.parametrize("mode", ["3d", "slice"])
def test_bistatic_views_take_the_fused_loop_with_the_references_numbers(mode, monkeypatch):
    # a receiver off the ladar's axis (flat normals, any coating, either radiometry, back
    # faces two-sided or ignored, views on threads or one view's rows): each face's weight
    # for the pair of directions at its first hit (built-in coatings, compiled) or before
    # the cast (GGX, numpy), each hit's occlusion ray toward the receiver cast in packets
    # inside the loop; the numbers of embreex's per-hit path
    from meshladar.forward import job as model
    from meshladar.weighing import faces

    monkeypatch.setattr(faces, "_FACE_BLOCK", 1000)        # the face weights in blocks
    plate = ml.meshes.MeshPart(np.array([[-0.5, -0.4, -0.3], [0.5, -0.4, 0.2], [0.5, 0.4, 0.3],
                                       [-0.5, 0.4, -0.2]]), np.array([[0, 1, 2], [0, 2, 3]]),
                             1, name="plate")
    parts = [ml.meshes.sphere((0.0, 0.0, 0.0), 0.3, 0, subdivisions=3),
             ml.meshes.sphere((0.5, 0.3, 0.1), 0.2, 0, subdivisions=3), plate]
    receiver = (0.6, 0.8, 0.0) if mode == "slice" else (0.3, 0.5, 0.81)
    for coatings in ([ALUMINUM, ml.brdf.Lambertian(0.3)], [ml.brdf.GGX(alpha=0.3), DARK_GRAY]):
        scene = ml.Scene.from_parts(parts, coatings)
        vectors = ml.meshes.fibonacci_sphere(5) if mode == "3d" else None
        ladar = ml.Ladar.covering(scene, n_bins=64, view_vectors=vectors,
                                  angles_deg=None if vectors is not None else [0, 70, 200])
        hits = ml.trace(scene, ladar, mode=mode, receiver=receiver, backend="embreex",
                        rays_per_bin=3)
        assert ((hits.bistatic[:, 0] == -1) & (hits.cos_theta > 0)).sum() > 100  # shadowed
        for options in ({}, {"back_faces": "ignore", "radiometry": "power"},
                        {"back_faces": "ignore"}, {"jobs": 2}):
            trace_options = {k: v for k, v in options.items() if k != "radiometry"}
            ref = ml.weigh(ml.trace(scene, ladar, mode=mode, receiver=receiver,
                                    backend="embreex", rays_per_bin=3, **trace_options),
                           radiometry=options.get("radiometry", "paper"))
            with monkeypatch.context() as m:
                m.setattr(model, "_bin_one", None)           # the per-hit path is not used
                fused = ml.simulate(scene, ladar, model="mesh", mode=mode,
                                    receiver=receiver, backend="packets", rays_per_bin=3,
                                    **options)
            assert fused.values.max() > 0
            # the result says it is bistatic, and toward where
            np.testing.assert_allclose(fused.info["receiver"],
                                       np.array(receiver) / np.linalg.norm(receiver))
            assert fused.info["back_face_hits"] == ref.info["back_face_hits"]
            np.testing.assert_allclose(fused.values, ref.values, rtol=SAME_HITS_RTOL,
                                       atol=SAME_HITS_RTOL * ref.values.max())
    if mode == "3d":                                   # one view's rows on two threads
        one_view = ml.Ladar.covering(scene, n_bins=40, view_vectors=[[0.2, 0.9, 0.3]])
        rows = ml.simulate(scene, one_view, model="mesh", receiver=receiver, jobs=2)
        one = ml.simulate(scene, one_view, model="mesh", receiver=receiver, jobs=1)
        np.testing.assert_allclose(rows.values, one.values, rtol=SAME_HITS_RTOL,
                                   atol=SAME_HITS_RTOL * one.values.max())
