"""The noise draws' memory guard counts the real peak (issue 29: it counted 8 bytes a sample
while the draw peaked at 5.1x that), and every seed= is checked the same way."""

import tracemalloc

import numpy as np
import pytest

import meshladar._validate as validate
from meshladar.errors import ParameterError
from meshladar.noise import DRAW_PEAK_BYTES, Noise, draw_noise
from meshladar.returns import Returns
from meshladar.waveforms import Waveforms

#: The heaviest configuration: speckle, excess noise, background and a digitiser.
HEAVY = dict(speckle_cells=2.0, excess_noise_factor=1.5, background_rate=1e6, gain=3.0)


def _peak_bytes_per_sample(noise, signal, n):
    tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        base = tracemalloc.get_traced_memory()[0]
        draw_noise(noise, signal, 1e-6, n, 7)
        peak = tracemalloc.get_traced_memory()[1] - base
    finally:
        tracemalloc.stop()
    return peak / (n * signal.size)


@pytest.mark.parametrize("options", [{}, {"speckle_cells": 3.0},
                                     {"excess_noise_factor": 2.0}, HEAVY])
def test_guard_covers_the_measured_peak(options):
    signal = np.random.default_rng(0).uniform(0.0, 40.0, (16, 500))
    per_sample = _peak_bytes_per_sample(Noise(**options), signal, 40)
    # the output alone is 8 bytes a sample: the guard's figure is at least the real peak
    assert 8.0 <= per_sample <= DRAW_PEAK_BYTES, per_sample


def test_refused_where_the_peak_would_pass_the_cap(monkeypatch):
    """A request whose output fits the cap but whose peak does not is refused before any
    draw (the old guard counted only the output)."""
    signal = np.full((4, 1000), 5.0)
    n = 100
    out_bytes = n * signal.size * 8
    monkeypatch.setattr(validate, "MAX_ARRAY_BYTES", 2 * out_bytes)   # output fits twice
    with pytest.raises(ParameterError, match=r"^n: 100 realisations of \(4, 1000\) samples"):
        draw_noise(Noise(**HEAVY), signal, 1e-6, n, 1)
    monkeypatch.setattr(validate, "MAX_ARRAY_BYTES", DRAW_PEAK_BYTES * n * signal.size)
    assert draw_noise(Noise(**HEAVY), signal, 1e-6, n, 1).shape == (n, 4, 1000)


def test_returns_realise_is_bounded():
    """Returns.realise had no guard at all: 10**10 draws went to numpy's MemoryError."""
    returns = Returns(np.ones((2, 3)), axes=("range",), edges=(np.arange(4.0),),
                      angles_deg=np.array([0.0, 90.0]),
                      view_vectors=np.array([[1.0, 0, 0], [0, 1.0, 0]]),
                      info={"units": "photoelectrons"})
    with pytest.raises(ParameterError, match=r"^n: 10000000000 realisations of \(2, 3\)"):
        returns.realise(Noise(), 10**10)


BAD_SEEDS = [-1, 1.5, "a", object(), True, -(2**70), np.float64(3.0)]


@pytest.mark.parametrize("seed", BAD_SEEDS, ids=repr)
def test_seeds_checked_with_one_message(seed):
    w = Waveforms(np.ones((2, 8)), time_edges=np.linspace(0, 8e-9, 9),
                  angles_deg=np.array([0.0, 90.0]), view_vectors=None, units="photoelectrons")
    for call in (lambda: w.realise(Noise(), 2, seed=seed),
                 lambda: w.detection_probability(Noise(), 1.0, 10, seed=seed),
                 lambda: draw_noise(Noise(), np.ones(3), 0.0, 1, seed)):
        with pytest.raises(ParameterError,
                           match=r"^seed must be None or a non-negative integer; got"):
            call()


def test_a_mean_count_beyond_the_draws_range_is_refused():
    """Scaled returns of 1e300 photoelectrons reached numpy's Poisson as "lam value too
    large"; the draw refuses them first, naming the mean count. 1e15 still draws (with
    fully developed speckle), finite."""
    with pytest.raises(ParameterError, match=r"^the largest mean count per cell would be "
                                             r"1e\+300 photoelectrons"):
        draw_noise(Noise(), np.full((2, 3), 1e300), 1e-6, 1, 0)
    out = draw_noise(Noise(speckle_cells=1.0), np.full((2, 3), 1e15), 1e-6, 2, 0)
    assert np.all(np.isfinite(out)) and out.max() > 1e14
