"""The sensor stage: radiometry conventions (Eq. 8 and received power) in every forward model,
finite standoff and beams (the receiver, pulses and noise are in
tests/records/test_waveforms.py)."""

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
    ("disk_aluminum", lambda: ml.phantoms.scene("disk", ALUMINUM)),
    ("disk_glint_e0.007", lambda: ml.phantoms.scene("disk", glint(0.007))),
    ("ellipse_rotated", lambda: ml.Scene([ml.Ellipse((0.05, -0.1), (0.6, 0.3), 20.0,
                                                     ALUMINUM)])),
    ("pair_gray_al", lambda: ml.phantoms.scene("disk_pair", large=DARK_GRAY,
                                               small=ALUMINUM)),
])
@pytest.mark.slow
def test_analytic_power_matches_quadrature(name, scene):
    """Received power is as exact as Eq. 8 in the analytic model: shadows, glints and
    ellipses against independent adaptive quadrature of F cos²θ."""
    scene = scene()
    # one view each (the quadrature reference is slow): the pair's at 0° has the small
    # disk shadowing the large one
    views = [0.0] if name.startswith("pair") else [37.0]
    ladar = ml.Ladar.paper(angles_deg=views)
    sino = ml.simulate(scene, ladar, radiometry="power")
    for i, phi in enumerate(views):
        _assert_bins_close(sino.values[i], quad_profile(scene, math.radians(phi),
                                                        ladar.bin_edges, power=True))


#: a Lambertian sphere mesh of 82k faces, smooth normals, 40 rays per bin across: faceting
#: and sampling error of the profile (measured 9e-4 of the largest bin)
SPHERE_TOL = 3e-3


@pytest.mark.slow
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


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # coarse on purpose
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


@pytest.mark.slow
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
    A, rho, pix = 0.8, 0.7, 0.01
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


# -- the sensor: finite standoff, beams, link budget ---------------------------------------

def _facing_disk_plate(radius, albedo, segments=4096):
    """A flat disk (triangle fan) in the plane x = 0 facing +x (view angle 0)."""
    trimesh = pytest.importorskip("trimesh")
    ang = np.linspace(0.0, 2 * math.pi, segments, endpoint=False)
    verts = np.concatenate([[[0.0, 0.0, 0.0]], np.stack(
        [np.zeros(segments), radius * np.cos(ang), radius * np.sin(ang)], -1)])
    k = np.arange(segments)
    faces = np.stack([np.zeros(segments, int), 1 + k, 1 + (k + 1) % segments], -1)
    return ml.Scene.from_mesh(trimesh.Trimesh(verts, faces, process=False),
                              material=lambertian(albedo))


#: a disk plate at standoff 5 radii traced with 400 rays per radius: the sampling error of
#: an annulus bin (measured 1.4e-3 at worst, halving with the ray spacing)
PLATE_BIN_RTOL = 3e-3
#: and of the sum over bins (measured 4e-5)
PLATE_TOTAL_RTOL = 3e-4


@pytest.mark.slow
@pytest.mark.parametrize("radiometry", ["paper", "power"])
def test_standoff_plate_closed_form(radiometry):
    """A Lambertian disk plate facing a sensor at standoff D: the point at distance ρ from
    the aim has R = sqrt(D² + ρ²), cos θ = D/R, flood irradiance (D/R)² and, under power,
    the receiver's (D/R)²; with ρ dρ = R dR a bin holds (ρd/π) 2π Dⁿ ∫ R^(1−n) dR, n = 3
    (Eq. 8) or 6 (received power). Ranges are R − D."""
    a, D, rho = 1.0, 5.0, 0.5
    scene = _facing_disk_plate(a, rho)
    edges = np.linspace(0.0, math.hypot(D, a) - D, 21)
    ladar = ml.Ladar(angles_deg=[0.0], bin_edges=edges)
    sensor = ml.sensor.Sensor(standoff=D)
    sino = ml.simulate(scene, ladar, model="mesh", radiometry=radiometry, sensor=sensor,
                       ray_spacing=a / 400)
    n = 3 if radiometry == "paper" else 6
    R = D + edges
    exact = rho / math.pi * np.diff(2 * math.pi * D ** n * R ** (2 - n) / (2 - n))
    inner = edges[1:] <= math.hypot(D, a * math.cos(math.pi / 4096)) - D   # not the rim
    np.testing.assert_allclose(sino.values[0][inner], exact[inner], rtol=PLATE_BIN_RTOL)
    np.testing.assert_allclose(sino.total(), exact.sum(), rtol=PLATE_TOTAL_RTOL)
    assert sino.info["sensor"]["standoff_m"] == D and sino.info["radiometry"] == radiometry
    # the same hits, traced once, re-weighed under either convention: the same numbers
    hits = ml.trace(scene, ladar, sensor=sensor, ray_spacing=a / 400)
    np.testing.assert_allclose(ml.weigh(hits, radiometry=radiometry).values, sino.values,
                               rtol=1e-12, atol=1e-12 * sino.values.max())


