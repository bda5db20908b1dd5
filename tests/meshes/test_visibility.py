"""Which parts can see themselves (meshladar.meshes.visibility): exact where it says a part
cannot (a flat part, a closed convex body), conservative elsewhere."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import meshladar as ml
from meshladar.meshes import MeshPart
from meshladar.meshes.visibility import part_sees_itself

GRAY = ml.materials.DARK_GRAY


def _bowl():
    """An icosphere's faces above its equator: an open bowl."""
    s = trimesh.creation.icosphere(2)
    return trimesh.Trimesh(s.vertices, s.faces[s.triangles_center[:, 2] > 0])


def _part(mesh, name="m"):
    return MeshPart(np.asarray(mesh.vertices), np.asarray(mesh.faces), 0, name)


@pytest.mark.parametrize("make", [
    lambda: trimesh.creation.box((1.0, 2.0, 3.0)),
    lambda: trimesh.creation.icosphere(3),
    lambda: trimesh.creation.cylinder(0.5, 2.0, sections=64),
    lambda: trimesh.creation.cone(1.0, 2.0),
    lambda: trimesh.creation.capsule(1.0, 0.5),
])
def test_closed_convex_bodies_cannot_see_themselves(make):
    """Convex solids, also moved far off the origin in millimetres, and wound inward."""
    mesh = make()
    assert not part_sees_itself(_part(mesh))
    far = mesh.copy()
    far.apply_scale(1000.0)
    far.apply_translation([2.0e5, -3.0e5, 1.0e4])
    assert not part_sees_itself(_part(far))
    inward = mesh.copy()
    inward.invert()
    assert not part_sees_itself(_part(inward))


@pytest.mark.parametrize("make", [
    lambda: trimesh.creation.annulus(0.5, 1.0, 1.0),           # a hole: sees itself
    lambda: trimesh.creation.torus(1.0, 0.3),
    lambda: trimesh.util.concatenate([trimesh.creation.box(),   # two bodies in one part
                                      trimesh.creation.box().apply_translation([3, 0, 0])]),
    lambda: _bowl(),
])
def test_bodies_that_can_see_themselves_say_so(make):
    assert part_sees_itself(_part(make()))


def test_a_dented_box_sees_itself():
    """One vertex of a subdivided box pushed inward by 1e-3 of its size makes it concave."""
    box = trimesh.creation.box().subdivide()
    v = np.array(box.vertices)
    centre = np.argmin(np.linalg.norm(v - [0.5, 0.0, 0.0], axis=1))
    assert np.allclose(v[centre], [0.5, 0.0, 0.0])
    v[centre, 0] -= 1e-3
    assert part_sees_itself(MeshPart(v, box.faces, 0, "dented"))


def test_flat_parts_cannot_see_themselves():
    """A plate (open), a disk of triangles, each far from the origin."""
    plate = MeshPart(np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [0, 1, 0.0]]) + 1e4,
                     [[0, 1, 2], [0, 2, 3]], 0, "plate")
    assert not part_sees_itself(plate)
    fan = MeshPart([[np.cos(t), np.sin(t), 0.0] for t in np.linspace(0, 6, 7)]
                   + [[0.0, 0.0, 0.0]], [[7, i, i + 1] for i in range(6)], 0, "fan")
    assert not part_sees_itself(fan)


def test_scene_visibility():
    """A single convex body needs no bounce; two convex bodies see each other; analytic
    shapes are convex, and two of them see each other."""
    ball = ml.Scene.from_parts([ml.meshes.sphere((0, 0, 0), 1.0, 0)], [GRAY])
    vis = ball.visibility()
    assert vis.convex == (True,) and not vis.needs_bounces
    assert ball.visibility() is vis                          # computed once
    two = ml.Scene.from_parts([ml.meshes.sphere((0, 0, 0), 1.0, 0, name="a"),
                               ml.meshes.sphere((3, 0, 0), 1.0, 0, name="b")], [GRAY])
    assert two.visibility().convex == (True, True) and two.visibility().needs_bounces
    assert two.visibility().sees.tolist() == [[False, True], [True, False]]
    one = ml.Scene([ml.Disk((0, 0), 0.8, GRAY)])
    assert not one.visibility().needs_bounces
    pair = ml.Scene([ml.Disk((-0.4, 0), 0.3, GRAY), ml.Disk((0.4, 0), 0.3, GRAY)])
    assert pair.visibility().needs_bounces


def test_the_scene_counts_bodies_once():
    """The scene's report counts each part's bodies (the visibility test reads it instead
    of counting again): one for a box, two for two boxes in one part."""
    one = ml.Scene.from_mesh(trimesh.creation.box(), material=GRAY)
    two = ml.Scene.from_mesh(trimesh.util.concatenate(
        [trimesh.creation.box(), trimesh.creation.box().apply_translation([3, 0, 0])]),
        material=GRAY)
    assert one.report["bodies"] == [1] and two.report["bodies"] == [2]
    assert one.visibility().convex == (True,) and two.visibility().convex == (False,)


def test_coplanar_flat_parts_cannot_see_each_other():
    """Tiles of one floor (1e4 off the origin, tilted) exchange no light: a scene of them
    needs no bounce and is never sampled; lift one tile by 1e-3 and they can."""
    tilt = np.array([[1.0, 0.0, 0.0], [0.0, 0.8, 0.6], [0.0, -0.6, 0.8]])

    def tile(x0, z=0.0, name="t"):
        v = (np.array([[0, 0, z], [1, 0, z], [1, 1, z], [0, 1, z]]) + [x0, 0, 0]) @ tilt.T
        return MeshPart(v + 1e4, [[0, 1, 2], [0, 2, 3]], 0, name)
    floor = ml.Scene.from_parts([tile(0.0, name="a"), tile(1.5, name="b"),
                                 tile(3.0, name="c")], [GRAY])
    assert not floor.visibility().needs_bounces
    lad = ml.Ladar(None, view_vectors=[[0.3, 0.2, 1.0]], bin_edges=np.linspace(-2e4, 0, 5))
    sino = ml.simulate(floor, lad, model="mesh", radiometry="power", bounces=3)
    assert sino.info["order_totals"][1:] == [0.0, 0.0]
    step = ml.Scene.from_parts([tile(0.0, name="a"), tile(1.5, 1e-3, name="b")], [GRAY])
    assert step.visibility().sees.tolist() == [[False, True], [True, False]]
