"""The one matplotlib style of every meshladar figure."""

from __future__ import annotations

__all__ = ["STYLE", "use", "styled", "pick_views", "save_png"]

STYLE = {
    "figure.dpi": 100,
    "savefig.dpi": 110,
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
    backend (a notebook's inline backend stays). Style them inside :func:`styled`."""
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

        fig = Figure(figsize=figsize)
        return fig, fig.subplots(nrows, ncols, squeeze=squeeze, **kwargs)

    @staticmethod
    def close(fig):
        """Nothing to close: the figure belongs to no pyplot state and is collected."""


def styled(func):
    """Run ``func`` with meshladar's style in a ``matplotlib.rc_context``: the user's
    rcParams are as they were afterwards."""
    import functools

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with _matplotlib().rc_context(STYLE):
            return func(*args, **kwargs)

    return wrapper


def pick_views(n_views, views=None, most=4):
    """The views a figure shows: ``views`` checked against ``n_views``, or up to ``most``
    spread over all of them."""
    import numpy as np

    from meshladar.errors import ParameterError

    if views is None:
        views = np.unique(np.linspace(0, n_views - 1, min(most, n_views)).round().astype(int))
    views = [int(v) for v in views]
    if not views or min(views) < 0 or max(views) >= n_views:
        raise ParameterError(f"views must index the {n_views} views; got {views}")
    return views


def save_png(fig, path, dpi=150):
    """Write ``fig`` as a PNG at ``path`` atomically (:func:`meshladar.results.write_atomic`:
    a crash never leaves half a file or a stray temporary); returns the path."""
    import os

    from meshladar.results import write_atomic

    path = os.fspath(path)
    write_atomic(path, lambda fh: fig.savefig(fh, format="png", dpi=dpi))
    return path
