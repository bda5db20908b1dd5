"""The :class:`MeshPart` record: one triangle mesh of a scene (vertices, faces, a material
index per face, and optionally the exact normal of the analytic shape it approximates), with
the geometry derived from it once (face normals and areas, convex hull), and the helpers that
build one from a trimesh object.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .._summary import text
from ..errors import GeometryError, ParameterError
from .hull import convex_hull

__all__ = ["MeshPart", "axis_spans", "part_from_trimesh"]


@dataclass(frozen=True, eq=False)
class MeshPart:
    """One triangle mesh of a scene.

    Parameters
    ----------
    vertices : (n, 3) float64
        Positions in scene units, finite. Stored as a read-only C-contiguous float64 array.
    faces : (m, 3) int64, counter-clockwise seen from outside (outward normals)
        Indices into ``vertices``, each in [0, n). Stored as a read-only int64 array.
    material : int or (m,) int
        Index into the scene's material list, for all faces or per face. Stored as a
        read-only (m,) int64 array; not range-checked here.
    name : str, default "mesh"
        A label, quoted in error messages and the repr.
    exact_normal : callable, optional
        Maps points (k, 3) to the unit outward normals (k, 3) of the smooth surface the mesh
        approximates (set by the tessellation of analytic shapes: ``normals="exact"``).
        Default None.

    Raises
    ------
    GeometryError
        When ``vertices`` is not of shape (n, 3) or not finite, ``faces`` is not an (m, 3)
        integer array (an empty one may be of any dtype), or a face index is outside
        [0, n).
    """

    vertices: np.ndarray
    faces: np.ndarray
    material: np.ndarray
    name: str = "mesh"
    exact_normal: object = field(default=None, repr=False)

    def __post_init__(self):
        v = np.asarray(self.vertices, dtype=np.float64)
        f = np.asarray(self.faces)
        if v.ndim != 2 or v.shape[1] != 3:
            raise GeometryError(f"{self.name}: vertices must have shape (n, 3); got {v.shape}")
        if not np.all(np.isfinite(v)):
            bad = int(np.argwhere(~np.isfinite(v))[0][0])
            raise GeometryError(f"{self.name}: vertices must be finite; got {v[bad].tolist()} "
                                f"at vertex {bad}")
        if f.ndim != 2 or f.shape[1] != 3 or (f.size and not np.issubdtype(f.dtype, np.integer)):
            raise GeometryError(f"{self.name}: faces must be an (m, 3) integer array; got "
                                f"shape {f.shape}, dtype {f.dtype}")
        f = f.astype(np.int64)
        if f.size and (f.min() < 0 or f.max() >= len(v)):
            raise GeometryError(f"{self.name}: faces index vertices 0..{len(v) - 1}; got "
                                f"{int(f.min())}..{int(f.max())}")
        mat = np.broadcast_to(np.asarray(self.material, dtype=np.int64), (len(f),)).copy()
        for name, a in (("vertices", v), ("faces", f), ("material", mat)):
            a = np.ascontiguousarray(a)
            a.flags.writeable = False
            object.__setattr__(self, name, a)

    def __repr__(self) -> str:
        lo, hi = (self.vertices.min(axis=0), self.vertices.max(axis=0)) if len(
            self.vertices) else (np.zeros(3), np.zeros(3))
        return text("MeshPart", ("name", self.name), ("vertices", len(self.vertices)),
                    ("faces", len(self.faces)),
                    ("materials", tuple(int(m) for m in np.unique(self.material))),
                    ("bounds", f"[{', '.join(f'{a:.4g}' for a in lo)}] to "
                               f"[{', '.join(f'{b:.4g}' for b in hi)}]"))

    @property
    def triangles(self) -> np.ndarray:
        """(m, 3, 3) vertex coordinates of each face."""
        return self.vertices[self.faces]

    def face_normals_areas(self):
        """Unit face normals (m, 3) and areas (m,), in float64: computed once per part (the
        part is immutable) and returned read-only.

        Returns
        -------
        normals : (m, 3) ndarray of float64
            (v1 − v0) × (v2 − v0) normalised: outward for faces wound counter-clockwise seen
            from outside; a zero vector for a zero-area face.
        areas : (m,) ndarray of float64
            Face areas, in squared scene units.
        """
        cached = self.__dict__.get("_normals_areas")
        if cached is None:
            tri = self.triangles
            cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
            norm = np.linalg.norm(cross, axis=1)
            cached = (cross / np.where(norm > 0, norm, 1.0)[:, None], 0.5 * norm)
            for a in cached:
                a.flags.writeable = False
            object.__setattr__(self, "_normals_areas", cached)
        return cached

    @cached_property
    def hull_points(self) -> np.ndarray:
        """(k, 3) points that include every vertex of this part's convex hull, read-only
        (:func:`~meshladar.meshes.hull.convex_hull`): computed once per part, so every scene
        built from the same part shares it."""
        return convex_hull(self.vertices)

    def digest(self) -> str:
        """Content hash of the geometry (vertices and faces).

        Returns
        -------
        str
            The 40-character hexadecimal SHA-1 of the bytes of ``vertices`` (float64)
            followed by those of ``faces`` (int64); ``material``, ``name`` and
            ``exact_normal`` do not enter.
        """
        h = hashlib.sha1()
        h.update(self.vertices.tobytes())
        h.update(self.faces.tobytes())
        return h.hexdigest()


def part_from_trimesh(mesh, material_index, *, name="mesh", transform=None):
    """A MeshPart from a trimesh.Trimesh or a :class:`~meshladar.meshes.TriangleMesh`
    (optionally transformed by a 4×4 matrix).

    Parameters
    ----------
    mesh : trimesh.Trimesh or TriangleMesh
        Read through its ``vertices`` and ``faces`` only.
    material_index : int or (m,) int
        Index into the scene's material list, for all faces or per face.
    name : str, keyword-only, default "mesh"
        The part's label.
    transform : (4, 4) array_like, keyword-only, optional
        Finite affine transform applied to the vertices as ``v @ T[:3, :3].T + T[:3, 3]``
        (the bottom row is not used). Default None: the vertices as they are.

    Returns
    -------
    MeshPart
        Without ``exact_normal``.

    Raises
    ------
    ParameterError
        When ``transform`` is not a finite 4×4 matrix.
    GeometryError
        When the vertices or faces are invalid (from :class:`MeshPart`).
    """
    v = np.asarray(mesh.vertices, dtype=np.float64)
    if transform is not None:
        t = np.asarray(transform, dtype=np.float64)
        if t.shape != (4, 4) or not np.all(np.isfinite(t)):
            raise ParameterError(f"transform must be a finite 4x4 matrix; got shape {t.shape}")
        v = v @ t[:3, :3].T + t[:3, 3]
    return MeshPart(v, np.asarray(mesh.faces), material_index, name)


def axis_spans(points):
    """The extent of a point set along each axis, column by column (numpy's ``ptp(axis=0)``
    of an (n, 3) array is ~25× slower: its inner loop runs over 3 values).

    Parameters
    ----------
    points : (n, d) array_like
        At least one point.

    Returns
    -------
    numpy.ndarray
        (d,) float64: max − min of each column, as ``np.ptp(points, axis=0)`` of the
        points as float64.
    """
    p = np.asarray(points, dtype=np.float64)
    return np.array([p[:, c].max() - p[:, c].min() for c in range(p.shape[1])])


def _point_index(vertices):
    """((n,) int64, k): each vertex's index among the k distinct positions, by exact float
    equality (-0.0 equals 0.0), numbered in lexicographic order of the positions."""
    v = np.asarray(vertices, dtype=np.float64)
    order = np.lexsort(v.T[::-1])
    s = v[order]
    new = np.zeros(len(v), dtype=bool)
    new[:1] = True
    for c in range(v.shape[1]):        # column by column: np.any(axis=1) is ~8x slower
        new[1:] |= s[1:, c] != s[:-1, c]
    out = np.empty(len(v), dtype=np.int64)
    out[order] = np.cumsum(new) - 1
    return out, int(new.sum())


def _edges(faces, n):
    """Every face's three directed edges a → b (face i's at rows i, m + i and 2m + i of the
    m faces) with (a, b, forward, key): ``forward`` is a < b and ``key`` the undirected
    edge as one integer, the lower of its ``n`` vertex indices × n + the higher, equal for
    an edge's two directions (sorted stably by it, an edge's faces are neighbours)."""
    f = np.asarray(faces, dtype=np.int64)
    a = np.concatenate([f[:, 0], f[:, 1], f[:, 2]])
    b = np.concatenate([f[:, 1], f[:, 2], f[:, 0]])
    forward = a < b
    return a, b, forward, np.where(forward, a, b) * n + np.where(forward, b, a)
