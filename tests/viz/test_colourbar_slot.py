"""A point cloud's colour bar in its own slot (a user trial: at 900 x 700 the bar sat over
the points, its title tight on the top label; at 320 x 240 its title ran off the right
edge), checked on the pixels rendered off screen at both sizes."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import meshladar as ml
from meshladar.scan import Platform, ScanBeam, ScanSensor, rotating, scan

from test_pyvista_viewer import rendering  # noqa: F401  (the off-screen probe)

SIZES = ((900, 700), (320, 240))


@pytest.fixture(scope="module")
def shown():
    """The trial's kind of view: a room and a crate scanned by a spinning head, coloured by
    intensity (the bar titled "log10 photoelectrons"), at the default size and a small one."""
    from meshladar.viz import points

    room = trimesh.creation.box((20.0, 20.0, 6.0))
    crate = trimesh.creation.box((2.0, 3.0, 2.0))
    crate.apply_translation((5.0, 1.0, -2.0))
    sc = ml.Scene.from_meshes([(room, ml.brdf.Lambertian(0.5)),
                               (crate, ml.brdf.Lambertian(0.9))])
    pat = rotating(np.linspace(-10, 10, 8), rotation_hz=10, pulse_rate=4e4, duration=0.1)
    sen = ScanSensor(pulse_energy=1e-7, aperture_diameter=0.05, sample_rate=2e9,
                     beam=ScanBeam(0.0))
    cloud = scan(sc, pat, Platform.static((0.0, 0.0, 0.0)), sen)
    return {size: points.show_points(cloud, sc, off_screen=True, window_size=size)
            for size in SIZES}


def _pixels(img):
    """(points, text): the viridis points' pixels (coloured: the white background, the
    grey mesh and the black text are not) and the text's (dark grey)."""
    rgb = img[..., :3].astype(int)
    spread = rgb.max(axis=-1) - rgb.min(axis=-1)
    return spread > 40, (rgb.max(axis=-1) < 140) & (spread < 30)


def _lines(mask):
    """The runs of rows holding any of ``mask``: [(first, last)], top to bottom."""
    rows = np.nonzero(mask.any(axis=1))[0]
    return [(r[0], r[-1]) for r in np.split(rows, np.nonzero(np.diff(rows) > 1)[0] + 1)]


def _bar_region(shown):
    """The bar's region in pixels (x0, y0, x1, y1; y down): its box, its labels and its
    title (the text around the box), and the title's columns."""
    img = shown.image
    h, w = img.shape[:2]
    (_, (x0, y0, x1, y1)), = [(t, b) for t, b in shown.scalar_bars]
    top, bottom, left = int((1 - y1) * h) - 40, int((1 - y0) * h) + 8, int(x0 * w) - 80
    _, text = _pixels(img)
    near = np.zeros_like(text)
    near[max(0, top):bottom, max(0, left):] = text[max(0, top):bottom, max(0, left):]
    ys, xs = np.nonzero(near)
    first, last = _lines(near)[0]                            # the title: the top line
    cols = np.nonzero(near[first:last + 1].any(axis=0))[0]
    region = (min(xs.min(), int(x0 * w)), min(ys.min(), int((1 - y1) * h)),
              max(xs.max(), int(np.ceil(x1 * w))), max(ys.max(), int(np.ceil((1 - y0) * h))))
    return region, (cols.min(), cols.max()), near


@pytest.mark.parametrize("size", SIZES)
def test_no_point_is_drawn_under_the_colour_bar_or_its_title(shown, size):
    """The bar's region (box, labels, title) holds no point's pixel but the bar's own
    colours; nor does the slot, the window's right part from the region's left edge: the
    scene is framed left of it. Points are drawn (the scene still fills its part)."""
    img = shown[size].image
    w, h = size
    (rx0, ry0, rx1, ry1), _, _ = _bar_region(shown[size])
    (_, (x0, y0, x1, y1)), = shown[size].scalar_bars
    dots, _ = _pixels(img)
    assert dots.sum() > 0.01 * w * h
    strip = np.zeros_like(dots)                # the bar's colours: the box's left part
    strip[int((1 - y1) * h) - 2:int(np.ceil((1 - y0) * h)) + 2,
          int(x0 * w) - 2:int(x0 * w + 0.375 * (x1 - x0) * w) + 3] = True
    region = np.zeros_like(dots)
    region[ry0:ry1 + 1, rx0:rx1 + 1] = True
    assert (dots & region & ~strip).sum() == 0
    slot = np.zeros_like(dots)
    slot[:, rx0:] = True
    assert (dots & slot & ~strip).sum() == 0
    assert dots[:, :rx0].any(axis=0).sum() > 0.5 * rx0     # the points span their part


def test_the_title_is_whole_inside_the_window_and_clear_of_the_top_label(shown):
    """At 320 x 240 the title "log10 photoelectrons" ran off the right edge (its last
    letters cut): now whole (as wide as at 900 x 700, where it fits), a margin from either
    edge; and a blank band of at least 12 rows parts it from the top label below it."""
    widths = {}
    for size in SIZES:
        w, _ = size
        _, (c0, c1), near = _bar_region(shown[size])
        assert c0 >= 4 and c1 <= w - 5
        widths[size] = c1 - c0 + 1
        (_, title_end), (label_start, _) = _lines(near)[:2]
        assert label_start - title_end - 1 >= 12
    assert widths[SIZES[1]] == widths[SIZES[0]] > 100
    assert [bar.title for bar in shown[SIZES[1]].scalar_bars] == ["log10 photoelectrons"]
