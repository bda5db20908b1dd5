"""receive's memory guard counts the real peak of its FFT convolution (issue 29: it counted
the fine grid alone, 24 bytes a cell, while the convolution peaked at ~5× that; a 1 ms
pulse at 1 GHz passed the guard and took 14 GB)."""

import tracemalloc

import numpy as np
import pytest

import meshladar as ml
import meshladar._validate as validate
from meshladar.errors import ParameterError
from meshladar.waveforms import RECEIVE_PEAK_BYTES, GaussianPulse, receive

#: (views, bins, pulse FWHM s): long and short pulses against wide and narrow windows.
SHAPES = [(1, 8, 1e-5), (4, 64, 1e-6), (16, 64, 2e-7), (32, 256, 1e-8), (3, 16, 3e-6)]
RATE, OVERSAMPLE = 1e9, 8


def _sino(n_views, n_bins):
    return ml.Sinogram(np.ones((n_views, n_bins)), angles_deg=np.linspace(0.0, 90.0, n_views),
                       bin_edges=np.linspace(-1.0, 1.0, n_bins + 1))


def _cells(sino, pulse, waves):
    """What the guard counts: (views + 1) × (fine window + kernel cells)."""
    support = pulse.support[1] - pulse.support[0]
    kernel = support * RATE * OVERSAMPLE
    return (sino.n_views + 1) * (waves.values.shape[1] * OVERSAMPLE + kernel)


@pytest.mark.parametrize("n_views, n_bins, fwhm", SHAPES)
def test_guard_covers_the_measured_peak(n_views, n_bins, fwhm):
    sino, pulse = _sino(n_views, n_bins), GaussianPulse(fwhm)
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        waves = receive(sino, sample_rate=RATE, pulse=pulse, oversample=OVERSAMPLE)
        peak = tracemalloc.get_traced_memory()[1] - base
    finally:
        tracemalloc.stop()
    assert peak <= RECEIVE_PEAK_BYTES * _cells(sino, pulse, waves), peak


def test_refused_where_the_peak_would_pass_the_cap(monkeypatch):
    """A request whose fine grid fits the cap but whose convolution does not is refused
    before any work, naming sample_rate."""
    monkeypatch.setattr(validate, "MAX_ARRAY_BYTES", 2 ** 24)             # 16 MiB
    with pytest.raises(ParameterError, match=r"^sample_rate: \d+ fine cells per view"):
        receive(_sino(4, 64), sample_rate=RATE, pulse=GaussianPulse(1e-6))
