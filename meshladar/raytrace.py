"""The mesh engine (``model="mesh"``): Embree first hits, SR weights, range bins.

Per view, an orthographic grid of parallel rays covers the scene's projected extent (the
convex hull's projection, not a fixed square) and travels along −w from just outside the
scene. Embree (embreex) returns each ray's first hit: that is the shadowing, so a monostatic
ladar casts no other ray. Each hit carries its range, cos θ of the chosen normal, the face's
material, and its footprint; weighing turns hits into bins with F(θ)·δA⊥ per ray
(DESIGN.md: P[k] = Σ F(θ_hit) δA⊥ over the rays whose first hit lies in bin k).

Two modes:

* ``mode="slice"`` (views about z): one row of rays in the plane z = z0, spaced δs; each
  ray stands for a strip δs wide and one unit high, so values are per unit height and match
  the analytic 2-D profile of an extruded phantom.
* ``mode="3d"``: a square grid of rays spaced δ (δA⊥ = δ²), any view vectors.

Precision (Embree works in float32): the scene is shifted to its bounding-box centre in
float64 before it is converted, rays start just outside its bounding sphere, and each hit's
distance is recomputed in float64 against the hit face's float64 plane, from the float32
origin exactly as cast: r = −c·w + t − o·w. A scene far from the origin or tiny keeps its
range accuracy relative to its own size, and a surface lying on a bin edge (the paper's
first edge is the disk's top, where the glint peaks) is binned to float64 precision.

Normals: ``"flat"`` (the face's geometric normal, float64), ``"smooth"`` (vertex normals
interpolated with Embree's barycentrics, averaged only across edges sharper than
``CREASE_DEG``), ``"exact"`` (the analytic shape's own normal at the hit point, for scenes
tessellated from analytic shapes).

Grazing incidence: a glossy coating's F grows like 1/cos θ toward a silhouette (A5), an
integrable singularity of the integrand per unit projected area; point samples of it
converge slowly there (~δ^½), so bins at a silhouette are the last to converge for
non-Lambertian coatings. Bins away from silhouettes converge at the facet and ray rates.

Footprint binning (``footprint=True``): a ray of width δ hitting a flat facet covers a range
interval, not a point: along the transverse axis u the range changes at dr/du = (n·u)/(n·w).
The ray's weight is spread over that interval (a box in slice mode; in 3-D the sum of the u
and v boxes, a trapezoid), exactly as the flat facet would return it.
"""

from __future__ import annotations

import math
import os
import warnings
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from ._validate import check_choice, check_flag, check_real, unit_vectors
from .errors import MeshladarWarning, ParameterError
from .ladar import Ladar
from .scene import Scene
from .sinogram import Sinogram
from .precision import FAR_RATIO as _FAR_RATIO
from .precision import MIN_COS_FACET as _MIN_COS_FACET
from .precision import ORIGIN_MARGIN as _ORIGIN_MARGIN
from .precision import RECEIVER_LIFT as _RECEIVER_LIFT
from .precision import REFINE_MIN_COS as _REFINE_MIN_COS
from .precision import SCENE_RADIUS_RANGE

__all__ = ["Hits", "trace", "weigh", "simulate_mesh", "first_hits", "occluded", "NORMALS",
           "MODES", "BACK_FACES", "SAMPLINGS"]

NORMALS = ("flat", "smooth", "exact")
MODES = ("slice", "3d")
BACK_FACES = ("two-sided", "ignore")
#: "regular": rays at cell centres (a midpoint rule: second order on smooth slice profiles,
#: but it aliases on thin walls seen edge-on); "stratified": one ray per cell at a seeded
#: random offset (unbiased areas; see _stratified_offsets).
SAMPLINGS = ("regular", "stratified")
#: Default rays per range-bin width: slice rows are cheap, 3-D grids are rays_per_bin² per
#: bin area.
_DEFAULT_RAYS_PER_BIN = {"slice": 8.0, "3d": 1.0}
#: A view's rays are held in memory together (origins and Embree's results, ~50 bytes a
#: ray): beyond this many a run is refused before it allocates (about 2.5 GB).
MAX_RAYS_PER_VIEW = 5e7
#: By default a 3-D grid has at least this many rays across the target's diameter.
_MIN_RAYS_ACROSS = 128
#: Views per task: enough work to amortise a task, few enough to balance two cores.
_VIEWS_PER_TASK = 8
#: Worker processes allowed per core (``jobs``): more only compete for the cores.
_MAX_JOBS_PER_CORE = 4
#: Resubmissions of a chunk whose task was cancelled (a worker lost with its data).
_MAX_RETRIES = 3


# ------------------------------------------------------------------ geometry held per job

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
        tri = self.vertices[self.faces]
        cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        self.face_normals = cross / np.linalg.norm(cross, axis=1)[:, None]
        # each face's plane n·p = d in shifted coordinates (float64), for exact hit distances
        self.plane_d = np.einsum("ij,ij->i", self.face_normals, shifted[self.faces[:, 0]])
        self.hull = scene.hull_points() - self.center
        self.normals = normals
        self.corner = None
        if normals == "smooth":
            from .mesh import corner_normals

            self.corner = np.concatenate([corner_normals(p) for p in parts])
        self.exact = [p.exact_normal for p in parts]
        if normals == "exact" and any(e is None for e in self.exact):
            missing = [p.name for p in parts if p.exact_normal is None]
            raise ParameterError(f"normals='exact' needs parts tessellated from analytic shapes; "
                                 f"{missing[0]!r} has no exact normal (use 'flat' or 'smooth')")
        self.key = _digest(self.vertices, self.faces)





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


#: Embree scenes built in this process, most recent last, keyed by the geometry's content:
#: alternating between a few meshes (a study, a comparison) reuses each one's BVH.
_EMBREE_CACHE: dict = {}
_EMBREE_CACHE_SIZE = 4


def _embree_scene(geo: _Geometry):
    """The Embree scene of the geometry, built once per process (cached by content)."""
    scene = _EMBREE_CACHE.pop(geo.key, None)
    if scene is None:
        try:
            from embreex import rtcore_scene
            from embreex.mesh_construction import TriangleMesh
        except ImportError as exc:  # pragma: no cover - embreex is a core dependency
            raise ImportError("the mesh model needs embreex: pip install embreex") from exc
        # robust mode: watertight ray-triangle tests, so a ray through a shared edge (the
        # diagonal of a prism's side quad crosses the mid-height slice plane) cannot slip
        # between the two triangles
        raw = rtcore_scene.EmbreeScene(robust=True)
        TriangleMesh(raw, np.ascontiguousarray(geo.shifted / geo.scale, dtype=np.float32),
                     geo.faces32)
        scene = _Embree(raw, geo.scale)
        while len(_EMBREE_CACHE) >= _EMBREE_CACHE_SIZE:
            del _EMBREE_CACHE[next(iter(_EMBREE_CACHE))]       # the least recently used
    _EMBREE_CACHE[geo.key] = scene
    return scene


class _Embree:
    """An Embree scene built at unit size: origins in, distances out, in the scene's own
    shifted units. Embree misses outright below ~1e-14 and above ~1e13 scene units, so the
    geometry is divided by a power of two near its radius; a power of two scales float32
    exactly, so origins and distances are the same numbers as an unscaled cast."""

    def __init__(self, scene, scale: float):
        self.scene = scene
        self.scale = scale
        self.inverse = np.float32(1.0 / scale)

    def run(self, origins, directions, **kwargs):
        if self.scale != 1.0:
            origins = origins * self.inverse
        res = self.scene.run(origins, directions, **kwargs)
        if self.scale != 1.0 and isinstance(res, dict):
            with np.errstate(over="ignore"):        # a miss's far distance: inf
                res["tfar"] = res["tfar"] * np.float32(self.scale)
        return res


