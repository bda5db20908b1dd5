"""Scenes, shapes, the ladar and the sinogram: validation and derived values."""

from __future__ import annotations

import math

import numpy as np
import pytest

import meshladar as ml
from meshladar.errors import GeometryError, ParameterError
from meshladar.materials import ALUMINUM, DARK_GRAY

M = DARK_GRAY


def test_shapes_are_frozen_values():
    d = ml.Disk((0.1, 0.2), 0.5, M)
    assert d.axes == (0.5, 0.5) and d.is_circle and d.angle == 0.0
    e = ml.Ellipse(center=(0, 0), semi_axes=(0.6, 0.3), angle_deg=90.0, material=ALUMINUM)
    assert e.angle == pytest.approx(math.pi / 2)
    with pytest.raises(AttributeError):
        d.radius = 1.0
    # boundary points satisfy the implicit equation
    t = np.linspace(0, 2 * math.pi, 17)
    np.testing.assert_allclose(e.implicit(e.boundary(t)), 1.0, rtol=1e-14)
    # Ramanujan's approximation is ~1e-9 accurate at this aspect ratio; a disk's is exact
    a, b = 0.6, 0.3
    h = ((a - b) / (a + b)) ** 2
    ramanujan = math.pi * (a + b) * (1 + 3 * h / (10 + math.sqrt(4 - 3 * h)))
    assert e.perimeter() == pytest.approx(ramanujan, rel=1e-8)
    assert d.perimeter() == pytest.approx(math.pi, rel=1e-15)


@pytest.mark.parametrize("make, match", [
    (lambda: ml.Disk((0, 0), 0.0, M), r"radius must be in \(0, inf\); got 0.0"),
    (lambda: ml.Disk((0, 0), -1.0, M), r"radius must be in \(0, inf\); got -1.0"),
    (lambda: ml.Disk((0, 0), float("nan"), M), r"radius must be finite"),
    (lambda: ml.Disk((0, 0, 0), 1.0, M), r"center must be a point \(x, y\); got shape \(3,\)"),
    (lambda: ml.Disk((0, float("inf")), 1.0, M), r"center must be finite"),
    (lambda: ml.Disk((0, 0), 1.0, "aluminum"), r"material must be a meshladar.brdf.BRDF .*"
     r"got str 'aluminum': a coating by name is meshladar.materials.PAPER\[name\] "
     r"\(list\(meshladar.materials.PAPER\) names the packaged ones\)"),
    (lambda: ml.Ellipse((0, 0), (0.6, 0.0), 0.0, M), r"semi_axes must be two positive"),
    (lambda: ml.Ellipse((0, 0), (0.6, 0.3), float("nan"), M), r"angle_deg must be finite"),
])
def test_bad_shapes(make, match):
    with pytest.raises(ParameterError, match=match):
        make()


def test_scene_validation():
    with pytest.raises(ParameterError, match="at least one shape; got an empty scene"):
        ml.Scene([])
    with pytest.raises(ParameterError, match=r"shapes\[1\] must be a Disk or an Ellipse"):
        ml.Scene([ml.Disk((0, 0), 1.0, M), "disk"])
    with pytest.raises(GeometryError, match=r"shapes\[0\] and shapes\[1\] overlap"):
        ml.Scene([ml.Disk((0, 0), 0.5, M), ml.Disk((0.9, 0), 0.5, M)])
    with pytest.raises(GeometryError, match="overlap"):              # one inside the other
        ml.Scene([ml.Disk((0, 0), 0.5, M), ml.Ellipse((0.1, 0), (0.2, 0.1), 10.0, M)])
    with pytest.raises(GeometryError, match="overlap"):              # ellipses crossing
        ml.Scene([ml.Ellipse((0, 0), (0.6, 0.1), 0.0, M), ml.Ellipse((0, 0), (0.6, 0.1), 90.0, M)])
    # touching is allowed: the paper's pair, an ellipse tangent to a disk
    ml.Scene([ml.Disk((-0.3, 0), 0.4, M), ml.Disk((0.4, 0), 0.3, M)])
    ml.Scene([ml.Ellipse((0, 0), (0.6, 0.3), 0.0, M), ml.Disk((0.0, 0.5), 0.2, M)])
    ml.Scene([ml.Ellipse((0, 0), (0.6, 0.3), 0.0, M), ml.Ellipse((1.2, 0), (0.6, 0.3), 0.0, M)])
    # an error is also a ValueError
    with pytest.raises(ValueError):
        ml.Scene([ml.Disk((0, 0), 0.5, M), ml.Disk((0.5, 0), 0.5, M)])


