"""One view's first hits: cast the grid, recompute distances in float64, and the normal of
each hit (flat, smooth or exact), its footprint, and, bistatic, the receiver's side."""

from __future__ import annotations

import numpy as np

from ..precision import MIN_COS_FACET as _MIN_COS_FACET
from ..precision import RECEIVER_LIFT as _RECEIVER_LIFT
from ..precision import REFINE_MIN_COS as _REFINE_MIN_COS
from .grid import dot, ray_grid
from ..hits import ViewHits
from ..precision import TINY


NORMALS = ("flat", "smooth", "exact")


BACK_FACES = ("two-sided", "ignore")



def trace_view(plan, scene, view, footprint=True, transverse=False):
    """Hits of one view (range relative to the shifted centre's plane) of a
    :class:`~meshladar.raytrace.plan.TracePlan`; ``view`` (a
    :class:`~meshladar.raytrace.plan.View`) gives its direction w, receiver w_r and rng.
    With a bistatic receiver direction w_r, one occlusion ray per hit toward it; with
    ``transverse``, each hit's coordinates along the view's (u, v) (its ray's, shifted)."""
    geo, mode, spacing, z0_shifted = plan.geo, plan.mode, plan.spacing, plan.z0_shifted
    back_faces, w, w_r, rng = plan.back_faces, view.w, view.w_r, view.rng
    grid = ray_grid(geo, w, mode, spacing, z0_shifted, rng)
    o, u, v = grid.origins, grid.u, grid.v
    d = np.ascontiguousarray((-w)[None, :], dtype=np.float32)
    res = scene.run(o, d, output=1, columns=grid.columns, coherent=plan.coherent)
    prim = res["primID"]
    hit = prim >= 0
    prim = prim[hit]
    n_geo = geo.face_normals[prim]
    t_hit = refine_t(geo, prim, o[hit], w, res["tfar"][hit])
    cos_geo = dot(n_geo, w)
    back = cos_geo < 0
    n, rho = _hit_normals(geo, prim, res, hit, n_geo,
                          lambda: (o[hit].astype(np.float64) - t_hit[:, None] * w)
                          + geo.center, mode == "slice")
    cos_t = dot(n, w)
    if back_faces == "two-sided" and back.any():
        sign = np.where(back, -1.0, 1.0)
        n = n * sign[:, None]
        n_geo = n_geo * sign[:, None]
        cos_t = cos_t * sign
    # sin θ from cos θ: near normal incidence the absolute error of 1 − cos² is 1e-16, far
    # below the glint lobe's e² ≥ 1e-8 that sin² is compared with in h(α)
    sin_t = np.sqrt(np.maximum(1.0 - cos_t * cos_t, 0.0))
    factor = None
    curve = None
    if geo.normals == "smooth" or (geo.normals == "exact" and mode == "3d"):
        factor = _shading_factor(cos_t, cos_geo)
    if geo.normals == "exact" and mode == "slice" and np.any(np.isfinite(rho)):
        factor = _arc_factor(n, u, cos_t, rho, spacing)
        if footprint:
            sin_signed = dot(n, u)
            r_ = np.where(np.isfinite(rho), rho, 0.0)
            half = np.where(r_ > 0, 0.5 * spacing / np.where(r_ > 0, r_, 1.0), 0.0)
            curve = np.stack([np.arcsin(np.clip(sin_signed, -1, 1)),
                              np.arcsin(np.clip(sin_signed - half, -1, 1)),
                              np.arcsin(np.clip(sin_signed + half, -1, 1)), r_], -1)
    if back_faces == "ignore":
        cos_t = np.where(back, -1.0, cos_t)
    bi = None
    rng_extra = 0.0
    if w_r is not None:
        # one occlusion ray per hit toward the receiver, from just off the facet
        p = o[hit].astype(np.float64) - t_hit[:, None] * w
        lift = _RECEIVER_LIFT * geo.radius
        o2 = np.ascontiguousarray(p + lift * n_geo, dtype=np.float32)
        blocked = scene.run(o2, np.ascontiguousarray(w_r[None, :], dtype=np.float32),
                            query="OCCLUDED") != -1
        bi = bistatic_angles(n, w, w_r, blocked | (back_faces == "ignore") & back)
        # range from the two-way path: r = −p·(w + w_r)/2 (monostatic: −p·w)
        rng_extra = -dot(p, w_r)
    # footprint: range spread along u and v on the flat facet, and the facet's own range
    # interval relative to the hit (a footprint cannot return ranges the facet does not span)
    # r = −(c + o − t w)·w = −c·w + t − o·w, with the float32 origin o exactly as cast
    oh = o[hit].astype(np.float64)
    rng_rel = t_hit - (oh[:, 0] * w[0] + oh[:, 1] * w[1] + oh[:, 2] * w[2])
    if w_r is not None:
        rng_rel = 0.5 * (rng_rel + rng_extra)     # r = −c·(w + w_r)/2 + ...
    spread = np.zeros((prim.size, 4))
    if footprint:
        cg = np.maximum(np.abs(dot(n_geo, w)), TINY)
        tri = geo.vertices[geo.faces[prim]] - geo.center
        tri_r = -(tri[..., 0] * w[0] + tri[..., 1] * w[1] + tri[..., 2] * w[2])
        spread[:, 0] = np.abs(dot(n_geo, u)) / cg * 0.5 * spacing
        if mode == "3d":
            spread[:, 1] = np.abs(dot(n_geo, v)) / cg * 0.5 * spacing
        spread[:, 2] = np.minimum(tri_r.min(axis=1) - rng_rel, 0.0)
        spread[:, 3] = np.maximum(tri_r.max(axis=1) - rng_rel, 0.0)
    across = np.stack([dot(oh, u), dot(oh, v)], -1) if transverse else None
    return ViewHits(rng_rel, cos_t, sin_t, geo.material[prim], spread, len(o),
                    int(back.sum()), bi, factor, curve, None, across)