def test_standoff_converges_to_the_orthographic_ladar_at_first_order():
    """As the standoff D grows, perspective profiles approach the parallel-ray ones with an
    error ∝ 1/D (the range curvature and the (D/R)² factors are first order in size/D):
    each doubling of D halves it (measured ratios 1.99-2.19)."""
    trimesh = pytest.importorskip("trimesh")
    scene = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=5),
                               material=lambertian(0.5))
    ladar = ml.Ladar(angles_deg=[0.0], bin_edges=np.linspace(-1.0, 0.2, 25))
    for radiometry in ("paper", "power"):
        ref = ml.simulate(scene, ladar, model="mesh", radiometry=radiometry,
                          normals="smooth", ray_spacing=2 / 600)
        errors = []
        for D in (10.0, 20.0, 40.0, 80.0):
            sino = ml.simulate(scene, ladar, model="mesh", radiometry=radiometry,
                               normals="smooth", ray_spacing=2 / 600,
                               sensor=ml.sensor.Sensor(standoff=D))
            errors.append(np.linalg.norm(sino.values - ref.values)
                          / np.linalg.norm(ref.values))
        ratios = np.array(errors[:-1]) / np.array(errors[1:])
        assert np.all((ratios > 1.7) & (ratios < 2.4)), (radiometry, errors)


def _square_plate(half, albedo, y0=0.0, z0=0.0):
    """A square plate in the plane x = 0 facing +x, centred on (0, y0, z0)."""
    trimesh = pytest.importorskip("trimesh")
    box = trimesh.Trimesh([[0, y0 - half, z0 - half], [0, y0 + half, z0 - half],
                           [0, y0 + half, z0 + half], [0, y0 - half, z0 + half]],
                          [[0, 1, 2], [0, 2, 3]], process=False)
    return ml.Scene.from_mesh(box, material=lambertian(albedo))


#: a stratified grid of 1e6 rays over a Gaussian spot: the estimate of its integral
#: (measured within 2e-4)
SPOT_RTOL = 1e-3


def test_gaussian_beam_at_infinity_integrates_the_spot():
    """A collimated Gaussian spot of waist w, offset (du, dv), on a square plate facing the
    ladar and off its axis: Eq. 8 gives (ρd/π) ∫∫ exp(−2ρ²/w²) dA over the plate, a
    product of erf differences. The plate's corner sits near the spot, so a flipped sign
    or swapped axes of the offset change the total."""
    from scipy.special import erf

    half, w0, rho = 0.5, 0.3, 0.5
    off = (0.2, -0.35)
    y0, z0 = 0.6, -0.7                 # the plate spans y in [0.1, 1.1], z in [-1.2, -0.2]
    scene = _square_plate(half, rho, y0, z0)
    ladar = ml.Ladar(angles_deg=[0.0], bin_edges=[-0.1, 0.1])
    beam = ml.sensor.GaussianBeam(waist=w0, offset=off)
    sino = ml.simulate(scene, ladar, model="mesh", sensor=ml.sensor.Sensor(beam=beam),
                       ray_spacing=2 * half / 1000)
    # the view's transverse axes at φ = 0: u = z × w = (0, 1, 0), v = w × u = (0, 0, 1)
    k = math.sqrt(2) / w0

    def line(centre, o):
        return w0 * math.sqrt(math.pi / 2) / 2 * (erf(k * (centre + half - o))
                                                 - erf(k * (centre - half - o)))

    exact = rho / math.pi * line(y0, off[0]) * line(z0, off[1])
    np.testing.assert_allclose(sino.total(), exact, rtol=SPOT_RTOL)
    for wrong in ((-off[0], off[1]), (off[1], off[0])):
        assert abs(rho / math.pi * line(y0, wrong[0]) * line(z0, wrong[1]) - exact) \
            > 10 * SPOT_RTOL * exact


