"""Ray grids (meshladar.raytrace.grid): the view's frame against numpy's cross products (one
view and many), the stratified offsets' 1-D form against their definition, and many
views' shifts against numpy's own generators."""

from __future__ import annotations

import numpy as np
import pytest

from meshladar.precision import PARALLEL_SLACK
from meshladar.raytrace.draws import entropy_words, view_uniforms
from meshladar.raytrace.grid import (stratified_sequences, frame, frames, stratified_offsets)


def _numpy_frame(w):
    z = np.array([0.0, 0.0, 1.0])
    u = np.cross(z, w)
    n = np.sqrt(np.add.reduce(u * u))          # the squares summed in order (not a BLAS dot)
    u = np.array([1.0, 0.0, 0.0]) if n < PARALLEL_SLACK else u / n
    return u, np.cross(w, u)


def test_the_frame_is_numpys_cross_products_bit_for_bit():
    """u = z × w / |z × w| and v = w × u as np.cross gives them, bit for bit (signed zeros
    too), on 20,000 seeded directions and the axes (±z: u = x)."""
    rng = np.random.default_rng(11)
    w = rng.normal(size=(20_000, 3))
    w /= np.linalg.norm(w, axis=1)[:, None]
    axes = [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0],
            [-0.0, 0.0, 1.0], [1e-17, 0.0, 1.0], [PARALLEL_SLACK, 0.0, 1.0],
            [0.0, -PARALLEL_SLACK * (1 - 2**-52), 1.0], [-0.0, -0.0, -1.0],
            [3.0, -4.0, 12.0], [1e-200, 1e-200, 1.0], [5e-324, 0.0, 1.0]]
    for d in np.vstack([w, axes]):
        for got, want in zip(frame(d), _numpy_frame(d)):
            np.testing.assert_array_equal(got, want)
            np.testing.assert_array_equal(np.signbit(got), np.signbit(want))
    u, v = frame(np.array([0.0, 0.0, 1.0]))
    np.testing.assert_array_equal(u, [1.0, 0.0, 0.0])
    many = np.vstack([w, axes])                  # and many views at once: the same bits
    u, v = frames(many)
    assert np.array_equal(frames([[0, 3, 4]])[0][0], frame(np.array([0, 3, 4]))[0])  # ints
    for d, a, b in zip(many, u, v):
        for got, want in zip((a, b), frame(d)):
            np.testing.assert_array_equal(got, want)
            np.testing.assert_array_equal(np.signbit(got), np.signbit(want))


@pytest.mark.parametrize("seed", [0, 7, 2**32 - 1, 2**32, 2**64 + 5, [3, 2**33], [[1, 2], 0]])
def test_many_views_draw_what_numpys_generators_draw(seed):
    """view_uniforms (the seed sequence and PCG64 written out) gives each view exactly
    ``default_rng([seed, i]).uniform(0, 1, n)`` for its column count n, then for its row
    count, bit for bit: seeds of one, two and three 32-bit words, lists and nested lists,
    view indices past 2³², empty draws."""
    views = np.array([0, 1, 2, 5, 2**32 - 1, 2**32, 2**40, 10**6], np.int64)
    ns, nt = np.array([3, 0, 40, 1, 7, 2, 5, 9]), np.array([2, 5, 0, 33, 1, 2, 3, 4])
    s_at, t_at = np.r_[0, np.cumsum(ns)], np.r_[0, np.cumsum(nt)]
    xi, eta = np.full(s_at[-1], np.nan), np.full(t_at[-1], np.nan)
    view_uniforms(entropy_words(seed), views, s_at, t_at, xi, eta)
    for j, i in enumerate(views):
        rng = np.random.default_rng([seed, int(i)])
        np.testing.assert_array_equal(xi[s_at[j]:s_at[j + 1]], rng.uniform(0, 1, ns[j]))
        np.testing.assert_array_equal(eta[t_at[j]:t_at[j + 1]], rng.uniform(0, 1, nt[j]))


