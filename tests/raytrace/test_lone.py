"""Bistatic occlusion rays are not cast from the front of a part that sees no part (a flat
part, or a closed convex body, alone or among coplanar flat parts: scene.visibility()),
as none could be blocked. The fused loop's sinograms stay those of embreex's per-hit path,
which casts every occlusion ray, and those of the fused loop told no face is lone."""

import numpy as np
import pytest
import trimesh

import meshladar as ml
from meshladar.materials import ALUMINUM, DARK_GRAY
from meshladar.raytrace.embree import geometry

#: The fused loop against the per-hit path (their summation orders differ).
SAME_RTOL = 1e-12


def _plate(z=0.0, x0=-0.5):
    return ml.meshes.MeshPart(np.array([[x0, -0.5, z], [x0 + 1.0, -0.5, z],
                                        [x0 + 1.0, 0.5, z], [x0, 0.5, z]]),
                              np.array([[0, 1, 2], [0, 2, 3]]), 0, name="plate")


def _torus():
    t = trimesh.creation.torus(major_radius=0.5, minor_radius=0.2)
    return ml.meshes.MeshPart(np.asarray(t.vertices), np.asarray(t.faces), 0, name="torus")


@pytest.mark.parametrize("parts, lone", [
    ([ml.meshes.sphere((0.1, -0.2, 0.3), 0.5, 0, subdivisions=3)], 1),   # convex, alone
    ([_plate(), _plate(x0=0.5)], 1),                                      # coplanar tiles
    ([_torus()], 0),                                                      # sees itself
    ([ml.meshes.sphere((0, 0, 0), 0.3, 0, subdivisions=2), _plate(-0.5)], 0),  # two bodies
])
def test_lone_faces_are_those_of_parts_that_see_nothing(parts, lone):
    scene = ml.Scene.from_parts(parts, [DARK_GRAY])
    geo = geometry(scene, "flat")
    assert geo.lone is None                         # made for bistatic runs only
    geo.for_receivers(scene, None)
    assert geo.lone is None                         # monostatic: not needed
    geo.for_receivers(scene, np.array([[0.0, 1.0, 0.0]]))
    assert geo.lone.dtype == np.uint8 and geo.lone.shape == (len(geo.faces),)
    assert np.all(geo.lone == lone)


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # faceted on purpose
@pytest.mark.filterwarnings("ignore::meshladar.errors.BounceWarning")  # the torus: one bounce
@pytest.mark.parametrize("parts", [
    [ml.meshes.sphere((0.1, -0.2, 0.3), 0.5, 0, subdivisions=4)],
    [_plate(), _plate(x0=0.5)],
    [_torus()],
], ids=["sphere", "tiles", "torus"])
def test_a_lone_parts_bistatic_sinogram_is_the_per_hit_paths(parts, monkeypatch):
    from meshladar.raytrace.embree import Geometry

    scene = ml.Scene.from_parts(parts, [ALUMINUM])
    views = ml.meshes.fibonacci_sphere(5)
    ladar = ml.Ladar.covering(scene, n_bins=48, view_vectors=views)
    for receiver, radiometry in (((0.3, 0.5, 0.81), "power"), ((-0.2, 0.9, 0.1), "paper")):
        options = dict(model="mesh", receiver=receiver, radiometry=radiometry,
                       rays_per_bin=3)
        ref = ml.simulate(scene, ladar, backend="embreex", **options)
        fused = ml.simulate(scene, ladar, backend="packets", **options)
        assert fused.values.max() > 0
        np.testing.assert_allclose(fused.values, ref.values, rtol=SAME_RTOL,
                                   atol=SAME_RTOL * ref.values.max())
        assert fused.info["back_face_hits"] == ref.info["back_face_hits"]
        with monkeypatch.context() as m:                 # every occlusion ray cast
            m.setattr(Geometry, "for_receivers", lambda self, scene, r: setattr(
                self, "lone", np.zeros(len(self.faces), np.uint8)))
            scene_again = ml.Scene.from_parts(parts, [ALUMINUM])
            every = ml.simulate(scene_again, ladar, backend="packets", **options)
        np.testing.assert_array_equal(every.values, fused.values)
