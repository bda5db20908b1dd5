"""Figures 5-11 of Jin & Levine (2009), drawn from a saved result of ``meshladar.studies.paper.run``.

Figures only load results, so restyling never means simulating again::

    from meshladar.viz import paper
    paths = paper.reproduce("figures/")          # run, save figures/paper_result.npz, draw
    paths = paper.draw("figures/paper_result.npz", "figures/")   # redraw only

Reconstructions are signed, so images use a diverging map symmetric about zero up to
±(largest |value| in the image): no pixel is saturated, so the bright surface ring keeps
its shape (a percentile top clips the ring, which is under 1 % of the image: at 512² the
99.9th percentile left up to 32 % of a shape's pixels within one range bin of its boundary
at the top colour; tests/viz/test_figure_scale.py). The ring's best-centred pixels reach
the top; the rest of it (pixels the boundary crosses off-centre) read on a symmetric-log
scale that stays linear within the 99th percentile of |value| inside the shapes (the
interior and background artifacts each figure is about) and is logarithmic beyond.
Outside the shapes (beyond 8 % of their size) a white veil fades FBP's streaks, which
are real but are not what the figures are about. Centre slices sit beside every
reconstruction, as in the paper's Fig. 6(c).
"""

from __future__ import annotations

import os

import numpy as np

from meshladar import io as mlio
from meshladar.studies import paper

from . import style

__all__ = ["reproduce", "draw", "save_run", "RESULT_NAME"]

RESULT_NAME = "paper_result.npz"


def save_run(outdir, *, size=None):
    """Run the paper's experiments and save them to ``outdir/paper_result.npz``.

    The arrays saved: every panel's sinogram (``sino/<key>``) and image
    (``image/<key>``), ``bin_edges`` and ``angles_deg``; the metadata: captions, metrics,
    extent, outlines, size, :data:`meshladar.studies.paper.FIGURES` and the model
    (``"analytic"``) (:func:`meshladar.io.save_result`).

    Parameters
    ----------
    outdir : str or os.PathLike
        The folder (created if missing).
    size : int, optional, keyword-only
        Pixels per side of the reconstructions (default None:
        :func:`meshladar.studies.paper.run`'s, 512); at least
        :data:`meshladar.studies.paper.MIN_SIZE` (475), where the findings hold.

    Returns
    -------
    path : str
        The result file's path.
    metrics : dict of str to float
        The findings' numbers (:func:`meshladar.studies.paper.run`'s ``metrics``).

    Raises
    ------
    ParameterError
        For a ``size`` below the minimum, before any work or file is written.
    """
    kwargs = {} if size is None else {"size": size}
    res = paper.run(**kwargs)
    arrays = {f"sino/{k}": v for k, v in res["sinograms"].items()}
    arrays.update({f"image/{k}": v for k, v in res["images"].items()})
    arrays["bin_edges"] = res["bin_edges"]
    arrays["angles_deg"] = res["angles_deg"]
    meta = {"captions": res["captions"], "metrics": res["metrics"], "extent": res["extent"],
            "outlines": res["outlines"],
            "size": res["size"], "figures": {str(k): v for k, v in paper.FIGURES.items()},
            "model": "analytic"}
    path = os.path.join(outdir, RESULT_NAME)
    mlio.save_result(path, arrays, meta)
    return path, res["metrics"]


#: The colour scale: ±(largest |value| in the image), linear within ±(this percentile of
#: |value| inside the shapes), logarithmic beyond.
LINEAR_PERCENTILE = 99.0
#: Opacity of the white veil over the image outside the shapes.
FADE = 0.7


def _inside(shape, outlines, extent, shrink=0.97):
    """Pixels inside the panel's shapes, shrunk to leave out the bright surface ring."""
    n = shape[0]
    c = -extent + (np.arange(n) + 0.5) * 2 * extent / n
    X, Y = np.meshgrid(c, c)
    mask = np.zeros(shape, bool)
    for o in outlines or ():
        ca, sa = np.cos(o["angle"]), np.sin(o["angle"])
        dx, dy = X - o["center"][0], Y - o["center"][1]
        xl, yl = ca * dx + sa * dy, -sa * dx + ca * dy
        mask |= (xl / (shrink * o["axes"][0])) ** 2 + (yl / (shrink * o["axes"][1])) ** 2 < 1
    return mask


def norm(img, inside=None):
    """The colour normalisation of a signed reconstruction: symmetric about 0 up to the
    image's largest |value| (no pixel saturates, so the surface ring, under 1 % of the
    pixels and the brightest of them, keeps its shape), linear within the
    interior's robust scale (``inside``: the shapes' interiors, where the darkening and
    streaks are) and logarithmic beyond it."""
    from matplotlib.colors import Normalize, SymLogNorm

    a = np.abs(np.asarray(img, dtype=float))
    top = float(a.max()) if a.size else 0.0
    top = top or 1.0
    core = a[inside] if inside is not None and inside.any() else a
    lin = float(np.percentile(core, LINEAR_PERCENTILE))
    if lin <= 0 or lin >= 0.3 * top:
        return Normalize(-top, top)
    return SymLogNorm(lin, linscale=2.0, vmin=-top, vmax=top, base=10)


