"""Detection against the Poisson threshold theory: the threshold's false-alarm bound, the
false-alarm rate on noise alone, and the detection probability of a weak echo, each
computed here from Poisson probabilities (scipy.stats), not by the detector."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import erf
from scipy.stats import poisson

from meshladar.errors import EmptyScanWarning
from meshladar.noise import Noise
from meshladar.scan import Detector, Platform, ScanPattern, scan

from _scan_scenes import photoelectrons_by_hand, plate, scene, sensor

R0 = 100.0


def _repeat(direction, n):
    return ScanPattern(np.arange(n) * 1e-4, np.tile(direction, (n, 1)))


@pytest.mark.parametrize("b, pfa", [(0.5, 1e-3), (0.05, 1e-6), (3.0, 1e-4)])
def test_the_threshold_is_the_smallest_count_whose_tail_is_below_the_false_alarm(b, pfa):
    n = Detector(false_alarm=pfa).level(b)
    assert poisson.sf(n - 1, b) <= pfa < poisson.sf(n - 2, b)


def test_false_alarms_on_noise_alone_follow_the_poisson_tail():
    """Pulses that meet nothing, 4096 samples each, background 0.5 per sample: each sample
    at or above the threshold n (P(N ≥ n) = 1.7e-4) gives one false return, less those
    within one echo width of a stronger one (at most 2 %): the count lies within 4 binomial
    σ of samples × P(N ≥ n) × (0.98 … 1)."""
    dt = 0.5e-9
    sen = sensor(noise=Noise(background_rate=0.5 / dt), samples=4096,
                 detector=Detector(false_alarm=1e-3))
    n_pulses = 500
    pc = scan(scene(plate(R0)), _repeat((-1.0, 0.0, 0.0), n_pulses), Platform.static((0, 0, 0)),
              sen, seed=3)
    level = sen.detector.level(0.5)
    p = poisson.sf(level - 1, 0.5)
    samples = n_pulses * 4096
    sd = math.sqrt(samples * p)
    assert 0.98 * samples * p - 4 * sd <= len(pc) <= samples * p + 4 * sd
    assert np.all(pc.points["true_face"] == -1) and np.all(np.isnan(pc.points["true_range"]))


def test_a_false_alarm_away_from_every_echo_has_no_ground_truth():
    """A user's trial: pulses lighting a plate with 1e-6 photoelectrons over a background
    of 0.5 a sample: every return is noise, yet each took the plate's truth (the nearest
    lit sub-ray's, however far in time: range errors of ±2.4 m, 7.5 σ). A return more than
    3 σ of its echo (the fitted width's, at least the pulse's) from every sub-ray's echo
    has none; the plate's range R0 is known here."""
    dt = 0.5e-9
    energy = 1e-6 / photoelectrons_by_hand(1.0, 0.05, R0)
    sen = sensor(noise=Noise(background_rate=0.5 / dt), pulse_energy=energy, samples=256,
                 detector=Detector(false_alarm=1e-3))
    pc = scan(scene(plate(R0)), _repeat((1.0, 0.0, 0.0), 2000), Platform.static((0, 0, 0)),
              sen, seed=3)
    p = pc.points
    sigma = np.maximum(p["width"].astype(float) / 2.3548200450309493, sen.sigma)
    gap = np.abs(p["range"] - R0) / (0.5 * 299_792_458.0)          # s, from the echo
    far, near = gap > 3.0 * sigma * (1 + 1e-6), gap < 3.0 * sigma * (1 - 1e-6)
    assert far.sum() > 20 and near.sum() > 0
    assert np.all(p["true_face"][far] == -1) and np.all(p["true_part"][far] == -1)
    assert np.all(np.isnan(p["true_range"][far])) and np.all(np.isnan(p["true_x"][far]))
    assert np.all(p["true_part"][near] == 0)
    assert np.allclose(p["true_range"][near], R0, atol=1e-9)


def test_the_detection_probability_of_a_weak_echo_follows_its_samples_poisson_counts():
    """An echo of 15 photoelectrons, no background, threshold 3: it is detected when one of
    its samples reaches 3 counts; P = 1 − Π P(N_j < 3 | λ_j), λ_j the echo's expected
    photoelectrons in sample j (erf differences, written here). 3000 pulses: the detected
    fraction within 4 binomial σ."""
    energy = 15.0 / photoelectrons_by_hand(1.0, 0.05, R0)
    sen = sensor(noise=Noise(), pulse_energy=energy, detector=Detector(threshold=3.0))
    n_pulses = 3000
    pc = scan(scene(plate(R0)), _repeat((1.0, 0.0, 0.0), n_pulses), Platform.static((0, 0, 0)),
              sen, seed=5)
    detected = len(np.unique(pc.points["pulse_id"]))
    total = photoelectrons_by_hand(energy, 0.05, R0)
    tau = 2 * R0 / 299_792_458.0
    start = math.floor((tau - 8 * sen.sigma) / sen.dt) * sen.dt
    edges = start + sen.dt * np.arange(200)
    z = (edges - tau) / (sen.sigma * math.sqrt(2))
    lam = 0.5 * total * np.diff(erf(z))
    p_detect = 1.0 - np.prod(poisson.cdf(2, lam))
    sd = math.sqrt(n_pulses * p_detect * (1 - p_detect))
    assert 0.2 < p_detect < 0.95
    assert abs(detected - n_pulses * p_detect) <= 4 * sd