def _dot(a, w):
    """Row-wise a·w for (k, 3) a, without BLAS (whose threads would oversubscribe the cores
    that worker processes already share)."""
    return a[:, 0] * w[0] + a[:, 1] * w[1] + a[:, 2] * w[2]


def _frame(w):
    """(u, v) completing w to a right-handed orthonormal frame; v = z for horizontal w."""
    z = np.array([0.0, 0.0, 1.0])
    u = np.cross(z, w)
    n = np.linalg.norm(u)
    if n < 1e-12:                                         # looking along ±z
        u = np.array([1.0, 0.0, 0.0])
    else:
        u = u / n
    return u, np.cross(w, u)


# ------------------------------------------------------------------ hits

class _ViewHits(NamedTuple):
    """One view's hits, as a worker returns them (ranges relative to the scene centre's
    plane); the fields are :class:`Hits`' per-hit arrays for that view, plus its ``rays``
    cast and ``back_face_hits`` counts."""

    range: np.ndarray
    cos_theta: np.ndarray
    sin_theta: np.ndarray
    material: np.ndarray
    spread: np.ndarray
    rays: int
    back_face_hits: int
    bistatic: np.ndarray | None
    weight_factor: np.ndarray | None
    curve: np.ndarray | None


@dataclass(frozen=True, eq=False)
class Hits:
    """First hits of every ray, per view: geometry only, no materials' BRDFs.

    Per hit, k hits in all (arrays frozen read-only in place):

    ==================  ===========  =====================================================
    field               shape        meaning
    ==================  ===========  =====================================================
    ``view``            (k,) int32   index into the ladar's views
    ``range``           (k,)         range of the hit, −p·w (monostatic), scene units
    ``cos_theta``       (k,)         cos θ of the chosen normal against w; −1 marks a
                                     back-face hit that ``back_faces="ignore"`` blocks
    ``sin_theta``       (k,)         sin θ ≥ 0
    ``material``        (k,) int32   index into ``materials``
    ``spread``          (k, 4)       footprint: range half-widths along the two
                                     transverse axes (the second 0 in slice mode), and
                                     the hit facet's own range interval relative to the
                                     hit (≤ 0, ≥ 0)
    ``bistatic``        (k, 4)       with a bistatic receiver: cos θr, sin θr, cos α,
                                     sin α (cos θr = −1 where the receiver is occluded);
                                     else None
    ``weight_factor``   (k,)         shading normals' area factor (cos θs/cos θg), or None
    ``curve``           (k, 4)       exact-normal slice footprints on curved surfaces, or
                                     None
    ==================  ===========  =====================================================

    Per view (n_views,): ``rays`` cast and ``back_face_hits``. Scalars: ``area`` (δA⊥ per
    ray), ``mode``, ``normals``; ``ladar`` and ``materials`` as traced; ``info`` the run's
    parameters.
    """

    view: np.ndarray
    range: np.ndarray
    cos_theta: np.ndarray
    sin_theta: np.ndarray
    material: np.ndarray
    spread: np.ndarray
    rays: np.ndarray
    back_face_hits: np.ndarray
    area: float
    mode: str
    normals: str
    ladar: Ladar
    materials: tuple
    bistatic: np.ndarray = None
    weight_factor: np.ndarray = None
    curve: np.ndarray = None
    info: dict = field(default_factory=dict)

    def __post_init__(self):
        k = self.view.shape[0] if np.ndim(self.view) == 1 else -1
        expected = {"view": (k,), "range": (k,), "cos_theta": (k,), "sin_theta": (k,),
                    "material": (k,), "spread": (k, 4), "bistatic": (k, 4),
                    "weight_factor": (k,), "curve": (k, 4)}
        for name, shape in expected.items():
            a = getattr(self, name)
            if a is None and name in ("bistatic", "weight_factor", "curve"):
                continue
            a = np.asarray(a)
            if k < 0 or a.shape != shape:
                raise ParameterError(f"Hits.{name} must have shape {shape}; got {a.shape}")
            a.flags.writeable = False        # frozen in place: hits can be gigabytes
            object.__setattr__(self, name, a)
        for name in ("rays", "back_face_hits"):
            a = np.asarray(getattr(self, name))
            a.flags.writeable = False
            object.__setattr__(self, name, a)

    @property
    def size(self) -> int:
        return self.view.size


def _ray_grid(geo, w, mode, spacing, z0_shifted, rng):
    """Origins (n, 3) float32 in shifted coordinates, the start distance L, and (u, v).

    Built component by component in float32 (Embree's precision): o = s u + t v + L w.
    """
    u, v = _frame(w)
    L = (1.0 + _ORIGIN_MARGIN) * geo.radius + spacing
    su = geo.hull @ u
    s_lo, s_hi = su.min() - spacing, su.max() + spacing
    ns = max(1, int(math.ceil((s_hi - s_lo) / spacing)))
    s = s_lo + (np.arange(ns) + 0.5) * spacing
    if mode == "slice":
        t = np.array([z0_shifted])
    else:
        tv = geo.hull @ v
        t_lo, t_hi = tv.min() - spacing, tv.max() + spacing
        nt = max(1, int(math.ceil((t_hi - t_lo) / spacing)))
        t = t_lo + (np.arange(nt) + 0.5) * spacing
    o = np.empty((s.size, t.size, 3), dtype=np.float32)
    if rng is None:
        s32, t32 = s.astype(np.float32), t.astype(np.float32)
        for k in range(3):
            np.add.outer(s32 * np.float32(u[k]), t32 * np.float32(v[k]), out=o[:, :, k])
    elif mode == "slice":
        S = s[:, None] + rng.uniform(-0.5, 0.5, (s.size, t.size)) * spacing
        T = np.broadcast_to(t[None, :], S.shape)
        for k in range(3):
            o[:, :, k] = S * u[k] + T * v[k]
    else:
        # in float32 (Embree's precision, as the regular grid): S = s + δ·du, T = t + δ·dv
        du, dv = _stratified_offsets(s.size, t.size, rng)
        sp = np.float32(spacing)
        S = du
        S *= sp
        S += s.astype(np.float32)[:, None]
        T = dv
        T *= sp
        T += t.astype(np.float32)[None, :]
        for k in range(3):
            np.multiply(S, np.float32(u[k]), out=o[:, :, k])
            o[:, :, k] += T * np.float32(v[k])
    for k in range(3):
        o[:, :, k] += np.float32(L * w[k])
    return o.reshape(-1, 3), L, u, v


#: The golden ratio's conjugate: the Kronecker sequence frac(x + kα) is the most evenly
#: spread sequence of its kind (its gaps take at most three lengths).
_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0


def _stratified_offsets(ns, nt, rng):
    """Offsets in [−½, ½) of each ray from its cell centre, (ns, nt) along u and along v.

    Every cell holds one ray uniformly distributed in it, so the expected number of rays
    hitting any region is its projected area over δ²: the estimate of every area (a thin
    wall seen edge-on, a sub-ray facet) is unbiased. Unlike independent jitter, the offsets
    are correlated along rows and columns to cancel most of the noise at straight edges:
    along each row (a run of cells across u at one v) the v offsets follow a randomly
    shifted Kronecker sequence frac(η + iα), and along each column the u offsets
    frac(ξ + jα), so the fraction of a row's rays that fall on one side of an edge parallel
    to it is right to O(log n / n) instead of O(n^-½). Each cell's offset stays uniform
    (η and ξ are uniform and independent), hence the expectation is exact.
    """
    xi = rng.uniform(0.0, 1.0, ns).astype(np.float32)     # one shift per column (along v)
    eta = rng.uniform(0.0, 1.0, nt).astype(np.float32)    # one shift per row (along u)
    # frac(kα) − ½ in float64, then float32 (offsets within a cell: float32 is plenty)
    ku = (np.mod(np.arange(nt) * _GOLDEN, 1.0) - 0.5).astype(np.float32)
    kv = (np.mod(np.arange(ns) * _GOLDEN, 1.0) - 0.5).astype(np.float32)
    du = np.add.outer(xi, ku)                             # frac(ξ + jα) − ½ ∈ [−½, 1½) ...
    du -= du >= np.float32(0.5)                           # ... wrapped into [−½, ½)
    dv = np.add.outer(kv, eta)
    dv -= dv >= np.float32(0.5)
    return du, dv


