"""Returns resolved in any linear coordinate of the hit, one to three at a time: range (the
sinogram's), cross-range and elevation (an angle–angle image per view), and Doppler for a
moving target (a turntable's rotation and/or a translation); range–Doppler images, range-gated
image stacks (cross-range, elevation and range: a 3-D point return per view). Mesh model;
the same streaming, executors, run folders and noise as range.

Coordinates of a hit p (world coordinates, metres) in view w, with the view's transverse
axes u = z × w / |z × w| (x when w is along ±z) and v = w × u:

``"range"``        r = −p·w, as every sinogram
``"cross_range"``  p·u (the horizontal angle–angle axis; angle = p·u / standoff)
``"elevation"``    p·v (the vertical one; z for views about the z axis)
``"doppler"``      f_D = 2 (V + Ω × (p − c))·w / λ in Hz, for a target translating at V and
                   rotating at Ω (rad/s, the rotation vector) about the point c
                   (:class:`Motion`); positive when the point approaches the ladar

Each ray's weight is the forward model's (F·δA⊥ under Eq. 8, × cos θ under received
power): whatever coordinates a view is binned by, its total is the same when the bins
cover its hits (tests/test_resolved.py).
"""

from __future__ import annotations

import numpy as np

from .._validate import finite_array
from ..errors import ParameterError
from ..motion import Motion
from ..returns import COORDINATES, Returns

__all__ = ["COORDINATES", "Motion", "Returns", "resolve"]



def _check_axes(axes, motion):
    if isinstance(axes, dict):
        axes = list(axes.items())
    if not isinstance(axes, (list, tuple)) or not 1 <= len(axes) <= 3:
        raise ParameterError(f"axes must give one to three (name, bin_edges) pairs (or a "
                             f"dict of them); got {axes!r}")
    names, edges = [], []
    for item in axes:
        if not isinstance(item, (list, tuple)) or len(item) != 2:
            raise ParameterError(f"axes must give (name, bin_edges) pairs; got {item!r}")
        name, e = item
        if name not in COORDINATES:
            raise ParameterError(f"axis name must be one of {COORDINATES}; got {name!r}")
        e = finite_array(f"{name} bin edges", e)
        if e.ndim != 1 or e.size < 2 or np.any(np.diff(e) <= 0):
            raise ParameterError(f"{name} bin edges must be a strictly increasing 1-D array "
                                 f"of at least 2 edges; got shape {e.shape}")
        names.append(name)
        edges.append(e)
    if len(set(names)) != len(names):
        raise ParameterError(f"axes must be different coordinates; got {names}")
    if "doppler" in names and not isinstance(motion, Motion):
        raise ParameterError("the doppler axis needs motion=Motion(omega=..., velocity=...); "
                             f"got motion={motion!r}")
    if motion is not None and not isinstance(motion, Motion):
        raise ParameterError(f"motion must be a meshladar.resolved.Motion; got "
                             f"{type(motion).__name__}")
    return tuple(names), tuple(edges)


