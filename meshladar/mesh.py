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

import contextlib
import hashlib
import io
import math
import os
import re
from dataclasses import dataclass, field

import numpy as np

from ._validate import check_count, check_size
from .errors import GeometryError, ParameterError
from .precision import DEGENERATE_AREA as _DEGENERATE_AREA
from .precision import WELD_REL as _WELD_REL
from .precision import CAP_REL

__all__ = ["MeshPart", "load_parts", "part_from_trimesh", "prism", "sphere", "ellipsoid",
           "fibonacci_sphere", "corner_normals", "CREASE_DEG"]

#: Vertex normals are averaged only over faces within this angle of each other, so the
#: edges of a prism or a box stay sharp ("smooth" normals that respect creases).
CREASE_DEG = 30.0


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

    def __repr__(self) -> str:
        from ._summary import text

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
        part is immutable) and returned read-only."""
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


def _bodies(part: MeshPart):
    """Per connected body of a part (faces joined through shared vertices): whether it is
    closed (every directed edge met once, and its reverse once) and its signed volume.
    Vectorised, so a scan of 1e5 loose bodies costs no Python loop."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    f = part.faces
    n = len(part.vertices)
    a = np.concatenate([f[:, 0], f[:, 1], f[:, 2]])
    b = np.concatenate([f[:, 1], f[:, 2], f[:, 0]])
    graph = coo_matrix((np.ones(a.size, np.int8), (a, b)), shape=(n, n))
    _, vertex_body = connected_components(graph, directed=False)
    face_body = vertex_body[f[:, 0]]
    bodies, face_body = np.unique(face_body, return_inverse=True)
    # a closed, consistently wound body meets each undirected edge exactly twice, once in
    # each direction: one sort of the undirected edges finds them (np.isin of the directed
    # codes against their reverses took 8 s at 1.3M faces)
    forward = a < b
    undirected = np.where(forward, a, b) * n + np.where(forward, b, a)
    order = np.argsort(undirected, kind="stable")
    u = undirected[order]
    start = np.flatnonzero(np.r_[True, u[1:] != u[:-1]])
    length = np.diff(np.r_[start, u.size])
    f_sorted = forward[order]
    # a run of exactly two, one forward and one backward
    run_ok = (length == 2) & (f_sorted[start] != f_sorted[np.minimum(start + 1, u.size - 1)])
    ok_edge = np.empty(u.size, bool)
    ok_edge[order] = np.repeat(run_ok, length)
    edge_body = np.tile(face_body, 3)
    open_edges = np.bincount(edge_body, weights=~ok_edge, minlength=bodies.size)
    # signed volume from the normals and areas the part caches: (p0·n) area / 3 per face
    normals, areas = part.face_normals_areas()
    p0 = part.vertices[f[:, 0]]
    vol = np.einsum("ij,ij->i", p0, normals) * areas / 3.0
    volume = np.bincount(face_body, weights=vol, minlength=bodies.size)
    return open_edges == 0, volume


def inspect_parts(parts):
    """Clean parts and build the scene's mesh report: ``watertight`` and ``inverted`` per
    part (inverted: some closed body of it has negative volume, its faces wound inward),
    ``inverted_bodies`` in all."""
    cleaned, dropped, watertight, inverted, n_inverted = [], 0, [], [], 0
    for p in parts:
        q, k = _clean(p)
        cleaned.append(q)
        dropped += k
        if len(q.faces):
            closed, volume = _bodies(q)
            bad = int(np.count_nonzero(closed & (volume < 0)))
        else:
            closed, bad = np.array([False]), 0
        watertight.append(bool(closed.all()))
        inverted.append(bad > 0)
        n_inverted += bad
    if not any(len(p.faces) for p in cleaned):
        raise GeometryError("the mesh scene has no faces (all degenerate or none given)")
    return cleaned, {"degenerate_faces": dropped, "watertight": watertight,
                     "inverted": inverted, "inverted_bodies": n_inverted,
                     "faces": sum(len(p.faces) for p in cleaned)}


