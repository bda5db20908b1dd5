"""Deprecated alias of meshladar.meshes (one release).

Every public name of :mod:`meshladar.meshes` is re-exported unchanged. ``corner_normals`` and
``CREASE_DEG`` (which load numba) and the private helpers other modules imported from here
(``_icosphere``, ``_part_name``, ...) are resolved on first use by :func:`__getattr__`, from
the module of :mod:`meshladar.meshes` that now holds them; that hook is where the deprecation
warning will be raised.
"""

from __future__ import annotations

from ._deprecated import warn_moved
import importlib

from . import meshes
from .meshes import (MeshPart, convex_hull, ellipsoid, fibonacci_sphere, icosphere,
                     inspect_parts, load_parts, part_from_trimesh, prism, sphere)

warn_moved("mesh", "meshes")

__all__ = ["MeshPart", "load_parts", "part_from_trimesh", "prism", "sphere", "ellipsoid",
           "fibonacci_sphere", "icosphere", "corner_normals", "CREASE_DEG", "inspect_parts",
           "convex_hull"]

#: The old module's private helpers: name -> the meshladar.meshes submodule holding it now
#: (``_icosphere`` is now the public ``icosphere``).
_MOVED = {"_clean": "checks", "_bodies": "checks", "_read_file": "formats", "_read": "formats",
          "_part_name": "formats", "_parts_of": "formats", "_describe": "formats",
          "_not_a_mesh": "formats", "_weld": "formats", "_sniff": "archives",
          "_suffix": "archives", "_is_binary": "archives", "_decompress": "archives",
          "_members": "archives", "_needs": "archives", "_readable_formats": "archives",
          "_one_line": "archives", "_printable": "archives", "_point_index": "part",
          "_PrismNormal": "primitives", "_EllipsoidNormal": "primitives",
          "corner_normals": "normals", "CREASE_DEG": "normals"}


def __getattr__(name):
    if name == "_icosphere":
        return icosphere
    if name in _MOVED:
        return getattr(importlib.import_module(f"{meshes.__name__}.{_MOVED[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
