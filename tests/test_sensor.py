"""The sensor stage: radiometry conventions (Eq. 8 and received power) in every forward model,
finite standoff, beams, pulses and receivers, and noise."""

from __future__ import annotations

import math

import numpy as np
import pytest
from _reference import quad_profile

import meshladar as ml
from meshladar.materials import ALUMINUM, DARK_GRAY, glint, lambertian

#: the analytic model against adaptive quadrature (as tests/test_analytic.py): 1e-9 relative
#: per bin, or 1e-12 of the profile's maximum for bins tiny next to it.
BIN_RTOL = 1e-9
BIN_ATOL_OF_MAX = 1e-12
#: closed forms evaluated in float64 against float64 sums of bins
CLOSED_RTOL = 1e-12


def _assert_bins_close(got, ref):
    tol = np.maximum(BIN_RTOL * np.abs(ref), BIN_ATOL_OF_MAX * np.abs(ref).max())
    bad = np.abs(got - ref) > tol
    assert not bad.any(), (f"{bad.sum()} bins off; worst rel "
                           f"{np.max(np.abs(got - ref)[bad] / np.abs(ref[bad]))}")


def _lambertian_disk_bins(edges, radius, albedo, power):
    """Closed form for a centred Lambertian disk: the point at angle a from the view has
    range −R cos a, incidence a and arc R da, so a bin holds
    2 (ρ/π) R ∫ cosⁿ a da over the a whose range lies in it (n = 1 paper, 2 power)."""
    a = np.arccos(np.clip(-np.asarray(edges) / radius, -1.0, 1.0))
    a = np.minimum(a, math.pi / 2)
    prim = a / 2 + np.sin(2 * a) / 4 if power else np.sin(a)
    return 2 * albedo / math.pi * radius * np.diff(prim)


# -- radiometry -----------------------------------------------------------------------------

@pytest.mark.parametrize("radiometry", ["paper", "power"])
def test_lambertian_disk_closed_form(radiometry):
    A, rho = 0.8, 0.6
    ladar = ml.Ladar.paper(angles_deg=[0.0, 77.0])
    sino = ml.simulate(ml.Scene([ml.Disk((0.0, 0.0), A, lambertian(rho))]), ladar,
                       radiometry=radiometry)
    exact = _lambertian_disk_bins(ladar.bin_edges, A, rho, radiometry == "power")
    np.testing.assert_allclose(sino.values, np.broadcast_to(exact, sino.shape),
                               rtol=CLOSED_RTOL, atol=CLOSED_RTOL * exact.max())
    assert sino.info["radiometry"] == radiometry
    # totals: ∫ cos a R da = 2R (paper), ∫ cos² a R da = πR/2 (power)
    total = 2 * A * rho / math.pi if radiometry == "paper" else rho * A / 2
    np.testing.assert_allclose(sino.total(), total, rtol=CLOSED_RTOL)


@pytest.mark.parametrize("name, scene", [
    ("disk_aluminum", lambda: ml.Scene([ml.Disk((0.0, 0.0), 0.8, ALUMINUM)])),
    ("disk_glint_e0.007", lambda: ml.Scene([ml.Disk((0.0, 0.0), 0.8, glint(0.007))])),
    ("ellipse_rotated", lambda: ml.Scene([ml.Ellipse((0.05, -0.1), (0.6, 0.3), 20.0,
                                                     ALUMINUM)])),
    ("pair_gray_al", lambda: ml.phantoms.scene("disk_pair", large=DARK_GRAY,
                                               small=ALUMINUM)),
])
def test_analytic_power_matches_quadrature(name, scene):
    """Received power is as exact as Eq. 8 in the analytic model: shadows, glints and
    ellipses against independent adaptive quadrature of F cos²θ."""
    scene = scene()
    views = [0.0, 37.0, 203.0] if name.startswith(("pair", "ellipse")) else [37.0]
    ladar = ml.Ladar.paper(angles_deg=views)
    sino = ml.simulate(scene, ladar, radiometry="power")
    for i, phi in enumerate(views):
        _assert_bins_close(sino.values[i], quad_profile(scene, math.radians(phi),
                                                        ladar.bin_edges, power=True))


#: a Lambertian sphere mesh of 82k faces, smooth normals, 40 rays per bin across: faceting
#: and sampling error of the profile (measured 9e-4 of the largest bin)
SPHERE_TOL = 3e-3


def test_lambertian_sphere_power_is_the_textbook_square_law():
    """A Lambertian sphere's received-power profile: the cap at depth r from the top holds
    2 (ρ/π) π R² ∫ cos²a sin a da, so a bin holds (2/3) ρ R² [c³] with c = 1 − r/R: the
    density ∝ (1 − r/R)², where Eq. 8 gives ∝ (1 − r/R)."""
    trimesh = pytest.importorskip("trimesh")
    R, rho = 1.0, 1.0
    scene = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=6, radius=R),
                               material=lambertian(rho))
    ladar = ml.Ladar(angles_deg=[0.0], bin_edges=np.linspace(-R, 0.0, 21))
    c = -ladar.bin_edges / R
    for radiometry, n in (("power", 3), ("paper", 2)):
        sino = ml.simulate(scene, ladar, model="mesh", radiometry=radiometry,
                           normals="smooth", rays_per_bin=40)
        exact = 2 * rho / n * R * R * (c[:-1] ** n - c[1:] ** n)
        err = np.abs(sino.values[0] - exact).max() / exact.max()
        assert err < SPHERE_TOL, (radiometry, err)


