"""Embree scenes of a mesh scene's triangles: the geometry a worker traces, built at unit
size, and a per-process cache of scenes keyed by content."""

from __future__ import annotations

import math
import threading
import warnings

import numpy as np

from .._validate import check_choice
from ..errors import MeshladarWarning, ParameterError
from ..precision import FAR_RATIO as _FAR_RATIO
from ..precision import SCENE_RADIUS_RANGE
from ..scene import Scene


class _Geometry:
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
        # each face's plane n·p = d in shifted coordinates (float64), for exact hit distances
        self.plane_d = np.einsum("ij,ij->i", self.face_normals, shifted[self.faces[:, 0]])
        self.hull = scene.hull_points() - self.center
        self.normals = normals
        self.corner = None
        if normals == "smooth":
            from ..mesh import corner_normals

            self.corner = np.concatenate([corner_normals(p) for p in parts])
        self.exact = [p.exact_normal for p in parts]
        if normals == "exact" and any(e is None for e in self.exact):
            missing = [p.name for p in parts if p.exact_normal is None]
            raise ParameterError(f"normals='exact' needs parts tessellated from analytic shapes; "
                                 f"{missing[0]!r} has no exact normal (use 'flat' or 'smooth')")
        self.key = _digest(self.vertices, self.faces)



def geometry(scene: Scene, normals: str) -> _Geometry:
    """The scene's traced geometry for a normal mode, built once per scene and mode: a
    Scene's parts are immutable, so a second call (another view, another coating, the
    viewer) reuses the concatenated arrays, face planes, hull and content digest."""
    cache = scene.__dict__.setdefault("_geometries", {})
    geo = cache.get(normals)
    if geo is None:
        geo = cache[normals] = _Geometry(scene, normals)
    return geo


def _check_scale(radius, offset):
    lo, hi = SCENE_RADIUS_RANGE
    if not lo <= radius <= hi:
        raise ParameterError(f"scene: the mesh's bounding radius is {radius:.3g} scene units; "
                             f"the mesh engine traces sizes in [{lo:g}, {hi:g}]: rescale the "
                             "mesh (e.g. to metres or millimetres)")
    if offset > _FAR_RATIO * radius:
        warnings.warn(f"the mesh (radius {radius:.3g}) lies {offset:.3g} from the origin: ranges "
                      f"carry only ~{offset * 2.0 ** -53 / radius:.1g} of its size in float64; "
                      "move it near the origin", MeshladarWarning, stacklevel=4)



def _digest(v, f):
    import hashlib

    h = hashlib.sha1(v.tobytes())
    h.update(f.tobytes())
    return h.hexdigest()


#: The mesh engine's ray casters. "packets": coherent packets of the CPU's native width,
#: cast through the Embree 4 library that the embreex wheel ships (:mod:`.embree4`);
#: "embreex": embreex's own run(), one ray at a time, the reference; "auto": packets when
#: they load, else embreex (said once, in a warning).
BACKENDS = ("auto", "packets", "embreex")
_FALLBACK_SAID = False


def resolve_backend(backend):
    """The backend a run uses: "packets" or "embreex" (see :data:`BACKENDS`)."""
    check_choice("backend", backend, BACKENDS)
    if backend == "embreex":
        return backend
    from . import embree4

    ok, why = embree4.available()
    if ok:
        return "packets"
    if backend == "packets":
        raise ParameterError(f"backend='packets' cannot load here ({why}); use "
                             "backend='embreex' or 'auto'")
    global _FALLBACK_SAID
    if not _FALLBACK_SAID:
        _FALLBACK_SAID = True
        warnings.warn(f"the packet backend cannot load ({why}): the mesh engine casts with "
                      "embreex, one ray at a time (backend='embreex'); the numbers are the "
                      "same, slower", MeshladarWarning, stacklevel=4)
    return "embreex"


#: Embree scenes built in this process, most recent last, keyed by the geometry's content
#: and the backend: alternating between a few meshes (a study, a comparison) reuses each
#: one's BVH. Threads of one run share them (the lock guards the cache, not the casts).
_EMBREE_CACHE: dict = {}
_EMBREE_CACHE_SIZE = 4
_CACHE_LOCK = threading.Lock()


