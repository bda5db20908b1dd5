"""Casting a chunk of pulses: sub-ray directions, first hits, and each sub-ray's expected
photoelectrons.

Geometry: Embree (the packet engine) picks the face each sub-ray meets first; its distance
is then recomputed in float64 from the float64 origin and direction against that face's
float64 plane, so a sensor a kilometre away ranges to ~1e-13 of its distance, not to
float32's 1e-7. Faces are two-sided: cos θ = |n·d| with n the face's flat normal.

Radiometry (``radiometry="power"``, monostatic, one bounce): a sub-ray carrying energy
share s of a pulse of energy E that meets a surface at distance R and incidence θ returns

    N = E s · F(θ; −θ) cos θ · (π D²/4) / R² · T η · exp(−2σR) / (h c / λ)

photoelectrons: the surface's irradiance E s cos θ / δA⊥ over the element δA⊥ / cos θ,
its radiance F E s cos θ / δA⊥, seen over δA⊥ from the aperture's solid angle π D²/4 / R²
— the link budget of :class:`meshladar.sensor.Sensor` per sub-ray (F cos θ is the
coating's :meth:`~meshladar.brdf.BRDF.projected` weight).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ..brdf import material_table
from ..raytrace.embree import embree_scene, geometry
from ..raytrace.backends import resolve_backend
from ..raytrace.embree4_ctypes import query_flags
from ..sensor import PLANCK, SPEED_OF_LIGHT
from ._kernels import pack_rays, refine_hits, world_sub_rays
from ._packets import cast_pulses, link_budget, projected_weights

__all__ = ["world_directions", "Cast", "cast_chunk", "cast_static", "photoelectrons"]

#: Below this |n·d| a hit's float64 refinement is not trusted (Embree's t is kept).
_MIN_COS = 1e-9
#: The coatings' rows where the one-loop cast does not weigh its hits.
_NO_ROWS = np.zeros((1, 7))


def world_directions(rot, directions, offsets, pixel_pitch=None):
    """World-frame directions of each pulse's sub-rays, in one compiled pass: in the
    sensor frame, a beam's sub-ray is the pulse's direction d offset by tan(offset) along
    two unit axes perpendicular to it (u = z × d normalised, or y × d where d is near z;
    v = d × u), a flash pixel's the pixel's point on the focal plane x = 1 moved by
    offset × pitch; each normalised and turned by the sensor's rotation.

    Parameters
    ----------
    rot : (n, 3, 3) array_like
        Sensor-to-world rotations, one per pulse.
    directions : (n, 3) array_like
        The pulses' unit directions in the sensor frame.
    offsets : (m, 2) array_like
        A beam's: angles (rad) about the pulse's direction; a flash pixel's: fractions of
        the pitch on the focal plane.
    pixel_pitch : float, optional
        A flash pixel's pitch tan(IFOV), or None for a beam.

    Returns
    -------
    (n, m, 3) numpy.ndarray
        Unit directions, world frame.
    """
    n, m = len(directions), len(offsets)
    out = np.empty((n, m, 3))
    world_sub_rays(np.ascontiguousarray(rot, np.float64),
                   np.ascontiguousarray(directions, np.float64),
                   np.ascontiguousarray(offsets, np.float64),
                   -1.0 if pixel_pitch is None else float(pixel_pitch), out)
    return out


class Cast:
    """One chunk's first hits, per sub-ray (module docstring).

    Attributes
    ----------
    face : (n, m) int64 numpy.ndarray
        The global face index hit, −1 on a miss.
    distance : (n, m) numpy.ndarray
        One-way distance from the pulse's origin (float64), inf on a miss.
    cos : (n, m) numpy.ndarray
        |n·d| at the hit, 0 on a miss.
    points : (n, m, 3) numpy.ndarray
        Hit points, world frame, nan on a miss.
    pe : (n, m) numpy.ndarray or None
        Each sub-ray's photoelectrons where the cast weighed them (:func:`cast_static`).
    blocked : (n, m) bool numpy.ndarray or None
        Where :func:`cast_chunk` found a first hit too near to range
        (:data:`._kernels.MIN_RANGE`: a surface through the origin), a miss that no other
        part's hit may fill (:func:`.moving.cast_moving`).
    """

    def __init__(self, face, distance, cos, points):
        self.face = face            # global face index, -1 on a miss
        self.distance = distance    # one-way distance from the origin, inf on a miss
        self.cos = cos              # |n·d| at the hit, 0 on a miss
        self.points = points        # (n, m, 3) hit points, nan on a miss
        self.pe = None              # photoelectrons, where the cast weighed its hits
        self.blocked = None         # first hits too near to range (cast_chunk's)

    @property
    def hit(self):
        return self.face >= 0


def cast_chunk(scene, origins, directions, backend=None):
    """First hits, distances in float64 (module docstring).

    Parameters
    ----------
    scene : Scene
        A mesh scene (its flat-normal geometry).
    origins : (n, 3) numpy.ndarray
        Pulse origins, world frame.
    directions : (n, m, 3) numpy.ndarray
        Unit sub-ray directions, world frame.
    backend : str, optional
        The backend (:func:`meshladar.raytrace.backends.resolve_backend`'s answer, found
        once per scan); default ``"auto"``'s.

    Returns
    -------
    Cast
        The sub-rays' first hits.
    """
    geo = geometry(scene, "flat")
    emb = embree_scene(geo, backend or resolve_backend("auto"))
    n, m = directions.shape[:2]
    shifted = np.ascontiguousarray(origins - geo.center)
    directions = np.ascontiguousarray(directions, np.float64)
    o32, d32 = np.empty((n * m, 3), np.float32), np.empty((n * m, 3), np.float32)
    pack_rays(shifted, directions, o32, d32)            # compiled: no GIL held
    res = emb.run(o32, d32)
    face = np.empty((n, m), np.int64)
    dist, cos = np.empty((n, m)), np.empty((n, m))
    pts = np.empty((n, m, 3))
    refine_hits(res["primID"], res["tfar"], shifted, directions, geo.face_normals,
                geo.plane_d, _MIN_COS, np.asarray(geo.center, np.float64), face, dist, cos,
                pts)
    cast = Cast(face, dist, cos, pts)
    cast.blocked = (face < 0) & (np.asarray(res["primID"]).reshape(n, m) >= 0)
    return cast


def cast_static(scene, origins, rot, directions, offsets, pixel_pitch, backend,
                sensor=None, shares=None):
    """:func:`cast_chunk` of :func:`world_directions`' sub-rays in one compiled loop where
    the backend's scenes allow it (the packet backend's: :mod:`._packets`), the same hits
    number for number; else the two in turn. With ``sensor`` and ``shares``, and where
    every coating has a compiled row (``kernel_params``: Lambertian, SandfordRobertson),
    the loop also weighs each hit: the result's ``pe`` is then :func:`photoelectrons`' bit
    for bit. Measured per 120,000 sub-rays: an SR coating weighed in the loop costs 4.9 ms
    (through its numpy model, 14); a Lambertian scene's whole scan of 30,000 pulses of 16
    sub-rays takes 54.3 ms weighed in the loop, 57.3 weighed after it.

    Parameters
    ----------
    scene : Scene
        A mesh scene that does not move.
    origins : (n, 3) numpy.ndarray
        Pulse origins, world frame.
    rot, directions, offsets, pixel_pitch
        As :func:`world_directions`.
    backend : str
        The resolved backend.
    sensor : ScanSensor, optional
        The link budget's parameters.
    shares : (m,) array_like, optional
        The sub-rays' shares of a pulse's energy (as :func:`photoelectrons`).

    Returns
    -------
    Cast
        The sub-rays' first hits; ``pe`` the photoelectrons where weighed here, else None.
    """
    geo = geometry(scene, "flat")
    emb = embree_scene(geo, backend)
    if not emb.fused:
        return cast_chunk(scene, origins, world_directions(rot, directions, offsets,
                                                            pixel_pitch), backend)
    sc = emb.scene.scene
    n, m = len(directions), len(offsets)
    out = (np.empty((n, m), np.int64), np.empty((n, m)), np.empty((n, m)),
           np.empty((n, m, 3)))
    rows = _compiled_rows(scene) if sensor is not None else None
    weigh = rows is not None
    pe = np.empty((n, m) if weigh else (0, 0))
    link = (geo.material, rows if weigh else _NO_ROWS,
            np.ascontiguousarray(np.broadcast_to(shares if weigh else 0.0, (m,)), np.float64),
            _budget(sensor) if weigh else 0.0,
            float(sensor.extinction) if weigh else 0.0, pe)
    cast_pulses(sc.lib.intersect[sc.lib.width], sc.live(), sc.lib.width, query_flags(True),
                np.ascontiguousarray(origins - geo.center, np.float64),
                np.ascontiguousarray(rot, np.float64),
                np.ascontiguousarray(directions, np.float64),
                np.ascontiguousarray(offsets, np.float64),
                -1.0 if pixel_pitch is None else float(pixel_pitch), emb.inverse,
                np.float32(emb.scale),
                (geo.face_normals, geo.plane_d, _MIN_COS, np.asarray(geo.center, np.float64)),
                out, link)
    cast = Cast(*out)
    cast.pe = pe if weigh else None
    return cast


def _compiled_rows(scene):
    """The coatings' compiled rows (:func:`meshladar.brdf.material_table`) where every
    coating has one; else None."""
    coatings = list(scene.materials)
    if any(getattr(c, "kernel_params", None) is None for c in coatings):
        return None
    return material_table(coatings)


def _budget(sensor):
    """The link budget's factor (module docstring): photoelectrons per unit of a sub-ray's
    share × F cos θ / R²."""
    photon = PLANCK * SPEED_OF_LIGHT / sensor.wavelength
    return (sensor.pulse_energy * np.pi * sensor.aperture_diameter ** 2 / 4.0
            * sensor.optics_transmission * sensor.quantum_efficiency / photon)


def photoelectrons(scene, cast, shares, sensor):
    """Each sub-ray's expected photoelectrons (module docstring). Where every coating has
    a compiled row, F·cos θ comes from the coatings' compiled twins (held to their numpy
    models to 1e-13 by the BRDF tests, a Lambertian's bit for bit); else from each
    coating's ``projected``.

    Parameters
    ----------
    scene : Scene
        The scene whose coatings weigh the hits.
    cast : Cast
        The sub-rays' hits.
    shares : (m,) array_like
        The sub-rays' shares of a pulse's energy (summing to 1 for a beam, to the pixel's
        share of the flash for an array).
    sensor : ScanSensor
        The link budget's parameters.

    Returns
    -------
    (n, m) numpy.ndarray
        Photoelectrons, 0 on a miss.
    """
    geo = geometry(scene, "flat")
    size = cast.face.size
    at, face = np.empty(size, np.int64), np.empty(size, np.int64)
    cos, sin, r, share = np.empty(size), np.empty(size), np.empty(size), np.empty(size)
    shares = np.ascontiguousarray(np.broadcast_to(shares, cast.face.shape[1:]), np.float64)
    k = _hit_terms(cast.face, cast.cos, cast.distance, shares, at, face, cos, sin, r, share)
    cos, sin = cos[:k], sin[:k]
    rows = _compiled_rows(scene)
    if rows is not None:                       # the coatings' compiled twins
        weight = np.empty(k)
        projected_weights(cos, face[:k], geo.material, rows, weight)
    elif len(scene.materials) == 1:            # one coating: no selection to make
        weight = np.asarray(scene.materials[0].projected(cos, sin), np.float64)
    else:
        weight = np.zeros(k)
        mat = geo.material[face[:k]]
        for i, coating in enumerate(scene.materials):
            sel = mat == i
            if np.any(sel):
                weight[sel] = coating.projected(cos[sel], sin[sel])
    out = np.zeros(cast.face.shape)
    _link(at[:k], np.broadcast_to(weight, (k,)), r, share, float(_budget(sensor)),
          float(sensor.extinction), out.reshape(-1))
    return out


@numba.njit(cache=True, nogil=True)
def _hit_terms(face, cos, dist, shares, at, hit_face, c, s, r, share):   # pragma: no cover
    """The hits' flat indices, faces, cos θ (at most 1), sin θ, distances and energy
    shares, packed; returns how many."""
    n, m = face.shape
    k = 0
    for p in range(n):
        for q in range(m):
            if face[p, q] < 0:
                continue
            at[k] = p * m + q
            hit_face[k] = face[p, q]
            c[k] = min(cos[p, q], 1.0)
            s[k] = math.sqrt(max(0.0, 1.0 - c[k] * c[k]))
            r[k] = dist[p, q]
            share[k] = shares[q]
            k += 1
    return k


@numba.njit(cache=True, nogil=True)
def _link(at, weight, r, share, scale, extinction, out):   # pragma: no cover - compiled
    """out[at] = the link budget's photoelectrons (module docstring) of each hit."""
    for i in range(at.shape[0]):
        out[at[i]] = link_budget(weight[i], r[i], share[i], scale, extinction)
