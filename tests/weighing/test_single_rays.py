"""Grids sparser than their faces go through the packet backend's compiled loops ray by ray
(rtcIntersect1, meshladar.weighing.fused.queries): the numbers of the embreex backend,
which casts the same float32 rays one at a time and weighs them in numpy, for every kind
of view the loops serve (flat and smooth normals, footprint bins, a bistatic receiver, a
sensor at a standoff, a slice's row); dense grids still go in packets."""

from __future__ import annotations

import numpy as np
import pytest

import meshladar as ml
from meshladar.sensor import Sensor
from meshladar.materials import ALUMINUM
from meshladar.raytrace import embree4

pytestmark = pytest.mark.skipif(not embree4.available(),
                                reason="the packet backend does not load here")

#: The two backends agree to float64 round-off where they report the same face (ranges
#: and weights recomputed in float64 from the same float32 origin and face plane).
SAME_HITS_RTOL = 1e-12

KINDS = {
    "flat": {},
    "smooth": {"normals": "smooth"},
    "footprint": {"footprint": True},
    "bistatic": {"receiver": [0.6, 0.0, 0.8], "radiometry": "power"},
    "sensor": {"sensor": Sensor(standoff=40.0), "radiometry": "power"},
    "slice": {"mode": "slice"},      # rays a face: the square roots, 0.32 and 6.3
}


def _scene():
    return ml.Scene.from_parts([ml.meshes.sphere((0.1, -0.2, 0.3), 0.5, 0, subdivisions=4)],
                               [ALUMINUM])


def _spacing(scene, per_face):
    """The ray spacing that puts ``per_face`` rays on the face a ray hits."""
    area = scene.parts[0].face_normals_areas()[1]
    return (float(area @ area / area.sum()) / per_face) ** 0.5


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # sparse on purpose
@pytest.mark.parametrize("kind", list(KINDS))
def test_sparse_grids_are_cast_ray_by_ray_with_embreex_numbers(kind, monkeypatch):
    from meshladar.weighing import fused, sensor_view

    asked = []
    queries = fused.queries

    def spy(lib, coherent):
        asked.append(coherent)
        return queries(lib, coherent)

    monkeypatch.setattr(fused, "queries", spy)
    monkeypatch.setattr(sensor_view, "queries", spy)
    scene = _scene()
    views = ({"angles_deg": [0.0, 72.0, 144.0, 216.0, 288.0]} if kind == "slice" else
             {"view_vectors": ml.meshes.fibonacci_sphere(5)})     # a slice's: about z
    ladar = ml.Ladar.covering(scene, n_bins=48, **views)
    for per_face, single in ((0.1, True), (40.0, False)):
        spacing = _spacing(scene, per_face)
        asked.clear()
        got = ml.simulate(scene, ladar, model="mesh", ray_spacing=spacing, backend="packets",
                          **KINDS[kind])
        assert asked == [not single] * 5                    # each view's loop, as planned
        ref = ml.simulate(scene, ladar, model="mesh", ray_spacing=spacing, backend="embreex",
                          **KINDS[kind])
        assert got.info["rays"] == ref.info["rays"] > 0
        assert np.count_nonzero(ref.values) >= 5 * 4        # the sphere fills bins each view
        np.testing.assert_allclose(got.values, ref.values, rtol=SAME_HITS_RTOL,
                                   atol=SAME_HITS_RTOL * np.abs(ref.values).max())


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # sparse on purpose
@pytest.mark.parametrize("options", [{}, {"normals": "smooth"}, {"mode": "slice"},
                                     {"sensor": Sensor(standoff=None)}],
                         ids=["flat", "smooth", "slice", "sensor-at-infinity"])
def test_the_per_hit_path_casts_sparse_grids_ray_by_ray_with_embreex_hits(options,
                                                                          monkeypatch):
    """``trace`` (the hits, for any later weighing) on the packet backend casts a grid
    sparser than its faces one ray at a time (``cast_grid(single=True)``) and a dense one
    in tiles; either way its hits are embreex's: the same rays hit, their ranges and
    angles to round-off."""
    from meshladar.raytrace.embree4 import PacketGeometry

    asked = []
    cast = PacketGeometry.cast_grid

    def spy(self, *args, **kwargs):
        asked.append(kwargs.get("single", False))
        return cast(self, *args, **kwargs)

    monkeypatch.setattr(PacketGeometry, "cast_grid", spy)
    scene = _scene()
    views = ({"angles_deg": [0.0, 72.0, 144.0]} if options.get("mode") == "slice" else
             {"view_vectors": ml.meshes.fibonacci_sphere(3)})
    ladar = ml.Ladar.covering(scene, n_bins=48, **views)
    for per_face, single in ((0.1, True), (40.0, False)):
        spacing = _spacing(scene, per_face)
        asked.clear()
        got = ml.trace(scene, ladar, ray_spacing=spacing, backend="packets", jobs=1, **options)
        assert asked == [single] * 3
        ref = ml.trace(scene, ladar, ray_spacing=spacing, backend="embreex", jobs=1, **options)
        np.testing.assert_array_equal(got.rays, ref.rays)
        np.testing.assert_array_equal(got.view, ref.view)        # the same rays hit
        assert len(got.range) >= 3 * 10
        for name in ("range", "cos_theta", "sin_theta"):
            np.testing.assert_allclose(getattr(got, name), getattr(ref, name), rtol=0,
                                       atol=SAME_HITS_RTOL)
