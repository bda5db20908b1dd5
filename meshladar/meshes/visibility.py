"""Which parts of a scene can send light to which: whether a part can see itself (the
second-order term of a convex scene is exactly zero, so it is never sampled).

A part cannot see itself when it is **flat** (every vertex within :data:`CONVEX_RTOL` of
the diagonal from the plane of its largest face; open or closed, one- or two-sided) or
**a closed convex body**: one connected body, closed (each undirected edge met by exactly
two faces, once in each direction) and convex at every edge (the far vertex of each face
across an edge is not in front of the other face's plane, by more than the tolerance; a
body whose faces are all wound inward is convex when every such vertex is in front). A
closed, connected, embedded surface that is convex at every edge bounds a convex solid,
so no segment between two of its points leaves it: no light goes from it to itself. Any
other part (an open curved shell, a body with a dent, several bodies in one part) is taken
to see itself: the test is exact where it says "cannot", conservative where it says
"can". Two different parts are taken to see each other (two convex bodies side by side
do), except two flat parts in one plane (tiles of a floor, panels of one face), which
cannot: no segment between them leaves the plane.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .checks import components
from .part import MeshPart, _edges, axis_spans

__all__ = ["CONVEX_RTOL", "Visibility", "part_plane", "part_sees_itself", "scene_visibility"]

#: A vertex within this fraction of its part's bounding-box diagonal of a face's plane is
#: on the plane (flat parts, convex edges): the rounding of coordinates written to files.
CONVEX_RTOL = 1e-9


@dataclass(frozen=True)
class Visibility:
    """Which parts can send light to which (module docstring).

    Attributes
    ----------
    names : tuple of str
        The parts' (or shapes') names, in scene order.
    sees : (n, n) numpy.ndarray of bool
        ``sees[i, j]``: light can go from part i to part j (symmetric; False exactly for
        coplanar flat parts and parts without faces, True, conservatively, for any other
        two); the diagonal says whether a part can see itself.
    """

    names: tuple
    sees: np.ndarray

    @property
    def convex(self) -> tuple:
        """Per part, whether it cannot see itself."""
        return tuple(not bool(s) for s in np.diag(self.sees))

    @property
    def needs_bounces(self) -> bool:
        """Whether any light can leave a surface for another (or itself): False for a
        convex scene, whose returns are exactly single-bounce."""
        return bool(self.sees.any())


def part_plane(part: MeshPart):
    """The plane of a flat part (every vertex within CONVEX_RTOL of its diagonal from the
    plane of its largest face), or None.

    Parameters
    ----------
    part : MeshPart
        A cleaned part with at least one face.

    Returns
    -------
    tuple of numpy.ndarray or None
        (unit normal (3,), a point on the plane (3,)), the largest face's; None when the
        part is not flat.
    """
    f, v = part.faces, part.vertices
    tol = CONVEX_RTOL * float(np.linalg.norm(axis_spans(v)))
    normals, areas = part.face_normals_areas()
    big = int(np.argmax(areas))
    point = v[f[big, 0]]
    if np.all(np.abs((v - point) @ normals[big]) <= tol):
        return normals[big], point
    return None


def part_sees_itself(part: MeshPart, bodies=None) -> bool:
    """Whether a part can send light to itself (module docstring: exact when False).

    Parameters
    ----------
    part : MeshPart
        A cleaned part (degenerate faces dropped).
    bodies : int, optional
        Its connected bodies, when known (the scene's ``report["bodies"]``); counted here
        otherwise.

    Returns
    -------
    bool
        False for a flat part or a closed convex body, True otherwise.
    """
    f = part.faces
    if not len(f):
        return False
    if part_plane(part) is not None:
        return False                                          # flat
    v = part.vertices
    tol = CONVEX_RTOL * float(np.linalg.norm(axis_spans(v)))
    normals, _ = part.face_normals_areas()
    a, b, forward, key = _edges(f, len(v))
    far = np.concatenate([f[:, 2], f[:, 0], f[:, 1]])         # each edge's opposite vertex
    face = np.tile(np.arange(len(f)), 3)
    if bodies is None:
        bodies = np.unique(components(len(v), a, b)[np.unique(f)]).size
    if bodies != 1:
        return True                                           # several bodies
    order = np.argsort(key, kind="stable")
    k = key[order]
    if k.size % 2 or np.any(k[0::2] != k[1::2]) or np.any(k[1:-1:2] == k[2::2]):
        return True                                           # open, or non-manifold
    first, second = order[0::2], order[1::2]
    if np.any(forward[first] == forward[second]):
        return True                                           # not consistently wound
    # the far vertex of each face across the edge, against the other face's plane
    s = np.concatenate([
        np.einsum("ij,ij->i", v[far[second]] - v[a[first]], normals[face[first]]),
        np.einsum("ij,ij->i", v[far[first]] - v[a[second]], normals[face[second]])])
    return not (np.all(s <= tol) or np.all(s >= -tol))


def scene_visibility(names, parts=None, bodies=None) -> Visibility:
    """The :class:`Visibility` of a scene's parts (or of analytic shapes, each convex).

    Parameters
    ----------
    names : sequence of str
        The parts' or shapes' names.
    parts : sequence of MeshPart, optional
        A mesh scene's parts; None for analytic shapes (disks and ellipses: convex).
    bodies : sequence of int, optional
        Each part's connected bodies, when known.

    Returns
    -------
    Visibility
        Different parts see each other unless both are flat and coplanar (or one has no
        face); a part sees itself per :func:`part_sees_itself`.
    """
    n = len(names)
    sees = ~np.eye(n, dtype=bool)
    if parts is not None:
        counts = [None] * len(parts) if bodies is None else bodies
        sees[np.diag_indices(n)] = [part_sees_itself(p, c) for p, c in zip(parts, counts)]
        _coplanar(parts, sees)
    sees.flags.writeable = False
    return Visibility(tuple(names), sees)


def _coplanar(parts, sees):
    """Clear ``sees`` between parts that cannot exchange light: a part without faces, and
    two flat parts in one plane (every vertex of each within CONVEX_RTOL of their joint
    bounding-box diagonal from the other's plane)."""
    planes = [part_plane(p) if len(p.faces) else None for p in parts]
    for i, p in enumerate(parts):
        if not len(p.faces):
            sees[i, :] = sees[:, i] = False
    flat = [i for i, plane in enumerate(planes) if plane is not None]
    for a in flat:
        for b in flat:
            if a < b:
                both = np.concatenate([parts[a].vertices, parts[b].vertices])
                tol = CONVEX_RTOL * float(np.linalg.norm(axis_spans(both)))
                if all(np.all(np.abs((parts[k].vertices - planes[j][1]) @ planes[j][0]) <= tol)
                       for j, k in ((a, b), (b, a))):
                    sees[a, b] = sees[b, a] = False