def part_from_trimesh(mesh, material_index, name="mesh", transform=None):
    """A MeshPart from a trimesh.Trimesh (optionally transformed by a 4×4 matrix)."""
    v = np.asarray(mesh.vertices, dtype=np.float64)
    if transform is not None:
        t = np.asarray(transform, dtype=np.float64)
        if t.shape != (4, 4) or not np.all(np.isfinite(t)):
            raise ParameterError(f"transform must be a finite 4x4 matrix; got shape {t.shape}")
        v = v @ t[:3, :3].T + t[:3, 3]
    return MeshPart(v, np.asarray(mesh.faces), material_index, name)


# ------------------------------------------------------------------ reading mesh files

#: Bytes read from the start of a file to recognise its format by content (magic numbers,
#: headers, the first lines of a text format).
_HEAD_BYTES = 1 << 16
#: Longest piece of a reader's own message quoted in a GeometryError (characters).
_MAX_REASON = 160
#: Single-file compression meshladar undoes itself with the standard library, then reads the
#: inner file by its own suffix (or content): trimesh reads neither .gz nor .xz, and its
#: .bz2 reader hides why the inner file failed.
_COMPRESSED = {"gz": "gzip", "bz2": "bzip2", "xz": "xz"}
#: Tar archives, by suffix, as trimesh's archive reader names them. Its reader opens any tar
#: with ``tarfile.open(mode="r")``, which detects the compression itself, so plain and xz tars
#: go through 'tar.gz' too.
_TAR = {"tar.gz": "tar.gz", "tgz": "tar.gz", "tar.bz2": "tar.bz2", "tbz2": "tar.bz2",
        "tbz": "tar.bz2", "tar.xz": "tar.gz", "txz": "tar.gz", "tar": "tar.gz"}
#: Formats trimesh reads only with an optional package installed (pip names), as its
#: ``trimesh.exchange`` modules import them: COLLADA through pycollada, 3MF and 3DXML through
#: lxml and networkx, XAML through lxml, STEP through cascadio, OpenCTM through openctm, and
#: the volume and finite-element formats through meshio. (SVG, through svg.path and lxml, is
#: a 2-D drawing format: see _DRAWINGS.)
_OPTIONAL_READERS = {
    "dae": "pycollada", "zae": "pycollada", "3mf": "lxml networkx", "3dxml": "lxml networkx",
    "xaml": "lxml", "step": "cascadio", "stp": "cascadio", "ctm": "openctm",
    **dict.fromkeys(("vtk", "vtu", "msh", "inp", "mesh", "meshb", "med", "xdmf", "xmf",
                     "h5m", "su2", "ugrid", "mdpa", "bdf", "fem", "nas", "avs", "cgns",
                     "exo", "e", "tec", "f3grid", "vol"), "meshio"),
}
#: Formats that hold 2-D drawings (trimesh Path2D), never a 3-D triangle mesh.
_DRAWINGS = {"svg": "svg.path lxml", "dxf": ""}
#: What each format is called in messages.
_NAMES = {"stl": "STL file", "obj": "OBJ file", "ply": "PLY file", "off": "OFF file",
          "glb": "GLB file", "gltf": "glTF file", "zip": "ZIP archive", "tar.gz": "tar archive",
          "tar.bz2": "tar archive", "bz2": "bzip2 file", "gz": "gzip file", "xz": "xz file",
          "dxf": "DXF drawing", "svg": "SVG drawing", "xyz": "XYZ point file",
          "dae": "COLLADA file", "3mf": "3MF file"}


