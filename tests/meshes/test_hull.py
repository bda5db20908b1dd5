"""convex_hull leaves the caller's points as they were: its read-only answer is a new
array, never the caller's own array made read-only in place."""

from __future__ import annotations

import numpy as np
import pytest

from meshladar.meshes import convex_hull


@pytest.mark.parametrize("points", [
    np.random.default_rng(0).normal(size=(10, 3)),                 # 64 or fewer: all kept
    np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]] * 20),
    np.random.default_rng(1).normal(size=(200, 3)),                 # Qhull drops some
], ids=["few", "flat-sheet", "many"])
def test_the_hull_leaves_the_callers_array_writeable_and_unchanged(points):
    before = points.copy()
    hull = convex_hull(points)
    assert points.flags.writeable                     # the caller's flags are untouched
    assert not np.shares_memory(hull, points)
    assert not hull.flags.writeable and hull.flags.c_contiguous
    np.testing.assert_array_equal(points, before)
    points[0, 0] += 1.0                               # still the caller's to change
    assert hull.dtype == points.dtype
    assert {tuple(p) for p in hull} <= {tuple(p) for p in before}     # the same points
    if len(before) <= 64 or np.ptp(before[:, 2]) == 0:                 # nothing dropped
        np.testing.assert_array_equal(hull, before)


@pytest.mark.filterwarnings("ignore:the target is far from the origin")
def test_a_few_views_build_no_hull_and_range_as_the_hull_does(monkeypatch):
    """Ranges and ray grids of fewer than HULL_MIN_VIEWS views are taken over every vertex
    (no hull is built: convex_hull is made to fail), and a run over them gives bit for
    bit what the same run over the hull's vertices gives: a torus (not convex: its hull
    holds about half its vertices) far from the origin, 5 views."""
    import trimesh

    import meshladar as ml
    from meshladar import scene as scene_module
    from meshladar.materials import DARK_GRAY

    tor = trimesh.creation.torus(1.0, 0.3, major_sections=48, minor_sections=24)
    part = ml.meshes.MeshPart(tor.vertices + [40.3, -2.2, 0.7], tor.faces,
                              np.zeros(len(tor.faces), np.int32), "torus")
    views = ml.meshes.fibonacci_sphere(5)
    hulled = ml.Scene.from_parts([part], [DARK_GRAY])
    assert len(hulled.hull_points()) < len(part.vertices)          # a proper subset
    assert len(hulled.support_points(5)) == len(hulled.hull_points())   # known: used
    results = []
    for scene in (hulled, ml.Scene.from_parts([part], [DARK_GRAY])):
        with monkeypatch.context() as m:
            if scene is not hulled:
                m.setattr(scene_module, "convex_hull", _no_hull)
            assert len(scene.support_points(len(views))) == (
                len(hulled.hull_points()) if scene is hulled else len(part.vertices))
            lad = ml.Ladar.covering(scene, n_bins=64, view_vectors=views)
            results.append((lad.bin_edges, ml.simulate(scene, lad, model="mesh", seed=3)))
    np.testing.assert_array_equal(results[0][0], results[1][0])
    np.testing.assert_array_equal(results[0][1].values, results[1][1].values)
    assert len(ml.Scene.from_parts([part], [DARK_GRAY]).support_points(
        scene_module.HULL_MIN_VIEWS)) == len(hulled.hull_points())       # many views: hull


def _no_hull(v):
    raise AssertionError("a hull was built for a few views")
