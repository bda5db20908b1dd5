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
