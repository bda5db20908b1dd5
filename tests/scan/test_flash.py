"""A flash frame against the closed form of a Lambertian plate, and its images."""

from __future__ import annotations

import math

import numpy as np
import pytest

from meshladar.errors import ParameterError
from meshladar.scan import Platform, flash, raster, scan

from _scan_scenes import photoelectrons_by_hand, plate, scene, sensor

D = 100.0


def test_a_flash_frames_photoelectrons_sum_to_the_plates_closed_form():
    """16 × 16 pixels of 0.05° on a plate at normal incidence: every sub-ray at off-axis α
    returns E s (ρ/π) cos α (π a²/4) cos²α / D², so the frame's sum is the on-axis budget
    of the whole pulse times a mean of cos³α between cos³ of the corner's angle and 1
    (a relative 1.5e-4 here); the waveforms hold it to rounding."""
    pat = flash(16, 16, ifov_deg=0.05)
    pc = scan(scene(plate(D)), pat, Platform.static((0, 0, 0)), sensor(), keep_waveforms=True)
    total = sum(block.sum() for block in pc.waveforms)
    on_axis = photoelectrons_by_hand(1e-6, 0.05, D)
    corner = math.atan(math.tan(math.radians(0.05)) * 8 * math.sqrt(2))
    assert math.cos(corner) ** 3 * on_axis <= total <= on_axis
    assert len(pc) == 256


def test_a_flash_frames_range_image_is_the_plates_distance_through_each_pixel():
    """Pixel (i, j) looks along (1, (7.5 − j) p, (7.5 − i) p), p = tan(IFOV): its range is
    D √(1 + y² + z²) (to 0.2 mm, 0.3 % of a sample: the centroid timing on 2 GS/s samples)."""
    pat = flash(16, 16, ifov_deg=0.05)
    pc = scan(scene(plate(D)), pat, Platform.static((0, 0, 0)), sensor())
    p = math.tan(math.radians(0.05))
    c = 7.5 - np.arange(16)
    expect = D * np.sqrt(1 + (c[None, :] * p) ** 2 + (c[:, None] * p) ** 2)
    np.testing.assert_allclose(pc.image("range"), expect, atol=2e-4)
    assert np.all(pc.image("intensity") > 0)
    with pytest.raises(ParameterError, match="field"):
        pc.image("colour")
    line = scan(scene(plate(D)), raster([0.0], [0.0], pulse_rate=1.0),
                Platform.static((0, 0, 0)), sensor())
    with pytest.raises(ParameterError, match="flash"):
        line.image()


def test_a_flash_frame_sums_to_the_mesh_engines_received_power_of_the_same_fluence():
    """Two forward models, one plate: a 32 × 32 flash frame 1 km away whose field covers
    2 × 2 m around a 1 m Lambertian plate (pixel edges on the plate's), against
    ``simulate(model="mesh", radiometry="power")`` with a flood beam of the same fluence
    at the plate and the same aperture: the frame's photoelectrons equal the profile's
    total to 1e-5 (measured 2.5e-7: the angles are below 1e-3 rad, so the two
    illuminations' perspective terms differ by less than 1e-6)."""
    import meshladar as ml
    from meshladar.sensor import FloodBeam, Sensor
    from meshladar.scan import ScanBeam

    far = 1000.0
    sc = scene(plate(0.0, half=0.5, thickness=0.001))
    pitch = 2.0 / 32 / far
    fs = sensor(pulse_energy=1e-3, aperture_diameter=0.1, beam=ScanBeam(0.0, tol=0.05),
                samples=256)
    frame = scan(sc, flash(32, 32, ifov_deg=math.degrees(math.atan(pitch))),
                 Platform.static((-far, 0, 0)), fs, keep_waveforms=True)
    total = sum(block.sum() for block in frame.waveforms)
    fluence = 1e-3 / (32 * 32 * (pitch * far) ** 2)
    flood = Sensor(standoff=far, beam=FloodBeam(radius=5.0), aperture_diameter=0.1,
                   pulse_energy=fluence * math.pi * 25.0)
    sino = ml.simulate(sc, ml.Ladar([180.0], np.linspace(-1, 1, 41)), model="mesh",
                       mode="3d", radiometry="power", sensor=flood, ray_spacing=2e-3)
    assert total == pytest.approx(sino.values.sum(), rel=1e-5)
