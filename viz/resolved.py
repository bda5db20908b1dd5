"""Figures of resolved returns (:class:`meshladar.returns.Returns`): a few views' profiles
(one coordinate) or images (two: angle–angle, range–Doppler), with labelled axes and units."""

from __future__ import annotations

import numpy as np

from meshladar.errors import ParameterError
from meshladar.returns import Returns

from . import style

__all__ = ["draw"]

_LABELS = {"range": "range r = -p.w", "cross_range": "cross-range p.u",
           "elevation": "elevation p.v", "doppler": "Doppler f_D"}


@style.styled
def draw(returns, path, *, views=None, log=False, dpi=None):
    """Write a PNG of up to four views of ``returns`` to ``path``; ``log`` shows
    log10 of the returns (glints next to diffuse parts). Returns the path.

    One panel per view, titled with its direction w: a profile (one coordinate) as steps
    against the coordinate's bin edges, or an image (two) as a ``magma`` colour mesh with
    the second coordinate across and a colour bar. Axes are labelled with the
    coordinates and their units, the values with ``returns.info["units"]``.

    Parameters
    ----------
    returns : Returns
        One or two coordinates (:class:`meshladar.returns.Returns`).
    path : str or os.PathLike
        The PNG to write (replaced if it exists).
    views : sequence of int, optional, keyword-only
        View indices (default None: up to four spread over all views).
    log : bool, keyword-only
        Show log10 of the values, each view's values floored at its smallest positive
        one (1 when it has none) (default False).
    dpi : float, optional, keyword-only
        Resolution (default None: the style's, 150).

    Returns
    -------
    str
        ``path``, as a string.

    Raises
    ------
    ParameterError
        When ``returns`` is not a Returns, has more than two coordinates, or ``views``
        does not index its views.
    """
    if not isinstance(returns, Returns):
        raise ParameterError(f"returns must be a meshladar.returns.Returns; got "
                             f"{type(returns).__name__}")
    if len(returns.axes) > 2:
        raise ParameterError(f"draw shows one or two coordinates; these returns have "
                             f"{returns.axes}: draw a marginal (a Returns of fewer axes)")
    n_views = returns.values.shape[0]
    views = style.pick_views(n_views, views)
    plt = style.use()
    fig, axes = plt.subplots(1, len(views), figsize=(3.4 * len(views), 3.4), squeeze=False)
    units = returns.info.get("units", "")
    labels = [f"{_LABELS[a]} ({u})" for a, u in zip(returns.axes, returns.units)]
    for ax, v in zip(axes[0], views):
        vals = returns.values[v]
        if log:
            pos = vals[vals > 0]
            floor = pos.min() if pos.size else 1.0
            vals = np.log10(np.maximum(vals, floor))
        w = returns.view_vectors[v]
        title = f"view {v}: w = ({w[0]:.2f}, {w[1]:.2f}, {w[2]:.2f})"
        if vals.ndim == 1:
            e = returns.edges[0]
            ax.stairs(vals, e, color="k")
            ax.set_xlabel(labels[0])
            ax.set_ylabel(("log10 " if log else "") + f"return per bin ({units})")
        else:
            e0, e1 = returns.edges
            h = ax.pcolormesh(e1, e0, vals, cmap="magma", shading="flat")
            ax.set_xlabel(labels[1])
            ax.set_ylabel(labels[0])
            fig.colorbar(h, ax=ax, fraction=0.046, pad=0.04,
                         label=("log10 " if log else "") + f"return per cell ({units})")
        ax.set_title(title, fontsize=8)
    fig.tight_layout()
    path = style.save_png(fig, path, dpi)
    plt.close(fig)
    return path
