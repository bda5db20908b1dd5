"""Quick looks at results: ``Sinogram.plot()`` and ``Image.plot()`` return a matplotlib
Figure (no pyplot state is touched, so a notebook shows it and a script saves it with
``fig.savefig``), labelled with the result's units and conventions."""

from __future__ import annotations

import numpy as np

from meshladar.errors import ParameterError

from . import style
from .paper import norm

__all__ = ["sinogram", "image", "volume", "profile", "target_voxel", "TARGET_LEVEL"]


@style.styled
def sinogram(sino, *, log=None):
    """The sinogram as an image, views against range, and the views' totals beside it;
    ``log`` shows the values on a log scale (glints next to diffuse parts); by default
    when the positive values span more than three decades. Views about z are placed at
    their angles in degrees (when evenly spaced), other view sets by index; empty bins
    take the scale's lowest colour.

    Parameters
    ----------
    sino : Sinogram
        The sinogram (its values, bins, views, model, units and radiometry label it).
    log : bool, optional, keyword-only
        A log colour scale from max(smallest positive value, 10⁻⁸ × the largest) to the
        largest. Default None: log when the largest positive value is more than 10³
        times the smallest.

    Returns
    -------
    matplotlib.figure.Figure
        Left, the values as an image: range r = −p·w across, views up, a colour bar in
        the sinogram's units; right, each view's total return.
    """
    import matplotlib
    from matplotlib.colors import LogNorm

    plt = style.use()
    fig, (a, b) = plt.subplots(1, 2, figsize=(10.0, 4.0),
                               gridspec_kw={"width_ratios": [2.2, 1]})
    v = sino.values
    units = sino.units or ""
    rad = sino.radiometry or "paper"
    pos = v[v > 0]
    if log is None:
        log = bool(pos.size) and pos.max() > 1e3 * pos.min()
    norm = LogNorm(max(pos.min(), pos.max() * 1e-8), pos.max()) if log and pos.size else None
    magma = matplotlib.colormaps["magma"]
    cmap = magma.with_extremes(bad=magma(0.0))  # zeros on a log scale: the lowest colour
    e = sino.bin_edges
    ang = np.asarray(sino.angles_deg, dtype=float)
    step = np.diff(ang)
    by_angle = sino.planar and ang.size > 1 and np.ptp(step) <= 1e-9 * max(abs(step[0]), 1.0) \
        and step[0] > 0
    if by_angle:
        ys, ylabel = (ang[0] - step[0] / 2, ang[-1] + step[0] / 2), "view angle φ [deg]"
        x_views = ang
    else:
        ys, ylabel = (-0.5, sino.n_views - 0.5), "view (index)"
        x_views = np.arange(sino.n_views)
    h = a.imshow(v, aspect="auto", origin="lower", interpolation="nearest", cmap=cmap,
                 norm=norm, extent=(e[0], e[-1], *ys))
    a.set_xlabel("range r = −p·w [scene units]")
    a.set_ylabel(ylabel)
    a.set_title(f"{sino.model} sinogram, {sino.n_views} views × {sino.n_bins} bins"
                + (", log scale" if log else ""), fontsize=9)
    bar = fig.colorbar(h, ax=a, shrink=0.85)
    bar.set_label(f"return per bin [{units}]\n{rad} radiometry", fontsize=8)
    bar.ax.tick_params(labelsize=7)
    b.plot(x_views, sino.total(), color="k", lw=0.8)
    b.set_xlabel(ylabel)
    b.set_ylabel(f"total return [{units}]", fontsize=8)
    b.set_title("each view's total", fontsize=9)
    fig.tight_layout()
    return fig


