"""Triangle-mesh scenes: the :class:`MeshPart` record, file formats and archives, checks,
tessellations of analytic shapes, convex hulls and normals.

A mesh scene is a list of :class:`MeshPart` (vertices, faces, a material index per face, and
optionally the exact normal of the analytic shape it approximates). trimesh is imported only
when a mesh other than a binary STL is loaded, or a mesh is built.

=================  ===========================================================================
module             holds
=================  ===========================================================================
``part``           :class:`MeshPart`, :func:`part_from_trimesh`
``formats``        :func:`load_parts`, :class:`TriangleMesh`: files, trimesh objects
                   (``archives``: sniffing, decompression, archive listings, messages;
                   ``stl``: binary STL read with numpy)
``checks``         :func:`inspect_parts`: degenerate faces, watertight bodies, signed volumes
``primitives``     :func:`prism`, :func:`ellipsoid`, :func:`sphere`, :func:`icosphere`,
                   :func:`fibonacci_sphere`
``hull``           :func:`convex_hull`
``normals``        :func:`corner_normals`, :data:`CREASE_DEG` (compiled twin
                   ``_normals_kernel``; imported on first use, it loads numba)
=================  ===========================================================================

Faces are hit from either side. A hit on a face's back (n·w < 0: an open mesh seen from
behind, or inverted normals) is counted per view in the sinogram's ``info["back_face_hits"]``
and handled by the ``back_faces`` option of tracing: ``"two-sided"`` (default) flips the
normal toward the ladar, ``"ignore"`` lets the face block the ray and return nothing.
"""

from __future__ import annotations

from .._lazy import lazy_attributes as _lazy_attributes

from .checks import inspect_parts
from .formats import TriangleMesh, load_parts
from .hull import convex_hull
from .part import MeshPart, part_from_trimesh
from .primitives import ellipsoid, fibonacci_sphere, icosphere, prism, sphere

__all__ = ["MeshPart", "load_parts", "TriangleMesh", "part_from_trimesh", "prism", "sphere", "ellipsoid",
           "fibonacci_sphere", "icosphere", "corner_normals", "curved_edge_angles", "CREASE_DEG",
           "curved_edge_rates", "inspect_parts",
           "convex_hull"]

# names reached lazily (their module imports numba): name -> submodule
__getattr__, __dir__ = _lazy_attributes(
    __name__, globals(), {"corner_normals": "normals", "curved_edge_angles": "normals",
                          "curved_edge_rates": "normals", "CREASE_DEG": "normals"},
    ("normals", "_normals_kernel"))
