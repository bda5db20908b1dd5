"""The scene viewer keeps its colour bar's slot clear (a user trial: pyvista's nut.ply seen
from the ladar at 640 x 480, the bar's title "log10 F cos(theta) [1/sr]" ran over the lit
target, white on white, and the ray grid's yellow frame crossed the bar), checked on the
pixels rendered off screen; a view already clear of it is drawn as before."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.ndimage import binary_erosion

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


#: The legend's own coloured pixels: its icons, in the first part of its box's width.
ICON_SHARE = 0.12


@pytest.mark.parametrize("size", [(640, 480), (720, 540), (900, 700)])
def test_nothing_of_the_scene_is_drawn_under_the_legend(size):
    """The tour's view (the pair from 20°, with its ladar's hits and iso-range planes): the
    ray grid's frame, the planes and the disks' hits ran under the legend at the top left
    (the translucent box dimmed them: 11,672 coloured pixels in it at 720 x 540). Inside
    the legend's box only its icons are coloured (its text is white on grey)."""
    from meshladar.viz import viewer

    pair = ml.phantoms.scene("disk_pair", large=DARK_GRAY, small=ALUMINUM)
    lad = ml.Ladar(np.arange(0.0, 360.0, 1.0), np.linspace(-0.8, 0.8, 513))
    shown = viewer.show_scene(pair, view_angle_deg=20.0, ladar=lad, off_screen=True,
                              window_size=size)
    img = shown.image[..., :3] / 255.0
    h, w = img.shape[:2]
    x0, y0, x1, y1 = shown.legend.box
    box = img[int((1 - y1) * h):int((1 - y0) * h), int(x0 * w):int(x1 * w)]
    coloured = np.nonzero(((box.max(-1) - box.min(-1)) > COLOUR_TOL).any(axis=0))[0]
    assert coloured.size and coloured.max() < ICON_SHARE * box.shape[1], coloured.max()
    drawn = _is(shown.image, (1.0, 1.0, 0.0))             # the frame, clear of the bars
    left = min(int(box[0] * w) for _, box in shown.scalar_bars)
    assert drawn.sum() > 500 and drawn[:, left - 2:].sum() == 0


@pytest.mark.parametrize("size", [(120, 90), (60, 45)])
def test_a_window_with_no_room_beside_its_bars_keeps_the_view(size, monkeypatch):
    """A review: at 120 pixels or less the bars' slot leaves no room, and the fit's scale
    came out negative (the camera's angle set below zero, clamped by VTK to 1e-8 degrees:
    nothing to see). The view is then kept as it is (pyvista's 30 degrees)."""
    from meshladar.viz import viewer

    angles = []
    fit = viewer._clear_of_bars

    def spy(plotter, xyz, **kw):
        fit(plotter, xyz, **kw)
        angles.append(plotter.camera.GetViewAngle())

    monkeypatch.setattr(viewer, "_clear_of_bars", spy)
    shown = viewer.show_scene(ml.phantoms.scene("disk_pair"), view_angle_deg=20.0,
                              off_screen=True, window_size=size)
    assert shown.image.shape[:2] == (size[1], size[0])
    assert angles == [30.0]


#: A slice's grey, clim (0, 2) at value 1: each channel near 128 of 255.
SLICE_GREY = (0.5, 0.5, 0.5)


def _in_slot(shown, drawn):
    """``drawn`` (a pixel mask) right of the bar's slot's left edge, less the bar itself
    (its colours are the scene's) and a 2-pixel rim around it, and less lines thinner
    than 3 pixels (the anti-aliased edges of the bar's white text are grey too)."""
    h, w = drawn.shape
    (_, (x0, y0, x1, y1)), = shown.scalar_bars
    drawn = binary_erosion(drawn, np.ones((3, 3), bool))
    drawn[max(0, int((1 - y1) * h) - 2):int((1 - y0) * h) + 2,
          max(0, int(x0 * w) - 2):int(x1 * w) + 2] = False
    return drawn[:, slot_left(shown) - 2:]


@pytest.mark.parametrize("size", [(640, 480), (900, 700)])
def test_a_slice_is_drawn_clear_of_its_bar_and_legend(size):
    """The default view of a slice over the disk pair: the slice ran under its colour bar,
    whose title ('reconstruction [radiance / area]', white) was lost on a bright slice,
    and its top rows under the legend. Now no pixel of the slice lies in the bar's slot
    and its top row is below the legend's box."""
    from meshladar.viz import viewer

    pair = ml.phantoms.scene("disk_pair")
    image = ml.Image(np.ones((64, 64)), 1.0)
    shown = viewer.show_slice(image, scene=pair, clim=(0.0, 2.0), off_screen=True,
                              window_size=size)
    grey = _is(shown.image, SLICE_GREY)
    h = shown.image.shape[0]
    assert grey.sum() > 0.2 * grey.size
    assert _in_slot(shown, grey).sum() == 0
    rows = np.nonzero(binary_erosion(grey, np.ones((3, 3), bool)).any(axis=1))[0]
    assert rows.min() >= int((1 - shown.legend.box[1]) * h)


@pytest.mark.parametrize("size", [(400, 300), (640, 480)])
def test_the_bounce_view_draws_nothing_under_its_legend(size):
    """A Lambertian ball seen obliquely with its sampled paths: the paths and the ball's
    top ran under the legend (949 coloured pixels in its box at 400 x 300)."""
    from meshladar.viz import bounce_view

    ball = ml.Scene.from_parts([ml.meshes.sphere((0, 0, 0), 0.5, 0, subdivisions=3)],
                               [ml.brdf.Lambertian(0.9)])
    shown = bounce_view.show_bounces(ball, view_vector=(0.3, 0.2, 1.0), off_screen=True,
                                     window_size=size)
    img = shown.image[..., :3] / 255.0
    h, w = img.shape[:2]
    x0, y0, x1, y1 = shown.legend.box
    box = img[int((1 - y1) * h):int((1 - y0) * h), int(x0 * w):int(x1 * w)]
    coloured = ((box.max(-1) - box.min(-1)) > COLOUR_TOL)
    assert coloured[:, int(ICON_SHARE * box.shape[1]):].sum() == 0
    assert _is(shown.image, bounce_view.PATH_COLOR).sum() > 200


@pytest.mark.parametrize("size", [(400, 400), (500, 700)])
def test_a_volume_rendering_is_drawn_clear_of_its_bar(size):
    """pyvista's isometric view of a stack drawn as a volume ran under the bar's slot in
    a square or tall window (2039 of its pixels at 400 x 400); now clear of it. The
    volume's magma colours are told from the bar's grey text by their hue."""
    from meshladar.viz import viewer

    x = np.linspace(-1, 1, 32)
    X, Y = np.meshgrid(x, x)
    zs = np.linspace(-0.5, 0.5, 8)
    images = [ml.Image(3.0 * (np.hypot(X, Y) < 0.8), 1.0) for _ in zs]
    shown = viewer.show_volume(images, zs, render="volume", off_screen=True,
                               window_size=size)
    rgb = shown.image[..., :3].astype(int)
    lit = (rgb.max(axis=-1) - rgb.min(axis=-1)) > 30
    assert lit.sum() > 2000
    assert _in_slot(shown, lit).sum() == 0