def _trace_view(geo, scene, w, mode, spacing, z0_shifted, back_faces, rng, w_r=None,
                footprint=True):
    """Hits of one view (range relative to the shifted centre's plane); with a bistatic
    receiver direction w_r, one occlusion ray per hit toward it."""
    o, L, u, v = _ray_grid(geo, w, mode, spacing, z0_shifted, rng)
    d = np.ascontiguousarray((-w)[None, :], dtype=np.float32)
    res = scene.run(o, d, output=1)
    prim = res["primID"]
    hit = prim >= 0
    prim = prim[hit]
    n_geo = geo.face_normals[prim]
    t_hit = _refine_t(geo, prim, o[hit], w, res["tfar"][hit])
    cos_geo = _dot(n_geo, w)
    back = cos_geo < 0
    if geo.normals == "flat":
        n = n_geo
    elif geo.normals == "smooth":
        bu = res["u"][hit].astype(np.float64)[:, None]
        bv = res["v"][hit].astype(np.float64)[:, None]
        c = geo.corner[prim]
        n = (1 - bu - bv) * c[:, 0] + bu * c[:, 1] + bv * c[:, 2]
        n /= np.linalg.norm(n, axis=1, keepdims=True)
    else:
        p = (o[hit].astype(np.float64) - t_hit[:, None] * w) + geo.center
        n = np.empty((prim.size, 3))
        rho = np.full(prim.size, np.inf)
        part = geo.part_of[prim]
        for k in np.unique(part):
            sel = part == k
            n[sel] = geo.exact[k](p[sel])
            radius = getattr(geo.exact[k], "curvature_radius", None)
            if radius is not None and mode == "slice":
                rho[sel] = radius(p[sel])
    cos_t = _dot(n, w)
    if back_faces == "two-sided" and back.any():
        sign = np.where(back, -1.0, 1.0)
        n = n * sign[:, None]
        n_geo = n_geo * sign[:, None]
        cos_t = cos_t * sign
    # sin θ from cos θ: near normal incidence the absolute error of 1 − cos² is 1e-16, far
    # below the glint lobe's e² ≥ 1e-8 that sin² is compared with in h(α)
    sin_t = np.sqrt(np.maximum(1.0 - cos_t * cos_t, 0.0))
    factor = None
    curve = None
    if geo.normals == "smooth" or (geo.normals == "exact" and mode == "3d"):
        factor = _shading_factor(cos_t, cos_geo)
    if geo.normals == "exact" and mode == "slice" and np.any(np.isfinite(rho)):
        factor = _arc_factor(n, u, cos_t, rho, spacing)
        if footprint:
            sin_signed = _dot(n, u)
            r_ = np.where(np.isfinite(rho), rho, 0.0)
            half = np.where(r_ > 0, 0.5 * spacing / np.where(r_ > 0, r_, 1.0), 0.0)
            curve = np.stack([np.arcsin(np.clip(sin_signed, -1, 1)),
                              np.arcsin(np.clip(sin_signed - half, -1, 1)),
                              np.arcsin(np.clip(sin_signed + half, -1, 1)), r_], -1)
    if back_faces == "ignore":
        cos_t = np.where(back, -1.0, cos_t)
    bi = None
    rng_extra = 0.0
    if w_r is not None:
        # one occlusion ray per hit toward the receiver, from just off the facet
        p = o[hit].astype(np.float64) - t_hit[:, None] * w
        lift = _RECEIVER_LIFT * geo.radius
        o2 = np.ascontiguousarray(p + lift * n_geo, dtype=np.float32)
        blocked = scene.run(o2, np.ascontiguousarray(w_r[None, :], dtype=np.float32),
                            query="OCCLUDED") != -1
        cos_r = _dot(n, w_r)
        sin_r = np.linalg.norm(np.cross(n, w_r), axis=1)
        half = (w + w_r) / np.linalg.norm(w + w_r)
        cos_a = _dot(n, half)
        sin_a = np.linalg.norm(np.cross(n, half), axis=1)
        cos_r = np.where(blocked | (back_faces == "ignore") & back, -1.0, cos_r)
        bi = np.stack([cos_r, sin_r, cos_a, sin_a], -1)
        # range from the two-way path: r = −p·(w + w_r)/2 (monostatic: −p·w)
        rng_extra = -_dot(p, w_r)
    # footprint: range spread along u and v on the flat facet, and the facet's own range
    # interval relative to the hit (a footprint cannot return ranges the facet does not span)
    # r = −(c + o − t w)·w = −c·w + t − o·w, with the float32 origin o exactly as cast
    oh = o[hit].astype(np.float64)
    rng_rel = t_hit - (oh[:, 0] * w[0] + oh[:, 1] * w[1] + oh[:, 2] * w[2])
    if w_r is not None:
        rng_rel = 0.5 * (rng_rel + rng_extra)     # r = −c·(w + w_r)/2 + ...
    spread = np.zeros((prim.size, 4))
    if footprint:
        cg = np.maximum(np.abs(_dot(n_geo, w)), 1e-300)
        tri = geo.vertices[geo.faces[prim]] - geo.center
        tri_r = -(tri[..., 0] * w[0] + tri[..., 1] * w[1] + tri[..., 2] * w[2])
        spread[:, 0] = np.abs(_dot(n_geo, u)) / cg * 0.5 * spacing
        if mode == "3d":
            spread[:, 1] = np.abs(_dot(n_geo, v)) / cg * 0.5 * spacing
        spread[:, 2] = np.minimum(tri_r.min(axis=1) - rng_rel, 0.0)
        spread[:, 3] = np.maximum(tri_r.max(axis=1) - rng_rel, 0.0)
    return _ViewHits(rng_rel, cos_t, sin_t, geo.material[prim], spread, len(o),
                     int(back.sum()), bi, factor, curve)




def _shading_factor(cos_shading, cos_facet):
    """Per-ray factor cos θs / cos θg that makes a shading normal's weight the Eq. 8
    integrand over the facet area the ray stands for.

    A ray of cross-section δA⊥ hitting a facet at incidence θg stands for the facet area
    δA⊥ / cos θg; with the shading normal (interpolated or exact) the integrand there is
    F(θs) cos θs, so the ray's weight is F(θs) cos θs · δA⊥ / cos θg = F(θs) δA⊥ · factor.
    F(θs) cos θs is finite up to θs = 90° (DESIGN.md), so a shading normal near grazing on a
    facet that faces the ladar no longer multiplies a divergent F by a full ray
    cross-section (F δA⊥ alone returned bins tens of times too large at mesh silhouettes).
    The expectation over rays is ∫ F(θs) cos θs dA over the facets: consistent as the mesh
    is refined. With flat normals θs = θg and the factor is 1.
    """
    cg = np.maximum(np.abs(cos_facet), _MIN_COS_FACET)
    return np.maximum(cos_shading, 0.0) / cg


