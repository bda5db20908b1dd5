"""A scan's echoes against closed forms: the link budget, range precision against the
Cramér–Rao bound, two surfaces in one footprint, a hole's energy split, and points on the
mesh. Every expectation is computed here, by hand, from the physics, not by the scan code."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from meshladar.noise import Noise
from meshladar.scan import Platform, ScanBeam, ScanPattern, raster, rotating, scan

from _scan_scenes import SPEED_OF_LIGHT, annulus, photoelectrons_by_hand, plate, scene, sensor

R0 = 100.0


def _repeat(direction, n):
    return ScanPattern(np.arange(n) * 1e-4, np.tile(direction, (n, 1)))


def test_a_plates_echo_carries_the_link_budget_at_normal_and_oblique_incidence():
    """One ray per pulse at 0° and 30° from the plate's normal: the echo's photoelectrons
    are E (ρ/π) cos θ (π D²/4)/R² / (hc/λ) at R = R0 / cos θ."""
    tol = 1e-3          # the Gaussian fit's area on 2 GS/s samples of a 5 ns pulse
    pat = raster([0.0, 30.0], [0.0], pulse_rate=1e4)
    pc = scan(scene(plate(R0)), pat, Platform.static((0, 0, 0)), sensor())
    for angle, rec in zip((0.0, 30.0), pc.points):
        c = math.cos(math.radians(angle))
        expect = photoelectrons_by_hand(1e-6, 0.05, R0 / c, c)
        assert rec["intensity"] == pytest.approx(expect, rel=tol)
        assert rec["true_range"] == pytest.approx(R0 / c, rel=1e-12)
    assert pc.info["conventions"]["radiometry"] == "power"


#: The mean intensity's tolerance over 400 pulses of 200 photoelectrons in a background
#: (its shot noise over the echo's ~10 samples: sd ≈ 0.1 of S a pulse, 0.005 the mean).
BACKGROUND_MEAN_TOL = 0.02


@pytest.mark.parametrize("b", [0.5, 5.0])
def test_an_echos_intensity_and_amplitude_are_above_the_background(b):
    """A user's trial: the echo was sized on its samples with the background in them, so
    its photoelectrons read 1.057 and 1.617 of the link budget over backgrounds of 0.5
    and 5 a sample (its timing took the background off, its size did not). Now the mean
    intensity over 400 pulses is the link budget S = 200 (by hand) and the amplitude the
    echo's peak per sample, S dt / (σ √(2π)), each within BACKGROUND_MEAN_TOL."""
    dt = 0.5e-9
    energy = 200.0 / photoelectrons_by_hand(1.0, 0.05, R0)
    sen = sensor(pulse_energy=energy, noise=Noise(background_rate=b / dt))
    pat = ScanPattern(np.arange(400) * 1e-4, np.tile((1.0, 0.0, 0.0), (400, 1)))
    p = scan(scene(plate(R0)), pat, Platform.static((0, 0, 0)), sen, seed=4).points
    p = p[np.abs(p["range"] - R0) < 0.5]                            # the echo's returns
    assert len(p) == 400
    assert np.mean(p["intensity"]) / 200.0 == pytest.approx(1.0, abs=BACKGROUND_MEAN_TOL)
    peak = 200.0 * dt / (sen.sigma * math.sqrt(2 * math.pi))
    assert np.mean(p["amplitude"]) / peak == pytest.approx(1.0, abs=BACKGROUND_MEAN_TOL)


def test_range_precision_meets_the_cramer_rao_bound_of_a_gaussian_pulse_in_shot_noise():
    """2000 pulses on a Lambertian plate, shot noise only, ~N photoelectrons each: the
    range's standard deviation is (c/2) σ_eff / √N (σ_eff² = σ² + Δt²/12: the pulse and the
    sample's box) within 15 %, and its bias below 2 % of a sample's range (c Δt / 2)."""
    n = 2000
    sen = sensor(noise=Noise(), pulse_energy=6e-9)
    pc = scan(scene(plate(R0)), _repeat((1.0, 0.0, 0.0), n), Platform.static((0, 0, 0)), sen)
    first = pc.points[pc.points["return_number"] == 1]
    assert len(first) >= 0.99 * n
    photons = photoelectrons_by_hand(6e-9, 0.05, R0)
    sigma_eff = math.sqrt(sen.sigma ** 2 + sen.dt ** 2 / 12)
    crb = 0.5 * SPEED_OF_LIGHT * sigma_eff / math.sqrt(photons)
    err = first["range"] - first["true_range"]
    assert np.std(err) == pytest.approx(crb, rel=0.15)
    assert abs(np.mean(err)) < 0.02 * 0.5 * SPEED_OF_LIGHT * sen.dt