def resolve(scene, ladar, axes, *, motion=None, radiometry="paper", sensor=None, mode=None,
            normals="flat", back_faces="two-sided", z0=None, ray_spacing=None,
            rays_per_bin=None, sampling=None, seed=None, jobs=None, executor=None,
            progress=False, run_dir=None, backend="auto") -> Returns:
    """Returns of a mesh scene binned by one to three coordinates of each hit.

    Parameters
    ----------
    scene, ladar : Scene, Ladar
        A mesh scene (an analytic one is tessellated, 1024 segments per shape) and the
        views; the ladar's range bins set the default ray density only.
    axes : sequence of (name, bin_edges), or a dict
        One to three of :data:`COORDINATES` with their bin edges (m, or Hz for Doppler):
        ``[("cross_range", e), ("elevation", e)]`` is an angle–angle image per view,
        ``[("range", e), ("doppler", f)]`` a range–Doppler image, and
        ``[("cross_range", e), ("elevation", e), ("range", r)]`` a range-gated stack.
    motion : Motion, optional
        The target's rotation and translation (needed for ``"doppler"``).
    radiometry : {"paper", "power"}
        As :func:`meshladar.simulate`.
    sensor : meshladar.sensor.Sensor, optional
        As the mesh model's: a finite standoff (perspective rays, ranges R − D − aim·w),
        a beam, extinction and the link budget (photoelectrons per cell).
    mode, normals, back_faces, z0, ray_spacing, rays_per_bin, sampling, seed, backend
        As :func:`meshladar.trace` (monostatic, point binning).
    jobs, executor, progress, run_dir
        Streaming, as :func:`meshladar.simulate`.

    Returns
    -------
    Returns
        ``values`` (n_views, n_0[, n_1[, n_2]]) with ``axes``, ``edges``, the views and
        ``info``.
    """
    from ..raytrace.embree import resolve_backend
    from ..raytrace.grid import (MAX_RAYS_PER_VIEW, _estimate_rays, _largest_grid, _sampling,
                                _spacing)
    from .mesh import _options
    from ..scene import Scene
    from ..sensor import check_radiometry
    from ..stream import joined, run_chunks

    from .mesh import _check_sensor

    names, edges = _check_axes(axes, motion)
    power = check_radiometry(radiometry)
    if isinstance(scene, Scene) and not scene.is_mesh:
        scene = scene.tessellate(1024)
    mode, geo, z0 = _options(scene, ladar, mode, normals, back_faces, z0)
    traced_with = _check_sensor(sensor, None, False, mode)
    if sensor is not None and (sensor.extinction > 0 or sensor.counts_photons) and not power:
        raise ParameterError("a sensor's extinction and photoelectrons are received power: "
                             "use radiometry='power'")
    backend = resolve_backend(backend)
    sampling, seed = _sampling(mode, sampling, seed)
    spacing = _spacing(ladar, mode, ray_spacing, rays_per_bin, geo.radius)
    if _largest_grid(geo, ladar.view_vectors, mode, spacing,
                     MAX_RAYS_PER_VIEW) > MAX_RAYS_PER_VIEW:
        raise ParameterError(f"one view would cast more than {MAX_RAYS_PER_VIEW:.0e} rays "
                             f"(ray spacing {spacing:.3g}); give a larger ray_spacing")
    area = spacing if mode == "slice" else spacing * spacing
    shape = tuple(e.size - 1 for e in edges)
    job = None
    if run_dir is not None:
        from ..runs import array_digest as digest

        job = {"kind": "resolve", "geometry": geo.key, "normals": geo.normals,
               "materials": [repr(m) for m in scene.materials], "axes": list(names),
               "edges": [digest(e) for e in edges], "radiometry": radiometry,
               "motion": None if motion is None else motion.describe(),
               "view_vectors": digest(ladar.view_vectors), "mode": mode,
               "sensor": None if sensor is None else sensor.describe(),
               "ray_spacing": spacing, "z0": z0, "back_faces": back_faces, "seed": seed}
    results = run_chunks(
        _resolve_job, geo, ladar.n_views, chunk_size=8,
        args=(np.asarray(ladar.view_vectors, np.float64), mode, spacing,
              z0 - float(geo.center[2]), back_faces, seed, tuple(scene.materials), area,
              power, names, edges, motion, backend, traced_with),
        jobs=jobs, executor=executor, progress=progress, unit="views",
        work=_estimate_rays(geo, ladar, mode, spacing), run_dir=run_dir, job=job,
        arrays={"values": shape, "rays": ()}, threads=True)
    info = {"radiometry": radiometry, "mode": mode, "normals": normals, "sampling": sampling,
            "seed": seed, "ray_spacing": spacing, "rays": int(joined(results, "rays").sum()),
            "backend": backend, "units": ("length" if mode == "slice" else "area") + "/sr",
            "motion": None if motion is None else motion.describe(),
            "frame": "u = z x w / |z x w| (x for w along z), v = w x u"}
    values = joined(results, "values")
    if sensor is not None:
        info["sensor"] = sensor.describe()
        if sensor.counts_photons:
            values = values * sensor.photoelectrons_per_unit()
            info["units"] = "photoelectrons"
    return Returns(values, axes=names, edges=edges,
                   angles_deg=ladar.angles_deg, view_vectors=ladar.view_vectors, info=info)