def _arc_factor(n, u, cos_t, rho, spacing):
    """Per-ray weight factor that integrates the exact surface over the ray's cell.

    A slice ray stands for the transverse cell s ± δ/2. The midpoint weight F(θ)·δ assumes
    the cell covers arc δ/cos θ, which near a silhouette samples an integrable 1/√ singularity
    (order-½ convergence for coatings whose F grows like 1/cos θ). With the exact normal and
    the shape's radius of curvature ρ at the hit, the locally circular surface covers
    arc = ρ [asin(sin θ + δ/2ρ) − asin(sin θ − δ/2ρ)] (clipped at the silhouette, sin θ signed
    toward u), so the weight becomes F cos θ · arc: factor = arc cos θ / δ (1 on flat caps).
    """
    sin_signed = n[:, 0] * u[0] + n[:, 1] * u[1] + n[:, 2] * u[2]
    finite = np.isfinite(rho) & (cos_t > 0)
    r = np.where(finite, rho, 1.0)
    half = 0.5 * spacing / r
    arc = r * (np.arcsin(np.clip(sin_signed + half, -1.0, 1.0))
               - np.arcsin(np.clip(sin_signed - half, -1.0, 1.0)))
    return np.where(finite, arc * np.maximum(cos_t, 0.0) / spacing, 1.0)




def _refine_t(geo, prim, origins32, w, t32):
    """Hit distances recomputed in float64 against the hit face's plane.

    Embree's t is float32 (~1e-7 of the scene's size): enough for geometry, not for a bin
    edge that coincides with a surface (the paper's first bin edge is the disk's top, where
    the glint peaks). The ray is o + t(−w) with o exactly the float32 origin cast; the face
    plane uses the float64 vertices: t = (d − n·o) / (−n·w), with d = n·v0."""
    n = geo.face_normals[prim]
    o = origins32.astype(np.float64)
    denom = -(n[:, 0] * w[0] + n[:, 1] * w[1] + n[:, 2] * w[2])
    num = geo.plane_d[prim] - (n[:, 0] * o[:, 0] + n[:, 1] * o[:, 1] + n[:, 2] * o[:, 2])
    ok = np.abs(denom) > _REFINE_MIN_COS
    return np.where(ok, num / np.where(ok, denom, 1.0), t32.astype(np.float64))


def _sampling(mode, sampling, seed):
    """(sampling, seed used): stratified by default in 3-D (and whenever a seed is given),
    regular in slice mode; seed 0 unless given."""
    if sampling is None:
        sampling = "stratified" if (mode == "3d" or seed is not None) else "regular"
    check_choice("sampling", sampling, SAMPLINGS)
    if sampling == "regular":
        if seed is not None:
            raise ParameterError(f"seed jitters the rays, so it needs sampling='stratified'; "
                                 f"got seed={seed!r} with sampling='regular'")
        return sampling, None
    if seed is None:
        return sampling, 0
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ParameterError(f"seed must be a non-negative integer; got {seed!r}")
    return sampling, int(seed)


def _spacing(ladar, mode, ray_spacing, rays_per_bin, radius):
    if ray_spacing is not None and rays_per_bin is not None:
        raise ParameterError("give ray_spacing or rays_per_bin, not both")
    if ray_spacing is not None:
        return check_real("ray_spacing", ray_spacing, low=0.0, low_open=True)
    if rays_per_bin is not None:
        rpb = check_real("rays_per_bin", rays_per_bin, low=0.0, low_open=True)
        return float(np.min(np.diff(ladar.bin_edges))) / rpb
    spacing = float(np.min(np.diff(ladar.bin_edges))) / _DEFAULT_RAYS_PER_BIN[mode]
    if mode == "3d":
        # bins much wider than the target (a target far off the rotation axis, seen from
        # all around) must not leave it with a handful of rays
        spacing = min(spacing, 2.0 * radius / _MIN_RAYS_ACROSS)
    return spacing


def _options(scene, ladar, mode, normals, back_faces, z0):
    if not isinstance(scene, Scene):
        raise ParameterError(f"scene must be a meshladar.Scene; got {type(scene).__name__}")
    if not isinstance(ladar, Ladar):
        raise ParameterError(f"ladar must be a meshladar.Ladar; got {type(ladar).__name__}")
    check_choice("normals", normals, NORMALS)
    check_choice("back_faces", back_faces, BACK_FACES)
    if mode is None:
        # a mesh is a 3-D target; only a scene tessellated from the 2-D analytic shapes (the
        # paper's phantoms) is an extruded slice by default
        mode = "slice" if (scene.shapes and ladar.planar) else "3d"
    check_choice("mode", mode, MODES)
    if mode == "slice" and not ladar.planar:
        raise ParameterError("mode='slice' needs views about the z axis (angles_deg); the "
                             "ladar has view vectors off the x-y plane: use mode='3d'")
    if not scene.is_mesh:
        raise ParameterError("the mesh model needs a mesh scene: Scene.from_mesh(...) or "
                             "scene.tessellate(segments=...)")
    if z0 is not None and mode == "3d":
        raise ParameterError(f"z0 places the slice plane of mode='slice'; got z0={z0!r} "
                             "with mode='3d'")
    geo = _Geometry(scene, normals)
    if z0 is None:
        z0 = float(geo.center[2])
    z0 = check_real("z0", z0)
    if mode == "slice":
        lo, hi = float(geo.vertices[:, 2].min()), float(geo.vertices[:, 2].max())
        if not lo <= z0 <= hi:
            warnings.warn(f"z0={z0:.6g} lies outside the target's heights [{lo:.6g}, "
                          f"{hi:.6g}]: the slice returns nothing", MeshladarWarning,
                          stacklevel=5)
    return mode, geo, z0


def _chunks(n, size):
    return [np.arange(i, min(i + size, n)) for i in range(0, n, size)]


def _job(geo, ladar_vectors, views, mode, spacing, z0_shifted, back_faces, seed, edges,
         weigh_with, receivers=None):
    """Trace a chunk of views; return hits (weigh_with None) or binned values."""
    scene = _embree_scene(geo)
    if (weigh_with is not None and geo.normals == "flat" and receivers is None
            and not weigh_with[1]
            and all(m.kernel_params is not None for m in weigh_with[0])):
        return _fast_job(geo, scene, ladar_vectors, views, mode, spacing, z0_shifted,
                         back_faces, seed, edges, weigh_with[0], weigh_with[2])
    out = []
    for i in views:
        w = ladar_vectors[i]
        w_r = None if receivers is None else receivers[i]
        rng = None if seed is None else np.random.default_rng([seed, int(i)])
        out.append(_trace_view(geo, scene, w, mode, spacing, z0_shifted, back_faces, rng,
                               w_r, footprint=weigh_with is None or weigh_with[1]))
    if weigh_with is None:
        return out
    materials, footprint, area = weigh_with
    vals = np.zeros((len(views), len(edges) - 1))
    for j, (i, h) in enumerate(zip(views, out)):
        r = h.range + _range_offset(geo.center, ladar_vectors[i],
                                 None if receivers is None else receivers[i])
        vals[j] = _bin_one(r, h.cos_theta, h.sin_theta, h.material, h.spread, materials, edges,
                           area, footprint, h.bistatic, h.weight_factor, h.curve)
    return vals, [h.rays for h in out], [h.back_face_hits for h in out]


def _material_table(materials):
    """(n, 7) rows of (rho_d, epsilon, b, e, G, has_diffuse, has_specular): each
    material's ``kernel_params`` (every material must have them for the compiled path)."""
    return np.array([m.kernel_params for m in materials], dtype=np.float64)


def _fast_job(geo, scene, vectors, views, mode, spacing, z0_shifted, back_faces, seed, edges,
              materials, area):
    """The common case fused in one compiled loop per view: monostatic, flat normals,
    point binning (no per-hit arrays beyond Embree's own output)."""
    from . import _kernels

    params = _material_table(materials)
    vals = np.zeros((len(views), len(edges) - 1))
    rays, backs = [], []
    for j, i in enumerate(views):
        w = vectors[i]
        rng = None if seed is None else np.random.default_rng([seed, int(i)])
        o, L, _, _ = _ray_grid(geo, w, mode, spacing, z0_shifted, rng)
        res = scene.run(o, np.ascontiguousarray((-w)[None, :], dtype=np.float32), output=1)
        start = _range_offset(geo.center, w, None)
        backs.append(_kernels.bin_flat_hits(res["primID"], res["tfar"], o, geo.plane_d,
                                            geo.face_normals, geo.material, params, w,
                                            start, edges, area, back_faces == "ignore",
                                            vals[j]))
        rays.append(len(o))
    return vals, rays, backs


