"""Whether a mesh run's rays resolve each coating's specular lobe, decided before the first
ray (:func:`unresolved_lobes`, warned by :func:`warn_unresolved_lobes`).

A glint narrower than the ray spacing resolves is missed without a word otherwise: the
rays sample the shading normal at points δ apart, so where it turns at κ radians per unit
length neighbouring rays see normals κδ apart, and a lobe of half-width w
(:meth:`meshladar.brdf.BRDF.lobe_width`) spans 2w/(κδ) rays. The criterion asks
:data:`RAYS_ACROSS_LOBE` rays across it (2 on a regular grid, 4 stratified), which the
spacing δ* = 2w / (rays · κ) meets.

κ is the rate at which the normal the engine shades with turns (smooth: the interpolated
corner normals; exact: the part's own): per face, the largest rate in any direction (in a
slice, along the row of rays); a part's κ is what its most-curved 5 % of curved area
reaches (an area-weighted quantile, so a sliver does not decide). Flat normals are not
checked: each face's normal is constant, so the rays sample its glint exactly (a curved
part's faceting is the faceting study's subject, see the README).
"""

from __future__ import annotations

import math
import warnings
from types import MappingProxyType
from typing import NamedTuple

import numpy as np

from ..errors import MeshladarWarning
from ..meshes import corner_normals
from ..raytrace.grid import MAX_RAYS_PER_VIEW

__all__ = ["RAYS_ACROSS_LOBE", "Unresolved", "normal_turn",
           "unresolved_lobes", "warn_unresolved_lobes"]

#: Rays the criterion asks across a lobe's full width 2w, per sampling: cell centres are
#: a midpoint rule (measured 1.7 % at 2 rays, 4 % at 1.8, 34 % at 1); stratified offsets
#: are unbiased but noisy (3-D: 2–3 % rms at 4 rays, 6–8 % at 2).
RAYS_ACROSS_LOBE = MappingProxyType({"regular": 2.0, "stratified": 4.0})
_TINY = 1e-300
#: The share of a part's curved area whose curvature decides (the most curved 5 %).
_CURVED_SHARE = 0.05


class Unresolved(NamedTuple):
    """One part and coating whose lobe the run's rays (or flat facets) do not resolve."""

    part: str
    coating: str
    width: float          # the lobe's half-width w, radians
    turn: float           # the normal's change between neighbouring rays κδ, radians
    spacing: float        # the spacing δ* that resolves it (RAYS_ACROSS_LOBE rays)
    needed: float         # rays the criterion asks across the lobe (per sampling)
    rays_per_view: float  # rays one view needs at δ* over the whole target


def normal_turn(part, normals, mode):
    """(κ, area) per face of a mesh part: the rate at which the normal the engine shades
    with turns across the face, in radians per unit length (0 on flat regions), and the
    face's area. ``normals`` "smooth": the corner normals' linear interpolant; "exact": the
    part's own normals at three points inside the face (not its corners, which a prism's
    caps share). In 3-D the largest rate in any direction; in a slice, the rate along the
    face's horizontal direction (the one the row of rays moves in). Vectorised over
    faces."""
    v = part.vertices[part.faces]                                # (m, 3, 3)
    if normals == "exact":
        c = v.mean(axis=1, keepdims=True)
        v = c + 0.5 * (v - c)
        n = part.exact_normal(v.reshape(-1, 3)).reshape(v.shape)
    else:
        n = corner_normals(part)                                 # (m, 3, 3)
    fn, area = part.face_normals_areas()
    e1 = v[:, 1] - v[:, 0]
    e1 = e1 / np.maximum(np.linalg.norm(e1, axis=1, keepdims=True), _TINY)
    e2 = np.cross(fn, e1)
    dx = np.stack([v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]], axis=-1)          # (m, 3, 2)
    X = np.einsum("mkj,mkl->mjl", np.stack([e1, e2], -1), dx)              # (m, 2, 2)
    dn = np.stack([n[:, 1] - n[:, 0], n[:, 2] - n[:, 0]], axis=-1)          # (m, 3, 2)
    det = X[:, 0, 0] * X[:, 1, 1] - X[:, 0, 1] * X[:, 1, 0]
    ok = np.abs(det) > _TINY * np.maximum(np.abs(X).max(axis=(1, 2)), _TINY) ** 2
    inv = np.stack([np.stack([X[:, 1, 1], -X[:, 0, 1]], -1),
                    np.stack([-X[:, 1, 0], X[:, 0, 0]], -1)], -2) / np.where(ok, det, 1.0)[:, None, None]
    J = np.einsum("mkj,mjl->mkl", dn, inv)                      # dn per unit (e1, e2)
    if mode == "slice":
        h = np.cross([0.0, 0.0, 1.0], fn)
        hn = np.linalg.norm(h, axis=1, keepdims=True)
        h = np.where(hn > _TINY, h / np.maximum(hn, _TINY), 0.0)
        rate = np.linalg.norm(np.einsum("mkl,ml->mk", J, np.stack(
            [np.einsum("mk,mk->m", h, e1), np.einsum("mk,mk->m", h, e2)], -1)), axis=1)
    else:
        rate = np.linalg.norm(J, ord=2, axis=(1, 2))
    return np.where(ok, rate, 0.0), area