def _split_plates(delta):
    """Two plates meeting at y = 0, the one at y > 0 ``delta`` farther: both in one beam."""
    near = trimesh.creation.box((0.01, 5.0, 10.0))
    near.apply_translation((R0 + 0.005, -2.5, 0.0))
    far = trimesh.creation.box((0.01, 5.0, 10.0))
    far.apply_translation((R0 + delta + 0.005, 2.5, 0.0))
    return scene(near, far)


#: The range resolution c τ / 2 of the default 5 ns pulse (m).
RESOLUTION = 0.5 * SPEED_OF_LIGHT * 5e-9


#: Each plate's share of the photoelectrons (less 1/R²) against the half the beam puts on
#: it (the sub-rays split evenly; two echoes 2 c τ / 2 apart shared 0.5011 / 0.4989).
SHARE_TOL = 5e-4


@pytest.mark.parametrize("ratio, returns", [(0.6, 1), (0.9, 1), (1.6, 2), (2.0, 2), (2.2, 2),
                                            (2.4, 2), (2.6, 2), (3.0, 2)])
def test_two_surfaces_in_one_footprint_resolve_beyond_the_pulses_resolution(ratio, returns):
    """Half the beam on each of two plates Δ apart: two returns at both ranges (within 1 %
    of c τ / 2), each with half the light, when Δ is 1.6 c τ / 2 or more, one return at
    0.9 c τ / 2 and below (the threshold measured: echoes merge below ~1.2 c τ / 2, the
    matched filter's σ√2 each). From 2.0 to 2.3 c τ / 2 (4.7 to 5.4 σ) each centroid took
    in the other's tail: 6 % of c τ / 2 off, before such peaks were refitted together."""
    delta = ratio * RESOLUTION
    sen = sensor(beam=ScanBeam(2e-3, profile="tophat", tol=0.02))
    pc = scan(_split_plates(delta), _repeat((1.0, 0.0, 0.0), 1), Platform.static((0, 0, 0)),
              sen)
    assert len(pc) == returns
    if returns == 2:
        pts = np.sort(pc.points, order="range")
        np.testing.assert_allclose(pts["range"], [R0, R0 + delta], atol=0.01 * RESOLUTION)
        share = pts["intensity"] * np.array([R0, R0 + delta]) ** 2
        np.testing.assert_allclose(share / share.sum(), 0.5, atol=SHARE_TOL)


def test_a_hole_smaller_than_the_footprint_splits_the_energy_as_the_beam_profile_predicts():
    """HELIOS++ #767's case: a plate with a hole of radius a at R0 and a wall 10 m behind,
    a Gaussian beam of 1/e² radius w = θ_d R0 centred on the hole: the fraction
    f = 1 − exp(−2a²/w²) passes and comes back from the wall; each echo's photoelectrons
    are the link budget of its share (to the quadrature's edge tolerance)."""
    theta_d, a, wall = 1e-3, 0.08, R0 + 10.0
    f = 1.0 - math.exp(-2.0 * a ** 2 / (theta_d * R0) ** 2)
    sc = scene(annulus(R0, a, 2.0), plate(wall))
    sen = sensor(beam=ScanBeam(theta_d, tol=0.01))
    pc = scan(sc, _repeat((1.0, 0.0, 0.0), 1), Platform.static((0, 0, 0)), sen)
    assert len(pc) == 2
    plate_echo, wall_echo = np.sort(pc.points, order="range")
    share_tol = 0.01      # the beam's tol: the quadrature's share of an edge
    unit = photoelectrons_by_hand(1e-6, 0.05, 1.0)
    assert plate_echo["intensity"] * R0 ** 2 / unit == pytest.approx(1 - f, abs=share_tol)
    assert wall_echo["intensity"] * wall ** 2 / unit == pytest.approx(f, abs=share_tol)
    assert wall_echo["true_part"] == 1 and plate_echo["true_part"] == 0


