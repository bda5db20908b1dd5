"""Figures of coating fits: the view design of :func:`meshladar.fit.design_views`."""

from __future__ import annotations

import numpy as np

from meshladar.errors import ParameterError
from meshladar.fit import ViewDesign

from . import style

__all__ = ["design_figure", "draw_design"]


@style.styled
def draw_design(design, path, *, dpi=None):
    """Write :func:`design_figure` as a PNG to ``path`` atomically; returns the path.

    Parameters
    ----------
    design : ViewDesign
        What :func:`meshladar.fit.design_views` returns.
    path : str or os.PathLike
        The PNG to write (replaced if it exists).
    dpi : float, optional, keyword-only
        Resolution (default None: the style's, 150).

    Returns
    -------
    str
        ``path``, as a string.

    Raises
    ------
    ParameterError
        When ``design`` is not a ViewDesign.
    """
    return style.save_png(design_figure(design), path, dpi)


@style.styled
def design_figure(design):
    """A :class:`~meshladar.fit.ViewDesign` as a matplotlib Figure (no pyplot state):
    each candidate view's own information against its angle with the chosen views numbered
    in the order they were added, and each parameter's σ from the chosen views against as
    many evenly spaced ones (log scale).

    Parameters
    ----------
    design : ViewDesign
        What :func:`meshladar.fit.design_views` returns.

    Returns
    -------
    matplotlib.figure.Figure
        Two panels: left, each candidate's log det of its own Fisher information against
        its angle in degrees, the evenly spaced views circled and the chosen ones filled
        and numbered; right, each parameter's σ from the chosen and from the evenly
        spaced views, as bars on a log scale.

    Raises
    ------
    ParameterError
        When ``design`` is not a :class:`~meshladar.fit.ViewDesign`.
    """
    if not isinstance(design, ViewDesign):
        raise ParameterError(f"design must be a meshladar.fit.ViewDesign; got "
                             f"{type(design).__name__}")
    plt = style.use()
    fig, (a, b) = plt.subplots(1, 2, figsize=(11.0, 3.8))
    ang = design.angles_deg
    order = np.argsort(ang)
    a.plot(ang[order], design.information[order], color="0.4", lw=1,
           label="each view alone")
    a.plot(ang[design.uniform], design.information[design.uniform], "o", mfc="none",
           color="tab:blue", label="evenly spaced")
    a.plot(ang[design.chosen], design.information[design.chosen], "o", color="tab:red",
           label="chosen")
    for k, v in enumerate(design.chosen):
        a.annotate(str(k + 1), (ang[v], design.information[v]), textcoords="offset points",
                   xytext=(0, 6), ha="center", fontsize=7, color="tab:red")
    a.set_xlabel("view angle (deg)")
    a.set_ylabel("log det of the view's Fisher information")
    a.set_title(f"{design.chosen.size} views chosen (D-optimal, greedy)")
    a.legend(fontsize=7)
    x = np.arange(len(design.names))
    b.bar(x - 0.2, design.stderr_uniform, 0.4, color="tab:blue", label="evenly spaced")
    b.bar(x + 0.2, design.stderr_designed, 0.4, color="tab:red", label="chosen")
    b.set_yscale("log")
    b.set_xticks(x)
    b.set_xticklabels(design.names, rotation=45, ha="right", fontsize=7)
    b.set_ylabel("parameter sigma")
    b.legend(fontsize=7)
    fig.tight_layout()
    return fig