def _range_offset(center, w, w_r):
    """−c·w (monostatic) or −c·(w + w_r)/2 (bistatic): the range of the shifted origin."""
    return -float(center @ w) if w_r is None else -0.5 * float(center @ (w + w_r))


def first_hits(scene, view_vector, *, ray_spacing):
    """First hits of one view's 3-D ray grid: (points (k, 3) float64 in scene coordinates,
    global face index (k,), range (k,)). Faces are numbered part by part in scene order;
    for the viewer (which faces are lit, where hits land)."""
    if not isinstance(scene, Scene) or not scene.is_mesh:
        raise ParameterError("first_hits needs a mesh scene")
    w = unit_vectors("view_vector", view_vector)
    if w.shape != (3,):
        raise ParameterError(f"view_vector must be one (3,) direction; got shape {w.shape}")
    spacing = check_real("ray_spacing", ray_spacing, low=0.0, low_open=True)
    geo = _Geometry(scene, "flat")
    emb = _embree_scene(geo)
    o, L, _, _ = _ray_grid(geo, w, "3d", spacing, 0.0, None)
    res = emb.run(o, np.ascontiguousarray((-w)[None, :], dtype=np.float32), output=1)
    hit = res["primID"] >= 0
    t = res["tfar"][hit].astype(np.float64)
    p = o[hit].astype(np.float64) - t[:, None] * w + geo.center
    return p, res["primID"][hit].astype(np.int64), -(p @ w)


def occluded(scene, points, direction, *, lift=_RECEIVER_LIFT):
    """Whether the ray from each point (k, 3) toward ``direction`` meets the scene; points
    are lifted by ``lift`` × the scene's radius along the direction first (so a point on a
    face does not hit that face)."""
    if not isinstance(scene, Scene) or not scene.is_mesh:
        raise ParameterError("occluded needs a mesh scene")
    d = unit_vectors("direction", direction)
    geo = _Geometry(scene, "flat")
    emb = _embree_scene(geo)
    p = np.asarray(points, dtype=np.float64) - geo.center + lift * geo.radius * d
    return emb.run(np.ascontiguousarray(p, dtype=np.float32),
                   np.ascontiguousarray(d[None, :], dtype=np.float32), query="OCCLUDED") != -1


# ------------------------------------------------------------------ weighing and binning

def _weights(cos_t, sin_t, mat, materials, area, bi=None):
    """F·δA⊥ per hit, evaluated per material group (0 where either direction is below the
    horizon): monostatic F(θ; −θ), or bistatic F(w, w_r) from (cos, sin) of θr and α."""
    if len(materials) == 1 and bi is None:
        return materials[0].value(cos_t, sin_t) * area
    wt = np.zeros(cos_t.size)
    for k in np.unique(mat):
        sel = mat == k
        c, s = cos_t[sel], sin_t[sel]
        if bi is None:
            wt[sel] = materials[k].value(c, s) * area
        else:
            b = bi[sel]
            wt[sel] = materials[k].bistatic_value(c, s, b[:, 0], b[:, 1], b[:, 2],
                                                  b[:, 3]) * area
    return wt


def _box_cdf(x, h):
    return np.clip((x + h) / np.where(h > 0, 2 * h, 1.0), 0.0, 1.0)


def _trap_cdf(x, a, b):
    """CDF of A + B, A ~ U(−a, a), B ~ U(−b, b): second differences of Q(y) = y₊²/2."""
    def q(y):
        return 0.5 * np.maximum(y, 0.0) ** 2

    return np.clip((q(x + a + b) - q(x + a - b) - q(x - a + b) + q(x - a - b))
                   / np.where(a * b > 0, 4 * a * b, 1.0), 0.0, 1.0)


def _curved_spread(r, wt, curve, edges):
    """Bin each ray's weight over its cell on the locally circular exact surface.

    ``curve`` rows: (θ at the hit, θ at the cell's two ends, ρ), θ signed incidence angles.
    Range along the circle is r(θ) = r_hit + ρ(cos θ_hit − cos θ), monotone in |θ|, and the
    weight is spread uniformly in θ (arc length) over the cell; a cell straddling the top
    (θ = 0) is split there."""
    nb = len(edges) - 1
    th, ta, tb, rho = curve.T
    total = np.maximum(tb - ta, 1e-300)
    # pieces in |θ|: [lo, hi] with their weight share
    straddle = (ta < 0) & (tb > 0)
    lo1 = np.where(straddle, 0.0, np.minimum(np.abs(ta), np.abs(tb)))
    hi1 = np.where(straddle, -ta, np.maximum(np.abs(ta), np.abs(tb)))
    lo2 = np.zeros_like(lo1)
    hi2 = np.where(straddle, tb, 0.0)
    out = np.zeros(nb)
    ct = np.cos(th)
    for lo, hi in ((lo1, hi1), (lo2, hi2)):
        ok = hi > lo
        if not ok.any():
            continue
        rr, w, c0, rh, l, h, tot = r[ok], wt[ok], ct[ok], rho[ok], lo[ok], hi[ok], total[ok]
        r_lo = rr + rh * (c0 - np.cos(l))
        r_hi = rr + rh * (c0 - np.cos(h))
        k0 = np.clip(np.searchsorted(edges, r_lo, side="right") - 1, 0, nb - 1)
        k1 = np.clip(np.searchsorted(edges, r_hi, side="right") - 1, 0, nb - 1)
        inside = (r_hi >= edges[0]) & (r_lo < edges[-1])
        cnt = np.where(inside, k1 - k0 + 1, 0)
        rows = np.repeat(np.arange(rr.size), cnt)
        kk = k0[rows] + np.arange(rows.size) - np.repeat(np.cumsum(cnt) - cnt, cnt)

        def theta_at(edge, i):
            # |θ| where r(θ) = edge, clipped to the piece
            x = np.clip(c0[i] - (edge - rr[i]) / rh[i], -1.0, 1.0)
            return np.clip(np.arccos(x), l[i], h[i])

        t1 = theta_at(edges[kk], rows)
        t2 = theta_at(edges[kk + 1], rows)
        out += np.bincount(kk, weights=w[rows] * (t2 - t1) / tot[rows], minlength=nb)
    return out


