"""The one matplotlib style of every meshladar figure."""

from __future__ import annotations

import functools
import os

import numpy as np

from meshladar.errors import ParameterError
from meshladar.io import write_atomic

__all__ = ["STYLE", "use", "styled", "pick_views", "save_png", "save_all"]

STYLE = {
    "figure.dpi": 100,
    "savefig.dpi": 150,
    "font.size": 9,
    "axes.titlesize": 9,
    "axes.labelsize": 9,
    "image.cmap": "gray",
    "image.origin": "lower",
    "axes.grid": False,
    "lines.linewidth": 1.2,
}


def use():
    """Figures without pyplot: an object with pyplot's ``subplots`` and ``close`` that makes
    plain ``matplotlib.figure.Figure`` objects, so drawing never switches the session's
    backend (a notebook's inline backend stays). Style them inside :func:`styled`.

    Returns
    -------
    object
        Its ``subplots(nrows=1, ncols=1, *, figsize=None, squeeze=True, **kwargs)`` makes
        a ``Figure`` (dpi: :data:`STYLE`'s ``savefig.dpi``, 150) and returns (figure,
        axes) as pyplot's does; its ``close(fig)`` does nothing (the figure belongs to no
        pyplot state).

    Raises
    ------
    ImportError
        When matplotlib is not installed, naming the ``viz`` extra.
    """
    _matplotlib()
    return _Figures()


def _matplotlib():
    try:
        import matplotlib
    except ImportError as exc:
        raise ImportError("figures need matplotlib: pip install 'meshladar[viz]'") from exc
    return matplotlib


class _Figures:
    @staticmethod
    def subplots(nrows=1, ncols=1, *, figsize=None, squeeze=True, **kwargs):
        from matplotlib.figure import Figure

        fig = Figure(figsize=figsize, dpi=STYLE["savefig.dpi"])   # a user's savefig too
        return fig, fig.subplots(nrows, ncols, squeeze=squeeze, **kwargs)

    @staticmethod
    def close(fig):
        """Nothing to close: the figure belongs to no pyplot state and is collected."""


def styled(func):
    """Run ``func`` with meshladar's style in a ``matplotlib.rc_context``: the user's
    rcParams are as they were afterwards.

    Parameters
    ----------
    func : callable
        The drawing function. A generator function's body would run when it is
        iterated, outside the style: generators of figures are left undecorated and
        iterated inside a styled function (as :func:`meshladar.viz.studies.draw` does).

    Returns
    -------
    callable
        ``func`` wrapped (``functools.wraps``): the same arguments and return value, run
        inside ``matplotlib.rc_context(STYLE)``.
    """
    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with _matplotlib().rc_context(STYLE):
            return func(*args, **kwargs)

    return wrapper


def pick_views(n_views, views=None, most=4):
    """The views a figure shows: ``views`` checked against ``n_views``, or up to ``most``
    spread over all of them.

    Parameters
    ----------
    n_views : int
        The record's number of views.
    views : sequence of int, optional
        The views to show, as indices in [0, ``n_views``) (negative indices are
        refused). Default None: ``min(most, n_views)`` views evenly spread from the first
        to the last (rounded, duplicates dropped).
    most : int
        How many views the default spreads (default 4).

    Returns
    -------
    list of int
        The view indices.

    Raises
    ------
    ParameterError
        When the views are empty or an index is outside [0, ``n_views``).
    """
    if views is None:
        views = np.unique(np.linspace(0, n_views - 1, min(most, n_views)).round().astype(int))
    views = [int(v) for v in views]
    if not views or min(views) < 0 or max(views) >= n_views:
        raise ParameterError(f"views must index the {n_views} views; got {views}")
    return views


def save_all(named_figures, outdir, dpi=None):
    """Write each (file name, Figure) of ``named_figures`` into ``outdir`` with
    :func:`save_png`; returns the paths.

    Parameters
    ----------
    named_figures : iterable of (str, matplotlib.figure.Figure)
        File names (relative to ``outdir``) and figures; a generator is drawn one
        figure at a time.
    outdir : str or os.PathLike
        The folder (created if missing).
    dpi : float, optional
        Resolution (default None: :data:`STYLE`'s ``savefig.dpi``, 150).

    Returns
    -------
    list of str
        The paths written, in order.
    """
    return [save_png(fig, os.path.join(outdir, name), dpi) for name, fig in named_figures]


def save_png(fig, path, dpi=None):
    """Write ``fig`` as a PNG at ``path`` atomically (:func:`meshladar.io.write_atomic`:
    a crash never leaves half a file or a stray temporary); returns the path.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str or os.PathLike
        The file to write (replaced if it exists); its folder is created if missing.
    dpi : float, optional
        Resolution (default None: :data:`STYLE`'s ``savefig.dpi``, 150).

    Returns
    -------
    str
        ``path``, as a string.
    """
    path = os.fspath(path)
    dpi = STYLE["savefig.dpi"] if dpi is None else dpi
    write_atomic(path, lambda fh: fig.savefig(fh, format="png", dpi=dpi))
    return path


def overlapping_texts(fig):
    """The pairs of visible, non-empty texts of ``fig`` whose drawn bounding boxes overlap
    (titles, labels, tick labels, legends, captions), as (text, text) strings, and each
    text cut off by the figure's edge as (text, "<outside the figure>")."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.text import Text

    if fig.canvas is None or not hasattr(fig.canvas, "get_renderer"):
        FigureCanvasAgg(fig)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    hidden = set()                       # tick labels of ticks outside the view: not drawn
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            lo, hi = sorted(axis.get_view_interval())
            eps = 1e-9 * max(abs(lo), abs(hi), 1.0)
            for tick in axis.get_major_ticks() + axis.get_minor_ticks():
                if not lo - eps <= tick.get_loc() <= hi + eps:
                    hidden.update((id(tick.label1), id(tick.label2)))
    texts = [t for t in fig.findobj(Text) if t.get_visible() and t.get_text().strip()
             and t.get_alpha() != 0 and id(t) not in hidden]
    boxes = [t.get_window_extent(renderer) for t in texts]
    frame = fig.bbox
    out = [(t.get_text(), "<outside the figure>") for t, b in zip(texts, boxes)
           if b.x0 < frame.x0 - 0.5 or b.x1 > frame.x1 + 0.5 or b.y0 < frame.y0 - 0.5
           or b.y1 > frame.y1 + 0.5]
    for i in range(len(texts)):
        for j in range(i + 1, len(texts)):
            a, b = boxes[i], boxes[j]
            if (a.x0 < b.x1 - 0.5 and b.x0 < a.x1 - 0.5 and a.y0 < b.y1 - 0.5
                    and b.y0 < a.y1 - 0.5):
                out.append((texts[i].get_text(), texts[j].get_text()))
    return out