def test_bounding_circle_contains_all():
    scene = ml.Scene([ml.Disk((-0.3, 0), 0.4, M), ml.Ellipse((0.5, 0.5), (0.3, 0.1), 45.0, M)])
    (cx, cy), r = scene.bounding_circle()
    for s in scene:
        pts = s.boundary(np.linspace(0, 2 * math.pi, 200))
        assert np.all(np.hypot(pts[:, 0] - cx, pts[:, 1] - cy) <= r * (1 + 1e-12))


def test_ladar_constructors():
    lad = ml.Ladar.paper()
    assert lad.n_views == 360 and lad.n_bins == 512
    np.testing.assert_allclose(np.diff(lad.bin_edges), 0.8 / 256, rtol=1e-12)
    assert lad.bin_edges[0] == pytest.approx(-0.8) and lad.bin_edges[-1] == pytest.approx(0.8)
    np.testing.assert_array_equal(lad.angles_deg, np.arange(360.0))
    c = ml.Ladar.centered(5, 0.5, center=1.0, angles_deg=[0.0])
    np.testing.assert_allclose(c.bin_edges, [-0.25, 0.25, 0.75, 1.25, 1.75, 2.25])
    np.testing.assert_allclose(c.bin_centers, [0.0, 0.5, 1.0, 1.5, 2.0])
    np.testing.assert_allclose(ml.Ladar([90.0], [0, 1]).view_vectors, [[0, 1, 0]], atol=1e-16)
    scene = ml.Scene([ml.Disk((0.3, 0.4), 0.5, M)])
    cov = ml.Ladar.covering(scene, bin_width=0.1)
    assert cov.bin_edges[0] <= -1.0 and cov.bin_edges[-1] >= 1.0
    assert ml.Ladar.covering(scene, n_bins=10).n_bins == 10
    with pytest.raises(ParameterError, match="give bin_width or n_bins"):
        ml.Ladar.covering(scene)


@pytest.mark.parametrize("args, match", [
    (([], [0, 1]), r"angles_deg must be a non-empty 1-D array"),
    (([0.0], [0.0]), r"bin_edges must be a 1-D array of at least 2 edges"),
    (([0.0], [0.0, 1.0, 1.0]), r"bin_edges must be strictly increasing; got 1.0 then 1.0 at "
                               r"index 1"),
    (([0.0], [1.0, 0.0]), r"strictly increasing"),
    (([0.0], [0.0, float("nan")]), r"bin_edges must be finite; got nan at index \(1,\)"),
    (([float("inf")], [0.0, 1.0]), r"angles_deg must be finite"),
])
def test_bad_ladar(args, match):
    with pytest.raises(ParameterError, match=match):
        ml.Ladar(*args)


def test_bad_ladar_helpers():
    with pytest.raises(ParameterError, match=r"n_bins must be an integer >= 1; got 0"):
        ml.Ladar.centered(0, 0.1)
    with pytest.raises(ParameterError, match=r"bin_width must be in \[1e-200, 5e\+29\]; got -0.1"):
        ml.Ladar.centered(4, -0.1)


def test_sinogram_contract():
    v = np.arange(6.0).reshape(2, 3)
    s = ml.Sinogram(v, angles_deg=[0.0, 90.0], bin_edges=[0.0, 1.0, 2.0, 4.0])
    assert s.shape == (2, 3) and s.model == "measured"
    assert s.values.dtype == np.float64 and not s.values.flags.writeable
    v[0, 0] = 99.0                                        # the sinogram keeps its own copy
    assert s.values[0, 0] == 0.0
    np.testing.assert_array_equal(s.bin_widths, [1.0, 1.0, 2.0])
    np.testing.assert_array_equal(s.total(), [3.0, 12.0])
    with pytest.raises(ValueError):
        s.values[0, 0] = 1.0
    with pytest.raises(ParameterError, match=r"angles_deg must have one angle per view"):
        ml.Sinogram(v, angles_deg=[0.0], bin_edges=[0.0, 1.0, 2.0, 4.0])
    with pytest.raises(ParameterError, match=r"bin_edges must have n_bins \+ 1 = 4 entries"):
        ml.Sinogram(v, angles_deg=[0.0, 1.0], bin_edges=[0.0, 1.0])
    with pytest.raises(ParameterError, match=r"values must be finite; got nan"):
        ml.Sinogram([[np.nan]], angles_deg=[0.0], bin_edges=[0.0, 1.0])
    with pytest.raises(ParameterError, match=r"values must be a 2-D array"):
        ml.Sinogram([1.0], angles_deg=[0.0], bin_edges=[0.0, 1.0])


