"""Light beyond one bounce against an independent renderer: Mitsuba 3 + mitransient at
max_depth 2, 3 and 4 (:mod:`meshladar.studies.peer_bounces`), on a 90° dihedral and a
hemispherical bowl, Lambertian and a rough conductor (GGX, Mitsuba's ``roughconductor``).

Each order's total power is compared (mitransient's directional emitter counts a constant
light leg, so its range bins of higher orders are not a plane wave's; the power each order
carries is). Without the renderer these tests skip, except under CI, where they fail (as
tests/studies/test_peer_mitsuba.py)."""

from __future__ import annotations


import numpy as np
import pytest
import trimesh

import meshladar as ml
from meshladar.meshes import MeshPart

#: Orders 1-3 summed: the issue's bar on the received power (measured 2026-12-04: at most
#: 3e-5 apart; order 1 is exact in both up to sampling).
TOTAL_RTOL = 2e-3
#: Each order beyond the first: meshladar's own standard errors (SIGMAS of them) plus
#: mitransient's remaining error at 1024 spp on 256² pixels (its third order moved 0.7 %
#: from 128² to 256² pixels; two seeds at 256² agree to 8e-4).
SIGMAS, PEER_RTOL = 4.0, 2e-3
#: meshladar's paths per view and order (standard errors 0.08-0.34 % of orders 2-3).
SAMPLES = 1 << 22
#: mitransient's samples per pixel and film.
SPP, FILM = 1024, (256, 256)

LAMBERT = ({"type": "diffuse", "reflectance": {"type": "uniform", "value": 0.6}},
           ml.brdf.Lambertian(0.6))
ROUGH = ({"type": "roughconductor", "distribution": "ggx", "alpha": 0.3, "material": "none",
          "specular_reflectance": {"type": "uniform", "value": 0.8}}, ml.brdf.GGX(0.3, 0.8))


def _dihedral():
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 0, 0.7], [0, 0, 0.7],
                  [0, 0, 0], [0, 0, 0.7], [0, 1, 0.7], [0, 1, 0]], float)
    f = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]])
    return v, f, np.array([np.cos(np.radians(30.0)), np.sin(np.radians(30.0)), 0.0])


def _bowl():
    s = trimesh.creation.icosphere(3)
    keep = s.triangles_center[:, 2] < 0
    w = np.array([0.3, 0.1, 1.0])
    return np.asarray(s.vertices), np.asarray(s.faces)[keep], w / np.linalg.norm(w)


@pytest.mark.slow
@pytest.mark.parametrize("shape", [_dihedral, _bowl], ids=["dihedral", "bowl"])
@pytest.mark.parametrize("coating", [LAMBERT, ROUGH], ids=["lambertian", "rough-conductor"])
def test_orders_of_bounces_match_mitransient(renderer, shape, coating):
    from meshladar.studies.peer_bounces import mitransient_orders

    v, f, w = shape()
    bsdf, brdf = coating
    theirs = mitransient_orders(v, f, w, bsdf=bsdf, bounces=3, spp=SPP, film=FILM, seed=0)
    scene = ml.Scene.from_parts([MeshPart(v, f, 0, "target")], [brdf])
    ladar = ml.Ladar(None, view_vectors=w[None], bin_edges=np.linspace(-4.0, 4.0, 9))
    sino = ml.simulate(scene, ladar, model="mesh", radiometry="power", ray_spacing=2e-3,
                       bounces=3, bounce_samples=SAMPLES, seed=1)
    ours = np.array(sino.info["order_totals"])
    se = np.array(sino.info["order_stderr"])
    assert sino.info["bounces"] == 3 and np.all(theirs[1:] > 0)
    assert abs(ours.sum() / theirs.sum() - 1) < TOTAL_RTOL, (ours, theirs)
    assert np.all(np.abs(ours[1:] - theirs[1:]) <= SIGMAS * se[1:] + PEER_RTOL * theirs[1:]), \
        (ours, theirs, se)


@pytest.mark.slow
def test_the_time_to_a_standard_error_is_measured_for_both(renderer):
    from meshladar.studies.peer_bounces import bench_second_bounce

    r = bench_second_bounce(rounds=2, spp=16, samples=1 << 12)
    assert all(np.isfinite(r[k]) and r[k] > 0 for k in
               ("meshladar_s", "mitransient_s", "meshladar_error", "mitransient_error"))
    # the bowl's second order, within 5 of meshladar's own standard errors of the
    # integrating-sphere closed form rho^2 A^2 / (4 pi^2) (faceting -0.5 % at 4 subdivisions)
    w = np.array([0.3, 0.1, 1.0]) / np.linalg.norm([0.3, 0.1, 1.0])
    exact = 0.6 ** 2 * (np.pi * w[2]) ** 2 / (4 * np.pi ** 2)
    assert abs(r["order2"] / exact - 1) < 5 * r["meshladar_error"] + 5e-3
