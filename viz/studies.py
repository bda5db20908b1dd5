"""Figures of the studies: the faceting study, drawn from its saved files
(``meshladar.studies``), and the reconstruction and 3-D tomography studies, drawn from
their images (``meshladar.studies.reconstruction``, ``meshladar.studies.paper.run_3d``).

``draw(outdir)`` reads ``faceting.json`` and ``faceting_examples.npz`` from ``outdir`` and
writes:

* ``pareto.png``: relative L2 sinogram error against wall time for every study point, one
  panel per phantom and coating, coloured by series, with the Pareto front (the cheapest
  point for each accuracy) drawn through them;
* ``error_vs_segments.png``: error against segments for flat, smooth and exact normals;
* ``difference_<phantom>_<coating>.png``: a coarse flat mesh's sinogram minus the analytic
  one, and the difference of their FBP images.
"""

from __future__ import annotations

import json
import os

import numpy as np

from meshladar import io as mlio
from meshladar.studies import reconstruction as study

from . import style
from .paper import norm

__all__ = ["draw", "figures", "reconstruction_figures", "draw_reconstruction",
           "tomography3d_figures", "draw_tomography3d"]

_SERIES_STYLE = {"position": ("exact normals", "C0"), "normal": ("flat normals", "C3"),
                 "smooth": ("smooth normals", "C2"), "rays": ("rays, point", "C1"),
                 "rays_footprint": ("rays, footprint", "C4"), "pixel": ("pixel model", "C5")}


def _pareto(points):
    """Indices of the Pareto front (no other point both faster and more accurate)."""
    order = np.argsort([p[0] for p in points])
    front, best = [], np.inf
    for i in order:
        if points[i][1] < best:
            front.append(i)
            best = points[i][1]
    return front


def _log_ticks(ax):
    """Log axes with a few labelled decades and unlabelled minor ticks (narrow spans
    otherwise crowd their minor labels into each other)."""
    from matplotlib.ticker import LogLocator, NullFormatter

    for axis in (ax.xaxis, ax.yaxis):
        if axis.get_scale() == "log":
            axis.set_major_locator(LogLocator(numticks=4))
            axis.set_minor_formatter(NullFormatter())


def figures(outdir):
    """Yield (file name, matplotlib Figure) for the study saved in ``outdir`` (inside
    :func:`meshladar.viz.style.styled`); :func:`draw` saves them.

    Parameters
    ----------
    outdir : str or os.PathLike
        A folder holding ``faceting.json`` and ``faceting_examples.npz``
        (:func:`meshladar.studies.save_study`).

    Yields
    ------
    (str, matplotlib.figure.Figure)
        ``pareto.png``, ``error_vs_segments.png``, then one
        ``difference_<phantom>_<coating>.png`` per example (module docstring); each grid
        has one panel per phantom (rows) and coating (columns).
    """
    plt = style.use()
    with open(os.path.join(outdir, "faceting.json"), encoding="utf-8") as fh:
        doc = json.load(fh)
    rows = doc["rows"]
    phantoms = sorted({r["phantom"] for r in rows})
    coatings = sorted({r["coating"] for r in rows})
    yield "pareto.png", _pareto_figure(plt, rows, phantoms, coatings, doc["setting"])
    yield "error_vs_segments.png", _segments_figure(plt, rows, phantoms, coatings)
    arrays, meta = mlio.load_result(os.path.join(outdir, "faceting_examples.npz"))
    for key, info in meta["examples"].items():
        yield (f"difference_{key.replace('/', '_')}.png",
               _difference_figure(plt, arrays, key, info["segments"]))


def _pareto_figure(plt, rows, phantoms, coatings, setting):
    """pareto.png: error against wall time, one panel per phantom (rows) and coating
    (columns), coloured by series, with the Pareto front drawn through the points."""
    shape = (len(phantoms), len(coatings))
    fig, axes = plt.subplots(*shape, figsize=(3.2 * shape[1], 2.8 * shape[0]), squeeze=False)
    for i, ph in enumerate(phantoms):
        for j, co in enumerate(coatings):
            ax = axes[i, j]
            sel = [r for r in rows if r["phantom"] == ph and r["coating"] == co]
            for s, (label, color) in _SERIES_STYLE.items():
                pts = [(r["seconds"], r["rel_l2"]) for r in sel if r["series"] == s]
                if pts:
                    ax.scatter(*zip(*pts), s=10, color=color, label=label)
            pts = [(r["seconds"], r["rel_l2"]) for r in sel]
            front = [pts[k] for k in _pareto(pts)]
            ax.plot(*zip(*front), "k-", lw=0.8)
            ax.set_xscale("log")
            ax.set_yscale("log")
            _log_ticks(ax)
            ax.set_title(f"{ph}, {co}")
            ax.set_xlabel("wall time [s]")
            ax.set_ylabel("relative L2 error")
    axes[0, 0].legend(fontsize=6, frameon=False)
    fig.suptitle(f"Faceting study ({setting}): error against time, Pareto fronts")
    fig.tight_layout()
    return fig