def load_parts(mesh_or_path):
    """Load a mesh file (or take a trimesh object) as the triangle meshes of a scene.

    Parameters
    ----------
    mesh_or_path : str, os.PathLike, trimesh.Trimesh or trimesh.Scene
        A file of any format trimesh reads: STL (ASCII or binary), OBJ, PLY, OFF, GLB/glTF
        (several parts, each placed by its node's transform), ZIP and tar archives; 3MF,
        COLLADA and others when their optional readers are installed. ``.gz``, ``.bz2`` and
        ``.xz`` files are decompressed and their inner file read. The format comes from the
        suffix, or from the content when the suffix is unknown or its reader fails (a binary
        STL named ``.dat`` loads). Textures, colours and normals in the file are not read.

    Returns
    -------
    list of (str, trimesh.Trimesh)
        Part names and meshes in world coordinates, each a fresh mesh of vertices and faces
        only, with vertices at the same position merged (see :func:`_welded`).

    Raises
    ------
    GeometryError
        With a one-line message naming the file and what is wrong: no such file, an empty
        file, binary junk, an unknown format, a format whose optional reader is not installed
        (naming the pip package), a point cloud, a 2-D drawing or a 3-D path (no faces), a
        scene without triangle meshes, non-finite vertices. Any exception of trimesh's reader
        becomes a GeometryError chained to it.
    """
    if isinstance(mesh_or_path, (str, os.PathLike)):
        path = os.fspath(mesh_or_path)
        if isinstance(path, bytes):
            path = os.fsdecode(path)
        return _read_file(path)
    return _parts_of(mesh_or_path, "mesh")


def _read_file(path):
    """load_parts for a path: check the file, undo single-file compression, read it."""
    where = _printable(path)
    if not os.path.exists(path):
        raise GeometryError(f"{where}: no such mesh file")
    if os.path.isdir(path):
        raise GeometryError(f"{where}: is a directory, not a mesh file")
    try:
        size = os.path.getsize(path)
        with open(path, "rb") as fh:
            head = fh.read(_HEAD_BYTES)
    except OSError as exc:
        raise GeometryError(f"{where}: cannot read the file "
                            f"({_one_line(exc.strerror or exc)})") from exc
    suffix = _suffix(path)
    kind = suffix if suffix in _COMPRESSED else _sniff(head, size)
    # a compressed file (by suffix, or by content unless a tar reader takes it whole)
    if kind in _COMPRESSED and (suffix == kind or suffix not in _TAR):
        import trimesh

        data = _decompress(path, kind, where)
        name = os.path.basename(path)
        inner = name[: -len(suffix) - 1] if suffix == kind else name

        return _read(f"{where} (decompressed {_COMPRESSED[kind]})", lambda: io.BytesIO(data),
                     _suffix(inner), data[:_HEAD_BYTES], len(data),
                     resolver=trimesh.resolvers.FilePathResolver(path),
                     default_name=inner or "mesh")
    return _read(where, lambda: path, suffix, head, size, resolver=None, default_name="mesh")


def _read(where, source, suffix, head, size, *, resolver, default_name):
    """Read one file's bytes (``source()`` gives a path or a fresh stream) with trimesh,
    trying the format its suffix names, then the format its content announces."""
    import trimesh

    if size == 0:
        raise GeometryError(f"{where}: empty file (0 bytes)")
    if size <= len(head) and not head.strip():
        raise GeometryError(f"{where}: empty file (only whitespace)")
    formats = _readable_formats()
    suffix = _TAR.get(suffix, suffix)
    sniffed = _sniff(head, size)
    sniffed = _TAR.get(sniffed, sniffed)
    tries = [t for t in dict.fromkeys((suffix, sniffed)) if t in formats]
    content = "binary data" if _is_binary(head) else "text"
    if suffix not in formats and (suffix in _OPTIONAL_READERS or suffix in _DRAWINGS):
        tries = []                # a 3MF is a ZIP too: say what its own reader needs
    if not tries:
        kind = suffix if suffix in _OPTIONAL_READERS or suffix in _DRAWINGS else sniffed
        if kind in _DRAWINGS:
            raise GeometryError(f"{where}: {_label(kind)} is a 2-D drawing format, not a 3-D "
                                f"triangle mesh")
        if kind in _OPTIONAL_READERS:
            raise GeometryError(_needs(where, kind))
        what = f"file format {_label(suffix)}" if suffix else "file format (no file suffix)"
        raise GeometryError(f"{where}: unknown {what}, and its content ({content}) is not "
                            f"a format trimesh reads either; readable formats: "
                            f"{', '.join(sorted((formats - set(_DRAWINGS)) | set(_COMPRESSED)))}")
    first = None
    for ftype in tries:
        reached_geometry = False
        try:
            with _quiet_reader():
                loaded = trimesh.load(source(), file_type=ftype, resolver=resolver,
                                      process=False, skip_materials=True)
        except ImportError as exc:
            err = GeometryError(_needs(where, ftype, exc))
            err.__cause__ = exc
        except Exception as exc:   # trimesh's readers raise many types on bad files
            err = GeometryError(f"{where}: not a readable {_name(ftype)}"
                                f" ({type(exc).__name__}: {_one_line(exc)})")
            err.__cause__ = exc
        else:
            if isinstance(loaded, trimesh.Scene) and not loaded.geometry:
                if ftype in ("zip", "tar.gz", "tar.bz2"):
                    err = GeometryError(f"{where}: the {_NAMES[ftype]} holds no file trimesh "
                                        f"reads as geometry{_members(source, ftype)}")
                else:
                    err = GeometryError(f"{where}: not a readable "
                                        f"{_name(ftype)} (trimesh found no "
                                        f"geometry in {size} bytes of {content})")
            else:
                reached_geometry = True
                try:
                    return _parts_of(loaded, where, default_name)
                except GeometryError as exc:
                    err = exc
        if first is None or (reached_geometry and not first[1]):
            first = (err, reached_geometry)
    raise first[0]


