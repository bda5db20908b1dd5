"""A scan's point cloud in 3-D over its mesh (pyvista), coloured by a field of its returns.

``show_points(cloud, scene=None, color_by="intensity")``: the scene's faces in light grey,
half transparent, and every return as a point coloured by ``color_by`` with one titled
colour bar (its unit in the title): ``"intensity"`` (photoelectrons, on a log scale: a glint
and a matte wall differ by 10⁴; titled "log10 photoelectrons"), ``"range"`` (m), ``"return_number"``, ``"range_error"``
(measured minus true range, m, on a diverging map centred on 0: blue short, red long; false
alarms, which have no truth, in black), ``"doppler"`` (Hz, diverging), or the pattern's
``"channel"``, ``"scan_angle"`` (deg) or ``"emission_time"`` (s): a scan pattern's
footprint on the scene is a scan with a single-ray beam coloured by one of these. Off screen it
returns the rendered image (:class:`~meshladar.viz.viewer.Shown`), as every viewer entry
point does.

The bar sits in the viewers' fixed slot at the right edge, moved left where its title or
labels would leave the window, and the scene (its mesh and points) is framed in the rest of
the window: no point is drawn under the bar or its title, at any window size.
"""

from __future__ import annotations

import numpy as np

from meshladar import Scene
from meshladar._validate import check_choice
from meshladar.errors import ParameterError
from meshladar.scan import PointCloud

from ._frame import _bar, _clear_of_bars, _finish, _headless_window, _pyvista

__all__ = ["show_points", "COLOR_BY", "NOISE_COLOR"]

#: The fields a cloud can be coloured by, with the colour bar's title.
COLOR_BY = {"intensity": "log10 photoelectrons", "range": "range [m]",
            "return_number": "return number", "range_error": "range error [m]",
            "doppler": "Doppler [Hz]", "channel": "channel", "scan_angle": "scan angle [deg]",
            "emission_time": "emission time [s]"}
#: The colour of returns without truth (false alarms) when coloured by range error.
NOISE_COLOR = (0.0, 0.0, 0.0)
_DIVERGING = ("range_error", "doppler")


def _title(cloud, color_by):
    """The colour bar's title: another tool's LAS intensity is not photoelectrons."""
    if color_by == "intensity" and cloud.info.get("foreign"):
        return "log10 LAS intensity"
    return COLOR_BY[color_by]


def _check_fields(cloud, color_by):
    """Refuse colouring another tool's LAS (``info["fields"]``) by a field it lacks."""
    fields = cloud.info.get("fields")
    need = ("range", "true_range") if color_by == "range_error" else (color_by,)
    if fields is not None and not set(need) <= set(fields):
        usable = [c for c in COLOR_BY if c in fields]
        raise ParameterError(f"color_by={color_by!r}: {cloud.info.get('file', 'the cloud')} "
                             f"is another tool's LAS, without meshladar's {need[-1]}; "
                             f"colour it by one of {usable}")


def _values(cloud, color_by):
    pts = cloud.points
    if color_by == "intensity":
        return np.log10(np.maximum(pts["intensity"].astype(np.float64), 1e-3))
    if color_by == "range_error":
        return cloud.range_error
    return pts[color_by].astype(np.float64)


@_headless_window
def show_points(cloud, scene=None, *, color_by="intensity", point_size=4.0, off_screen=False,
                screenshot=None, window_size=(900, 700)):
    """Draw ``cloud``'s returns over ``scene``'s mesh (module docstring).

    Parameters
    ----------
    cloud : meshladar.scan.PointCloud
        The returns (:func:`meshladar.scan.scan`, :func:`meshladar.scan.read_las`; another
        tool's LAS read with ``foreign=True`` is coloured by the fields it holds, its
        intensity titled "log10 LAS intensity").
    scene : meshladar.Scene, optional
        The scene scanned, drawn under the points (default: the points alone).
    color_by : str
        One of :data:`COLOR_BY` (default ``"intensity"``).
    point_size : float
        Points' size in pixels (default 4).
    off_screen, screenshot, window_size
        As :func:`meshladar.viz.viewer.show_scene`'s.

    Returns
    -------
    Shown
        The image (off screen) or the plotter, the legend (None) and the colour bar.

    Raises
    ------
    ParameterError
        When ``cloud`` is not a PointCloud or holds no returns, ``scene`` is not a mesh
        Scene, or ``color_by`` is unknown or a field another tool's LAS lacks.
    """
    if not isinstance(cloud, PointCloud):
        raise ParameterError(f"cloud must be a meshladar.scan.PointCloud; got "
                             f"{type(cloud).__name__}")
    if len(cloud) == 0:
        raise ParameterError("cloud holds no returns: nothing to draw")
    if scene is not None and not (isinstance(scene, Scene) and scene.is_mesh):
        raise ParameterError("scene must be a mesh Scene (or None)")
    check_choice("color_by", color_by, tuple(COLOR_BY))
    _check_fields(cloud, color_by)
    title = _title(cloud, color_by)
    pv = _pyvista()
    plotter = pv.Plotter(off_screen=off_screen, window_size=list(window_size))
    plotter.set_background("white")
    if scene is not None:
        for part in scene.parts:
            faces = np.hstack([np.full((len(part.faces), 1), 3), part.faces]).ravel()
            plotter.add_mesh(pv.PolyData(part.vertices, faces), color=(0.8, 0.8, 0.8),
                             opacity=0.35, lighting=False)
    values = _values(cloud, color_by)
    known = np.isfinite(values)
    cloud_pts = pv.PolyData(cloud.xyz[known])
    cloud_pts[title] = values[known]
    span = np.abs(values[known]).max() if known.any() else 1.0
    plotter.add_mesh(cloud_pts, scalars=title, point_size=point_size,
                     render_points_as_spheres=False, lighting=False,
                     cmap="coolwarm" if color_by in _DIVERGING else "viridis",
                     clim=(-span, span) if color_by in _DIVERGING and span > 0 else None,
                     scalar_bar_args=dict(_bar(title), color="black"))
    if not known.all():
        plotter.add_mesh(pv.PolyData(cloud.xyz[~known]), color=NOISE_COLOR,
                         point_size=point_size, lighting=False)
    plotter.view_isometric()
    plotter.reset_camera()
    drawn = [cloud.xyz] + ([p.vertices for p in scene.parts] if scene is not None else [])
    drawn = np.concatenate(drawn)
    _clear_of_bars(plotter, drawn[np.isfinite(drawn).all(axis=1)])   # the bar's own slot
    return _finish(plotter, off_screen, screenshot)
