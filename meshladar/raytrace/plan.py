"""The trace plan (:class:`TracePlan`): everything about a run's geometry, built and
validated once at the API boundary (:func:`plan_trace`), then trusted by every per-chunk
job. Geometry only: which rays (mode, spacing, slice plane, sampling, seed), which hits
(normals, back faces), who receives (collocated, bistatic receivers, a sensor), how they
are cast (backend) and how many (the estimate the stream and the threads are sized by).
Weights are the weigh stage's (:class:`meshladar.weighing.Weighing`, checked against a
plan before the first ray)."""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .._validate import check_choice, check_real, unit_vectors
from ..errors import MeshladarWarning, ParameterError, user_stacklevel
from ..ladar import Ladar
from ..precision import (ORIGIN_MARGIN, PARALLEL_SLACK, SCENE_RADIUS_RANGE,
                         STANDOFF_ROUNDING_SHARE)
from ..scene import Scene
from ..sensor import FloodBeam, Sensor
from .backends import resolve_backend
from .embree import Geometry, geometry
from .grid import (MAX_RAYS_PER_VIEW, MODES, _estimate_rays, _largest_grid, _sampling,
                   _spacing)
from .views import BACK_FACES, NORMALS

__all__ = ["TracePlan", "View", "plan_trace", "check_scene", "check_sensor", "check_receivers",
           "COHERENT_RAYS_PER_FACE", "COHERENT_SCALE"]

#: A grid is dense from this many rays on the face a ray hits (TracePlan.rays_per_face):
#: a slice's rays are cast in coherent packets from there on (below it one at a time,
#: where a packet's rays would part at once), footprints made before the cast.
COHERENT_RAYS_PER_FACE = 1.0
#: 3-D grids are cast in coherent tiles from COHERENT_SCALE / √faces rays a face on, below
#: it one ray at a time (a bigger BVH has more levels that a tile's rays share):
#: icospheres' same tiles with and without Embree's coherent flag even out at 0.45 rays a
#: face at 82k faces, 0.25 at 328k, 0.11 at 1.31M, 0.06 at 5.2M (× √faces: 129, 143,
#: 126, 137), and coherent tiles against single rays near 0.4 at 82k, 0.05 at 1.31M and
#: 3.7 at 1.3k (× √faces: 110, 55, 132; the guide's Sparse grids).
COHERENT_SCALE = 128.0


@dataclass(frozen=True, eq=False)
class TracePlan:
    """A run's geometry, validated once.

    Attributes
    ----------
    geo : Geometry
        The scene's triangles as a worker traces them (shifted, float32 copies).
    mode : {"slice", "3d"}
    normals, back_faces : str
    z0 : float
        The slice plane (scene coordinates; the scene's mid-height in 3-D).
    spacing : float
        Ray spacing δ; ``area`` is δ (slice, per unit height) or δ² (3-D).
    sampling : {"regular", "stratified"}
    seed : int or None
    receivers : (n_views, 3) float64 or None
        Bistatic receiver directions (None: monostatic).
    sensor : Sensor or None
        The sensor as given (results record it).
    traced_with : Sensor or None
        The sensor the job traces with: None where it changes nothing (at infinity, an
        unbounded flood: parallel rays and the compiled loops apply).
    backend : str
        The resolved backend ("packets", "embreex").
    rays : float
        The run's estimated rays (sizes threads and progress).
    """

    geo: Geometry
    mode: str
    normals: str
    back_faces: str
    z0: float
    spacing: float
    sampling: str
    seed: int | None
    receivers: np.ndarray | None
    sensor: Sensor | None
    traced_with: Sensor | None
    backend: str
    rays: float

    @property
    def area(self) -> float:
        """δA⊥ of one ray: δ in slice mode (per unit height), δ² in 3-D."""
        return self.spacing if self.mode == "slice" else self.spacing * self.spacing

    @property
    def rays_per_face(self) -> float:
        """The grid's rays on the face a ray hits: ``geo.hit_face_area`` / δ² in 3-D, its
        square root / δ in a slice."""
        a = self.geo.hit_face_area
        return a / self.area if self.mode == "3d" else math.sqrt(a) / self.spacing

    @property
    def dense(self) -> bool:
        """Whether the grid is dense: at least :data:`COHERENT_RAYS_PER_FACE` rays on the
        face a ray hits (footprint bins then make every face's row before the cast)."""
        return self.rays_per_face >= COHERENT_RAYS_PER_FACE

    @property
    def coherent(self) -> bool:
        """Whether the grid's rays are cast in coherent packets (else one at a time): in
        3-D from :data:`COHERENT_SCALE` / √faces rays on the face a ray hits, in a slice
        where the grid is :attr:`dense`."""
        if self.mode == "3d":
            return self.rays_per_face * math.sqrt(len(self.geo.faces)) >= COHERENT_SCALE
        return self.dense

    @property
    def z0_shifted(self) -> float:
        """The slice plane relative to the geometry's centre (as the grids are built)."""
        return self.z0 - float(self.geo.center[2])

    @property
    def ignore_back(self) -> bool:
        """Whether back-face hits are blocked (``back_faces == "ignore"``)."""
        return self.back_faces == "ignore"