#: The module a pip package is imported as, where the two differ.
_IMPORT_NAMES = {"pycollada": "collada"}
#: trimesh makes node names unique with a random hexadecimal suffix (a glTF node with
#: several primitives, unnamed nodes): such names change on every load.
_RANDOM_SUFFIX = re.compile(r"(_[0-9a-f]{6}|[0-9a-f]{12})$")


def _part_name(node, geometry, taken):
    """A part's name that is the same on every load: the scene node's own name, or, when
    trimesh made it unique with a random suffix, the geometry's (deterministic) name; a
    repeat gets '#2', '#3', ... in scene order."""
    name = geometry if _RANDOM_SUFFIX.search(node) else node
    if name in taken:
        k = 2
        while f"{name}#{k}" in taken:
            k += 1
        name = f"{name}#{k}"
    return name


def _parts_of(loaded, where, default_name="mesh"):
    """(name, welded mesh) of each triangle mesh in a trimesh object, or a GeometryError
    saying what the object holds instead."""
    import trimesh

    if isinstance(loaded, trimesh.Scene):
        out, other = [], []
        for node in loaded.graph.nodes_geometry:
            transform, geom_name = loaded.graph[node]
            g = loaded.geometry[geom_name]
            if isinstance(g, trimesh.Trimesh) and len(g.faces):
                name = _part_name(str(node), str(geom_name), {n for n, _ in out})
                m = _welded(g, f"{where}: part {name!r}")
                m.apply_transform(transform)
                out.append((name, m))
            else:
                other.append(g)
        if not out:
            held = other or list(loaded.geometry.values())
            if len(held) == 1:
                raise GeometryError(f"{where}: {_not_a_mesh(held[0])}")
            kinds = ", ".join(dict.fromkeys(_describe(g) for g in held))
            raise GeometryError(f"{where}: the scene holds no triangle meshes"
                                f"{f' (only {_one_line(kinds)})' if held else ''}")
        return out
    if isinstance(loaded, trimesh.Trimesh) and len(loaded.faces):
        meta = getattr(loaded, "metadata", None) or {}
        return [(str(meta.get("name") or default_name), _welded(loaded, where))]
    raise GeometryError(f"{where}: {_not_a_mesh(loaded)}")


def _describe(g):
    """What a trimesh geometry without triangles is, in a few words (by class name, so that
    trimesh.path, which needs more optional packages, is never imported here)."""
    import trimesh

    kind = type(g).__name__
    if isinstance(g, (trimesh.PointCloud, trimesh.Trimesh)):
        return f"a point cloud ({_count(len(g.vertices), 'point')}, no faces)"
    if kind == "Path2D":
        return f"a 2-D drawing ({_count(len(g.entities), 'line or curve', 'lines or curves')})"
    if kind == "Path3D":
        return (f"a 3-D path ({_count(len(g.entities), 'line or curve', 'lines or curves')}, "
                "no faces)")
    return f"a {kind}"


