"""The packet backend: coherent Embree 4 packets through ctypes and numba
(:mod:`.embree4`), behind embreex's ``run`` interface, registered in
:data:`meshladar.raytrace.backends.REGISTRY` as "packets". Its scenes also serve the weigh
stage's fused loop (:mod:`meshladar.weighing.fused`)."""

from __future__ import annotations

import numpy as np

from . import embree4
from .backends import Backend, register

__all__ = ["PacketScene", "build"]


class PacketScene:
    """A packet scene behind embreex's ``run`` interface (one direction for all rays, or one
    per ray), so every path of the engine casts through either backend unchanged."""

    #: the weigh stage's fused loop casts with this scene (:mod:`meshladar.weighing.fused`)
    fused = True

    def __init__(self, scene):
        self.scene = scene

    def run(self, origins, directions, output=None, query="INTERSECT"):
        d = np.asarray(directions, dtype=np.float32).reshape(-1, 3)
        if query == "OCCLUDED":
            return np.where(self.scene.occluded_grid(origins, d), 0, -1)
        got = self.scene.cast_grid(origins, d, barycentrics=True)
        return {"primID": got.prim, "tfar": got.tfar, "u": got.u, "v": got.v}


def build(vertices, faces):
    """A packet scene of float32 vertices (n, 3) and int32 faces (m, 3), robust mode."""
    return PacketScene(embree4.PacketGeometry(vertices, faces, robust=True))


register(Backend("packets", build, embree4.available, fused=True))