class View(NamedTuple):
    """One view of a chunk: its slot in the chunk, its index, its direction w (3,), its
    bistatic receiver w_r (3,) or None, and its seeded rng (None: a regular grid).

    Attributes
    ----------
    slot : int
        The view's position within its chunk.
    index : int
        The view's index into the ladar's views.
    w : (3,) numpy.ndarray
        The view direction, a unit vector from the scene toward the ladar (rays travel
        along −w).
    w_r : (3,) numpy.ndarray or None
        The bistatic receiver's direction; None for a monostatic view.
    rng : numpy.random.Generator or None
        The view's seeded generator for stratified rays; None for a regular grid.
    """

    slot: int
    index: int
    w: np.ndarray
    w_r: np.ndarray | None
    rng: np.random.Generator | None


def check_scene(scene, ladar, mode, normals, back_faces, z0):
    """(mode, geometry, z0) of a mesh run, after the scene, ladar, normals, back faces,
    mode and slice plane are checked (a slice plane off the target warns).

    Parameters
    ----------
    scene : meshladar.Scene
        A mesh scene (``Scene.from_mesh`` or ``scene.tessellate``).
    ladar : meshladar.Ladar
        The views and range bins.
    mode : {"slice", "3d"} or None
        None: ``"slice"`` when the scene was tessellated from analytic shapes and every
        view lies in the x-y plane, else ``"3d"``. ``"slice"`` needs views in the x-y
        plane.
    normals : {"flat", "smooth", "exact"}
        The normal each hit is weighed with; ``"exact"`` needs parts tessellated from
        analytic shapes.
    back_faces : {"two-sided", "ignore"}
        Whether back-face hits count (with the normal turned toward the ladar) or are
        blocked.
    z0 : float or None
        The slice plane's height (scene coordinates, scene units), slice mode only; None:
        the middle of the scene's bounding box in z.

    Returns
    -------
    mode : str
        ``"slice"`` or ``"3d"``, as given or chosen.
    geo : Geometry
        The scene's traced geometry for ``normals``
        (:func:`meshladar.raytrace.embree.geometry`, cached on the scene).
    z0 : float
        The slice plane's height (in 3-D too: the middle of the bounding box in z).

    Raises
    ------
    ParameterError
        When ``scene`` is not a Scene or not a mesh scene; ``ladar`` is not a Ladar;
        ``normals``, ``back_faces`` or ``mode`` is not one of its choices; ``mode="slice"``
        has views off the x-y plane; ``z0`` is given in 3-D or is not a finite real;
        ``normals="exact"`` meets a part without an exact normal; the mesh's bounding
        radius lies outside ``meshladar.precision.SCENE_RADIUS_RANGE``.

    Warns
    -----
    MeshladarWarning
        In slice mode, when ``z0`` lies outside the target's heights (the slice returns
        nothing); when the mesh lies far from the origin for its size
        (``meshladar.precision.FAR_RATIO``).
    """
    mode = _checked_mode(scene, ladar, mode, normals, back_faces, z0)
    if z0 is not None:                  # within the scenes' range, before any geometry
        z0 = check_real("z0", z0, low=-SCENE_RADIUS_RANGE[1], high=SCENE_RADIUS_RANGE[1])
    geo = geometry(scene, normals)
    if z0 is None:
        z0 = float(geo.center[2])
    if mode == "slice":
        lo, hi = float(geo.vertices[:, 2].min()), float(geo.vertices[:, 2].max())
        if not lo <= z0 <= hi:
            warnings.warn(f"z0={z0:.6g} lies outside the target's heights [{lo:.6g}, "
                          f"{hi:.6g}]: the slice returns nothing", MeshladarWarning,
                          stacklevel=user_stacklevel())
    return mode, geo, z0


