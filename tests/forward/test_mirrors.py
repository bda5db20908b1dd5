"""Next-event estimation through flat mirrors (meshladar.forward.mirrors): a Lambertian
plate facing a near-mirror plate against the mirror-image closed form, for glints as
narrow as e = 1e-4 where sampling alone fails; the same run with and without the mirrors'
chain agreeing where both converge (no path counted twice); a distant sensor."""

from __future__ import annotations

import numpy as np
import pytest

import meshladar as ml
from meshladar.brdf import Lambertian, SandfordRobertson
from meshladar.forward import mirrors as mirror_module
from meshladar.forward.bounces import higher_orders
from meshladar.forward.mirrors import MIRROR_LOBE, chains, find_mirrors
from meshladar.meshes import MeshPart
from meshladar.raytrace.embree import geometry
from meshladar.sensor import Sensor

#: Plate width and height, the Lambertian plate's albedo, the view's angle from plate B.
A, B, RHO, PHI = 1.0, 0.7, 0.5, np.radians(30.0)
W = np.array([np.cos(PHI), np.sin(PHI), 0.0])
#: The mirror's specular reflectivity: SR with ρd = 0, ε = 0.1, b = 0 (Eq. A8: 1 − ε).
RHO_S = 0.9
#: The apex's range bin: the sampled mirror-first paths leave within ~2e of the mirror
#: direction, so their ranges spread by ~e of the plates' size (the chain's are exact).
EDGES = np.array([-1.0, -0.05, 0.05, 1.0])
SIGMAS = 4.0


def dihedral(e):
    """Lambertian plate A in y = 0 (x in [0, A]) and plate B in x = 0 (y in [0, A]), of
    SR coating with glint width ``e``, both z in [0, B]."""
    plates = [MeshPart(np.array(c, float), [[0, 1, 2], [0, 2, 3]], k, name) for c, k, name in (
        ([[0, 0, 0], [A, 0, 0], [A, 0, B], [0, 0, B]], 0, "A"),
        ([[0, 0, 0], [0, 0, B], [0, A, B], [0, A, 0]], 1, "B"))]
    return ml.Scene.from_parts(plates, [Lambertian(RHO), SandfordRobertson(0.0, 0.1, 0.0, e)])


def closed_form():
    """The second order of the plate and its mirror, in the mirror limit: light on A
    (cos θ = sin φ) seen through B along the reflected direction (also at sin φ from A's
    normal) — all of A at φ ≤ 45° — and light reflected by B onto A (B's projected area
    A tan φ · B · cos φ lit), seen directly: each ρs (ρ/π) sin²φ A B, and every path as
    long as the apex's (range 0)."""
    return 2.0 * RHO_S * RHO / np.pi * np.sin(PHI) ** 2 * A * B


@pytest.mark.parametrize("e", [1e-2, 3e-3, 1e-4])
def test_a_plate_and_its_mirror_match_the_mirror_image_closed_form(e):
    lad = ml.Ladar(None, view_vectors=W[None], bin_edges=EDGES)
    o = higher_orders(dihedral(e), lad, bounces=2, ray_spacing=4e-3, samples=1 << 16,
                      seed=1)
    total, se = o.values.sum(), np.sqrt(np.sum(o.stderr ** 2))
    assert abs(total - closed_form()) <= SIGMAS * se + 2e-3 * closed_form()
    assert se < 0.02 * total
    assert o.values[0, 0, 1] >= 0.99 * total                        # at the apex's range


def test_sampling_alone_fails_there():
    """Without the mirrors' chain (MIRROR_LOBE 0) the same run at e = 3e-3 is far off or
    uncertain: why the chain is there."""
    lad = ml.Ladar(None, view_vectors=W[None], bin_edges=EDGES)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(mirror_module, "MIRROR_LOBE", 0.0)
        o = higher_orders(dihedral(3e-3), lad, bounces=2, ray_spacing=4e-3,
                          samples=1 << 16, seed=1)
    total, se = o.values.sum(), np.sqrt(np.sum(o.stderr ** 2))
    assert abs(total / closed_form() - 1) > 0.1 or se > 0.05 * total


def test_with_and_without_the_chain_agree_where_both_converge():
    """A glint of e = 0.03, three bounces: sampled alone (many paths), and with the plate
    counted a mirror (MIRROR_LOBE raised to 0.05): every order within SIGMAS combined
    standard errors plus the mirror limit's error (of order e²)."""
    lad = ml.Ladar(None, view_vectors=W[None], bin_edges=np.linspace(-1.0, 1.0, 9))
    scene = dihedral(3e-2)
    sampled = higher_orders(scene, lad, bounces=3, ray_spacing=4e-3, samples=1 << 20, seed=2)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(mirror_module, "MIRROR_LOBE", 0.05)
        assert find_mirrors(scene, geometry(scene, "flat")) is not None
        chained = higher_orders(scene, lad, bounces=3, ray_spacing=4e-3, samples=1 << 16,
                                seed=3)
    for k in range(2):
        a, b = sampled.values[k].sum(), chained.values[k].sum()
        se = np.hypot(np.sqrt(np.sum(sampled.stderr[k] ** 2)),
                      np.sqrt(np.sum(chained.stderr[k] ** 2)))
        assert abs(a - b) <= SIGMAS * se + 2e-3 * b, (k, a, b, se)


