"""The mesh model's entry points: :func:`trace` (hits, geometry only), :func:`simulate_mesh`
(trace and weigh in one streaming pass), and the viewer's queries :func:`first_hits` and
:func:`occluded`. Each builds the geometry once and hands :mod:`meshladar.stream` a
per-chunk job; weighing is :mod:`meshladar.weighing`'s."""

from __future__ import annotations

import os
import warnings

import numpy as np

from .._validate import check_choice, check_flag, check_real, unit_vectors
from ..errors import MeshladarWarning, ParameterError
from ..ladar import Ladar
from ..precision import MIN_COS_FACET as _MIN_COS_FACET
from ..precision import RECEIVER_LIFT as _RECEIVER_LIFT
from ..scene import Scene
from ..sinogram import Sinogram
from ..weighing import _bin_one, _material_table, _sinogram, _weights
from ..raytrace.perspective import _trace_sensor_view
from ..weighing.fused import cast_bin_grid
from ..weighing.faces import (_face_bistatic_weights, _face_footprints, _face_weights,
                              face_bistatic_weights, face_footprints, face_weights)
from ..raytrace.embree import _embree_scene, geometry, resolve_backend
from ..raytrace.grid import (MAX_RAYS_PER_VIEW, MODES, _dot, _estimate_rays, _frame, _grid_plan,
                   _largest_grid, _ray_grid, _sampling, _spacing)
from ..raytrace.hits import Hits
from ..raytrace.views import BACK_FACES, NORMALS, _bistatic_angles, _range_offset, _trace_view
from ..precision import PARALLEL_SLACK
from ..precision import TINY

__all__ = ["trace", "simulate_mesh", "first_hits", "occluded"]


#: Views per task: enough work to amortise a task, few enough to balance two cores.
_VIEWS_PER_TASK = 8