def test_a_sampled_box_pulse_ranges_true_and_carries_the_link_budget():
    """A 4 ns box pulse starting at emission (its mean 2 ns late) and a Gaussian response:
    the record sums to the link budget (to 1e-9) and the plate ranges true within 1 mm
    (the shape's delay taken off)."""
    from meshladar.waveforms import GaussianPulse, SampledPulse

    sen = sensor(pulse=SampledPulse(np.ones(4), interval=1e-9), response=GaussianPulse(1e-9))
    pc = scan(scene(plate(R0)), _repeat((1.0, 0.0, 0.0), 1), Platform.static((0, 0, 0)),
              sen, keep_waveforms=True)
    wave, _ = pc.waveform(0)
    assert wave.sum() == pytest.approx(photoelectrons_by_hand(1e-6, 0.05, R0), rel=1e-9)
    assert len(pc) == 1 and pc.points["range"][0] == pytest.approx(R0, abs=1e-3)


def test_a_finely_sampled_gaussian_pulse_matches_the_exact_gaussian():
    """The 5 ns Gaussian as 200 samples of 0.1 ns: its record equals the erf integrals of
    the Gaussian pulse's to 1e-3 of the peak."""
    from meshladar.waveforms import SampledPulse

    t = (np.arange(200) + 0.5) * 0.1e-9 - 10e-9
    sig = 5e-9 / 2.3548200450309493
    shape = SampledPulse(np.exp(-0.5 * (t / sig) ** 2), interval=0.1e-9, start=-10e-9)
    exact = scan(scene(plate(R0)), _repeat((1.0, 0.0, 0.0), 1), Platform.static((0, 0, 0)),
                 sensor(samples=128), keep_waveforms=True).waveform(0)
    tabled = scan(scene(plate(R0)), _repeat((1.0, 0.0, 0.0), 1), Platform.static((0, 0, 0)),
                  sensor(pulse=shape, samples=128), keep_waveforms=True).waveform(0)
    offset = round((tabled[1] - exact[1]) / 0.5e-9)        # the records' starts may differ
    a, b = exact[0], np.roll(tabled[0], offset)
    assert np.abs(a - b).max() <= 1e-3 * a.max()


def test_overlapping_echoes_are_decomposed_into_their_gaussians():
    """Two point-sampled Gaussians 3.8 σ apart, heights 100 and 80 (written here, not by
    the scan): the decomposition finds both centres within 0.01 sample and both heights
    within 0.5 %; without it, the weaker one's centroid is pulled toward the stronger."""
    from meshladar.scan.echoes import find_returns

    s, x = 4.0, np.arange(200) + 0.5
    truth = [(100.0, 80.3), (80.0, 80.3 + 3.8 * 4.0)]
    wave = sum(h * np.exp(-0.5 * ((x - c) / s) ** 2) for h, c in truth)[None, :]
    fit = find_returns(wave, np.zeros(1), 1.0, s, 1.0, 5, True)
    np.testing.assert_allclose(fit.time - 0.0, [c for _, c in truth], atol=0.01)
    np.testing.assert_allclose(fit.amplitude, [h for h, _ in truth], rtol=0.005)
    plain = find_returns(wave, np.zeros(1), 1.0, s, 1.0, 5, False)
    assert plain.time[1] < truth[1][1] - 0.1


def test_the_compiled_erf_agrees_with_libm_to_an_ulp():
    """The records' erf (a table and a Taylor series) against the C library's, at its
    nodes, between them, near 0 and beyond its clamp at ±6."""
    from meshladar.scan._kernels import erf

    ulp = 2.0 ** -52                    # one ulp of 1: libm's own accuracy there
    rng = np.random.default_rng(3)
    nodes = np.arange(-384, 385) / 64.0
    xs = np.concatenate([nodes, nodes + 1 / 128, nodes - 1 / 128 + 1e-15,
                         rng.uniform(-9.0, 9.0, 20_000), [0.0, 1e-300, -1e-300, 5.93, -40.0]])
    for x in xs:
        want = math.erf(x)
        assert abs(erf(x) - want) <= max(ulp, 2.0 * abs(want) * ulp / 2), x


