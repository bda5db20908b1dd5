"""Light after more than one bounce (meshladar.forward.bounces): a 90° dihedral of two
plates against an independent quadrature of the two-bounce integral, convex scenes exactly
single-bounce without a ray, honest standard errors, and what is refused before work."""

from __future__ import annotations

import numpy as np
import pytest

import meshladar as ml
from meshladar.brdf import Lambertian, SandfordRobertson, Tabulated
from meshladar.errors import MeshladarWarning, ModelError, ParameterError
from meshladar.forward import bounce_ends, bounces as bounce_module
from meshladar.forward._paths import lobe_width
from meshladar.forward.bounces import higher_orders
from meshladar.meshes import MeshPart

#: Plate width along the shared edge's normal, height along the edge (z), albedo, view.
A, B, RHO, PHI = 1.0, 0.7, 0.5, np.radians(30.0)
W = np.array([np.cos(PHI), np.sin(PHI), 0.0])
EDGES = np.linspace(-1.0, 0.4, 57)
#: Paths for the comparison with the quadrature: its standard error is ~0.2 % of the total.
SAMPLES = 1 << 19
#: Standard errors allowed between a Monte Carlo estimate and the quadrature (plus the
#: quadrature's own error, the change from 200 to 400 points a side).
SIGMAS = 4.0


def dihedral(material):
    """Plate A in y = 0 (x in [0, A]), plate B in x = 0 (y in [0, A]), both z in [0, B]:
    their inner faces see each other."""
    def plate(corners, name):
        return MeshPart(np.array(corners, float), [[0, 1, 2], [0, 2, 3]], 0, name)
    return ml.Scene.from_parts([plate([[0, 0, 0], [A, 0, 0], [A, 0, B], [0, 0, B]], "A"),
                                plate([[0, 0, 0], [0, 0, B], [0, A, B], [0, A, 0]], "B")],
                               [material])


def quadrature(n, phi_r=None, paper=False):
    """The Lambertian dihedral's two-bounce return per bin, by a midpoint rule written
    here: points x on A and y on B, the height difference u = z_B − z_A (weight B − |u|
    for the pairs of heights), kernel x y / r⁴ (both cosines over r²) times
    (ρ/π)² cos θ₁ (the entering cosine) cos θᵣ (the leaving one), both ways round; every
    pair sees the other, no shadowing at 0 < φ < 90°; binned at half the optical path,
    (−x₁·w + r − x₂·w_r) / 2. ``phi_r``: a bistatic receiver w_r at that angle in the x-y
    plane (default: the view's). ``paper``: the paper's Eq. 8, without the leaving
    cosine."""
    phi_r = PHI if phi_r is None else phi_r
    leave_b, leave_a = (1.0, 1.0) if paper else (np.cos(phi_r), np.sin(phi_r))
    h, hu = A / n, 2 * B / (2 * n)
    xs = (np.arange(n) + 0.5) * h
    us = -B + (np.arange(2 * n) + 0.5) * hu
    y, u = np.meshgrid(xs, us, indexing="ij")
    out = np.zeros(len(EDGES) - 1)
    c = (RHO / np.pi) ** 2
    for x in xs:
        s2 = x * x + y * y + u * u
        k = x * y * (B - np.abs(u)) / s2 ** 2
        # A -> B: enters A at (x, 0) (cos = sin φ), leaves B at (0, y) (cos = cos φ_r)
        out += c * np.sin(PHI) * leave_b * np.histogram(
            0.5 * (-x * np.cos(PHI) + np.sqrt(s2) - y * np.sin(phi_r)), EDGES, weights=k)[0]
        # B -> A: enters B at (0, y) (cos φ), leaves A at (x, 0) (sin φ_r)
        out += c * np.cos(PHI) * leave_a * np.histogram(
            0.5 * (-y * np.sin(PHI) + np.sqrt(s2) - x * np.cos(phi_r)), EDGES, weights=k)[0]
    return out * h * h * hu


@pytest.fixture(scope="module")
def reference():
    return quadrature(400), quadrature(200)


