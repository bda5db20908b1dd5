"""Waveform figures: a few views' noiseless waveforms against two-way time, with the band
their noise realisations fill and one realisation drawn through it."""

from __future__ import annotations

import numpy as np

from meshladar.errors import ParameterError
from meshladar.sensor import SPEED_OF_LIGHT as c
from meshladar.waveforms import Waveforms

from . import style

__all__ = ["draw", "figure"]


@style.styled
def draw(waves, path, *, realisations=None, noise=None, views=None, band=(5.0, 95.0),
         dpi=None):
    """Write a PNG of :func:`figure` to ``path``; returns the path.

    Parameters
    ----------
    waves : Waveforms
        The waveforms (:class:`meshladar.waveforms.Waveforms`).
    path : str or os.PathLike
        The PNG to write, atomically (replaced if it exists).
    realisations, noise, views, band :
        As :func:`figure`.
    dpi : float, optional
        Resolution (default None: the style's, 150).

    Returns
    -------
    str
        ``path``, as a string.

    Raises
    ------
    ParameterError
        As :func:`figure`.
    """
    plt = style.use()
    fig = figure(waves, realisations=realisations, noise=noise, views=views, band=band)
    path = style.save_png(fig, path, dpi)
    plt.close(fig)
    return path


@style.styled
def figure(waves, *, realisations=None, noise=None, views=None, band=(5.0, 95.0)):
    """A matplotlib Figure of ``waves`` (:class:`meshladar.waveforms.Waveforms`;
    ``Waveforms.plot()``).

    Parameters
    ----------
    waves : Waveforms
        The noiseless waveforms: each view's samples against two-way time in ns (a range
        axis r = ct/2 − standoff in metres on top).
    realisations : (n, n_views, n_samples) array, optional
        Noise realisations (:meth:`Waveforms.realise`): their ``band`` percentiles are
        shaded around the expected waveform, and the first is drawn.
    noise : meshladar.noise.Noise, optional
        The noise that drew them: the expected waveform is then its mean, gain × (signal +
        background), in its output units; a view whose draws clip at the digitiser's full
        scale shows it as a dotted line labelled with the view's clipped fraction.
    views : sequence of int, optional
        Which views (default up to four, spread over all).
    band : (low, high) percentiles
        The shaded band's percentiles of the realisations, in [0, 100] (default (5, 95)).

    Returns
    -------
    matplotlib.figure.Figure
        One panel per view, stacked, sharing the time axis.

    Raises
    ------
    ParameterError
        When ``waves`` is not a Waveforms, ``realisations`` is not (n, n_views,
        n_samples), or ``views`` does not index the views.
    """
    if not isinstance(waves, Waveforms):
        raise ParameterError(f"waves must be a meshladar.waveforms.Waveforms; got "
                             f"{type(waves).__name__}")
    n_views = waves.values.shape[0]
    views = style.pick_views(n_views, views)
    if realisations is not None:
        realisations = np.asarray(realisations, np.float64)
        if realisations.ndim != 3 or realisations.shape[1:] != waves.values.shape:
            raise ParameterError(f"realisations must have shape (n, {n_views}, "
                                 f"{waves.values.shape[1]}); got {realisations.shape}")
    plt = style.use()
    fig, axes = plt.subplots(len(views), 1, figsize=(6.4, 1.9 * len(views) + 0.8),
                             squeeze=False, sharex=True)
    t_ns = waves.times * 1e9
    expected, units, what = _expected(waves, noise)
    for ax, v in zip(axes[:, 0], views):
        if realisations is not None:
            lo, hi = np.percentile(realisations[:, v, :], band, axis=0)
            ax.fill_between(t_ns, lo, hi, step="mid", color="C0", alpha=0.25, lw=0,
                            label=f"noise, {band[0]:g}-{band[1]:g} percentile")
            ax.step(t_ns, realisations[0, v], where="mid", color="C0", lw=0.6,
                    label="one realisation")
        ax.step(t_ns, expected[v], where="mid", color="k", lw=1.0, label=what)
        if realisations is not None and noise is not None and noise.bits is not None:
            clipped = noise.clipped_fraction(realisations[:, v, :])
            if clipped > 0:                  # draws flat at the top code: say why
                ax.axhline(noise.full_scale, color="C3", ls=":", lw=0.8,
                           label=f"full scale: {100 * clipped:.3g} % clipped")
        ax.set_ylabel(f"per sample\n({units})")
        if np.abs(ax.get_ylim()).max() >= 1e4:   # "20 M", not a "1e7" offset under the top axis
            from matplotlib.ticker import EngFormatter

            ax.yaxis.set_major_formatter(EngFormatter(sep=" "))
        ax.text(0.01, 0.95, f"view {v}: {waves.angles_deg[v]:g} deg", transform=ax.transAxes,
                va="top", ha="left")
    axes[0, 0].legend(loc="upper right", fontsize=7, frameon=False)
    axes[-1, 0].set_xlabel(f"two-way time (ns); sample interval "
                           f"{waves.sample_interval * 1e9:.3g} ns")
    _range_axis(axes[0, 0], waves)
    fig.tight_layout()
    return fig


def _expected(waves, noise):
    """What the black line shows: (values, their units, its legend label): the noiseless
    waveforms, or with ``noise`` its mean, gain × (signal + background)."""
    units = waves.units or "sinogram units"
    if noise is not None:
        expected = noise.mean(waves.values, waves.sample_interval)
        units = units if noise.gain == 1 else f"{noise.gain:g} x {units}"
        what = "expected: gain x (signal + background)"
    else:
        expected, what = waves.values, "noiseless"
    return expected, units, what


def _range_axis(ax, waves):
    """The range axis r = ct/2 − standoff in metres on top of the time axis (ns) of ``ax``."""
    top = ax.secondary_xaxis(
        "top", functions=(lambda t: t * 1e-9 * c / 2 - waves.standoff,
                          lambda r: (r + waves.standoff) * 2 / c * 1e9))
    top.set_xlabel("range r = ct/2 - standoff (m)")
    from matplotlib.ticker import MaxNLocator

    # no label in the corners, where the left axis's top label sits
    top.xaxis.set_major_locator(MaxNLocator(5, prune="both"))
