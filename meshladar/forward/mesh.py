"""The mesh model's entry points: :func:`trace` (hits, geometry only), :func:`simulate_mesh`
(trace and weigh in one streaming pass), and the viewer's queries :func:`first_hits` and
:func:`occluded`. Each validates once at the boundary (a
:class:`~meshladar.raytrace.plan.TracePlan`, and a :class:`~meshladar.weighing.Weighing`
checked against it before the first ray), then hands :mod:`meshladar.stream` the one
per-chunk job (:mod:`.job`); :func:`run_plan` is shared with resolved returns
(:mod:`meshladar.forward.resolved`)."""

from __future__ import annotations

import os
import warnings
from typing import NamedTuple

import numpy as np

from .._validate import check_flag, check_real, unit_vectors
from ..errors import MeshladarWarning, ParameterError, user_stacklevel
from ..ladar import Ladar
from ..precision import MIN_COS_FACET as _MIN_COS_FACET
from ..precision import RECEIVER_LIFT as _RECEIVER_LIFT
from ..scene import Scene
from ..sinogram import Sinogram
from ..raytrace.embree import embree_scene
from ..raytrace.embree import geometry, resolve_backend
from ..hits import Hits
from ..raytrace.plan import plan_trace
from ..weighing import sinogram_of as _sinogram
from ..runs import array_digest as digest
from ..sensor import check_radiometry
from ..stream import MAX_JOBS_PER_CORE, THREADS_FROM, joined, run_chunks
from ..weighing.record import Weighing
from .job import mesh_job, plan_job, sensor_offset
from .sampling import warn_unresolved_lobes
from ..raytrace.grid import MAX_SPACING, MIN_SPACING, ray_grid
from ..raytrace.views import range_offset
from ..raytrace.views import refine_t

__all__ = ["trace", "simulate_mesh", "first_hits", "occluded"]


#: Views per task: enough work to amortise a task, few enough to balance two cores.
_VIEWS_PER_TASK = 8
#: The same for a batched job's chunk, planned and cast in one call (small views): its own
#: costs (bins, the weight cache, the call's arrays: some 0.3 ms) amortised over more views
#: (2,000 views of 1,444 rays of an 82k-face sphere: 0.44 ms a view against 0.48 at 8).
_BATCHED_VIEWS_PER_TASK = 64


