"""The packet backend: coherent Embree 4 packets through ctypes and numba
(:mod:`.embree4`), behind embreex's ``run`` interface, registered in
:data:`meshladar.raytrace.backends.REGISTRY` as "packets". Its scenes also serve the weigh
stage's fused loop (:mod:`meshladar.weighing.fused`)."""

from __future__ import annotations

import numpy as np

from . import embree4
from .backends import Backend, register

__all__ = ["PacketScene", "build", "build_raster"]


class PacketScene:
    """A packet scene behind embreex's ``run`` interface (one direction for all rays, or one
    per ray), so every path of the engine casts through either backend unchanged.

    Parameters
    ----------
    scene : PacketGeometry
        The committed packet scene (:class:`meshladar.raytrace.embree4.PacketGeometry`)
        that :meth:`run` casts with.

    Attributes
    ----------
    scene : PacketGeometry
        As given.
    fused : bool
        True (a class attribute): the weigh stage's fused loop can cast with this scene.
    """

    #: the weigh stage's fused loop casts with this scene (:mod:`meshladar.weighing.fused`)
    fused = True
    #: (vertices, faces) where the fused loop finds an orthographic view's first hits by
    #: drawing them (:func:`build_raster`), else None
    raster = None

    def __init__(self, scene):
        self.scene = scene

    def run(self, origins, directions, output=None, query="INTERSECT", columns=0,
            single=False):
        """Cast rays as embreex's ``run`` does: first hits, or occlusion.

        Parameters
        ----------
        origins : (n, 3) array_like
            Ray origins, cast as float32.
        directions : (3,), (1, 3) or (n, 3) array_like
            One direction for every ray, or one per ray, cast as float32; distances come
            back in units of its length.
        output : object, optional
            Ignored: accepted for embreex's signature (the result is always the dict
            below).
        query : str
            ``"OCCLUDED"`` for the occlusion query; any other value (default
            ``"INTERSECT"``) casts for first hits.
        columns : int
            First hits: the length of the rows of a grid of rays (row-major), cast in tiles
            (:meth:`meshladar.raytrace.embree4.PacketGeometry.cast_grid`); 0 (default):
            packets of consecutive rays.
        single : bool
            First hits: cast the rays one at a time (``rtcIntersect1``), as a grid sparser
            than its faces is cast fastest; default False.

        Returns
        -------
        dict or numpy.ndarray
            First hits: a dict of (n,) arrays ``"primID"`` (int32, the hit face's index,
            -1 on a miss), ``"tfar"`` (float32, the hit distance, inf on a miss), ``"u"``
            and ``"v"`` (float32, the hit's barycentrics). ``"OCCLUDED"``: (n,) integers,
            0 where the ray meets anything and -1 where it does not (embreex's
            convention).

        Raises
        ------
        ValueError
            When ``directions`` is neither one direction nor one per ray.
        RuntimeError
            When the scene has been released.
        """
        d = np.asarray(directions, dtype=np.float32).reshape(-1, 3)
        if query == "OCCLUDED":
            return np.where(self.scene.occluded_grid(origins, d), 0, -1)
        got = self.scene.cast_grid(origins, d, barycentrics=True, columns=columns,
                                   single=single)
        return {"primID": got.prim, "tfar": got.tfar, "u": got.u, "v": got.v}


def build(vertices, faces):
    """A packet scene of float32 vertices (n, 3) and int32 faces (m, 3), robust mode.

    Parameters
    ----------
    vertices : (n, 3) numpy.ndarray
        The triangles' corners (float32, as a backend's ``build`` receives them; copied
        as float32 into the scene's shared buffer).
    faces : (m, 3) numpy.ndarray
        Each triangle's three vertex indices into ``vertices`` (int32; converted to uint32).

    Returns
    -------
    PacketScene
        A :class:`meshladar.raytrace.embree4.PacketGeometry` built with ``robust=True``,
        behind embreex's ``run`` interface.

    Raises
    ------
    OSError
        When the Embree 4 library cannot be loaded (:func:`meshladar.raytrace.embree4.library`).
    ValueError
        When ``vertices`` or ``faces`` is not (k, 3), or a face index is out of range.
    RuntimeError
        When Embree reports an error building the scene.
    """
    return PacketScene(embree4.PacketGeometry(vertices, faces, robust=True))


def build_raster(vertices, faces):
    """:func:`build`'s scene, which also keeps its vertices (float64 of the float32 ones
    Embree holds) and faces, so that the fused loop finds a dense orthographic view's
    first hits by drawing its faces into a depth buffer over the ray grid
    (:mod:`meshladar.weighing._raster_kernels`; the "raster" backend). Everything else
    casts with Embree, as :func:`build`'s.

    Parameters
    ----------
    vertices, faces
        As :func:`build`.

    Returns
    -------
    PacketScene
        With ``raster`` = (vertices (n, 3) float64, faces (m, 3) int32).
    """
    scene = build(vertices, faces)
    scene.raster = (np.asarray(vertices, np.float32).astype(np.float64),
                    np.ascontiguousarray(faces, np.int32))
    return scene


register(Backend("packets", build, embree4.available, fused=True))
register(Backend("raster", build_raster, embree4.available, fused=True))