def _curved_quantile(values, area):
    """The value the top :data:`_CURVED_SHARE` of the curved area (values > 0) reaches."""
    curved = values > 0
    if not curved.any():
        return 0.0
    x, a = values[curved], area[curved]
    order = np.argsort(x)[::-1]
    reach = np.cumsum(a[order])
    k = int(np.searchsorted(reach, _CURVED_SHARE * reach[-1]))
    return float(x[order][min(k, x.size - 1)])


def _turns(scene, normals, mode):
    """Per part and material index: its κ, computed once per scene, normals and mode."""
    cache = scene.__dict__.setdefault("_lobe_turns", {})
    if (normals, mode) not in cache:
        out = cache[normals, mode] = {}
        for k, part in enumerate(scene.parts):
            rate, area = normal_turn(part, normals, mode)
            mats = np.broadcast_to(np.asarray(part.material), rate.shape)
            out[k] = {int(m): _curved_quantile(rate[mats == m], area[mats == m])
                      for m in np.unique(mats)}
    return cache[normals, mode]


def unresolved_lobes(scene, materials, plan):
    """The parts and coatings whose specular lobe the rays of ``plan`` (a
    :class:`~meshladar.raytrace.plan.TracePlan`: its spacing, normals and mode) do not
    resolve: :class:`Unresolved` records, empty when every lobe is resolved or no coating
    states a lobe width."""
    widths = [_lobe_width(m) for m in materials]
    if plan.normals == "flat" or all(w is None for w in widths):
        return []                   # flat faces are sampled exactly; no lobe: nothing to do
    need = RAYS_ACROSS_LOBE[plan.sampling]
    out = []
    for k, per_material in _turns(scene, plan.normals, plan.mode).items():
        for m, kappa in per_material.items():
            w = widths[m] if m < len(widths) else None
            if w is None or kappa <= 0 or 2.0 * w / (kappa * plan.spacing) >= need:
                continue
            good = 2.0 * w / (need * kappa)
            out.append(Unresolved(scene.parts[k].name, _label(materials[m]), float(w),
                                  float(kappa * plan.spacing), float(good), need,
                                  float((2.0 * plan.geo.radius / good)
                                        ** (1 if plan.mode == "slice" else 2))))
    return out


def _lobe_width(m):
    """The coating's lobe half-width, or None (a user's model without ``lobe_width``)."""
    f = getattr(m, "lobe_width", None)
    w = f() if callable(f) else None
    return float(w) if w is not None and np.isfinite(w) and w > 0 else None


def _label(m):
    return m.name or type(m).__name__


def warn_unresolved_lobes(scene, materials, plan, stacklevel=2):
    """One warning per part and coating that :func:`unresolved_lobes` finds, naming the
    lobe width, the normal change per ray and the spacing that resolves it."""
    for u in unresolved_lobes(scene, materials, plan):
        warnings.warn(_message(u, plan.spacing), MeshladarWarning, stacklevel=stacklevel + 1)


def _message(u, spacing):
    fix = f"ray_spacing={u.spacing:.3g} puts {u.needed:g} rays across it"
    if u.rays_per_view > MAX_RAYS_PER_VIEW:
        fix += (f" (about {u.rays_per_view:.2g} rays per view over the target, past the "
                f"{MAX_RAYS_PER_VIEW:.0e} a view may hold: simulate the glinting region "
                "alone, or expect the glint to be undersampled)")
    return (f"part {u.part!r}: the specular lobe of {u.coating} is {u.width:.3g} rad wide "
            f"(half-width) but the normal turns by {u.turn:.3g} rad between neighbouring "
            f"rays (ray_spacing {spacing:.3g}): {2 * u.width / u.turn:.2g} rays across the "
            f"lobe, fewer than {u.needed:g}, so the glint is undersampled (its return comes "
            f"out low or noisy); {fix}")