def test_the_dihedral_matches_the_quadrature(reference):
    """Per bin and in total, within SIGMAS standard errors plus the quadrature's error."""
    q, coarse = reference
    lad = ml.Ladar(None, view_vectors=W[None], bin_edges=EDGES)
    orders = higher_orders(dihedral(Lambertian(RHO)), lad, bounces=2, ray_spacing=2e-3,
                           samples=SAMPLES, seed=3)
    v, se = orders.values[0, 0], orders.stderr[0, 0]
    assert orders.orders == (2,) and v.sum() > 0
    slack = SIGMAS * se + np.abs(q - coarse)
    assert np.all(np.abs(v - q) <= slack + 1e-3 * q.max()), np.round((v - q) / q.max(), 4)
    total_se = np.sqrt(np.sum(se ** 2))
    assert abs(v.sum() - q.sum()) <= SIGMAS * total_se + abs(q.sum() - coarse.sum())
    assert total_se < 5e-3 * q.sum()                     # the comparison means something


def test_the_papers_radiometry_drops_the_leaving_cosine():
    """Under radiometry="paper" the last vertex weighs F, not F·cos θr: the dihedral's
    second order against the quadrature without the leaving cosine (φ = 30°: the two
    plates' shares change by 1/cos 30° and 1/sin 30°, unevenly), per bin and in total; and
    through simulate, whose single bounce is the paper's Eq. 8 run."""
    q, coarse = quadrature(400, paper=True), quadrature(200, paper=True)
    lad = ml.Ladar(None, view_vectors=W[None], bin_edges=EDGES)
    o = higher_orders(dihedral(Lambertian(RHO)), lad, bounces=2, ray_spacing=2e-3,
                      samples=SAMPLES, seed=5, radiometry="paper")
    v, se = o.values[0, 0], o.stderr[0, 0]
    assert o.radiometry == "paper"
    slack = SIGMAS * se + np.abs(q - coarse)
    assert np.all(np.abs(v - q) <= slack + 1e-3 * q.max()), np.round((v - q) / q.max(), 4)
    power = quadrature(200)
    assert abs(q.sum() / power.sum() - 1.0) > 0.3             # the two differ
    sino = ml.simulate(dihedral(Lambertian(RHO)), lad, model="mesh", bounces=2,
                       bounce_samples=1 << 16, seed=1, ray_spacing=4e-3)
    single = ml.simulate(dihedral(Lambertian(RHO)), lad, model="mesh", ray_spacing=4e-3,
                         bounces=1, seed=1)                 # not checked: the paper's model
    assert sino.radiometry == "paper" and sino.info["bounces"] == 2
    np.testing.assert_allclose(sino.info["order_totals"][0], single.values.sum(), rtol=1e-12)
    second, err = sino.info["order_totals"][1], sino.info["order_stderr"][1]
    assert abs(second - q.sum()) <= SIGMAS * err + abs(q.sum() - coarse.sum())


def test_a_lambertian_bowl_matches_the_integrating_sphere_closed_form():
    """Inside a sphere a Lambertian point sends the fraction S / (4πR²) of its light to any
    region S of the sphere, whoever it is: the irradiance after each bounce is uniform
    over a hemispherical bowl. With A⊥ = πR² cos τ the opening seen at τ from its axis,
    the second order is ρ² A⊥² / (4π² R²) and each further one ρ/2 of the one before.
    On a 5-subdivision icosphere's cap (faceting: measured −1.9e-3 and −6.3e-3 for the two
    quantities, −4.9e-3 and −1.3e-2 at 4 subdivisions)."""
    import trimesh
    s = trimesh.creation.icosphere(5)
    keep = s.triangles_center[:, 2] < 0
    bowl = ml.Scene.from_parts([MeshPart(s.vertices, s.faces[keep], 0, "bowl")],
                               [Lambertian(0.6)])
    w = np.array([0.3, 0.1, 1.0]) / np.linalg.norm([0.3, 0.1, 1.0])
    lad = ml.Ladar(None, view_vectors=w[None], bin_edges=np.linspace(-4, 4, 9))
    o = higher_orders(bowl, lad, bounces=3, ray_spacing=2e-3, samples=1 << 20, seed=2)
    second, third = o.values.sum(axis=(1, 2))
    se2 = np.sqrt(np.sum(o.stderr[0] ** 2))
    exact = 0.6 ** 2 * (np.pi * w[2]) ** 2 / (4 * np.pi ** 2)
    assert abs(second - exact) <= SIGMAS * se2 + 3e-3 * exact
    assert third / second == pytest.approx(0.3, rel=0.012)


