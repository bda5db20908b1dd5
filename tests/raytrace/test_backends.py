"""The backend registry (meshladar.raytrace.backends): a registered backend is chosen by
name and casts every ray of a run, with no edit anywhere else (the place a GPU backend
plugs in)."""

from __future__ import annotations

import numpy as np
import pytest

import meshladar as ml
from meshladar.errors import ParameterError
from meshladar.raytrace import backends

trimesh = pytest.importorskip("trimesh")


def test_a_registered_backend_is_chosen_by_name_and_gives_the_references_numbers(
        monkeypatch):
    # a stand-in backend that counts the rays it casts through embreex's scenes
    reference = backends.backend("embreex")
    cast = []

    class Counting:
        def __init__(self, raw):
            self.raw = raw

        def run(self, origins, directions, **kwargs):
            cast.append(len(origins))
            return self.raw.run(origins, directions, **kwargs)

    # weighed as the reference's runs are (a small one in numpy: its quick_start)
    monkeypatch.setitem(backends.REGISTRY, "counting", backends.Backend(
        "counting", lambda v, f: Counting(reference.build(v, f)), lambda: (True, "test"),
        quick_start=reference.quick_start))
    assert backends.choices() == ("auto", "packets", "raster", "embreex", "warp", "warp-cpu",
                                 "counting")
    scene = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=2),
                               material=ml.materials.DARK_GRAY)
    ladar = ml.Ladar.covering(scene, n_bins=16, angles_deg=[0.0, 90.0])
    got = ml.simulate(scene, ladar, model="mesh", backend="counting")
    want = ml.simulate(scene, ladar, model="mesh", backend="embreex")
    assert got.info["backend"] == "counting" and sum(cast) == got.info["rays"] > 0
    np.testing.assert_array_equal(got.values, want.values)


def test_an_unregistered_backend_names_the_registered_ones():
    with pytest.raises(ParameterError, match=r"backend must be one of \('auto', 'packets', "
                                             r"'raster', 'embreex', 'warp', 'warp-cpu'\); "
                                             r"got 'optix'"):
        backends.resolve_backend("optix")
