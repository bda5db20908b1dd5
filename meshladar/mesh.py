"""Triangle-mesh scenes: loading, checks, tessellation of analytic shapes, normals.

A mesh scene is a list of :class:`MeshPart` (vertices, faces, a material index per face, and
optionally the exact normal of the analytic shape it approximates). trimesh is imported only
here, lazily, when a mesh is loaded or built.

Checks, with clear outcomes:

* NaN or infinite vertices: :class:`~meshladar.errors.GeometryError`.
* Degenerate faces (zero area, or repeated vertex indices): dropped and counted in
  ``scene.report["degenerate_faces"]``.
* Open meshes are allowed (a plate, a scanned shell); ``report["watertight"]`` says which.
* Faces are hit from either side. A hit on a face's back (n·w < 0: an open mesh seen from
  behind, or inverted normals) is counted per view in the sinogram's ``info["back_face_hits"]``
  and handled by the ``back_faces`` option of tracing: ``"two-sided"`` (default) flips the
  normal toward the ladar, ``"ignore"`` lets the face block the ray and return nothing.
  A closed mesh with inverted normals (negative volume) is reported as ``report["inverted"]``.
"""

from __future__ import annotations

import hashlib
import math
import os
from dataclasses import dataclass, field

import numpy as np

from ._validate import check_count
from .errors import GeometryError, ParameterError

__all__ = ["MeshPart", "load_parts", "part_from_trimesh", "prism", "sphere", "ellipsoid",
           "fibonacci_sphere", "corner_normals", "CREASE_DEG"]

#: Vertex normals are averaged only over faces within this angle of each other, so the
#: edges of a prism or a box stay sharp ("smooth" normals that respect creases).
CREASE_DEG = 30.0
#: Faces with area below this fraction of (bounding-box diagonal)² are degenerate.
_DEGENERATE_AREA = 1e-14


@dataclass(frozen=True, eq=False)
class MeshPart:
    """One triangle mesh of a scene.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (m, 3) int64, counter-clockwise seen from outside (outward normals)
    material : int or (m,) int
        Index into the scene's material list, for all faces or per face.
    name : str
    exact_normal : callable, optional
        Maps points (k, 3) to the unit outward normals (k, 3) of the smooth surface the mesh
        approximates (set by the tessellation of analytic shapes: ``normals="exact"``).
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

    @property
    def triangles(self) -> np.ndarray:
        """(m, 3, 3) vertex coordinates of each face."""
        return self.vertices[self.faces]

    def face_normals_areas(self):
        """Unit face normals (m, 3) and areas (m,), in float64."""
        tri = self.triangles
        cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        norm = np.linalg.norm(cross, axis=1)
        return cross / np.where(norm > 0, norm, 1.0)[:, None], 0.5 * norm

    def digest(self) -> str:
        """Content hash of the geometry (vertices and faces)."""
        h = hashlib.sha1()
        h.update(self.vertices.tobytes())
        h.update(self.faces.tobytes())
        return h.hexdigest()


def _clean(part: MeshPart):
    """Drop degenerate faces; return the cleaned part and the number dropped."""
    if not len(part.faces):
        return part, 0
    _, area = part.face_normals_areas()
    diag = float(np.linalg.norm(np.ptp(part.vertices, axis=0)))
    f = part.faces
    repeated = (f[:, 0] == f[:, 1]) | (f[:, 1] == f[:, 2]) | (f[:, 0] == f[:, 2])
    bad = repeated | (area <= _DEGENERATE_AREA * diag * diag)
    if not bad.any():
        return part, 0
    return (MeshPart(part.vertices, f[~bad], part.material[~bad], part.name,
                     part.exact_normal), int(bad.sum()))


def _signed_volume(part: MeshPart) -> float:
    tri = part.triangles
    return float(np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6.0)


def _is_watertight(part: MeshPart) -> bool:
    """Every undirected edge shared by exactly two faces, in opposite directions."""
    f = part.faces
    e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    directed = {tuple(x) for x in e.tolist()}
    if len(directed) != len(e):
        return False
    return all((b, a) in directed for a, b in directed)


def inspect_parts(parts):
    """Clean parts and build the scene's mesh report."""
    cleaned, dropped, watertight, inverted = [], 0, [], []
    for p in parts:
        q, k = _clean(p)
        cleaned.append(q)
        dropped += k
        wt = _is_watertight(q) if len(q.faces) < 2_000_000 else None
        watertight.append(wt)
        inverted.append(bool(wt and _signed_volume(q) < 0))
    if not any(len(p.faces) for p in cleaned):
        raise GeometryError("the mesh scene has no faces (all degenerate or none given)")
    return cleaned, {"degenerate_faces": dropped, "watertight": watertight,
                     "inverted": inverted, "faces": sum(len(p.faces) for p in cleaned)}