def _segments_figure(plt, rows, phantoms, coatings):
    """error_vs_segments.png: error against segments for flat, smooth and exact normals,
    one panel per phantom and coating, with an N⁻² guide."""
    shape = (len(phantoms), len(coatings))
    fig, axes = plt.subplots(*shape, figsize=(3.2 * shape[1], 2.8 * shape[0]), squeeze=False)
    for i, ph in enumerate(phantoms):
        for j, co in enumerate(coatings):
            ax = axes[i, j]
            for s in ("normal", "smooth", "position"):
                sel = sorted([r for r in rows if r["phantom"] == ph and r["coating"] == co
                              and r["series"] == s], key=lambda r: r["segments"])
                if sel:
                    label, color = _SERIES_STYLE[s]
                    ax.loglog([r["segments"] for r in sel], [r["rel_l2"] for r in sel], "o-",
                              color=color, ms=3, label=label)
            n = np.array([8.0, 4096.0])
            ax.loglog(n, 0.5 * (n / 64.0) ** -2.0, "k:", lw=0.8, label="N⁻²")
            _log_ticks(ax)
            ax.set_title(f"{ph}, {co}")
            ax.set_xlabel("segments N")
            ax.set_ylabel("relative L2 error")
    axes[0, 0].legend(fontsize=6, frameon=False)
    fig.suptitle("Error against tessellation segments")
    fig.tight_layout()
    return fig


def _difference_figure(plt, arrays, key, segments):
    """difference_<phantom>_<coating>.png: the coarse flat mesh's sinogram (of ``segments``
    segments) minus the analytic one, and the difference of their FBP images."""
    edges = arrays["bin_edges"]
    angles = arrays["angles_deg"]
    diff = arrays[f"{key}/mesh"] - arrays[f"{key}/analytic"]
    idiff = arrays[f"{key}/mesh_image"] - arrays[f"{key}/analytic_image"]
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.0))
    lim = np.max(np.abs(diff)) or 1.0
    h = axes[0].imshow(diff, aspect="auto", cmap="RdBu_r", vmin=-lim, vmax=lim,
                       extent=(edges[0], edges[-1], angles[0], angles[-1]))
    axes[0].set_xlabel("range [scene units]")
    axes[0].set_ylabel("view angle [deg]")
    axes[0].set_title(f"sinogram: {segments}-segment flat mesh − analytic")
    fig.colorbar(h, ax=axes[0], label="bin difference")
    lim = np.max(np.abs(idiff)) or 1.0
    h = axes[1].imshow(idiff, cmap="RdBu_r", vmin=-lim, vmax=lim, extent=(-1, 1, -1, 1))
    axes[1].set_xlabel("x [scene units]")
    axes[1].set_ylabel("y [scene units]")
    axes[1].set_title("FBP image difference")
    fig.colorbar(h, ax=axes[1], label="image difference")
    fig.suptitle(f"{key}: what a coarse flat mesh gets wrong")
    fig.tight_layout()
    return fig


@style.styled
def draw(outdir):
    """Write the faceting study's figures into ``outdir`` atomically; returns their
    paths.

    Parameters
    ----------
    outdir : str or os.PathLike
        The study's folder: its files are read from it and the PNGs written into it
        (:func:`figures`).

    Returns
    -------
    list of str
        The paths written.
    """
    return style.save_all(figures(outdir), outdir)


def _signed_panel(ax, img, extent):
    """A signed reconstruction on the paper figures' scale (:func:`meshladar.viz.paper.norm`:
    symmetric about 0, the surfaces unsaturated), without ticks."""
    ax.imshow(img, origin="lower", cmap="RdBu_r", norm=norm(img), extent=extent,
              interpolation="nearest")
    ax.set_xticks([])
    ax.set_yticks([])