@pytest.mark.parametrize("sigma_samples, tabulated",
                         [(4.2, True), (0.3, True), (1.0, True), (40.0, True), (1000.0, False)])
def test_a_records_samples_are_the_gaussian_echos_integrals_over_them(sigma_samples,
                                                                      tabulated):
    """Sub-rays apart by more than the merge: each sample holds Σ e/2 (erf((t_{j+1} − τ)/
    (σ√2)) − erf((t_j − τ)/(σ√2))) over its edges t_j = t₀ + j Δt, with scipy's erf; for
    echoes of σ from 0.3 to 40 samples (the table's interpolation) and of 1000 (no table
    is made: the erf differences). (At σ = 0.01 sample the times' own rounding, 1e-22 s at
    600 ns, alone makes 1.2e-12 of the reference and the record alike.)"""
    from scipy.special import erf as scipy_erf

    from meshladar.scan._sampling import sample_table
    from meshladar.scan.echoes import waveforms

    tol = 1e-13                         # of the pulse's photoelectrons, per sample
    dt = 0.5e-9
    sigma = sigma_samples * dt
    assert (sample_table(sigma_samples) is not None) == tabulated
    rng = np.random.default_rng(4)
    tau = 600e-9 + np.cumsum(rng.uniform(0.5, 3.0, (40, 3)) * max(sigma, dt), axis=1)
    tau += rng.uniform(0.0, dt, (40, 1))                     # every phase within a sample
    pe = rng.uniform(1.0, 1e4, (40, 3))
    tau[5, 2], pe[5, 2] = np.inf, 0.0                        # a sub-ray that missed
    waves, start = waveforms(tau, pe, sigma, dt)
    edges = start[:, None] + dt * np.arange(waves.shape[1] + 1)
    x = (edges[:, None, :] - np.where(pe > 0, tau, 0.0)[:, :, None]) / (sigma * math.sqrt(2))
    expect = (0.5 * pe[:, :, None] * np.diff(scipy_erf(x), axis=2)).sum(axis=1)
    assert np.abs(waves - expect).max() <= tol * pe.sum(axis=1).max()


def test_an_echos_filtered_samples_from_the_table_are_scipys_gaussian_filter_of_its_record():
    """A record's one echo, filtered through the filtered table, against scipy's
    gaussian_filter1d (σ the echo's, truncate 4, zeros beyond the record) of the record
    computed with scipy's erf, to the table's error, at every phase; records of one echo
    (merged sub-rays too) are marked, those of two or of an echo the record cuts are not;
    and the returns found with the marked echoes are those found by filtering."""
    from scipy.ndimage import gaussian_filter1d
    from scipy.special import erf as scipy_erf

    from meshladar.scan._sampling import filtered_span, sample_table
    from meshladar.scan.echoes import find_returns, waveforms_with_echoes

    tol = 1e-13                         # of the echo's photoelectrons, per sample
    dt, sigma = 0.5e-9, 2.1e-9
    s = sigma / dt
    tables = sample_table(s)
    ns = 120
    centres = np.linspace(40.0, 41.0, 33)
    x = (np.arange(ns + 1)[None, :] - centres[:, None]) / (s * math.sqrt(2))
    record = 0.5 * np.diff(scipy_erf(x), axis=1)          # one photoelectron at 40 … 41
    want = gaussian_filter1d(record, s, axis=1, mode="constant", truncate=4.0)
    for c, row in zip(centres, want):
        filt = np.empty(ns + 2)
        filtered_span(1.0, c, tables, 0, ns - 1, filt)
        assert np.abs(filt[1:-1] - row).max() <= tol
    rng = np.random.default_rng(5)
    tau = 600e-9 + np.cumsum(rng.uniform(0.5, 6.0, (60, 3)) * sigma, axis=1)
    tau[:20, 1:] = tau[:20, :1] + rng.uniform(0, 1e-12, (20, 2))   # merged: one echo
    tau[20:30, 1:], pe = np.inf, rng.uniform(1.0, 1e4, (60, 3))   # one sub-ray lit
    pe[20:30, 1:] = 0.0
    waves, start, echoes = waveforms_with_echoes(tau, pe, sigma, dt)
    np.testing.assert_array_equal(echoes[:30, 0] > 0, True)
    np.testing.assert_array_equal(echoes[30:, 0], 0.0)                # several echoes
    np.testing.assert_allclose(echoes[:30, 0], pe[:30].sum(axis=1), rtol=1e-15)
    cut = waveforms_with_echoes(tau, pe, sigma, dt, samples=20)[2]
    np.testing.assert_array_equal(cut[:, 0], 0.0)                     # cut by the record
    got = find_returns(waves, start, dt, sigma, 1.0, 5, True, echoes=echoes)
    ref = find_returns(waves, start, dt, sigma, 1.0, 5, True)
    assert len(got) == len(ref) > 60
    np.testing.assert_array_equal(got.pulse, ref.pulse)
    np.testing.assert_allclose(got.time, ref.time, rtol=0, atol=1e-9 * dt)
    np.testing.assert_allclose(got.intensity, ref.intensity, rtol=1e-9)


