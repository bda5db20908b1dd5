"""The mesh model's one per-chunk job: cast, then weigh, fused or per hit as decided once.

:func:`plan_job` looks at a :class:`~meshladar.raytrace.plan.TracePlan` and a
:class:`~meshladar.weighing.Weighing` (or none: keep the hits) once and picks the view
stage; :func:`mesh_job` is the function the stream runs on every chunk of views: it builds
the chunk's state (its bins, and the per-face weight cache the compiled loops read), then
runs the chosen stage on each view (or, for a batched job, on all of them at once). The
stages:

* ``hits``: each view's :class:`~meshladar.hits.ViewHits` (:func:`meshladar.trace`);
* ``per_hit``: hits weighed and binned in numpy (any normals, coating, receiver, sensor),
  and every run of at most :data:`QUICK_RAYS` rays on a ``quick_start`` backend (embreex),
  which then calls none of numba's compiled loops;
* ``flat``: flat normals, monostatic: F·δA⊥ one number per face and view, binned by the
  compiled loop (in the fused cast-weigh-bin loop on a fused backend; grids sparser than
  their faces with compiled coatings, a chunk's views in one call:
  :attr:`MeshJob.batched`);
* ``smooth``: smooth normals, coatings with a compiled kernel, binned by the compiled loop
  (in the fused cast-weigh-bin loop on a fused backend, the barycentrics kept per band;
  sparse grids a chunk's views in one call, as ``flat``);
* ``bistatic``: flat normals, a receiver, a fused backend: per-face bistatic weights and
  occlusion rays cast in the fused loop (sparse grids with built-in
  compiled coatings a chunk's views in one call, as ``flat``);
* ``sensor``: a sensor at a finite standoff, flat or smooth normals, compiled coatings;
* ``resolved``: hits weighed and binned by one to three coordinates (resolved returns).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable, NamedTuple

import numpy as np

from .._lazy import deferred_module
from ..precision import MIN_COS_FACET
from ..raytrace.backends import backend as get_backend
from ..raytrace.embree import embree_scene
from ..raytrace.grid import ray_grid
from ..raytrace.perspective import trace_sensor_view
from ..raytrace.plan import TracePlan, View
from ..raytrace.views import range_offset, trace_view
from ..weighing import bin_one as _bin_one
from ..brdf import material_table
from ..weighing.faces import (face_bistatic_weights, footprint_args,
                              face_weights)
from ..weighing.record import Weighing
from ..weighing.resolved import bin_resolved
from .fused_views import (FlatBins, _bistatic_views, _flat_views, _smooth_views, fused_view,
                          receiver_args)
from ..weighing.sensor_view import bin_sensor_view

if TYPE_CHECKING:            # the layers' check sees the edge; numba loads at first use
    import meshladar.weighing._kernels as _weigh_kernels
else:
    _weigh_kernels = deferred_module("meshladar.weighing._kernels")

__all__ = ["MeshJob", "plan_job", "mesh_job", "sensor_offset", "QUICK_RAYS"]


class Stage(NamedTuple):
    """A view stage: ``run(job, scene, view, chunk)`` casts (and weighs) one view into
    ``chunk``, returning (rays cast, back-face hits); ``faces``: it reads the per-face
    weight cache (and the coatings' table); ``views``: ``views(job, scene, views, chunk)``
    does a whole chunk at once, returning (k, 2) (rays cast, back-face hits), for a
    :attr:`MeshJob.batched` job; ``table``: it reads the coatings' compiled table
    (``chunk.params``) without the cache."""

    name: str
    run: Callable
    faces: bool = False
    views: Callable | None = None
    table: bool = False


@dataclass(frozen=True, eq=False)
class MeshJob:
    """Everything a chunk needs, decided once: the plan, the weighing (None: keep hits),
    the views, the stage, threads for one view's rows, and whether the backend's fused
    loop casts the grids. Built by :func:`plan_job`; frozen.

    Attributes
    ----------
    plan : meshladar.raytrace.plan.TracePlan
        The run's geometry, validated once (rays, normals, back faces, receivers, sensor,
        backend).
    weighing : meshladar.weighing.Weighing or None
        How hits become bins; None keeps the hits (:func:`meshladar.trace`).
    vectors : (n_views, 3) float64
        Every view's unit vector w, from the scene toward the ladar; a chunk's views index
        its rows.
    stage : Stage
        The view stage every view of the run goes through: ``"hits"``, ``"per_hit"``,
        ``"flat"``, ``"smooth"``, ``"bistatic"``, ``"sensor"`` or ``"resolved"`` (module
        docstring).
    row_jobs : int
        Threads one view's rows are split over, in the fused loop of the ``"flat"``,
        ``"smooth"`` and ``"bistatic"`` stages only (default 1).
    fused : bool
        Whether the backend's fused cast-weigh-bin loop casts the grids (default False).
    batched : bool
        Whether each chunk's views go through the fused loop in one call
        (:func:`.fused_views.chunk_views`; default False): sparse grids (not
        :attr:`~meshladar.raytrace.plan.TracePlan.coherent`: small views, where planning
        and calling a view cost as much as casting it), the ``"flat"``, ``"smooth"`` or
        ``"bistatic"`` stage, coatings with compiled kernels (SR, Lambertian; bistatic:
        built-in ones), point or footprint bins, one thread a view.
    """

    plan: TracePlan
    weighing: Weighing | None
    vectors: np.ndarray
    stage: Stage
    row_jobs: int = 1
    fused: bool = False
    batched: bool = False


@dataclass(eq=False)
class Chunk:
    """A chunk's output and working state: bins (or hits), and the compiled loops' per-face
    weight cache (``stamp`` tags the faces whose ``weight`` is the current view's) and
    footprint rows and their stamps ((n_faces, 4), (n_faces,))."""

    values: np.ndarray | None
    hits: list
    params: np.ndarray | None = None
    stamp: np.ndarray | None = None
    weight: np.ndarray | None = None
    footprints: tuple | None = None


def sensor_offset(geo, w, sensor):
    """What the range of a sensor's hit is relative to: absolute (R − D − aim·w) at a finite
    standoff, the shifted centre's plane at infinity.

    Parameters
    ----------
    geo : meshladar.raytrace.embree.Geometry
        The traced geometry; its ``center`` (3,) is the origin of the shifted coordinates
        the rays are cast in.
    w : (3,) float64
        The view's unit vector, from the scene toward the ladar.
    sensor : meshladar.sensor.Sensor
        The sensor the run traces with.

    Returns
    -------
    float
        The offset added to the hits' ranges (scene units): 0.0 when ``sensor.standoff``
        is set (the ranges are already absolute), else −c·w, the range of the geometry's
        centre c.
    """
    return 0.0 if sensor.standoff is not None else range_offset(geo.center, w, None)


def _trace(job, scene, view, footprint=True, transverse=False):
    """One view's hits, through parallel rays or the plan's sensor."""
    if job.plan.traced_with is not None:
        return trace_sensor_view(job.plan, scene, view)
    return trace_view(job.plan, scene, view, footprint=footprint, transverse=transverse)


def _offset(job, view):
    p = job.plan
    if p.traced_with is not None:
        return sensor_offset(p.geo, view.w, p.traced_with)
    return range_offset(p.geo.center, view.w, view.w_r)


def _hits_stage(job, scene, view, chunk):
    h = _trace(job, scene, view)
    chunk.hits.append(h)
    return h.rays, h.back_face_hits


def _per_hit_stage(job, scene, view, chunk):
    wg, sensed = job.weighing, job.plan.traced_with is not None
    h = _trace(job, scene, view, footprint=wg.footprint)
    r = h.range + _offset(job, view)
    if sensed:
        chunk.values[view.slot] = _bin_one(
            r, h.cos_theta, h.sin_theta, h.material, h.spread, wg.materials, wg.edges[0],
            job.plan.area, footprint=False, factor=h.weight_factor, power=wg.power,
            receive=h.receive_factor)
    else:
        chunk.values[view.slot] = _bin_one(
            r, h.cos_theta, h.sin_theta, h.material, h.spread, wg.materials, wg.edges[0],
            job.plan.area, footprint=wg.footprint, bi=h.bistatic, factor=h.weight_factor,
            curve=h.curve, power=wg.power)
    return h.rays, h.back_face_hits


def _resolved_stage(job, scene, view, chunk):
    h = _trace(job, scene, view, footprint=False, transverse=True)
    offset = -float(job.plan.geo.center @ view.w) if job.plan.traced_with is None \
        else _offset(job, view)
    bin_resolved(h, view.w, offset, job.plan, job.weighing, chunk.values[view.slot])
    return h.rays, 0


def _sensor_stage(job, scene, view, chunk):
    n, back = bin_sensor_view(job.plan, job.weighing, scene, view.w, view.rng,
                              chunk.values[view.slot], chunk.params)
    return n, back


def _bins(job, view, chunk, start):
    p, wg = job.plan, job.weighing
    # a dense grid hits most faces: every row in one pass over the mesh beats making each
    # at its face's first hit (1.31M faces: 5.0 against 4.6 Mrays/s); a sparse one makes
    # only the rows of the faces it hits
    fp = None if chunk.footprints is None else footprint_args(
        p.geo, view.w, p.mode, p.spacing, chunk.footprints,
        -1 if p.dense else view.slot + 1)
    return FlatBins(p.geo.plane_d, p.geo.face_normals, p.geo.material, chunk.params, view.w,
                    start, wg.edges[0], p.area, wg.power, p.ignore_back,
                    chunk.values[view.slot], chunk.stamp, chunk.weight, view.slot + 1, fp)


def _cast(job, scene, view):
    """One view's parallel rays cast one at a time: (origins, Embree's results)."""
    p = job.plan
    grid = ray_grid(p.geo, view.w, p.mode, p.spacing, p.z0_shifted, view.rng)
    return grid.origins, scene.run(grid.origins, np.ascontiguousarray((-view.w)[None, :],
                                                                      dtype=np.float32),
                                   output=1, columns=grid.columns, coherent=p.coherent)


def _smooth_stage(job, scene, view, chunk):
    p, wg = job.plan, job.weighing
    start = range_offset(p.geo.center, view.w, None)
    if job.fused:
        # packets: grid, cast, weigh and bin in one loop, the barycentrics kept per band
        return fused_view(job, scene, view, _bins(job, view, chunk, start), None,
                           (p.geo.corner, MIN_COS_FACET))
    o, res = _cast(job, scene, view)
    back = _weigh_kernels.bin_smooth_hits(
        res["primID"], res["tfar"], res["u"], res["v"], o, p.geo.plane_d,
        p.geo.face_normals, p.geo.corner, p.geo.material, chunk.params, view.w, start,
        wg.edges[0], p.area, wg.power, p.ignore_back, MIN_COS_FACET,
        chunk.values[view.slot], _bins(job, view, chunk, start).footprint)
    return len(o), back


def _flat_stage(job, scene, view, chunk):
    """Flat normals, monostatic or (fused backends) bistatic: each face's weight for the
    view before the cast where the compiled kernel cannot evaluate it at a hit."""
    p, wg = job.plan, job.weighing
    start = range_offset(p.geo.center, view.w, view.w_r)
    receiver = None
    if view.w_r is not None:
        if not wg.compiled_bistatic:                 # F in numpy, every face first
            face_bistatic_weights(p.geo, wg.materials, view.w, view.w_r, p.area,
                                  chunk.weight, wg.power, p.ignore_back)
            chunk.stamp[:] = view.slot + 1
        receiver = receiver_args(job, view.w, view.w_r)
    elif not wg.compiled:
        face_weights(p.geo, wg.materials, view.w, p.area, chunk.weight, wg.power)
        chunk.stamp[:] = view.slot + 1               # every face's weight is this view's
    bins = _bins(job, view, chunk, start)
    if job.fused:
        # packets: grid, cast, weigh and bin in one loop, no per-ray arrays
        return fused_view(job, scene, view, bins, receiver, None)
    if scene.bins_hits and receiver is None and not wg.footprint:
        # a backend with its own cast-weigh-bin kernel (Warp): every face's weight first
        if wg.compiled:
            face_weights(p.geo, wg.materials, view.w, p.area, chunk.weight, wg.power)
        grid = ray_grid(p.geo, view.w, p.mode, p.spacing, p.z0_shifted, view.rng)
        return len(grid.origins), scene.cast_bin(grid.origins, -view.w, bins)
    o, res = _cast(job, scene, view)
    return len(o), _weigh_kernels.bin_flat_hits(res["primID"], res["tfar"], o, *bins)


def _fused(plan):
    """Whether the backend's fused loop casts the plan's grids (a regular slice row or any
    3-D grid: stratified slice offsets are drawn by the per-ray grid)."""
    return get_backend(plan.backend).fused and (plan.mode == "3d" or plan.seed is None)


#: The most rays (the plan's estimate) a run on a ``quick_start`` backend (embreex) weighs
#: in numpy, calling no compiled loop: numba's compiling (2-3 s) or loading (0.3-0.4 s) of
#: one costs more than it saves on this many rays (150-230 ns a ray). The command line's
#: ``--backend auto`` casts such runs with embreex (:mod:`meshladar.cli.simulate`).
QUICK_RAYS = 1 << 20

STAGES = {s.name: s for s in (
    Stage("hits", _hits_stage), Stage("per_hit", _per_hit_stage),
    Stage("resolved", _resolved_stage), Stage("sensor", _sensor_stage, table=True),
    Stage("smooth", _smooth_stage, faces=True, views=_smooth_views),
    Stage("flat", _flat_stage, faces=True, views=_flat_views),
    Stage("bistatic", _flat_stage, faces=True, views=_bistatic_views))}


def _stage_name(plan, weighing):
    if weighing is None:
        return "hits"
    if weighing.resolved:
        return "resolved"
    if get_backend(plan.backend).quick_start and plan.rays <= QUICK_RAYS:
        return "per_hit"
    normals, compiled = plan.normals, weighing.compiled
    if plan.traced_with is not None:
        fast = plan.traced_with.standoff is not None and normals in ("flat", "smooth") \
            and compiled
        return "sensor" if fast else "per_hit"
    if plan.receivers is None and normals == "flat":
        return "flat"
    if plan.receivers is None and normals == "smooth" and compiled:
        return "smooth"
    if plan.receivers is not None and normals == "flat" and _fused(plan):
        return "bistatic"
    return "per_hit"


def plan_job(plan, weighing, vectors, row_jobs=1) -> MeshJob:
    """The chunk job of a plan and a weighing (None: keep hits), its stage chosen once.

    The stage: ``"hits"`` without a weighing; ``"resolved"`` for resolved returns;
    ``"per_hit"`` for a run of at most :data:`QUICK_RAYS` rays on a backend whose
    ``quick_start`` is set (embreex); with a
    sensor traced, ``"sensor"`` at a finite standoff with flat or smooth normals and
    compiled coatings, else ``"per_hit"``; monostatic, ``"flat"`` for flat normals and
    ``"smooth"`` for smooth normals with compiled coatings; ``"bistatic"`` for flat normals
    and receivers on a fused backend; ``"per_hit"`` otherwise. Nothing is checked here: the
    plan and the weighing were checked against each other before.

    Parameters
    ----------
    plan : meshladar.raytrace.plan.TracePlan
        The run's validated geometry.
    weighing : meshladar.weighing.Weighing or None
        How hits become bins; None keeps each view's hits.
    vectors : (n_views, 3) array_like
        The views' unit vectors w (the ladar's ``view_vectors``); stored as float64.
    row_jobs : int, optional
        Threads for one view's rows in the fused loop (default 1).

    Returns
    -------
    MeshJob
        The job :func:`mesh_job` runs on every chunk of views.
    """
    stage, fused = STAGES[_stage_name(plan, weighing)], _fused(plan)
    batched = (stage.views is not None and fused and not plan.coherent and row_jobs == 1
               and weighing.compiled
               and (plan.receivers is None or weighing.compiled_bistatic))
    return MeshJob(plan=plan, weighing=weighing,
                   vectors=np.asarray(vectors, dtype=np.float64), stage=stage,
                   row_jobs=row_jobs, fused=fused, batched=batched)


def _chunk(job, n_views):
    geo, wg = job.plan.geo, job.weighing
    if wg is None:
        return Chunk(values=None, hits=[])
    shape = tuple(e.size - 1 for e in wg.edges)
    chunk = Chunk(values=np.zeros((n_views,) + shape), hits=[])
    if job.stage.faces or job.stage.table:
        chunk.params = material_table(wg.materials) if wg.compiled else \
            np.zeros((len(wg.materials), 7))
    if job.stage.faces:
        chunk.stamp = np.zeros(len(geo.faces), np.int64)
        chunk.weight = np.empty(len(geo.faces))
        # None for point bins: the compiled loops then leave out (and do not compile)
        # the footprint's spreading
        chunk.footprints = (np.zeros((len(geo.faces), 4)), np.zeros(len(geo.faces), np.int64)) \
            if wg.footprint else None
    return chunk


def mesh_job(geo, views, job):
    """The stream's per-chunk job (``run_chunks(mesh_job, geo, ..., args=(job,))``): the
    views' hits (a list of :class:`~meshladar.hits.ViewHits`) when ``job.weighing`` is
    None, else ``{"values", "rays", "backs"}`` arrays.

    Parameters
    ----------
    geo : meshladar.raytrace.embree.Geometry
        The plan's traced geometry (``job.plan.geo``); its Embree scene is built for the
        plan's backend.
    views : (n,) array_like of int
        The chunk's view indices into ``job.vectors``. With a seeded plan, view i draws
        from ``np.random.default_rng([seed, i])``, whichever chunk holds it.
    job : MeshJob
        From :func:`plan_job`.

    Returns
    -------
    list of meshladar.hits.ViewHits or dict
        Without a weighing, each view's hits in the order of ``views``. Otherwise
        ``"values"``: (n, n_0[, n_1, ...]) float64, the view's bins over the weighing's
        axes (``(n, n_bins)`` for a sinogram); ``"rays"``: (n,) int64, rays cast per view;
        ``"backs"``: (n,) int64, hits on the back of a face per view (0 in the
        ``"resolved"`` stage).
    """
    scene = embree_scene(geo, job.plan.backend)
    chunk = _chunk(job, len(views))
    seed, receivers = job.plan.seed, job.plan.receivers
    rays = np.zeros(len(views), np.int64)
    backs = np.zeros(len(views), np.int64)
    if job.batched:
        rays[:], backs[:] = job.stage.views(job, scene, views, chunk).T
        return {"values": chunk.values, "rays": rays, "backs": backs}
    for j, i in enumerate(views):
        view = View(slot=j, index=int(i), w=job.vectors[i],
                    w_r=None if receivers is None else receivers[i],
                    rng=None if seed is None else np.random.default_rng([seed, int(i)]))
        rays[j], backs[j] = job.stage.run(job, scene, view, chunk)
    if job.weighing is None:
        return chunk.hits
    return {"values": chunk.values, "rays": rays, "backs": backs}
