"""The paper's own forward method (``model="pixel"``): a rasterised surface, Siddon rays.

Every shape is rasterised on a square pixel grid: a pixel belongs to a shape when its centre
lies inside it. Each filled pixel carries its shape's coating and the unit outward normal
of the implicit function's gradient at the pixel centre (the normal of the level curve
through it; radial, hence exact in direction, for disks).

For each view, parallel rays spaced ``ray_spacing`` apart across the scene travel from the
ladar along −w and are traced through the grid with Siddon's algorithm
(``meshladar.forward.siddon``) to the first filled pixel they cross: the rasterised surface.
The hit's range is that of the middle of the ray's path through the pixel. A ray of
cross-section δs covers the arc length δs / cos θ of the surface, cos θ = n·w, and deposits
F(θ) cos θ times that arc (Σ F δs → ∫ F cos θ dl), but never more arc than one ray can cover
on the true shape: the outermost ray at a silhouette covers at most sqrt(2 ρ δs) of a
boundary with radius of curvature ρ, so the weight is
F(θ) cos θ · min(δs / cos θ, sqrt(2 ρ_max δs)). Without that cap, surface
pixels whose centre normal is near grazing (cos θ → 0 on the staircase near a silhouette,
where the true surface is not) would deposit the divergent 1/cos θ of the specular lobe
(A5) and dominate the view. A pixel whose centre normal faces away (cos θ < 0, on the
staircase next to a silhouette) still stops the ray and is weighed as at grazing incidence,
the unit pair (cos θ, sin θ) = (0, 1) (:func:`meshladar.brdf.projected_weight`): its
coating's F·cos θ at θ = π/2 times that largest arc, which is 0 for a diffuse lobe and
ρs(π/2) e/(2π) for the SR glint, and 0 under received power. Hits are binned by range.

This is the pixelation baseline: positions are known to a pixel, so bins near edges and the
narrow glint lobe carry O(pixel) errors that the analytic model does not have.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
import numpy as np

from .._lazy import deferred_module
from .._validate import check_real, check_size
from ..brdf import projected_weight
from ..errors import ParameterError
from ..ladar import Ladar
from ..scene import Scene
from ..shapes import ellipse_normal
from .siddon import PixelGrid
from ..runs import array_digest
from ..sensor import check_radiometry
from ..sinogram import Sinogram
from ..stream import in_worker, joined, run_chunks
from ..precision import TINY

# compiled loops, imported (with numba) at their first use: a small run loads neither
_kernels = deferred_module("meshladar.forward._siddon_kernels")

__all__ = ["simulate_pixel", "rasterize"]


def rasterize(scene: Scene, grid: PixelGrid):
    """The scene rasterised on a grid: which shape fills each pixel, and its normals.

    A pixel belongs to a shape when its centre lies inside it. A ray entering the filled
    region from outside stops at its first filled pixel, which is always on the region's
    border: the rasterised surface. (Marking only pixels the boundary crosses would leave
    diagonal gaps through which rays slip to the far side.)

    Parameters
    ----------
    scene : Scene
        A scene of analytic shapes (disks and ellipses, ``scene.shapes``); where shapes
        overlap, the later one owns the pixel.
    grid : PixelGrid
        The pixels; pixel ``[i, j]`` is centred at ``(grid.x[j], grid.y[i])``.

    Returns
    -------
    owner : (ny, nx) int
        Index of the shape filling the pixel, −1 outside every shape.
    normal : (ny, nx, 2) float
        Unit outward normal of the shape's level curve through the pixel centre (the
        gradient of (x'/A)² + (y'/B)², radial for a disk); 0 outside and at a centre.
    """
    xc, yc = np.meshgrid(grid.x, grid.y)
    owner = np.full(grid.shape, -1, dtype=np.int64)
    normal = np.zeros(grid.shape + (2,))
    for k, shape in enumerate(scene.shapes):
        inside = shape.implicit(np.stack([xc, yc], -1)) < 1.0
        nx, ny = ellipse_normal(shape.center, shape.axes, shape.angle, xc[inside], yc[inside])
        owner[inside] = k
        normal[inside] = np.stack([nx, ny], -1)
    return owner, normal


#: A chunk of a streaming run holds at most this many views, and this many rays (memory).
_VIEWS_PER_CHUNK = 32
_RAYS_PER_CHUNK = 2_000_000


def simulate_pixel(scene: Scene, ladar: Ladar, *, pixel_size=None, ray_spacing=None,
                   radiometry="paper", jobs=None, executor=None, progress=False,
                   run_dir=None) -> Sinogram:
    """Range profiles by the paper's pixel method (see the module docstring).

    Parameters
    ----------
    scene, ladar : Scene, Ladar
    pixel_size : float, optional
        Side of the square pixels; default the narrowest range bin.
    ray_spacing : float, optional
        Transverse distance between parallel rays; default pixel_size / 4.
    radiometry : {"paper", "power"}
        "paper" (default): Eq. 8; "power": received power, one cos θ more per hit
        (:mod:`meshladar.sensor`).
    jobs, executor, progress, run_dir : keyword-only
        Streaming options, as :func:`meshladar.simulate` (chunks of views on worker
        processes or any executor, a progress bar over the views, a resumable run folder).

    Returns
    -------
    Sinogram
        ``values`` (n_views, n_bins) bin integrals (paper Eq. 8); ``info`` holds
        ``radiometry``, ``pixel_size``, ``ray_spacing`` and ``n_rays`` per view.

    Raises
    ------
    ParameterError
        If ``radiometry`` is not a valid choice, ``pixel_size`` or ``ray_spacing`` is not a
        finite real > 0, ``pixel_size`` exceeds half the smallest semi-axis of any shape,
        or the pixel grid or the rays would need more memory than meshladar allocates at
        once.

    References
    ----------
    Jin & Levine (2009), Eq. 8 (each hit's weight), and Section 4 (the pixel method with
    Siddon ray tracing, their ref. 29).
    """
    power = check_radiometry(radiometry)
    width = float(np.min(np.diff(ladar.bin_edges)))
    pix = check_real("pixel_size", width if pixel_size is None else pixel_size, low=0.0,
                     low_open=True)
    ds = check_real("ray_spacing", pix / 4 if ray_spacing is None else ray_spacing, low=0.0,
                    low_open=True)
    payload = _pixel_job(scene, ladar, pix, ds, power)
    n_rays = payload.s_rel.size
    job = None
    if run_dir is not None:
        job = {"kind": "simulate_pixel", "radiometry": radiometry,
               "shapes": [repr(s) for s in scene.shapes], "pixel_size": pix, "ray_spacing": ds,
               "angles_deg": array_digest(ladar.angles_deg),
               "bin_edges": array_digest(ladar.bin_edges)}
    results = run_chunks(_views, payload, ladar.n_views,
                         chunk_size=max(1, min(_VIEWS_PER_CHUNK, _RAYS_PER_CHUNK // n_rays)),
                         jobs=jobs, executor=executor, progress=progress, run_dir=run_dir,
                         job=job, arrays={"values": (ladar.n_bins,)})
    return Sinogram(joined(results, "values"), angles_deg=ladar.angles_deg,
                    bin_edges=ladar.bin_edges, model="pixel",
                    info={"radiometry": radiometry, "units": "length/sr (per unit height)",
                          "pixel_size": pix, "ray_spacing": ds,
                          "n_rays": n_rays})


def _pixel_job(scene, ladar, pix, ds, power):
    """What every chunk of views shares (:class:`_PixelJob`): the scene rasterised with
    pixels of side ``pix`` and the layout of rays ``ds`` apart, after the pixel size is
    checked against the shapes and the grid and the rays against memory."""
    smallest = min(min(sh.axes) for sh in scene.shapes)
    if pix > 0.5 * smallest:
        raise ParameterError(f"pixel_size must be at most {0.5 * smallest:g} (half the "
                             f"smallest shape's semi-axis, {smallest:g}), so that every shape "
                             f"covers pixels; got {pix:g}")
    (cx, cy), radius = scene.bounding_circle()
    half = radius + 2 * pix
    n = int(math.ceil(2 * half / pix))
    check_size("pixel_size", float(n) * n, 40, f"a {n} x {n} pixel grid (pixel size {pix:g})",
               "give a larger pixel_size")
    check_size("ray_spacing", float(math.ceil(2 * half / ds)), 8 * 8,
               f"rays spaced {ds:g} over a scene {2 * half:g} across", "give a larger "
               "ray_spacing")
    grid = PixelGrid(n, n, pix, (cx - n * pix / 2, cy - n * pix / 2))
    owner, normal = rasterize(scene, grid)
    mask = (owner >= 0).astype(np.float64)

    n_rays = int(math.ceil(2 * half / ds))
    s_rel = (np.arange(n_rays) - (n_rays - 1) / 2) * ds          # about the scene centre
    # the most arc one ray covers: sqrt(2 ρ δs) at a silhouette of curvature radius ρ
    arc_max = [math.sqrt(2.0 * max(sh.axes) ** 2 / min(sh.axes) * ds) for sh in scene.shapes]
    return _PixelJob(mask, grid, owner.ravel(), normal.reshape(-1, 2),
                     tuple(s.material for s in scene.shapes), arc_max, s_rel, (cx, cy),
                     2 * half, ds, np.deg2rad(ladar.angles_deg), ladar.bin_edges, power)


@dataclass(frozen=True)
class _PixelJob:
    """What every chunk of views shares: the rasterised scene and the rays' layout."""

    mask: np.ndarray            # (H, W) 1 where a shape covers the pixel
    grid: PixelGrid
    flat_owner: np.ndarray      # (H·W,) the shape index of each pixel, −1 outside
    flat_normal: np.ndarray     # (H·W, 2) the outward normal of each pixel
    materials: tuple            # one per shape
    arc_max: list               # the most arc one ray covers, per shape
    s_rel: np.ndarray           # the rays' transverse offsets about the scene centre
    center: tuple               # (cx, cy), the scene centre
    distance: float             # how far toward the ladar the rays start
    ds: float                   # the ray spacing
    phi: np.ndarray             # every view's angle (rad)
    edges: np.ndarray           # the range bin edges
    power: bool                 # radiometry "power" (else "paper")