def test_returns_are_ordered_by_time_within_each_pulse_and_numbered():
    """A chunk's returns, each pulse's in any order, come out as numpy's lexsort orders
    them (stable: equal times keep their order), numbered from 1 with their pulse's
    count; pulses out of order are refused."""
    from meshladar.scan.echoes import Returns

    rng = np.random.default_rng(8)
    pulse = np.sort(rng.integers(0, 300, 1000))
    time = rng.choice([1.0, 2.0, 3.0, 4.0], 1000)             # ties on purpose
    value = np.arange(1000.0)
    ret = Returns(pulse, time, value, value, value)
    order = np.lexsort((time, pulse))
    np.testing.assert_array_equal(ret.amplitude, value[order])
    counts = np.bincount(pulse)
    np.testing.assert_array_equal(ret.number_of_returns, counts[pulse[order]])
    first = np.searchsorted(pulse[order], pulse[order])
    np.testing.assert_array_equal(ret.return_number, np.arange(1000) - first + 1)
    with pytest.raises(ValueError, match="ascending"):
        Returns(pulse[::-1], time, value, value, value)


def test_the_compiled_sort_is_numpys_stable_argsort():
    """The scan loops' small sort (insertion up to 64 values, a merge sort beyond) against
    numpy's stable argsort, ties and infinities (missed sub-rays) included."""
    from meshladar.scan._kernels import sort_small

    rng = np.random.default_rng(9)
    for m in (0, 1, 2, 5, 64, 65, 100, 257, 1000):
        for _ in range(10):
            values = rng.integers(0, 5, m).astype(float)
            values[rng.random(m) < 0.1] = np.inf
            order = np.empty(m, np.int64)
            sort_small(values, order)
            np.testing.assert_array_equal(order, np.argsort(values, kind="stable"))


#: A record from a user's trial (a rotating scanner over an airliner's wing at grazing
#: incidence, photoelectrons per 0.5 ns sample): three humps of one spread echo, which the
#: decomposition (echo σ = 4.25 samples) fitted with two wide Gaussians and a third of
#: height 0, reported as a return of amplitude 0 and intensity 0.
WING = np.array([
    2.51, 2.7, 2.87, 3.01, 3.13, 3.24, 3.36, 3.49, 3.65, 3.84, 4.03, 4.22, 4.38, 4.5, 4.57,
    4.58, 4.54, 4.46, 4.35, 4.23, 4.1, 3.97, 3.82, 3.65, 3.47, 3.28, 3.11, 2.99, 2.95, 3.0,
    3.12, 3.3, 3.49, 3.65, 3.74, 3.73, 3.62, 3.42, 3.14, 2.84, 2.54, 2.27, 2.07, 1.93, 1.84,
    1.79, 1.76, 1.73, 1.69, 1.64, 1.58, 1.52, 1.47, 1.42, 1.4, 1.38, 1.39, 1.41, 1.44, 1.49,
    1.55, 1.61, 1.67, 1.7, 1.7, 1.66, 1.56, 1.42, 1.23, 1.02, 0.81, 0.61, 0.44])