@pytest.mark.parametrize("radiometry", ["power", "paper"])
def test_with_and_without_the_chain_agree_from_a_near_sensor(radiometry):
    """A sensor 2 units away (its image through the mirror 2-3 units from the plate): the
    chain's unfolded solid angle (power) and the mirror's area per emitter area (paper)
    against sampling alone, at e = 0.03 counted a mirror or not."""
    lad = ml.Ladar(None, view_vectors=W[None], bin_edges=np.linspace(-3.0, 3.0, 9))
    scene, sensor = dihedral(3e-2), Sensor(standoff=2.0, aim=(0.3, 0.3, 0.35))
    kw = dict(bounces=2, ray_spacing=4e-3, sensor=sensor, radiometry=radiometry)
    sampled = higher_orders(scene, lad, samples=1 << 20, seed=2, **kw)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(mirror_module, "MIRROR_LOBE", 0.05)
        chained = higher_orders(scene, lad, samples=1 << 16, seed=3, **kw)
    a, b = sampled.values.sum(), chained.values.sum()
    se = np.hypot(np.sqrt(np.sum(sampled.stderr ** 2)), np.sqrt(np.sum(chained.stderr ** 2)))
    assert abs(a - b) <= SIGMAS * se + 2e-3 * b, (a, b, se)
    assert se < 0.03 * b


def test_a_distant_sensor_sees_what_the_ladar_at_infinity_sees():
    """At D = 1e5 the sensor's image through the mirror is along the mirrored direction,
    and its solid angle (D/R)² within 1e-4 of 1."""
    lad = ml.Ladar(None, view_vectors=W[None], bin_edges=EDGES)
    far = higher_orders(dihedral(1e-3), lad, bounces=2, ray_spacing=4e-3, samples=1 << 14,
                        seed=1)
    near = higher_orders(dihedral(1e-3), lad, bounces=2, ray_spacing=4e-3, samples=1 << 14,
                         seed=1, sensor=Sensor(standoff=1e5))
    np.testing.assert_allclose(near.values.sum(), far.values.sum(), rtol=3e-3)


def test_which_parts_are_mirrors():
    scene = dihedral(1e-3)
    found = find_mirrors(scene, geometry(scene, "flat"))
    assert found.part == ((1,),) and found.emits.tolist() == [True, False]
    assert found.longest == 3                           # (no chain of two exists)
    np.testing.assert_allclose(np.abs(found.normal[0]), [1.0, 0.0, 0.0])
    assert find_mirrors(dihedral(2 * MIRROR_LOBE), geometry(dihedral(2 * MIRROR_LOBE),
                                                            "flat")) is None
    glossy = ml.Scene.from_parts(dihedral(1e-3).parts,
                                 [Lambertian(RHO), SandfordRobertson(0.3, 0.1, 0.0, 1e-3)])
    assert find_mirrors(glossy, geometry(glossy, "flat")) is None     # a diffuse lobe too
    assert chains(3, 2) == [(0,), (1,), (2,), (0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1)]


def test_coplanar_mirrors_are_one_and_many_mirrors_shorten_the_chains():
    """Mirror tiles in one plane reflect alike: one mirror. Five mirror planes make
    5·4·4 = 80 chains of three, more than MAX_CHAINS: chains of two (20); and with more
    than MAX_CHAINS planes the mirrors are sampled like any surface (None)."""
    from meshladar.forward.mirrors import MAX_CHAINS
    glint = SandfordRobertson(0.0, 0.1, 0.0, 1e-3)

    def tile(x0, normal_axis, name):
        v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float) + [x0, 0, 0]
        v = np.roll(v, normal_axis, axis=1)
        return MeshPart(v, [[0, 1, 2], [0, 2, 3]], 1, name)

    floor = MeshPart(np.array([[0, 0, -5], [9, 0, -5], [9, 9, -5], [0, 9, -5]], float),
                     [[0, 1, 2], [0, 2, 3]], 0, "floor")
    tiles = ml.Scene.from_parts([floor, tile(0, 0, "t0"), tile(2, 0, "t1")],
                                [Lambertian(0.5), glint])
    found = find_mirrors(tiles, geometry(tiles, "flat"))
    assert found.part == ((1, 2),) and found.of_face.tolist() == [-1, -1, 0, 0, 0, 0]

    def plates(n):
        parts = [floor] + [MeshPart(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.1 * k]], float)
                                    + [3.0 * k, 0, 0], [[0, 1, 2]], 1, f"p{k}")
                           for k in range(n)]
        scene = ml.Scene.from_parts(parts, [Lambertian(0.5), glint])
        return find_mirrors(scene, geometry(scene, "flat"))
    assert MAX_CHAINS == 64 and plates(5).longest == 2 and plates(3).longest == 3
    assert plates(10).longest == 1 and plates(65) is None          # 10·9 = 90 > 64