def _not_a_mesh(g):
    """The end of the message for a geometry that is not a triangle mesh."""
    import trimesh

    if type(g).__name__ == "Path2D":
        return f"is {_describe(g)}, not a 3-D triangle mesh"
    if isinstance(g, trimesh.parent.Geometry):
        return f"holds {_describe(g)}, not a triangle mesh"
    return f"expected a triangle mesh or a scene of meshes; got {type(g).__name__}"


def _welded(mesh, where):
    """A fresh trimesh.Trimesh of ``mesh``'s vertices and faces only, with the vertices at
    the same position merged into one (STL stores each triangle's own) and unreferenced
    vertices dropped, after checking that every vertex is finite and every face indexes a
    vertex.

    Nothing else is kept: meshladar needs positions and faces, and copying a texture needs
    Pillow. Merging by position alone also joins the vertices a file splits at UV seams and
    at split normals, which are not creases (:func:`corner_normals` finds creases from the
    face normals); trimesh's own merge keeps them apart on a textured mesh, and rounds to
    1e-8 absolute, which merges the vertices of a nanometre-sized part and overflows far
    from the origin. Positions are compared relative to the mesh's size (_WELD_REL).
    """
    import trimesh

    v = np.array(mesh.vertices, dtype=np.float64)         # a copy: the caller's mesh stays
    f = np.asarray(mesh.faces)
    if v.ndim != 2 or v.shape[1] != 3:
        raise GeometryError(f"{where}: vertices must have shape (n, 3); got {v.shape}")
    if not np.all(np.isfinite(v)):
        bad = int(np.argwhere(~np.isfinite(v))[0][0])
        raise GeometryError(f"{where}: vertices must be finite; got {v[bad].tolist()} at "
                            f"vertex {bad}")
    if f.ndim != 2 or f.shape[1] != 3 or (f.size and not np.issubdtype(f.dtype, np.integer)):
        raise GeometryError(f"{where}: faces must be an (m, 3) integer array; got shape "
                            f"{f.shape}, dtype {f.dtype}")
    if f.size and (f.min() < 0 or f.max() >= len(v)):
        raise GeometryError(f"{where}: faces index vertices 0..{len(v) - 1}; got "
                            f"{int(f.min())}..{int(f.max())}")
    used = np.zeros(len(v), dtype=bool)
    used[f.ravel()] = True
    v = v[used]
    f = (np.cumsum(used) - 1)[f]
    if len(v):
        # positions on a grid of _WELD_REL × the mesh's size, from its lowest corner: exact
        # integers in float64 (below 2**40), whatever the scale and offset
        size = float(np.ptp(v, axis=0).max())
        key = np.round((v - v.min(axis=0)) / (size * _WELD_REL)) if size > 0 else 0.0 * v
        point, n = _point_index(key)
        first = np.full(n, len(v))
        np.minimum.at(first, point, np.arange(len(v)))     # each point's first vertex
        rank = np.empty(n, dtype=np.int64)
        rank[np.argsort(first)] = np.arange(n)               # points numbered in file order
        v, f = v[np.sort(first)], rank[point][f]
    return trimesh.Trimesh(vertices=v, faces=f.astype(np.int64), process=False)


def _count(n, one, many=None):
    """'1 point', '2 points'."""
    return f"{n} {one if n == 1 else (many or one + 's')}"


def _readable_formats():
    """The formats this trimesh reads with what is installed ('stl_ascii' is an alias)."""
    import trimesh

    return set(trimesh.available_formats()) - {"stl_ascii"}