def test_a_peak_the_decomposition_takes_to_nothing_is_not_a_return():
    """The wing's record (its ends tapered to 0 by Gaussian tails): every return has a
    positive amplitude and intensity, is numbered 1..n in time, and lies in the record."""
    from meshladar.scan.echoes import find_returns

    taper = np.arange(1, 31)
    record = np.concatenate([WING[0] * np.exp(-0.5 * (taper[::-1] / 8.0) ** 2), WING,
                             WING[-1] * np.exp(-0.5 * (taper / 4.0) ** 2)])
    dt = 0.5e-9
    found = find_returns(record[None, :], np.zeros(1), dt, 4.2466 * dt, 0.5, 5, True)
    assert len(found) >= 1
    assert np.all(found.amplitude > 0) and np.all(found.intensity > 0)
    np.testing.assert_array_equal(found.return_number, np.arange(1, len(found) + 1))
    assert np.all(found.number_of_returns == len(found))
    assert np.all((found.time > 0) & (found.time < len(record) * dt))


#: From 2 samples across the echo's FWHM (measured on this plate: 0.14 % and 0.17 %).
TWO_SAMPLE_RANGE_TOL = 2e-3            # of c τ / 2
TWO_SAMPLE_PE_RTOL = 3e-3


def test_an_echo_of_two_samples_ranges_and_counts_true_and_one_of_fewer_is_refused():
    """A 1 ns pulse digitised at 2 GS/s (its FWHM two samples), the plate at 13 sub-sample
    offsets: range within 0.2 % of c τ / 2 and photoelectrons within 0.3 % of the link
    budget by hand. 1.5 samples warns, 0.5 refuses naming the rate that would serve (a
    user's 0.5 ns at 1 GS/s read 0.83 of the budget, 5 ns at 1 MS/s every range on a
    150 m grid), and so is a Geiger-mode array's histogram (its returns read by the same
    detector: half a bin per FWHM read 1.48 of the photoelectrons); discrete returns have
    no such detector."""
    from meshladar.errors import MeshladarWarning, ParameterError
    from meshladar.scan import GeigerMode
    from meshladar.waveforms import GaussianPulse

    resolution = 0.5 * SPEED_OF_LIGHT * 1e-9
    sen = sensor(sample_rate=2e9, pulse=GaussianPulse(1e-9))
    for shift in np.linspace(0.0, 0.15, 13):
        pc = scan(scene(plate(R0)), _repeat((1.0, 0.0, 0.0), 1), Platform.static((shift, 0, 0)),
                  sen)
        assert len(pc) == 1
        assert abs(pc.points["range"][0] - (R0 - shift)) < TWO_SAMPLE_RANGE_TOL * resolution
        assert pc.points["intensity"][0] == pytest.approx(
            photoelectrons_by_hand(1e-6, 0.05, R0 - shift), rel=TWO_SAMPLE_PE_RTOL)
    with pytest.warns(MeshladarWarning, match=r"^the echo \(the pulse and the response: "
                                              r"2\.355 sigma = 1\.5e-09 s, a Gaussian's "
                                              r"FWHM\) spans 1\.5 samples at sample_rate="
                                              r"1e\+09: .* sample_rate >= 1\.34e\+09 "):
        sensor(sample_rate=1e9, pulse=GaussianPulse(1.5e-9))
    # the rate advised does not warn, nor does one two samples to rounding (filterwarnings
    # is error): 4/3 GS/s rounded up, and a 0.7 ns pulse at 2 / (0.7 ns) samples a second
    sensor(sample_rate=1.34e9, pulse=GaussianPulse(1.5e-9))
    sensor(sample_rate=2.0 / 7e-10, pulse=GaussianPulse(7e-10))
    for geiger in (None, GeigerMode(shots=4)):    # a Geiger array's histogram bins too
        with pytest.raises(ParameterError, match=r"spans 0\.5 samples at sample_rate=1e\+09; "
                                                 r"the detector .* needs 1 or more"):
            sensor(sample_rate=1e9, pulse=GaussianPulse(0.5e-9), geiger=geiger)
    sensor(sample_rate=1e9, pulse=GaussianPulse(0.5e-9), echoes="discrete")