def test_cfar_estimates_each_records_background_and_keeps_the_poisson_false_alarm_rate():
    """The same noise-only pulses as above with a cell-averaging CFAR detector: each
    record's background is estimated from it (4096 samples: 0.5 ± 0.011), and the false
    returns stay within the Poisson bound of the true background."""
    dt = 0.5e-9
    sen = sensor(noise=Noise(background_rate=0.5 / dt), samples=4096,
                 detector=Detector(false_alarm=1e-3, cfar=True))
    n_pulses = 500
    pc = scan(scene(plate(R0)), _repeat((-1.0, 0.0, 0.0), n_pulses), Platform.static((0, 0, 0)),
              sen, seed=3)
    p = poisson.sf(Detector(false_alarm=1e-3).level(0.5) - 1, 0.5)
    samples = n_pulses * 4096
    sd = math.sqrt(samples * p)
    assert 0.98 * samples * p - 4 * sd <= len(pc) <= samples * p + 4 * sd


def test_cfar_finds_an_echo_over_a_background_the_detector_was_not_told():
    """An echo of 300 photoelectrons over 2 background counts per sample: CFAR's
    threshold (from the record) finds it in every pulse, at the plate's range within
    5 σ of the shot-noise bound (σ = 1.8 cm at 300 photoelectrons) and unbiased within
    1 cm over the 50 pulses."""
    dt = 0.5e-9
    energy = 300.0 / photoelectrons_by_hand(1.0, 0.05, R0)
    sen = sensor(noise=Noise(background_rate=2.0 / dt), pulse_energy=energy, samples=1024,
                 detector=Detector(cfar=True))
    pc = scan(scene(plate(R0)), _repeat((1.0, 0.0, 0.0), 50), Platform.static((0, 0, 0)),
              sen, seed=8)
    first = pc.points[pc.points["true_face"] >= 0]
    assert len(np.unique(first["pulse_id"])) == 50
    assert np.all(np.abs(first["range"] - R0) < 5 * 0.018)
    assert abs(np.mean(first["range"] - R0)) < 0.01


def test_cfar_on_short_quiet_records_does_not_take_the_background_for_zero():
    """Short records (70 samples, the fewest that hold one echo) of a faint background
    (0.05 per sample): many hold no count at all beyond the guard, and a background
    estimated as 0 would set a threshold of one count, which ~3 % of the samples cross
    (~1000 false returns here); kept off zero, the threshold is 4 counts and
    P(N ≥ 4 | 0.05) × 35 000 samples ≈ 0.01."""
    dt = 0.5e-9
    sen = sensor(noise=Noise(background_rate=0.05 / dt), samples=70,
                 detector=Detector(cfar=True))
    with pytest.warns(EmptyScanWarning, match="none of the 500 pulses met the scene"):
        pc = scan(scene(plate(R0)), _repeat((-1.0, 0.0, 0.0), 500),
                  Platform.static((0, 0, 0)), sen, seed=6)
    assert len(pc) == 0


@pytest.mark.parametrize("half, samples", [(0, 40), (2, 1), (2, 3), (5, 200), (9, 64)])
def test_peaks_are_the_filtered_records_maxima_where_a_window_holds_a_detection(half,
                                                                               samples):
    """The compiled peak search against scipy: the records' gaussian_filter1d (truncate
    4, zeros beyond the ends), the samples whose window of ±``half`` holds a sample at or
    above the level (maximum_filter1d), their local maxima (ties to the later neighbour
    excluded), strongest first, each farther than the separation from a stronger one kept,
    at most three a record; continuous random records, so no two filtered values tie."""
    from scipy.ndimage import gaussian_filter1d, maximum_filter1d

    from meshladar.scan._peaks import find_peaks
    from meshladar.scan._sampling import matched_filter

    s, level, separation, most = 2.0, 2.5, 4.0, 3
    rng = np.random.default_rng(half + samples)
    n = 400
    waves = rng.uniform(0.0, 1.0, (n, samples)) ** 8 * rng.uniform(0.0, 6.0, (n, 1))
    p, j = np.empty(n * most, np.int64), np.empty(n * most, np.int64)
    f3 = np.empty((n * most, 3))
    no_table = (np.zeros((1, 1)), np.zeros((1, 1)), 0, 0, np.zeros((1, 1)), np.zeros((1, 1)))
    k = find_peaks(waves, np.zeros((0, 2)), no_table, waves,
                   np.broadcast_to(np.asarray(level), waves.shape), matched_filter(s), half,
                   separation, most, p, j, f3)
    filt = gaussian_filter1d(waves, s, axis=1, mode="constant", truncate=4.0)
    active = maximum_filter1d((waves >= level).astype(np.uint8), 2 * half + 1, axis=1,
                              mode="constant") > 0
    want = []
    for q in range(n):
        f = np.concatenate([[-np.inf], filt[q], [-np.inf]])
        cand = [i for i in range(samples) if active[q, i] and f[i + 1] > 0
                and f[i + 1] >= f[i] and f[i + 1] > f[i + 2]]
        kept = []
        for i in sorted(cand, key=lambda i: -f[i + 1]):
            if len(kept) < most and all(abs(i - o) > separation for o in kept):
                kept.append(i)
        want += [(q, i) for i in kept]
    assert list(zip(p[:k].tolist(), j[:k].tolist())) == want
    assert k > 0 or samples < 3
