"""The laser radar cross section's figure (``CrossSection.plot()``): its signature over the
views (a polar plot for views about z, a map of azimuth and elevation for views over the
sphere) in dBsm, and the range-resolved cross section of the brightest view."""

from __future__ import annotations

import numpy as np

from . import style

__all__ = ["signature"]


@style.styled
def signature(cross_section, *, floor_db=60.0):
    """The signature over the views and the brightest view's range-resolved profile.

    Parameters
    ----------
    cross_section : CrossSection
        The result of :func:`meshladar.lrcs` (its views, values, profile and units).
    floor_db : float, keyword-only
        Decibels below the largest σ where the colour (or radial) scale stops at most:
        zero and tiny cross sections sit there instead of at −inf (the scale starts 3 dB
        below the smallest σ shown when that is higher).

    Returns
    -------
    matplotlib.figure.Figure
        Left, σ in dB relative to one square scene unit against the view; right, the
        brightest view's 4π P[k] per range bin.
    """
    from matplotlib.figure import Figure

    style.use()
    cs, prof = cross_section, cross_section.profile
    db = cs.dbsm
    top = float(np.max(db[np.isfinite(db)])) if np.isfinite(db).any() else 0.0
    shown = np.maximum(np.where(np.isfinite(db), db, top - floor_db), top - floor_db)
    fig = Figure(figsize=(10.0, 4.2), dpi=style.STYLE["savefig.dpi"])
    w = np.asarray(prof.view_vectors, dtype=float)
    units = f"dB re 1 {cs.units.replace('^2', '²')}"           # unit²: the scene's
    if prof.planar:
        a = fig.add_subplot(1, 2, 1, projection="polar")
        phi = np.radians(np.asarray(prof.angles_deg, dtype=float))
        order = np.argsort(phi)
        a.plot(np.r_[phi[order], phi[order][:1]], np.r_[shown[order], shown[order][:1]],
               color="k", lw=1.0, marker=".", ms=3)
        a.set_rlim(max(float(shown.min()) - 3.0, top - floor_db), top + 1.0)
        a.set_title(f"σ [{units}] against the view angle φ", fontsize=9)
    else:
        a = fig.add_subplot(1, 2, 1)
        az = np.degrees(np.arctan2(w[:, 1], w[:, 0]))
        el = np.degrees(np.arcsin(np.clip(w[:, 2], -1.0, 1.0)))
        low = max(float(shown.min()) - 3.0, top - floor_db)
        h = a.scatter(az, el, c=shown, cmap="magma", s=18, vmin=low, vmax=top)
        a.set_xlim(-180, 180)
        a.set_ylim(-90, 90)
        a.set_xlabel("view azimuth [deg]")
        a.set_ylabel("view elevation [deg]")
        bar = fig.colorbar(h, ax=a, shrink=0.85)
        bar.set_label(f"σ [{units}]", fontsize=8)
        a.set_title(f"signature over {len(w)} views", fontsize=9)
    i = int(np.argmax(cs.values))
    e = prof.bin_edges
    b = fig.add_subplot(1, 2, 2)
    b.stairs(prof.values[i], e, color="k", lw=0.9)
    lit = np.flatnonzero(prof.values[i] > 0)
    if lit.size:           # the bins that hold returns, at least 20 bins, and a margin
        lo, hi = e[lit[0]], e[lit[-1] + 1]
        pad = max(0.05 * (hi - lo), 10.0 * float(np.diff(e).mean()))
        b.set_xlim(max(lo - pad, e[0]), min(hi + pad, e[-1]))
    b.set_xlabel("range r = −p·w [scene units]")
    b.set_ylabel(f"σ per bin [{cs.units.replace('^2', '²')}]")
    b.set_title(f"brightest view's range profile (σ = {cs.values[i]:.4g}, "
                f"{cs.bounces} bounce{'s' if cs.bounces > 1 else ''})", fontsize=9)
    fig.tight_layout()
    return fig
