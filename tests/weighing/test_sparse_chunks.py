"""A run of many small views (grids sparser than their faces) casts each chunk's views in one
compiled call (meshladar.forward.fused_views.chunk_views: built-in coatings; flat or smooth
normals, monostatic, point or footprint bins, or flat ones, point bins and a receiver): the
grids planned together
(meshladar.raytrace.grid.grid_plans, Geometry.extents), each view's offsets drawn from its
own seed. Every number is the one the view gets alone (cast_bin_grid, a call a view), bit
for bit, and the embreex backend's (its own caster, weighed in numpy) to round-off."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import meshladar as ml
from meshladar.forward import mesh as mesh_module
from meshladar.materials import ALUMINUM, DARK_GRAY
from meshladar.raytrace import embree4
from meshladar.raytrace.embree import Geometry
from meshladar.raytrace.grid import grid_plan, grid_plans
from meshladar.weighing.fused import _coating

pytestmark = pytest.mark.skipif(not embree4.available(),
                                reason="the packet backend does not load here")

#: The embreex backend agrees to float64 round-off where it reports the same face.
SAME_HITS_RTOL = 1e-12


def _scene(subdivisions=4):
    return ml.Scene.from_parts(
        [ml.meshes.sphere((0.1, -0.2, 0.3), 0.5, 0, subdivisions=subdivisions),
         ml.meshes.sphere((0.4, 0.5, 0.0), 0.2, 1, subdivisions=2)], [ALUMINUM, DARK_GRAY])


def _spacing(scene, per_face):
    area = np.concatenate([p.face_normals_areas()[1] for p in scene.parts])
    return (float(area @ area / area.sum()) / per_face) ** 0.5


def _run(scene, ladar, batched, monkeypatch, **options):
    """The run with its job's ``batched`` as given (each chunk in one call, or a call a
    view), and the jobs as planned."""
    plan_job, planned = mesh_module.plan_job, []

    def forced(*args, **kwargs):
        job = plan_job(*args, **kwargs)
        planned.append(job)
        return dataclasses.replace(job, batched=batched)

    monkeypatch.setattr(mesh_module, "plan_job", forced)
    out = ml.simulate(scene, ladar, model="mesh", backend="packets", jobs=1, **options)
    monkeypatch.undo()
    return out, planned


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # sparse on purpose
@pytest.mark.parametrize("options", [{}, {"sampling": "regular"},
                                     {"radiometry": "power", "back_faces": "ignore"},
                                     {"normals": "smooth"}, {"mode": "slice"},
                                     {"receiver": [0.6, 0.0, 0.8], "radiometry": "power"},
                                     {"receiver": [0.0, 0.6, 0.8], "back_faces": "ignore"},
                                     {"footprint": True}, {"footprint": True, "per_face": 1.3},
                                     {"normals": "smooth", "footprint": True},
                                     {"mode": "slice", "footprint": True}],
                         ids=["stratified", "regular", "power", "smooth", "slice",
                              "bistatic", "bistatic-paper", "footprint", "footprint-dense",
                              "smooth-footprint", "slice-footprint"])
@pytest.mark.filterwarnings("ignore::meshladar.errors.BounceWarning")  # two spheres: power
def test_a_chunk_in_one_call_gives_each_views_own_numbers(options, monkeypatch):
    """Footprint bins too, their rows made at first hits, or every row first where the grid
    is dense (1.3 rays a face) though sparser than coherent packets need (5,440 faces:
    128 / √faces = 1.7)."""
    scene, options = _scene(), dict(options)
    per_face = options.pop("per_face", None)              # the dense case's rays a face
    views = ({"angles_deg": np.linspace(0.0, 360.0, 40, endpoint=False)}
             if options.get("mode") == "slice" else
             {"view_vectors": np.vstack([ml.meshes.fibonacci_sphere(38),
                                         [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]])})
    ladar = ml.Ladar.covering(scene, n_bins=64, **views)
    spacing = _spacing(scene, per_face or (0.1 if options.get("mode") != "slice" else 0.05))
    together, planned = _run(scene, ladar, True, monkeypatch, ray_spacing=spacing, **options)
    assert [job.batched for job in planned] == [True]         # sparse: a chunk a call
    if per_face is not None:                                  # dense, not coherent
        assert planned[0].plan.dense and not planned[0].plan.coherent
    alone, _ = _run(scene, ladar, False, monkeypatch, ray_spacing=spacing, **options)
    np.testing.assert_array_equal(together.values, alone.values)
    assert together.info["rays"] == alone.info["rays"] > 0
    assert together.info["back_face_hits"] == alone.info["back_face_hits"]
    ref = ml.simulate(scene, ladar, model="mesh", backend="embreex", ray_spacing=spacing,
                      **options)
    assert ref.info["rays"] == together.info["rays"]
    assert np.count_nonzero(ref.values) >= 40 * 3             # the spheres fill bins
    np.testing.assert_allclose(together.values, ref.values, rtol=SAME_HITS_RTOL,
                               atol=SAME_HITS_RTOL * np.abs(ref.values).max())


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")
@pytest.mark.parametrize("options", [{"sampling": "regular"}, {"phong": True},
                                     {"receiver": [0.6, 0.0, 0.8], "phong": True}],
                         ids=["dense", "phong", "bistatic-phong"])
def test_only_sparse_grids_of_built_in_coatings_go_a_chunk_a_call(options, monkeypatch):
    scene, options = _scene(2), dict(options)
    if options.pop("phong", False):               # a coating without a compiled kernel
        scene = ml.Scene.from_parts(scene.parts, [ml.brdf.Phong(0.3, 0.5, 40.0)] * 2)
    ladar = ml.Ladar.covering(scene, n_bins=16, view_vectors=ml.meshes.fibonacci_sphere(3))
    per_face = 40.0 if options.get("sampling") else 0.1
    _, planned = _run(scene, ladar, False, monkeypatch, ray_spacing=_spacing(scene, per_face),
                      radiometry="power", **options)
    assert [job.batched for job in planned] == [False]


@pytest.mark.parametrize("views", [8, 40])          # the extents over clusters from 32 on
@pytest.mark.parametrize("mode", ["3d", "slice"])
def test_grids_planned_together_are_each_views_own(views, mode):
    scene = ml.Scene.from_parts([ml.meshes.sphere((3.0, -1.0, 2.0), 1.5, 0, subdivisions=5)],
                                [ALUMINUM])
    geo = Geometry(scene, "flat")
    geo.for_views(scene, views)
    w = np.vstack([ml.meshes.fibonacci_sphere(views - 2), [[0.0, 0.0, 1.0],
                                                            [-0.0, 0.0, -1.0]]])
    plans = grid_plans(geo, w, mode, 0.037, 0.25)
    assert plans.s_at[-1] == plans.s.size and plans.t_at[-1] == plans.t.size
    for j, x in enumerate(w):
        one = grid_plan(geo, x, mode, 0.037, 0.25, None)
        np.testing.assert_array_equal(plans.s[plans.s_at[j]:plans.s_at[j + 1]], one.s)
        np.testing.assert_array_equal(plans.t[plans.t_at[j]:plans.t_at[j + 1]], one.t)
        np.testing.assert_array_equal(plans.u[j], one.u)
        np.testing.assert_array_equal(plans.v[j], one.v)
        assert plans.L == one.L
    ext = geo.extents(plans.u)                       # against numpy over every point
    x = geo.support @ plans.u.T
    np.testing.assert_allclose(ext[:, 0], x.min(axis=0), rtol=0, atol=1e-15 * geo.radius)
    np.testing.assert_allclose(ext[:, 1], x.max(axis=0), rtol=0, atol=1e-15 * geo.radius)


def test_the_bistatic_half_vectors_are_the_same_on_every_cpu():
    """The bistatic loops' half vectors (w + w_r)/|w + w_r| (fused._coating), one view or a
    chunk's rows, equal plain Python floats' (|w + w_r| the root of the squares summed in
    order: no BLAS dot, whose order and fused multiplies are the CPU's), bit for bit."""
    rng = np.random.default_rng(11)
    w = rng.normal(size=(500, 3))
    wr = rng.normal(size=(500, 3)) * rng.uniform(1e-3, 1e3, (500, 1))
    bins = dataclasses.make_dataclass("Bins", ["face_material", "params", "area", "power"])(
        None, None, 1.0, True)
    half = _coating(bins, w, wr, True)[2]
    for k in range(len(w)):
        x = [float(a + b) for a, b in zip(w[k], wr[k])]
        n = math.sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2])
        assert half[k].tolist() == [c / n for c in x]
        assert _coating(bins, w[k], wr[k], True)[2].tolist() == [c / n for c in x]
