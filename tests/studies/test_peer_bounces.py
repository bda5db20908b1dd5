"""Light beyond one bounce against an independent renderer: Mitsuba 3 + mitransient at
max_depth 2, 3 and 4 (:mod:`meshladar.studies.peer_bounces`), on a 90° dihedral and a
hemispherical bowl, Lambertian and a rough conductor (GGX, Mitsuba's ``roughconductor``):
the range profiles, bin by bin, of each order and of their sum (mitransient lit by a point
source 1e4 radii away, whose light leg is a plane wave's to 5e-5 radii). Without the
renderer these tests skip, except under CI, where they fail (as
tests/studies/test_peer_mitsuba.py)."""

from __future__ import annotations


import numpy as np
import pytest
import trimesh

import meshladar as ml
from meshladar.forward.bounces import higher_orders
from meshladar.meshes import MeshPart

#: The profile of orders 1-3 summed, relative L2 over the range bins: the issue's bar, on
#: top of SIGMAS of meshladar's own standard errors (its L2 over the bins). Measured
#: 2026-12-04 at 2^21 paths: 0.8e-3 to 3.6e-3 in all, order 1 alone 2.5e-4 to 4e-4 (two
#: mitransient seeds: 0.3e-4 to 1.7e-4).
TOTAL_RTOL = 2e-3
#: Each order beyond the first, L2 over the bins: meshladar's own standard errors (SIGMAS
#: of them) plus mitransient's remaining noise at 1024 spp on 256² pixels (two seeds:
#: 1e-4 to 1.1e-3 for order 2, 7e-4 to 7.5e-3 for order 3), relative.
SIGMAS, PEER_RTOL = 4.0, 3e-3
#: meshladar's paths per view and order.
SAMPLES = 1 << 22
#: mitransient's samples per pixel and film.
SPP, FILM = 1024, (256, 256)

LAMBERT = ({"type": "diffuse", "reflectance": {"type": "uniform", "value": 0.6}},
           ml.brdf.Lambertian(0.6))
ROUGH = ({"type": "roughconductor", "distribution": "ggx", "alpha": 0.3, "material": "none",
          "specular_reflectance": {"type": "uniform", "value": 0.8}}, ml.brdf.GGX(0.3, 0.8))


def _dihedral():
    """The plates, the view, and range bins 0.05 wide (no edge at the apex's range 0)."""
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 0, 0.7], [0, 0, 0.7],
                  [0, 0, 0], [0, 0, 0.7], [0, 1, 0.7], [0, 1, 0]], float)
    f = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]])
    return (v, f, np.array([np.cos(np.radians(30.0)), np.sin(np.radians(30.0)), 0.0]),
            np.linspace(-1.025, 0.975, 41))


def _bowl():
    """A 320-face icosphere's lower half seen 17° off its axis, bins 0.1 wide."""
    s = trimesh.creation.icosphere(3)
    keep = s.triangles_center[:, 2] < 0
    w = np.array([0.3, 0.1, 1.0])
    return (np.asarray(s.vertices), np.asarray(s.faces)[keep], w / np.linalg.norm(w),
            np.linspace(-1.05, 3.05, 42))


def _rel(a, b):
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


@pytest.mark.slow
@pytest.mark.parametrize("shape", [_dihedral, _bowl], ids=["dihedral", "bowl"])
@pytest.mark.parametrize("coating", [LAMBERT, ROUGH], ids=["lambertian", "rough-conductor"])
def test_profiles_of_each_order_match_mitransient(renderer, shape, coating):
    from meshladar.studies.peer_bounces import mitransient_profiles

    v, f, w, edges = shape()
    bsdf, brdf = coating
    theirs = mitransient_profiles(v, f, w, edges, bsdf=bsdf, bounces=3, spp=SPP, film=FILM,
                                  seed=0)
    scene = ml.Scene.from_parts([MeshPart(v, f, 0, "target")], [brdf])
    ladar = ml.Ladar(None, view_vectors=w[None], bin_edges=edges)
    with pytest.warns(ml.errors.BounceWarning, match="bounces beyond the first return about"):
        first = ml.simulate(scene, ladar, model="mesh", radiometry="power",
                            ray_spacing=2e-3).values[0]
    orders = higher_orders(scene, ladar, bounces=3, ray_spacing=2e-3, samples=SAMPLES,
                           seed=1)
    assert np.all(theirs[1:].sum(axis=1) > 0)
    total, se = first + orders.values[:, 0].sum(axis=0), orders.stderr[:, 0]
    noise = np.linalg.norm(np.sqrt((se ** 2).sum(axis=0)))
    assert np.linalg.norm(total - theirs.sum(axis=0)) <= \
        TOTAL_RTOL * np.linalg.norm(theirs.sum(axis=0)) + SIGMAS * noise, \
        (_rel(total, theirs.sum(axis=0)), noise / np.linalg.norm(total))
    for k in (0, 1):
        ours, se_k = orders.values[k, 0], se[k]
        assert np.linalg.norm(ours - theirs[k + 1]) <= SIGMAS * np.linalg.norm(se_k) + \
            PEER_RTOL * np.linalg.norm(theirs[k + 1]), (k + 2, _rel(ours, theirs[k + 1]))


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
