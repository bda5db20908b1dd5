"""Moving target parts: each part given a :class:`~meshladar.motion.Motion` moves rigidly
against time while the scan runs, so motion blur and Doppler come out of the same run.

A part's pose at time t (s, the pattern's clock): its points p₀ (as meshed) are at
R(t)(p₀ − c) + c + V t, R(t) the rotation by the vector Ω t (Rodrigues), c the motion's
centre, V its velocity. A pulse is cast at each moving part in the part's own frame at its
emission time (the ray taken back by the inverse pose: distances are unchanged by a rigid
motion) and at the static parts as they are; the nearest hit wins, and its point is taken
forward into the world.

Doppler: each sub-ray's hit point moves at v = V + Ω × (p − c − V t); the sensor at the
platform's velocity v_s (:meth:`Platform.sensor_velocities
<meshladar.scan.platforms.Platform.sensor_velocities>`); the
shift is f_D = 2 (v − v_s)·u / λ with u the unit vector from the point toward the sensor
(positive when they close), λ the sensor's wavelength. A return's ``doppler`` is its
sub-rays' photoelectron-weighted shift.
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
from scipy.spatial.transform import Rotation

from ..errors import MeshladarWarning, ParameterError, user_stacklevel
from ..motion import Motion
from ..scene import Scene
from .cast import Cast, cast_chunk

__all__ = ["moving_parts", "cast_moving", "doppler", "at_wavelength"]


class _MovingParts:
    """The scene split for casting: its static parts (one scene, or None) and each moving
    part (its own scene, its motion, its first global face index)."""

    def __init__(self, static, static_faces, moving):
        self.static = static                   # Scene or None
        self.static_faces = static_faces       # (k,) global face index of each static face
        self.moving = moving                   # [(Scene, Motion, first face), ...]


def _part_index(scene, key):
    names = [p.name for p in scene.parts]
    if isinstance(key, (int, np.integer)) and not isinstance(key, bool):
        if 0 <= key < len(names):
            return int(key)
    elif isinstance(key, str) and key in names:
        return names.index(key)
    raise ParameterError(f"motions: {key!r} is not a part of the scene; its parts are "
                         f"0 to {len(names) - 1}, named {names[:8]}")


def at_wavelength(motions, wavelength):
    """``motions`` (checked by :func:`moving_parts`) at the sensor's ``wavelength``: a
    scan's Doppler shifts are the sensor's (2 v·u / λ), whatever a Motion's own (which is
    :func:`meshladar.simulate`'s and ``resolve``'s); a Motion whose wavelength was set to
    another than the sensor's is warned of (its default, 1.064 µm, is taken as unset: a
    1.55 µm sensor's every motion would warn).

    Parameters
    ----------
    motions : dict or None
        ``{part: Motion}``.
    wavelength : float
        The sensor's, m.

    Returns
    -------
    dict or None
        The motions with the sensor's wavelength (what the scan records).
    """
    if not motions:
        return motions
    unset = Motion.__dataclass_fields__["wavelength"].default
    for part, m in motions.items():
        if m.wavelength not in (wavelength, unset):
            warnings.warn(f"motions[{part!r}] has wavelength {m.wavelength:g} m; a scan's "
                          f"Doppler shifts are at its sensor's, {wavelength:g} m (a "
                          "Motion's own wavelength is simulate's and resolve's)",
                          MeshladarWarning, stacklevel=user_stacklevel())
    return {part: replace(m, wavelength=wavelength) for part, m in motions.items()}


def moving_parts(scene, motions):
    """The scene split into its static and moving parts, checked before any ray is cast.

    Parameters
    ----------
    scene : Scene
        A mesh scene.
    motions : dict or None
        ``{part index or name: Motion}``.

    Returns
    -------
    object or None
        The split (static parts as one scene, each moving part as its own with its
        motion and first face index), or None when nothing moves.

    Raises
    ------
    ParameterError
        When ``motions`` is not a dict, a key is not a part, or a value not a Motion.
    """
    if motions is None or len(motions) == 0:
        return None
    if not isinstance(motions, dict):
        raise ParameterError(f"motions must be a dict of part (index or name) to Motion; "
                             f"got {type(motions).__name__}")
    chosen = {}
    for key, motion in motions.items():
        if not isinstance(motion, Motion):
            raise ParameterError(f"motions[{key!r}] must be a meshladar.motion.Motion; got "
                                 f"{type(motion).__name__}")
        chosen[_part_index(scene, key)] = motion
    first = np.cumsum([0] + [len(p.faces) for p in scene.parts])
    mats = list(scene.materials)
    with warnings.catch_warnings():          # the parts' checks were reported once already
        warnings.simplefilter("ignore", MeshladarWarning)
        rest = [i for i in range(len(scene.parts)) if i not in chosen]
        static = Scene.from_parts([scene.parts[i] for i in rest], mats) if rest else None
        moving = [(Scene.from_parts([scene.parts[i]], mats), m, int(first[i]))
                  for i, m in sorted(chosen.items())]
    faces = (np.concatenate([np.arange(first[i], first[i + 1]) for i in rest]) if rest
             else np.zeros(0, np.int64))
    return _MovingParts(static, faces, moving)


def _pose(motion, t):
    """The part's rotations and the translation of its centre at times t."""
    rot = Rotation.from_rotvec(np.outer(t, motion.omega))
    shift = np.asarray(motion.center) + np.outer(t, motion.velocity)
    return rot, shift