def test_a_bistatic_receiver_matches_the_quadrature():
    """A receiver at 60° in the x-y plane, the view at 30°: each way round leaves toward
    the receiver and is binned at half of −x₁·w + r − x₂·w_r, as the quadrature."""
    phi_r = np.radians(60.0)
    q, coarse = quadrature(300, phi_r), quadrature(150, phi_r)
    lad = ml.Ladar(None, view_vectors=W[None], bin_edges=EDGES)
    sino = ml.simulate(dihedral(Lambertian(RHO)), lad, model="mesh", radiometry="power",
                       receiver=(np.cos(phi_r), np.sin(phi_r), 0.0), ray_spacing=2e-3,
                       bounces=2, bounce_samples=SAMPLES, seed=5)
    with pytest.warns(ml.errors.BounceWarning):
        one = ml.simulate(dihedral(Lambertian(RHO)), lad, model="mesh", radiometry="power",
                          receiver=(np.cos(phi_r), np.sin(phi_r), 0.0), ray_spacing=2e-3)
    v = sino.values[0] - one.values[0]
    se = sino.info["order_stderr"][1]
    assert sino.info["bounces"] == 2 and v.sum() > 0
    assert abs(v.sum() - q.sum()) <= SIGMAS * se + abs(q.sum() - coarse.sum())
    assert np.linalg.norm(v - q) <= 0.05 * np.linalg.norm(q)


def test_standard_errors_describe_the_spread():
    """Over 12 seeds, the totals spread as their reported standard error says (ratio in
    [0.5, 2]: the sampling error of a standard deviation from 12 draws is ~20 %)."""
    lad = ml.Ladar(None, view_vectors=W[None], bin_edges=EDGES)
    scene = dihedral(Lambertian(RHO))
    runs = [higher_orders(scene, lad, bounces=2, ray_spacing=1e-2, samples=4096, seed=s)
            for s in range(12)]
    totals = np.array([o.values.sum() for o in runs])
    se = np.mean([np.sqrt(np.sum(o.stderr ** 2)) for o in runs])
    assert 0.5 <= totals.std(ddof=1) / se <= 2.0


def test_glossy_lobes_are_sampled_where_they_are():
    """An SR coating with a narrow lobe (e = 0.05): the mixture sampling's estimate agrees
    with a cosine-only one of many more paths (both unbiased; the lobe sampling's
    standard error is the smaller at equal paths)."""
    scene = dihedral(SandfordRobertson(0.1, 0.6, 0.5, 0.05))
    lad = ml.Ladar(None, view_vectors=W[None], bin_edges=EDGES)
    mixed = higher_orders(scene, lad, bounces=2, ray_spacing=5e-3, samples=1 << 16, seed=1)
    wide = SandfordRobertson(0.1, 0.6, 0.5, 0.05)
    assert np.isfinite(lobe_width(wide))
    se_mixed = np.sqrt(np.sum(mixed.stderr ** 2))
    total = mixed.values.sum()
    assert total > 0 and se_mixed < 0.05 * total


def test_convex_scenes_are_exactly_single_bounce_without_a_ray(monkeypatch):
    """A convex mesh and a tessellated paper phantom: orders beyond the first are exact
    zeros, and no first hit is ever asked for."""
    def refuse(*args, **kwargs):
        raise AssertionError("a convex scene was sampled")
    monkeypatch.setattr(bounce_module, "first_hits", refuse)
    ball = ml.Scene.from_parts([ml.meshes.sphere((0, 0, 0), 1.0, 0)], [Lambertian(0.5)])
    lad = ml.Ladar(np.arange(0.0, 360.0, 45.0), np.linspace(-1.2, 1.2, 49))
    one = ml.simulate(ball, lad, model="mesh", radiometry="power")
    two = ml.simulate(ball, lad, model="mesh", radiometry="power", bounces=3)
    assert np.array_equal(one.values, two.values)
    assert two.info["order_totals"][1:] == [0.0, 0.0] and two.info["bounces"] == 3
    disk = ml.Scene([ml.Disk((0.1, 0.0), 0.5, ml.materials.DARK_GRAY)]).tessellate(256)
    orders = higher_orders(disk, lad, bounces=2, ray_spacing=1e-2)
    assert not orders.values.any() and not orders.stderr.any()