def part_from_trimesh(mesh, material_index, name="mesh", transform=None):
    """A MeshPart from a trimesh.Trimesh (optionally transformed by a 4×4 matrix)."""
    v = np.asarray(mesh.vertices, dtype=np.float64)
    if transform is not None:
        t = np.asarray(transform, dtype=np.float64)
        if t.shape != (4, 4) or not np.all(np.isfinite(t)):
            raise ParameterError(f"transform must be a finite 4x4 matrix; got shape {t.shape}")
        v = v @ t[:3, :3].T + t[:3, 3]
    return MeshPart(v, np.asarray(mesh.faces), material_index, name)


def load_parts(mesh_or_path):
    """Load anything trimesh loads; returns a list of (name, trimesh.Trimesh) in world
    coordinates (a GLB/GLTF scene's transforms applied)."""
    import trimesh

    if isinstance(mesh_or_path, (str, os.PathLike)):
        path = os.fspath(mesh_or_path)
        if not os.path.exists(path):
            raise GeometryError(f"{path}: no such mesh file")
        try:
            # unprocessed, so that NaN vertices reach meshladar's own check (trimesh's
            # processing would silently drop them); vertices are merged below
            loaded = trimesh.load(path, process=False)
        except Exception as exc:  # trimesh raises many types on bad files
            raise GeometryError(f"{path}: cannot load mesh ({type(exc).__name__}: {exc})") \
                from exc
        source = path
    else:
        loaded, source = mesh_or_path, "mesh"
    if isinstance(loaded, trimesh.Scene):
        out = []
        for node in loaded.graph.nodes_geometry:
            transform, geom_name = loaded.graph[node]
            g = loaded.geometry[geom_name]
            if isinstance(g, trimesh.Trimesh):
                m = _welded(g, f"{source}: part {node!r}")
                m.apply_transform(transform)
                out.append((str(node), m))
        if not out:
            raise GeometryError(f"{source}: the scene holds no triangle meshes")
        return out
    if isinstance(loaded, trimesh.Trimesh):
        name = str(loaded.metadata.get("name", "mesh")) if hasattr(loaded, "metadata") \
            else "mesh"
        return [(name, _welded(loaded, source))]
    raise GeometryError(f"{source}: expected a triangle mesh or a scene of meshes; got "
                        f"{type(loaded).__name__}")


def _welded(mesh, where):
    """A copy with shared vertices merged (STL stores each triangle's own), after checking
    that every vertex is finite."""
    v = np.asarray(mesh.vertices, dtype=np.float64)
    if not np.all(np.isfinite(v)):
        bad = int(np.argwhere(~np.isfinite(v))[0][0])
        raise GeometryError(f"{where}: vertices must be finite; got {v[bad].tolist()} at "
                            f"vertex {bad}")
    m = mesh.copy()
    m.merge_vertices()
    return m


# ------------------------------------------------------------------ analytic tessellations

class _PrismNormal:
    """Exact outward normal of an extruded ellipse (x-y gradient of its implicit function
    on the sides, ±z on the caps). A plain class, so that parts pickle to worker processes."""

    def __init__(self, center, axes, angle, lo, hi):
        self.center, self.axes, self.angle, self.lo, self.hi = center, axes, angle, lo, hi

    def __call__(self, p):
        p = np.asarray(p, dtype=np.float64)
        (cx, cy), (a, b) = self.center, self.axes
        ca, sa = math.cos(self.angle), math.sin(self.angle)
        dx, dy = p[:, 0] - cx, p[:, 1] - cy
        xl, yl = ca * dx + sa * dy, -sa * dx + ca * dy
        gx, gy = xl / a**2, yl / b**2
        nx, ny = ca * gx - sa * gy, sa * gx + ca * gy
        nn = np.hypot(nx, ny)
        nn = np.where(nn > 0, nn, 1.0)
        out = np.stack([nx / nn, ny / nn, np.zeros_like(nx)], -1)
        eps = 1e-9 * max(a, b, self.hi - self.lo)
        top = np.abs(p[:, 2] - self.hi) < eps
        bottom = np.abs(p[:, 2] - self.lo) < eps
        out[top | bottom] = 0.0
        out[top, 2] = 1.0
        out[bottom, 2] = -1.0
        return out

    def curvature_radius(self, p):
        """Radius of curvature of the cross-section at the points' eccentric angle (inf on
        the caps): (a² sin²t + b² cos²t)^(3/2) / (a b)."""
        p = np.asarray(p, dtype=np.float64)
        (cx, cy), (a, b) = self.center, self.axes
        ca, sa = math.cos(self.angle), math.sin(self.angle)
        dx, dy = p[:, 0] - cx, p[:, 1] - cy
        t = np.arctan2((-sa * dx + ca * dy) / b, (ca * dx + sa * dy) / a)
        rho = (a * a * np.sin(t) ** 2 + b * b * np.cos(t) ** 2) ** 1.5 / (a * b)
        eps = 1e-9 * max(a, b, self.hi - self.lo)
        cap = (np.abs(p[:, 2] - self.hi) < eps) | (np.abs(p[:, 2] - self.lo) < eps)
        return np.where(cap, np.inf, rho)


