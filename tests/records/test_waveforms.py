"""The receiver stage: pulses, responses, digitiser and noise (the sensor and its radiometry
are tested in tests/values/test_sensor_beams.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import meshladar as ml
from meshladar.materials import ALUMINUM, DARK_GRAY

# -- the receiver: pulses, responses, digitiser, noise -------------------------------------

from meshladar.waveforms import GaussianPulse, receive, SampledPulse, Waveforms
from meshladar.noise import Noise

#: energy through the bin spreading, convolutions and digitiser: rounding only
ENERGY_RTOL = 1e-12


def _power_sinogram():
    return ml.simulate(ml.phantoms.scene("disk_pair", large=DARK_GRAY, small=ALUMINUM),
                       ml.Ladar(np.arange(0.0, 360.0, 15.0),
                                np.concatenate([[-0.9], np.linspace(-0.8, 0.8, 130),
                                                [0.95]])),
                       radiometry="power")


@pytest.mark.parametrize("pulse, response, rate", [
    (None, None, 1e10),
    (GaussianPulse(fwhm=1e-9), None, 2e9),
    (GaussianPulse(fwhm=1e-9), GaussianPulse(fwhm=0.3e-9), 5e9),
    (SampledPulse([0.0, 1.0, 3.0, 2.0, 0.5], interval=0.25e-9, start=-0.5e-9),
     GaussianPulse(fwhm=2e-9), 1e9),
])
def test_waveforms_conserve_energy(pulse, response, rate):
    sino = _power_sinogram()
    waves = receive(sino, sample_rate=rate, pulse=pulse, response=response)
    np.testing.assert_allclose(waves.total(), sino.total(), rtol=ENERGY_RTOL)
    assert np.all(waves.values >= 0)
    np.testing.assert_allclose(np.diff(waves.time_edges), 1.0 / rate, rtol=1e-9)
    assert waves.info["radiometry"] == "power" and waves.info["sample_rate_hz"] == rate


def test_waveform_of_one_bin_is_the_pulse():
    """A single narrow return at range r: the samples are the Gaussian pulse's integral
    over each sample, centred at the two-way time 2(r + D)/c."""
    from scipy.special import ndtr

    c = ml.sensor.SPEED_OF_LIGHT
    r, D, fwhm, rate = 0.3, 100.0, 2e-9, 4e9
    edges = np.array([r - 1e-7, r + 1e-7])
    sino = ml.Sinogram([[2.5]], angles_deg=[0.0], bin_edges=edges,
                       info={"sensor": {"standoff_m": D}})
    waves = receive(sino, sample_rate=rate, pulse=GaussianPulse(fwhm), oversample=64)
    t0 = 2 * (r + D) / c
    sigma = fwhm / (2 * math.sqrt(2 * math.log(2)))
    expected = 2.5 * np.diff(ndtr((waves.time_edges - t0) / sigma))
    # the return is a box of 0.67 ps and the fine grid 4 ps: both far below the pulse
    np.testing.assert_allclose(waves.values[0], expected, atol=2e-3 * expected.max())
    np.testing.assert_allclose(waves.range_edges, c * waves.time_edges / 2 - D, rtol=1e-15)


def test_a_recorded_standoff_out_of_range_is_named_as_the_files():
    """The standoff taken from the sinogram's record is refused in its own name (a user who
    gave none was told their standoff was wrong); one given is refused as the argument."""
    sino = ml.Sinogram([[1.0]], angles_deg=[0.0], bin_edges=[0.0, 0.1],
                       info={"sensor": {"standoff_m": -5.0}})
    with pytest.raises(ml.errors.ParameterError, match=r"^the sinogram's info\['sensor'\]"
                                                r"\['standoff_m'\] must be in \[0, 1e\+09\]; "
                                                r"got -5.0$"):
        receive(sino, sample_rate=1e9)
    with pytest.raises(ml.errors.ParameterError, match=r"^standoff must be in \[0, 1e\+09\]; got -1.0"):
        receive(sino, sample_rate=1e9, standoff=-1.0)
    assert receive(sino, sample_rate=1e9, standoff=2.0).standoff == 2.0


def _photo_waves():
    values = np.array([[0.0, 0.05, 1.0, 5.0, 50.0, 400.0]])
    return Waveforms(values, time_edges=np.arange(7) * 1e-9, angles_deg=[0.0],
                     view_vectors=[[1.0, 0.0, 0.0]], info={"units": "photoelectrons"})


#: |z| of a sample mean or variance against its theory, over 6 samples: a Gaussian z
#: beyond 5 has probability 6e-7 (the runs are seeded, so the test is deterministic)
Z_MAX = 5.0


@pytest.mark.parametrize("noise", [
    Noise(),
    Noise(speckle_cells=1.0),
    Noise(speckle_cells=4.0, background_rate=2e8, dark_rate=5e7),
    Noise(excess_noise_factor=3.0, gain=20.0),
    Noise(speckle_cells=2.0, background_rate=1e8, excess_noise_factor=2.5, gain=10.0),
], ids=["poisson", "speckle_M1", "speckle_background_dark", "apd", "all"])
def test_noise_means_and_variances_match_goodman(noise):
    """Means converge to the noiseless waveform (plus background), variances to
    G²(F (s + b) + s²/M), each within its own sampling error (the variance's from the
    sample's fourth moment)."""
    waves = _photo_waves()
    n = 100_000
    draws = waves.realise(noise, n, seed=7)[:, 0, :]
    mu = noise.mean(waves.values[0], waves.sample_interval)
    var = noise.variance(waves.values[0], waves.sample_interval)
    live = var > 0
    z_mean = (draws.mean(0) - mu)[live] / np.sqrt(var[live] / n)
    assert np.all(np.abs(z_mean) < Z_MAX), z_mean
    dev = draws - draws.mean(0)
    s2 = (dev ** 2).mean(0)
    m4 = (dev ** 4).mean(0)
    z_var = (s2 - var)[live] / np.sqrt((m4 - s2 ** 2)[live] / n)
    assert np.all(np.abs(z_var) < Z_MAX), z_var
    assert np.all(draws[:, ~live] == 0)


def test_noise_is_seeded_and_quantised():
    waves = _photo_waves()
    noise = Noise(speckle_cells=3.0, background_rate=1e8, excess_noise_factor=2.0, gain=5.0,
                  bits=10, full_scale=4000.0)
    with pytest.warns(ml.errors.MeshladarWarning, match="clip"):    # the brightest do
        a = waves.realise(noise, 50, seed=11)
        b = waves.realise(noise, 50, seed=11)
        assert a.tobytes() == b.tobytes()
        assert not np.array_equal(a, waves.realise(noise, 50, seed=12))
    lsb = 4000.0 / 2 ** 10
    np.testing.assert_allclose(a / lsb, np.round(a / lsb), atol=1e-9)
    assert a.max() <= 4000.0 - lsb and a.min() >= 0.0


def _constant_waves(photoelectrons):
    """2 views x 5 samples of a constant number of photoelectrons per sample."""
    return Waveforms(np.full((2, 5), float(photoelectrons)), time_edges=np.arange(6) * 1e-9,
                     angles_deg=np.array([0.0, 90.0]), view_vectors=None,
                     units="photoelectrons")


def test_noise_that_clips_warns_with_the_fraction_and_the_full_scale_that_holds_it(
        tmp_path):
    """Closed form: Poisson(1e6) photoelectrons x gain 1 on a 1000-unit, 8-bit digitiser
    clip in every sample (100 %; the 1e6 ± 5σ draws need a full scale of 1.1e6 at 2
    digits), and Poisson(10) on a 1e6-unit one never does (0 %, no warning); the saved
    realisations record the fraction."""
    noise = Noise(bits=8, full_scale=1000.0)
    top = 1000.0 * 255 / 256
    with pytest.warns(ml.errors.MeshladarWarning, match=r"100 % of the noisy samples clip"
                      r".*full scale \(1000;.*full_scale >= 1\.1e\+06") as rec:
        draws = _constant_waves(1e6).realise(noise, 4, seed=0)
    assert len(rec) == 1
    np.testing.assert_array_equal(draws, top)
    assert noise.clipped_fraction(draws) == 1.0
    path = tmp_path / "clip.npz"
    ml.io.save_waveforms(path, _constant_waves(1e6), realisations=draws, noise=noise)
    assert ml.io.load_waveforms(path)[2]["noise"]["clipped_fraction"] == 1.0
    quiet = Noise(bits=8, full_scale=1e6)
    draws = _constant_waves(10.0).realise(quiet, 4, seed=0)       # no warning (errors)
    assert quiet.clipped_fraction(draws) == 0.0 and Noise().clipped_fraction(draws) == 0.0
    ml.io.save_waveforms(path, _constant_waves(10.0), realisations=draws, noise=quiet)
    assert ml.io.load_waveforms(path)[2]["noise"]["clipped_fraction"] == 0.0


def test_noise_needs_photoelectrons():
    sino = _power_sinogram()
    waves = receive(sino, sample_rate=2e9)
    with pytest.raises(ml.errors.ParameterError, match="photoelectrons"):
        waves.realise(Noise())
    counted = waves.scaled(1e4)
    draws = counted.realise(Noise(), 3, seed=0)
    assert draws.shape == (3,) + waves.values.shape


@pytest.mark.parametrize("kwargs, match", [
    ({"speckle_cells": 0.5}, "speckle_cells"),
    ({"excess_noise_factor": 0.9}, "excess_noise_factor"),
    ({"bits": 8}, "both bits and full_scale"),
    ({"bits": 0, "full_scale": 1.0}, "bits"),
    ({"background_rate": -1.0}, "background_rate"),
])
def test_noise_checks_its_parameters(kwargs, match):
    with pytest.raises(ml.errors.ParameterError, match=match):
        Noise(**kwargs)


def test_receive_checks_its_parameters():
    sino = _power_sinogram()
    with pytest.raises(ml.errors.ParameterError, match="sample_rate"):
        receive(sino, sample_rate=0.0)
    with pytest.raises(ml.errors.ParameterError, match="pulse must be"):
        receive(sino, sample_rate=1e9, pulse=1e-9)
    with pytest.raises(ml.errors.ParameterError, match="samples"):
        SampledPulse([0.0, 0.0], interval=1e-9)
    with pytest.raises(ml.errors.ParameterError, match="sample_rate"):
        receive(sino, sample_rate=1e18)


def test_waveforms_save_and_load_without_pickle(tmp_path):
    waves = receive(_power_sinogram(), sample_rate=3e9, pulse=GaussianPulse(1e-9)).scaled(50.0)
    noise = Noise(speckle_cells=2.0, gain=4.0)
    draws = waves.realise(noise, 4, seed=1)
    path = tmp_path / "w.npz"
    ml.io.save_waveforms(path, waves, realisations=draws, noise=noise)
    back, got, meta = ml.io.load_waveforms(path)
    np.testing.assert_array_equal(back.values, waves.values)
    np.testing.assert_array_equal(back.time_edges, waves.time_edges)
    np.testing.assert_array_equal(got, draws)
    assert meta["noise"]["speckle_cells"] == 2.0 and back.info["units"] == "photoelectrons"
    assert back.info["pulse"] == {"kind": "gaussian", "fwhm_s": 1e-9}
    with np.load(path, allow_pickle=False) as z:
        np.testing.assert_allclose(z["range_edges_m"], waves.range_edges)


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # faceted on purpose
def test_cli_simulate_with_a_sensor_then_receive_with_noise(tmp_path):
    """The command line end to end: a sphere at 500 m counted in photoelectrons, then its
    waveforms with noise and a figure; the waveforms hold the sinogram's photoelectrons."""
    trimesh = pytest.importorskip("trimesh")
    pytest.importorskip("matplotlib")
    from meshladar.cli import main

    stl = tmp_path / "ball.stl"
    trimesh.creation.icosphere(subdivisions=4, radius=0.5).export(stl)
    sino_path, wave_path, png = tmp_path / "s.npz", tmp_path / "w.npz", tmp_path / "w.png"
    assert main([
        "simulate", str(stl), "-o", str(sino_path), "--model", "mesh", "--material",
        "aluminum", "--radiometry", "power", "--views", "3", "--standoff", "500",
        "--beam-waist", "0.02", "--beam-divergence", "1e-3", "--pulse-energy", "1e-5",
        "--aperture", "0.1", "--quiet"]) == 0
    sino, meta = ml.io.load_sinogram(sino_path)
    assert sino.info["units"] == "photoelectrons"
    assert meta["params"]["options"]["sensor"]["beam"]["divergence_rad"] == 1e-3
    assert main(["receive", str(sino_path), "-o", str(wave_path), "--sample-rate", "5e9",
                 "--pulse-fwhm", "1e-9", "--realisations", "20", "--speckle-cells", "1",
                 "--seed", "3", "--plot", str(png), "--quiet"]) == 0
    waves, draws, meta = ml.io.load_waveforms(wave_path)
    np.testing.assert_allclose(waves.total(), sino.total(), rtol=ENERGY_RTOL)
    assert draws.shape == (20,) + waves.values.shape and png.stat().st_size > 10_000
    assert waves.standoff == 500.0 and meta["params"]["seed"] == 3
    # the same seed: the same realisations, bit for bit
    again = tmp_path / "w2.npz"
    assert main(["receive", str(sino_path), "-o", str(again), "--sample-rate", "5e9",
                 "--pulse-fwhm", "1e-9", "--realisations", "20", "--speckle-cells", "1",
                 "--seed", "3", "--quiet"]) == 0
    assert ml.io.load_waveforms(again)[1].tobytes() == draws.tobytes()
    # noise options without realisations, and noise on relative units, are clear errors
    assert main(["receive", str(sino_path), "-o", str(tmp_path / "x.npz"), "--sample-rate",
                 "5e9", "--gain", "3"]) == 2


def test_detection_probability_matches_the_poisson_tail():
    """One sample of mean s and no other noise: a threshold k is reached with probability
    P(N ≥ k) of Poisson(s); background alone (rate b per sample) raises a false alarm with
    P(N ≥ k) of Poisson(b). Both within 5 binomial standard errors."""
    from scipy.stats import poisson

    s, b, k, n = 6.0, 0.5, 8, 20_000
    waves = Waveforms([[s]], time_edges=[0.0, 1e-9], angles_deg=[0.0],
                      view_vectors=[[1.0, 0.0, 0.0]], info={"units": "photoelectrons"})
    noise = Noise(background_rate=b / 1e-9)
    got = waves.detection_probability(noise, k, n, seed=5)
    pd, pfa = poisson.sf(k - 1, s + b), poisson.sf(k - 1, b)
    assert abs(got["detection"][0] - pd) < 5 * math.sqrt(pd * (1 - pd) / n)
    assert abs(got["false_alarm"] - pfa) < 5 * math.sqrt(pfa * (1 - pfa) / n) + 1 / n
    assert got == waves.detection_probability(noise, k, n, seed=5)      # seeded


def test_cli_receive_with_the_users_pulse_samples(tmp_path):
    """--pulse-samples: the user's pulse from a text file; the waveform's energy is kept and
    a missing interval, a file of junk and both pulse options are clear errors."""
    from meshladar.cli import main

    sino_path = tmp_path / "s.npz"
    ml.io.save_sinogram(sino_path, _power_sinogram())
    pulse = tmp_path / "pulse.txt"
    pulse.write_text("# measured pulse\n0, 1, 3\n2 0.5\n")
    out = tmp_path / "w.npz"
    assert main(["receive", str(sino_path), "-o", str(out), "--sample-rate", "2e9",
                 "--pulse-samples", str(pulse), "--pulse-interval", "2.5e-10",
                 "--quiet"]) == 0
    waves, _, _ = ml.io.load_waveforms(out)
    np.testing.assert_allclose(waves.total(), _power_sinogram().total(), rtol=ENERGY_RTOL)
    assert waves.info["pulse"]["kind"] == "samples"
    junk = tmp_path / "junk.txt"
    junk.write_text("1, two, 3\n")
    for argv in (["--pulse-samples", str(pulse)],
                 ["--pulse-samples", str(junk), "--pulse-interval", "1e-10"],
                 ["--pulse-samples", str(pulse), "--pulse-interval", "1e-10",
                  "--pulse-fwhm", "1e-9"]):
        assert main(["receive", str(sino_path), "-o", str(tmp_path / "x.npz"),
                     "--sample-rate", "2e9"] + argv) == 2
