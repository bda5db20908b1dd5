"""Resolved returns' binning: one view's hits weighed (:func:`meshladar.weighing.weights`)
and binned by one to three coordinates (range, cross-range, elevation, Doppler; module
docstring of :mod:`meshladar.forward.resolved`), on a flat index over the cells."""

from __future__ import annotations

import numpy as np

from ..raytrace.grid import frame
from .hit_weights import scaled, weights

__all__ = ["bin_resolved"]


def bin_resolved(h, w, offset, plan, weighing, out):
    """Add view ``w``'s hits ``h`` (with ``transverse``) into ``out`` (n_0[, n_1[, n_2]]),
    the axes and edges of ``weighing`` (:class:`.record.Weighing`); ``offset`` places the
    ranges; ``plan`` (:class:`~meshladar.raytrace.plan.TracePlan`) the geometry, the ray
    area and the sensor the view was traced with.

    Each hit weighs :func:`meshladar.weighing.weights` (monostatic) times its factors
    (:func:`meshladar.weighing.scaled`) and falls in the cell whose bins hold its
    coordinates, each bin half-open, [e[k], e[k + 1]); a hit outside any axis' edges, or of
    weight 0, is dropped. Coordinates (world, scene units; Doppler in Hz): ``"range"``
    h.range + ``offset``; ``"cross_range"`` and ``"elevation"`` the hit's transverse
    coordinates along the view's u and v plus the geometry centre's; ``"doppler"``
    ``weighing.motion.doppler`` of the hit points.

    Parameters
    ----------
    h : ViewHits
        The view's k hits, traced with ``transverse`` (k, 2) coordinates along (u, v).
    w : (3,) numpy.ndarray
        The view direction, a unit vector from the scene toward the ladar.
    offset : float
        Added to ``h.range`` to give the binned range (scene units).
    plan : TracePlan
        The run's plan: ``geo``, ``area`` and ``traced_with``.
    weighing : Weighing
        The coatings, radiometry, ``axes`` (one to three names), their ``edges`` and,
        for ``"doppler"``, the ``motion``.
    out : (n_0[, n_1[, n_2]]) float64 numpy.ndarray
        The view's cells, n_i = len(weighing.edges[i]) − 1, in the order of
        ``weighing.axes``; the weights are added into it.
    """
    geo, sensor = plan.geo, plan.traced_with
    wt = scaled(weights(h.cos_theta, h.sin_theta, h.material, weighing.materials,
                         plan.area, power=weighing.power),
                h.weight_factor, h.receive_factor, power=weighing.power)
    u, v = frame(w)
    s, t = h.transverse[:, 0], h.transverse[:, 1]
    coords = {"range": h.range + offset,
              "cross_range": s + float(geo.center @ u),
              "elevation": t + float(geo.center @ v)}
    if "doppler" in weighing.axes:
        if sensor is None or sensor.standoff is None:
            points = geo.center + s[:, None] * u + t[:, None] * v - h.range[:, None] * w
        else:
            # the hit point from its transverse coordinates and its true distance
            points = _sensor_points(geo, w, u, v, s, t, h.range, sensor)
        coords["doppler"] = weighing.motion.doppler(points, w)
    shape = out.shape
    flat = np.zeros(wt.size, np.int64)
    ok = wt != 0
    for name, e in zip(weighing.axes, weighing.edges):
        k = np.searchsorted(e, coords[name], side="right") - 1
        ok &= (k >= 0) & (k < e.size - 1)
        flat = flat * (e.size - 1) + k
    out += np.bincount(flat[ok], weights=wt[ok], minlength=int(np.prod(shape))).reshape(shape)


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