def test_stratified_offsets_are_one_per_cell_from_row_and_column_sequences():
    """The offsets built from the four 1-D sequences lie in [−½, ½), and du_ij − ξ_i and
    dv_ij − η_j depend only on j and on i (mod 1): the Kronecker sequences along rows
    and columns, each shifted by one uniform."""
    rng = np.random.default_rng(3)
    seq = stratified_sequences(37, 53, rng)
    du, dv = stratified_offsets(seq)
    assert du.shape == dv.shape == (37, 53) and du.dtype == dv.dtype == np.float32
    assert du.min() >= -0.5 and du.max() < 0.5 and dv.min() >= -0.5 and dv.max() < 0.5
    xi, ku, kv, eta = seq
    np.testing.assert_allclose(np.mod(du - xi[:, None] + 0.5, 1.0),
                               np.broadcast_to(np.mod(ku + 0.5, 1.0), du.shape), atol=1e-6)
    np.testing.assert_allclose(np.mod(dv - eta[None, :] + 0.5, 1.0),
                               np.broadcast_to(np.mod(kv + 0.5, 1.0)[:, None], dv.shape),
                               atol=1e-6)


@pytest.mark.parametrize("compiled_from", [0, None])
def test_a_views_extent_over_clusters_is_every_points_extent(compiled_from, monkeypatch):
    """The least and greatest p·u found over clusters of the points equal numpy's over
    every point (the same products and sums: equal, not close), for a sphere's hull, an
    anisotropic cloud far from the origin, a flat disk, a line, repeated points and a box,
    along unit and non-unit directions and the axes; and so do the extents from an origin
    and in perspective from a pinhole (a sensor at a standoff). points_extent's compiled
    pass (every set, with COMPILED_FROM 0) and its numpy branch (these sets are below the
    default) alike; and many directions' extents in one pass (axes_extents), over the
    clusters or every point."""
    import trimesh

    from meshladar.meshes import fibonacci_sphere
    from meshladar.raytrace import _support
    from meshladar.raytrace._support import ClusteredPoints, axes_extents, points_extent
    from meshladar.raytrace.grid import dot

    if compiled_from is not None:
        monkeypatch.setattr(_support, "COMPILED_FROM", compiled_from)

    rng = np.random.default_rng(5)
    sets = [trimesh.creation.icosphere(5).vertices,
            rng.normal(size=(30_000, 3)) * [5.0, 1.0, 0.1] + [100.0, -3.0, 7.0],
            np.c_[rng.uniform(-1, 1, (8000, 2)), np.zeros(8000)],
            np.c_[np.linspace(0.0, 1.0, 5000), np.zeros(5000), np.zeros(5000)],
            np.repeat(rng.normal(size=(50, 3)), 100, axis=0),
            trimesh.creation.box((3.0, 1.0, 0.2)).vertices]
    dirs = np.vstack([fibonacci_sphere(400), np.eye(3), -np.eye(3),
                      rng.normal(size=(100, 3)) * 7.0])
    for points in sets:
        points = np.asarray(points, np.float64)
        clusters = ClusteredPoints(points)
        centre = points.mean(axis=0)
        reach = np.linalg.norm(points - centre, axis=1).max()
        # many directions in one compiled pass (a chunk of views planned together)
        want = np.array([(dot(points, u).min(), dot(points, u).max()) for u in dirs])
        np.testing.assert_array_equal(clusters.extents(dirs), want)
        np.testing.assert_array_equal(axes_extents(points, dirs), want)     # every point
        for u in dirs:
            x = dot(points, u)
            assert clusters.extent(u) == (x.min(), x.max())
            assert points_extent(points, u) == (x.min(), x.max())       # one pass, no clusters
            # from a pinhole three reaches away along w, in perspective onto a plane D
            # in front of it: (q·a)·D / (−q·w), q = p − pinhole
            w = u / np.linalg.norm(u)
            pinhole = centre + 3.0 * reach * w
            q = points - pinhole
            assert clusters.extent(w, pinhole) == (dot(q, w).min(), dot(q, w).max())
            assert points_extent(points, w, pinhole) == (dot(q, w).min(), dot(q, w).max())
            for a in frame(w):
                seen = dot(q, a) * 2.5 / -dot(q, w)
                assert clusters.seen_extent(a, w, 2.5, pinhole) == (seen.min(), seen.max())
                assert points_extent(points, a, pinhole, w, 2.5) == (seen.min(), seen.max())
        # pinholes just outside the points (strong perspective: depths vary most) and far
        # (nearly parallel: the clusters' bounds, sphere and cone, decide which are seen)
        for u in dirs[::7]:
            w = u / np.linalg.norm(u)
            for distance in (1.05, 60.0):
                pinhole = centre + distance * reach * w
                q = points - pinhole
                for a in frame(w):
                    seen = dot(q, a) * 7.0 / -dot(q, w)
                    assert clusters.seen_extent(a, w, 7.0, pinhole) == (seen.min(), seen.max())
        # and against plain Python floats, point by point (not numpy's expression, which
        # points_extent's numpy branch shares), along a few of the directions
        for u in dirs[::97]:
            w = u / np.linalg.norm(u)
            pinhole = centre + 3.0 * reach * w
            a = frame(w)[0]
            assert points_extent(points, u) == _python_extent(points, u)
            assert points_extent(points, w, pinhole) == _python_extent(points, w, pinhole)
            assert points_extent(points, a, pinhole, w, 2.5) == _python_extent(
                points, a, pinhole, w, 2.5)