def test_gaussian_beam_at_standoff_matches_radial_quadrature():
    """A diverging Gaussian beam on a plate facing a sensor at standoff D: every point of
    the plate lies at z = D along the axis, so the irradiance is exp(−2ρ²/w(D)²), and
    Eq. 8's total is (ρd/π) ∫ (D/R) exp(−2ρ²/w(D)²) 2πρ dρ."""
    from scipy import integrate

    a, D, rho = 1.0, 4.0, 0.5
    beam = ml.sensor.GaussianBeam(waist=0.05, divergence=0.06)
    scene = _facing_disk_plate(a, rho)
    ladar = ml.Ladar(angles_deg=[0.0], bin_edges=[0.0, math.hypot(D, a) - D + 1e-9])
    sino = ml.simulate(scene, ladar, model="mesh", sensor=ml.sensor.Sensor(
        standoff=D, beam=beam), ray_spacing=a / 500)
    W = float(beam.radius(D))
    exact, _ = integrate.quad(lambda r: D / math.hypot(D, r) * math.exp(-2 * r * r / W / W)
                              * 2 * math.pi * r, 0.0, a * math.cos(math.pi / 4096),
                              epsabs=0.0, epsrel=1e-12)
    np.testing.assert_allclose(sino.total(), rho / math.pi * exact, rtol=SPOT_RTOL)


def test_photoelectrons_of_a_small_spot_on_a_lambertian_plate():
    """The link budget in closed form: a spot much smaller than the plate and the standoff
    puts the whole pulse energy E on the plate; a Lambertian plate of albedo ρ facing the
    sensor sends E ρ/π per steradian back, of which the aperture A_r at distance D collects
    E ρ A_r / (π D²): times the optics, the two-way atmosphere exp(−2σD) and the quantum
    efficiency, over hc/λ, photoelectrons."""
    a, D, rho = 0.2, 200.0, 0.4
    E, diam, opt, qe, lam, sigma = 1e-6, 0.05, 0.7, 0.3, 1.55e-6, 1e-4
    sensor = ml.sensor.Sensor(standoff=D, beam=ml.sensor.GaussianBeam(waist=0.01,
                                                                     divergence=1e-4),
                              pulse_energy=E, aperture_diameter=diam,
                              optics_transmission=opt, quantum_efficiency=qe,
                              wavelength=lam, extinction=sigma)
    scene = _facing_disk_plate(a, rho, segments=256)
    ladar = ml.Ladar(angles_deg=[0.0], bin_edges=[-0.01, 0.01])
    sino = ml.simulate(scene, ladar, model="mesh", radiometry="power", sensor=sensor,
                       ray_spacing=0.001)
    photon = ml.sensor.PLANCK * ml.sensor.SPEED_OF_LIGHT / lam
    exact = E * rho * (math.pi * diam ** 2 / 4) / (math.pi * D ** 2) * opt * qe \
        * math.exp(-2 * sigma * D) / photon
    # the spot (w(D) = 0.022) is sampled by ~1500 rays; its edge far inside the plate (the
    # plate's radius 0.2 is 9 spot radii: exp(-2·81) of the energy misses it)
    np.testing.assert_allclose(sino.total(), exact, rtol=SPOT_RTOL)
    assert sino.info["units"] == "photoelectrons"
    with pytest.raises(ml.errors.ParameterError, match="radiometry='power'"):
        ml.simulate(scene, ladar, model="mesh", sensor=sensor, ray_spacing=0.001)
    hazy = ml.sensor.Sensor(standoff=D, extinction=sigma)
    with pytest.raises(ml.errors.ParameterError, match="extinction .* radiometry='power'"):
        ml.simulate(scene, ladar, model="mesh", sensor=hazy, ray_spacing=0.001)


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # coarse on purpose
@pytest.mark.parametrize("sensor", [
    ml.sensor.Sensor(standoff=5.0),
    ml.sensor.Sensor(standoff=8.0, aim=(0.1, 0.2, 0.0), extinction=0.01,
                     beam=ml.sensor.GaussianBeam(0.05, divergence=0.1, offset=(0.2, -0.1))),
    ml.sensor.Sensor(standoff=6.0, beam=ml.sensor.FloodBeam(0.6)),
], ids=["flood", "gaussian_aim_extinction", "top_hat"])
@pytest.mark.parametrize("normals", ["flat", "smooth"])
@pytest.mark.parametrize("back_faces", ["two-sided", "ignore"])
def test_sensor_compiled_loop_equals_trace_then_weigh(sensor, normals, back_faces):
    """The compiled loop for a sensor at a standoff weighs exactly as the per-hit path:
    trace(sensor=...) then weigh, under both conventions (to rounding)."""
    trimesh = pytest.importorskip("trimesh")
    scene = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=4),
                               material=ALUMINUM)
    ladar = ml.Ladar.covering(scene, n_bins=64, angles_deg=[0.0, 40.0])
    hits = ml.trace(scene, ladar, sensor=sensor, normals=normals, back_faces=back_faces)
    # extinction attenuates received power only (with Eq. 8 it is an error)
    for radiometry in ("power",) if sensor.extinction else ("paper", "power"):
        sino = ml.simulate(scene, ladar, model="mesh", radiometry=radiometry, sensor=sensor,
                           normals=normals, back_faces=back_faces)
        ref = ml.weigh(hits, radiometry=radiometry)
        np.testing.assert_allclose(sino.values, ref.values, rtol=1e-12,
                                   atol=1e-12 * ref.values.max())
        assert ref.values.max() > 0


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # faceted on purpose
def test_standoff_runs_are_reproducible_and_streamed():
    """Seeded stratified perspective rays: the same numbers on threads and in one call."""
    trimesh = pytest.importorskip("trimesh")
    scene = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=3),
                               material=ALUMINUM)
    ladar = ml.Ladar.covering(scene, n_bins=40, angles_deg=np.arange(0.0, 360.0, 30.0))
    sensor = ml.sensor.Sensor(standoff=6.0)
    one = ml.simulate(scene, ladar, model="mesh", sensor=sensor, seed=3, jobs=1)
    two = ml.simulate(scene, ladar, model="mesh", sensor=sensor, seed=3, jobs=2)
    np.testing.assert_array_equal(one.values, two.values)
    assert np.all(one.values >= 0) and np.all(np.isfinite(one.values))


