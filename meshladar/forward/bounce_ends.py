"""Where a view's bounce paths start and end (:mod:`meshladar.forward.bounces`): the first
hits and the power each brings in, from parallel rays or a sensor's, and the receiver
each later vertex is joined to, at infinity or at the sensor.

Parallel rays (no sensor, or a sensor at infinity): a square grid of spacing δ across the
view, each first hit bringing δ² (× the beam's irradiance there relative to the aim
point's, with a sensor), its incoming path measured as r(x₁) = −x₁·w; a vertex x is joined
to the receiver along w_r (w when monostatic), its outgoing path −x·w_r.

A sensor at a finite standoff D (at S = aim + D w; monostatic): its own rays through a
grid of spacing δ on the reference plane through the aim point, each first hit bringing
δ² × the sensor's weight factor (the ray's cross-section cos³α (R/D)² and the beam's
irradiance, :func:`meshladar.raytrace.perspective.sensor_factors`), its incoming path
R₁ = |x₁ − S|; a vertex x is joined to S itself, its outgoing path R = |x − S|, and the
receiver's solid angle relative to the aim point's, (D/R)², and the atmosphere's
transmission over the whole path, exp(−σ(R₁ + L + R)), multiply its return under received
power (the single bounce's receive factor, whose two-way exp(−2σR) is the case L = 0,
R = R₁). Ranges are half the optical path less the sensor's distance from the plane
through the origin, (R₁ + L + R)/2 − D − aim·w: the single bounce's R − D − aim·w.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..raytrace.perspective import sensor_cast, sensor_factors
from ..raytrace.views import refine_t_along
from .mesh import first_hits

__all__ = ["Ends", "view_ends", "entries", "to_receiver"]


class Ends(NamedTuple):
    """A view's source and receiver, as a bounce path sees them.

    Attributes
    ----------
    w : (3,) numpy.ndarray
        The unit view (the beam travels along −w).
    w_r : (3,) numpy.ndarray
        The receiver's direction at infinity (w when monostatic; unused with ``position``).
    position : (3,) numpy.ndarray or None
        The sensor's position in scene coordinates at a finite standoff (None: at infinity).
    sensor : Sensor or None
        The sensor, when one is given.
    power : bool
        Received power (True) or the paper's Eq. 8 (False: no receive factor).
    """

    w: np.ndarray
    w_r: np.ndarray
    position: np.ndarray | None = None
    sensor: object = None
    power: bool = True

    @property
    def offset(self) -> float:
        """What the apparent range is measured from: D + aim·w at a finite standoff, else 0."""
        if self.position is None:
            return 0.0
        return float(self.sensor.standoff + np.asarray(self.sensor.aim, np.float64) @ self.w)


def view_ends(w, receiver=None, sensor=None, power=True) -> Ends:
    """A view's :class:`Ends`.

    Parameters
    ----------
    w : (3,) array_like
        The unit view.
    receiver : (3,) array_like, optional
        A bistatic receiver's unit direction (None: monostatic).
    sensor : Sensor, optional
        The run's sensor (monostatic; None: parallel rays, no beam).
    power : bool
        Received power (default) or the paper's Eq. 8.

    Returns
    -------
    Ends
        The view's ends.
    """
    w = np.asarray(w, np.float64)
    w_r = w if receiver is None else np.asarray(receiver, np.float64)
    position = None
    if sensor is not None and sensor.standoff is not None:
        position = np.asarray(sensor.aim, np.float64) + sensor.standoff * w
    return Ends(w, w_r, position, sensor, bool(power))


def entries(scene, geo, emb, ends, spacing):
    """A view's first hits and what each brings in (module docstring).

    Parameters
    ----------
    scene : Scene
        The mesh scene.
    geo, emb :
        Its flat-normal geometry and Embree scene (:mod:`meshladar.raytrace.embree`).
    ends : Ends
        The view's ends.
    spacing : float
        The grid's spacing δ.

    Returns
    -------
    points : (k, 3) numpy.ndarray
        The first hits, scene coordinates.
    faces : (k,) numpy.ndarray of int
        Their global faces.
    path : (k,) numpy.ndarray
        Each hit's incoming path (−x₁·w, or R₁ from the sensor).
    power : (k,) numpy.ndarray
        The power each hit's ray brings in, per unit irradiance at the aim point.
    """
    w, sensor = ends.w, ends.sensor
    if ends.position is None:
        p, f, r = first_hits(scene, w, ray_spacing=spacing)
        power = np.full(len(f), spacing * spacing)
        if sensor is not None and len(f):
            aim = np.asarray(sensor.aim, np.float64)
            power = power * sensor_factors(sensor, w, aim, p)[0]
        return p, f, r, power
    aim = np.asarray(sensor.aim, np.float64) - geo.center
    cast = sensor_cast(geo, emb, w, spacing, None, sensor, aim)
    prim = cast.res["primID"].astype(np.int64)
    hit = prim >= 0
    prim, dirs = prim[hit], cast.dirs[hit]
    t = refine_t_along(geo, prim, cast.sensor_pos, dirs,
                       cast.t0 + cast.res["tfar"][hit].astype(np.float64))
    p = cast.sensor_pos + t[:, None] * dirs
    cos3 = (sensor.standoff / cast.length[hit]) ** 3
    factor = sensor_factors(sensor, w, aim, p, cast.sensor_pos, t, cos3)[0]
    return p + geo.center, prim, t, spacing * spacing * factor


def to_receiver(ends, x, path_in, length):
    """Each vertex's direction to the receiver, its outgoing path and receive factor.

    Parameters
    ----------
    ends : Ends
        The view's ends.
    x : (k, 3) numpy.ndarray
        The vertices, scene coordinates.
    path_in : (k,) numpy.ndarray
        Their paths' incoming paths (:func:`entries`).
    length : (k,) numpy.ndarray
        Their paths' lengths from the first hit to ``x``.

    Returns
    -------
    directions : (k, 3) numpy.ndarray
        Unit directions from each vertex toward the receiver.
    path_out : (k,) numpy.ndarray
        −x·w_r, or |x − S| from the sensor.
    receive : (k,) numpy.ndarray or None
        The receive factor under received power with a sensor at a finite standoff, else
        None (1).
    """
    if ends.position is None:
        return np.broadcast_to(ends.w_r, x.shape), -(x @ ends.w_r), None
    d = ends.position - x
    R = np.linalg.norm(d, axis=1)
    receive = None
    if ends.power:
        sensor = ends.sensor
        receive = (sensor.standoff / R) ** 2 * np.exp(
            -sensor.extinction * (path_in + length + R))
    return d / R[:, None], R, receive