def _bin_one(r, cos_t, sin_t, mat, spread, materials, edges, area, footprint, bi=None,
             factor=None, curve=None):
    """One view's profile from its hits."""
    nb = len(edges) - 1
    wt = _weights(cos_t, sin_t, mat, materials, area, bi)
    if factor is not None:
        wt = wt * factor
    if footprint and curve is not None:
        curved = curve[:, 3] > 0
        out = _curved_spread(r[curved], wt[curved], curve[curved], edges)
        flat = ~curved
        return out + _bin_one(r[flat], cos_t[flat], sin_t[flat], mat[flat], spread[flat],
                              materials, edges, area, True, None if bi is None else bi[flat],
                              None)
    if not footprint:
        k = np.searchsorted(edges, r, side="right") - 1
        ok = (k >= 0) & (k < nb)
        return np.bincount(k[ok], weights=wt[ok], minlength=nb)
    a = np.maximum(spread[:, 0], spread[:, 1])
    b = np.minimum(spread[:, 0], spread[:, 1])
    # the footprint's interval, clipped to the facet's own range interval
    lo_c = np.maximum(-(a + b), spread[:, 2])
    hi_c = np.minimum(a + b, spread[:, 3])
    point = (a <= 0) | (hi_c <= lo_c)
    k0 = np.clip(np.searchsorted(edges, r + lo_c, side="right") - 1, 0, nb - 1)
    k1 = np.clip(np.searchsorted(edges, r + hi_c, side="right") - 1, 0, nb - 1)
    k0 = np.where(point, np.clip(np.searchsorted(edges, r, side="right") - 1, 0, nb - 1), k0)
    k1 = np.where(point, k0, k1)
    inside = (r + hi_c >= edges[0]) & (r + lo_c < edges[-1]) & (wt != 0)
    cnt = np.where(inside, k1 - k0 + 1, 0)
    rows = np.repeat(np.arange(r.size), cnt)
    kk = k0[rows] + np.arange(rows.size) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    lo = np.maximum(edges[kk] - r[rows], lo_c[rows])
    hi = np.minimum(edges[kk + 1] - r[rows], hi_c[rows])
    ar, br = a[rows], b[rows]
    tiny = br <= 1e-12 * np.maximum(ar, 1e-300)

    def cdf(x):
        return np.where(tiny, _box_cdf(x, ar), _trap_cdf(x, ar, br))

    mass = cdf(hi_c[rows]) - cdf(lo_c[rows])
    frac = np.where(hi > lo, cdf(hi) - cdf(lo), 0.0) / np.where(mass > 0, mass, 1.0)
    frac = np.where(point[rows], ((edges[kk] <= r[rows]) & (r[rows] < edges[kk + 1]))
                    .astype(float), frac)
    return np.bincount(kk, weights=wt[rows] * frac, minlength=nb)


def _executor(jobs, executor, n_rays_total):
    """The executor to use: the user's, or processes when it pays (embreex holds the GIL)."""
    if executor is not None:
        if not callable(getattr(executor, "submit", None)):
            raise ParameterError(f"executor must be a concurrent.futures.Executor (with "
                                 f"submit); got {type(executor).__name__}")
        return executor, False
    if jobs is None:
        jobs = 1 if n_rays_total < 4e6 else (os.cpu_count() or 1)
    cores = os.cpu_count() or 1
    if isinstance(jobs, bool) or not isinstance(jobs, (int, np.integer)) or jobs < 1:
        raise ParameterError(f"jobs must be an integer >= 1; got {jobs!r}")
    if jobs > _MAX_JOBS_PER_CORE * cores:
        raise ParameterError(f"jobs must be at most {_MAX_JOBS_PER_CORE * cores} "
                             f"({_MAX_JOBS_PER_CORE} per core on this {cores}-core machine: "
                             f"more processes only compete for the cores); got {jobs}")
    if jobs == 1:
        return None, False
    from concurrent.futures import ProcessPoolExecutor

    return ProcessPoolExecutor(max_workers=int(jobs), initializer=_worker_init), True


def _worker_init():
    """In a worker process: die with the parent (Linux), so a killed run leaves no
    workers behind; elsewhere a no-op."""
    import signal
    import sys

    if sys.platform.startswith("linux"):
        import ctypes

        try:
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(1, int(signal.SIGKILL))           # PR_SET_PDEATHSIG
        except (OSError, AttributeError):
            pass
    signal.signal(signal.SIGINT, signal.SIG_IGN)        # the parent handles Ctrl-C


def _largest_grid(geo, vectors, mode, spacing):
    """The most rays any one view's grid holds (the grids of _ray_grid: the projected
    hull's extent along u, and along v in 3-D, plus a spacing each side)."""
    largest = 0.0
    for start in range(0, len(vectors), 256):               # bounded memory
        frames = [_frame(w) for w in vectors[start:start + 256]]
        u = np.array([f[0] for f in frames])
        su = geo.hull @ u.T
        n = np.ceil((np.ptp(su, axis=0) + 2 * spacing) / spacing)
        if mode == "3d":
            tv = geo.hull @ np.array([f[1] for f in frames]).T
            n = n * np.ceil((np.ptp(tv, axis=0) + 2 * spacing) / spacing)
        largest = max(largest, float(n.max()))
    return largest


def _estimate_rays(geo, ladar, mode, spacing):
    extent = 2 * geo.radius / spacing + 2
    return ladar.n_views * (extent if mode == "slice" else extent * extent)


def _receivers(receiver, ladar, mode, footprint):
    if receiver is None:
        return None
    if np.shape(receiver) not in ((3,), (ladar.n_views, 3)):
        raise ParameterError(f"receiver must be a direction (3,) or one per view "
                             f"({ladar.n_views}, 3); got shape {np.shape(receiver)}")
    r = np.broadcast_to(unit_vectors("receiver", receiver), (ladar.n_views, 3))
    if np.any(np.einsum("ij,ij->i", r, ladar.view_vectors) <= -1 + 1e-12):
        k = int(np.argmax(np.einsum("ij,ij->i", r, ladar.view_vectors) <= -1 + 1e-12))
        raise ParameterError(f"receiver must not point exactly opposite the view (no light "
                             f"returns); got receiver {r[k].tolist()} for view {k}, "
                             f"{ladar.view_vectors[k].tolist()}")
    if mode == "slice" and np.any(r[:, 2] != 0):
        raise ParameterError("in slice mode the receiver must lie in the x-y plane")
    if footprint:
        raise ParameterError("footprint binning is monostatic only; use footprint=False with "
                             "a bistatic receiver")
    return np.ascontiguousarray(r)


def _job_description(geo, scene, ladar, mode, spacing, z0, back_faces, seed, weigh_with,
                     receivers):
    """Everything that determines a streaming run's result, for its run folder."""
    import hashlib

    def digest(a):
        return hashlib.sha256(np.ascontiguousarray(a).tobytes()).hexdigest()

    mats, footprint, area = weigh_with
    return {"kind": "simulate_mesh", "geometry": geo.key, "normals": geo.normals,
            "materials": [repr(m) for m in mats], "view_vectors": digest(ladar.view_vectors),
            "bin_edges": digest(ladar.bin_edges), "n_views": ladar.n_views, "mode": mode,
            "ray_spacing": spacing, "z0": z0, "back_faces": back_faces, "seed": seed,
            "footprint": bool(footprint), "receivers": None if receivers is None
            else digest(receivers), "views_per_chunk": _VIEWS_PER_TASK}


