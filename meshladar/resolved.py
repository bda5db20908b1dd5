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

from dataclasses import dataclass, field

import numpy as np

from ._validate import check_real, finite_array, readonly_copy
from .errors import ParameterError

__all__ = ["COORDINATES", "Motion", "Returns", "resolve"]

#: The coordinates a view's returns can be binned by (module docstring).
COORDINATES = ("range", "cross_range", "elevation", "doppler")


def _vector(name, value):
    a = finite_array(name, value)
    if a.shape != (3,):
        raise ParameterError(f"{name} must be a 3-vector; got shape {a.shape}")
    return tuple(float(x) for x in a)


@dataclass(frozen=True)
class Motion:
    """A rigid target's motion, for Doppler.

    Parameters
    ----------
    omega : (3,) float
        Rotation vector Ω (rad/s): the axis times the rate, right-handed (a turntable
        turning counter-clockwise seen from above at 0.1 rad/s: (0, 0, 0.1)).
    center : (3,) float
        A point on the rotation axis (m; default the origin).
    velocity : (3,) float
        Translation V (m/s).
    wavelength : float
        λ (m; default 1.064e-6).
    """

    omega: tuple = (0.0, 0.0, 0.0)
    center: tuple = (0.0, 0.0, 0.0)
    velocity: tuple = (0.0, 0.0, 0.0)
    wavelength: float = 1.064e-6

    def __post_init__(self):
        for name in ("omega", "center", "velocity"):
            object.__setattr__(self, name, _vector(name, getattr(self, name)))
        object.__setattr__(self, "wavelength", check_real("wavelength", self.wavelength,
                                                          low=0.0, low_open=True))

    def doppler(self, points, w):
        """f_D (Hz) of ``points`` (k, 3) seen from view ``w``: 2 (V + Ω × (p − c))·w / λ."""
        rel = np.asarray(points, np.float64) - np.asarray(self.center)
        vel = np.cross(np.asarray(self.omega), rel) + np.asarray(self.velocity)
        return 2.0 * (vel @ np.asarray(w, np.float64)) / self.wavelength

    def describe(self):
        return {"omega_rad_per_s": list(self.omega), "center_m": list(self.center),
                "velocity_m_per_s": list(self.velocity), "wavelength_m": self.wavelength}


_UNITS = {"range": "m", "cross_range": "m", "elevation": "m", "doppler": "Hz"}