def reconstruction_figures(images, methods=None, spacings=(1.0, 10.0)):
    """Yield ("reconstruction.png", Figure): every method's image (columns) of every
    phantom at each view spacing (rows), from the reconstruction study's
    ``images[(phantom, spacing_deg, method)]``; each panel on its own symmetric scale.

    Parameters
    ----------
    images : dict
        (phantom, spacing_deg, method) → (size, size) image over [−1, 1]²
        (:func:`meshladar.studies.reconstruction.run`'s second value).
    methods : sequence of str, optional
        The columns (default None: :data:`meshladar.studies.reconstruction.METHODS`); a
        missing image leaves its panel blank.
    spacings : sequence of float
        The view spacings in degrees shown for each phantom (default (1.0, 10.0)).

    Yields
    ------
    (str, matplotlib.figure.Figure)
        One pair: ``"reconstruction.png"`` and the figure, one row per phantom and
        spacing.
    """
    plt = style.use()
    methods = list(study.METHODS if methods is None else methods)
    panels = [(ph, sp) for ph in sorted({k[0] for k in images}) for sp in spacings]
    fig, axes = plt.subplots(len(panels), len(methods),
                             figsize=(1.6 * len(methods), 1.75 * len(panels) + 0.6),
                             squeeze=False)
    for i, (ph, sp) in enumerate(panels):
        for j, m in enumerate(methods):
            ax = axes[i, j]
            img = images.get((ph, sp, m))
            if img is None:
                ax.set_axis_off()
            else:
                _signed_panel(ax, img, (-1, 1, -1, 1))
            if i == 0:
                ax.set_title(m.replace("_", " "), fontsize=8)
        axes[i, 0].set_ylabel(f"{ph.replace('_', ' ')}\n{sp:g}° spacing", fontsize=7)
    fig.suptitle("Each method's reconstruction (signed, symmetric scale per panel)",
                 fontsize=10)
    fig.tight_layout()
    yield "reconstruction.png", fig


def tomography3d_figures(volumes, views, size):
    """Yield ("tomography3d.png", Figure): the middle z slice (z ≈ 0) of every volume of
    the 3-D study (``meshladar.studies.paper.run_3d``), on the paper figures' symmetric
    scale.

    The slice is ``values[nz // 2]``: at z = 0 for an odd nz on a grid centred on the
    origin, half a voxel above it for an even one (the study's 64³ and 128³).

    Parameters
    ----------
    volumes : dict of str to Volume
        The study's volumes by name (each a panel, in two rows).
    views : int
        The number of views, for the title.
    size : int
        Voxels per side, for the title.

    Yields
    ------
    (str, matplotlib.figure.Figure)
        One pair: ``"tomography3d.png"`` and the figure.
    """
    plt = style.use()
    keys = list(volumes)
    cols = (len(keys) + 1) // 2
    fig, axes = plt.subplots(2, cols, figsize=(2.6 * cols, 5.8), squeeze=False)
    for ax, key in zip(axes.ravel(), keys):
        v = volumes[key]
        mid = v.values[v.values.shape[0] // 2]
        _signed_panel(ax, mid, (v.x[0], v.x[-1], v.y[0], v.y[-1]))
        ax.set_title(key.replace("_", " "), fontsize=8)
    for ax in axes.ravel()[len(keys):]:
        ax.set_axis_off()
    fig.suptitle(f"3-D reflective tomography: z = 0 slices ({views} views, {size}³ voxels)",
                 fontsize=10)
    fig.tight_layout()
    yield "tomography3d.png", fig


@style.styled
def draw_reconstruction(images, outdir, **kwargs):
    """Write :func:`reconstruction_figures` into ``outdir`` atomically; returns the paths.

    Parameters
    ----------
    images : dict
        As :func:`reconstruction_figures`.
    outdir : str or os.PathLike
        The folder (created if missing).
    **kwargs
        ``methods`` and ``spacings`` of :func:`reconstruction_figures`.

    Returns
    -------
    list of str
        The path of ``reconstruction.png``.
    """
    return style.save_all(reconstruction_figures(images, **kwargs), outdir)


@style.styled
def draw_tomography3d(volumes, outdir, views, size):
    """Write :func:`tomography3d_figures` into ``outdir`` atomically; returns the paths.

    Parameters
    ----------
    volumes : dict of str to Volume
        As :func:`tomography3d_figures`.
    outdir : str or os.PathLike
        The folder (created if missing).
    views, size : int
        The number of views and voxels per side, for the title.

    Returns
    -------
    list of str
        The path of ``tomography3d.png``.
    """
    return style.save_all(tomography3d_figures(volumes, views, size), outdir)
