"""A scene's contents, checked and assembled for :class:`meshladar.scene.Scene`: analytic
shapes, which may touch but not overlap; mesh parts and the coatings their faces index; and
the parts of a loaded mesh file with their coatings (one for every part, one per part name,
or one per face).
"""

from __future__ import annotations

import numpy as np

from .brdf import check_brdf
from .errors import GeometryError, ParameterError
from .meshes import MeshPart, load_parts, part_from_trimesh
from .shapes import Shape, _overlap

__all__ = ["checked_shapes", "checked_coatings", "parts_by_face", "parts_by_name",
           "parts_of_items"]


def checked_shapes(shapes) -> tuple:
    """``shapes`` as a tuple, refused unless it is a non-empty sequence of Disk or Ellipse
    of which no two overlap."""
    try:
        shapes = tuple(shapes)
    except TypeError:
        raise ParameterError(f"shapes must be a sequence of Disk or Ellipse; got "
                             f"{type(shapes).__name__}") from None
    if not shapes:
        raise ParameterError("shapes must hold at least one shape; got an empty scene")
    for i, s in enumerate(shapes):
        if not isinstance(s, Shape):
            raise ParameterError(f"shapes[{i}] must be a Disk or an Ellipse; got "
                                 f"{type(s).__name__}")
    for i in range(len(shapes)):
        for j in range(i + 1, len(shapes)):
            if _overlap(shapes[i], shapes[j]):
                raise GeometryError(
                    f"shapes[{i}] and shapes[{j}] overlap; shapes in a scene may touch "
                    "but not overlap (the boundary of their union is not theirs)")
    return shapes


def checked_coatings(parts, materials) -> tuple:
    """The coatings ``materials`` as a tuple, once ``parts`` and ``materials`` are checked:
    lists (or tuples) of MeshPart and of BRDF, every face's material index pointing into
    ``materials``."""
    if not isinstance(materials, (list, tuple)) or not isinstance(parts, (list, tuple)):
        raise ParameterError(f"parts and materials must be lists; got "
                             f"{type(parts).__name__} and {type(materials).__name__}")
    mats = tuple(materials)
    for i, m in enumerate(mats):
        check_brdf(f"materials[{i}]", m)
    for i, p in enumerate(parts):
        if not isinstance(p, MeshPart):
            raise ParameterError(f"parts[{i}] must be a meshladar.meshes.MeshPart; got "
                                 f"{type(p).__name__}")
    for p in parts:
        if len(p.material) and (p.material.min() < 0 or p.material.max() >= len(mats)):
            raise ParameterError(f"{p.name}: face material indices must be in "
                                 f"[0, {len(mats) - 1}]; got {int(p.material.min())}.."
                                 f"{int(p.material.max())}")
    return mats


def parts_by_face(loaded, materials, face_materials, transform):
    """(parts, materials) of a file's single mesh whose faces index the coating list
    ``materials`` through ``face_materials`` (``loaded``: the file's (name, mesh) pairs)."""
    if len(loaded) != 1:
        raise ParameterError("face_materials needs a single mesh; got a scene of "
                             f"{len(loaded)} parts (use materials={{part: m}})")
    if not isinstance(materials, (list, tuple)):
        raise ParameterError("with face_materials, materials must be a list of "
                             "BRDF indexed by face_materials")
    name, m = loaded[0]
    fm = np.asarray(face_materials)
    if fm.shape != (len(m.faces),) or not np.issubdtype(fm.dtype, np.integer):
        raise ParameterError(f"face_materials must be ({len(m.faces)},) integers; got "
                             f"shape {fm.shape}, dtype {fm.dtype}")
    return [part_from_trimesh(m, fm, name=name, transform=transform)], materials


def parts_by_name(loaded, material, materials, transform):
    """(parts, materials) of a file's meshes (``loaded``: its (name, mesh) pairs), each
    coated with ``materials[name]`` or else ``material``; each distinct coating listed once,
    in the parts' order."""
    if materials is not None and not isinstance(materials, dict):
        raise ParameterError(f"materials must be a dict of part name -> coating; got "
                             f"{type(materials).__name__}")
    named = dict(materials or {})
    unknown = sorted(set(named) - {n for n, _ in loaded})
    if unknown:
        raise ParameterError(f"materials: no part named {unknown[0]!r}; parts are "
                             f"{[n for n, _ in loaded]}")
    mats, parts = [], []
    for name, m in loaded:
        coat = named.get(name, material)
        if coat is None:
            raise ParameterError(f"part {name!r} has no material: give material= or "
                                 f"materials={{{name!r}: ...}}")
        check_brdf(f"materials[{name!r}]" if name in named else "material", coat)
        if coat not in mats:
            mats.append(coat)
        parts.append(part_from_trimesh(m, mats.index(coat), name=name, transform=transform))
    return parts, mats


def parts_of_items(items):
    """(parts, materials) of several meshes, ``items`` of (mesh_or_path, material[,
    transform]): the k-th item's parts named ``"<k>:<part name>"``, each distinct coating
    listed once."""
    mats, parts = [], []
    for k, item in enumerate(items):
        if not isinstance(item, (tuple, list)) or len(item) not in (2, 3):
            raise ParameterError(f"items[{k}] must be (mesh, material[, transform]); got "
                                 f"{item!r}")
        mesh, coat = item[0], item[1]
        transform = item[2] if len(item) == 3 else None
        if coat not in mats:
            mats.append(coat)
        for name, m in load_parts(mesh):
            parts.append(part_from_trimesh(m, mats.index(coat), name=f"{k}:{name}",
                                           transform=transform))
    return parts, mats
