"""A view seen by a sensor at a finite standoff, cast by
:func:`meshladar.raytrace.perspective.sensor_cast` and weighed and binned by the compiled
loop ``meshladar.weighing._sensor_kernels.bin_sensor_hits`` (flat or smooth normals, coatings with
``kernel_params``): the numbers of the per-hit path."""

from __future__ import annotations

import numpy as np

from .._lazy import deferred_module
from ..precision import MIN_COS_FACET, REFINE_MIN_COS
from ..raytrace.embree4_ctypes import query_flags
from ..raytrace.grid import stratified_sequences
from ..raytrace.perspective import plane_axes, sensor_cast, start_distance
from ..sensor import FloodBeam
from ._scratch import scratch
from .fused import queries
from ..brdf import material_table

# compiled loops, imported (with numba) at their first use: a small run loads neither
_fused_kernels = deferred_module("meshladar.weighing._fused_kernels")
_sensor_kernels = deferred_module("meshladar.weighing._sensor_kernels")

__all__ = ["bin_sensor_view"]


def bin_sensor_view(plan, weighing, scene, w, rng, out, params=None):
    """One view seen by the plan's sensor at a finite standoff, weighed and binned into
    ``out`` by the compiled loop (``meshladar.weighing._sensor_kernels.bin_sensor_hits``; flat or
    smooth normals, coatings with ``kernel_params``): the numbers of
    :func:`meshladar.raytrace.perspective.trace_sensor_view` then weighing. Returns
    (rays cast, back-face hits).

    Monostatic. Each ray's weight is F·area × cos³α (R/D)² × the beam's irradiance at the
    hit relative to the aim point's (× the smooth normal's area factor), and under
    received power also × cos θ (D/R)² exp(−2σR); it is binned at its range
    R − D − aim·w (world coordinates, scene units) by the first range axis' edges.
    Smooth normals are used when ``plan.geo.normals == "smooth"``, the flat face normals
    otherwise.

    Parameters
    ----------
    plan : TracePlan
        The run's plan, whose ``traced_with`` sensor has a finite standoff D; its
        geometry, ray spacing δ, ray area and back faces.
    weighing : Weighing
        The coatings (each with ``kernel_params``), the radiometry and the range edges
        (``weighing.edges[0]``).
    scene : EmbreeScene
        The geometry's scene to cast with (``meshladar.raytrace.embree.embree_scene``).
    w : (3,) numpy.ndarray
        The view direction, a unit vector from the aim point toward the sensor.
    rng : numpy.random.Generator or None
        The view's generator for a stratified grid on the reference plane; None: regular.
    out : (n_bins,) float64 numpy.ndarray
        The view's range profile; the weights are added into it.
    params : numpy.ndarray, optional
        The coatings' table (:func:`meshladar.brdf.material_table` of
        ``weighing.materials``), made once for a run's many views; default: made here.

    Returns
    -------
    rays : int
        The rays cast.
    back : int
        The view's back-face hits.

    Raises
    ------
    ParameterError
        When the standoff puts the sensor inside the target's extent seen from this view
        (``plan_trace`` refuses that for every view first).
    """
    geo, sensor, spacing = plan.geo, plan.traced_with, plan.spacing
    aim = np.asarray(sensor.aim, np.float64) - geo.center
    if params is None:
        params = material_table(weighing.materials)
    if scene.fused:
        return _fused_view(plan, weighing, scene, w, rng, out, aim, params)
    cast = sensor_cast(geo, scene, w, spacing, rng, sensor, aim)
    sensor_pos, u, v = cast.sensor_pos, cast.u, cast.v
    o, res = cast.origins, cast.res
    smooth = geo.normals == "smooth"
    empty = np.zeros(0, np.float32)
    back = _sensor_kernels.bin_sensor_hits(
        res["primID"], cast.t0 + res["tfar"].astype(np.float64), cast.dirs, cast.length,
        res["u"] if smooth else empty, res["v"] if smooth else empty,
        float(sensor.standoff), sensor_pos, *_binning(plan, weighing, aim, u, v, sensor_pos,
                                                      w, params), out)
    return len(o), back


def _fused_view(plan, weighing, scene, w, rng, out, aim, params):
    """The view through the packet backend's fused loop
    (:func:`._fused_kernels.cast_bin_sensor`): rays built, cast, weighed and binned a band
    of rows at a time. Returns (rays cast, back-face hits)."""
    geo, sensor, spacing = plan.geo, plan.traced_with, plan.spacing
    D = float(sensor.standoff)
    sensor_pos = aim + D * w
    s, t, u, v = plane_axes(geo, w, spacing, sensor_pos, D, aim)
    offsets = stratified_sequences(s.size, t.size, rng) if rng is not None else \
        (np.empty(0, np.float32),) * 4
    plane = (s, t, offsets, float(spacing), u, v, np.asarray(w, np.float64))
    pk = scene.scene.scene
    lib = pk.lib
    flags = query_flags(plan.coherent)
    back, n = _fused_kernels.cast_bin_sensor(
        queries(lib, plan.coherent), pk.live(), lib.width, flags, plane,
        (D, sensor_pos, start_distance(geo, sensor_pos, spacing)), np.float32(scene.inverse),
        float(scene.scale), geo.normals == "smooth",
        _binning(plan, weighing, aim, u, v, sensor_pos, w, params), out,
        scratch("sensor", lib.width, t.size))
    return n, back


def _binning(plan, weighing, aim, u, v, sensor_pos, w, params):
    """bin_sensor_hits' arguments after the sensor's position, but ``out``."""
    geo, sensor = plan.geo, plan.traced_with
    back_faces, area = plan.back_faces, plan.area
    power, edges = weighing.power, weighing.edges[0]
    beam = sensor.beam
    off = aim if isinstance(beam, FloodBeam) else \
        aim + beam.offset[0] * u + beam.offset[1] * v
    axis = (off - sensor_pos) / np.linalg.norm(off - sensor_pos)
    if isinstance(beam, FloodBeam):
        spec = (0.0, -1.0 if beam.radius is None else beam.radius, 0.0, 0.0)
    else:
        spec = (1.0, -1.0, beam.waist, beam.divergence)
    smooth = geo.normals == "smooth"
    return (float(sensor.standoff) + float((aim + geo.center) @ w), geo.plane_d,
            geo.face_normals, geo.corner if smooth else np.zeros((0, 3, 3)), smooth,
            geo.material, params, np.array(spec + tuple(axis)),
            float(sensor.extinction), edges, float(area), bool(power), back_faces == "ignore",
            MIN_COS_FACET, REFINE_MIN_COS)
