"""The Warp backends (meshladar.raytrace.warp_backend): Warp's ray queries, run here on the
CPU ("warp-cpu", the kernels a CUDA device runs), against the packet backend on the same
rays; "warp" itself needs a CUDA device and says so in one line where there is none."""

from __future__ import annotations

import importlib.util
import warnings
from dataclasses import replace

import numpy as np
import pytest

import meshladar as ml
from meshladar.errors import ParameterError
from meshladar.materials import ALUMINUM, DARK_GRAY
from meshladar.raytrace import backends
from meshladar.raytrace.embree import Geometry, embree_scene

pytest.importorskip("warp")          # a test dependency: present in CI (pyproject [test])

from meshladar.raytrace import warp_backend  # noqa: E402

#: Rays whose first hit is on another face than Embree's: only rays within float32
#: round-off of an edge shared by two faces (Warp's triangle test is not watertight).
MAX_OTHER_FACE = 1e-3
#: Barycentrics: both engines work in float32, each by its own formula; on faces 0.05 across
#: hit from origins 2 away, round-off in the hit point of ~2e-7 is ~4e-6 of an edge, and
#: Warp's formula loses more on thin intersections (measured: 1.2e-4 at most, on 20,000
#: rays). A wrong convention (Warp's own weights of p0 and p1) would be off by ~0.3.
BARY_ATOL = 5e-4
#: Sinograms: flat normals weigh each hit by its face, recomputing its range in float64
#: from the face's plane: equal where the faces are; smooth normals interpolate Warp's
#: float32 barycentrics (measured 1.0e-6 of the peak on the sphere below).
FLAT_RTOL, SMOOTH_RTOL = 1e-9, 1e-5


def _sphere(subdivisions=4):
    return ml.Scene.from_parts([ml.meshes.sphere((0.1, -0.2, 0.3), 0.5, 0,
                                               subdivisions=subdivisions)], [DARK_GRAY])


def _scenes(scene):
    geo = Geometry(scene, "flat")
    return geo, embree_scene(geo, "packets"), embree_scene(geo, "warp-cpu")


def test_first_hits_are_the_packet_backends_ray_for_ray():
    geo, pk, wp = _scenes(_sphere())
    rng = np.random.default_rng(3)
    n = 20_000
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    one = np.array([[0.3, -0.4, -0.866]])
    one /= np.linalg.norm(one)
    jitter = 0.4 * rng.uniform(-1, 1, (n, 3))
    for dirs in (d, one):                               # one direction per ray, or one
        o = (-2.0 * dirs + jitter).astype(np.float32)
        dirs = dirs.astype(np.float32)
        a, b = pk.run(o, dirs, output=1), wp.run(o, dirs, output=1)
        hit = a["primID"] >= 0
        assert 0.2 < hit.mean() < 0.95
        np.testing.assert_array_equal(b["primID"] >= 0, hit)
        same = a["primID"] == b["primID"]
        assert (~same).mean() <= MAX_OTHER_FACE
        both = hit & same
        np.testing.assert_allclose(b["tfar"][both], a["tfar"][both],
                                   rtol=warp_backend.HIT_RTOL)
        np.testing.assert_allclose(b["u"][both], a["u"][both], atol=BARY_ATOL)
        np.testing.assert_allclose(b["v"][both], a["v"][both], atol=BARY_ATOL)
        assert np.all(np.isinf(b["tfar"][~hit]))
        np.testing.assert_array_equal(wp.run(o, dirs, query="OCCLUDED"),
                                      pk.run(o, dirs, query="OCCLUDED"))


@pytest.mark.filterwarnings("ignore::meshladar.errors.BounceWarning")  # two glinting bodies
@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # coarse on purpose
@pytest.mark.parametrize("normals, rtol", [("flat", FLAT_RTOL), ("smooth", SMOOTH_RTOL)])
def test_sinograms_are_the_packet_backends(normals, rtol, monkeypatch):
    # flat normals: cast, weigh and bin in Warp's one kernel (only the bins come back);
    # smooth ones: Warp's hits through the compiled per-hit binning
    kernels = []
    spy = warp_backend.WarpScene.cast_bin
    monkeypatch.setattr(warp_backend.WarpScene, "cast_bin",
                        lambda self, *a: kernels.append(1) or spy(self, *a))
    parts = [ml.meshes.sphere((0.0, 0.0, 0.0), 0.4, 0, subdivisions=3),
             ml.meshes.sphere((0.9, 0.1, 0.0), 0.3, 1, subdivisions=2)]
    scene = ml.Scene.from_parts(parts, [ALUMINUM, DARK_GRAY])
    ladar = ml.Ladar.covering(scene, n_bins=48, view_vectors=ml.meshes.fibonacci_sphere(5))
    a = ml.simulate(scene, ladar, model="mesh", normals=normals, backend="packets")
    b = ml.simulate(scene, ladar, model="mesh", normals=normals, backend="warp-cpu")
    assert b.info["backend"] == "warp-cpu" and b.info["rays"] == a.info["rays"]
    assert len(kernels) == (5 if normals == "flat" else 0)
    np.testing.assert_allclose(b.values, a.values, rtol=0, atol=rtol * a.values.max())