@style.styled
def image(img, *, y=None, title=None):
    """The image on a diverging map symmetric about zero (the paper figures' scale:
    :func:`meshladar.viz.paper.norm`) and its slice along x at ``y`` (default the centre)
    beside it; ``title`` replaces the image panel's (method, input, size).

    Parameters
    ----------
    img : Image
        The reconstruction.
    y : float, optional, keyword-only
        The slice's height in scene units: the pixel row containing it (clamped to the
        grid). Default None: the image's centre.
    title : str, optional, keyword-only
        The image panel's title.

    Returns
    -------
    matplotlib.figure.Figure
        Left, the image (x across, y up, scene units) with its colour bar; right, the
        row's values against x, on a symmetric-log scale when the colour scale is one.
    """
    plt = style.use()
    fig, (a, b) = plt.subplots(1, 2, figsize=(10.0, 4.2),
                               gridspec_kw={"width_ratios": [1.25, 1]})
    v = img.values
    x0, y0 = img.center
    ext = img.extent
    n = norm(v)
    h = a.imshow(v, origin="lower", cmap="RdBu_r", norm=n, interpolation="nearest",
                 extent=(x0 - ext, x0 + ext, y0 - ext, y0 + ext))
    info = img.info
    what = info.get("method", "fbp" if "filter" in info else "image")
    inp = info.get("preprocess")
    a.set_title(title or (f"{what}" + (f" of {inp}" if inp else "") + f", {img.size}^2"),
                fontsize=9)
    a.set_xlabel("x [scene units]")
    a.set_ylabel("y [scene units]")
    bar = fig.colorbar(h, ax=a, shrink=0.85)
    label = "reconstruction of log input" if inp and inp.startswith("log") else \
        "reconstruction [radiance / area]"
    bar.set_label(label, fontsize=7)
    if hasattr(n, "linthresh"):
        ticks = [n.vmin, -n.linthresh, 0.0, n.linthresh, n.vmax]
        bar.set_ticks(ticks, labels=[f"{t:.2g}" for t in ticks])
    bar.ax.tick_params(labelsize=7)
    yy = y0 if y is None else float(y)
    row = int(np.clip(np.floor((yy - (y0 - ext)) / img.pixel_size), 0, img.size - 1))
    b.plot(img.x, v[row], color="k", lw=0.8)
    if hasattr(n, "linthresh"):
        b.set_yscale("symlog", linthresh=n.linthresh, linscale=2.0)
    b.set_xlabel(f"x [scene units] (y = {img.y[row]:.3g})")
    b.set_ylabel(label.replace("reconstruction", "value"))     # the colour bar's units
    b.set_title("slice", fontsize=9)
    fig.tight_layout()
    return fig


#: The volume's slices pass through the centroid of the voxels brighter (in magnitude) than
#: this fraction of the peak: the target, not the streaks and noise spread over the cube.
TARGET_LEVEL = 0.1