def test_a_clusters_cone_bounds_every_point_of_it():
    """The cone bound a cluster is held to (its points' reach from the centroid and the
    widest angle of their directions from its axis) is at least every one of its points'
    (p − o)·a, for clouds a sphere's, a flat disk's, a line's and repeated points', along
    unit and non-unit directions, from the origin and from a far point."""
    import trimesh

    from meshladar.meshes import fibonacci_sphere
    from meshladar.raytrace._support import ClusteredPoints
    from meshladar.raytrace._support_kernels import cone_bound

    rng = np.random.default_rng(8)
    sets = [trimesh.creation.icosphere(4).vertices * 3.0 + [40.0, 0.0, -2.0],
            np.c_[rng.uniform(-1, 1, (3000, 2)), np.zeros(3000)],
            np.c_[np.linspace(0.0, 1.0, 500), np.zeros(500), np.zeros(500)],
            np.repeat(rng.normal(size=(20, 3)), 50, axis=0),
            trimesh.creation.capsule(height=8.0, radius=1.0, count=[40, 40]).vertices]
    dirs = np.vstack([fibonacci_sphere(300), rng.normal(size=(50, 3)) * 4.0])
    for points in sets:
        c = ClusteredPoints(np.asarray(points, np.float64))
        for o in (np.zeros(3), np.array([-7.0, 3.0, 11.0])):
            for a in dirs:
                oa = float((c.cones[0] - o) @ a)
                la = float(np.linalg.norm(a))
                for k in range(len(c.radii)):
                    q = c.points[c.starts[k]:c.starts[k + 1]] - o
                    assert cone_bound.py_func(c.cones, k, oa, a, la) >= (q @ a).max()


def _python_extent(points, u, origin=(0.0, 0.0, 0.0), w=None, scale=1.0):
    """(least, greatest) of q·u (or (q·u)·scale / (−q·w)), q = p − origin, one point at
    a time in Python floats (q·u summed q₀u₀ + q₁u₁ + q₂u₂, as the engine defines it)."""
    u0, u1, u2 = (float(x) for x in u)
    o0, o1, o2 = (float(x) for x in origin)
    values = []
    for p0, p1, p2 in points.tolist():
        q0, q1, q2 = (p0 - o0, p1 - o1, p2 - o2) if any(origin) else (p0, p1, p2)
        x = q0 * u0 + q1 * u1 + q2 * u2
        if w is not None:
            x = x * scale / -(q0 * float(w[0]) + q1 * float(w[1]) + q2 * float(w[2]))
        values.append(x)
    return min(values), max(values)


def test_a_geometry_takes_its_extents_over_clusters_only_for_many_views():
    """A run of few views projects every support point; from CLUSTER_MIN_VIEWS views the
    geometry builds the clusters once and keeps to them: the same extents either way."""
    import meshladar as ml
    from meshladar.raytrace.embree import CLUSTER_MIN_VIEWS, Geometry
    from meshladar.raytrace.grid import dot

    scene = ml.Scene.from_parts([ml.meshes.sphere((3.0, -1.0, 2.0), 0.5, 0, subdivisions=5)],
                                [ml.materials.DARK_GRAY])
    geo = Geometry(scene, "flat")
    u = np.array([0.48, -0.6, 0.64])
    v = frame(u)[0]
    pinhole = 4.0 * u

    def expect():
        q = geo.support - pinhole
        seen = dot(q, v) * 3.0 / -dot(q, u)
        return (dot(geo.support, u).min(), dot(geo.support, u).max()), \
            (seen.min(), seen.max())

    geo.for_views(scene, 1)
    assert (geo.extent(u), geo.seen_extent(v, u, 3.0, pinhole)) == expect()
    assert geo._clusters is None
    geo.for_views(scene, CLUSTER_MIN_VIEWS)
    assert (geo.extent(u), geo.seen_extent(v, u, 3.0, pinhole)) == expect()
    assert geo._clusters is not None