def _views_per_task(n_views, batched=False):
    """Views per chunk: :data:`_VIEWS_PER_TASK` (:data:`_BATCHED_VIEWS_PER_TASK` for a
    batched job), but at most a quarter of the views, so a handful of big views still
    spreads over the threads (8 views of 1e6 rays were one chunk, hence one thread). It
    depends on the views and the plan alone, so a run folder's chunks are the same on any
    machine."""
    most = _BATCHED_VIEWS_PER_TASK if batched else _VIEWS_PER_TASK
    return int(min(most, max(1, n_views // 4)))



def first_hits(scene, view_vector, *, ray_spacing):
    """First hits of one view's 3-D ray grid: (points (k, 3) float64 in scene coordinates,
    global face index (k,), range (k,) float64). Faces are numbered part by part in scene
    order; for the viewer (which faces are lit, where hits land). Distances are float64
    (recomputed against the hit face's plane, as the binning paths): points lie on their
    faces and ranges are exact to ~1e-14 of the scene's size, not Embree's float32 ~1e-7.

    The rays sit at the centres of a regular square grid (no stratified offsets) covering
    the scene's hull seen from the view plus one spacing on each side; they are cast on
    the flat-normal geometry with the ``"auto"`` backend.

    Parameters
    ----------
    scene : Scene
        A mesh scene (``Scene.from_mesh``, ``Scene.tessellate``).
    view_vector : (3,) array_like
        The view w, from the scene toward the ladar (normalised here); rays travel along
        −w.
    ray_spacing : float
        Distance between neighbouring rays (scene units), from 1e-150 to 1e30.

    Returns
    -------
    points : (k, 3) float64
        The first hit of each ray that meets the scene, in scene coordinates.
    faces : (k,) int64
        Global index of the face hit (faces numbered part by part in scene order).
    range : (k,) float64
        Each hit's range r = −p·w (scene units, growing away from the ladar).

    Raises
    ------
    ParameterError
        If ``scene`` is not a mesh scene, ``view_vector`` is not one finite non-zero (3,)
        direction, or ``ray_spacing`` is not a real from 1e-150 to 1e30.
    """
    if not isinstance(scene, Scene) or not scene.is_mesh:
        raise ParameterError("first_hits needs a mesh scene")
    w = unit_vectors("view_vector", view_vector)
    if w.shape != (3,):
        raise ParameterError(f"view_vector must be one (3,) direction; got shape {w.shape}")
    spacing = check_real("ray_spacing", ray_spacing, low=MIN_SPACING, high=MAX_SPACING)
    geo = geometry(scene, "flat")
    emb = embree_scene(geo, resolve_backend("auto"))
    grid = ray_grid(geo, w, "3d", spacing, 0.0, None)
    o = grid.origins
    res = emb.run(o, np.ascontiguousarray((-w)[None, :], dtype=np.float32), output=1,
                  columns=grid.columns)
    hit = res["primID"] >= 0
    prim = res["primID"][hit].astype(np.int64)
    # Embree's float32 t recomputed in float64 against the hit face's plane, as the binning
    # paths do (meshladar.raytrace.views): r = −(c + o − t w)·w with o the float32 origin
    t = refine_t(geo, prim, o[hit], w, res["tfar"][hit])
    oh = o[hit].astype(np.float64)
    p = oh - t[:, None] * w + geo.center
    return p, prim, t - oh @ w + range_offset(geo.center, w, None)



def occluded(scene, points, direction, *, lift=_RECEIVER_LIFT):
    """Whether the ray from each point (k, 3) toward ``direction`` meets the scene; points
    are lifted by ``lift`` × the scene's radius along the direction first (so a point on a
    face does not hit that face).

    Parameters
    ----------
    scene : Scene
        A mesh scene; cast on its flat-normal geometry with the ``"auto"`` backend.
    points : (k, 3) array_like
        Start points in scene coordinates (not checked).
    direction : (3,) array_like
        The direction of every ray (normalised here), e.g. toward a receiver.
    lift : float, optional
        The lift off each point along ``direction``, as a fraction of the scene's radius
        (the largest distance of a vertex from its bounding box's centre); default
        :data:`meshladar.precision.RECEIVER_LIFT` (1e-5). Not checked.

    Returns
    -------
    (k,) bool ndarray
        True where the ray meets a face of the scene.

    Raises
    ------
    ParameterError
        If ``scene`` is not a mesh scene or ``direction`` is not a finite non-zero
        direction.
    """
    if not isinstance(scene, Scene) or not scene.is_mesh:
        raise ParameterError("occluded needs a mesh scene")
    d = unit_vectors("direction", direction)
    geo = geometry(scene, "flat")
    emb = embree_scene(geo, resolve_backend("auto"))
    p = np.asarray(points, dtype=np.float64) - geo.center + lift * geo.radius * d
    return emb.run(np.ascontiguousarray(p, dtype=np.float32),
                   np.ascontiguousarray(d[None, :], dtype=np.float32), query="OCCLUDED") != -1



def _job_description(plan, scene, ladar, weighing):
    """Everything that determines a streaming run's result, for its run folder."""
    return {"kind": "simulate_mesh", "radiometry": weighing.radiometry,
            "geometry": plan.geo.key, "normals": plan.geo.normals,
            "materials": [repr(m) for m in weighing.materials],
            "view_vectors": digest(ladar.view_vectors), "bin_edges": digest(ladar.bin_edges),
            "n_views": ladar.n_views, "mode": plan.mode, "ray_spacing": plan.spacing,
            "z0": plan.z0, "back_faces": plan.back_faces, "seed": plan.seed,
            "footprint": bool(weighing.footprint),
            "receivers": None if plan.receivers is None else digest(plan.receivers),
            "sensor": None if plan.sensor is None else plan.sensor.describe()}


class Streaming(NamedTuple):
    """How a run's chunks are streamed (:func:`meshladar.stream.run_chunks`)."""

    jobs: int | None = None
    executor: object = None
    progress: bool = False
    run_dir: object = None


def run_plan(plan, weighing, ladar, streaming, description=None, chunk_size=None):
    """Run the one per-chunk job (:func:`.job.mesh_job`) of ``plan`` and ``weighing``
    (None: keep the hits) over the ladar's views: the stream's results."""
    check_flag("progress", streaming.progress)
    job = plan_job(plan, weighing, ladar.view_vectors,
                   _row_jobs(ladar.n_views, streaming.jobs, streaming.executor, plan.rays))
    shape = (ladar.n_bins,) if weighing is None else tuple(e.size - 1 for e in weighing.edges)
    return run_chunks(
        mesh_job, plan.geo, ladar.n_views,
        chunk_size=chunk_size or _views_per_task(ladar.n_views, job.batched), args=(job,),
        jobs=streaming.jobs, executor=streaming.executor, progress=streaming.progress,
        unit="views", work=plan.rays, run_dir=streaming.run_dir, job=description,
        arrays=_CHUNK_ARRAYS[weighing is not None and weighing.resolved](shape),
        threads=True)


#: The arrays a run folder's chunk must hold (resolved returns' folders hold no back-face
#: counts: their chunks from before stay valid).
_CHUNK_ARRAYS = {False: lambda shape: {"values": shape, "rays": (), "backs": ()},
                 True: lambda shape: {"values": shape, "rays": ()}}


def _run(scene, ladar, options, streaming, weighing=None):
    """Plan (every check, before the first ray), then run: (plan, results)."""
    plan = plan_trace(scene, ladar, **options)
    if weighing is not None:
        weighing.check(plan)                        # every rule, before the first ray
        # a glint narrower than the rays resolve is missed without a word otherwise
        warn_unresolved_lobes(scene, weighing.materials, spacing=plan.spacing,
                              normals=plan.normals, mode=plan.mode, sampling=plan.sampling)
    description = None
    if streaming.run_dir is not None:
        description = _job_description(plan, scene, ladar, weighing)
    return plan, run_plan(plan, weighing, ladar, streaming, description)


def _run_info(plan):
    """The plan as a run's provenance (``Sinogram.info`` and ``Hits.info``)."""
    return {"mode": plan.mode, "ray_spacing": plan.spacing, "z0": plan.z0,
            "sampling": plan.sampling, "seed": plan.seed, "receiver": plan.receivers,
            "backend": plan.backend, "sensor": plan.sensor, "traced_with": plan.traced_with}


def _row_jobs(n_views, jobs, executor, work):
    """Threads for the rows of a single view (the stream parallelises chunks of views):
    ``jobs``, or one per core once the view is worth it; 1 with an executor or an invalid
    ``jobs`` (which the stream then refuses)."""
    if n_views != 1 or executor is not None:
        return 1
    if jobs is None:
        return (os.cpu_count() or 1) if work >= THREADS_FROM else 1
    ok = isinstance(jobs, (int, np.integer)) and not isinstance(jobs, bool) and 1 <= jobs
    return min(int(jobs), MAX_JOBS_PER_CORE * (os.cpu_count() or 1)) if ok else 1


def trace(scene, ladar, *, mode=None, normals="flat", back_faces="two-sided", z0=None,
          ray_spacing=None, rays_per_bin=None, sampling=None, seed=None, receiver=None,
          jobs=None, executor=None, progress=False, backend="auto", sensor=None) -> Hits:
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
        Worker threads. Both backends release the GIL while they cast, so the threads of a
        run share one Embree scene (nothing pickled, nothing rebuilt). Default: 1 below
        :data:`meshladar.stream.THREADS_FROM` (5e4) rays in all, else one per core (at
        most one per chunk of views; a single view splits its rows over them).
    executor : concurrent.futures.Executor, optional
        Any executor (e.g. a Dask client's, whose workers are processes on other machines)
        to run chunks of views on; overrides ``jobs``.
    progress : bool
        A progress bar on a terminal.
    backend : {"auto", "packets", "raster", "embreex", "warp", "warp-cpu"}
        How rays are cast: "packets" ("raster": the same here), Embree 4 packets of the CPU's
        native width; "embreex", one ray at a time (the reference); "warp" and "warp-cpu",
        NVIDIA Warp's kernels on a CUDA device or the CPU (the ``gpu`` extra); "auto"
        (default): warp where a CUDA device is present, else raster when the packets load,
        else embreex, with a warning. All give the same hits (a ray along an edge shared by
        two faces may report either; Warp's, to float32 round-off); ``info["backend"]`` says which.
    sensor : meshladar.sensor.Sensor, optional
        A sensor at a finite standoff (perspective rays, true distances) and/or a beam
        pattern, atmosphere and link budget (:mod:`meshladar.sensor`). Monostatic, point
        binning. Default: at infinity, an unbounded flood (the paper's ladar).

    Returns
    -------
    Hits
        k hits in all: per hit ``view`` (k,), ``range`` (k,), ``cos_theta`` and
        ``sin_theta`` (k,), ``material`` (k,), ``spread`` (k, 4), and ``bistatic``,
        ``weight_factor``, ``curve`` where they apply; per view ``rays`` and
        ``back_face_hits`` (n_views,); ``area`` (δA⊥ per ray), ``mode``, ``normals``,
        ``ladar``, ``materials`` and ``info`` (see :class:`Hits`). Arrays are read-only.

    Examples
    --------
    >>> import numpy as np, meshladar as ml
    >>> scene = ml.phantoms.scene("disk").tessellate(256, height=1.0)   # a one-part mesh
    >>> ladar = ml.Ladar.covering(scene, n_bins=64, angles_deg=np.arange(0.0, 360.0, 30.0))
    >>> hits = ml.trace(scene, ladar)      # geometry only, traced once; then any coatings:
    >>> for m in (ml.materials.DARK_GRAY, ml.materials.ALUMINUM): alu = ml.weigh(hits, [m])
    >>> alu.values.shape
    (12, 64)
    """
    options = dict(mode=mode, normals=normals, back_faces=back_faces, z0=z0,
                   ray_spacing=ray_spacing, rays_per_bin=rays_per_bin, sampling=sampling,
                   seed=seed, receiver=receiver, backend=backend, sensor=sensor)
    plan, results = _run(scene, ladar, options, Streaming(jobs, executor, progress))
    return _hits(plan, scene, ladar, [h for res in results for h in res])


def _hits(plan, scene, ladar, per_view):
    """The :class:`Hits` record of every view's hits, ranges placed per view."""
    geo, receivers, sensed = plan.geo, plan.receivers, plan.traced_with
    vectors = ladar.view_vectors
    offsets = [range_offset(geo.center, vectors[i],
                             None if receivers is None else receivers[i]) if sensed is None
               else sensor_offset(geo, vectors[i], sensed) for i in range(ladar.n_views)]
    view = np.concatenate([np.full(h.range.size, i, np.int32) for i, h in enumerate(per_view)])

    def field(name):
        parts = [getattr(h, name) for h in per_view]
        return None if parts[0] is None else np.concatenate(parts)

    return Hits(view=view,
                range=np.concatenate([h.range + offsets[i] for i, h in enumerate(per_view)]),
                cos_theta=field("cos_theta"), sin_theta=field("sin_theta"),
                material=field("material"), spread=field("spread"),
                rays=np.array([h.rays for h in per_view]),
                back_face_hits=np.array([h.back_face_hits for h in per_view]),
                area=plan.area, mode=plan.mode, normals=plan.normals, ladar=ladar,
                materials=tuple(scene.materials), bistatic=field("bistatic"),
                weight_factor=field("weight_factor"), curve=field("curve"),
                receive_factor=field("receive_factor"), info=_run_info(plan))


def simulate_mesh(scene, ladar, *, mode=None, normals=None, back_faces="two-sided", z0=None,
                  ray_spacing=None, rays_per_bin=None, footprint=None, sampling=None,
                  seed=None, receiver=None, jobs=None, executor=None, progress=False,
                  run_dir=None, backend="auto", radiometry="paper", sensor=None) -> Sinogram:
    """Trace and weigh in one streaming pass.

    Each chunk of views is binned and its hits dropped, so memory stays bounded whatever
    the number of views and rays. An analytic scene is tessellated first (1024 segments
    per shape, see :meth:`Scene.tessellate`). The accuracy knob (``tol``, ``max_rays``) is
    :func:`meshladar.simulate`'s, which refines runs of this function
    (:mod:`meshladar.forward.refine`). Before the first ray, with smooth or exact normals,
    it warns for each part whose coating's specular lobe the ray spacing cannot resolve
    (fewer than 2 regular or 4 stratified rays across it), with the spacing that would
    (:mod:`meshladar.forward.sampling`).

    Parameters
    ----------
    scene, ladar : Scene, Ladar
    mode, normals, back_faces, z0, ray_spacing, rays_per_bin, sampling, seed, receiver,
    jobs, executor, progress, backend
        As :func:`trace` (default normals "flat").
    footprint : bool, optional
        As :func:`meshladar.weigh` (default False: point binning).
    radiometry : {"paper", "power"}
        "paper" (default): Eq. 8, Σ F(θ)·δA⊥ per bin; "power": received power,
        Σ F·cos θr·δA⊥ (:mod:`meshladar.sensor`).
    sensor : meshladar.sensor.Sensor, optional
        As :func:`trace`. With ``pulse_energy``, ``aperture_diameter`` and a standoff,
        received power comes out in photoelectrons per bin (``info["units"]``).
    run_dir : path, optional
        Makes the run resumable and loss-free (:mod:`meshladar.runs`): each finished chunk
        of views is saved there atomically with a checksum, and running the same job again
        reuses them and computes only what is missing.

    Returns
    -------
    Sinogram
        ``values`` (n_views, n_bins) bin integrals of F(θ) cos θ dA (paper Eq. 8) or of
        F cos θ_i cos θ_r dA (power), model "mesh"; ``info`` records radiometry, mode,
        normals, footprint, ray_spacing, sampling, seed, rays cast and back-face hits per
        view.

    References
    ----------
    Jin & Levine (2009), Eq. 8 (the ``"paper"`` radiometry's bin integral).
    """
    normals = "flat" if normals is None else normals
    footprint = False if footprint is None else footprint
    check_radiometry(radiometry)
    if isinstance(scene, Scene) and not scene.is_mesh:
        scene = scene.tessellate(1024)
    weighing = Weighing(tuple(scene.materials) if isinstance(scene, Scene) else (),
                        footprint=footprint, radiometry=radiometry, edges=(ladar.bin_edges,)
                        if isinstance(ladar, Ladar) else ())
    options = dict(mode=mode, normals=normals, back_faces=back_faces, z0=z0,
                   ray_spacing=ray_spacing, rays_per_bin=rays_per_bin, sampling=sampling,
                   seed=seed, receiver=receiver, backend=backend, sensor=sensor)
    plan, results = _run(scene, ladar, options,
                         Streaming(jobs, executor, progress, run_dir), weighing)
    vals, rays, back = (joined(results, k) for k in ("values", "rays", "backs"))
    run = _run_info(plan)
    if not np.any(vals):
        _warn_empty(scene, ladar, run, back_faces, int(back.sum()), plan.geo.face_normals)
    return _sinogram(vals, ladar, ladar.bin_edges, run, normals=normals, footprint=footprint,
                     rays=rays, back=back, radiometry=radiometry)


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
                  "; ".join(reasons), MeshladarWarning, stacklevel=user_stacklevel())