def _units(key):
    if key.endswith("_log"):
        return "reconstruction of log(radiance / floor) [1 / area]"
    if key.endswith("_clip"):
        return "reconstruction of clipped radiance [radiance / area]"
    return "reconstruction [radiance / area]"


def _image_panel(fig, ax, img, extent, title, key="", outlines=None):
    h = ax.imshow(img, extent=(-extent, extent, -extent, extent),
                  norm=norm(img, _inside(img.shape, outlines, extent)),
                  cmap="RdBu_r", interpolation="nearest")
    ax.set_xlabel("x [scene units]")
    ax.set_ylabel("y [scene units]")
    if outlines:
        # outside the shapes (beyond 8 % of their size) FBP's streaks are drawn faded:
        # still there, no longer the loudest thing in the picture
        veil = np.zeros(img.shape + (4,))
        veil[..., :3] = 1.0
        veil[..., 3] = np.where(_inside(img.shape, outlines, extent, 1.08), 0.0, FADE)
        ax.imshow(veil, extent=(-extent, extent, -extent, extent), interpolation="nearest")
    ax.set_title(title, fontsize=8)
    bar = fig.colorbar(h, ax=ax, shrink=0.8)
    bar.set_label(_units(key), fontsize=7)
    n = h.norm
    if hasattr(n, "linthresh"):                   # the scale's landmarks, nothing crowded
        ticks = [n.vmin, -n.linthresh, 0.0, n.linthresh, n.vmax]
        bar.set_ticks(ticks, labels=[f"{t:.2g}" for t in ticks])
    bar.ax.tick_params(labelsize=7)
    return h


#: Rows averaged about y = 0 for a slice: the rings cross them at right angles and stay
#: sharp, the streaks that run every way average down.
_SLICE_ROWS = 8