def bistatic_angles(n, w, w_r, hidden):
    """(k, 4) rows (cos θr, sin θr, cos α, sin α) of normals n (k, 3) for the ladar along
    w and the receiver along w_r (α to the half vector), cos θr = −1 where ``hidden`` (the
    receiver cannot see the point, or its face is an ignored back face)."""
    cos_r = dot(n, w_r)
    sin_r = np.linalg.norm(np.cross(n, w_r), axis=1)
    half = (w + w_r) / np.linalg.norm(w + w_r)
    cos_a = dot(n, half)
    sin_a = np.linalg.norm(np.cross(n, half), axis=1)
    cos_r = np.where(hidden, -1.0, cos_r)
    return np.stack([cos_r, sin_r, cos_a, sin_a], -1)


def _hit_normals(geo, prim, res, hit, n_geo, points, curvature=False):
    """The normal of each hit as the geometry's ``normals`` asks: the face's (flat), the
    corner normals interpolated with Embree's barycentrics (smooth), or the part's exact
    normal at the hit points (scene coordinates, from ``points()``), with, for
    ``curvature``, the exact surface's radius of curvature there (inf where unknown).
    Returns (normals (k, 3), radii (k,) or None)."""
    if geo.normals == "flat":
        return n_geo, None
    if geo.normals == "smooth":
        bu = res["u"][hit].astype(np.float64)[:, None]
        bv = res["v"][hit].astype(np.float64)[:, None]
        c = geo.corner[prim]
        n = (1 - bu - bv) * c[:, 0] + bu * c[:, 1] + bv * c[:, 2]
        return n / np.linalg.norm(n, axis=1, keepdims=True), None
    p = points()
    n = np.empty((prim.size, 3))
    rho = np.full(prim.size, np.inf)
    part = geo.part_of[prim]
    for k in np.unique(part):
        sel = part == k
        n[sel] = geo.exact[k](p[sel])
        radius = getattr(geo.exact[k], "curvature_radius", None)
        if radius is not None and curvature:
            rho[sel] = radius(p[sel])
    return n, rho


