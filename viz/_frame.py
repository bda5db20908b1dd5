"""The frame every viewer figure shares: pyvista on demand, a headless EGL window, titled
colour bars in fixed slots (moved left where a title or its labels would leave the window;
a scene can be framed clear of them), the legend of flat colours, the mesh an analytic
scene is drawn as, and the :class:`Shown` record an entry point returns (image or plotter,
legend, colour bars) instead of module state."""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from meshladar.io import write_atomic

__all__ = ["Shown", "Legend", "ScalarBar"]


def _pyvista():
    try:
        import pyvista as pv
    except ImportError as exc:
        raise ImportError("the viewer needs pyvista: pip install 'meshladar[viz]'") from exc
    return pv


def _mesh_scene(scene, segments):
    """The scene as drawn: a mesh scene itself, an analytic one tessellated into prisms of
    ``segments`` sides as tall as its bounding-circle radius."""
    if scene.is_mesh:
        return scene
    (cx, cy), r = scene.bounding_circle()
    return scene.tessellate(segments, height=r)


def _headless_window(func):
    """Run a viewer entry point with VTK pointed at its EGL window when there is no
    display, restoring the environment afterwards (a user's session is left as it was)."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        key = "VTK_DEFAULT_OPENGL_WINDOW"
        headless = not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY")
        before = os.environ.get(key)
        if headless and before is None:
            os.environ[key] = "vtkEGLRenderWindow"
        try:
            return func(*args, **kwargs)
        finally:
            if headless and before is None:
                os.environ.pop(key, None)

    return wrapper


class ScalarBar(NamedTuple):
    """A colour bar drawn: its ``title`` and ``box`` (x0, y0, x1, y1) in viewport units."""

    title: str
    box: tuple


class Legend(NamedTuple):
    """The legend drawn: its ``labels`` (top to bottom) and ``box`` (x0, y0, x1, y1) in
    viewport units."""

    labels: tuple
    box: tuple


@dataclass(frozen=True, eq=False)
class Shown:
    """What a viewer entry point drew: ``image`` (height, width, 3) off screen (else None),
    ``plotter`` on a desktop (else None), its ``legend`` (None without one) and its
    ``scalar_bars``, for checks that they are titled and do not overlap.

    Attributes
    ----------
    image : (height, width, 3) uint8 array or None
        The rendered picture off screen; None when shown on a desktop.
    plotter : pyvista.Plotter or None
        The live plotter on a desktop; None off screen.
    legend : Legend or None
        The legend's entries and box, None without one.
    scalar_bars : tuple
        The scalar bars drawn, with their titles and boxes.
    """

    image: np.ndarray | None
    plotter: object
    legend: Legend | None
    scalar_bars: tuple

    def __array__(self, dtype=None, copy=None):
        if self.image is None:
            raise TypeError("shown on a desktop: no image (give off_screen=True)")
        return np.asarray(self.image, dtype=dtype)


def _bar(title, slot=0):
    """scalar_bar_args for a titled vertical colour bar in one of two fixed slots at the
    right edge (0: lower, 1: upper), so two bars never overlap."""
    return {"title": title, "vertical": True, "position_x": 0.8,
            "position_y": 0.06 + 0.48 * slot, "width": 0.08, "height": 0.38,
            "title_font_size": 12, "label_font_size": 10, "n_labels": 4, "fmt": "%.3g",
            "color": "white"}             # the backgrounds are black


def _legend(plotter, entries):
    """A legend of the flat colours drawn, ``entries`` [(label, colour)], in the top-left
    corner, clear of the colour bars' slots at the right edge."""
    if not entries:
        return
    height = 0.05 * len(entries)
    legend = plotter.add_legend(labels=[list(e) for e in entries],
                                bcolor=(0.12, 0.12, 0.12), size=(0.44, height),
                                loc="upper left", face="none", background_opacity=0.8)
    from vtkmodules.vtkCommonDataModel import vtkImageData

    # VTK colours an entry's text as its symbol: white text, and the colour as an icon
    for i, (_, colour) in enumerate(entries):
        icon = vtkImageData()
        icon.SetDimensions(16, 16, 1)
        icon.AllocateScalars(3, 3)                  # VTK_UNSIGNED_CHAR, RGB
        pixels = icon.GetPointData().GetScalars()
        rgb = [int(round(255 * c)) for c in colour]
        for k in range(16 * 16):                    # a light frame: dark colours show too
            edge = k % 16 in (0, 15) or k // 16 in (0, 15)
            pixels.SetTuple3(k, *((220, 220, 220) if edge else rgb))
        legend.SetEntryIcon(i, icon)
        legend.SetEntryColor(i, 1.0, 1.0, 1.0)
    return legend