def _needs(where, ftype, exc=None):
    """The message for a format whose optional reader is not installed."""
    import importlib.util

    pkgs = _OPTIONAL_READERS.get(ftype) or _DRAWINGS.get(ftype)
    if pkgs:                       # name only what is missing (networkx may be there)
        def installed(name):
            try:
                return importlib.util.find_spec(_IMPORT_NAMES.get(name, name)) is not None
            except ImportError:                    # a dotted name whose parent is missing
                return False

        missing = [p for p in pkgs.split() if not installed(p)]
        pkgs = " ".join(missing) or pkgs
        names = " and ".join(pkgs.split())
        return (f"{where}: reading {_label(ftype)} files needs the optional package"
                f"{'s' if ' ' in pkgs else ''} {names}: pip install {pkgs}")
    return (f"{where}: reading {_label(ftype)} files needs a package that is not installed "
            f"({_one_line(exc)})")


def _label(suffix):
    return f"'.{suffix}'"


def _name(ftype):
    return _NAMES.get(ftype, f"{ftype.upper()} file")


def _suffix(name):
    """Lower-case suffix of a file name without the dot ('tar.gz' style for tars), or ''."""
    base = os.path.basename(name).lower()
    for double in ("tar.gz", "tar.bz2", "tar.xz"):
        if base.endswith("." + double):
            return double
    stem, dot, ext = base.rpartition(".")
    return ext if dot and stem else ""


def _sniff(head, size):
    """The format a file's first bytes announce (magic numbers and headers), or None."""
    import re

    if head.startswith(b"glTF"):
        return "glb"
    if head.startswith(b"PK\x03\x04"):
        return "zip"
    if head.startswith(b"\x1f\x8b"):
        return "gz"
    if head.startswith(b"BZh"):
        return "bz2"
    if head.startswith(b"\xfd7zXZ\x00"):
        return "xz"
    if head[257:262] == b"ustar":
        return "tar"
    if head[:3] == b"ply" and head[3:4] in (b"\n", b"\r"):
        return "ply"
    # binary STL: an 80-byte header, a triangle count, 50 bytes per triangle
    if size >= 134 and 84 + 50 * int.from_bytes(head[80:84], "little") == size:
        return "stl"
    text = head[:4096].decode("utf-8", "replace").lstrip("\ufeff \t\r\n")
    low = text.lower()
    if low.startswith("solid") and "facet" in low:
        return "stl"
    if low.split(None, 1)[:1] in (["off"], ["coff"]):
        return "off"
    if low.startswith("{") and '"asset"' in low:
        return "gltf"
    if "<collada" in low:
        return "dae"
    if "<svg" in low:
        return "svg"
    if re.search(r"^\s*0\s*\n\s*section\s*$", low, re.M):
        return "dxf"
    if re.search(r"^v\s+\S+\s+\S+\s+\S+", text, re.M):
        return "obj"
    return None


def _is_binary(head):
    """True when the bytes are not text (a NUL byte, or not UTF-8 before the last char)."""
    if b"\x00" in head:
        return True
    try:
        head.decode("utf-8")
    except UnicodeDecodeError as exc:
        return exc.start < len(head) - 3
    return False


def _decompress(path, kind, where):
    import bz2
    import gzip
    import lzma

    opener = {"gz": gzip.open, "bz2": bz2.open, "xz": lzma.open}[kind]
    try:
        with opener(path, "rb") as fh:
            return fh.read()
    except Exception as exc:                  # BadGzipFile, OSError, EOFError, LZMAError
        raise GeometryError(f"{where}: not a valid {_name(kind)} "
                            f"({type(exc).__name__}: {_one_line(exc)})") from exc


def _members(source, ftype):
    """' (files: a, b, ...)' of an archive, for a message; '' if it cannot be listed."""
    import tarfile
    import zipfile

    try:
        src = source()
        if ftype == "zip":
            with zipfile.ZipFile(src) as z:
                names = z.namelist()
        else:
            with (tarfile.open(src) if isinstance(src, str)
                  else tarfile.open(fileobj=src)) as t:
                names = t.getnames()
    except Exception:                          # only a nicety of the message
        return ""
    shown = ", ".join(names[:4]) + (f", ... ({len(names)} files)" if len(names) > 4 else "")
    return f" (files: {_one_line(shown)})" if names else " (it is empty)"


