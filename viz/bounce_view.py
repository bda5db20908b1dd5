"""The bounce viewer: a mesh scene's faces coloured by the order of bounces whose return
dominates there for one view, and a few sampled paths drawn from the ladar through their
bounces and on toward the receiver (:mod:`meshladar.forward.bounce_paths`)."""

from __future__ import annotations

import numpy as np

from meshladar.forward.bounce_paths import dominant_order, face_orders, sample_paths

from ._frame import _clear_of_bars, _finish, _headless_window, _legend, _pyvista
from .viewer import _camera_position, _check_view_options, _Frame, _joined, _view_vector

__all__ = ["show_bounces", "ORDER_COLORS", "PATH_COLOR", "DARK_COLOR"]

#: Faces by the order that dominates their return: 1, 2, 3, 4 and more.
ORDER_COLORS = ((0.75, 0.75, 0.75), (1.0, 0.55, 0.0), (0.9, 0.1, 0.1), (0.6, 0.2, 0.8))
#: Faces that return nothing for the view.
DARK_COLOR = (0.12, 0.12, 0.3)
#: The sampled paths.
PATH_COLOR = (1.0, 1.0, 0.0)


@_headless_window
def show_bounces(scene, *, view_angle_deg=None, view_vector=None, bounces=3, paths=12,
                 samples=1 << 14, seed=0, off_screen=False, screenshot=None,
                 window_size=(900, 700), camera=None):
    """Show which order of bounces dominates each face's return, and sampled paths.

    Parameters
    ----------
    scene : Scene
        A mesh scene.
    view_angle_deg, view_vector :
        The view, as :func:`meshladar.viz.viewer.show_scene`'s.
    bounces : int
        The highest order, 1 to 8 (default 3).
    paths : int
        Sampled paths drawn, each from a different first hit (default 12).
    samples : int
        Paths sampled for the faces' orders.
    seed : int
        Seeds both samplings.
    off_screen, screenshot, window_size, camera :
        As :func:`meshladar.viz.viewer.show_scene` (a named camera's picture, the scene
        and the paths, kept below or beside the legend).

    Returns
    -------
    Shown
        The image (off screen) or the plotter, with the legend (one entry per order
        drawn, the paths, faces returning nothing).

    Raises
    ------
    ParameterError
        For an analytic scene, a bad view, ``bounces``, ``paths``, ``window_size`` or
        ``camera``; ModelError for a coating without a bistatic evaluation.
    """
    _check_view_options(scene, 0, window_size, 3, camera)
    w = _view_vector(view_angle_deg, view_vector)
    order = dominant_order(face_orders(scene, w, bounces=bounces, samples=samples,
                                       seed=seed))
    trails = sample_paths(scene, w, paths=paths, bounces=bounces, seed=seed)
    pv = _pyvista()
    v, f = _joined(scene)
    plotter = pv.Plotter(off_screen=off_screen, window_size=window_size)
    plotter.set_background("black")
    legend = []
    for k in range(0, 5):
        sel = order == k if k < 4 else order >= 4
        if not sel.any():
            continue
        colour = DARK_COLOR if k == 0 else ORDER_COLORS[k - 1]
        cells = np.hstack([np.full((sel.sum(), 1), 3), f[sel]]).ravel()
        plotter.add_mesh(pv.PolyData(v, cells), color=colour, lighting=False)
        legend.append(("no return" if k == 0 else
                       f"order {k}{' or more' if k == 4 else ''} dominates", colour))
    frame = _Frame(0.5 * (v.min(axis=0) + v.max(axis=0)), float(np.ptp(v, axis=0).max()), w)
    drawn = [v]
    for pts in trails:
        line = np.vstack([pts[0] + frame.size * w, pts, pts[-1] + 0.5 * frame.size * w])
        plotter.add_mesh(pv.lines_from_points(line), color=PATH_COLOR, line_width=2,
                         lighting=False)
        drawn.append(line)
    if trails:
        legend.append((f"{len(trails)} sampled paths (in from the ladar, out toward it)",
                       PATH_COLOR))
    plotter.camera_position = _camera_position(camera, frame)
    legend = _legend(plotter, legend)
    if camera is None or isinstance(camera, str):     # a named view: clear of the legend
        _clear_of_bars(plotter, np.vstack(drawn), grow=False, legend=legend)
    return _finish(plotter, off_screen, screenshot)