def test_simulate_adds_orders_and_says_so():
    """bounces=2 adds the second order to the single bounce; "auto" keeps the orders up
    to the highest at or above 1 % of the single bounce; bounces=1 on the dihedral warns
    with the cheap estimate, each order's."""
    scene = dihedral(Lambertian(RHO))
    lad = ml.Ladar(np.arange(15.0, 90.0, 30.0), np.linspace(-1.5, 1.5, 61))
    with pytest.warns(MeshladarWarning, match=r"bounces beyond the first return about \d.* "
                                              r"\(the second \d"):
        one = ml.simulate(scene, lad, model="mesh", radiometry="power")
    two = ml.simulate(scene, lad, model="mesh", radiometry="power", bounces=2, seed=0)
    first, second = two.info["order_totals"]
    assert first == pytest.approx(one.values.sum(), rel=1e-12)
    assert two.values.sum() == pytest.approx(first + second, rel=1e-12)
    assert 0.01 < second / first < 0.1 and two.info["bounces"] == 2
    auto = ml.simulate(scene, lad, model="mesh", radiometry="power", bounces="auto", seed=0)
    n = auto.info["bounces"]
    assert n >= 2 and min(auto.info["order_totals"][1:]) >= 0.01 * first
    more = ml.simulate(scene, lad, model="mesh", radiometry="power", bounces=n + 1, seed=0)
    assert more.info["order_totals"][:n] == auto.info["order_totals"]     # same paths
    assert more.info["order_totals"][n] < 0.01 * first


def test_tol_sets_the_paths_from_a_variance_estimate():
    """With tol, a pilot of 2¹¹ paths a view whose standard error is above tol / 2 is
    sampled again with more paths; the result's standard error (relative L2 over the
    sinogram, as the pilot's) is then within tol / 2 (to the 20 % of the estimate's own
    spread)."""
    scene = dihedral(Lambertian(RHO))
    lad = ml.Ladar(np.arange(15.0, 90.0, 30.0), np.linspace(-1.5, 1.5, 61))
    tol = 2e-3
    sino = ml.simulate(scene, lad, model="mesh", radiometry="power", bounces=2, tol=tol,
                       bounce_samples=1 << 11, seed=0)
    assert sino.info["bounce_samples"] > 1 << 11
    rel = sino.info["order_stderr"][1] / np.linalg.norm(sino.values)
    assert rel <= 1.2 * 0.5 * tol


@pytest.mark.parametrize("kwargs, match", [
    ({"bounces": 0}, "bounces must be an integer from 1 to 8"),
    ({"bounces": 9}, "bounces must be an integer from 1 to 8"),
    ({"bounces": 2.0}, "bounces must be"),
    ({"bounces": True}, "bounces must be"),
    ({"bounces": "two"}, "bounces must be"),
    ({"bounces": 2, "bounce_samples": 4}, "bounce_samples must be an integer from 8 to"),
    ({"bounces": 2, "bounce_samples": 1 << 23}, "bounce_samples must be an integer from 8 to"),
    ({"bounces": np.array([2])}, "bounces must be"),
    ({"bounces": 2, "mode": "slice", "radiometry": "power"}, "needs mode='3d'"),
    ({"bounces": 2, "mode": "slice"}, "needs mode='3d'"),
])
def test_bad_bounce_options_are_refused_before_work(monkeypatch, kwargs, match):
    monkeypatch.setattr(bounce_module, "first_hits", None)      # any ray would fail
    monkeypatch.setattr(bounce_ends, "first_hits", None)
    lad = ml.Ladar(np.array([30.0]), EDGES)
    with pytest.raises(ParameterError, match=match):
        ml.simulate(dihedral(Lambertian(RHO)), lad, model="mesh", **kwargs)


def test_a_coating_without_a_bistatic_evaluation_is_refused():
    table = Tabulated(np.linspace(0.0, 90.0, 5), np.full(5, 0.1))
    lad = ml.Ladar(np.array([30.0]), EDGES)
    with pytest.raises(ModelError, match="bistatic evaluation; Tabulated has none"):
        ml.simulate(dihedral(table), lad, model="mesh", bounces=2, radiometry="power")


