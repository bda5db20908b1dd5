"""Figures 5-11 of Jin & Levine (2009), drawn from a saved result of ``meshladar.paper.run``.

Figures only load results, so restyling never means simulating again::

    from meshladar.viz import paper
    paths = paper.reproduce("figures/")          # run, save figures/paper_result.npz, draw
    paths = paper.draw("figures/paper_result.npz", "figures/")   # redraw only

Images take their grey levels from the shapes' interiors (0.5th-99.5th percentile, with
headroom), so the interior pedestal and its darkening show while the bright surface ring
saturates.
"""

from __future__ import annotations

import os

import numpy as np

from . import style

__all__ = ["reproduce", "draw", "save_run", "RESULT_NAME"]

RESULT_NAME = "paper_result.npz"


def save_run(outdir, *, size=None):
    """Run the paper's experiments and save them to ``outdir/paper_result.npz``."""
    from meshladar import paper, results

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
    results.save_result(path, arrays, meta)
    return path, res["metrics"]


def _inside(shape, outlines, extent, shrink=0.97):
    """Pixels inside the panel's shapes, shrunk to leave out the bright surface ring."""
    n = shape[0]
    c = -extent + (np.arange(n) + 0.5) * 2 * extent / n
    X, Y = np.meshgrid(c, c)
    mask = np.zeros(shape, bool)
    for o in outlines:
        ca, sa = np.cos(o["angle"]), np.sin(o["angle"])
        dx, dy = X - o["center"][0], Y - o["center"][1]
        xl, yl = ca * dx + sa * dy, -sa * dx + ca * dy
        mask |= (xl / (shrink * o["axes"][0])) ** 2 + (yl / (shrink * o["axes"][1])) ** 2 < 1
    return mask


def _limits(img, mask=None):
    """Grey levels set by the shapes' interiors (the surface ring saturates), so the
    interior pedestal and its darkening show; the whole image when no outline is known."""
    vals = img[mask] if mask is not None and mask.any() else img
    lo, hi = np.percentile(vals, [0.5, 99.5])
    if mask is not None and mask.any():
        span = max(hi - lo, 1e-300)
        hi = hi + 0.5 * span                      # room above the interior for the ring
    return (lo, hi) if hi > lo else (img.min(), img.max() + 1e-300)


def _image_panel(fig, ax, img, extent, title, outlines=None):
    lo, hi = _limits(img, None if outlines is None else _inside(img.shape, outlines, extent))
    h = ax.imshow(img, extent=(-extent, extent, -extent, extent), vmin=lo, vmax=hi,
                  interpolation="nearest")
    ax.set_xlabel("x [scene units]")
    ax.set_ylabel("y [scene units]")
    ax.set_title(title)
    fig.colorbar(h, ax=ax, shrink=0.8, label="reconstruction [radiance / area]")


def _caption(fig, text):
    import textwrap

    fig.text(0.5, 0.01, "\n".join(textwrap.wrap(text, 120)), ha="center", va="bottom",
             fontsize=8)


