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
cover its hits (tests/forward/test_resolved.py).
"""

from __future__ import annotations

import warnings

import numpy as np

from .._validate import check_size, finite_array
from ..errors import MeshladarWarning, ParameterError, user_stacklevel
from ..motion import Motion
from ..raytrace.plan import plan_trace
from ..returns import COORDINATES, Returns
from ..runs import array_digest as digest
from ..scene import Scene
from ..sensor import check_radiometry
from ..stream import joined
from ..weighing.record import Weighing
from .mesh import Streaming, run_plan
from .sampling import warn_unresolved_lobes

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
        raise ParameterError(f"motion must be a meshladar.motion.Motion; got "
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

    Raises
    ------
    ParameterError
        If ``axes`` does not give one to three distinct coordinates of
        :data:`COORDINATES`, each with strictly increasing 1-D finite edges (at least 2),
        a ``"doppler"`` axis comes without a :class:`Motion`, ``motion`` is not one,
        ``radiometry`` is invalid, or the result would need more memory than meshladar
        allocates at once; and whatever the mesh model's plan refuses.

    Examples
    --------
    >>> import numpy as np, trimesh, meshladar as ml
    >>> ball = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=3, radius=0.5),
    ...                           material=ml.materials.DARK_GRAY)
    >>> ladar = ml.Ladar.covering(ball, n_bins=64, angles_deg=[0.0, 90.0])
    >>> e = np.linspace(-0.6, 0.6, 33)
    >>> image = resolve(ball, ladar, [("cross_range", e), ("elevation", e)])
    >>> image.values.shape                           # angle-angle images, one per view
    (2, 32, 32)
    """
    names, edges = _check_axes(axes, motion)
    check_radiometry(radiometry)
    if isinstance(scene, Scene) and not scene.is_mesh:
        scene = scene.tessellate(1024)
    weighing = Weighing(tuple(scene.materials) if isinstance(scene, Scene) else (),
                        radiometry=radiometry, axes=names, edges=edges, motion=motion)
    options = dict(mode=mode, normals=normals, back_faces=back_faces, z0=z0,
                   ray_spacing=ray_spacing, rays_per_bin=rays_per_bin, sampling=sampling,
                   seed=seed, backend=backend, sensor=sensor)
    plan = plan_trace(scene, ladar, **options)
    cells = float(np.prod([e.size - 1 for e in edges]))
    # the result and the chunks' copies of it before they are joined
    check_size("axes", cells * ladar.n_views, 8 * 2,
               f"{ladar.n_views} views of {' x '.join(str(e.size - 1) for e in edges)} cells",
               "give fewer or wider bins, or fewer views")
    weighing.check(plan)                            # every rule, before the first ray
    warn_unresolved_lobes(scene, weighing.materials, spacing=plan.spacing,
                          normals=plan.normals, mode=plan.mode, sampling=plan.sampling)
    description = None
    if run_dir is not None:
        description = _description(plan, scene, ladar, weighing)
    results = run_plan(plan, weighing, ladar, Streaming(jobs, executor, progress, run_dir),
                       description, chunk_size=_CHUNK_VIEWS)
    return _returns(plan, weighing, ladar, results)


#: Views per chunk of a resolved run (its run folders' chunks).
_CHUNK_VIEWS = 8


def _description(plan, scene, ladar, weighing):
    """Everything that determines a resolved run's result, for its run folder."""
    motion = weighing.motion
    return {"kind": "resolve", "geometry": plan.geo.key, "normals": plan.geo.normals,
            "materials": [repr(m) for m in scene.materials], "axes": list(weighing.axes),
            "edges": [digest(e) for e in weighing.edges], "radiometry": weighing.radiometry,
            "motion": None if motion is None else motion.describe(),
            "view_vectors": digest(ladar.view_vectors), "mode": plan.mode,
            "sensor": None if plan.sensor is None else plan.sensor.describe(),
            "ray_spacing": plan.spacing, "z0": plan.z0, "back_faces": plan.back_faces,
            "seed": plan.seed}


def _warn_empty(weighing, rays):
    """All cells zero (issue 29: said by simulate, silent here): name each axis's bins."""
    if rays == 0:
        why = "no ray hit the target (check the views and the ray spacing)"
    else:
        why = (f"{rays} rays hit the target but every return fell outside the cells: " +
               ", ".join(f"{a} bins [{e[0]:.6g}, {e[-1]:.6g}]"
                         for a, e in zip(weighing.axes, weighing.edges)) +
               " (widen them to the target's ranges, cross-ranges or Doppler shifts)")
    warnings.warn(f"the returns are all zeros: {why}", MeshladarWarning, stacklevel=user_stacklevel())


def _returns(plan, weighing, ladar, results):
    """The :class:`Returns` record of a resolved run, photoelectrons where counted."""
    sensor, motion = plan.sensor, weighing.motion
    info = {"radiometry": weighing.radiometry, "mode": plan.mode, "normals": plan.normals,
            "sampling": plan.sampling, "seed": plan.seed, "ray_spacing": plan.spacing,
            "rays": int(joined(results, "rays").sum()), "backend": plan.backend,
            "units": ("length" if plan.mode == "slice" else "area") + "/sr",
            "motion": None if motion is None else motion.describe(),
            "frame": "u = z x w / |z x w| (x for w along z), v = w x u"}
    values = joined(results, "values")
    if not np.any(values):
        _warn_empty(weighing, info["rays"])
    if sensor is not None:
        info["sensor"] = sensor.describe()
        if sensor.counts_photons:
            values = values * sensor.photoelectrons_per_unit()
            info["units"] = "photoelectrons"
    return Returns(values, axes=weighing.axes, edges=weighing.edges,
                   angles_deg=ladar.angles_deg, view_vectors=ladar.view_vectors, info=info)
