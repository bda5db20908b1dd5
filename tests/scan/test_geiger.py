"""Geiger-mode pixels against the closed form of pile-up, and Coates' correction."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy.special import erf

from meshladar.noise import Noise
from meshladar.scan import GeigerMode, Platform, ScanPattern, coates, scan

from _scan_scenes import SPEED_OF_LIGHT, photoelectrons_by_hand, plate, scene, sensor

R0 = 100.0
SHOTS = 20_000


def _one_pulse():
    return ScanPattern([0.0], [[1.0, 0.0, 0.0]])


def _expected_events(sen, total, b, start, ns):
    """λ_j: the echo's photoelectrons in each sample (erf differences) plus b."""
    tau = 2 * R0 / SPEED_OF_LIGHT
    edges = start + sen.dt * np.arange(ns + 1)
    return 0.5 * total * np.diff(erf((edges - tau) / (sen.sigma * math.sqrt(2)))) + b


@pytest.fixture(scope="module")
def piled():
    """3 photoelectrons per shot and background 0.002 per sample: heavy pile-up."""
    energy = 3.0 / photoelectrons_by_hand(1.0, 0.05, R0)
    sen = sensor(pulse_energy=energy, noise=Noise(background_rate=0.002 * 2e9),
                 geiger=GeigerMode(shots=SHOTS), samples=80)
    pc = scan(scene(plate(R0)), _one_pulse(), Platform.static((0, 0, 0)), sen,
              keep_waveforms=True, seed=11)
    return sen, pc


def test_the_detection_histogram_piles_up_as_the_first_photon_law_says(piled):
    """With one detection per shot, E[h_j] = K (1 − e^{−λ_j}) exp(−Σ_{i<j} λ_i): every bin
    within 5 Poisson σ (+1 count)."""
    sen, pc = piled
    hist, start = pc.waveform(0)
    lam = _expected_events(sen, 3.0, 0.002, start, len(hist))
    expect = SHOTS * -np.expm1(-lam) * np.exp(-(np.cumsum(lam) - lam))
    assert np.all(np.abs(hist - expect) <= 5 * np.sqrt(expect) + 1)
    assert hist.sum() <= SHOTS


def test_coates_recovers_the_echo_that_pile_up_pulls_early(piled):
    """The raw histogram's centroid sits early (pile-up); the Coates-corrected point's
    range is within 1 cm of the plate (0.13 of a sample), and its photoelectrons per shot
    within 5 % of the 3 sent."""
    sen, pc = piled
    hist, start = pc.waveform(0)
    hist = hist.astype(float)
    x = start + (np.arange(len(hist)) + 0.5) * sen.dt
    raw_range = 0.5 * SPEED_OF_LIGHT * np.sum(hist * x) / hist.sum()
    assert raw_range < R0 - 0.1                                   # pulled early
    assert len(pc) == 1
    assert pc.points["range"][0] == pytest.approx(R0, abs=0.01)
    assert pc.points["intensity"][0] == pytest.approx(3.0, rel=0.05)


def test_a_geiger_points_intensity_is_above_the_background():
    """A user's trial: one photoelectron per shot over a background of 0.01 a sample read
    1.24 photoelectrons (the corrected histogram's background sized in). Now within 5 % of
    the one sent (by hand), and the point ranges true to 2 cm."""
    energy = 1.0 / photoelectrons_by_hand(1.0, 0.05, R0)
    sen = sensor(pulse_energy=energy, noise=Noise(background_rate=0.01 * 2e9),
                 geiger=GeigerMode(shots=SHOTS), samples=80)
    pc = scan(scene(plate(R0)), _one_pulse(), Platform.static((0, 0, 0)), sen, seed=12)
    echo = pc.points[np.abs(pc.points["range"] - R0) < 0.5]
    assert len(echo) == 1
    assert echo["intensity"][0] == pytest.approx(1.0, rel=0.05)
    assert echo["range"][0] == pytest.approx(R0, abs=0.02)


@pytest.mark.parametrize("dead", [0, 3])
def test_coates_inverts_the_expected_histogram_exactly(dead):
    """Fed the expected histogram of known λ (infinite dead time, or three samples),
    Coates' λ̂ is λ to rounding: the estimator, checked on its own closed form."""
    lam = np.array([[0.01, 0.2, 1.5, 0.7, 0.05, 0.01, 0.3]])
    k = 1000.0
    if dead == 0:
        h = k * -np.expm1(-lam) * np.exp(-(np.cumsum(lam) - lam))
    else:
        # armed fraction a_j = 1 − Σ_{i=j−D}^{j−1} (detections_i / K), built sample by sample
        h = np.zeros_like(lam)
        for j in range(lam.shape[1]):
            blind = h[0, max(0, j - dead):j].sum()
            h[0, j] = (k - blind) * -np.expm1(-lam[0, j])
    np.testing.assert_allclose(coates(h, k, dead), lam, rtol=1e-12)


def test_a_saturated_bin_gives_a_finite_estimate():
    est = coates(np.array([[10, 0, 0]]), 10, 0)
    assert np.all(np.isfinite(est)) and est[0, 0] == pytest.approx(math.log(11))