def target_voxel(values):
    """(k, i, j): the voxel nearest the centroid of |values| above ``TARGET_LEVEL`` of their
    peak (the cube's centre for an all-zero volume): where a slice cuts the target, wherever
    in the cube it lies.

    Parameters
    ----------
    values : (nz, ny, nx) array_like
        A volume's values, ``values[k, i, j]``.

    Returns
    -------
    tuple of int
        (k, i, j): the rounded centroid of the weights max(|values| − ``TARGET_LEVEL`` ×
        peak, 0) along each axis, clipped to the grid; (nz // 2, ny // 2, nx // 2) when
        every weight is 0.
    """
    a = np.abs(np.asarray(values, dtype=np.float64))
    w = np.maximum(a - TARGET_LEVEL * a.max(initial=0.0), 0.0)
    total = w.sum()
    if not total > 0:
        return tuple(n // 2 for n in a.shape)
    index = []
    for axis, n in enumerate(a.shape):
        marginal = w.sum(axis=tuple(d for d in range(3) if d != axis))
        index.append(int(np.clip(np.rint(marginal @ np.arange(n) / total), 0, n - 1)))
    return tuple(index)


@style.styled
def volume(vol, *, title=None):
    """Three slices of a :class:`meshladar.images.Volume` through the target (planes z, y
    and x through the centroid of its bright voxels, :func:`target_voxel`: the cube's centre
    for a target there, and an off-centre target is cut too) on one colour scale, symmetric
    about zero as the images' (:func:`meshladar.viz.paper.norm`); log input is labelled as
    such.

    Parameters
    ----------
    vol : Volume
        The reconstruction, ``values[k, i, j]`` at (x[j], y[i], z[k]).
    title : str, optional, keyword-only
        The figure's title. Default None: the volume's method (``info["method"]``, else
        "volume") and its size in voxels (nx × ny × nz).

    Returns
    -------
    matplotlib.figure.Figure
        Three panels, the slices at z, y and x through :func:`target_voxel`, axes in
        scene units, with one colour bar.
    """
    plt = style.use()
    fig, axes = plt.subplots(1, 3, figsize=(12.5, 4.0))
    fig.subplots_adjust(wspace=0.4, left=0.06, right=0.88, top=0.85, bottom=0.14)
    v = np.asarray(vol.values)
    kz, ky, kx = target_voxel(v)
    cuts = ((v[kz], vol.x, vol.y, f"z = {vol.z[kz]:.3g}", "x", "y"),
            (v[:, ky, :], vol.x, vol.z, f"y = {vol.y[ky]:.3g}", "x", "z"),
            (v[:, :, kx], vol.y, vol.z, f"x = {vol.x[kx]:.3g}", "y", "z"))
    n = norm(v)
    for ax, (img, h, w, cut, xl, yl) in zip(axes, cuts):
        im = ax.imshow(img, extent=(h[0], h[-1], w[0], w[-1]), origin="lower",
                       cmap="RdBu_r", norm=n, interpolation="nearest")
        ax.set_title(f"slice {cut}", fontsize=9)
        ax.set_xlabel(f"{xl} [scene units]")
        ax.set_ylabel(f"{yl} [scene units]")
    inp = vol.info.get("preprocess") or ""
    bar = fig.colorbar(im, ax=list(axes), fraction=0.02)
    bar.set_label("reconstruction of log input" if inp.startswith("log") else
                  "reconstruction [return / volume]", fontsize=8)
    bar.ax.tick_params(labelsize=7)
    fig.suptitle(title or f"{vol.info.get('method', 'volume')}, "
                 f"{'x'.join(str(s) for s in v.shape[::-1])} voxels", fontsize=10)
    return fig


@style.styled
def profile(sino, reference, *, view=0, label="closed form"):
    """One view's range profile against a reference (an array of the view's bin values,
    or a callable of the bin edges giving them, e.g. a closed form), with their difference
    relative to the reference's peak below: the picture of an analytic check.

    Parameters
    ----------
    sino : Sinogram
        The simulated profiles.
    reference : Sinogram, (n_bins,) array_like or callable
        The reference: a sinogram on the same bins (its same view is taken, e.g. the
        analytic model's), the view's bin values, or a function of the bin edges
        (n_bins + 1,) that returns them.
    view : int, keyword-only
        The view's index (default 0).
    label : str, keyword-only
        The reference's name in the legend and title (default "closed form").

    Returns
    -------
    matplotlib.figure.Figure
        Above, both profiles as steps; below, (profile − reference) / max|reference|
        (the axis at least ±10⁻³), titled with the relative L2 difference.

    Raises
    ------
    ParameterError
        When the reference does not have the view's n_bins values (a sinogram: on the same
        bin edges), or is not numbers.
    """
    plt = style.use()
    got = np.asarray(sino.values[view], dtype=float)
    e = sino.bin_edges
    if hasattr(reference, "values") and hasattr(reference, "bin_edges"):    # a Sinogram
        if not np.array_equal(reference.bin_edges, e):
            raise ParameterError("reference: a sinogram on other bin edges than sino's; "
                                 "simulate it with the same Ladar")
        reference = reference.values[view]
    try:
        ref = np.asarray(reference(e) if callable(reference) else reference, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ParameterError(f"reference must be a Sinogram, the view's {got.size} bin "
                             f"values or a function of the bin edges; got "
                             f"{type(reference).__name__} ({exc})") from None
    if ref.shape != got.shape:
        raise ParameterError(f"reference must give the view's {got.size} bins; got shape "
                             f"{ref.shape}")
    fig, (a, b) = plt.subplots(2, 1, figsize=(7.0, 5.0), sharex=True,
                               gridspec_kw={"height_ratios": [2.2, 1]})
    a.stairs(got, e, color="k", lw=1.0, label=f"{sino.model} model")
    a.stairs(ref, e, color="C1", lw=1.0, ls="--", label=label)
    units = sino.units or ""
    a.set_ylabel(f"return per bin ({units})", fontsize=8)
    a.set_title(f"view {view} ({sino.angles_deg[view]:g} deg): profile against {label}",
                fontsize=9)
    a.legend(frameon=False, fontsize=8)
    peak = float(np.abs(ref).max()) or 1.0
    rel = (got - ref) / peak
    b.stairs(rel, e, color="C3", lw=0.8)
    b.axhline(0.0, color="0.5", lw=0.5)
    lim = max(1e-3, 1.2 * float(np.abs(rel).max()))     # a per-mille window at least:
    b.set_ylim(-lim, lim)                                # rounding-level noise stays flat
    err = float(np.linalg.norm(got - ref) / (np.linalg.norm(ref) or 1.0))
    b.set_ylabel("difference / peak", fontsize=8)
    b.set_xlabel("range r = -p.w")
    b.set_title(f"relative L2 difference {err:.2g}", fontsize=8)
    fig.tight_layout()
    return fig
