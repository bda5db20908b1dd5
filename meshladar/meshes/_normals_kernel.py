"""The compiled twin of :mod:`meshladar.meshes.normals` (numba): the corner-normal
accumulation loop, moved here from the dissolved ``_kernels.py`` (its
``corner_normals``). Tested against a numpy
evaluation of the same sums in tests/meshes/test_normals_kernel.py.
"""

from __future__ import annotations

import math

from numba import njit

__all__ = ["accumulate_corner_normals"]


@njit(cache=True)
def accumulate_corner_normals(faces, face_normals, face_areas, ptr, face_of, cos_crease, out):
    """out[f, c] = normalised Σ area_g n_g over faces g around vertex faces[f, c] with
    n_g · n_f ≥ cos_crease (always including f itself)."""
    m = faces.shape[0]
    for f in range(m):
        for c in range(3):
            vtx = faces[f, c]
            sx = 0.0
            sy = 0.0
            sz = 0.0
            for k in range(ptr[vtx], ptr[vtx + 1]):
                g = face_of[k]
                d = (face_normals[g, 0] * face_normals[f, 0] + face_normals[g, 1]
                     * face_normals[f, 1] + face_normals[g, 2] * face_normals[f, 2])
                if d >= cos_crease or g == f:
                    sx += face_areas[g] * face_normals[g, 0]
                    sy += face_areas[g] * face_normals[g, 1]
                    sz += face_areas[g] * face_normals[g, 2]
            nn = math.sqrt(sx * sx + sy * sy + sz * sz)
            if nn > 0.0:
                out[f, c, 0] = sx / nn
                out[f, c, 1] = sy / nn
                out[f, c, 2] = sz / nn
            else:
                out[f, c, 0] = face_normals[f, 0]
                out[f, c, 1] = face_normals[f, 1]
                out[f, c, 2] = face_normals[f, 2]


