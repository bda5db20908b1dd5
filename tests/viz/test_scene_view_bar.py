"""The scene viewer keeps its colour bar's slot clear (a user trial: pyvista's nut.ply seen
from the ladar at 640 x 480, the bar's title "log10 F cos(theta) [1/sr]" ran over the lit
target, white on white, and the ray grid's yellow frame crossed the bar), checked on the
pixels rendered off screen; a view already clear of it is drawn as before."""

from __future__ import annotations

import numpy as np
import pytest

import meshladar as ml
from meshladar.materials import ALUMINUM, DARK_GRAY

from _rendering import slot_left  # noqa: E402  (tests/, on the path with the conftest)
from test_pyvista_viewer import rendering  # noqa: F401  (the off-screen probe)

#: A pixel within this of a colour (each channel, of 1) is drawn in it.
COLOUR_TOL = 0.08


def _is(img, color):
    return np.all(np.abs(img[..., :3] / 255.0 - np.asarray(color)) < COLOUR_TOL, axis=-1)


@pytest.mark.parametrize("size", [(640, 480), (900, 700)])
def test_nothing_of_the_scene_is_drawn_in_the_colour_bars_slot(size):
    from meshladar.viz import viewer

    pair = ml.phantoms.scene("disk_pair", large=DARK_GRAY, small=ALUMINUM)
    shown = viewer.show_scene(pair, view_angle_deg=0.0, camera="view", log_scale=True,
                              off_screen=True, window_size=size)
    img = shown.image
    drawn = _is(img, (1.0, 1.0, 0.0)) | _is(img, viewer.SHADOW_COLOR)   # frame, shadow
    assert drawn.sum() > 500
    left = slot_left(shown)
    assert left > 0.5 * size[0]
    assert drawn[:, left - 2:].sum() == 0
