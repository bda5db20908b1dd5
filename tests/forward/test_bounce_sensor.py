"""Bounces seen by a sensor (meshladar.forward.bounce_ends): a 90° Lambertian dihedral's
second order from a sensor at a finite standoff, with the atmosphere, against an
independent four-dimensional quadrature of the two-bounce integral with the sensor a point
source and receiver; and the photoelectrons of a counting sensor."""

from __future__ import annotations

import numpy as np
import pytest

import meshladar as ml
from meshladar.brdf import Lambertian
from meshladar.forward.bounces import higher_orders
from meshladar.meshes import MeshPart
from meshladar.sensor import Sensor

#: Plate width, height, albedo, view (as tests/forward/test_bounces.py's dihedral).
A, B, RHO, PHI = 1.0, 0.7, 0.5, np.radians(30.0)
W = np.array([np.cos(PHI), np.sin(PHI), 0.0])
#: The sensor: standoff (a few plate widths: its rays fan out by ±15°), aim point, extinction
#: (per unit length: exp(−σ × path) is 0.45 over the ~8-unit round trip).
D, AIM, SIGMA = 3.0, np.array([0.3, 0.3, 0.35]), 0.1
EDGES = np.linspace(-1.0, 0.6, 41)
#: Paths: the total's standard error is ~0.2 % of it.
SAMPLES = 1 << 21
SIGMAS = 4.0


def dihedral(material):
    """Plate A in y = 0 (x in [0, A]), plate B in x = 0 (y in [0, A]), both z in [0, B]."""
    def plate(corners, name):
        return MeshPart(np.array(corners, float), [[0, 1, 2], [0, 2, 3]], 0, name)
    return ml.Scene.from_parts([plate([[0, 0, 0], [A, 0, 0], [A, 0, B], [0, 0, B]], "A"),
                                plate([[0, 0, 0], [0, 0, B], [0, A, B], [0, A, 0]], "B")],
                               [material])


def quadrature(n):
    """The dihedral's two-bounce return per bin from a point sensor S = aim + D w, per unit
    irradiance at the aim point, by a midpoint rule written here (n points across a plate,
    0.7 n up it): pairs X on one plate, Y on the other, integrand
    (ρ/π)² · cos θ_X (D/R_X)² (the flood's irradiance) · cos_X cos_Y / r² · cos θ_Y (D/R_Y)²
    (the receiver's solid angle) · exp(−σ (R_X + r + R_Y)), both ways round; nothing
    shadows (the sensor sees both inner faces, which see each other); binned at
    (R_X + r + R_Y)/2 − D − aim·w."""
    m = int(round(0.7 * n))
    a, z = (g.ravel() for g in np.meshgrid((np.arange(n) + 0.5) * A / n,
                                           (np.arange(m) + 0.5) * B / m, indexing="ij"))
    plates = [np.stack([a, 0 * a, z], 1), np.stack([0 * a, a, z], 1)]     # normals y, x
    S = AIM + D * W
    lit = []
    for P, k in zip(plates, (1, 0)):
        R = np.linalg.norm(S - P, axis=1)
        lit.append(((S - P)[:, k] / R * (D / R) ** 2, R))
    out = np.zeros(len(EDGES) - 1)
    for (P, Q), ((cp, rp), (cq, rq)) in (((plates[0], plates[1]), (lit[0], lit[1])),
                                         ((plates[1], plates[0]), (lit[1], lit[0]))):
        for s in range(0, len(P), 256):
            d = Q[None, :, :] - P[s:s + 256, None, :]
            r = np.sqrt(np.einsum("ijk,ijk->ij", d, d))
            kern = -d[..., 0] * d[..., 1] / r ** 4          # cos at each end over r²
            val = kern * cp[s:s + 256, None] * cq[None, :] * np.exp(
                -SIGMA * (rp[s:s + 256, None] + r + rq[None, :]))
            rng = 0.5 * (rp[s:s + 256, None] + r + rq[None, :]) - (D + AIM @ W)
            out += np.histogram(rng, EDGES, weights=val)[0]
    return out * (RHO / np.pi) ** 2 * (A / n * B / m) ** 2


@pytest.fixture(scope="module")
def reference():
    """Richardson's extrapolation of the first-order midpoint rule (measured: the total
    changes by −1.2 % from 25 to 50 points and −0.53 % from 50 to 100), and its error
    taken as the last change."""
    fine, coarse = quadrature(100), quadrature(50)
    return 2 * fine - coarse, np.abs(fine - coarse)


def test_a_sensor_at_a_finite_standoff_matches_the_point_source_quadrature(reference):
    """Per bin and in total, within SIGMAS standard errors plus the quadrature's error; the
    sensor's answer is far from the ladar at infinity's (the comparison means something)."""
    q, err = reference
    lad = ml.Ladar(None, view_vectors=W[None], bin_edges=EDGES)
    scene = dihedral(Lambertian(RHO))
    sensor = Sensor(standoff=D, aim=tuple(AIM), extinction=SIGMA)
    o = higher_orders(scene, lad, bounces=2, ray_spacing=2e-3, samples=SAMPLES, seed=4,
                      sensor=sensor)
    v, se = o.values[0, 0], o.stderr[0, 0]
    assert np.all(np.abs(v - q) <= SIGMAS * se + err + 1e-3 * q.max()), \
        np.round((v - q) / q.max(), 4)
    total_se = np.sqrt(np.sum(se ** 2))
    assert abs(v.sum() - q.sum()) <= SIGMAS * total_se + err.sum()
    assert total_se < 5e-3 * q.sum()
    far = higher_orders(scene, lad, bounces=2, ray_spacing=2e-3, samples=1 << 15, seed=4)
    assert far.values.sum() > 1.5 * q.sum()            # measured: 2.1 times


def test_a_counting_sensor_gives_the_orders_in_photoelectrons():
    """With pulse energy and an aperture the single bounce is in photoelectrons; the second
    order is scaled by the same factor (its share of the total is the non-counting run's,
    the same seed drawing the same paths)."""
    scene = dihedral(Lambertian(RHO))
    lad = ml.Ladar(None, view_vectors=W[None], bin_edges=EDGES)
    plain = Sensor(standoff=D, aim=tuple(AIM), beam=ml.sensor.FloodBeam(radius=2.0))
    counting = Sensor(standoff=D, aim=tuple(AIM), beam=ml.sensor.FloodBeam(radius=2.0),
                      pulse_energy=1e-3, aperture_diameter=0.1)
    runs = [ml.simulate(scene, lad, model="mesh", radiometry="power", bounces=2,
                        bounce_samples=1 << 12, seed=2, sensor=s, ray_spacing=1e-2)
            for s in (plain, counting)]
    k = counting.photoelectrons_per_unit()
    assert runs[1].info["units"] == "photoelectrons" and k > 1e6
    np.testing.assert_allclose(runs[1].info["order_totals"],
                               k * np.asarray(runs[0].info["order_totals"]), rtol=1e-12)
    np.testing.assert_allclose(runs[1].values, k * runs[0].values, rtol=1e-12)