def _embree_scene(geo: _Geometry, backend: str = "embreex"):
    """The Embree scene of the geometry for a resolved backend, built once per process."""
    with _CACHE_LOCK:
        key = (geo.key, backend)
        scene = _EMBREE_CACHE.pop(key, None)
        if scene is None:
            unit = np.ascontiguousarray(geo.shifted / geo.scale, dtype=np.float32)
            raw = _packet_scene(unit, geo.faces32) if backend == "packets" else \
                _embreex_scene(unit, geo.faces32)
            scene = _Embree(raw, geo.scale)
            while len(_EMBREE_CACHE) >= _EMBREE_CACHE_SIZE:
                del _EMBREE_CACHE[next(iter(_EMBREE_CACHE))]       # the least recently used
        _EMBREE_CACHE[key] = scene
        return scene


def _embreex_scene(vertices, faces):
    try:
        from embreex import rtcore_scene
        from embreex.mesh_construction import TriangleMesh
    except ImportError as exc:  # pragma: no cover - embreex is a core dependency
        raise ImportError("the mesh model needs embreex: pip install embreex") from exc
    # robust mode: watertight ray-triangle tests, so a ray through a shared edge (the
    # diagonal of a prism's side quad crosses the mid-height slice plane) cannot slip
    # between the two triangles
    raw = rtcore_scene.EmbreeScene(robust=True)
    TriangleMesh(raw, vertices, faces)
    return raw


class _Packets:
    """A packet scene behind embreex's ``run`` interface (one direction for all rays, or one
    per ray), so every path of the engine casts through either backend unchanged."""

    def __init__(self, scene):
        self.scene = scene

    def run(self, origins, directions, output=None, query="INTERSECT"):
        d = np.asarray(directions, dtype=np.float32).reshape(-1, 3)
        if query == "OCCLUDED":
            return np.where(self.scene.occluded_grid(origins, d), 0, -1)
        prim, tfar, u, v = self.scene.cast_grid(origins, d, barycentrics=True)
        return {"primID": prim, "tfar": tfar, "u": u, "v": v}


    def cast_bin_grid(self, plan, direction, spacing, scale, inverse, bins, receiver=None):
        """One view from grid to bins in one compiled loop (see
        :func:`.embree4.cast_bin_grid`): ``plan`` is :func:`.grid._grid_plan`'s,
        ``bins`` the weigh-and-bin arguments from ``plane_d`` to ``footprint``;
        ``receiver`` (direction, lift) makes the view bistatic."""
        from . import embree4

        s, t, du, dv, u, v, L = plan
        sc = self.scene
        lib = sc.lib
        empty = np.empty((0, 0), np.float32)
        w = np.asarray(direction, dtype=np.float64)
        return embree4.cast_bin_grid(
            lib.intersect[lib.width], sc._live(), lib.width,
            embree4.RTC_RAY_QUERY_FLAG_COHERENT, s.astype(np.float32), t.astype(np.float32),
            empty if du is None else du, empty if dv is None else dv, np.float32(spacing),
            u.astype(np.float32), v.astype(np.float32), (L * w).astype(np.float32),
            (-w).astype(np.float32)[None, :], np.float32(inverse), float(scale), *bins,
            lib.occluded[lib.width],
            np.empty(0) if receiver is None else np.asarray(receiver[0], np.float64),
            0.0 if receiver is None else float(receiver[1]))


def _packet_scene(vertices, faces):
    from . import embree4

    return _Packets(embree4.Scene(vertices, faces, robust=True))


class _Embree:
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
        """Whether the backend weighs and bins inside its cast (the packet backend)."""
        return hasattr(self.scene, "cast_bin_grid")

    def cast_bin_grid(self, plan, direction, spacing, bins, receiver=None):
        return self.scene.cast_bin_grid(plan, direction, spacing, self.scale, self.inverse,
                                        bins, receiver)

    def run(self, origins, directions, **kwargs):
        if self.scale != 1.0:
            origins = origins * self.inverse
        res = self.scene.run(origins, directions, **kwargs)
        if self.scale != 1.0 and isinstance(res, dict):
            with np.errstate(over="ignore"):        # a miss's far distance: inf
                res["tfar"] = res["tfar"] * np.float32(self.scale)
        return res