@pytest.mark.parametrize("options", [
    {"back_faces": "ignore", "radiometry": "power"},
    {"sampling": "regular", "jobs": 2},
    {"mode": "slice", "z0": 505.0},
], ids=["ignore-power", "regular-2-jobs", "slice"])
def test_warps_kernel_bins_as_the_packets_far_from_the_origin(options):
    # a big sphere far off (a real unit-size rescaling), an open half-sphere's back faces,
    # a GGX coating (no compiled kernel): the bins of Warp's kernel against the packets'
    part = ml.meshes.sphere((1e3, -2e3, 5e2), 37.0, 0, subdivisions=4)
    keep = part.triangles.mean(axis=1)[:, 2] > 5e2 - 10.0    # open: back faces seen
    half = replace(part, faces=part.faces[keep], material=part.material[keep], name="cap")
    scene = ml.Scene.from_parts([half, ml.meshes.sphere((1e3 + 80, -2e3, 5e2), 20.0, 1,
                                                        subdivisions=3)],
                                [DARK_GRAY, ml.brdf.GGX(alpha=0.3)])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ml.errors.MeshladarWarning)    # far-off bins
        views = ({"angles_deg": [0.0, 70.0, 200.0]} if options.get("mode") == "slice"
                 else {"view_vectors": ml.meshes.fibonacci_sphere(4)})
        ladar = ml.Ladar.covering(scene, n_bins=40, **views)
        a = ml.simulate(scene, ladar, model="mesh", backend="packets", **options)
        b = ml.simulate(scene, ladar, model="mesh", backend="warp-cpu", **options)
    assert a.values.max() > 0 and b.info["rays"] == a.info["rays"]
    assert b.info["back_face_hits"] == a.info["back_face_hits"]
    np.testing.assert_allclose(b.values, a.values, rtol=0, atol=FLAT_RTOL * a.values.max())


def test_warp_without_a_cuda_device_is_refused_in_one_line():
    ok, why = warp_backend.available_cuda()
    if ok:                                     # a machine with a GPU: it loads
        assert backends.resolve_backend("auto") == "warp"
        return
    assert "warp-cpu" in why and "\n" not in why
    with pytest.raises(ParameterError, match=r"backend='warp' cannot load here .*warp-cpu"):
        backends.resolve_backend("warp")
    with warnings.catch_warnings():
        warnings.simplefilter("error")         # "auto" passes over it without a word
        assert backends.resolve_backend("auto") == "raster"


def test_without_warp_installed_both_say_how_to_install_it(monkeypatch):
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name == "warp" else real(name, *a))
    for check in (warp_backend.available_cpu, warp_backend.available_cuda):
        ok, why = check()
        assert not ok and "pip install 'meshladar[gpu]'" in why


def test_the_bench_gpu_line_times_warp_against_the_packets_on_the_same_rays(capsys):
    from meshladar.cli import main
    from meshladar.studies.bench_gpu import bench_gpu

    g = bench_gpu(repeats=1, subdivisions=3, rays_per_view=20_000, views=2)
    assert g["backend"] == ("warp" if warp_backend.available_cuda()[0] else "warp-cpu")
    assert g["rays"] > 2 * 15_000 and g["same_face"] > 1 - MAX_OTHER_FACE
    assert g["warp_mrays"] > 0 and g["packets_mrays"] > 0
    np.testing.assert_allclose(g["warp_over_packets"], g["warp_mrays"] / g["packets_mrays"])
    np.testing.assert_allclose(g["bins_warp_over_packets"],
                               g["warp_bins_mrays"] / g["packets_bins_mrays"])
    assert main(["bench", "--gpu", "--repeats", "1"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("first hits, 81920 triangles") and "Mrays/s" in out[0]
    assert out[1].startswith("  rays to bins (flat normals, 512 bins): warp")
