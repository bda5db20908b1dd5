"""Per-face footprints of a view (meshladar.weighing.faces.face_footprints, one compiled
pass) against the numpy expressions they replace, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

import meshladar as ml
from meshladar.materials import DARK_GRAY
from meshladar.precision import TINY
from meshladar.raytrace.embree import Geometry
from meshladar.raytrace.grid import frame
from meshladar.weighing.faces import face_footprints


def _numpy_footprints(geo, w, mode, spacing):
    """The footprint rows as numpy computed them before (its float64 expressions)."""
    u, v = frame(w)
    n = geo.face_normals

    def dot(a, d):
        return a[:, 0] * d[0] + a[:, 1] * d[1] + a[:, 2] * d[2]

    out = np.empty((len(n), 4))
    cg = np.maximum(np.abs(dot(n, w)), TINY)
    out[:, 0] = np.abs(dot(n, u)) / cg * 0.5 * spacing
    out[:, 1] = np.abs(dot(n, v)) / cg * 0.5 * spacing if mode == "3d" else 0.0
    r = -dot(geo.shifted, w)
    corners = r[geo.faces]
    out[:, 2] = corners.min(axis=1)
    out[:, 3] = corners.max(axis=1)
    return out


@pytest.mark.parametrize("mode", ["3d", "slice"])
def test_footprints_equal_the_numpy_expressions_bit_for_bit(mode):
    """A torus (faces seen edge-on and from behind, off-centre) from 8 seeded directions,
    the axes among them (|n·w| = 0 on some faces: the TINY floor)."""
    import trimesh

    tor = trimesh.creation.torus(1.0, 0.3, major_sections=40, minor_sections=20)
    part = ml.meshes.MeshPart(tor.vertices + [0.3, -0.2, 0.1], tor.faces,
                              np.zeros(len(tor.faces), np.int32), "torus")
    geo = Geometry(ml.Scene.from_parts([part], [DARK_GRAY]), "flat")
    rng = np.random.default_rng(5)
    views = np.vstack([rng.normal(size=(6, 3)), [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]])
    for w in views / np.linalg.norm(views, axis=1)[:, None]:
        got = np.full((len(geo.faces), 4), np.nan)
        face_footprints(geo, w, mode, 0.0123, got)
        np.testing.assert_array_equal(got, _numpy_footprints(geo, w, mode, 0.0123))
