"""Whether off-screen rendering works here: a subprocess smoke test of pyvista (VTK
segfaults instead of raising when it is missing), shared by the viewer's, the command
line's and the notebooks' tests; and where a viewer's colour bar's slot begins."""

import numpy as np

_SMOKE = ("from meshladar.viz import viewer; pv = viewer._pyvista(); "
          "p = pv.Plotter(off_screen=True, window_size=(64, 48)); p.add_mesh(pv.Sphere()); "
          "img = p.screenshot(return_img=True); assert img.shape == (48, 64, 3)")


def slot_left(shown):
    """The leftmost column of a shown view's colour bar's slot: its box, or its title's
    first white pixel in the 40 rows above the box (the right half of the window),
    whichever is further left."""
    img = shown.image
    h, w = img.shape[:2]
    (_, (x0, _, _, y1)), = shown.scalar_bars
    top = int((1 - y1) * h)
    band = img[max(0, top - 40):top, w // 2:, :3].min(axis=-1) > 200     # white text
    cols = np.nonzero(band.any(axis=0))[0]
    return min(int(x0 * w), w // 2 + int(cols.min()) if cols.size else w)
