"""One view's hits seen by a :class:`meshladar.sensor.Sensor`: rays fanning out from a
sensor at a finite standoff (or parallel rays, at infinity), each weighed by its
cross-section at the hit and the beam's irradiance there, and the receiver's factors.

Geometry of a perspective view. The sensor sits at S = aim + D w (D the standoff). Its rays
pass through a square grid of spacing δ on the reference plane through the aim point
normal to w (regular, or stratified exactly as the orthographic grid), covering the
target's hull as projected from S. A ray through a grid point at distance D/cos α from S
stands for the solid angle δΩ = δ² cos³α / D², so at distance R its cross-section is
δA⊥ = δ² cos³α (R/D)². The per-ray weight on F·δ² is then

* ``weight_factor`` = cos³α (R/D)² × the beam's irradiance at the hit relative to the aim
  point's (flood: (D/R)²; Gaussian: (w(D)/w(z))² exp(−2ρ²/w(z)²)) [× the shading factor of
  smooth or exact normals], and under received power also
* ``receive_factor`` = (D/R)² exp(−2σR): the receiver's solid angle relative to the aim
  point's, and the atmosphere's two-way transmission.

As D → ∞, cos α → 1 and R/D → 1: the orthographic weights. Ranges are R − D − aim·w (the
sensor's distance from the plane through the origin is D + aim·w, so they tend to the
orthographic −p·w), exact in float64: the hit distance is recomputed against the hit face's
plane from the sensor's float64 position along the float64 ray.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..errors import ParameterError
from ..precision import ORIGIN_MARGIN
from .grid import stratified_sequences, dot, frame, ray_grid, stratified_offsets
from ..hits import ViewHits
from .views import _hit_normals, _shading_factor, refine_t_along


class PlaneGrid(NamedTuple):
    """A sensor view's rays on the reference plane: each ray's grid coordinates S, T (n,)
    along the view's transverse axes u, v, row-major in rows of ``columns`` rays."""

    S: np.ndarray
    T: np.ndarray
    u: np.ndarray
    v: np.ndarray
    columns: int = 0


def plane_axes(geo, w, spacing, sensor_pos, standoff, aim):
    """(s, t, u, v): the cell centres s (ns,) and t (nt,) along u and v of the reference
    plane's grid (aim + S u + T v) covering the target's support points as projected from
    the sensor at ``sensor_pos`` (shifted coordinates); ParameterError when the sensor is
    inside the target's extent seen from w."""
    u, v = frame(w)
    near = -geo.extent(w, sensor_pos)[1]           # the least distance along the boresight
    if near <= ORIGIN_MARGIN * geo.radius:
        raise ParameterError(
            f"standoff {standoff:g} puts the sensor inside the target's extent (the target "
            f"reaches {standoff - near:.6g} toward it from the aim point): "
            "give a larger standoff")
    axes = []
    for a in (u, v):
        # (q·a)·D/depth + (sensor − aim)·a over the points: the least and greatest of the
        # first term, then the sum (rounding is monotonic: the same extremes)
        lo, hi = geo.seen_extent(a, w, standoff, sensor_pos)
        off = (sensor_pos - aim) @ a
        lo, hi = (lo + off) - spacing, (hi + off) + spacing
        n = max(1, int(math.ceil((hi - lo) / spacing)))
        axes.append(lo + (np.arange(n) + 0.5) * spacing)
    s, t = axes
    return s, t, u, v


def _plane_grid(geo, w, spacing, rng, sensor_pos, standoff, aim):
    """Cell centres (S, T) (n,) float64 on the reference plane (aim + S u + T v) covering
    the hull as projected from the sensor (:func:`plane_axes`), each moved by its
    stratified offset (float32 offsets, δ du added in float64) when ``rng`` is given, and
    (u, v)."""
    s, t, u, v = plane_axes(geo, w, spacing, sensor_pos, standoff, aim)
    S = np.repeat(s, t.size).reshape(s.size, t.size)
    T = np.tile(t, s.size).reshape(s.size, t.size)
    if rng is not None:
        du, dv = stratified_offsets(stratified_sequences(s.size, t.size, rng))
        S = S + du.astype(np.float64) * spacing
        T = T + dv.astype(np.float64) * spacing
    return PlaneGrid(S.ravel(), T.ravel(), u, v, t.size)


