"""The one matplotlib style of every meshladar figure."""

from __future__ import annotations

__all__ = ["STYLE", "use"]

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
    """Apply the style and the non-interactive backend; returns matplotlib.pyplot."""
    try:
        import matplotlib
    except ImportError as exc:
        raise ImportError("figures need matplotlib: pip install 'meshladar[viz]'") from exc
    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    plt.rcParams.update(STYLE)
    return plt
