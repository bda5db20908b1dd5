"""The corner-normal loop's compiled twin (meshladar.meshes._normals_kernel) against a numpy
evaluation of the same sums, and the mesh package's lazy face."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest

import meshladar as ml
from meshladar.meshes._normals_kernel import accumulate_corner_normals
from meshladar.meshes.normals import corner_normals
from meshladar.meshes.part import _point_index, axis_spans

#: the loop and the numpy sums add the same terms in a different order: a few ulps
ORDER_RTOL = 1e-13


def _numpy_corner_normals(part, crease_deg):
    fn, area = part.face_normals_areas()
    point, _ = _point_index(part.vertices)
    f = point[part.faces]
    cos_crease = math.cos(math.radians(crease_deg))
    out = np.empty((len(f), 3, 3))
    for face in range(len(f)):
        for c in range(3):
            around = np.flatnonzero((f == f[face, c]).any(axis=1))
            keep = around[(fn[around] @ fn[face] >= cos_crease) | (around == face)]
            s = (area[keep, None] * fn[keep]).sum(axis=0)
            out[face, c] = s / np.linalg.norm(s)
    return out


@pytest.mark.parametrize("crease_deg", [30.0, 100.0])
def test_the_compiled_loop_equals_numpy_sums_on_a_prism_with_creases(crease_deg):
    disk = ml.Disk((0.1, -0.2), 0.5, ml.materials.DARK_GRAY)
    part = ml.meshes.prism(disk, 16, 0.4, 0)          # sides 22.5° apart: no tie at 30°
    got = corner_normals(part, crease_deg=crease_deg)
    np.testing.assert_allclose(got, _numpy_corner_normals(part, crease_deg), rtol=ORDER_RTOL,
                               atol=ORDER_RTOL)
    # the side faces meet the caps at 90°: sharp at 30°, blended at 100°
    fn, _ = part.face_normals_areas()
    top = np.flatnonzero(fn[:, 2] > 0.99)
    sharp = np.allclose(got[top], [0.0, 0.0, 1.0])
    assert sharp == (crease_deg < 90.0)


def test_import_meshladar_meshes_stays_light_until_normals_are_asked_for():
    # numba comes with the compiled loop, at the first call that needs it
    code = ("import sys, meshladar.meshes as m; "
            "assert 'numba' not in sys.modules; "
            "m.corner_normals; assert 'numba' not in sys.modules; "
            "m.corner_normals(m.sphere((0, 0, 0), 1.0, 0, subdivisions=1)); "
            "assert 'numba' in sys.modules; "
            "from meshladar.meshes import CREASE_DEG; "
            "assert CREASE_DEG == 30.0")
    subprocess.run([sys.executable, "-c", code], check=True)


def test_point_index_and_axis_spans_against_numpy():
    # the column-by-column forms against numpy's row-wise ones: distinct positions by exact
    # equality (-0.0 is 0.0), numbered in lexicographic order; max − min per axis
    rng = np.random.default_rng(7)
    v = rng.integers(-2, 3, (2000, 3)).astype(float)
    v[::7] *= -0.0                                     # signed zeros among the integers
    point, n = _point_index(v)
    unique, inverse = np.unique(v + 0.0, axis=0, return_inverse=True)
    assert n == len(unique) == len(np.unique(point))
    np.testing.assert_array_equal(point, inverse.ravel())
    assert _point_index(v[:1])[1] == 1 and _point_index(v[:0])[1] == 0
    w = rng.normal(size=(1000, 3)) * [1.0, 1e-3, 1e6] + [5.0, -7.0, 1e9]
    np.testing.assert_array_equal(axis_spans(w), np.ptp(w, axis=0))
