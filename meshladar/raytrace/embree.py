"""Embree scenes of a mesh scene's triangles: the geometry a worker traces, built at unit
size, and a per-process cache of scenes keyed by content."""

from __future__ import annotations

import hashlib
import math
import threading
import warnings

import numpy as np

from ..errors import MeshladarWarning, ParameterError, user_stacklevel
from ..precision import FAR_RATIO as _FAR_RATIO
from ..precision import SCENE_RADIUS_RANGE
from ..meshes import corner_normals
from ..scene import Scene
from ._support import ClusteredPoints, axes_extents, points_extent
from .backends import BACKENDS, resolve_backend
from .backends import backend as get_backend

#: From this many support points and views on, a view's extents are found over clusters
#: of the points (:mod:`._support`): an extent over a sphere's 41k hull points takes 10 µs
#: so and 100 µs projected, but the clusters cost as much as some 55 extents to build (5 ms;
#: 0.1 s for 655k points), about 30 views' planning.
CLUSTER_MIN_POINTS = 4096
CLUSTER_MIN_VIEWS = 32


class Geometry:
    """Everything a worker needs to trace: float64 originals and float32 shifted copies."""

    def __init__(self, scene: Scene, normals: str):
        parts = scene.parts
        offs = np.cumsum([0] + [len(p.vertices) for p in parts])
        self.vertices = np.concatenate([p.vertices for p in parts])
        self.faces = np.concatenate([p.faces + o for p, o in zip(parts, offs[:-1])])
        self.material = np.concatenate([p.material for p in parts]).astype(np.int32)
        self.part_of = np.concatenate([np.full(len(p.faces), i, np.int32)
                                       for i, p in enumerate(parts)])
        lo, hi = self.vertices.min(axis=0), self.vertices.max(axis=0)
        self.center = 0.5 * (lo + hi)
        shifted = self.vertices - self.center
        self.radius = float(np.max(np.linalg.norm(shifted, axis=1)))
        self.shifted = np.ascontiguousarray(shifted)
        _check_scale(self.radius, np.abs(self.center).max())
        # Embree's geometry is divided by this power of two (exact in float32): unit size
        self.scale = 2.0 ** math.ceil(math.log2(self.radius)) if self.radius > 0 else 1.0
        self.faces32 = np.ascontiguousarray(self.faces, dtype=np.int32)
        # the parts' own face normals (computed once per part, whatever the calls)
        self.face_normals = np.concatenate([p.face_normals_areas()[0] for p in parts])
        # the area of the face a ray hits, on average over rays spread evenly over the
        # surface (Σa² / Σa): how many rays of a grid share a face
        areas = np.concatenate([p.face_normals_areas()[1] for p in parts])
        total = float(areas.sum())
        self.hit_face_area = float(areas @ areas) / total if total > 0 else 0.0
        # each face's plane n·p = d in shifted coordinates (float64), for exact hit distances
        self.plane_d = np.einsum("ij,ij->i", self.face_normals, shifted[self.faces[:, 0]])
        # every extreme of a grid's extent is attained among these points (shifted): every
        # vertex, or the hull's vertices once known (for_views)
        self.support = self.shifted
        self._views, self._clusters = 0, None      # the runs' most views; extents' clusters
        self.lone = None                           # :meth:`for_receivers`
        # 1 where a face's part is closed with outward normals (watertight, not inverted):
        # a ray from outside meets such a part first on a face turned toward it
        report = scene.report
        closed = np.array([w and not i for w, i in zip(report["watertight"],
                                                       report["inverted"])], np.uint8)
        self.closed = np.ascontiguousarray(closed[self.part_of])
        self.for_views(scene, 0)
        self.normals = normals
        self.corner = None
        if normals == "smooth":
            self.corner = np.concatenate([corner_normals(p) for p in parts])
        self.exact = [p.exact_normal for p in parts]
        if normals == "exact" and any(e is None for e in self.exact):
            missing = [p.name for p in parts if p.exact_normal is None]
            raise ParameterError(f"normals='exact' needs parts tessellated from analytic shapes; "
                                 f"{missing[0]!r} has no exact normal (use 'flat' or 'smooth')")
        self.key = _digest(self.vertices, self.faces)

    def for_receivers(self, scene, receivers):
        """With bistatic ``receivers`` (not None), set ``lone`` (n_faces,) uint8, once: 1
        on the faces of parts that can see no part, themselves included
        (:meth:`meshladar.scene.Scene.visibility`: a flat part, or a closed convex body,
        alone or among coplanar flat parts), so that no ray leaving the front of such a
        face can meet the scene (a receiver's occlusion ray then need not be cast)."""
        if self.lone is None and receivers is not None:
            free = ~np.asarray(scene.visibility().sees, dtype=bool).any(axis=1)
            self.lone = np.ascontiguousarray(free.astype(np.uint8)[self.part_of])

    def for_views(self, scene, n_views):
        """Take the extents of ``n_views`` views' grids over the scene's
        :meth:`~meshladar.scene.Scene.support_points` for that many views (its hull's
        vertices when known or when the views are many, else every vertex)."""
        points = scene.support_points(n_views)
        self._views = max(self._views, n_views)
        if len(points) < len(self.support):
            self.support = points - self.center
            self._clusters = None

    def extent(self, u, origin=None):
        """(least, greatest) q·u over the support points (shifted), q = p − ``origin``
        (default q = p), exactly: over clusters of them (:mod:`._support`, built on first
        use) for runs of :data:`CLUSTER_MIN_VIEWS` views or more over
        :data:`CLUSTER_MIN_POINTS` points or more, else over every point (the same
        operations: the same bits)."""
        clusters = self._clustered()
        if clusters is not None:
            return clusters.extent(u, origin)
        return points_extent(self.support, u, origin)

    def extents(self, axes):
        """:meth:`extent` along each row of ``axes`` (k, 3), in one compiled pass: (k, 2)
        float64 (least, greatest), the same numbers."""
        clusters = self._clustered()
        if clusters is not None:
            return clusters.extents(axes)
        return axes_extents(self.support, axes)

    def seen_extent(self, u, w, scale, origin):
        """(least, greatest) (q·u)·scale / (−q·w) over the support points (shifted),
        q = p − ``origin``: their coordinate along u on a plane ``scale`` in front of a
        pinhole at ``origin`` looking along −w; as :meth:`extent`, exactly."""
        clusters = self._clustered()
        if clusters is not None:
            return clusters.seen_extent(u, w, scale, origin)
        return points_extent(self.support, u, origin, w, scale)

    def _clustered(self):
        if len(self.support) < CLUSTER_MIN_POINTS or self._views < CLUSTER_MIN_VIEWS:
            return None
        if self._clusters is None:
            self._clusters = ClusteredPoints(self.support)
        return self._clusters