def _slices(ax, arrays, keys, extent, outlines, tags="ab"):
    """Centre slices (y = 0) of the panels' reconstructions on one axis, each divided by
    its own image's colour-scale top (so a log-input and a radiance image compare, and
    both read on the images' scales), symmetric-log with the images' linear range, over
    the shapes' extent along x."""
    lines = ("-", ":")
    colours = ("k", "C3")
    lins, xs = [], []
    for key, ls, colour, tag in zip(keys, lines, colours, tags):
        img = arrays[f"image/{key}"]
        n = img.shape[0]
        x = -extent + (np.arange(n) + 0.5) * 2 * extent / n
        row = img[n // 2 - _SLICE_ROWS // 2:n // 2 + _SLICE_ROWS // 2].mean(axis=0)
        t = norm(img, _inside(img.shape, outlines.get(key), extent))
        ax.plot(x, row / t.vmax, ls, color=colour, lw=0.8, label=f"({tag})")
        lins.append(getattr(t, "linthresh", t.vmax) / t.vmax)
        for o in outlines.get(key) or ():
            half = max(o["axes"])
            xs += [o["center"][0] - half, o["center"][0] + half]
    lin = min(lins)
    ax.set_ylim(-1.05, 1.05)
    if lin < 0.3:
        ax.set_yscale("symlog", linthresh=lin, linscale=2.0)
        ticks = [-1.0, -lin, 0.0, lin, 1.0]
        ax.set_yticks(ticks, labels=[f"{t:.2g}" for t in ticks])
    if xs:                                    # the shapes and a margin: their rings, inside
        lo, hi = min(xs), max(xs)
        pad = 0.15 * (hi - lo)
        ax.set_xlim(max(lo - pad, -extent), min(hi + pad, extent))
    else:
        ax.set_xlim(-0.95 * extent, 0.95 * extent)
    ax.tick_params(labelsize=7)
    ax.set_xlabel(f"x [scene units] (mean of the {_SLICE_ROWS} rows about y = 0)")
    ax.set_ylabel("centre slice / its image's scale top")
    ax.legend(loc="lower right", frameon=True, framealpha=0.9, fontsize=7)


def _caption(fig, text):
    import textwrap

    width = int(fig.get_figwidth() * 15)            # characters that fit at 8 pt
    fig.text(0.5, 0.01, "\n".join(textwrap.wrap(text, width)), ha="center", va="bottom",
             fontsize=8)


def figures(arrays, meta):
    """Yield (figure number, matplotlib Figure) for Figs 5-11 of a loaded result (inside
    :func:`meshladar.viz.style.styled`); :func:`draw` saves them."""
    plt = style.use()
    extent = meta["extent"]
    caps = meta["captions"]
    met = meta["metrics"]
    outl = meta.get("outlines", {})
    edges = arrays["bin_edges"]

    # Fig. 5: range profiles of the diffuse disk (view-independent), b = 0 and 0.99
    fig, ax = plt.subplots(figsize=(7.0, 4.2))
    width = float(np.min(np.diff(edges)))
    for key, ls in (("disk_b0", "-"), ("disk_b0.99", ":")):
        prof = arrays[f"sino/{key}"][0]
        lit = np.nonzero(prof)[0]
        k = np.arange(lit.min(), lit.max() + 1)
        ax.plot(k - lit.min(), prof[k] / width, ls, color="k", label=caps[key])
    ax.set_yscale("log")
    ax.set_xlabel("range bin from the disk top (bin width A/256)")
    ax.set_ylabel("binned radiance / bin width [1/sr]")
    ax.set_title("Fig. 5 — range profile of a diffuse disk (A = 0.8, ρd = 1)", fontsize=10)
    ax.legend(frameon=False, fontsize=8)
    fig.subplots_adjust(bottom=0.25)
    _caption(fig, "b = 0.99 returns more from the disk centre (near bins) and less from the "
                  "periphery than the Lambertian b = 0; the lower half is shadowed.")
    yield 5, fig

    texts = {
        6: ("Lambertian: a clean ring (flat interior, the centre dip is a sampling "
            "artifact). b = 0.99: the interior darkens toward the surface (the "
            "beam-hardening analogue)."),
        7: ("darkening concentrates at the tapered ends for b = 0.99 "
            f"(ends {met['ellipse_b0.99.ends_darkening']:+.2f}, sides "
            f"{met['ellipse_b0.99.sides_darkening']:+.2f})."),
        8: ("e = 1 reconstructs cleanly; the e = 0.007 glint darkens a deep, narrow band "
            f"inside the surface (darkening {met['disk_e0.007.darkening']:+.1f}, width "
            f"{met['disk_e0.007.darkening_width']:.3f} A)."),
        9: "both coatings: interior darkening plus crossed streaks from component shadowing "
           "(the limited-angle analogue).",
        10: ("the gray disk all but vanishes next to aluminium (visibility "
             f"{met['pair_gray_al.visibility']:.3f} and {met['pair_al_gray.visibility']:.3f})."),
        11: ("log input (visibility {:.2f}) and clipping at 0.008 × max ({:.2f}) bring the "
             "gray disk back.").format(met["pair_gray_al_log.visibility"],
                                       met["pair_gray_al_clip.visibility"]),
    }
    for n in (6, 7, 8, 9, 10, 11):
        title, keys = meta["figures"][str(n)]
        fig, axes = plt.subplots(1, 3, figsize=(15.0, 4.6),
                                 gridspec_kw={"width_ratios": [1, 1, 0.9]})
        for ax, key, tag in zip(axes, keys, "ab"):
            extra = ""
            if f"{key}.visibility" in met:
                extra = f"\ngray/aluminium visibility {met[f'{key}.visibility']:.3f}"
            elif f"{key}.darkening" in met:
                extra = f"\ndarkening {met[f'{key}.darkening']:+.2f}"
            _image_panel(fig, ax, arrays[f"image/{key}"], extent,
                         f"({tag}) {caps[key]}{extra}", key, outl.get(key))
        _slices(axes[2], arrays, keys, extent, outl)
        axes[2].set_title("(c) centre slices, each on its image's scale", fontsize=8)
        fig.suptitle(f"Fig. {n} — {title}", fontsize=11)
        fig.subplots_adjust(left=0.05, right=0.97, bottom=0.22, top=0.84, wspace=0.45)
        _caption(fig, texts[n])
        yield n, fig


@style.styled
def draw(result_path, outdir, *, dpi=None):
    """Draw Figs 5-11 as PNGs in ``outdir`` from a saved result; returns their paths.

    ``dpi`` overrides the style's resolution (150, as the README's copies).

    Parameters
    ----------
    result_path : str or os.PathLike
        A result written by :func:`save_run`.
    outdir : str or os.PathLike
        The folder (created if missing); ``fig05.png`` to ``fig11.png`` are replaced.
    dpi : float, optional, keyword-only
        Resolution (default None: 150).

    Returns
    -------
    list of str
        The paths of ``fig05.png`` to ``fig11.png``, in order.
    """
    arrays, meta = mlio.load_result(result_path)
    os.makedirs(outdir, exist_ok=True)
    return style.save_all(((f"fig{n:02d}.png", fig) for n, fig in figures(arrays, meta)),
                          outdir, dpi)


def reproduce(outdir, *, size=None):
    """Run, save and draw: returns (figure paths, metrics).

    Parameters
    ----------
    outdir : str or os.PathLike
        The folder for ``paper_result.npz`` and the figures (created if missing).
    size : int, optional, keyword-only
        Pixels per side of the reconstructions (default None: 512; at least 475:
        :func:`save_run`).

    Returns
    -------
    paths : list of str
        The figures' paths (:func:`draw`).
    metrics : dict of str to float
        The findings' numbers (:func:`save_run`).
    """
    path, metrics = save_run(outdir, size=size)
    return draw(path, outdir), metrics