@pytest.mark.parametrize("normals", ["flat", "smooth"])
@pytest.mark.parametrize("backend", ["packets", "embreex"])
@pytest.mark.parametrize("coating", [ALUMINUM, ml.brdf.GGX(alpha=0.3)],
                         ids=["sr", "ggx"])
def test_mesh_power_fused_equals_trace_then_weigh(normals, backend, coating):
    """The compiled loops weigh received power exactly as weigh(hits, radiometry="power")
    does, and a trace re-weighs under either convention."""
    trimesh = pytest.importorskip("trimesh")
    if backend == "packets" and not ml.raytrace.embree4.available():
        pytest.skip("the packet backend does not load here")
    scene = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=4), material=coating)
    ladar = ml.Ladar.covering(scene, n_bins=64, angles_deg=[0.0, 40.0])
    hits = ml.trace(scene, ladar, normals=normals, backend=backend)
    for radiometry in ("paper", "power"):
        sino = ml.simulate(scene, ladar, model="mesh", radiometry=radiometry,
                           normals=normals, backend=backend)
        ref = ml.weigh(hits, radiometry=radiometry)
        np.testing.assert_allclose(sino.values, ref.values, rtol=1e-12,
                                   atol=1e-12 * ref.values.max())
        assert sino.info["radiometry"] == ref.info["radiometry"] == radiometry
    # monostatic power is Eq. 8 with one cos θ more, hit by hit: never larger
    paper, power = ml.weigh(hits).values, ml.weigh(hits, radiometry="power").values
    assert np.all(power <= paper * (1 + 1e-12)) and power.sum() < paper.sum()


def test_bistatic_power_at_the_ladar_is_monostatic_power():
    """A receiver collocated with the ladar, through the bistatic path (occlusion rays,
    bistatic BRDF), gives the monostatic numbers under both conventions."""
    trimesh = pytest.importorskip("trimesh")
    scene = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=3),
                               material=lambertian(0.5))
    ladar = ml.Ladar.covering(scene, n_bins=32, angles_deg=[10.0])
    for radiometry in ("paper", "power"):
        mono = ml.simulate(scene, ladar, model="mesh", radiometry=radiometry)
        bi = ml.simulate(scene, ladar, model="mesh", radiometry=radiometry,
                         receiver=ladar.view_vectors[0])
        np.testing.assert_allclose(bi.values, mono.values, rtol=1e-9,
                                   atol=1e-12 * mono.values.max())


def test_bistatic_power_has_the_receivers_cosine():
    """Bistatic received power is Eq. 8's bistatic weight times cos θr, hit by hit."""
    trimesh = pytest.importorskip("trimesh")
    scene = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=3),
                               material=lambertian(0.5))
    ladar = ml.Ladar.covering(scene, n_bins=32, angles_deg=[0.0])
    w_r = np.array([math.cos(0.6), math.sin(0.6), 0.0])
    hits = ml.trace(scene, ladar, receiver=w_r)
    cos_r = np.maximum(hits.bistatic[:, 0], 0.0)
    k = np.searchsorted(ladar.bin_edges, hits.range, side="right") - 1
    ok = (k >= 0) & (k < ladar.n_bins)
    expected = np.bincount(k[ok], weights=(0.5 / math.pi * hits.area * cos_r)[ok],
                           minlength=ladar.n_bins)
    got = ml.weigh(hits, radiometry="power").values[0]
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-15)


def test_pixel_power_total():
    """The pixel model under received power: a Lambertian disk returns ρ A / 2 in all
    (∫ (ρ/π) cos²a A da over the lit half), within the pixelation of its rim."""
    A, rho, pix = 0.8, 0.7, 0.005
    sino = ml.simulate(ml.Scene([ml.Disk((0, 0), A, lambertian(rho))]),
                       ml.Ladar.paper(angles_deg=[0.0, 17.0]), model="pixel",
                       pixel_size=pix, radiometry="power")
    np.testing.assert_allclose(sino.total(), rho * A / 2, rtol=4 * pix / A)
    assert sino.info["radiometry"] == "power"


@pytest.mark.parametrize("model", ["analytic", "pixel", "mesh"])
def test_radiometry_is_checked(model):
    scene = ml.Scene([ml.Disk((0.0, 0.0), 0.5, lambertian(0.5))])
    with pytest.raises(ml.errors.ParameterError, match=r"radiometry must be one of "
                       r"\('paper', 'power'\); got 'watts'"):
        ml.simulate(scene, ml.Ladar.paper(angles_deg=[0.0]), model=model, radiometry="watts")