def _checked_mode(scene, ladar, mode, normals, back_faces, z0):
    """The run's mode, as given or chosen, after the arguments of :func:`check_scene` are
    checked on their own (the scene's geometry is not built yet)."""
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
    return mode


def check_sensor(sensor, receiver, mode):
    """The sensor a job traces with (None for none, or for one that changes nothing: at
    infinity, an unbounded flood), after its type, its monostatic receiver and its mode
    are checked.

    Parameters
    ----------
    sensor : meshladar.sensor.Sensor or None
        The run's sensor.
    receiver : array_like or None
        The run's bistatic receiver; must be None with a sensor.
    mode : {"slice", "3d"}
        The run's (checked) mode; a sensor at a finite standoff needs ``"3d"``.

    Returns
    -------
    meshladar.sensor.Sensor or None
        ``sensor``, or None when it is None or is at infinity (``standoff=None``) with an
        unbounded ``FloodBeam`` (``radius=None``): parallel rays then trace it.

    Raises
    ------
    ParameterError
        When ``sensor`` is not a Sensor, is given with a ``receiver``, or has a finite
        standoff with ``mode`` other than ``"3d"``.
    """
    if sensor is None:
        return None
    if not isinstance(sensor, Sensor):
        raise ParameterError(f"sensor must be a meshladar.sensor.Sensor; got "
                             f"{type(sensor).__name__}")
    if receiver is not None:
        raise ParameterError("a sensor is monostatic (its receiver sits with its "
                             "transmitter); drop receiver or sensor")
    if sensor.standoff is not None and mode != "3d":
        raise ParameterError("a sensor at a finite standoff needs mode='3d' (its rays fan "
                             "out in both transverse directions)")
    if sensor.standoff is None and isinstance(sensor.beam, FloodBeam) \
            and sensor.beam.radius is None:
        return None
    return sensor


