"""Reading mesh files (and trimesh objects) as the parts of a scene.

Any format trimesh reads: STL, OBJ (its named objects as parts), PLY, OFF, GLB/glTF with
parts, ZIP and tar archives, .gz/.bz2/.xz files, 3MF and COLLADA with their optional
readers. Only vertices, faces and part names are read (a :class:`TriangleMesh` per part);
vertices at the same position are merged. trimesh is imported lazily, when a file other
than a binary STL (:mod:`.stl`, read with numpy) is read. Every way a file can fail is one
:class:`~meshladar.errors.GeometryError` naming the file; what a reader prints while it reads
is kept off the terminal (and quoted in that error).
"""

from __future__ import annotations

import io
import os
import re
from typing import NamedTuple

import numpy as np

from ..errors import GeometryError
from ..precision import WELD_REL as _WELD_REL
from .archives import (_COMPRESSED, _DRAWINGS, _HEAD_BYTES, _NAMES, _OPTIONAL_READERS, _TAR,
                       _count, _decompress, check_archive, _is_binary, _label, _members, _name, _needs,
                       _one_line, _printable, _quiet_reader, _readable_formats, _sniff,
                       _suffix, _with_output)
from .part import _point_index
from .stl import binary_stl

__all__ = ["load_parts", "TriangleMesh"]


class TriangleMesh(NamedTuple):
    """A part as :func:`load_parts` reads it: its vertices and faces, nothing else
    (``trimesh.Trimesh(*mesh)`` makes a trimesh of it).

    Attributes
    ----------
    vertices : (n, 3) float64 numpy.ndarray
        The vertices, in the file's units and world coordinates.
    faces : (m, 3) int64 numpy.ndarray
        Each triangle's three vertex indices, in the file's order and winding.
    """

    vertices: np.ndarray
    faces: np.ndarray


