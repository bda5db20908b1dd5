"""Discrete returns (``echoes="discrete"``): no record, a pulse's sub-rays grouped in time,
checked against the link budget and the geometry written out here."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from meshladar.errors import ParameterError
from meshladar.noise import Noise
from meshladar.scan import Platform, ScanBeam, ScanPattern, rotating, scan

from _scan_scenes import SPEED_OF_LIGHT, photoelectrons_by_hand, plate, scene, sensor

R0 = 100.0


def test_a_plate_returns_its_link_budget_at_its_true_range():
    pc = scan(scene(plate(R0)), ScanPattern([0.0, 0.0], [[1, 0, 0], [1, 0.1, 0]]),
              Platform.static((0, 0, 0)), sensor(echoes="discrete"))
    c = 1 / np.sqrt(1.01)
    np.testing.assert_allclose(pc.points["intensity"],
                               [photoelectrons_by_hand(1e-6, 0.05, R0),
                                photoelectrons_by_hand(1e-6, 0.05, R0 / c, c)], rtol=1e-6)
    np.testing.assert_allclose(pc.points["range"], [R0, R0 / c], rtol=1e-12)


def test_the_atmosphere_takes_its_two_way_transmission_off_the_link_budget():
    """Extinction σ = 2e-3 /m over R and back: exp(−2σR) of the clear link budget, by hand,
    at both ranges of the plate (normal and oblique)."""
    sigma = 2e-3
    pc = scan(scene(plate(R0)), ScanPattern([0.0, 0.0], [[1, 0, 0], [1, 0.1, 0]]),
              Platform.static((0, 0, 0)), sensor(echoes="discrete", extinction=sigma))
    c = 1 / np.sqrt(1.01)
    np.testing.assert_allclose(pc.points["intensity"],
                               [photoelectrons_by_hand(1e-6, 0.05, R0)
                                * np.exp(-2 * sigma * R0),
                                photoelectrons_by_hand(1e-6, 0.05, R0 / c, c)
                                * np.exp(-2 * sigma * R0 / c)], rtol=1e-6)


@pytest.mark.parametrize("ratio, returns", [(0.9, 1), (1.1, 2), (3.0, 2)])
def test_two_plates_in_one_footprint_split_where_their_arrivals_are_a_fwhm_apart(ratio,
                                                                                 returns):
    """Two half-plates Δ apart: the groups split when Δ exceeds c·FWHM/2 (0.75 m here),
    each at its plate's range (to 1 mm: the footprint's own spread)."""
    near = trimesh.creation.box((0.01, 5.0, 10.0))
    near.apply_translation((R0 + 0.005, -2.5, 0.0))
    delta = ratio * 0.5 * SPEED_OF_LIGHT * 5e-9
    far = trimesh.creation.box((0.01, 5.0, 10.0))
    far.apply_translation((R0 + delta + 0.005, 2.5, 0.0))
    pc = scan(scene(near, far), ScanPattern([0.0], [[1.0, 0.0, 0.0]]),
              Platform.static((0, 0, 0)),
              sensor(echoes="discrete", beam=ScanBeam(2e-3, profile="tophat", tol=0.02)))
    assert len(pc) == returns
    if returns == 2:
        np.testing.assert_allclose(np.sort(pc.points["range"]), [R0, R0 + delta], atol=1e-3)


def test_discrete_points_lie_on_the_mesh_exactly():
    room = trimesh.creation.box((40.0, 40.0, 12.0))
    pat = rotating(np.linspace(-15, 15, 16), rotation_hz=10, pulse_rate=1e5, duration=0.02)
    pc = scan(scene(room), pat, Platform.moving((0, 0, 0), (10, 0, 0)),
              sensor(echoes="discrete", beam=ScanBeam(0.0)))
    ratio = np.max(np.abs(pc.xyz) / [20.0, 20.0, 6.0], axis=1)
    np.testing.assert_allclose(ratio, 1.0, atol=1e-9)
    np.testing.assert_allclose(pc.range_error, 0.0, atol=1e-9)


@pytest.mark.parametrize("kw", [dict(noise=Noise()), dict(samples=64)])
def test_records_options_are_refused_with_discrete_echoes(kw):
    with pytest.raises(ParameterError, match="discrete"):
        sensor(echoes="discrete", **kw)
    with pytest.raises(ParameterError, match="keep_waveforms"):
        scan(scene(plate(R0)), ScanPattern([0.0], [[1, 0, 0]]), Platform.static((0, 0, 0)),
             sensor(echoes="discrete"), keep_waveforms=True)
