"""Property-based fuzz over the newer surfaces' constructors and calls (issue 29): arbitrary
floats (0, ±inf, NaN, 1e±308, subnormals), integers and types. The only outcomes allowed are
a result whose numbers are finite, or a MeshladarError of one line."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import meshladar as ml
from meshladar.errors import MeshladarError
from meshladar.noise import Noise
from meshladar.sensor import FloodBeam, GaussianBeam, Sensor
from meshladar.waveforms import GaussianPulse, SampledPulse

FUZZ = settings(max_examples=150, deadline=None,
                suppress_health_check=[HealthCheck.too_slow])
#: floats at the extremes, and values of the wrong kind
extreme = st.one_of(st.floats(allow_nan=True, allow_infinity=True, allow_subnormal=True),
                    st.sampled_from([0.0, -0.0, 1e-308, 5e-324, 1e308, -1e308, 1e-200]),
                    st.integers(-(10 ** 400), 10 ** 400), st.none(), st.booleans(),
                    st.text(max_size=3))


def _outcome(call):
    """The call's result, or None when it refused with one clear line."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ml.errors.MeshladarWarning)
            return call()
    except MeshladarError as exc:
        assert "\n" not in str(exc) and len(str(exc)) < 1000, str(exc)
        return None


def _finite_fields(obj):
    for value in vars(obj).values():
        if isinstance(value, float):
            assert np.isfinite(value), (obj, value)


SURFACES = {
    "Sensor.standoff": lambda v: Sensor(standoff=v),
    "Sensor.pulse_energy": lambda v: Sensor(standoff=10.0, pulse_energy=v,
                                            aperture_diameter=0.1, beam=FloodBeam(1.0)),
    "Sensor.aperture": lambda v: Sensor(standoff=10.0, pulse_energy=1.0, aperture_diameter=v,
                                        beam=FloodBeam(1.0)),
    "Sensor.extinction": lambda v: Sensor(standoff=10.0, extinction=v),
    "Sensor.wavelength": lambda v: Sensor(wavelength=v),
    "FloodBeam.radius": lambda v: FloodBeam(v),
    "GaussianBeam.waist": lambda v: GaussianBeam(v),
    "GaussianBeam.divergence": lambda v: GaussianBeam(0.1, divergence=v),
    "GaussianPulse.fwhm": lambda v: GaussianPulse(v),
    "SampledPulse.interval": lambda v: SampledPulse([1.0, 2.0], v),
    "Noise.background_rate": lambda v: Noise(background_rate=v),
    "Noise.speckle_cells": lambda v: Noise(speckle_cells=v),
    "Noise.gain": lambda v: Noise(gain=v),
    "Ladar.centered.bin_width": lambda v: ml.Ladar.centered(8, v),
    "Ladar.centered.center": lambda v: ml.Ladar.centered(8, 0.1, center=v),
    "Ladar.paper.radius": lambda v: ml.Ladar.paper(v),
    "Tabulated.values": lambda v: ml.brdf.Tabulated([0.0, 90.0], [v, 1.0]),
}


def _use(made):
    """Compute with what was made: every number that comes out is finite (or refused)."""
    sino = ml.Sinogram(np.ones((1, 4)), angles_deg=[0.0], bin_edges=np.linspace(-1, 1, 5))
    if isinstance(made, Sensor) and made.counts_photons:
        assert np.isfinite(made.photoelectrons_per_unit())
    elif isinstance(made, (GaussianPulse, SampledPulse)):
        from meshladar.waveforms import receive

        waves = _outcome(lambda: receive(sino, sample_rate=1e9, pulse=made))
        assert waves is None or np.all(np.isfinite(waves.values))
    elif isinstance(made, ml.Ladar):
        e = made.bin_edges
        assert np.all(np.isfinite(e)) and np.all(np.diff(e) > 0)
    elif isinstance(made, ml.brdf.BRDF):
        f = made.monostatic(np.linspace(0.0, 1.5, 7))
        assert np.all(np.isfinite(f))


@pytest.mark.parametrize("name", list(SURFACES))
@FUZZ
@given(value=extreme)
def test_constructors_refuse_or_hold_finite_numbers(name, value):
    made = _outcome(lambda: SURFACES[name](value))
    if made is not None:
        _finite_fields(made)
        _use(made)


@FUZZ
@given(photons=st.floats(0.0, 1e12), n=st.integers(1, 4),
       seed=st.one_of(st.integers(-3, 2 ** 70), st.floats(), st.text(max_size=2)))
def test_noise_draws_are_finite_or_refused(photons, n, seed):
    signal = np.full((2, 3), photons)
    out = _outcome(lambda: ml.noise.draw_noise(
        Noise(speckle_cells=2.0, excess_noise_factor=1.5), signal, 1e-6, n, seed))
    if out is not None:
        assert out.shape == (n, 2, 3) and np.all(np.isfinite(out)) and np.all(out >= 0)