def load_parts(mesh_or_path):
    """Load a mesh file (or take a trimesh object) as the triangle meshes of a scene.

    Parameters
    ----------
    mesh_or_path : str, os.PathLike, trimesh.Trimesh, trimesh.Scene or TriangleMesh
        A file of any format trimesh reads: STL (ASCII or binary), OBJ, PLY, OFF, GLB/glTF
        (several parts, each placed by its node's transform), OBJ with named objects (one
        part per ``o NAME``, in file order), ZIP and tar archives; 3MF,
        COLLADA and others when their optional readers are installed. ``.gz``, ``.bz2`` and
        ``.xz`` files are decompressed and their inner file read. The format comes from the
        suffix, or from the content when the suffix is unknown or its reader fails (a binary
        STL named ``.dat`` loads). Textures, colours and normals in the file are not read.

    Returns
    -------
    list of (str, TriangleMesh)
        Part names and meshes in world coordinates, each fresh arrays of vertices and faces
        only (:class:`TriangleMesh`), with vertices at the same position merged (positions rounded to a grid of
        2⁻⁴⁰ times the mesh's largest extent, from its lowest corner) and unreferenced
        vertices dropped.

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
    if suffix in _TAR or kind == "zip" or suffix in ("zip", "3mf"):
        check_archive(path, head, where)
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
    try:
        corners = binary_stl(path, size, head) if suffix == "stl" else None
    except (OSError, MemoryError) as exc:
        raise GeometryError(f"{where}: cannot read the file "
                            f"({_one_line(getattr(exc, 'strerror', None) or exc)})") from exc
    if corners is not None:                 # trimesh's reading, without importing it
        return [("mesh", TriangleMesh(*_weld(*corners, where)))]
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
            with _quiet_reader() as said:
                # an OBJ's named objects ('o NAME') are parts, as a glTF's nodes are
                loaded = trimesh.load(source(), file_type=ftype, resolver=resolver,
                                      process=False, skip_materials=True,
                                      **({"split_objects": True} if ftype == "obj" else {}))
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
                    parts = _parts_of(loaded, where, default_name)
                    return _in_file_order(parts, source) if ftype == "obj" else parts
                except GeometryError as exc:
                    err = exc
        err = _with_output(err, said)
        if first is None or (reached_geometry and not first[1]):
            first = (err, reached_geometry)
    raise first[0]

def _in_file_order(parts, source):
    """An OBJ's parts named and ordered by its objects ('o NAME'): in the order they come in
    the file (trimesh builds them last first), a part trimesh split off an object by material
    ('NAME_1') after its object, and a file of one object named by it (trimesh's one mesh
    has lost the name), as a glTF's single node is."""
    try:
        src = source()
        with (open(src, "rb") if isinstance(src, str) else src) as fh:
            text = fh.read()
    except OSError:                            # only names and order: keep trimesh's
        return parts
    names = re.findall(rb"^o[ \t]+(\S.*?)[ \t\r]*$", text, re.M)
    order = {n.decode("utf-8", "replace"): i for i, n in reversed(list(enumerate(names)))}
    if len(parts) == 1:
        return [(next(iter(order)), parts[0][1])] if len(order) == 1 else parts

    def rank(item):
        name = item[0]
        return order.get(name, order.get(name.rsplit("_", 1)[0], len(order)))

    return sorted(parts, key=rank)


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
    """(name, welded mesh) of each triangle mesh in a trimesh object (or in a
    :class:`TriangleMesh`, as :func:`load_parts` gives), or a GeometryError saying what the
    object holds instead."""
    if isinstance(loaded, TriangleMesh):
        return [(default_name, TriangleMesh(*_weld(loaded.vertices, loaded.faces, where)))]
    import trimesh

    if isinstance(loaded, trimesh.Scene):
        out, other = [], []
        for node in loaded.graph.nodes_geometry:
            transform, geom_name = loaded.graph[node]
            g = loaded.geometry[geom_name]
            if isinstance(g, trimesh.Trimesh) and len(g.faces):
                name = _part_name(str(node), str(geom_name), {n for n, _ in out})
                m = trimesh.Trimesh(*_weld(g.vertices, g.faces, f"{where}: part {name!r}"),
                                    process=False)
                m.apply_transform(transform)
                out.append((name, TriangleMesh(np.asarray(m.vertices, np.float64),
                                               np.asarray(m.faces, np.int64))))
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
        return [(str(meta.get("name") or default_name),
                 TriangleMesh(*_weld(loaded.vertices, loaded.faces, where)))]
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


def _weld(vertices, faces, where):
    """(vertices, faces): fresh arrays of a mesh's vertices and faces only, with the
    vertices at the same position merged into one (STL stores each triangle's own) and
    unreferenced vertices dropped, after checking that every vertex is finite and every
    face indexes a vertex.

    Nothing else is kept: meshladar needs positions and faces, and copying a texture needs
    Pillow. Merging by position alone also joins the vertices a file splits at UV seams and
    at split normals, which are not creases (:func:`corner_normals` finds creases from the
    face normals); trimesh's own merge keeps them apart on a textured mesh, and rounds to
    1e-8 absolute, which merges the vertices of a nanometre-sized part and overflows far
    from the origin. Positions are compared relative to the mesh's size (_WELD_REL).
    """
    v = np.array(vertices, dtype=np.float64)              # a copy: the caller's mesh stays
    f = np.asarray(faces)
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
        # column by column: numpy's min over axis 0 of (n, 3) is ~25x slower
        low = np.array([v[:, c].min() for c in range(3)])
        size = max(float(v[:, c].max() - low[c]) for c in range(3))
        key = np.round((v - low) / (size * _WELD_REL)) if size > 0 else 0.0 * v
        point, n = _point_index(key)
        first = np.full(n, len(v))
        np.minimum.at(first, point, np.arange(len(v)))     # each point's first vertex
        rank = np.empty(n, dtype=np.int64)
        rank[np.argsort(first)] = np.arange(n)               # points numbered in file order
        v, f = v[np.sort(first)], rank[point][f]
    return v, f.astype(np.int64)
