"""Normals of a mesh: the unit normal at each face corner, averaged over the faces around
the corner's point within a crease angle (smooth where the surface is, sharp at creases).

Its compiled loop is :mod:`meshladar.meshes._normals_kernel` (numba), imported here: this
module is reached lazily through :mod:`meshladar.meshes`, so ``import meshladar`` stays light.
"""

from __future__ import annotations

import math

import numpy as np

from ._normals_kernel import accumulate_corner_normals
from .part import MeshPart, _point_index

__all__ = ["corner_normals", "CREASE_DEG"]

#: Vertex normals are averaged only over faces within this angle of each other, so the
#: edges of a prism or a box stay sharp ("smooth" normals that respect creases).
CREASE_DEG = 30.0


def corner_normals(part: MeshPart, *, crease_deg=CREASE_DEG):
    """(m, 3, 3) unit normal at each face corner: the area-weighted mean of the normals of
    the faces around that corner's point that lie within ``crease_deg`` of the face's own
    normal (so shared smooth edges blend and creases stay sharp).

    Faces meet at a point when their corners have the same position (exact float equality),
    whatever the vertex indices: a file's UV seams and split normals store one point as
    several vertices, and they are not creases.
    """
    fn, area = part.face_normals_areas()
    point_of, n_points = _point_index(part.vertices)
    f = np.ascontiguousarray(point_of[part.faces], dtype=np.int64)
    order = np.argsort(f.ravel(), kind="stable")
    point_at = f.ravel()[order]
    face_of = order // 3
    ptr = np.searchsorted(point_at, np.arange(n_points + 1))
    out = np.zeros((len(f), 3, 3))
    accumulate_corner_normals(f, fn, area, ptr, face_of, math.cos(math.radians(crease_deg)), out)
    return out