@pytest.mark.parametrize("kwargs, match", [
    ({"standoff": -1.0}, "standoff"),
    ({"standoff": float("nan")}, "standoff"),
    ({"extinction": 1e-3}, "extinction .* needs a finite standoff"),
    ({"beam": ml.sensor.GaussianBeam(0.1, divergence=0.01)}, "divergence .* needs a finite"),
    ({"beam": "gauss"}, "beam must be"),
    ({"aim": (0.0, 1.0)}, "aim"),
    ({"optics_transmission": 0.0}, "optics_transmission"),
    ({"quantum_efficiency": 1.5}, "quantum_efficiency"),
])
def test_sensor_checks_its_parameters(kwargs, match):
    with pytest.raises(ml.errors.ParameterError, match=match):
        ml.sensor.Sensor(**kwargs)


def test_sensor_refuses_what_it_cannot_model():
    trimesh = pytest.importorskip("trimesh")
    scene = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=2),
                               material=lambertian(0.5))
    ladar = ml.Ladar.covering(scene, n_bins=16, angles_deg=[0.0])
    near = ml.sensor.Sensor(standoff=0.5)
    with pytest.raises(ml.errors.ParameterError, match="inside the target"):
        ml.simulate(scene, ladar, model="mesh", sensor=near)
    far = ml.sensor.Sensor(standoff=10.0)
    with pytest.raises(ml.errors.ParameterError, match="mode='3d'"):
        ml.simulate(scene, ladar, model="mesh", sensor=far, mode="slice")
    with pytest.raises(ml.errors.ParameterError, match="monostatic"):
        ml.simulate(scene, ladar, model="mesh", sensor=far, receiver=(0.0, 1.0, 0.0))
    with pytest.raises(ml.errors.ParameterError, match="footprint"):
        ml.simulate(scene, ladar, model="mesh", sensor=far, footprint=True)
    with pytest.raises(ml.errors.ParameterError, match="sensor"):
        ml.simulate(ml.Scene([ml.Disk((0, 0), 0.5, lambertian(0.5))]), ladar, sensor=far)