def geometry(scene: Scene, normals: str) -> Geometry:
    """The scene's traced geometry for a normal mode, built once per scene and mode: a
    Scene's parts are immutable, so a second call (another view, another coating, the
    viewer) reuses the concatenated arrays, face planes, hull and content digest."""
    return scene.cached(("geometry", normals), lambda: Geometry(scene, normals))


def _check_scale(radius, offset):
    lo, hi = SCENE_RADIUS_RANGE
    if not lo <= radius <= hi:
        raise ParameterError(f"scene: the mesh's bounding radius is {radius:.3g} scene units; "
                             f"the mesh engine traces sizes in [{lo:g}, {hi:g}]: rescale the "
                             "mesh (e.g. to metres or millimetres)")
    if offset > _FAR_RATIO * radius:
        warnings.warn(f"the mesh (radius {radius:.3g}) lies {offset:.3g} from the origin: ranges "
                      f"carry only ~{offset * 2.0 ** -53 / radius:.1g} of its size in float64; "
                      "move it near the origin", MeshladarWarning, stacklevel=user_stacklevel())



def _digest(v, f):
    h = hashlib.sha1(v.tobytes())
    h.update(f.tobytes())
    return h.hexdigest()


#: The mesh engine's ray casters. "packets": coherent packets of the CPU's native width,
#: cast through the Embree 4 library that the embreex wheel ships (:mod:`.embree4`);
#: "raster": the same, a dense orthographic view's first hits drawn into a depth buffer;
#: "embreex": embreex's own run(), one ray at a time, the reference; "auto": raster when
#: the packets load, else embreex (said once, in a warning).
#: Embree scenes built in this process, most recent last, keyed by the geometry's content
#: and the backend: alternating between a few meshes (a study, a comparison) reuses each
#: one's BVH. Threads of one run share them (the lock guards the cache, not the casts).
_EMBREE_CACHE: dict = {}
_EMBREE_CACHE_SIZE = 4
_CACHE_LOCK = threading.Lock()