@dataclass(frozen=True, eq=False)
class Returns:
    """Returns of many views binned by one to three coordinates.

    ``values`` (n_views, n_0[, n_1[, n_2]]): per cell, the sum of the weights of the rays whose
    first hit lies in it (bin integrals, as a sinogram's); ``axes`` the coordinates' names
    (:data:`COORDINATES`), ``edges`` their bin edges (in ``units``); ``angles_deg`` and
    ``view_vectors`` the views; ``info`` the run's parameters (radiometry, units, motion).
    """

    values: np.ndarray
    axes: tuple = field(kw_only=True)
    edges: tuple = field(kw_only=True)
    angles_deg: np.ndarray = field(kw_only=True)
    view_vectors: np.ndarray = field(kw_only=True)
    info: dict = field(default_factory=dict, kw_only=True)

    def __post_init__(self):
        v = finite_array("values", self.values)
        edges = tuple(readonly_copy(finite_array(f"edges[{i}]", e))
                      for i, e in enumerate(self.edges))
        if v.ndim != 1 + len(self.axes) or len(edges) != len(self.axes) or any(
                e.shape != (n + 1,) for e, n in zip(edges, v.shape[1:])):
            raise ParameterError(f"values must be (n_views, one size per axis) with edges one "
                                 f"longer per axis; got {v.shape}, axes {self.axes}")
        object.__setattr__(self, "values", readonly_copy(v))
        object.__setattr__(self, "edges", edges)
        object.__setattr__(self, "axes", tuple(self.axes))
        object.__setattr__(self, "angles_deg", readonly_copy(self.angles_deg))
        object.__setattr__(self, "view_vectors", readonly_copy(self.view_vectors))
        object.__setattr__(self, "info", dict(self.info))

    @property
    def units(self) -> tuple:
        return tuple(_UNITS[a] for a in self.axes)

    def centers(self, axis) -> np.ndarray:
        """Bin centres of ``axis`` (a name or an index)."""
        e = self.edges[self._index(axis)]
        return 0.5 * (e[1:] + e[:-1])

    def _index(self, axis):
        if isinstance(axis, str):
            if axis not in self.axes:
                raise ParameterError(f"axis must be one of {self.axes}; got {axis!r}")
            return self.axes.index(axis)
        return int(axis)

    def total(self) -> np.ndarray:
        """(n_views,) each view's total return."""
        return self.values.reshape(self.values.shape[0], -1).sum(axis=1)

    def marginal(self, axis) -> np.ndarray:
        """(n_views, n) the returns binned by ``axis`` alone (summed over the others)."""
        k = self._index(axis)
        others = tuple(1 + j for j in range(len(self.axes)) if j != k)
        return self.values.sum(axis=others) if others else self.values

    def sinogram(self):
        """The range marginal as a :class:`~meshladar.sinogram.Sinogram`."""
        from .sinogram import Sinogram

        planar = bool(np.all(self.view_vectors[:, 2] == 0.0))
        return Sinogram(self.marginal("range"), angles_deg=self.angles_deg,
                        bin_edges=self.edges[self.axes.index("range")], model="mesh",
                        view_vectors=None if planar else self.view_vectors,
                        info=dict(self.info))

    def realise(self, noise, n=1, *, seed=None, dwell=0.0):
        """``n`` noise realisations (n, *values.shape) (:class:`meshladar.receiver.Noise`),
        each cell integrating background and dark counts over ``dwell`` seconds (its range
        gate); the returns must count photoelectrons (a sensor that counts them, or
        :meth:`scaled`)."""
        from ._validate import check_count
        from .receiver import Noise, draw_noise

        if not isinstance(noise, Noise):
            raise ParameterError(f"noise must be a meshladar.receiver.Noise; got "
                                 f"{type(noise).__name__}")
        if self.info.get("units") != "photoelectrons":
            raise ParameterError(f"noise counts photoelectrons; these returns are in "
                                 f"{self.info.get('units')!r}: convert with scaled(factor)")
        dwell = check_real("dwell", dwell, low=0.0)
        if dwell == 0 and (noise.background_rate > 0 or noise.dark_rate > 0):
            raise ParameterError("background and dark counts accumulate over each cell's "
                                 "dwell time: give dwell (s), e.g. its range gate")
        return draw_noise(noise, self.values, dwell, check_count("n", n), seed)

    def scaled(self, factor, units="photoelectrons") -> "Returns":
        f = check_real("factor", factor, low=0.0, low_open=True)
        return Returns(self.values * f, axes=self.axes, edges=self.edges,
                       angles_deg=self.angles_deg, view_vectors=self.view_vectors,
                       info=dict(self.info, units=units, scaled_by=f))

    def _summary(self):
        return (("n_views", self.values.shape[0]),
                *((a, f"[{e[0]:.4g}, {e[-1]:.4g}] {u} in {e.size - 1}")
                  for a, e, u in zip(self.axes, self.edges, self.units)),
                ("units", self.info.get("units")), ("radiometry", self.info.get("radiometry")))

    def __repr__(self) -> str:
        from ._summary import text

        return text("Returns", *self._summary())

    def _repr_html_(self) -> str:
        from ._summary import table

        return table("Returns", *self._summary())


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
    from .raytrace.embree import resolve_backend
    from .raytrace.grid import (MAX_RAYS_PER_VIEW, _estimate_rays, _largest_grid, _sampling,
                                _spacing)
    from .raytrace.model import _options
    from .scene import Scene
    from .sensor import check_radiometry
    from .stream import joined, run_chunks

    from .raytrace.model import _check_sensor

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
        from .runs import array_digest as digest

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
    from .raytrace.embree import _embree_scene
    from .raytrace.grid import _frame
    from .raytrace.model import _sensor_offset
    from .raytrace.perspective import _trace_sensor_view
    from .raytrace.views import _trace_view
    from .weighing import _weights

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
