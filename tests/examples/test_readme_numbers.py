"""Numbers README.md and the guide's pages (``docs/guide/``, once the README's sections)
state about their examples' output that no other test asserted.

Sections covered: the top, the tour, the BRDF, scenes and the ladar, meshes, the sensor,
long runs, material tables, the command line and the layout. Where a claim is already
asserted elsewhere it is not repeated; the module that holds it is named here:

* SR energy check by quadrature down to e = 1e-4, the BRDF table's ranges:
  ``tests/brdf/test_brdf.py``; GGX F(0) = 1/(4πα²), Lambertian and Phong albedos:
  ``tests/brdf/test_brdf.py``; Matte = Lambertian(0.3) = SR b = 0 in every model (1e-12):
  ``tests/forward/test_user_model.py``.
* Analytic bins against adaptive quadrature (1e-9): ``tests/forward/test_analytic.py``;
  the phantoms' names and shapes: ``tests/phantoms/test_phantoms.py``.
* Meshes' normals errors (0.17 → 0.008, 0.32–0.46 / 0.83–1.05, 47×):
  ``tests/meshes/test_normals.py``; a 3 mm plate edge-on to 5e-4:
  ``tests/meshes/test_user_meshes.py``; sizes 1e-25…1e25 and 1e9 × size:
  ``tests/forward/test_extremes.py``; packets equal embreex (1e-12):
  ``tests/forward/test_trace.py``.
* The sensor: the Lambertian sphere's square law, finite standoff's first order, the link
  budget: ``tests/values/test_sensor_beams.py``; samples summing to bins (1e-12), noise
  moments: ``tests/records/test_waveforms.py``; Mitsuba within 1e-3:
  ``tests/studies/test_peer_mitsuba.py``.
* The bad-input matrix's 1251 cases: ``tests/matrix/test_matrix.py``; modules ≤ 450 lines,
  functions ≤ 80: ``tests/test_house.py``.

Timings (seconds, Mrays/s, speed-ups) are measurements of one machine and are not asserted
(tests do not depend on timing).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate

import meshladar as ml
from meshladar.errors import EnergyConservationWarning


def test_b099_diffuse_coating_reflects_1_99_at_normal_incidence():
    """'Fig. 5's b = 0.99 (warns: reflects up to 1/G(b) ≈ 1.99 at normal)': the albedo at
    normal incidence by quadrature of F cos θr over the hemisphere, not the code's G(b)."""
    with pytest.warns(EnergyConservationWarning, match=r"1\.987"):
        m = ml.SandfordRobertson(1.0, 0.0, 0.99, 1.0, lobes="diffuse")

    def integrand(theta_r):
        f = float(m.evaluate_angles(0.0, theta_r, 0.0))
        return 2 * math.pi * f * math.cos(theta_r) * math.sin(theta_r)

    albedo, err = integrate.quad(integrand, 0.0, math.pi / 2, epsabs=0, epsrel=1e-10,
                                 limit=200)
    assert round(albedo, 2) == 1.99
    assert albedo == pytest.approx(1.987, abs=5e-4)


def test_lambertian_table_entry_is_rho_over_pi_and_the_glint_reflects_everything():
    """'lambertian(rho_d=1.0)  # F = ρd/π' and 'glint(e=0.007)  # ρs = 1'."""
    theta = np.deg2rad([0.0, 10.0, 45.0, 80.0])
    np.testing.assert_allclose(ml.materials.lambertian(rho_d=1.0).monostatic(theta),
                               1 / math.pi, rtol=1e-14)
    np.testing.assert_allclose(ml.materials.glint(e=0.007).specular_reflectance(theta),
                               1.0, rtol=1e-9)


def test_the_paper_ladar_is_the_explicit_one():
    """'ladar = ml.Ladar.paper()  # the same: A/256 bins (A = 0.8), 360 views' and
    'Ladar.centered(n_bins=512, bin_width=0.003125, center=0.0)'."""
    explicit = ml.Ladar(angles_deg=np.arange(360.0), bin_edges=np.linspace(-0.8, 0.8, 513))
    centered = ml.Ladar.centered(n_bins=512, bin_width=0.003125, center=0.0)
    for lad in (ml.Ladar.paper(), centered):
        np.testing.assert_array_equal(lad.angles_deg, explicit.angles_deg)
        np.testing.assert_allclose(lad.bin_edges, explicit.bin_edges, rtol=0, atol=1e-15)
    assert explicit.n_bins == 512 and np.allclose(np.diff(explicit.bin_edges), 0.8 / 256)