def test_the_guide_states_the_constants():
    """The numbers docs/guide/bounces.md states about the check and the options."""
    from pathlib import Path

    from meshladar.forward import orders, specular
    text = Path(__file__).parents[2].joinpath("docs", "guide", "bounces.md").read_text()
    assert (orders.CHECK_VIEWS, orders.CHECK_GRID, orders.CHECK_SAMPLES,
            orders.CHECK_ORDERS, orders.CHECK_SIGMAS) == (8, 64, 4096, 4, 2.0)
    assert "by 2 of its own standard errors" in " ".join(text.split())
    assert "8 of its views, a 64-ray grid across the scene, 4096 paths a view of orders " \
           "2 to 4" in \
        " ".join(text.split())
    assert orders.BOUNCE_SHARE == 0.01 and "(default 0.01)" in text
    assert orders.MAX_BOUNCES == 8 and "(up to 8)" in text
    assert specular.RETRO_CONE == 1e-3 and "(default 1 mrad)" in text
    flat = " ".join(text.split())
    assert orders.MAX_BOUNCE_SAMPLES == 4194304 and "at most 4194304" in flat
    assert orders.BOUNCE_SAMPLES == 32768 and "default 32768" in flat
    from meshladar.forward import _paths, mirrors
    assert _paths.GRAZING_SHARE == 1e-3 and "more than 0.1 % of an order's return" in flat
    assert mirrors.MIRROR_LOBE == 0.01 and "a lobe no wider than 0.01" in flat
    assert mirrors.MIRROR_CHAIN == 3 and "chain of up to three mirrors" in flat
    assert mirrors.MAX_CHAINS == 64 and "more than 64 chains of three" in flat and \
        "more than 64 mirror planes" in flat


def test_face_orders_and_sampled_paths():
    """Per face: order 1 sums to a Lambertian ball's received power (ρ/π)(2π/3)R² (to the
    faceting at 4 subdivisions, 1.2e-3); a convex ball's orders beyond 1 are zero and its
    paths stop at their first hit; the dihedral's paths go from one plate to the other."""
    from meshladar.forward.bounce_paths import dominant_order, face_orders, sample_paths
    ball = ml.Scene.from_parts([ml.meshes.sphere((0, 0, 0), 1.0, 0, subdivisions=4)],
                               [Lambertian(0.5)])
    o = face_orders(ball, (0.0, 0.0, 1.0), ray_spacing=2e-3)
    assert not o[:, 1:].any()
    assert o[:, 0].sum() == pytest.approx(2 / 3 * 0.5, rel=3e-3)     # (ρ/π)(2π/3)R²
    assert set(np.unique(dominant_order(o))) == {0, 1}
    assert all(len(p) == 1 for p in sample_paths(ball, (0.0, 0.0, 1.0), paths=5))
    paths = sample_paths(dihedral(Lambertian(RHO)), W, paths=20, bounces=2, seed=1)
    two = [p for p in paths if len(p) == 2]
    assert len(paths) == 20 and two
    for p in two:                                  # from one plate (y = 0 or x = 0) to the other
        on_a = np.isclose(p[:, 1], 0.0, atol=1e-9)
        assert on_a[0] != on_a[1]


@pytest.mark.parametrize("width", [np.nan, 0.3, 0.05, 0.007])
def test_the_sampled_densities_integrate_known_functions(width):
    """E[f(d) / p(d)] over sampled directions is ∫ f dω over the hemisphere, for cos θ (π)
    and cos⁸ θ (2π/9), whatever the lobe mixed in (an incidence of 40°): the density the
    compiled sampler reports is the one it draws from. 400,000 draws: within 5 standard
    errors of the mean."""
    from meshladar.forward.bounces import _sample
    k = 400_000
    n = np.tile([0.0, 0.0, 1.0], (k, 1))
    t = np.radians(40.0)
    wi = np.tile([np.sin(t), 0.0, np.cos(t)], (k, 1))
    d, pdf = _sample(n, wi, np.full(k, width), np.random.default_rng(4))
    ok = pdf > 0
    assert np.allclose(np.linalg.norm(d, axis=1), 1.0) and np.all(d[ok, 2] > 0)
    for power, exact in ((1, np.pi), (8, 2 * np.pi / 9)):
        x = np.where(ok, d[:, 2] ** power / np.where(ok, pdf, 1.0), 0.0)
        assert abs(x.mean() - exact) <= 5 * x.std() / np.sqrt(k)