@contextlib.contextmanager
def _quiet_reader():
    """Keep trimesh's own diagnostics off stderr while it reads a file: meshladar accepts
    the file or rejects it with its own one-line message. trimesh logs without a handler, so
    Python's last-resort handler would print its warnings (some with tracebacks); its
    ``warnings.warn`` calls (deprecations) are silenced in this scope only."""
    import logging
    import warnings

    logger = logging.getLogger("trimesh")
    handler = logging.NullHandler()
    logger.addHandler(handler)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            yield
    finally:
        logger.removeHandler(handler)


def _one_line(text):
    """``text`` on one line (whitespace runs collapsed, control characters escaped), cut to
    _MAX_REASON characters."""
    s = _printable(" ".join(str(text).split()))
    return s if len(s) <= _MAX_REASON else s[: _MAX_REASON - 3] + "..."


def _printable(path):
    """A path for a one-line message: line breaks and other control characters escaped."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in path)


# ------------------------------------------------------------------ analytic tessellations

class _PrismNormal:
    """Exact outward normal of an extruded ellipse (x-y gradient of its implicit function
    on the sides, ±z on the caps). A plain class, so that parts pickle to worker processes."""

    def __init__(self, center, axes, angle, lo, hi):
        self.center, self.axes, self.angle, self.lo, self.hi = center, axes, angle, lo, hi

    def __call__(self, p):
        from .shapes import ellipse_normal

        p = np.asarray(p, dtype=np.float64)
        a, b = self.axes
        nx, ny = ellipse_normal(self.center, self.axes, self.angle, p[:, 0], p[:, 1])
        out = np.stack([nx, ny, np.zeros_like(nx)], -1)
        eps = CAP_REL * max(a, b, self.hi - self.lo)
        top = np.abs(p[:, 2] - self.hi) < eps
        bottom = np.abs(p[:, 2] - self.lo) < eps
        out[top | bottom] = 0.0
        out[top, 2] = 1.0
        out[bottom, 2] = -1.0
        return out

    def curvature_radius(self, p):
        """Radius of curvature of the cross-section at the points' eccentric angle (inf on
        the caps): (a² sin²t + b² cos²t)^(3/2) / (a b)."""
        from .shapes import to_frame

        p = np.asarray(p, dtype=np.float64)
        (cx, cy), (a, b) = self.center, self.axes
        xl, yl = to_frame(self.angle, p[:, 0] - cx, p[:, 1] - cy)
        t = np.arctan2(yl / b, xl / a)
        rho = (a * a * np.sin(t) ** 2 + b * b * np.cos(t) ** 2) ** 1.5 / (a * b)
        eps = CAP_REL * max(a, b, self.hi - self.lo)
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
    check_size("segments", n, 400, f"a prism of {n} segments", "use fewer segments")
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
    the faces around that corner's point that lie within ``crease_deg`` of the face's own
    normal (so shared smooth edges blend and creases stay sharp).

    Faces meet at a point when their corners have the same position (exact float equality),
    whatever the vertex indices: a file's UV seams and split normals store one point as
    several vertices, and they are not creases.
    """
    from . import _kernels

    fn, area = part.face_normals_areas()
    point_of, n_points = _point_index(part.vertices)
    f = np.ascontiguousarray(point_of[part.faces], dtype=np.int64)
    order = np.argsort(f.ravel(), kind="stable")
    point_at = f.ravel()[order]
    face_of = order // 3
    ptr = np.searchsorted(point_at, np.arange(n_points + 1))
    out = np.zeros((len(f), 3, 3))
    _kernels.corner_normals(f, fn, area, ptr, face_of, math.cos(math.radians(crease_deg)), out)
    return out


def _point_index(vertices):
    """((n,) int64, k): each vertex's index among the k distinct positions, by exact float
    equality (-0.0 equals 0.0), numbered in lexicographic order of the positions."""
    v = np.asarray(vertices, dtype=np.float64)
    order = np.lexsort(v.T[::-1])
    s = v[order]
    new = np.ones(len(v), dtype=bool)
    new[1:] = np.any(s[1:] != s[:-1], axis=1)
    out = np.empty(len(v), dtype=np.int64)
    out[order] = np.cumsum(new) - 1
    return out, int(new.sum())
