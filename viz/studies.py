"""Figures of the faceting study, drawn from its saved files (``meshladar.studies``).

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

from . import style

__all__ = ["draw"]

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
    :func:`meshladar.viz.style.styled`); :func:`draw` saves them."""
    from meshladar import results

    plt = style.use()
    with open(os.path.join(outdir, "faceting.json"), encoding="utf-8") as fh:
        doc = json.load(fh)
    rows = doc["rows"]
    phantoms = sorted({r["phantom"] for r in rows})
    coatings = sorted({r["coating"] for r in rows})

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
    fig.suptitle(f"Faceting study ({doc['setting']}): error against time, Pareto fronts")
    fig.tight_layout()
    yield "pareto.png", fig

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
    yield "error_vs_segments.png", fig

    arrays, meta = results.load_result(os.path.join(outdir, "faceting_examples.npz"))
    edges = arrays["bin_edges"]
    angles = arrays["angles_deg"]
    for key, info in meta["examples"].items():
        diff = arrays[f"{key}/mesh"] - arrays[f"{key}/analytic"]
        idiff = arrays[f"{key}/mesh_image"] - arrays[f"{key}/analytic_image"]
        fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.0))
        lim = np.max(np.abs(diff)) or 1.0
        h = axes[0].imshow(diff, aspect="auto", cmap="RdBu_r", vmin=-lim, vmax=lim,
                           extent=(edges[0], edges[-1], angles[0], angles[-1]))
        axes[0].set_xlabel("range [scene units]")
        axes[0].set_ylabel("view angle [deg]")
        axes[0].set_title(f"sinogram: {info['segments']}-segment flat mesh − analytic")
        fig.colorbar(h, ax=axes[0], label="bin difference")
        lim = np.max(np.abs(idiff)) or 1.0
        h = axes[1].imshow(idiff, cmap="RdBu_r", vmin=-lim, vmax=lim, extent=(-1, 1, -1, 1))
        axes[1].set_xlabel("x [scene units]")
        axes[1].set_ylabel("y [scene units]")
        axes[1].set_title("FBP image difference")
        fig.colorbar(h, ax=axes[1], label="image difference")
        fig.suptitle(f"{key}: what a coarse flat mesh gets wrong")
        fig.tight_layout()
        yield f"difference_{key.replace('/', '_')}.png", fig


@style.styled
def draw(outdir):
    """Write the study's figures into ``outdir`` atomically; returns their paths."""
    plt = style.use()
    paths = []
    for name, fig in figures(outdir):
        paths.append(style.save_png(fig, os.path.join(outdir, name)))
        plt.close(fig)
    return paths