def check_receivers(receiver, ladar, mode):
    """Bistatic receivers (n_views, 3), or None for a collocated (monostatic) ladar.

    Parameters
    ----------
    receiver : (3,) or (n_views, 3) array_like, or None
        The receiver's direction (from the scene toward the receiver, at infinity), one
        for every view or one per view; any non-zero length (normalised here). None:
        monostatic.
    ladar : meshladar.Ladar
        The views the receivers pair with.
    mode : {"slice", "3d"}
        The run's mode; in slice mode every receiver must lie in the x-y plane (z exactly
        0).

    Returns
    -------
    (n_views, 3) float64 numpy.ndarray or None
        Unit receiver directions, one row per view (C-contiguous); None when ``receiver``
        is None.

    Raises
    ------
    ParameterError
        When ``receiver`` has another shape, is not finite or is a zero vector; when a
        receiver points opposite its view (w_r·w ≤ −1 +
        ``meshladar.precision.PARALLEL_SLACK``: no light returns); when in slice mode a
        receiver has a z component.
    """
    if receiver is None:
        return None
    if np.shape(receiver) not in ((3,), (ladar.n_views, 3)):
        raise ParameterError(f"receiver must be a direction (3,) or one per view "
                             f"({ladar.n_views}, 3); got shape {np.shape(receiver)}")
    r = np.broadcast_to(unit_vectors("receiver", receiver), (ladar.n_views, 3))
    opposite = np.einsum("ij,ij->i", r, ladar.view_vectors) <= -1 + PARALLEL_SLACK
    if np.any(opposite):
        k = int(np.argmax(opposite))
        raise ParameterError(f"receiver must not point exactly opposite the view (no light "
                             f"returns); got receiver {r[k].tolist()} for view {k}, "
                             f"{ladar.view_vectors[k].tolist()}")
    if mode == "slice" and np.any(r[:, 2] != 0):
        raise ParameterError("in slice mode the receiver must lie in the x-y plane")
    return np.ascontiguousarray(r)


def _check_standoff(geo, ladar, sensor):
    """A sensor at a finite standoff must lie outside the target seen from every view
    (the test each perspective view's grid makes, made for all views before any ray)."""
    if sensor is None or sensor.standoff is None:
        return
    aim = np.asarray(sensor.aim, np.float64) - geo.center
    for w in np.asarray(ladar.view_vectors, np.float64):
        near = -geo.extent(w, aim + sensor.standoff * w)[1]    # as each view's grid does
        if near <= ORIGIN_MARGIN * geo.radius:
            raise ParameterError(
                f"standoff {sensor.standoff:g} puts the sensor inside the target's extent "
                f"(the target reaches {sensor.standoff - near:.6g} toward "
                "it from the aim point): give a larger standoff")
    # ranges R − D: differences of numbers ~D, each rounded to D·2⁻⁵³
    rounding = (sensor.standoff + float(np.linalg.norm(aim))) * 2.0 ** -53
    width = float(np.min(np.diff(ladar.bin_edges)))
    if rounding > STANDOFF_ROUNDING_SHARE * width:
        warnings.warn(f"standoff {sensor.standoff:g} leaves the ranges a float64 rounding of "
                      f"~{rounding:.2g}, {rounding / width:.2g} of the narrowest bin "
                      f"({width:.3g}): give a smaller standoff or wider bins",
                      MeshladarWarning, stacklevel=user_stacklevel())


