"""Normals of a mesh: the unit normal at each face corner, averaged over the faces around
the corner's point within a crease angle (smooth where the surface is, sharp at creases).

Its compiled loop is ``meshladar.meshes._normals_kernel`` (numba), imported at its first
call: a run on flat normals loads neither.
"""

from __future__ import annotations

import math
import numpy as np

from .._lazy import deferred_module
from .part import MeshPart, _edges, _point_index

# compiled loops, imported (with numba) at their first use: a small run loads neither
_normals_kernel = deferred_module("meshladar.meshes._normals_kernel")

__all__ = ["corner_normals", "curved_edge_angles", "curved_edge_rates", "CREASE_DEG"]

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

    Parameters
    ----------
    part : MeshPart
        The mesh, of m faces.
    crease_deg : float, keyword-only, degrees, default CREASE_DEG (30.0)
        A neighbouring face g joins the mean at a corner of face f when n_g·n_f ≥
        cos(crease_deg); f itself always does. Not validated.

    Returns
    -------
    (m, 3, 3) ndarray of float64
        ``out[f, c]`` is the normal at corner c of face f (the corner at vertex
        ``part.faces[f, c]``). Where the weighted sum vanishes, the face's own normal is
        used (a zero vector for a zero-area face).
    """
    fn, area = part.face_normals_areas()
    point_of, n_points = _point_index(part.vertices)
    f = np.ascontiguousarray(point_of[part.faces], dtype=np.int64)
    order = np.argsort(f.ravel(), kind="stable")
    point_at = f.ravel()[order]
    face_of = order // 3
    ptr = np.searchsorted(point_at, np.arange(n_points + 1))
    out = np.zeros((len(f), 3, 3))
    _normals_kernel.accumulate_corner_normals(f, fn, area, ptr, face_of,
                                              math.cos(math.radians(crease_deg)), out)
    return out


def curved_edge_angles(part: MeshPart, *, crease_deg=CREASE_DEG):
    """((k,) angles in radians, (k,) material indices) between the normals of the two faces
    at each of the part's curved edges: edges shared by two faces of one material (by
    position, as :func:`corner_normals` joins them) that meet at more than 0 and less than
    ``crease_deg`` (an edge inside a flat face's triangulation is not curved, a crease is
    not either).

    An edge is two positions (exact float equality, as in :func:`corner_normals`); an edge
    met by more than two faces gives one entry per consecutive pair of them in sorted
    order. "More than 0" is an angle above 1e-9 rad.

    Parameters
    ----------
    part : MeshPart
        The mesh.
    crease_deg : float, keyword-only, degrees, default CREASE_DEG (30.0)
        Edges whose faces' normals are this far apart or more are creases, not curved. Not
        validated.

    Returns
    -------
    angles : (k,) ndarray of float64
        The angle between the two faces' unit normals at each curved edge, in radians.
    materials : (k,) ndarray of int64
        The material index of the two faces at each curved edge.
    """
    angles, _, materials = curved_edge_rates(part, crease_deg=crease_deg)
    return angles, materials


def curved_edge_rates(part: MeshPart, *, crease_deg=CREASE_DEG):
    """((k,) angles, (k,) rates, (k,) material indices) at each of the part's curved edges
    (:func:`curved_edge_angles`): the angle between the two faces' normals and the rate
    at which the flat normal turns across the edge, that angle over the distance between
    the faces' centroids measured across the edge (perpendicular to it: along n_a × n_b).

    Parameters
    ----------
    part : MeshPart
        The mesh.
    crease_deg : float, keyword-only, degrees, default CREASE_DEG (30.0)
        As :func:`curved_edge_angles`.

    Returns
    -------
    angles : (k,) ndarray of float64
        Radians, as :func:`curved_edge_angles`.
    rates : (k,) ndarray of float64
        Radians per scene unit.
    materials : (k,) ndarray of int64
        The material index of the two faces at each curved edge.
    """
    fn, _ = part.face_normals_areas()
    point, count = _point_index(part.vertices)
    f = point[part.faces]
    key = _edges(f, count)[3]                                   # edges by position
    order = np.argsort(key, kind="stable")
    key, face = key[order], np.tile(np.arange(len(f)), 3)[order]
    pair = np.flatnonzero(key[1:] == key[:-1])                       # an edge's two faces
    a, b = face[pair], face[pair + 1]
    mats = np.broadcast_to(np.asarray(part.material), (len(f),))
    angle = np.arccos(np.clip(np.einsum("ij,ij->i", fn[a], fn[b]), -1.0, 1.0))
    curved = (angle > 1e-9) & (angle < math.radians(crease_deg)) & (mats[a] == mats[b])
    a, b, angle = a[curved], b[curved], angle[curved]
    centre = part.vertices[part.faces].mean(axis=1)
    d = centre[b] - centre[a]
    edge = np.cross(fn[a], fn[b])                  # along the shared edge (|·| = sin angle)
    size = np.linalg.norm(edge, axis=1, keepdims=True)
    edge = np.divide(edge, size, out=np.zeros_like(edge), where=size > 0)  # 0: d as it is
    d -= np.einsum("ij,ij->i", d, edge)[:, None] * edge
    across = np.linalg.norm(d, axis=1)
    rates = angle / np.maximum(across, np.finfo(float).tiny)
    return angle, rates, np.asarray(mats[a], dtype=np.int64)