def _run(scene, ladar, *, mode, normals, back_faces, z0, ray_spacing, rays_per_bin, seed,
         jobs, executor, progress, weigh_with, receiver=None, run_dir=None, sampling=None):
    mode, geo, z0 = _options(scene, ladar, mode, normals, back_faces, z0)
    sampling, seed = _sampling(mode, sampling, seed)
    check_flag("progress", progress)
    if weigh_with is not None:
        check_flag("footprint", weigh_with[1])
    receivers = _receivers(receiver, ladar, mode, bool(weigh_with and weigh_with[1]))
    spacing = _spacing(ladar, mode, ray_spacing, rays_per_bin, geo.radius)
    per_view = _largest_grid(geo, ladar.view_vectors, mode, spacing)
    if per_view > MAX_RAYS_PER_VIEW:
        raise ParameterError(
            f"one view would cast about {per_view:.3g} rays (ray spacing {spacing:.3g} over "
            f"a target {2 * geo.radius:.3g} across), more than the {MAX_RAYS_PER_VIEW:.0e} a "
            "view may hold in memory; give a larger ray_spacing (or fewer rays_per_bin, "
            "or wider bins)")
    area = spacing if mode == "slice" else spacing * spacing
    if weigh_with is not None:
        weigh_with = (weigh_with[0], weigh_with[1], area)
    z0_shifted = z0 - float(geo.center[2])
    vectors = np.asarray(ladar.view_vectors, dtype=np.float64)
    chunks = _chunks(ladar.n_views, _VIEWS_PER_TASK)
    ex, own = _executor(jobs, executor, _estimate_rays(geo, ladar, mode, spacing))
    from ._progress import Progress

    bar = Progress(ladar.n_views, "views", enabled=progress)
    args = (mode, spacing, z0_shifted, back_faces, seed, ladar.bin_edges, weigh_with,
            receivers)
    folder = None
    results = [None] * len(chunks)
    if run_dir is not None:
        if not isinstance(run_dir, (str, os.PathLike)) or not os.fspath(run_dir):
            raise ParameterError(f"run_dir must be a folder path; got {run_dir!r}")
        if os.path.exists(run_dir) and not os.path.isdir(run_dir):
            raise ParameterError(f"run_dir must be a folder; {os.fspath(run_dir)!r} is a file")
        if weigh_with is None:
            raise ParameterError("run_dir is for streaming runs (simulate), not trace()")
        from .runs import RunFolder

        folder = RunFolder(run_dir, _job_description(geo, scene, ladar, mode, spacing, z0,
                                                     back_faces, seed, weigh_with, receivers),
                           len(chunks))
        for k in range(len(chunks)):
            n = len(chunks[k])
            arrays = folder.load(k, {"values": (n, ladar.n_bins), "rays": (n,),
                                     "backs": (n,)})
            if arrays is not None:
                results[k] = (arrays["values"], arrays["rays"].tolist(),
                              arrays["backs"].tolist())
                bar.update(len(chunks[k]))

    def keep(k, res):
        results[k] = res
        if folder is not None:
            folder.save(k, {"values": res[0], "rays": np.asarray(res[1]),
                            "backs": np.asarray(res[2])})
        bar.update(len(chunks[k]))

    todo = [k for k in range(len(chunks)) if results[k] is None]
    payload = geo
    try:
        if ex is None or not todo:
            for k in todo:
                keep(k, _job(geo, vectors, chunks[k], *args))
        else:
            payload = _scatter(ex, geo)
            futures = {ex.submit(_job, payload, vectors, chunks[k], *args): k for k in todo}
            from concurrent.futures import CancelledError, as_completed

            retries = {}
            while futures:
                for f in as_completed(list(futures)):
                    k = futures.pop(f)
                    try:
                        keep(k, f.result())
                    except CancelledError:
                        # a lost worker took the scattered mesh (or the task) with it: send
                        # the chunk again with the mesh itself, a bounded number of times
                        retries[k] = retries.get(k, 0) + 1
                        if retries[k] > _MAX_RETRIES:
                            raise
                        futures[ex.submit(_job, geo, vectors, chunks[k], *args)] = k
                    break
    except BaseException:
        if own:                          # interrupted or failed: drop the queued chunks,
            ex.shutdown(wait=False, cancel_futures=True)     # the workers exit with us
            own = False
        raise
    finally:
        bar.close()
        if folder is not None:
            folder.close()
        if own:
            ex.shutdown()
    run = {"mode": mode, "ray_spacing": spacing, "z0": z0, "sampling": sampling, "seed": seed,
           "receiver": receivers}
    return geo, run, area, chunks, results


def _scatter(ex, geo):
    """On a Dask executor, the mesh shipped once to every worker (a future standing for
    it); elsewhere the mesh itself. A worker lost while the mesh is being scattered is
    retried like a lost chunk; if scattering keeps failing, every task carries the mesh."""
    scatter = getattr(getattr(ex, "_client", None), "scatter", None)
    if scatter is None:
        return geo
    from concurrent.futures import CancelledError

    for _ in range(_MAX_RETRIES):
        try:
            return scatter(geo, broadcast=True, hash=False)
        except (OSError, TimeoutError, CancelledError):   # distributed's CommClosedError is
            continue                                      # an OSError
    return geo


def trace(scene, ladar, *, mode=None, normals="flat", back_faces="two-sided", z0=None,
          ray_spacing=None, rays_per_bin=None, sampling=None, seed=None, receiver=None,
          jobs=None, executor=None, progress=False) -> Hits:
    """Trace every view once and keep the hits (geometry only): re-weigh them with
    :func:`weigh` for any coating without tracing again.

    Parameters
    ----------
    scene : Scene
        A mesh scene (``Scene.from_mesh``, ``Scene.tessellate``).
    ladar : Ladar
        Views (angles about z, or view vectors) and range bins.
    mode : {"slice", "3d"}, optional
        "3d" (default for meshes): a square grid of rays per view over the whole target.
        "slice": one row of rays in the plane z = z0, values per unit height (the default
        only for scenes tessellated from the 2-D analytic shapes, the paper's phantoms).
    normals : {"flat", "smooth", "exact"}
    back_faces : {"two-sided", "ignore"}
    z0 : float, optional
        Slice plane, slice mode only (default the scene's mid-height).
    ray_spacing, rays_per_bin : float, optional
        Ray spacing, or rays per range-bin width (default 8 in slice mode; in 3-D 1, and
        at least 128 rays across the target's diameter).
    sampling : {"stratified", "regular"}, optional
        Where each ray sits in its cell of the grid. "stratified" (default in 3-D, and
        whenever ``seed`` is given): at a seeded random offset, so every area (a thin wall
        seen edge-on) is estimated without bias; "regular" (default in slice mode): at the
        cell centre, a midpoint rule that can alias on thin walls.
    seed : int, optional
        Seed of the stratified offsets (default 0), reproducible per view.
    receiver : (3,) or (n_views, 3) array_like, optional
        Bistatic receiver direction(s) from the scene (default: collocated, monostatic).
        Each hit then casts one occlusion ray toward the receiver, F is the bistatic SR
        BRDF, and range is half the two-way path, r = −p·(w + w_r)/2.
    jobs : int, optional
        Worker processes (embreex holds the GIL during casts, so threads do not help).
        Default: 1 for small jobs, all cores from 4e6 rays.
    executor : concurrent.futures.Executor, optional
        Any executor (e.g. a Dask client's) to run chunks of views on; overrides ``jobs``.
    progress : bool
        A progress bar on a terminal.
    """
    geo, run, area, chunks, results = _run(
        scene, ladar, mode=mode, normals=normals, back_faces=back_faces, z0=z0,
        ray_spacing=ray_spacing, rays_per_bin=rays_per_bin, seed=seed, jobs=jobs,
        executor=executor, progress=progress, weigh_with=None, receiver=receiver,
        sampling=sampling)
    receivers = run["receiver"]
    per_view = [h for res in results for h in res]
    vectors = ladar.view_vectors
    offsets = [_range_offset(geo.center, vectors[i],
                             None if receivers is None else receivers[i])
               for i in range(ladar.n_views)]
    view = np.concatenate([np.full(h.range.size, i, np.int32) for i, h in enumerate(per_view)])

    def joined(field):
        parts = [getattr(h, field) for h in per_view]
        return None if parts[0] is None else np.concatenate(parts)

    return Hits(view=view,
                range=np.concatenate([h.range + offsets[i] for i, h in enumerate(per_view)]),
                cos_theta=joined("cos_theta"), sin_theta=joined("sin_theta"),
                material=joined("material"), spread=joined("spread"),
                rays=np.array([h.rays for h in per_view]),
                back_face_hits=np.array([h.back_face_hits for h in per_view]),
                area=area, mode=run["mode"], normals=normals, ladar=ladar,
                materials=tuple(scene.materials), bistatic=joined("bistatic"),
                weight_factor=joined("weight_factor"), curve=joined("curve"), info=run)