def _resolve_job(geo, views, vectors, mode, spacing, z0_shifted, back_faces, seed, materials,
                 area, power, names, edges, motion, backend, sensor=None):
    """The stream's per-chunk job: each view's hits, weighed and binned by ``names``."""
    from ..raytrace.embree import _embree_scene
    from ..raytrace.grid import _frame
    from .mesh import _sensor_offset
    from ..raytrace.perspective import _trace_sensor_view
    from ..raytrace.views import _trace_view
    from ..weighing import _weights

    scene = _embree_scene(geo, backend)
    shape = tuple(e.size - 1 for e in edges)
    out = np.zeros((len(views),) + shape)
    rays = np.zeros(len(views), np.int64)
    for j, i in enumerate(views):
        w = vectors[i]
        rng = None if seed is None else np.random.default_rng([seed, int(i)])
        if sensor is None:
            h = _trace_view(geo, scene, w, mode, spacing, z0_shifted, back_faces, rng,
                            footprint=False, transverse=True)
            offset = -float(geo.center @ w)
        else:
            h = _trace_sensor_view(geo, scene, w, mode, spacing, z0_shifted, back_faces, rng,
                                   sensor)
            offset = _sensor_offset(geo, w, sensor)
        rays[j] = h.rays
        wt = _weights(h.cos_theta, h.sin_theta, h.material, materials, area, power=power)
        if h.weight_factor is not None:
            wt = wt * h.weight_factor
        if power and h.receive_factor is not None:
            wt = wt * h.receive_factor
        u, v = _frame(w)
        s, t = h.transverse[:, 0], h.transverse[:, 1]
        coords = {"range": h.range + offset,
                  "cross_range": s + float(geo.center @ u),
                  "elevation": t + float(geo.center @ v)}
        if "doppler" in names:
            if sensor is None or sensor.standoff is None:
                points = geo.center + s[:, None] * u + t[:, None] * v - h.range[:, None] * w
            else:
                # the hit point from its transverse coordinates and its true distance
                points = _sensor_points(geo, w, u, v, s, t, h.range, sensor)
            coords["doppler"] = motion.doppler(points, w)
        flat = np.zeros(wt.size, np.int64)
        ok = wt != 0
        for name, e in zip(names, edges):
            k = np.searchsorted(e, coords[name], side="right") - 1
            ok &= (k >= 0) & (k < e.size - 1)
            flat = flat * (e.size - 1) + k
        out[j] = np.bincount(flat[ok], weights=wt[ok],
                             minlength=int(np.prod(shape))).reshape(shape)
    return {"values": out, "rays": rays}


def _sensor_points(geo, w, u, v, s, t, r, sensor):
    """World hit points of a sensor view from their (u, v) coordinates s, t (shifted) and
    ranges r = R − D − aim·w: p − c = s u + t v + a w with a fixed by |p − S| = R."""
    aim = np.asarray(sensor.aim, np.float64)
    S = aim - geo.center + sensor.standoff * w                    # the sensor, shifted
    R = r + sensor.standoff + float(aim @ w)
    q0 = s[:, None] * u + t[:, None] * v - S                       # p − S without its w part
    b = q0 @ w
    c = np.einsum("ij,ij->i", q0, q0) - R * R
    a = -b - np.sqrt(np.maximum(b * b - c, 0.0))                   # the root toward the sensor
    return geo.center + s[:, None] * u + t[:, None] * v + a[:, None] * w