def embree_scene(geo: Geometry, backend: str = "embreex"):
    """The Embree scene of the geometry for a resolved backend, built once per process."""
    with _CACHE_LOCK:
        key = (geo.key, backend)
        scene = _EMBREE_CACHE.pop(key, None)
        if scene is None:
            unit = np.ascontiguousarray(geo.shifted / geo.scale, dtype=np.float32)
            raw = get_backend(backend).build(unit, geo.faces32)
            scene = EmbreeScene(raw, geo.scale)
            while len(_EMBREE_CACHE) >= _EMBREE_CACHE_SIZE:
                del _EMBREE_CACHE[next(iter(_EMBREE_CACHE))]       # the least recently used
        _EMBREE_CACHE[key] = scene
        return scene


class EmbreeScene:
    """An Embree scene built at unit size: origins in, distances out, in the scene's own
    shifted units. Embree misses outright below ~1e-14 and above ~1e13 scene units, so the
    geometry is divided by a power of two near its radius; a power of two scales float32
    exactly, so origins and distances are the same numbers as an unscaled cast."""

    def __init__(self, scene, scale: float):
        self.scene = scene
        self.scale = scale
        self.inverse = np.float32(1.0 / scale)

    @property
    def fused(self):
        """Whether the weigh stage's fused loop can cast with this scene (the packet
        backend's, :mod:`meshladar.weighing.fused`)."""
        return getattr(self.scene, "fused", False)

    @property
    def raster(self):
        """(vertices at unit size (n, 3) float64, faces (m, 3) int32) where the fused loop
        draws a dense orthographic view's first hits (the "raster" backend's scenes), else
        None."""
        return getattr(self.scene, "raster", None)

    @property
    def bins_hits(self):
        """Whether the backend weighs and bins its hits in its own kernel
        (:meth:`cast_bin`: Warp's)."""
        return hasattr(self.scene, "cast_bin")

    def cast_bin(self, origins, direction, bins):
        """The backend's own cast-weigh-bin kernel (see :attr:`bins_hits`) on ``origins``
        as built (shifted coordinates), cast at unit size; returns the back-face hits."""
        return self.scene.cast_bin(origins, direction, self.inverse, self.scale, bins)

    def run(self, origins, directions, columns=0, coherent=True, **kwargs):
        """The backend's ``run`` at unit size; ``columns`` (the rows' length of a grid of
        rays) lets the packet backend cast it in tiles, and ``coherent`` False (a grid
        sparser than its faces: :attr:`meshladar.raytrace.plan.TracePlan.coherent`) one ray
        at a time; both are dropped for the other backends."""
        if self.fused and not coherent:
            kwargs["single"] = True
        elif self.fused and columns:
            kwargs["columns"] = columns
        if self.scale != 1.0:
            origins = origins * self.inverse
        res = self.scene.run(origins, directions, **kwargs)
        if self.scale != 1.0 and isinstance(res, dict):
            with np.errstate(over="ignore"):        # a miss's far distance: inf
                res["tfar"] = res["tfar"] * np.float32(self.scale)
        return res


#: The scene a worker casts with, public for the stages above (forward, weighing).