class SensorCast(NamedTuple):
    """One view's rays cast from a sensor at a finite standoff, in shifted coordinates:
    the sensor's position, each ray's grid coordinates S, T (n,) on the reference plane
    along u, v, its length |q| to the plane, its unit direction (n, 3), the start distance
    t0, the float32 origins as cast and Embree's results."""

    sensor_pos: np.ndarray
    S: np.ndarray
    T: np.ndarray
    u: np.ndarray
    v: np.ndarray
    length: np.ndarray
    dirs: np.ndarray
    t0: float
    origins: np.ndarray
    res: dict


def sensor_cast(geo, scene, w, spacing, rng, sensor, aim):
    """Cast one view's rays from a sensor at a finite standoff: a :class:`SensorCast`."""
    D = sensor.standoff
    sensor_pos = aim + D * w
    plane = _plane_grid(geo, w, spacing, rng, sensor_pos, D, aim)
    S, T, u, v = plane.S, plane.T, plane.u, plane.v
    q = S[:, None] * u + T[:, None] * v - D * w
    length = np.sqrt(S * S + T * T + D * D)
    dirs = q / length[:, None]
    # start each ray where it enters the target's bounding sphere (Embree's float32 stays
    # at the target's scale, however far the sensor)
    t0 = start_distance(geo, sensor_pos, spacing)
    o = np.ascontiguousarray(sensor_pos + t0 * dirs, dtype=np.float32)
    # the packet backend casts the grid in square tiles (neighbouring rays nearly parallel)
    res = scene.run(o, np.ascontiguousarray(dirs, dtype=np.float32), output=1,
                    columns=plane.columns)
    return SensorCast(sensor_pos, S, T, u, v, length, dirs, t0, o, res)


def start_distance(geo, sensor_pos, spacing):
    """Where a sensor's rays start (distance from the sensor): where they enter the
    target's bounding sphere, less a margin (0 when the sensor is inside it)."""
    return max(0.0, float(np.linalg.norm(sensor_pos)) - (1.0 + ORIGIN_MARGIN) * geo.radius
               - spacing)