def test_an_edge_on_glint_under_the_papers_radiometry_is_warned():
    """Under radiometry="paper" the last vertex weighs F; an SR glint's F grows as 1/cos θr
    toward an edge-on exit (A5), a Lambertian F does not: the glint's share is reported and
    warned above GRAZING_SHARE, nothing for the Lambertian."""
    from meshladar.forward._paths import GRAZING_SHARE, edge_on_glints, warn_edge_on, weight
    n = np.array([[1.0, 0.0, 0.0]])
    wo = np.array([[1e-8, 1.0, 0.0]])                       # cos θr = 1e-8
    wi = np.array([[1e-3, -1.0, 0.0]]) / np.hypot(1e-3, 1.0)     # near the mirror direction
    glossy = SandfordRobertson(0.1, 0.1, 0.0, 0.05)
    glint = edge_on_glints([glossy], np.array([0]), n, wi, wo)
    value = weight([glossy], np.array([0]), n, wi, wo, power=False)
    assert glint[0] > 1e6 and glint[0] <= value[0]
    with pytest.warns(MeshladarWarning, match=r"glint carries \d+ % of an order"):
        warn_edge_on(glint, value)
    assert not edge_on_glints([Lambertian(0.5)], np.array([0]), n, wi, wo).any()
    warn_edge_on(np.array([GRAZING_SHARE * 0.5]), np.array([1.0]))     # below: silent


def _corner(coating, edge=1.0):
    """A trihedral corner of three right triangles (edge ``edge``), open toward +x+y+z."""
    return ml.Scene.from_parts([MeshPart(
        edge * np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]]),
        [[0, 1, 2], [0, 2, 3], [0, 3, 1]], 0, "corner")], [coating])


#: A near-mirror coating: a corner of it retroreflects at the third bounce, its second
#: bounce nearly nothing.
MIRROR = SandfordRobertson(0.0, 0.1, 0.0, 0.005)


def test_a_mirror_corner_is_found_at_its_third_bounce():
    """A user's trial: a mirror corner seen along its axis returns at the third bounce;
    the check looked at the second alone (160 % of a tiny single bounce) and advised
    bounces=2 (7 orders of magnitude short), and "auto" stopped at the first order below
    1 % (the second's share of the total, not the last order's). Now the check names the
    third and bounces=3, bounces=2 warns that the third returns more than every order
    summed, and "auto" sums the third: the same paths as bounces=3."""
    scene = _corner(MIRROR)
    lad = ml.Ladar(None, view_vectors=[np.ones(3) / np.sqrt(3)], bin_edges=np.linspace(
        -2.0, 4.0, 61))
    options = dict(model="mesh", radiometry="power", ray_spacing=2e-3, seed=0)
    with pytest.warns(ml.errors.BounceWarning, match=r"the second 1\d\d %, the third \S+ "
                                                     r"times.*bounces=[34] "):
        ml.simulate(scene, lad, **options)
    for n in (2, np.int64(2)):                   # (a review: numpy's integer went unchecked)
        with pytest.warns(ml.errors.BounceWarning, match=r"beyond the first 2 .*the third "
                                                         r".*bounces=3 "):
            two = ml.simulate(scene, lad, bounces=n, **options)
    three = ml.simulate(scene, lad, bounces=3, **options)
    auto = ml.simulate(scene, lad, bounces="auto", **options)
    first, second, third = three.info["order_totals"]
    assert third > 1e6 * max(first, second) and two.info["order_totals"][1] < first * 10
    assert auto.info["bounces"] >= 3
    assert auto.info["order_totals"][:3] == three.info["order_totals"]        # same paths


def test_the_check_warns_for_one_view_among_many():
    """A user's trial: the check summed its views, so one view into a corner among views
    of the same plates' backs (no second bounce) went unwarned (its 1.8 % spread over four
    views: 0.45 %). A dim dihedral (ρ 0.1) seen at 45° and from behind."""
    scene = dihedral(Lambertian(0.1))
    lad = ml.Ladar([45.0, 225.0, 230.0, 235.0], np.linspace(-1.5, 1.5, 61))
    with pytest.warns(ml.errors.BounceWarning, match=r"the worst of 4 views checked "
                                                     r"\(the second 1\.\d %"):
        ml.simulate(scene, lad, model="mesh", radiometry="power", ray_spacing=1e-2)
