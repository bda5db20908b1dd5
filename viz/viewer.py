"""The pyvista 3-D viewer: scenes coloured by their return, hits, slices and volumes.

Every entry point takes ``off_screen`` and ``screenshot``: on a desktop it opens a window
(the plotter is the returned record's ``plotter``); off screen (a headless machine, a test)
it renders the image array (height, width, 3), the record's ``image``, writing
``screenshot`` if given. With no display, VTK is
pointed at its EGL window (Mesa's software renderer: Debian packages libegl1 and
libgl1-mesa-dri), so nothing needs Xvfb.

Colours: lit faces by their return F(θ)·cos θ for the chosen view (monostatic, grey scale,
lighting off so the colour is the value), faces that face the ladar but are hidden by
another face (of this part or another) in ``shadow_color``, faces turned away in ``back_color``; with a ladar, the
first hits as points coloured by range bin (viridis) and iso-range planes in cyan; the
beam and the ray grid's footprint in yellow. Each quantity has one titled colour bar in a
fixed slot at the right edge; a legend at the top left names the flat colours drawn.

Each entry point returns a :class:`Shown` record: the image (off screen) or the plotter
(on a desktop), with the figure's legend and colour bars (their titles and boxes); no
module state is kept between calls. ``np.asarray(shown)`` is the image, so
``ax.imshow(shown)`` keeps working.

The scene viewer is defined here; the slices and volumes (:func:`show_slice`,
:func:`show_volume`, :func:`volume_surface`, :func:`volume_iso`) in the private
``_reconstruction_view`` beside it, and the frame they share in ``_frame``; all are
importable from here.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from meshladar import Scene
from meshladar._validate import check_count, check_real, unit_vectors
from meshladar.errors import ParameterError
from meshladar.forward.mesh import first_hits, occluded

from ._frame import (Legend, ScalarBar, Shown, _bar, _clear_of_bars, _finish,
                     _headless_window, _legend, _mesh_scene, _pyvista)
from ._reconstruction_view import show_slice, show_volume, volume_iso, volume_surface

__all__ = ["show_scene", "show_slice", "show_volume", "volume_surface", "volume_iso",
           "face_returns", "SHADOW_COLOR", "BACK_COLOR", "CAMERAS", "Shown", "Legend",
           "ScalarBar"]

#: Colour of faces that face the ladar but are shadowed by another face.
SHADOW_COLOR = (1.0, 0.0, 1.0)
#: Named camera placements of show_scene: "oblique" beside and above the ladar (default),
#: "view" along the beam from the ladar.
CAMERAS = ("oblique", "view")
#: Colour of faces turned away from the ladar.
BACK_COLOR = (0.15, 0.15, 0.35)


def _view_vector(view_angle_deg, view_vector):
    if view_vector is not None:
        w = unit_vectors("view_vector", view_vector)
        if w.shape != (3,):
            raise ParameterError(f"view_vector must be one direction (x, y, z); got shape "
                                 f"{w.shape}")
        return w
    angle = 90.0 if view_angle_deg is None else check_real("view_angle_deg", view_angle_deg)
    phi = np.deg2rad(angle)
    return np.array([np.cos(phi), np.sin(phi), 0.0])


def _check_view_options(scene, iso_ranges, window_size, segments, camera=None):
    if not isinstance(scene, Scene):
        raise ParameterError(f"scene must be a meshladar.Scene; got {type(scene).__name__}")
    check_count("iso_ranges", iso_ranges, low=0)
    check_count("segments", segments, low=3)
    if (not isinstance(window_size, (tuple, list)) or len(window_size) != 2
            or not all(isinstance(n, (int, np.integer)) and not isinstance(n, bool)
                       and 1 <= n <= 16384 for n in window_size)):
        raise ParameterError(f"window_size must be (width, height) in pixels, each in "
                             f"[1, 16384]; got {window_size!r}")
    if isinstance(camera, str) and camera not in CAMERAS:
        raise ParameterError(f"camera must be one of {', '.join(CAMERAS)} or a pyvista "
                             f"camera position; got {camera!r}")


def face_returns(scene, w, *, segments=256):
    """Per face of the (tessellated) scene: the monostatic return F(θ)·cos θ for view ``w``
    and a state: 0 lit, 1 shadowed (facing the ladar, but the ray from its centroid toward
    the ladar meets another face), 2 turned away. Returns (mesh scene, returns (m,),
    state (m,)).

    Parameters
    ----------
    scene : Scene
        A mesh scene, or an analytic one, tessellated here into prisms of ``segments``
        sides as tall as its bounding-circle radius.
    w : (3,) numpy.ndarray
        The view direction, from the scene toward the ladar, of unit length (neither
        checked nor normalised here: :func:`show_scene` passes a checked one).
    segments : int, keyword-only
        Sides of an analytic scene's prisms (default 256).

    Returns
    -------
    mesh : Scene
        The mesh scene the faces belong to (``scene`` itself when it is a mesh); faces are
        numbered part by part in its order.
    returns : (m,) numpy.ndarray of float64
        Each lit face's F(θ)·cos θ in 1/sr, θ the angle between its normal and ``w``
        (its coating's ``monostatic(θ, projected=True)``);
        0 for shadowed and turned-away faces.
    state : (m,) numpy.ndarray of int
        0 lit, 1 shadowed, 2 turned away (cos θ ≤ 0).
    """
    mesh = _mesh_scene(scene, segments)
    v, f = _joined(mesh)
    mat = np.concatenate([p.material for p in mesh.parts])
    tri = v[f]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    cos_t = n @ w
    facing = cos_t > 0
    blocked = np.zeros(len(f), bool)
    blocked[facing] = occluded(mesh, tri[facing].mean(axis=1), w)
    state = np.where(~facing, 2, np.where(blocked, 1, 0))
    ret = np.zeros(len(f))
    for k, m in enumerate(mesh.materials):
        sel = mat == k
        ret[sel] = m.monostatic(np.arccos(np.clip(cos_t[sel], -1, 1)), projected=True)
    return mesh, np.where(state == 0, ret, 0.0), state


@_headless_window
def show_scene(scene, *, view_angle_deg=None, view_vector=None, ladar=None, segments=256,
               show_rays=True, show_hits=True, iso_ranges=6, log_scale=False,
               shadow_color=SHADOW_COLOR, back_color=BACK_COLOR, off_screen=False,
               screenshot=None, window_size=(900, 700), camera=None):
    """Show a scene coloured by its return for one view.

    A legend in the top-left corner names the flat colours drawn (shadowed, turned away,
    beam and ray grid, iso-range planes); colour bars sit at the right edge.

    Parameters
    ----------
    scene : Scene
        A mesh scene, or an analytic one (drawn as prisms of ``segments`` sides).
    view_angle_deg, view_vector :
        The view: an angle about z (default 90°, the paper's Fig. 1) or any vector.
        ``view_vector`` (3,), normalised here, wins when both are given.
    ladar : Ladar, optional
        For hits coloured by range bin and iso-range planes at its bin edges.
    segments : int
        Sides of an analytic scene's prisms, ≥ 3 (default 256); their height is the
        scene's bounding-circle radius.
    show_rays, show_hits : bool
        Draw the ray grid's footprint and the view direction; draw first hits coloured by
        range bin (with ``ladar`` only). Default True.
    iso_ranges : int
        Number of iso-range planes drawn, ≥ 0 (0: none; default 6).
    log_scale : bool
        Colour lit faces by log10 of their return (glints next to diffuse coatings).
    shadow_color, back_color : (3,) float
        RGB in [0, 1] of shadowed faces and of faces turned away (default
        :data:`SHADOW_COLOR`, :data:`BACK_COLOR`).
    off_screen, screenshot, window_size :
        See the module docstring. ``window_size`` is (width, height) in pixels, each
        integer in [1, 16384] (default (900, 700)).
    camera : "oblique", "view" or a pyvista camera position
        "view" looks along the beam from the ladar; "oblique" (default, also None) from
        beside and above the ladar, so the lit side and the shadows both show.

    Returns
    -------
    Shown
        Off screen, its ``image`` (height, width, 3) (also written to ``screenshot`` when
        given); on a desktop, its ``plotter`` (shown with ``plotter.show``). With the
        ``legend`` and the ``scalar_bars`` drawn.

    Raises
    ------
    ParameterError
        When ``scene`` is not a Scene, ``iso_ranges`` < 0, ``segments`` < 3,
        ``window_size`` is not two integers in [1, 16384], ``camera`` is a string other
        than "oblique" or "view", ``view_vector`` is not one finite non-zero (3,)
        direction, or ``view_angle_deg`` is not a finite number.
    ImportError
        When pyvista is not installed.
    """
    _check_view_options(scene, iso_ranges, window_size, segments, camera)
    w = _view_vector(view_angle_deg, view_vector)
    pv = _pyvista()
    mesh, ret, state = face_returns(scene, w, segments=segments)
    v, _ = _joined(mesh)
    plotter = pv.Plotter(off_screen=off_screen, window_size=window_size)
    plotter.set_background("black")
    legend = _draw_faces(plotter, pv, mesh, ret, state, log_scale=log_scale,
                         colors=(shadow_color, back_color))
    frame = _Frame(0.5 * (v.min(axis=0) + v.max(axis=0)), float(np.ptp(v, axis=0).max()), w)
    drawn = [v]
    if show_rays:
        legend += _draw_rays(plotter, pv, frame, drawn, arrow=camera != "view")
    if ladar is not None and show_hits:
        legend += _draw_hits(plotter, pv, mesh, ladar, frame, iso_ranges)
    plotter.camera_position = _camera_position(camera, frame)
    legend = _legend(plotter, legend)
    if camera is None or isinstance(camera, str):     # a named view: clear of bar and legend
        _clear_of_bars(plotter, np.vstack(drawn), grow=False, legend=legend)
    return _finish(plotter, off_screen, screenshot)


class _Frame(NamedTuple):
    """Where the scene sits: its box ``center`` (3,), ``size`` (largest side) and the view
    ``w`` (3,)."""

    center: np.ndarray
    size: float
    w: np.ndarray


def _joined(mesh):
    """All parts' vertices (n, 3) and faces (m, 3) in one numbering."""
    v = np.concatenate([p.vertices for p in mesh.parts])
    offs = np.cumsum([0] + [len(p.vertices) for p in mesh.parts])[:-1]
    return v, np.concatenate([p.faces + o for p, o in zip(mesh.parts, offs)])


def _draw_faces(plotter, pv, mesh, ret, state, *, log_scale, colors):
    """Lit faces by their return (grey, a colour bar), shadowed and turned-away faces in
    ``colors`` (shadow, back); returns the legend's entries."""
    v, f = _joined(mesh)

    def poly(sel):
        cells = np.hstack([np.full((sel.sum(), 1), 3), f[sel]]).ravel()
        return pv.PolyData(v, cells)

    lit = state == 0
    legend = []
    if lit.any():
        pd = poly(lit)
        vals = ret[lit]
        pd.cell_data["return"] = np.log10(np.maximum(vals, 1e-12)) if log_scale else vals
        plotter.add_mesh(pd, scalars="return", cmap="gray", lighting=False,
                         show_scalar_bar=True,
                         scalar_bar_args=_bar("log10 F cos(theta) [1/sr]" if log_scale
                                              else "F cos(theta) [1/sr]", 0))
    for k, colour, label in ((1, colors[0], "shadowed (another face in the way)"),
                             (2, colors[1], "turned away from the ladar")):
        if (state == k).any():
            plotter.add_mesh(poly(state == k), color=colour, lighting=False)
            legend.append((label, colour))
    return legend


def _draw_rays(plotter, pv, frame, drawn, *, arrow):
    """The beam (an arrow, unless seen end-on) and the ray grid's footprint, in yellow;
    their points appended to ``drawn``."""
    center, size, w = frame
    if arrow:          # seen end-on from the ladar the arrow is a disc: omitted
        # outside the scene's extent, so it covers none of it
        shaft = pv.Arrow(start=center + 1.25 * size * w, direction=-w, scale=0.4 * size)
        plotter.add_mesh(shaft, color="yellow", lighting=False)
        drawn.append(np.asarray(shaft.points))
    plane = pv.Plane(center=center + 0.8 * size * w, direction=w, i_size=1.1 * size,
                     j_size=1.1 * size, i_resolution=1, j_resolution=1)
    plotter.add_mesh(plane, style="wireframe", color="yellow", line_width=2, lighting=False)
    drawn.append(np.asarray(plane.points))
    return [("ladar beam and ray grid", (1.0, 1.0, 0.0))]


def _draw_hits(plotter, pv, mesh, ladar, frame, iso_ranges):
    """First hits coloured by range bin (a colour bar) and up to ``iso_ranges`` iso-range
    planes at the ladar's bin edges; returns the legend's entries."""
    center, size, w = frame
    pts, _, rng = first_hits(mesh, w, ray_spacing=size / 150.0)
    k = np.searchsorted(ladar.bin_edges, rng, side="right") - 1
    cloud = pv.PolyData(pts)
    cloud.point_data["range bin"] = k
    plotter.add_mesh(cloud, scalars="range bin", cmap="viridis", point_size=3,
                     render_points_as_spheres=False, lighting=False,
                     scalar_bar_args=_bar("first hits: range bin", 1))
    if not iso_ranges:
        return []
    edges = ladar.bin_edges
    inside = edges[(edges >= rng.min()) & (edges <= rng.max())] if rng.size else []
    for r in np.asarray(inside)[:: max(1, len(inside) // iso_ranges)][:iso_ranges]:
        plane = pv.Plane(center=center - (r + center @ w) * w, direction=w,
                         i_size=size, j_size=size, i_resolution=1, j_resolution=1)
        plotter.add_mesh(plane, color="cyan", opacity=0.08, lighting=False)
    return [("iso-range planes (bin edges)", (0.0, 1.0, 1.0))] if len(inside) else []


def _camera_position(camera, frame):
    """A pyvista camera position for ``camera`` ("view", "oblique", None or a position)."""
    center, size, w = frame
    if camera == "view":                     # look along the beam, from the ladar
        return [tuple(center + 2.5 * size * w), tuple(center),
                (0.0, 0.0, 1.0) if abs(w[2]) < 0.9 else (0.0, 1.0, 0.0)]
    if camera is None or camera == "oblique":   # beside and above the ladar
        side = np.cross([0.0, 0.0, 1.0], w)
        side = side / np.linalg.norm(side) if np.linalg.norm(side) > 1e-9 else \
            np.array([1.0, 0.0, 0.0])
        eye = w + 0.9 * side + np.array([0.0, 0.0, 0.7])
        return [tuple(center + 2.8 * size * eye / np.linalg.norm(eye)), tuple(center),
                (0.0, 0.0, 1.0)]
    return camera