def weigh(hits: Hits, materials=None, *, footprint=False, bin_edges=None) -> Sinogram:
    """Turn hits into a sinogram: F(θ)·δA⊥ per ray, binned by range.

    Parameters
    ----------
    hits : Hits
    materials : sequence of BRDF, optional
        Replacement coatings, one per material index of the traced scene (default: the
        scene's). A material sweep re-weighs the same hits.
    footprint : bool
        Spread each ray over the range interval its footprint covers on the hit facet.
    bin_edges : array_like, optional
        Other range bins (default the ladar's).
    """
    if not isinstance(hits, Hits):
        raise ParameterError(f"hits must be the Hits that meshladar.trace returns; got "
                             f"{type(hits).__name__}")
    check_flag("footprint", footprint)
    if footprint and hits.bistatic is not None:
        raise ParameterError("footprint binning is monostatic only; these hits are bistatic")
    from .brdf import BRDF, check_brdf

    if isinstance(materials, BRDF):
        materials = [materials]                       # one coating for a one-material scene
    if materials is not None and not isinstance(materials, (list, tuple)):
        raise ParameterError(f"materials must be a list of coatings, one per material index; "
                             f"got {type(materials).__name__}")
    mats = hits.materials if materials is None else tuple(materials)
    for i, m in enumerate(mats):
        check_brdf(f"materials[{i}]", m)
    if len(mats) != len(hits.materials):
        raise ParameterError(f"materials must give {len(hits.materials)} coatings (one per "
                             f"material index); got {len(mats)}")
    if bin_edges is None:
        edges = hits.ladar.bin_edges
    else:
        edges = Ladar([0.0], bin_edges).bin_edges      # the ladar's own checks of edges
    order = np.argsort(hits.view, kind="stable")
    bounds = np.searchsorted(hits.view[order], np.arange(hits.ladar.n_views + 1))
    vals = np.zeros((hits.ladar.n_views, len(edges) - 1))
    for i in range(hits.ladar.n_views):
        sel = order[bounds[i]:bounds[i + 1]]
        vals[i] = _bin_one(hits.range[sel], hits.cos_theta[sel], hits.sin_theta[sel],
                           hits.material[sel], hits.spread[sel], mats, edges, hits.area,
                           footprint, None if hits.bistatic is None else hits.bistatic[sel],
                           None if hits.weight_factor is None else hits.weight_factor[sel],
                           None if hits.curve is None else hits.curve[sel])
    return _sinogram(vals, hits.ladar, edges, hits.info, hits.normals, footprint, hits.rays,
                     hits.back_face_hits)


def _sinogram(vals, ladar, edges, run, normals, footprint, rays, back):
    """The mesh model's sinogram; its info says how it was made (mode, normals, sampling,
    rays) and under which convention (radiometry)."""
    info = {"radiometry": "paper", "mode": run["mode"], "normals": normals,
            "footprint": footprint, "ray_spacing": run["ray_spacing"],
            "sampling": run["sampling"], "seed": run["seed"], "rays": int(np.sum(rays)),
            "back_face_hits": np.asarray(back).tolist()}
    if run["mode"] == "slice":
        info["z0"] = run["z0"]
    return Sinogram(vals, angles_deg=ladar.angles_deg, bin_edges=edges, model="mesh",
                    view_vectors=None if ladar.planar else ladar.view_vectors, info=info)


def simulate_mesh(scene, ladar, *, mode=None, normals=None, back_faces="two-sided", z0=None,
                  ray_spacing=None, rays_per_bin=None, footprint=None, sampling=None,
                  seed=None, receiver=None, tol=None, max_rays=None, jobs=None,
                  executor=None, progress=False, run_dir=None) -> Sinogram:
    """Trace and weigh in one streaming pass: each chunk of views is binned and its hits
    dropped, so memory stays bounded whatever the number of views and rays. Options as
    :func:`trace` and :func:`weigh` (defaults: flat normals, point binning). An analytic
    scene is tessellated first (1024 segments per shape, see :meth:`Scene.tessellate`).

    ``tol`` asks for a relative L2 sinogram accuracy instead: meshladar refines rays per bin
    (and segments, for analytic scenes) from 256 segments and 1 ray per bin, doubling until
    a refinement check (the difference between successive runs, extrapolated with the
    measured convergence order) estimates the error at most ``tol``; defaults then become
    exact (analytic) or smooth (mesh) normals and footprint binning. The knob stops early,
    keeping its best run and warning why, when an estimate fails to fall or when the next
    run would pass ``max_rays`` rays in all (default ``refine.TOL_MAX_RAYS`` = 2e9). The result's
    ``info`` holds ``chosen``, ``error_estimate``, ``stopped`` and every ``refinement``
    run.

    ``run_dir`` makes the run resumable and loss-free (:mod:`meshladar.runs`): each finished
    chunk of views is saved there atomically with a checksum, and running the same job
    again reuses them and computes only what is missing.
    """
    common = dict(mode=mode, back_faces=back_faces, z0=z0, sampling=sampling, seed=seed,
                  receiver=receiver, jobs=jobs, executor=executor, progress=progress)
    if tol is not None:
        if run_dir is not None:
            raise ParameterError("run_dir and tol do not combine: the knob runs several jobs")
        from .refine import simulate_tol

        return simulate_tol(scene, ladar, tol, normals, footprint, max_rays,
                            dict(common, ray_spacing=ray_spacing, rays_per_bin=rays_per_bin))
    if max_rays is not None:
        raise ParameterError("max_rays is the budget of the tol knob; give tol too")
    normals = "flat" if normals is None else normals
    footprint = False if footprint is None else footprint
    if isinstance(scene, Scene) and not scene.is_mesh:
        scene = scene.tessellate(1024)
    geo, run, area, chunks, results = _run(
        scene, ladar, mode=mode, normals=normals, back_faces=back_faces, z0=z0,
        ray_spacing=ray_spacing, rays_per_bin=rays_per_bin, seed=seed, jobs=jobs,
        executor=executor, progress=progress, weigh_with=(tuple(scene.materials), footprint),
        receiver=receiver, run_dir=run_dir, sampling=sampling)
    vals = np.concatenate([r[0] for r in results])
    rays = [x for r in results for x in r[1]]
    back = [x for r in results for x in r[2]]
    if not np.any(vals):
        _warn_empty(scene, ladar, run, back_faces, sum(back), geo.face_normals)
    return _sinogram(vals, ladar, ladar.bin_edges, run, normals, footprint, rays, back)


def _warn_empty(scene, ladar, run, back_faces, back_hits, face_normals):
    """One line saying that a run returned nothing, and the likely reasons."""
    lo, hi = scene.range_span(ladar.view_vectors)
    reasons = []
    if hi < ladar.bin_edges[0] or lo >= ladar.bin_edges[-1]:
        reasons.append(f"the target spans ranges [{lo:.6g}, {hi:.6g}], outside the bins "
                       f"[{ladar.bin_edges[0]:.6g}, {ladar.bin_edges[-1]:.6g}]")
    if run["mode"] == "slice":
        reasons.append(f"the slice z0 = {run['z0']:.6g} may miss the target (mode='3d' "
                       "returns all of it)")
    if back_faces == "ignore" and any(scene.report.get("inverted", [])):
        reasons.append("the scene has inverted parts and back_faces='ignore' blanks them")
    elif back_faces == "ignore" and back_hits:
        reasons.append(f"{back_hits} rays hit the back of a face, which back_faces='ignore' "
                       "blanks (an open mesh seen from behind?)")
    facing = max(float(np.max(np.abs(face_normals @ w))) for w in ladar.view_vectors)
    if facing < _MIN_COS_FACET:
        reasons.append("every face is edge-on to every view (a flat target seen in its own "
                       "plane): views off that plane (view_vectors) see it")
    elif not reasons:
        reasons.append(f"ray_spacing {run['ray_spacing']:.4g} may be too coarse for the "
                       "target")
    warnings.warn("the sinogram is all zeros: no return reached any bin; " +
                  "; ".join(reasons), MeshladarWarning, stacklevel=4)