def trace_sensor_view(plan, scene, view):
    """Hits of one view of a :class:`~meshladar.raytrace.plan.TracePlan` seen by its
    sensor (``plan.traced_with``); ranges absolute (R − D − aim·w at a finite standoff), or
    relative to the plane through the shifted centre (at infinity), as
    :func:`meshladar.raytrace.views.trace_view`'s."""
    geo, mode, spacing, z0_shifted = plan.geo, plan.mode, plan.spacing, plan.z0_shifted
    back_faces, sensor, w, rng = plan.back_faces, plan.traced_with, view.w, view.rng
    D = sensor.standoff
    aim = np.asarray(sensor.aim, np.float64) - geo.center
    if D is None:
        grid = ray_grid(geo, w, mode, spacing, z0_shifted, rng)
        o, u, v = grid.origins, grid.u, grid.v
        d = np.ascontiguousarray((-w)[None, :], dtype=np.float32)
        res = scene.run(o, d, output=1, columns=grid.columns, coherent=plan.coherent)
        prim = res["primID"]
        hit = prim >= 0
        prim = prim[hit]
        start = o[hit].astype(np.float64)           # each ray from its float32 origin
        dirs = np.broadcast_to(-w, start.shape)
        t32 = res["tfar"][hit].astype(np.float64)
        n_rays, cos3 = len(o), 1.0
        sensor_pos = None
    else:
        if mode != "3d":
            raise ParameterError("a sensor at a finite standoff needs mode='3d' (its rays "
                                 "fan out in both transverse directions)")
        cast = sensor_cast(geo, scene, w, spacing, rng, sensor, aim)
        sensor_pos, S, T, u, v = cast.sensor_pos, cast.S, cast.T, cast.u, cast.v
        length, dirs_all, t0_all, o, res = cast.length, cast.dirs, cast.t0, cast.origins, \
            cast.res
        prim = res["primID"]
        hit = prim >= 0
        prim = prim[hit]
        dirs = dirs_all[hit]
        start = np.broadcast_to(sensor_pos, dirs.shape)
        t32 = t0_all + res["tfar"][hit].astype(np.float64)
        n_rays = len(o)
        cos3 = (D / length[hit]) ** 3
    t = refine_t_along(geo, prim, start, dirs, t32)    # float64, to the hit face's plane
    p = start + t[:, None] * dirs
    n_geo = geo.face_normals[prim]
    toward = -dirs                                   # from the hit toward the sensor
    cos_geo = _rowdot(n_geo, toward)
    back = cos_geo < 0
    n, _ = _hit_normals(geo, prim, res, hit, n_geo, lambda: p + geo.center)
    cos_t = _rowdot(n, toward)
    if back_faces == "two-sided":
        cos_t = np.where(back, -cos_t, cos_t)
    sin_t = np.sqrt(np.maximum(1.0 - cos_t * cos_t, 0.0))
    factor = np.ones(prim.size)
    if geo.normals != "flat":
        factor = _shading_factor(cos_t, cos_geo)
    if back_faces == "ignore":
        cos_t = np.where(back, -1.0, cos_t)
    beam_factor, receive = sensor_factors(sensor, w, aim, p, sensor_pos, t, cos3)
    factor = factor * beam_factor
    if D is None:
        rng_rel = t - dot(start, w)                # r = −p·w relative to the shifted centre
    else:
        rng_rel = t - D - float((aim + geo.center) @ w)
    across = np.stack([dot(p, u), dot(p, v)], -1)       # shifted, as trace_view's
    return ViewHits(rng_rel, cos_t, sin_t, geo.material[prim], np.zeros((prim.size, 4)),
                    n_rays, int(back.sum()), None, factor, None, receive, across)


def sensor_factors(sensor, w, aim, p, sensor_pos=None, R=None, cos3=1.0):
    """Per hit, the sensor's ``weight_factor`` (the beam's irradiance at the hit relative to
    the aim point's, and at a finite standoff the ray's cross-section cos³α (R/D)²) and
    ``receive_factor`` ((D/R)² exp(−2σR); None at infinity), as the module docstring
    gives them; the shading factor of smooth normals is not included.

    Parameters
    ----------
    sensor : meshladar.sensor.Sensor
        The sensor.
    w : (3,) numpy.ndarray
        The unit view.
    aim : (3,) numpy.ndarray
        The aim point, in the same coordinates as ``p`` and ``sensor_pos``.
    p : (k, 3) numpy.ndarray
        The hits.
    sensor_pos : (3,) numpy.ndarray, optional
        The sensor's position at a finite standoff (None: at infinity).
    R : (k,) numpy.ndarray, optional
        The hits' distances from the sensor (at a finite standoff).
    cos3 : float or (k,) numpy.ndarray
        cos³α of each ray against the boresight (1 at infinity).

    Returns
    -------
    factor : (k,) numpy.ndarray
        The weight factor.
    receive : (k,) numpy.ndarray or None
        The receive factor (None at infinity: no extinction, the receiver's solid angle
        the same for every hit).
    """
    beam, D = sensor.beam, sensor.standoff
    u, v = frame(w)
    off = aim + beam.offset[0] * u + beam.offset[1] * v if hasattr(beam, "offset") else aim
    if sensor_pos is None:
        rel = p - off
        along = dot(rel, w)
        rho = np.linalg.norm(rel - along[:, None] * w, axis=1)
        return beam.relative(rho, None, None), None
    axis = off - sensor_pos
    axis = axis / np.linalg.norm(axis)
    rel = p - sensor_pos
    z = dot(rel, axis)
    rho = np.linalg.norm(rel - z[:, None] * axis, axis=1)
    return (cos3 * (R / D) ** 2 * beam.relative(rho, z, D),
            (D / R) ** 2 * np.exp(-2.0 * sensor.extinction * R))


def _rowdot(a, b):
    return a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1] + a[:, 2] * b[:, 2]


# public names for the stages above (weighing, forward)