def _views_per_task(n_views):
    """Views per chunk: :data:`_VIEWS_PER_TASK`, but a quarter of the views when they are
    fewer than 32, so a handful of big views still spreads over the threads (8 views of
    1e6 rays were one chunk, hence one thread). It depends on the views alone, so a run
    folder's chunks are the same on any machine."""
    return int(min(_VIEWS_PER_TASK, max(1, n_views // 4)))



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
    geo = geometry(scene, normals)
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



def _job(geo, views, ladar_vectors, mode, spacing, z0_shifted, back_faces, seed, edges,
         weigh_with, receivers=None, backend="embreex", row_jobs=1, sensor=None):
    """Trace a chunk of views (the stream's per-chunk job): the views' hits (``weigh_with``
    None), or their binned values, rays and back-face hits as a dict of arrays."""
    scene = _embree_scene(geo, backend)
    if sensor is not None:
        return _sensor_job(geo, scene, views, ladar_vectors, mode, spacing, z0_shifted,
                           back_faces, seed, edges, weigh_with, sensor)
    if (weigh_with is not None and receivers is None
            and (geo.normals == "flat" or geo.normals == "smooth"
                 and all(m.kernel_params is not None for m in weigh_with[0]))):
        return _fast_job(geo, scene, ladar_vectors, views, mode, spacing, z0_shifted,
                         back_faces, seed, edges, weigh_with[0], weigh_with[2], row_jobs,
                         weigh_with[3], weigh_with[1])
    if (weigh_with is not None and receivers is not None and geo.normals == "flat"
            and scene.fused and (mode == "3d" or seed is None)):
        return _fast_job(geo, scene, ladar_vectors, views, mode, spacing, z0_shifted,
                         back_faces, seed, edges, weigh_with[0], weigh_with[2], row_jobs,
                         weigh_with[3], receivers=receivers)
    out = []
    for i in views:
        w = ladar_vectors[i]
        w_r = None if receivers is None else receivers[i]
        rng = None if seed is None else np.random.default_rng([seed, int(i)])
        out.append(_trace_view(geo, scene, w, mode, spacing, z0_shifted, back_faces, rng,
                               w_r, footprint=weigh_with is None or weigh_with[1]))
    if weigh_with is None:
        return out
    materials, footprint, area, power = weigh_with
    vals = np.zeros((len(views), len(edges) - 1))
    for j, (i, h) in enumerate(zip(views, out)):
        r = h.range + _range_offset(geo.center, ladar_vectors[i],
                                 None if receivers is None else receivers[i])
        vals[j] = _bin_one(r, h.cos_theta, h.sin_theta, h.material, h.spread, materials, edges,
                           area, footprint, h.bistatic, h.weight_factor, h.curve, power)
    return {"values": vals, "rays": np.array([h.rays for h in out], np.int64),
            "backs": np.array([h.back_face_hits for h in out], np.int64)}



def _sensor_job(geo, scene, views, vectors, mode, spacing, z0_shifted, back_faces, seed,
                edges, weigh_with, sensor):
    """:func:`_job` for a view seen by a sensor (finite standoff, a beam): hits from
    :func:`meshladar.raytrace.perspective._trace_sensor_view`, weighed point by point."""

    # compiled loops (numba) load on first use while meshladar/__init__ imports trace eagerly
    from ..weighing.sensor_view import _bin_sensor_view

    if (weigh_with is not None and sensor.standoff is not None
            and geo.normals in ("flat", "smooth")
            and all(m.kernel_params is not None for m in weigh_with[0])):
        materials, _, area, power = weigh_with
        vals = np.zeros((len(views), len(edges) - 1))
        rays, backs = [], []
        for j, i in enumerate(views):
            rng = None if seed is None else np.random.default_rng([seed, int(i)])
            n, back = _bin_sensor_view(geo, scene, vectors[i], spacing, back_faces, rng,
                                       sensor, materials, area, power, edges, vals[j])
            rays.append(n)
            backs.append(back)
        return {"values": vals, "rays": np.array(rays, np.int64),
                "backs": np.array(backs, np.int64)}
    out = []
    for i in views:
        rng = None if seed is None else np.random.default_rng([seed, int(i)])
        out.append(_trace_sensor_view(geo, scene, vectors[i], mode, spacing, z0_shifted,
                                      back_faces, rng, sensor))
    if weigh_with is None:
        return out
    materials, _, area, power = weigh_with
    vals = np.zeros((len(views), len(edges) - 1))
    for j, (i, h) in enumerate(zip(views, out)):
        r = h.range + _sensor_offset(geo, vectors[i], sensor)
        vals[j] = _bin_one(r, h.cos_theta, h.sin_theta, h.material, h.spread, materials, edges,
                           area, False, None, h.weight_factor, None, power, h.receive_factor)
    return {"values": vals, "rays": np.array([h.rays for h in out], np.int64),
            "backs": np.array([h.back_face_hits for h in out], np.int64)}


def _sensor_offset(geo, w, sensor):
    """What the range of a sensor's hit is relative to: absolute (R − D − aim·w) at a finite
    standoff, the shifted centre's plane at infinity."""
    return 0.0 if sensor.standoff is not None else _range_offset(geo.center, w, None)


def _fast_job(geo, scene, vectors, views, mode, spacing, z0_shifted, back_faces, seed, edges,
              materials, area, row_jobs=1, power=False, footprint=False, receivers=None):
    """The common cases in one compiled loop per view: monostatic, point or footprint
    binning, flat normals (any coating) or smooth ones (coatings with a compiled kernel:
    SR, Lambertian), no per-hit arrays beyond Embree's own output. With flat
    normals F·area is one number per face and view: the compiled SR kernel evaluates it at
    a face's first hit when every coating has ``kernel_params``; any other coating (Phong,
    GGX, a table, a user's model) has it evaluated for all faces at once through its own
    ``value`` before the view is cast. A footprint's extent is also one row per face and
    view (:func:`_face_footprints`). Bistatic views (``receivers``, flat normals, the
    packet backend's fused loop) have every face's weight for the pair of directions
    evaluated before the cast too (:func:`_face_bistatic_weights`); the loop casts each
    hit's occlusion ray toward the receiver."""
    # compiled loops (numba) load on first use while meshladar/__init__ imports trace eagerly
    from ..weighing._kernels import bin_flat_hits, bin_smooth_hits

    compiled = all(m.kernel_params is not None for m in materials)
    params = _material_table(materials) if compiled else np.zeros((len(materials), 7))
    # each face's F·area for the view being binned (valid where stamp is the view's tag)
    stamp = np.zeros(len(geo.faces), np.int64)
    weight = np.empty(len(geo.faces))
    vals = np.zeros((len(views), len(edges) - 1))
    fp = np.zeros((len(geo.faces) if footprint else 0, 4))
    rays, backs = [], []
    for j, i in enumerate(views):
        w = vectors[i]
        rng = None if seed is None else np.random.default_rng([seed, int(i)])
        w_r = None if receivers is None else receivers[i]
        start = _range_offset(geo.center, w, w_r)
        if footprint:
            _face_footprints(geo, w, mode, spacing, fp)
        if geo.normals == "smooth":
            o, L, _, _ = _ray_grid(geo, w, mode, spacing, z0_shifted, rng)
            res = scene.run(o, np.ascontiguousarray((-w)[None, :], dtype=np.float32),
                            output=1)
            backs.append(bin_smooth_hits(
                res["primID"], res["tfar"], res["u"], res["v"], o, geo.plane_d,
                geo.face_normals, geo.corner, geo.material, params, w, start, edges, area,
                power, back_faces == "ignore", _MIN_COS_FACET, vals[j], fp))
            rays.append(len(o))
            continue
        receiver = None
        if w_r is not None:
            _face_bistatic_weights(geo, materials, w, w_r, area, weight, power,
                                   back_faces == "ignore")
            stamp[:] = j + 1
            receiver = (w_r, _RECEIVER_LIFT * geo.radius)
        elif not compiled:
            _face_weights(geo, materials, w, area, weight, power)
            stamp[:] = j + 1                         # every face's weight is this view's
        bins = (geo.plane_d, geo.face_normals, geo.material, params, w, start, edges, area,
                power, back_faces == "ignore", vals[j], stamp, weight, j + 1, fp)
        if scene.fused and (mode == "3d" or rng is None):
            # packets: grid, cast, weigh and bin in one loop, no per-ray arrays
            plan = _grid_plan(geo, w, mode, spacing, z0_shifted, rng)
            if row_jobs > 1:
                back, n = _rows_on_threads(scene, plan, w, spacing, bins, row_jobs,
                                           receiver)
            else:
                back, n = cast_bin_grid(scene, plan, w, spacing, bins, receiver)
        else:
            o, L, _, _ = _ray_grid(geo, w, mode, spacing, z0_shifted, rng)
            res = scene.run(o, np.ascontiguousarray((-w)[None, :], dtype=np.float32),
                            output=1)
            back, n = bin_flat_hits(res["primID"], res["tfar"], o, *bins), len(o)
        backs.append(back)
        rays.append(n)
    return {"values": vals, "rays": np.array(rays, np.int64), "backs": np.array(backs, np.int64)}



def _rows_on_threads(scene, plan, w, spacing, bins, row_jobs, receiver=None):
    """One big view's grid split into ``row_jobs`` bands of rows, cast on as many threads
    (the fused loop releases the GIL), each band with its own bins and a copy of the weight
    cache (weights already evaluated for the view stay valid); the
    bands' bins are added in order, so a given ``row_jobs`` always gives the same numbers
    (and the one-thread numbers to rounding). Returns (back-face hits, rays cast)."""
    from concurrent.futures import ThreadPoolExecutor

    s, t, du, dv, u, v, L = plan
    *head, out, stamp, weight, tag, fp = bins
    cuts = np.linspace(0, s.size, row_jobs + 1).astype(int)
    parts = []
    for a0, a1 in zip(cuts[:-1], cuts[1:]):
        if a1 > a0:
            band = (s[a0:a1], t, None if du is None else du[a0:a1],
                    None if dv is None else dv[a0:a1], u, v, L)
            parts.append((band, np.zeros_like(out), stamp.copy(), weight.copy()))
    with ThreadPoolExecutor(len(parts)) as ex:
        done = list(ex.map(lambda p: cast_bin_grid(scene, p[0], w, spacing,
                                                         (*head, p[1], p[2], p[3], tag, fp),
                                                         receiver),
                           parts))
    for _, band_out, _, _ in parts:
        out += band_out
    return sum(b for b, _ in done), sum(n for _, n in done)


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
    geo = geometry(scene, "flat")
    emb = _embree_scene(geo, resolve_backend("auto"))
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
    geo = geometry(scene, "flat")
    emb = _embree_scene(geo, resolve_backend("auto"))
    p = np.asarray(points, dtype=np.float64) - geo.center + lift * geo.radius * d
    return emb.run(np.ascontiguousarray(p, dtype=np.float32),
                   np.ascontiguousarray(d[None, :], dtype=np.float32), query="OCCLUDED") != -1



def _receivers(receiver, ladar, mode, footprint):
    if receiver is None:
        return None
    if np.shape(receiver) not in ((3,), (ladar.n_views, 3)):
        raise ParameterError(f"receiver must be a direction (3,) or one per view "
                             f"({ladar.n_views}, 3); got shape {np.shape(receiver)}")
    r = np.broadcast_to(unit_vectors("receiver", receiver), (ladar.n_views, 3))
    if np.any(np.einsum("ij,ij->i", r, ladar.view_vectors) <= -1 + PARALLEL_SLACK):
        k = int(np.argmax(np.einsum("ij,ij->i", r, ladar.view_vectors) <= -1 + PARALLEL_SLACK))
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
    from ..runs import array_digest as digest

    mats, footprint, area, power = weigh_with
    return {"kind": "simulate_mesh", "radiometry": "power" if power else "paper", "geometry": geo.key, "normals": geo.normals,
            "materials": [repr(m) for m in mats], "view_vectors": digest(ladar.view_vectors),
            "bin_edges": digest(ladar.bin_edges), "n_views": ladar.n_views, "mode": mode,
            "ray_spacing": spacing, "z0": z0, "back_faces": back_faces, "seed": seed,
            "footprint": bool(footprint), "receivers": None if receivers is None
            else digest(receivers)}



def _check_sensor(sensor, receiver, footprint, mode):
    """The sensor a job traces with: None for none, or for one that changes nothing (at
    infinity, an unbounded flood: the compiled loops apply)."""
    from ..sensor import FloodBeam, Sensor

    if sensor is None:
        return None
    if not isinstance(sensor, Sensor):
        raise ParameterError(f"sensor must be a meshladar.sensor.Sensor; got "
                             f"{type(sensor).__name__}")
    if receiver is not None:
        raise ParameterError("a sensor is monostatic (its receiver sits with its "
                             "transmitter); drop receiver or sensor")
    if footprint:
        raise ParameterError("footprint binning is for parallel rays without a sensor; use "
                             "footprint=False with a sensor")
    if sensor.standoff is not None and mode != "3d":
        raise ParameterError("a sensor at a finite standoff needs mode='3d' (its rays fan "
                             "out in both transverse directions)")
    if sensor.standoff is None and isinstance(sensor.beam, FloodBeam) \
            and sensor.beam.radius is None:
        return None
    return sensor


def _run(scene, ladar, *, mode, normals, back_faces, z0, ray_spacing, rays_per_bin, seed,
         jobs, executor, progress, weigh_with, receiver=None, run_dir=None, sampling=None,
         backend="auto", sensor=None):
    mode, geo, z0 = _options(scene, ladar, mode, normals, back_faces, z0)
    traced_with = _check_sensor(sensor, receiver, bool(weigh_with and weigh_with[1]), mode)
    backend = resolve_backend(backend)
    sampling, seed = _sampling(mode, sampling, seed)
    if weigh_with is not None:
        check_flag("footprint", weigh_with[1])
    receivers = _receivers(receiver, ladar, mode, bool(weigh_with and weigh_with[1]))
    spacing = _spacing(ladar, mode, ray_spacing, rays_per_bin, geo.radius)
    per_view = _largest_grid(geo, ladar.view_vectors, mode, spacing, MAX_RAYS_PER_VIEW)
    if per_view > MAX_RAYS_PER_VIEW:
        raise ParameterError(
            f"one view would cast about {per_view:.3g} rays (ray spacing {spacing:.3g} over "
            f"a target {2 * geo.radius:.3g} across), more than the {MAX_RAYS_PER_VIEW:.0e} a "
            "view may hold in memory; give a larger ray_spacing (or fewer rays_per_bin, "
            "or wider bins)")
    area = spacing if mode == "slice" else spacing * spacing
    if weigh_with is not None:
        weigh_with = (weigh_with[0], weigh_with[1], area, weigh_with[2])
    z0_shifted = z0 - float(geo.center[2])
    check_flag("progress", progress)
    from ..stream import run_chunks

    job = None
    if run_dir is not None:
        job = _job_description(geo, scene, ladar, mode, spacing, z0, back_faces, seed,
                               weigh_with, receivers)
        job["sensor"] = None if sensor is None else sensor.describe()
    work = _estimate_rays(geo, ladar, mode, spacing)
    results = run_chunks(
        _job, geo, ladar.n_views, chunk_size=_views_per_task(ladar.n_views),
        args=(np.asarray(ladar.view_vectors, dtype=np.float64), mode, spacing, z0_shifted,
              back_faces, seed, ladar.bin_edges, weigh_with, receivers, backend,
              _row_jobs(ladar.n_views, jobs, executor, work), traced_with),
        jobs=jobs, executor=executor, progress=progress, unit="views",
        work=work, run_dir=run_dir, job=job,
        arrays={"values": (ladar.n_bins,), "rays": (), "backs": ()}, threads=True)
    run = {"mode": mode, "ray_spacing": spacing, "z0": z0, "sampling": sampling, "seed": seed,
           "receiver": receivers, "backend": backend, "sensor": sensor,
           "traced_with": traced_with}
    return geo, run, area, results


def _row_jobs(n_views, jobs, executor, work):
    """Threads for the rows of a single view (the stream parallelises chunks of views):
    ``jobs``, or one per core once the view is worth it; 1 with an executor or an invalid
    ``jobs`` (which the stream then refuses)."""
    from ..stream import _MAX_JOBS_PER_CORE, _THREADS_FROM

    if n_views != 1 or executor is not None:
        return 1
    if jobs is None:
        return (os.cpu_count() or 1) if work >= _THREADS_FROM else 1
    ok = isinstance(jobs, (int, np.integer)) and not isinstance(jobs, bool) and 1 <= jobs
    return min(int(jobs), _MAX_JOBS_PER_CORE * (os.cpu_count() or 1)) if ok else 1


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
        2e5 rays in all, else one per core (at most one per chunk of 8 views).
    executor : concurrent.futures.Executor, optional
        Any executor (e.g. a Dask client's, whose workers are processes on other machines)
        to run chunks of views on; overrides ``jobs``.
    progress : bool
        A progress bar on a terminal.
    backend : {"auto", "packets", "embreex"}
        How rays are cast: "packets", coherent packets of the CPU's native width through
        the Embree 4 library embreex ships (:mod:`meshladar.raytrace.embree4`); "embreex",
        one ray at a time through embreex (the reference); "auto" (default), packets when
        they load, else embreex with one warning saying so. Both give the same hits (a ray
        exactly along an edge shared by two faces may report the other face). The result's
        ``info["backend"]`` says which ran.
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
    >>> hits = ml.trace(scene, ladar)                        # geometry only, traced once
    >>> for m in (ml.materials.DARK_GRAY, ml.materials.ALUMINUM):
    ...     sino = ml.weigh(hits, [m])                        # any coating, no new trace
    """
    geo, run, area, results = _run(
        scene, ladar, mode=mode, normals=normals, back_faces=back_faces, z0=z0,
        ray_spacing=ray_spacing, rays_per_bin=rays_per_bin, seed=seed, jobs=jobs,
        executor=executor, progress=progress, weigh_with=None, receiver=receiver,
        sampling=sampling, backend=backend, sensor=sensor)
    receivers = run["receiver"]
    per_view = [h for res in results for h in res]
    vectors = ladar.view_vectors
    sensed = run["traced_with"]
    offsets = [_range_offset(geo.center, vectors[i],
                             None if receivers is None else receivers[i]) if sensed is None
               else _sensor_offset(geo, vectors[i], sensed) for i in range(ladar.n_views)]
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
                weight_factor=joined("weight_factor"), curve=joined("curve"),
                receive_factor=joined("receive_factor"), info=run)



def simulate_mesh(scene, ladar, *, mode=None, normals=None, back_faces="two-sided", z0=None,
                  ray_spacing=None, rays_per_bin=None, footprint=None, sampling=None,
                  seed=None, receiver=None, jobs=None, executor=None, progress=False,
                  run_dir=None, backend="auto", radiometry="paper", sensor=None) -> Sinogram:
    """Trace and weigh in one streaming pass.

    Each chunk of views is binned and its hits dropped, so memory stays bounded whatever
    the number of views and rays. An analytic scene is tessellated first (1024 segments
    per shape, see :meth:`Scene.tessellate`). The accuracy knob (``tol``, ``max_rays``) is
    :func:`meshladar.simulate`'s, which refines runs of this function
    (:mod:`meshladar.refine`).

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
        F cos θ_i cos θ_r dA (power), model "mesh"; ``info`` records radiometry, mode, normals, footprint, ray_spacing,
        sampling, seed, rays cast and back-face hits per view.
    """
    normals = "flat" if normals is None else normals
    footprint = False if footprint is None else footprint
    from ..sensor import check_radiometry

    power = check_radiometry(radiometry)
    if isinstance(scene, Scene) and not scene.is_mesh:
        scene = scene.tessellate(1024)
    geo, run, area, results = _run(
        scene, ladar, mode=mode, normals=normals, back_faces=back_faces, z0=z0,
        ray_spacing=ray_spacing, rays_per_bin=rays_per_bin, seed=seed, jobs=jobs,
        executor=executor, progress=progress,
        weigh_with=(tuple(scene.materials), footprint, power),
        receiver=receiver, run_dir=run_dir, sampling=sampling, backend=backend,
        sensor=sensor)
    from ..stream import joined

    vals, rays, back = (joined(results, k) for k in ("values", "rays", "backs"))
    if not np.any(vals):
        _warn_empty(scene, ladar, run, back_faces, int(back.sum()), geo.face_normals)
    return _sinogram(vals, ladar, ladar.bin_edges, run, normals, footprint, rays, back,
                     radiometry)



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