def test_simulate_validation():
    scene = ml.Scene([ml.Disk((0, 0), 0.5, M)])
    lad = ml.Ladar([0.0], [-1.0, 1.0])
    with pytest.raises(ParameterError, match=r"model must be one of \('analytic', 'mesh', "
                                             r"'pixel'\); got 'mesh2'"):
        ml.simulate(scene, lad, model="mesh2")
    with pytest.raises(ParameterError, match=r"model 'analytic' takes options "
                                             r"\('radiometry', 'jobs', 'executor', 'progress', "
                                             r"'run_dir'\); "
                                             r"got 'pixel_size'"):
        ml.simulate(scene, lad, pixel_size=0.1)
    with pytest.raises(ParameterError, match=r"scene must be a meshladar.Scene; got list"):
        ml.simulate([scene], lad)
    with pytest.raises(ParameterError, match=r"ladar must be a meshladar.Ladar; got dict"):
        ml.simulate(scene, {})
    out = ml.simulate(scene, lad)
    assert out.model == "analytic" and out.shape == (1, 1)


def test_the_convex_hull_is_cached_by_mesh_content():
    from scipy.spatial import ConvexHull

    sphere = ml.meshes.sphere((0.0, 0.0, 0.0), 0.5, 0, subdivisions=3)
    a = ml.Scene.from_parts([sphere], [M])
    b = ml.Scene.from_parts([sphere], [M])             # a new Scene of the same mesh
    assert b.hull_points() is a.hull_points()          # computed once, shared
    v = sphere.vertices
    np.testing.assert_array_equal(np.sort(a.hull_points(), axis=0),
                                  np.sort(v[ConvexHull(v).vertices], axis=0))
    moved = ml.meshes.sphere((1.0, 0.0, 0.0), 0.5, 0, subdivisions=3)
    assert ml.Scene.from_parts([moved], [M]).hull_points() is not a.hull_points()


def test_a_large_meshs_hull_points_keep_every_extreme(monkeypatch):
    """Above the filter's threshold the points strictly inside the polytope of their
    extremes are dropped before Qhull (and beyond Qhull's limit the filtered points are
    the answer): either way every hull vertex is kept, so every extreme along any
    direction is the same number, and interior points are gone."""
    from scipy.spatial import ConvexHull

    from meshladar.meshes import hull as hull_module

    rng = np.random.default_rng(0)
    sphere = ml.meshes.sphere((0.2, -0.1, 0.3), 0.5, 0, subdivisions=4)
    inside = (0.2, -0.1, 0.3) + rng.normal(size=(20000, 3)) * 0.08      # well inside
    v = np.vstack([sphere.vertices, inside])
    truth = v[ConvexHull(v).vertices]
    dirs = ml.meshes.fibonacci_sphere(500)
    for qhull_max in (200_000, 1000):             # Qhull on the kept points; or not at all
        monkeypatch.setattr(hull_module, "_HULL_FILTER_ABOVE", 1000)
        monkeypatch.setattr(hull_module, "_QHULL_MAX", qhull_max)
        got = hull_module.convex_hull(v)
        np.testing.assert_array_equal((got @ dirs.T).max(axis=0), (truth @ dirs.T).max(axis=0))
        np.testing.assert_array_equal((got @ dirs.T).min(axis=0), (truth @ dirs.T).min(axis=0))
        assert len(got) < len(sphere.vertices) + 100                # the interior is dropped
        kept = {tuple(p) for p in got}
        assert all(tuple(p) in kept for p in truth)                  # every hull vertex


def test_what_the_engine_derives_from_a_scene_is_computed_once_per_key():
    """Scene.cached: one call of ``make`` per scene and key (the traced geometry of a
    normal mode, the curvature estimates); another scene of the same parts has its own."""
    sphere = ml.meshes.sphere((0.0, 0.0, 0.0), 0.5, 0, subdivisions=1)
    scene = ml.Scene.from_parts([sphere], [DARK_GRAY])
    calls = []

    def make():
        calls.append(1)
        return len(calls)

    assert scene.cached("k", make) == 1 and scene.cached("k", make) == 1
    assert scene.cached(("k", 2), make) == 2
    other = ml.Scene.from_parts([sphere], [ALUMINUM])
    assert other.cached("k", make) == 3 and len(calls) == 3
    from meshladar.raytrace.embree import geometry
    assert geometry(scene, "flat") is geometry(scene, "flat")
    assert geometry(scene, "flat") is not geometry(other, "flat")