def _box(actor):
    x, y = actor.GetPosition()
    w, h = actor.GetPosition2()
    return (x, y, x + w, y + h)


#: Pixels kept clear between a colour bar's slot and the window's edge or the scene.
_MARGIN = 6
#: Pixels between a bar's title and its frame: the top label, centred on the bar's top
#: edge, sits between them with room above it.
_TITLE_SEPARATION = 18


def _text_width(prop, text, dpi):
    """The width in pixels of ``text`` drawn with text property ``prop``."""
    from vtkmodules.vtkRenderingCore import vtkTextRenderer

    bbox = [0, 0, 0, 0]
    vtkTextRenderer().GetBoundingBox(prop, text, bbox, dpi)
    return bbox[1] - bbox[0] + 1


def _bar_slot(plotter):
    """Move each colour bar left until its title (centred over its box) and its labels
    are inside the window, and return the left edge, in pixels, of the slot the bars and
    their titles take at the right edge: the scene is kept left of it
    (:func:`_clear_of_bars`)."""
    width = plotter.window_size[0]
    dpi = plotter.ren_win.GetDPI()
    left = float(width)
    for bar in plotter.scalar_bars.values():
        bar.SetVerticalTitleSeparation(_TITLE_SEPARATION)
        box = bar.GetPosition2()[0] * width
        title = _text_width(bar.GetTitleTextProperty(), bar.GetTitle() or "", dpi)
        low, high = bar.GetLookupTable().GetRange()
        labels = max(_text_width(bar.GetLabelTextProperty(), bar.GetLabelFormat() % v, dpi)
                     for v in np.linspace(low, high, max(2, bar.GetNumberOfLabels())))
        x0 = min(bar.GetPosition()[0] * width,
                 width - _MARGIN - 0.5 * (box + title),          # the title inside
                 width - _MARGIN - box * bar.GetBarRatio() - 4 - labels,   # the labels
                 width - _MARGIN - box)
        x0 = max(0.0, x0)
        bar.SetPosition(x0 / width, bar.GetPosition()[1])
        left = min(left, x0, x0 + 0.5 * (box - title))
    return max(0.0, left - _MARGIN)