def _shading_factor(cos_shading, cos_facet):
    """Per-ray factor cos θs / cos θg that makes a shading normal's weight the Eq. 8
    integrand over the facet area the ray stands for.

    A ray of cross-section δA⊥ hitting a facet at incidence θg stands for the facet area
    δA⊥ / cos θg; with the shading normal (interpolated or exact) the integrand there is
    F(θs) cos θs, so the ray's weight is F(θs) cos θs · δA⊥ / cos θg = F(θs) δA⊥ · factor.
    F(θs) cos θs is finite up to θs = 90° (every BRDF's ``projected``), so a shading normal
    near grazing on a facet that faces the ladar no longer multiplies a divergent F by a full
    ray cross-section (F δA⊥ alone returned bins tens of times too large at mesh silhouettes).
    The expectation over rays is ∫ F(θs) cos θs dA over the facets: consistent as the mesh
    is refined. With flat normals θs = θg and the factor is 1.
    """
    cg = np.maximum(np.abs(cos_facet), _MIN_COS_FACET)
    return np.maximum(cos_shading, 0.0) / cg



def _arc_factor(n, u, cos_t, rho, spacing):
    """Per-ray weight factor that integrates the exact surface over the ray's cell.

    A slice ray stands for the transverse cell s ± δ/2. The midpoint weight F(θ)·δ assumes
    the cell covers arc δ/cos θ, which near a silhouette samples an integrable 1/√ singularity
    (order-½ convergence for coatings whose F grows like 1/cos θ). With the exact normal and
    the shape's radius of curvature ρ at the hit, the locally circular surface covers
    arc = ρ [asin(sin θ + δ/2ρ) − asin(sin θ − δ/2ρ)] (clipped at the silhouette, sin θ signed
    toward u), so the weight becomes F cos θ · arc: factor = arc cos θ / δ (1 on flat caps).
    """
    sin_signed = n[:, 0] * u[0] + n[:, 1] * u[1] + n[:, 2] * u[2]
    finite = np.isfinite(rho) & (cos_t > 0)
    r = np.where(finite, rho, 1.0)
    half = 0.5 * spacing / r
    arc = r * (np.arcsin(np.clip(sin_signed + half, -1.0, 1.0))
               - np.arcsin(np.clip(sin_signed - half, -1.0, 1.0)))
    return np.where(finite, arc * np.maximum(cos_t, 0.0) / spacing, 1.0)



def refine_t(geo, prim, origins32, w, t32):
    """Hit distances recomputed in float64 against the hit face's plane.

    Embree's t is float32 (~1e-7 of the scene's size): enough for geometry, not for a bin
    edge that coincides with a surface (the paper's first bin edge is the disk's top, where
    the glint peaks). The ray is o + t(−w) with o exactly the float32 origin cast; the face
    plane uses the float64 vertices: t = (d − n·o) / (−n·w), with d = n·v0."""
    n = geo.face_normals[prim]
    o = origins32.astype(np.float64)
    denom = -(n[:, 0] * w[0] + n[:, 1] * w[1] + n[:, 2] * w[2])
    num = geo.plane_d[prim] - (n[:, 0] * o[:, 0] + n[:, 1] * o[:, 1] + n[:, 2] * o[:, 2])
    ok = np.abs(denom) > _REFINE_MIN_COS
    return np.where(ok, num / np.where(ok, denom, 1.0), t32.astype(np.float64))



def refine_t_along(geo, prim, start, dirs, t32):
    """:func:`refine_t` for rays of their own directions: the float64 distance along each
    unit direction ``dirs`` (k, 3) from ``start`` (k, 3) or (3,) (float64, the coordinates
    the geometry is shifted to) to its hit face's plane, Embree's ``t32`` where the ray is
    within REFINE_MIN_COS of the plane."""
    n = geo.face_normals[prim]
    o = np.broadcast_to(start, dirs.shape)
    denom = n[:, 0] * dirs[:, 0] + n[:, 1] * dirs[:, 1] + n[:, 2] * dirs[:, 2]
    num = geo.plane_d[prim] - (n[:, 0] * o[:, 0] + n[:, 1] * o[:, 1] + n[:, 2] * o[:, 2])
    ok = np.abs(denom) > _REFINE_MIN_COS
    return np.where(ok, num / np.where(ok, denom, 1.0), np.asarray(t32, np.float64))


def range_offset(center, w, w_r):
    """−c·w (monostatic) or −c·(w + w_r)/2 (bistatic): the range of the shifted origin."""
    return -float(center @ w) if w_r is None else -0.5 * float(center @ (w + w_r))


# public names for the stages above (weighing, forward)