class _EllipsoidNormal:
    """Exact outward normal of an ellipsoid: the gradient of Σ ((x − c)_i / a_i)²."""

    def __init__(self, center, axes):
        self.center, self.axes = np.asarray(center), np.asarray(axes)

    def __call__(self, p):
        g = (np.asarray(p, dtype=np.float64) - self.center) / self.axes**2
        return g / np.linalg.norm(g, axis=-1, keepdims=True)


def prism(shape, segments, height, material_index, *, z0=0.0):
    """A disk/ellipse extruded to a prism of ``height`` centred on z = z0, with ``segments``
    vertices on the exact boundary (uniform in the eccentric angle) and flat caps.

    The part's ``exact_normal`` is the shape's own outward normal (in x-y) for side points
    and ±z on the caps.
    """
    n = check_count("segments", segments, 3)
    t = 2 * math.pi * np.arange(n) / n
    ring = shape.boundary(t)                                 # (n, 2)
    lo, hi = z0 - height / 2, z0 + height / 2
    v = np.concatenate([np.c_[ring, np.full(n, lo)], np.c_[ring, np.full(n, hi)],
                        [[shape.center[0], shape.center[1], lo],
                         [shape.center[0], shape.center[1], hi]]])
    i = np.arange(n)
    j = (i + 1) % n
    side = np.concatenate([np.c_[i, j, n + j], np.c_[i, n + j, n + i]])
    bottom = np.c_[np.full(n, 2 * n), j, i]
    top = np.c_[np.full(n, 2 * n + 1), n + i, n + j]
    faces = np.concatenate([side, bottom, top])
    exact_normal = _PrismNormal(shape.center, shape.axes, shape.angle, lo, hi)
    return MeshPart(v, faces, material_index, shape.name or type(shape).__name__.lower(),
                    exact_normal)


def _icosphere(subdivisions):
    import trimesh

    subdivisions = check_count("subdivisions", subdivisions, 0)
    m = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    return np.asarray(m.vertices, dtype=np.float64), np.asarray(m.faces)


def ellipsoid(center, semi_axes, material_index, *, subdivisions=4, name="ellipsoid"):
    """A tessellated ellipsoid (a scaled icosphere: 20·4^subdivisions faces) whose
    ``exact_normal`` is the ellipsoid's own (the gradient of Σ (x_i/a_i)²)."""
    c = np.asarray(center, dtype=np.float64)
    ax = np.asarray(semi_axes, dtype=np.float64)
    if c.shape != (3,) or ax.shape != (3,) or np.any(ax <= 0) or not np.all(np.isfinite(ax)):
        raise ParameterError(f"ellipsoid needs a 3-D center and three positive semi_axes; got "
                             f"{center!r}, {semi_axes!r}")
    v, f = _icosphere(subdivisions)
    return MeshPart(c + v * ax, f, material_index, name, _EllipsoidNormal(c, ax))


def sphere(center, radius, material_index, *, subdivisions=4, name="sphere"):
    """A tessellated sphere (icosphere: 20·4^subdivisions faces) with its exact normals."""
    return ellipsoid(center, (radius, radius, radius), material_index,
                     subdivisions=subdivisions, name=name)


def fibonacci_sphere(n, *, hemisphere=False):
    """n view vectors spread evenly over the sphere (or the upper hemisphere z ≥ 0), by the
    golden-angle (Fibonacci) lattice: each covers ~4π/n sr."""
    n = check_count("n", n)
    k = np.arange(n) + 0.5
    z = 1 - k / n if hemisphere else 1 - 2 * k / n
    r = np.sqrt(np.maximum(1 - z * z, 0.0))
    phi = math.pi * (3 - math.sqrt(5)) * k
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], -1)


# ------------------------------------------------------------------ normals

def corner_normals(part: MeshPart, crease_deg=CREASE_DEG):
    """(m, 3, 3) unit normal at each face corner: the area-weighted mean of the normals of
    the faces around that vertex that lie within ``crease_deg`` of the face's own normal
    (so shared smooth edges blend and creases stay sharp)."""
    from . import _kernels

    fn, area = part.face_normals_areas()
    f = part.faces
    order = np.argsort(f.ravel(), kind="stable")
    vert_of = f.ravel()[order]
    face_of = order // 3
    ptr = np.searchsorted(vert_of, np.arange(len(part.vertices) + 1))
    out = np.zeros((len(f), 3, 3))
    _kernels.corner_normals(f, fn, area, ptr, face_of, math.cos(math.radians(crease_deg)), out)
    return out