def _clear_of_bars(plotter, xyz, grow=True, legend=None):
    """Aim the camera so that points ``xyz`` (n, 3), the scene's extent, fill the window
    left of the colour bars' slot (:func:`_bar_slot`) and nothing drawn lies under a bar
    or its title; the view's direction is kept. Exact: a perspective view's angle scales
    its picture about the window's centre and its window centre shifts it. ``grow``
    False: the picture is only made smaller and moved as little as it must (a view that
    is clear of the bars is kept as it is). ``legend``: its actor, drawn already (the
    top-left corner): the picture's box is kept below it or right of it, whichever leaves
    it larger."""
    width, height = plotter.window_size
    right = _bar_slot(plotter) - _MARGIN
    cam = plotter.camera
    ndc = _projected(cam, np.asarray(xyz, np.float64), width / height)
    lo, hi = ndc.min(axis=0), ndc.max(axis=0)
    # the target, in normalised device coordinates: x in [margin, right], y in margins
    t_lo = np.array([2.0 * _MARGIN / width - 1.0, 2.0 * _MARGIN / height - 1.0])
    t_hi = np.array([2.0 * right / width - 1.0, 1.0 - 2.0 * _MARGIN / height])
    fit = _fit(lo, hi, t_lo, t_hi, grow)
    if fit is None:                  # a window too small for any room: the view as it is
        return
    scale, shift = fit
    if legend is not None:
        x0, y0, x1, _ = 2.0 * np.asarray(_box(legend)) - 1.0          # its box, NDC
        gap = 2.0 * _MARGIN / np.array([width, height])
        if (scale * lo - shift)[0] < x1 + gap[0] and (scale * hi - shift)[1] > y0 - gap[1]:
            fits = [f for f in (_fit(lo, hi, t_lo, np.array([t_hi[0], y0 - gap[1]]), grow),
                                _fit(lo, hi, np.array([x1 + gap[0], t_lo[1]]), t_hi, grow))
                    if f is not None]                      # below it, or beside it
            scale, shift = max(fits, key=lambda f: f[0]) if fits else (scale, shift)
    if cam.GetParallelProjection():
        cam.SetParallelScale(cam.GetParallelScale() / scale)
    else:
        half = np.radians(cam.GetViewAngle()) / 2.0
        cam.SetViewAngle(float(np.degrees(2.0 * np.arctan(np.tan(half) / scale))))
    cam.SetWindowCenter(*(np.asarray(cam.GetWindowCenter()) * scale + shift))
    plotter.reset_camera_clipping_range()


def _corners(plotter):
    """The eight corners of the box around everything the plotter draws in 3-D (its
    ``bounds``): the points to keep clear of its bars and legend."""
    x0, x1, y0, y1, z0, z1 = plotter.bounds
    return np.array([(x, y, z) for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)])


def _fit(lo, hi, t_lo, t_hi, grow):
    """(scale, shift) taking the picture's box [lo, hi] into [t_lo, t_hi] (normalised
    device coordinates: x' = scale x − shift), filling it; ``grow`` False: made no larger,
    moved as little as it must. None where the target has no room (a window a few dozen
    pixels wide: a negative scale would mirror the picture)."""
    if np.any(t_hi <= t_lo):
        return None
    span = hi - lo
    fits = np.where(span > 1e-9, (t_hi - t_lo) / np.maximum(span, 1e-9), np.inf)
    scale = float(fits.min()) if np.isfinite(fits).any() else 1.0    # one point: kept
    shift = scale * 0.5 * (lo + hi) - 0.5 * (t_lo + t_hi)
    if not grow:
        scale = min(scale, 1.0)
        shift = np.clip(0.0, scale * hi - t_hi, scale * lo - t_lo)
    return scale, shift


def _projected(cam, xyz, aspect):
    """Points' (x, y) in normalised device coordinates ([-1, 1] across the window)."""
    m = cam.GetCompositeProjectionTransformMatrix(aspect, -1.0, 1.0)
    mat = np.array([[m.GetElement(i, j) for j in range(4)] for i in range(4)])
    h = np.c_[xyz, np.ones(len(xyz))] @ mat.T
    return h[:, :2] / h[:, 3:4]


def _finish(plotter, off_screen, screenshot):
    bars = []
    _bar_slot(plotter)                      # every title and label inside the window
    for bar in plotter.scalar_bars.values():
        bars.append(ScalarBar(bar.GetTitle() or "", _box(bar)))
    legend = getattr(plotter, "legend", None)
    if legend is not None:
        legend = Legend(tuple(legend.GetEntryString(i)
                              for i in range(legend.GetNumberOfEntries())), _box(legend))
    if off_screen:
        img = plotter.screenshot(None, return_img=True)
        plotter.close()
        if screenshot is not None:          # PNG written atomically (never half a file)
            from matplotlib.image import imsave

            write_atomic(screenshot, lambda fh: imsave(fh, img, format="png"))
        return Shown(img, None, legend, tuple(bars))
    plotter.show(screenshot=screenshot)
    return Shown(None, plotter, legend, tuple(bars))