def _views(payload, views):
    """The stream's per-chunk job: the profiles of views ``views``."""
    p = payload
    mask, grid, flat_owner, flat_normal = p.mask, p.grid, p.flat_owner, p.flat_normal
    materials, arc_max, s_rel, (cx, cy) = p.materials, p.arc_max, p.s_rel, p.center
    distance, ds, phi, edges, power = p.distance, p.ds, p.phi, p.edges, p.power
    n_rays, n_bins = s_rel.size, edges.size - 1
    w = np.stack([np.cos(phi[views]), np.sin(phi[views])], -1)
    u = np.stack([-np.sin(phi[views]), np.cos(phi[views])], -1)
    r_c = -(w @ np.array([cx, cy]))
    # rays across the scene, starting `distance` toward the ladar (past the grid), along −w
    o = (np.array([cx, cy])[None, None, :] + s_rel[None, :, None] * u[:, None, :]
         + distance * w[:, None, :])
    ox, oy = o[..., 0].ravel(), o[..., 1].ravel()
    dx = np.repeat(-w[:, 0], n_rays)
    dy = np.repeat(-w[:, 1], n_rays)
    hit = np.empty(ox.size, np.int64)
    alpha = np.empty(ox.size)
    first_hits = _kernels.siddon_first_hits_serial if in_worker() else _kernels.siddon_first_hits
    first_hits(mask, ox, oy, dx, dy, *grid._args(), hit, alpha)
    got = hit >= 0
    view = np.repeat(np.arange(views.size), n_rays)[got]
    pixel_idx = hit[got]
    # range of the hit: r = r_c − distance + α (the origin sits `distance` toward w)
    rng = r_c[view] - distance + alpha[got]
    cos_t = np.einsum("ij,ij->i", flat_normal[pixel_idx], w[view])
    sin_t = np.abs(flat_normal[pixel_idx, 0] * w[view, 1] - flat_normal[pixel_idx, 1]
                   * w[view, 0])
    weight = np.zeros(view.size)
    own = flat_owner[pixel_idx]
    for k, m in enumerate(materials):
        sel = own == k
        c, s = cos_t[sel], sin_t[sel]     # c < 0 (facing away) is weighed as (0, 1)
        arc = np.minimum(ds / np.maximum(c, TINY), arc_max[k])
        weight[sel] = projected_weight(m, c, s) * arc * (np.maximum(c, 0.0) if power else 1.0)
    b = np.searchsorted(edges, rng, side="right") - 1
    ok = (b >= 0) & (b < n_bins)
    values = np.bincount(view[ok] * n_bins + b[ok], weights=weight[ok],
                         minlength=views.size * n_bins).reshape(views.size, n_bins)
    return {"values": values}