def test_sinogram_values_are_bin_integrals_not_densities():
    """'sino.values  # (360, 512) bin integrals of F(θ) cos θ dl, per unit height': a
    Lambertian disk's view sums to (ρ/π)·2R, the closed form of ∫ cos θ R dθ over the lit
    half, whatever the bin width."""
    rho, radius = 0.6, 0.4
    scene = ml.Scene([ml.Disk(center=(0.1, 0.0), radius=radius,
                              material=ml.materials.lambertian(rho_d=rho))])
    for n_bins in (512, 64):
        lad = ml.Ladar.centered(n_bins=n_bins, bin_width=1.6 / n_bins, center=0.0)
        sino = ml.simulate(scene, lad)
        assert sino.values.shape == (360, n_bins)
        np.testing.assert_allclose(sino.values.sum(axis=1), rho / math.pi * 2 * radius,
                                   rtol=1e-9)


def test_the_tours_image_summary():
    """The tour's example line 'Image(size=256, extent=0.8, center=(0, 0), values=(-9710,
    2.876e+04), method='fbp', filter='ramp', input='log(floor=1e-06)', radiometry='paper',
    ...)': the first example's log-input FBP of the paper's pair (over the bins' reach,
    [−0.8, 0.8]², fbp's default frame)."""
    from meshladar.materials import ALUMINUM, DARK_GRAY

    scene = ml.phantoms.scene("disk_pair", large=DARK_GRAY, small=ALUMINUM)
    image = ml.fbp(ml.log_radiance(ml.simulate(scene, ml.Ladar.paper())), size=256)
    text = repr(image)
    assert len(text) <= 400
    for part in ("Image(size=256, extent=0.8, center=(0, 0), values=(-9710, 2.876e+04), "
                 "method='fbp', filter='ramp', input='log(floor=1e-06)', radiometry='paper'",):
        assert part in text, (part, text)


@pytest.fixture(scope="module")
def paper_512():
    from meshladar.studies import paper

    return paper.run(size=512)["metrics"]


#: The sensor section's 'received power as the data' numbers (512² images, `meshladar
#: paper`): metric -> (stated value, its Eq. 8 counterpart's stated value). These are
#: measurements of the study itself; the tolerance is the stated rounding.
POWER = {
    "disk_b0.darkening": (-0.04, 0.07),
    "ellipse_b0.ends_darkening": (-0.82, -0.12),
    "disk_b0.99.darkening": (-2.02, -1.36),
    "ellipse_b0.99.ends_darkening": (-5.29, -4.07),
}


@pytest.mark.slow
@pytest.mark.parametrize("key", sorted(POWER))
def test_received_power_findings_as_stated(paper_512, key):
    power, paper_value = POWER[key]
    assert paper_512[f"power.{key}"] == pytest.approx(power, abs=0.0051)
    assert paper_512[key] == pytest.approx(paper_value, abs=0.0051)


@pytest.mark.slow
def test_received_power_log_and_clip_bring_the_gray_disk_back(paper_512):
    """'Log and clip input still bring the gray disk back (visibility 0.91, 0.87)'."""
    assert paper_512["power.pair_gray_al_log.visibility"] == pytest.approx(0.91, abs=0.0051)
    assert paper_512["power.pair_gray_al_clip.visibility"] == pytest.approx(0.87, abs=0.0051)


@pytest.mark.slow
def test_fbp_agrees_with_iradon_at_1024():
    """The Speed paragraph: FBP of 360 × 1024 to 1024² 'agreeing to 1.2e-7 of the image
    maximum' with scikit-image's iradon (an independent implementation) on the same data
    (measured 1.22e-7; the bound allows summation-order differences elsewhere)."""
    from meshladar.studies.bench import bench_fbp

    assert bench_fbp(repeats=1)["max_diff_rel"] <= 1.5e-7


def test_default_ray_density():
    """'default 8 per bin in slice mode; 1 in 3-D, and at least 128 across the target': a
    unit-diameter sphere with bins 8× wider than 1/128 gets rays 1/128 apart; the paper's
    tessellated disk in slice mode gets rays an eighth of A/256 apart."""
    import trimesh

    sphere = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=3, radius=0.5),
                                material=ml.materials.DARK_GRAY)
    lad = ml.Ladar.covering(sphere, n_bins=16, angles_deg=[0.0, 90.0])
    sino = ml.simulate(sphere, lad, model="mesh")
    assert sino.info["mode"] == "3d"
    assert sino.info["ray_spacing"] == pytest.approx(1.0 / 128, rel=1e-12)
    disk = ml.phantoms.scene("disk").tessellate(256, height=1.0)
    sino = ml.simulate(disk, ml.Ladar.paper(angles_deg=[0.0, 90.0]), model="mesh")
    assert sino.info["mode"] == "slice"
    assert sino.info["ray_spacing"] == pytest.approx(0.8 / 256 / 8, rel=1e-12)