def plan_trace(scene, ladar, *, mode=None, normals="flat", back_faces="two-sided", z0=None,
               ray_spacing=None, rays_per_bin=None, sampling=None, seed=None,
               receiver=None, backend="auto", sensor=None) -> TracePlan:
    """The :class:`TracePlan` of a mesh run, every geometric option checked (the messages
    name the argument, the value and what is valid); nothing is cast.

    Parameters
    ----------
    scene : meshladar.Scene
        A mesh scene.
    ladar : meshladar.Ladar
        The views and range bins (the bins set the default ray spacing).
    mode : {"slice", "3d"}, optional
        As :func:`check_scene` (default None: ``"slice"`` for a scene tessellated from
        analytic shapes seen about the z axis, else ``"3d"``).
    normals : {"flat", "smooth", "exact"}
        The hits' normals (default ``"flat"``).
    back_faces : {"two-sided", "ignore"}
        Back-face hits count, the normal turned toward the ladar (default
        ``"two-sided"``), or are blocked (``"ignore"``).
    z0 : float, optional
        The slice plane's height (scene coordinates), slice mode only; default the middle
        of the scene's bounding box in z.
    ray_spacing : float, optional
        The ray spacing δ (scene units, from 1e-150 to 1e30); not with ``rays_per_bin``.
    rays_per_bin : float, optional
        Rays per width of the narrowest range bin, in [1e-300, 1e6]: δ = narrowest bin
        width / ``rays_per_bin``. Default (neither given): 8 in slice mode, 1 in 3-D, where
        δ is also at most the scene's bounding diameter / 128 (the bounding radius is
        about the bounding box's centre).
    sampling : {"regular", "stratified"}, optional
        Rays at cell centres, or one ray per cell at a seeded random offset. Default:
        ``"stratified"`` in 3-D or whenever ``seed`` is given, else ``"regular"``.
    seed : int, optional
        The stratified offsets' seed, a non-negative integer (default 0 when stratified);
        refused with ``sampling="regular"``.
    receiver : (3,) or (n_views, 3) array_like, optional
        Bistatic receivers' direction(s) (:func:`check_receivers`); default None.
    backend : str
        The ray caster: ``"auto"`` (default), ``"packets"``, ``"raster"``, ``"embreex"`` or a
        registered backend (:func:`meshladar.raytrace.backends.resolve_backend`).
    sensor : meshladar.sensor.Sensor, optional
        The sensor (:func:`check_sensor`); default None, parallel rays.

    Returns
    -------
    TracePlan
        The validated plan: ``backend`` resolved, ``spacing`` chosen, ``traced_with`` the
        sensor the rays follow (or None), and ``rays`` the estimated total,
        n_views × (2 radius / δ + 2) in slice mode or n_views × (2 radius / δ + 2)² in 3-D.

    Raises
    ------
    ParameterError
        Any refusal of :func:`check_scene`, :func:`check_sensor`,
        :func:`check_receivers` or ``resolve_backend``; ``sampling`` not one of its
        choices, or ``seed`` not a non-negative integer or given with regular sampling;
        both ``ray_spacing`` and ``rays_per_bin``, either out of its range, or a spacing
        that overflows; a view that would cast more than ``MAX_RAYS_PER_VIEW`` (5e7)
        rays; a sensor whose standoff puts it inside the target's extent from some view.

    Warns
    -----
    MeshladarWarning
        As :func:`check_scene` and ``resolve_backend``; when a finite standoff leaves the
        ranges a float64 rounding above ``STANDOFF_ROUNDING_SHARE`` (1e-3) of the
        narrowest bin.
    """
    mode, geo, z0 = check_scene(scene, ladar, mode, normals, back_faces, z0)
    geo.for_views(scene, ladar.n_views)
    traced_with = check_sensor(sensor, receiver, mode)
    backend = resolve_backend(backend)
    sampling, seed = _sampling(mode, sampling, seed)
    receivers = check_receivers(receiver, ladar, mode)
    geo.for_receivers(scene, receivers)
    spacing, rays = _checked_spacing(geo, ladar, mode, ray_spacing, rays_per_bin)
    _check_standoff(geo, ladar, traced_with)
    return TracePlan(geo=geo, mode=mode, normals=normals, back_faces=back_faces, z0=z0,
                     spacing=spacing, sampling=sampling, seed=seed, receivers=receivers,
                     sensor=sensor, traced_with=traced_with, backend=backend, rays=rays)


def _checked_spacing(geo, ladar, mode, ray_spacing, rays_per_bin):
    """(δ, estimated rays) of a run: the ray spacing given or chosen, refused when one view
    would cast more rays than :data:`MAX_RAYS_PER_VIEW`, and the run's estimated total."""
    spacing = _spacing(ladar, mode, ray_spacing, rays_per_bin, geo.radius)
    per_view = _largest_grid(geo, ladar.view_vectors, mode, spacing, MAX_RAYS_PER_VIEW)
    if per_view > MAX_RAYS_PER_VIEW:
        raise ParameterError(
            f"one view would cast about {per_view:.3g} rays (ray spacing {spacing:.3g} over "
            f"a target {2 * geo.radius:.3g} across), more than the {MAX_RAYS_PER_VIEW:.0e} a "
            "view may hold in memory; give a larger ray_spacing (or fewer rays_per_bin, "
            "or wider bins)")
    return spacing, _estimate_rays(geo, ladar, mode, spacing)
