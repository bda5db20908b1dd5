"""The weigh stage's compiled loop for a sensor at a standoff (numba): one view's hits
weighed through the sensor's perspective, beam and link budget, and binned (beside
:mod:`._kernels`, whose helpers it shares: the flat loops' file had grown past its size).

numba is imported here; the stages that use this loop import this module, never
``import meshladar`` itself. The kernel is cached on disk (``cache=True``)."""

from __future__ import annotations

import math

from ._kernels import _bin_of, _smooth_cos
from ..brdf._sandford_robertson_kernel import sr_monostatic as _sr_monostatic
from ._compiled import njit_loop
from ._prefetch import ahead as _ahead
from ._prefetch import prefetch as _prefetch

__all__ = ["bin_sensor_hits"]


@njit_loop()
def bin_sensor_hits(prim, t_cast, dirs, length, bu, bv, D, sensor_pos, range_offset,
                    plane_d, face_normals, corner, smooth, face_material, params, beam,
                    extinction, edges, area, power, ignore_back, min_cos_facet, refine_min_cos,
                    out):
    """Monostatic weighing and binning of one view seen by a sensor at standoff D, fused
    (the numbers of meshladar.raytrace.perspective.trace_sensor_view then
    meshladar.weighing._bin_one, without per-hit arrays; faces' rows prefetched as in
    :func:`._kernels.bin_flat_hits`): ray i leaves ``sensor_pos``
    along ``dirs[i]`` = q/|q| (float64), q = S u + T v − D w its offset to its grid point
    on the reference plane, |q| = ``length[i]``; its hit distance R is recomputed in float64
    against the hit face's plane (``t_cast`` where the plane is edge-on); its weight is
    F·area × cos³α (R/D)² × the beam's relative irradiance (× the smooth normal's area
    factor), and under ``power`` × cos θ (D/R)² exp(−2σR); its range R − ``range_offset``.
    ``beam`` = (kind, radius or −1, waist, divergence, ax, ay, az): kind 0 a flood (a
    top-hat of ``radius`` at distance D when ≥ 0), 1 a Gaussian of 1/e² radius
    sqrt(waist² + (divergence z)²) about the axis (ax, ay, az) from the sensor. Returns
    the number of back-face hits."""
    nb, e0 = edges.size - 1, edges[0]
    inv = nb / (edges[nb] - edges[0])
    back, kind = 0, beam[0]
    ax, ay, az = beam[4], beam[5], beam[6]
    w_ref = math.sqrt(beam[2] * beam[2] + (beam[3] * D) ** 2)
    ahead, n = _ahead(face_normals), prim.size
    for i in range(n):
        if i + ahead < n and prim[i + ahead] >= 0:   # a later hit's rows (._prefetch)
            _prefetch((face_normals, plane_d, face_material), prim[i + ahead])
            if smooth:                          # (an empty array otherwise)
                _prefetch(corner, prim[i + ahead])
        p = prim[i]
        if p < 0:
            continue
        dx, dy, dz = dirs[i, 0], dirs[i, 1], dirs[i, 2]
        nx, ny, nz = face_normals[p, 0], face_normals[p, 1], face_normals[p, 2]
        denom = nx * dx + ny * dy + nz * dz
        if abs(denom) > refine_min_cos:
            R = (plane_d[p] - (nx * sensor_pos[0] + ny * sensor_pos[1]
                               + nz * sensor_pos[2])) / denom
        else:
            R = t_cast[i]
        cg = -denom
        c = _smooth_cos(corner, p, bu[i] * 1.0, bv[i] * 1.0, -dx, -dy, -dz) if smooth else cg
        if cg < 0.0:
            back += 1
            if ignore_back:
                continue
            c = -c
        if c <= 0.0:
            continue
        r = R - range_offset
        if r < edges[0] or r >= edges[nb]:
            continue
        k = _bin_of(r, edges, e0, inv)
        px, py, pz = R * dx, R * dy, R * dz          # the hit relative to the sensor
        z = px * ax + py * ay + pz * az
        rx, ry, rz = px - z * ax, py - z * ay, pz - z * az
        rho2 = rx * rx + ry * ry + rz * rz
        if kind == 0:
            rel = D * D / (rho2 + z * z)
            if beam[1] >= 0.0 and math.sqrt(rho2) * D > beam[1] * z:
                rel = 0.0
        else:
            wz2 = beam[2] * beam[2] + (beam[3] * z) ** 2
            rel = w_ref * w_ref / wz2 * math.exp(-2.0 * rho2 / wz2)
        factor = (D / length[i]) ** 3 * (R / D) ** 2 * rel
        if smooth:
            factor *= c / max(abs(cg), min_cos_facet)
        m = face_material[p]
        f = _sr_monostatic(c, max(1.0 - c * c, 0.0), params[m, 0], params[m, 1], params[m, 2],
                           params[m, 3], params[m, 4], params[m, 5] > 0.5, params[m, 6] > 0.5)
        wt = f * area * factor
        if power:                          # exp(−0) = 1 exactly: skipped without extinction
            wt *= c * (D / R) ** 2 * (math.exp(-2.0 * extinction * R) if extinction else 1.0)
        out[k] += wt
    return back