@style.styled
def draw(result_path, outdir, *, dpi=None):
    """Draw Figs 5-11 as PNGs in ``outdir`` from a saved result; returns their paths.

    ``dpi`` overrides the style's resolution (the README's thumbnails use 55).
    """
    from meshladar import results

    plt = style.use()
    arrays, meta = results.load_result(result_path)
    os.makedirs(outdir, exist_ok=True)
    extent = meta["extent"]
    caps = meta["captions"]
    met = meta["metrics"]
    outl = meta.get("outlines", {})
    edges = arrays["bin_edges"]
    paths = []

    def save(fig, n):
        p = os.path.join(outdir, f"fig{n:02d}.png")
        fig.savefig(p + ".tmp.png", **({} if dpi is None else {"dpi": dpi}))
        os.replace(p + ".tmp.png", p)
        plt.close(fig)
        paths.append(p)

    # Fig. 5: range profiles of the diffuse disk (view-independent), b = 0 and 0.99
    fig, ax = plt.subplots(figsize=(6.0, 3.8))
    width = float(np.min(np.diff(edges)))
    for key, ls in (("disk_b0", "-"), ("disk_b0.99", ":")):
        prof = arrays[f"sino/{key}"][0]
        lit = np.nonzero(prof)[0]
        k = np.arange(lit.min(), lit.max() + 1)
        ax.plot(k - lit.min(), prof[k] / width, ls, color="k", label=caps[key])
    ax.set_yscale("log")
    ax.set_xlabel("range bin from the disk top (bin width A/256)")
    ax.set_ylabel("binned radiance / bin width [1/sr]")
    ax.set_title("Fig. 5 — range profile of a diffuse disk (A = 0.8, ρd = 1)")
    ax.legend(frameon=False)
    fig.subplots_adjust(bottom=0.22)
    _caption(fig, "b = 0.99 returns more from the disk centre (near bins) and less from the "
                  "periphery than the Lambertian b = 0; the lower half is shadowed.")
    save(fig, 5)

    # Fig. 6: reconstructions and centre slices
    fig, axes = plt.subplots(1, 3, figsize=(13.5, 4.2))
    for ax, key in zip(axes[:2], ("disk_b0", "disk_b0.99")):
        _image_panel(fig, ax, arrays[f"image/{key}"], extent,
                     f"{caps[key]}\ndarkening {met[f'{key}.darkening']:+.2f}",
                     outlines=outl.get(key))
    size = arrays["image/disk_b0"].shape[0]
    x = -extent + (np.arange(size) + 0.5) * 2 * extent / size
    row = size // 2
    for key, ls in (("disk_b0", "-"), ("disk_b0.99", ":")):
        img = arrays[f"image/{key}"]
        ax_slice = axes[2]
        ax_slice.plot(x, 0.5 * (img[row] + img[row - 1]), ls, color="k", label=caps[key])
    inner = np.abs(x) < 0.95 * 0.8
    lo = min(arrays[f"image/{k}"][row][inner].min() for k in ("disk_b0", "disk_b0.99"))
    axes[2].set_xlim(-0.9, 0.9)
    axes[2].set_ylim(1.5 * lo, -1.5 * lo)
    axes[2].set_xlabel("x [scene units] (y = 0)")
    axes[2].set_ylabel("reconstruction [radiance / area]")
    axes[2].set_title("Fig. 6(c) — centre slices")
    axes[2].legend(frameon=False, fontsize=7)
    fig.suptitle("Fig. 6 — diffuse disk reconstructions (360 views, A/256 bins)")
    fig.subplots_adjust(bottom=0.2, wspace=0.45)
    _caption(fig, "Lambertian: a clean ring (flat interior, the centre dip is a sampling "
                  "artifact). b = 0.99: the interior darkens toward the surface "
                  "(the beam-hardening analogue).")
    save(fig, 6)

    texts = {
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
    for n in (7, 8, 9, 10, 11):
        title, keys = meta["figures"][str(n)]
        fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.4))
        for ax, key, tag in zip(axes, keys, "ab"):
            extra = ""
            if f"{key}.visibility" in met:
                extra = f"\ngray/aluminium visibility {met[f'{key}.visibility']:.3f}"
            elif f"{key}.darkening" in met:
                extra = f"\ndarkening {met[f'{key}.darkening']:+.2f}"
            _image_panel(fig, ax, arrays[f"image/{key}"], extent,
                         f"({tag}) {caps[key]}{extra}", outlines=outl.get(key))
        fig.suptitle(f"Fig. {n} — {title}")
        fig.subplots_adjust(bottom=0.2, wspace=0.35)
        _caption(fig, texts[n])
        save(fig, n)
    return paths


def reproduce(outdir, *, size=None):
    """Run, save and draw: returns (figure paths, metrics)."""
    path, metrics = save_run(outdir, size=size)
    return draw(path, outdir), metrics