def test_a_saturating_echo_walks_early_as_the_guide_says():
    """The scanning guide's Geiger sensor (one pixel's share of its flash) 0.3° off the
    normal of an aluminium face 6 m away (a glint of many events per shot): every shot
    fires on the leading edge, and the range reads more than a metre short (and a warning
    says so: a user's trial found the pile-up silent); the dark gray wall beside it,
    about one event per shot, reads true to 5 cm."""
    import trimesh
    import meshladar as ml

    face = trimesh.creation.box((0.1, 6.0, 6.0))
    face.apply_translation((6.05, 3.0, 0.0))
    wall = trimesh.creation.box((0.1, 6.0, 6.0))
    wall.apply_translation((20.05, -3.0, 0.0))
    sc = ml.Scene.from_meshes([(face, ml.materials.ALUMINUM), (wall, ml.materials.DARK_GRAY)])
    # the guide's flash spreads 2e-11 J over 8 x 8 pixels: one pixel's share per pulse here
    gm = sensor(pulse_energy=2e-11 / 64, geiger=GeigerMode(shots=1000),
                noise=Noise(dark_rate=1e5))
    with pytest.warns(ml.errors.MeshladarWarning, match=r"1 of 2 Geiger-mode returns read "
                                                        r"6\.91 events per shot or more"):
        pc = scan(sc, ScanPattern([0.0, 0.0], [[1.0, 0.005, 0.0], [1.0, -0.005, 0.0]]),
                  Platform.static((0, 0, 0)), gm, seed=2)
    first = pc.points[pc.points["return_number"] == 1]
    assert first["true_range"][0] - first["range"][0] > 1.0       # its truth: the face's
    assert first["true_part"][0] == 0 and first["true_range"][0] == pytest.approx(6.0, abs=0.01)
    assert first["range"][1] == pytest.approx(first["true_range"][1], abs=0.05)


def test_the_histograms_are_drawn_in_blocks_of_one_stream(monkeypatch):
    """A user's trial: a flash frame of 10^6 shots a pixel ran as one compiled call that
    no Ctrl-C or SIGTERM could stop (17 s after SIGTERM for 16 x 16 pixels, ten minutes
    and more for 128 x 128). The records are drawn in blocks (the interpreter runs between
    them) from one stream: the same histograms whatever the block."""
    from meshladar.scan import geiger

    lam = np.random.default_rng(0).uniform(0.0, 0.05, (37, 60))
    whole = geiger.fire(lam, 500, 3, 7)
    calls = []
    original = geiger._fire

    def spy(*args):
        calls.append(len(args[0]))
        return original(*args)

    monkeypatch.setattr(geiger, "_fire", spy)
    monkeypatch.setattr(geiger, "FIRE_BLOCK", 5 * 500 * 60)
    assert np.array_equal(geiger.fire(lam, 500, 3, 7), whole)
    assert calls == [5] * 7 + [2]


def test_a_dead_time_out_of_range_names_inf_too():
    with pytest.raises(ValueError, match=r"dead_time must be in \(0, 1\] s, or inf .*got 0"):
        GeigerMode(dead_time=0)


def test_few_shots_of_a_weak_echo_are_not_taken_for_pile_up():
    """A review: the level ln K − 1 warned every return of 1 to 3 shots, and 22 of 151 of
    5 shots at 0.3 events per shot. Arrays of fewer than GEIGER_PILEUP_SHOTS shots are not
    checked, and 10 shots at 0.5 events per shot (reading within 5 %) are not warned."""
    for shots in (1, 3, 10):
        energy = 0.5 / photoelectrons_by_hand(1.0, 0.05, R0)
        sen = sensor(pulse_energy=energy, geiger=GeigerMode(shots=shots))
        pattern = ScanPattern(np.arange(32) * 1e-3, np.tile([1.0, 0.0, 0.0], (32, 1)))
        scan(scene(plate(R0)), pattern, Platform.static((0, 0, 0)), sen, seed=2)  # no warning


@pytest.mark.parametrize("events, read, early, warned", [
    (4.0, (0.97, 1.03), (-0.01, 0.01), False),
    (8.0, (0.87, 0.95), (0.04, 0.065), True),
    (20.0, (0.35, 0.385), (0.31, 0.335), True)])
def test_pile_up_past_the_warnings_level_reads_low_and_early(events, read, early, warned):
    """The scanning guide's figures for the pile-up warning (a return reading ln K events
    per shot or more: 6.91 here), 1000 shots of a 5 ns pulse at
    2 GS/s on a plate, the mean of 64 pulses: 4 events per shot read within 3 % and 1 cm
    (no warning), 8 read 0.91 of them 5 cm early, 20 read 0.37 32 cm early (warned); the
    events sent are the link budget by hand (bounds: over seeds 3-5, ±4 σ of a mean)."""
    from meshladar.scan.run import GEIGER_PILEUP_SHOTS

    energy = events / photoelectrons_by_hand(1.0, 0.05, R0)
    sen = sensor(pulse_energy=energy, geiger=GeigerMode(shots=1000))
    pattern = ScanPattern(np.arange(64) * 1e-3, np.tile([1.0, 0.0, 0.0], (64, 1)))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        pc = scan(scene(plate(R0)), pattern, Platform.static((0, 0, 0)), sen, seed=3)
    assert any("events per shot" in str(w.message) for w in caught) == warned
    assert read[0] < np.mean(pc.points["intensity"]) / events < read[1]
    assert early[0] < R0 - np.mean(pc.points["range"]) < early[1]
    assert GEIGER_PILEUP_SHOTS <= 1000