def cast_moving(split, origins, directions, t, backend=None):
    """First hits among the static and the moving parts (module docstring).

    Parameters
    ----------
    split : object
        :func:`moving_parts`'s split.
    origins : (n, 3) numpy.ndarray
        Pulse origins, world frame.
    directions : (n, m, 3) numpy.ndarray
        Unit sub-ray directions, world frame.
    t : (n,) numpy.ndarray
        Emission times, s.
    backend : str, optional
        As :func:`~meshladar.scan.cast.cast_chunk`'s.

    Returns
    -------
    Cast
        The nearest hit of each sub-ray, faces numbered over the whole scene; a miss where
        any part's surface passes through the sub-ray's origin (as a static scan's).
    """
    n, m = directions.shape[:2]
    best = Cast(np.full((n, m), -1, np.int64), np.full((n, m), np.inf), np.zeros((n, m)),
                np.full((n, m, 3), np.nan))
    blocked = np.zeros((n, m), bool)
    if split.static is not None:
        c = cast_chunk(split.static, origins, directions, backend)
        _take(best, c, np.where(c.face >= 0, split.static_faces[np.maximum(c.face, 0)], -1))
        blocked |= c.blocked
    for scene, motion, first in split.moving:
        rot, shift = _pose(motion, t)
        inv = rot.inv()
        c0 = np.asarray(motion.center)
        o_body = inv.apply(origins - shift) + c0
        d_body = np.einsum("nji,nmj->nmi", rot.as_matrix(), directions)   # R(t)^T d
        c = cast_chunk(scene, o_body, np.ascontiguousarray(d_body), backend)
        hit = c.face >= 0
        world = np.einsum("nij,nmj->nmi", rot.as_matrix(), c.points - c0) + shift[:, None, :]
        c.points = np.where(hit[..., None], world, np.nan)
        _take(best, c, np.where(hit, first + c.face, -1))
        blocked |= c.blocked
    if blocked.any():             # a surface through the origin: nothing ranged beyond
        best.face[blocked], best.distance[blocked] = -1, np.inf
        best.cos[blocked], best.points[blocked] = 0.0, np.nan
    return best


def _take(best, c, faces):
    """Keep, sub-ray by sub-ray, ``c``'s hits nearer than ``best``'s (in place)."""
    near = c.distance < best.distance
    best.face[near] = faces[near]
    best.distance[near] = c.distance[near]
    best.cos[near] = c.cos[near]
    best.points[near] = c.points[near]


def doppler(split, platform, cast, origins, t, wavelength):
    """Each sub-ray's Doppler shift (module docstring).

    Parameters
    ----------
    split : object or None
        :func:`moving_parts`'s split (None: nothing moves).
    platform : Platform
        The sensor's carrier (its velocity counts).
    cast : Cast
        The sub-rays' hits.
    origins : (n, 3) numpy.ndarray
        Pulse origins, world frame.
    t : (n,) numpy.ndarray
        Emission times, s.
    wavelength : float
        λ, m.

    Returns
    -------
    (n, m) numpy.ndarray
        f_D, Hz, positive closing; 0 on a miss.
    """
    if split is None and platform.is_static:             # nothing moves: no shift at all
        return np.zeros(cast.face.shape)
    v_s = platform.sensor_velocities(t)
    vel = np.zeros(cast.points.shape)
    if split is not None:
        for part_scene, motion, first in split.moving:
            n_faces = len(part_scene.parts[0].faces)
            mine = (cast.face >= first) & (cast.face < first + n_faces)
            centre = np.asarray(motion.center)[None, :] + np.outer(t, motion.velocity)
            rel = cast.points - centre[:, None, :]
            v = np.cross(np.asarray(motion.omega), rel) + np.asarray(motion.velocity)
            vel = np.where(mine[..., None], v, vel)
    toward = origins[:, None, :] - cast.points
    dist = np.linalg.norm(toward, axis=2, keepdims=True)
    u = np.divide(toward, dist, out=np.zeros_like(toward), where=dist > 0)
    f = 2.0 * np.einsum("nmi,nmi->nm", vel - v_s[:, None, :], u) / wavelength
    return np.where(cast.face >= 0, f, 0.0)
