"""Where a sinogram's target lies (meshladar.reconstruct.framing), against targets placed
by hand: a disk far off the axis the views turn about, and the default image that holds it
small (a user's trial: pyvista's nut moved 1e4 units away reconstructed into streaks in a
square 2.8e4 wide, without a word)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import meshladar as ml
from meshladar.brdf import Lambertian
from meshladar.reconstruct.framing import FRAME_MARGIN, check_frame, target_frame

#: The disk: centre and radius, and the bins' half-span (the default square's half-width).
CENTRE, RADIUS, REACH = (30.0, -20.0), 1.0, 40.0


def _far_disk(n_bins=2048, views=180):
    scene = ml.Scene([ml.Disk(CENTRE, RADIUS, Lambertian(0.5))])
    ladar = ml.Ladar(np.arange(views) * 360.0 / views, np.linspace(-REACH, REACH, n_bins + 1))
    return ml.simulate(scene, ladar)


def test_the_frame_is_the_targets_centre_and_holds_it():
    """The centre within two bins of the disk's; the half-width holds the disk (at least
    its radius: a lit half-disk is R deep) and is FRAME_MARGIN × at most its diameter
    plus two bins."""
    sino = _far_disk()
    (cx, cy), half = target_frame(sino)
    width = 2 * REACH / 2048
    assert np.hypot(cx - CENTRE[0], cy - CENTRE[1]) < 2 * width
    assert RADIUS <= half <= FRAME_MARGIN * (2 * RADIUS + 2 * width)


def test_the_default_square_warns_and_the_named_frame_finds_the_disk():
    """fbp's default square (the bins' reach, 40) holds the disk at 3 % of its width: a
    warning names center=(…) and extent=…; the image on that frame has its brightest
    pixel on the disk's rim (a reflective disk reconstructs as its lit boundary)."""
    sino = _far_disk()
    with pytest.warns(ml.errors.MeshladarWarning, match=r"fills about [\d.]+ % .*"
                                                        r"center=\(([-\d.]+), ([-\d.]+)\) "
                                                        r"and extent=([\d.]+) frame it"):
        ml.fbp(sino, size=64)
    (cx, cy), half = target_frame(sino)
    image = ml.fbp(sino, size=256, extent=half, center=(cx, cy))
    i, j = np.unravel_index(np.argmax(image.values), image.values.shape)
    r = np.hypot(image.x[j] - CENTRE[0], image.y[i] - CENTRE[1])
    assert abs(r - RADIUS) < 0.1
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ml.fbp(sino, size=64, extent=half, center=(cx, cy))        # given: not checked
        check_frame(sino, 2 * half, (cx, cy))                       # framed: no warning


def test_a_centred_target_and_a_narrow_arc_of_views_are_not_warned_of():
    """The paper's disk on the axis fills its default square; views over 10 degrees
    cannot tell a centre (None)."""
    disk = ml.phantoms.load("disk")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ml.fbp(ml.simulate(disk.scene, disk.ladar), size=32)
    narrow = ml.simulate(disk.scene, ml.Ladar(np.linspace(0.0, 10.0, 11),
                                              disk.ladar.bin_edges))
    assert target_frame(narrow) is None


def test_a_mirror_disks_glint_is_framed_whole():
    """A review: a near-mirror disk's returns are its glint alone (no depth), so the frame
    took it for 0.28 wide and the warning advised cropping the radius-5 disk away. The
    glint stands |d| = R in front of the centre: the frame holds 2|d|, and the default
    square (which holds the disk) is not warned of."""
    scene = ml.Scene([ml.Disk((0.0, 0.0), 5.0, ml.SandfordRobertson(0.0, 0.1, 0.0, 0.005))])
    sino = ml.simulate(scene, ml.Ladar(np.arange(180) * 2.0, np.linspace(-6.0, 6.0, 513)))
    (cx, cy), half = target_frame(sino)
    assert np.hypot(cx, cy) < 0.05 and half >= 5.0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ml.fbp(sino, size=32)
