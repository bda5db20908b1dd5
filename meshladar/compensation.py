"""BRDF compensation: reconstruct the surface as if it returned light equally to every view.

A surface point's return depends on the view through its BRDF and its normal: the weight
h(θ) = F(θ; −θ) cos θ (``radiometry="paper"``, Eq. 8; times another cos θ for received
power) falls to 0 at glancing incidence, is 0 from behind, and is 0 where another surface
shadows it. FBP assumes every view sees every pixel equally, and the missing glancing and
hidden views are what darkens the inside of a reconstructed boundary (the paper's Sec. 4.A)
and draws the crossed shadow streaks (Sec. 4.C).

Compensation puts that view dependence into the projector instead:

1. a first reconstruction (default: FBP of the log radiance, where weak surfaces show next
   to glints) gives sub-pixel surface points and normals (Steger's ridge detector: across
   a bright thin ridge the Hessian's most negative eigenvector), turned outward by the
   data (the side from which the views see returns), then moved together along their
   normals by the offset (within ±1 bin) that fits the data best;
2. :func:`surface_weights` evaluates, per surface pixel and view, h(θ) / ⟨h⟩ (⟨h⟩ the mean
   of h over all directions in the plane), 0 from behind and, with ``shadows``, 0 where the
   ray to the ladar crosses another surface of the first reconstruction;
3. :class:`SurfaceProjector` projects those points as short straight segments with those
   weights, and :func:`compensate` solves for the image with it (CGLS or SIRT of
   :mod:`meshladar.iterative`), masked to the surface pixels.

The result is in FBP's units: a surface of line density 1 reads ⟨h⟩ per unit length, as a
reflector that returned its view-averaged power to every view would under FBP. The
coatings must be known (``material``: one BRDF, or several with a label image).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._validate import check_choice, check_count, check_real, check_sinogram, finite_array
from .errors import ParameterError

__all__ = ["Surface", "estimate_surface", "surface_weights", "SurfaceProjector", "compensate"]

#: Samples of the tabulated weight h(θ) on [0, π/2].
_TABLE = 8193


@dataclass(frozen=True)
class Surface:
    """Surface points on an image grid, one per pixel the surface crosses, with outward
    normals.

    Attributes
    ----------
    points : (n, 2) array
        Sub-pixel points (x, y) on the surface's centre line, scene units.
    rows, cols : (n,) int arrays
        The pixel ``[rows, cols]`` of a ``size`` × ``size`` grid that holds each point.
    normals : (n, 2) array
        Outward unit normals (x, y).
    size, extent, center
        The grid, as :class:`meshladar.Image`.
    shadowed : (n, n_views) bool array or None
        Where another surface lies between the point and the ladar of each view.
    """

    points: np.ndarray
    rows: np.ndarray
    cols: np.ndarray
    normals: np.ndarray
    size: int
    extent: float
    center: tuple[float, float]
    shadowed: np.ndarray | None = None

    def __repr__(self) -> str:
        from ._summary import text

        return text("Surface", ("points", int(self.points.shape[0])), ("size", self.size),
                    ("extent", float(self.extent)),
                    ("shadow_map", None if self.shadowed is None else self.shadowed.shape))

    @property
    def mask(self) -> np.ndarray:
        """The pixels holding surface points, as a (size, size) bool image."""
        m = np.zeros((self.size, self.size), bool)
        m[self.rows, self.cols] = True
        return m

    @property
    def grid(self):
        from .siddon import PixelGrid

        return PixelGrid.square(self.size, self.extent, self.center)

    @property
    def pixel_size(self) -> float:
        return 2.0 * self.extent / self.size


def _ridges(values, sigma, threshold):
    """Steger's sub-pixel ridge points (IEEE PAMI 20, 1998) of a bright thin structure:
    across a ridge the Gaussian Hessian has a strongly negative eigenvalue, whose
    eigenvector n is the normal; the intensity's maximum along n lies at t = −(∇I·n) /
    (nᵀ H n) from the pixel centre, and the pixel holds a ridge point when that maximum is
    inside it. Keeps points whose strength (−eigenvalue) reaches ``threshold`` × the
    largest. Returns (rows, cols, offsets (n, 2) in pixels (x, y), normals (n, 2))."""
    from scipy.ndimage import gaussian_filter

    d = {o: gaussian_filter(values, sigma, order=o) for o in
         ((0, 1), (1, 0), (0, 2), (2, 0), (1, 1))}
    gx, gy, hxx, hyy, hxy = d[0, 1], d[1, 0], d[0, 2], d[2, 0], d[1, 1]
    root = np.hypot(0.5 * (hxx - hyy), hxy)
    low = 0.5 * (hxx + hyy) - root
    high = 0.5 * (hxx + hyy) + root
    # a ridge curves down across itself only; a blob (a point-like artefact) both ways
    strength = np.where(high > 0.5 * low, np.maximum(-low, 0.0), 0.0)
    peak = float(strength.max(initial=0.0))
    if peak <= 0:
        raise ParameterError("first has no bright ridge: no surface to compensate")
    # the larger eigenvalue's eigenvector is at ½ atan2(2 hxy, hxx − hyy); n ⟂ it
    a = 0.5 * np.arctan2(2.0 * hxy, hxx - hyy) + 0.5 * math.pi
    nx, ny = np.cos(a), np.sin(a)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = -(gx * nx + gy * ny) / low          # nᵀ H n = low along its own eigenvector
    ok = ((strength >= threshold * peak) & np.isfinite(t) & (np.abs(t * nx) <= 0.5)
          & (np.abs(t * ny) <= 0.5))
    rows, cols = np.nonzero(ok)
    tt = t[rows, cols]
    n = np.stack([nx[rows, cols], ny[rows, cols]], axis=1)
    return rows, cols, tt[:, None] * n, n


def estimate_surface(first, sino, *, threshold=0.2, sigma=1.5, shadows=True):
    """Surface points and outward normals from a first reconstruction.

    Parameters
    ----------
    first : Image
        A first reconstruction of ``sino`` in which every surface is a bright ridge (FBP
        of :func:`~meshladar.log_radiance` shows weak surfaces next to glints).
    sino : Sinogram
        The data, which decides each normal's sign: a surface faces the views that see it,
        so the sign whose front half of the views holds more returns (summed as
        :func:`~meshladar.log_radiance`, so weak surfaces next to glints count) wins.
    threshold : float in (0, 1)
        Keep ridge points at least this fraction of the strongest ridge's strength.
    sigma : float
        Gaussian scale, pixels, of the ridge detector.
    shadows : bool
        Also find, per point and view, whether another surface hides it from the ladar
        (:attr:`Surface.shadowed`).
    """
    from . import _kernels
    from .reconstruct import Image, log_radiance

    if not isinstance(first, Image):
        raise ParameterError(f"first must be a meshladar.Image; got {type(first).__name__}")
    check_sinogram("sino", sino)
    threshold = check_real("threshold", threshold, low=0.0, high=1.0, low_open=True,
                           high_open=True)
    sigma = check_real("sigma", sigma, low=0.0, low_open=True)
    rows, cols, offset, normals = _ridges(first.values, sigma, threshold)
    if rows.size == 0:
        raise ParameterError("no surface points found in first")
    pix = 2.0 * first.extent / first.size
    x0 = first.center[0] - first.extent
    y0 = first.center[1] - first.extent
    points = np.stack([x0 + (cols + 0.5 + offset[:, 0]) * pix,
                       y0 + (rows + 0.5 + offset[:, 1]) * pix], axis=1)
    phi = np.deg2rad(sino.angles_deg)
    cos_phi, sin_phi = np.cos(phi), np.sin(phi)
    lit = np.ascontiguousarray(log_radiance(sino).values)   # every return counts, glints too
    side = np.sign(normals[:, :1] * cos_phi + normals[:, 1:] * sin_phi)       # (n, views)
    e0, inv_dr = _uniform(sino.bin_edges)
    seen = np.zeros(rows.size)
    bare = Surface(points, rows, cols, normals, first.size, first.extent, first.center)
    _kernels.surface_backproject(lit, *_segments(bare, side), cos_phi, sin_phi, e0, inv_dr,
                                 seen)
    normals[seen < 0] *= -1.0
    shadowed = None
    if shadows:
        from scipy.ndimage import binary_dilation

        mask = np.zeros(first.shape, bool)
        mask[rows, cols] = True
        occupied = binary_dilation(mask).astype(np.uint8)
        shadowed = np.zeros((rows.size, phi.size), bool)
        _kernels.surface_shadows(occupied, rows, cols, cos_phi, sin_phi, shadowed)
    return Surface(points, rows, cols, normals, first.size, first.extent, first.center,
                   shadowed)


def _uniform(edges):
    """(first edge, 1 / bin width) of uniform bins."""
    w = np.diff(edges)
    if np.ptp(w) > 1e-9 * w.mean():
        raise ParameterError("compensation needs uniform range bins")
    return float(edges[0]), 1.0 / float(w.mean())


def _segments(surface, H):
    """The kernels' segment arguments: centres, tangents, half-lengths, weights."""
    from scipy.spatial import cKDTree

    p, n = surface.points, surface.normals
    # each segment reaches halfway to its two nearest neighbours along the surface
    if p.shape[0] > 2:
        d, _ = cKDTree(p).query(p, k=3)
        half = np.minimum(0.25 * (d[:, 1] + d[:, 2]), surface.pixel_size)
    else:
        half = np.full(p.shape[0], 0.5 * surface.pixel_size)
    c = np.ascontiguousarray
    return (c(p[:, 0]), c(p[:, 1]), c(-n[:, 1]), c(n[:, 0]), half, c(H))


def _weight_table(material, radiometry, blur_deg):
    """(θ grid on [0, π/2], h(θ)/⟨h⟩): the monostatic weight blurred by a Gaussian of
    ``blur_deg`` in θ (the normals' uncertainty) and divided by its mean over the plane's
    directions, ⟨h⟩ = (1/π) ∫₀^{π/2} h dθ."""
    from scipy.ndimage import gaussian_filter1d

    theta = np.linspace(0.0, 0.5 * math.pi, _TABLE)
    c, s = np.cos(theta), np.sin(theta)
    h = np.asarray(material.projected(c, s), dtype=float)
    if radiometry == "power":
        h = h * c
    if blur_deg > 0:
        step = theta[1] - theta[0]
        # mirror at normal incidence (h is even in θ), zero beyond the horizon
        full = np.concatenate([h[:0:-1], h, np.zeros(_TABLE - 1)])
        full = gaussian_filter1d(full, math.radians(blur_deg) / step, mode="constant")
        h = full[_TABLE - 1:2 * _TABLE - 1]
    mean = float(np.trapezoid(h, theta)) / math.pi
    if not mean > 0:
        raise ParameterError(f"material {material!r} returns no light to a monostatic ladar")
    return theta, h / mean


def surface_weights(surface, angles_deg, material, *, labels=None, radiometry="paper",
                    blur_deg=1.0):
    """(n_pixels, n_views) view weights h(θ)/⟨h⟩ of :class:`Surface` pixels, θ between the
    pixel's normal and the view, 0 from behind or where shadowed.

    ``material`` is one BRDF, or a sequence of them with ``labels`` a (size, size) int image
    giving each pixel's index into it."""
    from .brdf import BRDF, check_brdf
    from .sensor import check_radiometry

    radiometry = "power" if check_radiometry(radiometry) else "paper"
    blur_deg = check_real("blur_deg", blur_deg, low=0.0)
    mats = [material] if isinstance(material, BRDF) else list(material)
    for i, m in enumerate(mats):
        check_brdf(f"material[{i}]", m)
    if len(mats) == 1:
        which = np.zeros(surface.rows.size, int)
    else:
        if labels is None:
            raise ParameterError("several materials need labels: a (size, size) int image "
                                 "of indices into material")
        lab = np.asarray(labels)
        if lab.shape != (surface.size, surface.size):
            raise ParameterError(f"labels must be a ({surface.size}, {surface.size}) array; "
                                 f"got {lab.shape}")
        which = lab[surface.rows, surface.cols].astype(int)
        if which.min() < 0 or which.max() >= len(mats):
            raise ParameterError(f"labels on the surface must be in [0, {len(mats)}); got "
                                 f"{which.min()}..{which.max()}")
    phi = np.deg2rad(finite_array("angles_deg", angles_deg).ravel())
    cos_t = surface.normals[:, :1] * np.cos(phi) + surface.normals[:, 1:] * np.sin(phi)
    theta = np.arccos(np.clip(np.abs(cos_t), 0.0, 1.0))
    H = np.zeros(cos_t.shape)
    for i, m in enumerate(mats):
        sel = which == i
        grid, h = _weight_table(m, radiometry, blur_deg)
        H[sel] = np.interp(theta[sel], grid, h)
    H[cos_t <= 0] = 0.0
    if surface.shadowed is not None:
        if surface.shadowed.shape != H.shape:
            raise ParameterError(f"the surface's shadow map has {surface.shadowed.shape[1]} "
                                 f"views; the sinogram has {H.shape[1]}")
        H[surface.shadowed] = 0.0
    return H


class SurfaceProjector:
    """A: image → (n_views, n_bins), the exact projector of a :class:`Surface` as straight
    segments (one per surface pixel, through its point, along its tangent, halfway to its
    neighbours), each weighted per view by ``H`` (:func:`surface_weights`) and spread over
    the bins its range interval covers; ``A.T`` its exact adjoint (zero off the surface).
    With ``smooth`` > 0 (pixels), the values are first averaged along the surface by a
    Gaussian of that width (A S, adjoint Sᵀ Aᵀ). Image values are areal densities (a segment carries value × pixel
    area), as FBP's. Composes with :func:`~meshladar.iterative.sirt` and
    :func:`~meshladar.iterative.cgls` through ``projector=``."""

    def __init__(self, surface, angles_deg, bin_edges, H, smooth=0.0):
        self.surface = surface
        self.smooth = _smoother(surface, check_real("smooth", smooth, low=0.0))
        self.grid = surface.grid
        self.angles_deg = finite_array("angles_deg", angles_deg).ravel()
        self.bin_edges = finite_array("bin_edges", bin_edges).ravel()
        self.e0, self.inv_dr = _uniform(self.bin_edges)
        self.n_views, self.n_bins = self.angles_deg.size, self.bin_edges.size - 1
        H = np.asarray(H, dtype=float)
        if H.shape != (surface.rows.size, self.n_views):
            raise ParameterError(f"H must be ({surface.rows.size}, {self.n_views}); got "
                                 f"{H.shape}")
        # image values are areal densities: a segment carries value × pixel area
        self.H = np.ascontiguousarray(H * self.grid.pixel_size ** 2)
        phi = np.deg2rad(self.angles_deg)
        self.cos, self.sin = np.cos(phi), np.sin(phi)

    @property
    def shape(self):
        return (self.n_views * self.n_bins, self.grid.nx * self.grid.ny)

    def _args(self):
        return (*_segments(self.surface, self.H), self.cos, self.sin, self.e0, self.inv_dr)

    def __matmul__(self, image):
        from . import _kernels

        v = np.asarray(image, float)[self.surface.rows, self.surface.cols]
        if self.smooth is not None:
            v = self.smooth @ v
        v = np.ascontiguousarray(v)
        out = np.zeros((self.n_views, self.n_bins))
        _kernels.surface_project(v, *self._args(), out)
        return out

    @property
    def T(self):
        return _SurfaceAdjoint(self)


class _SurfaceAdjoint:
    def __init__(self, forward):
        self._f = forward

    def __matmul__(self, values):
        from . import _kernels

        f = self._f
        q = np.ascontiguousarray(np.asarray(values, float).reshape(f.n_views, f.n_bins))
        acc = np.zeros(f.surface.rows.size)
        _kernels.surface_backproject(q, *f._args(), acc)
        if f.smooth is not None:
            acc = f.smooth.T @ acc
        out = np.zeros(f.grid.shape)
        out[f.surface.rows, f.surface.cols] = acc
        return out


def _backed(surface, H, sino, keep, share=0.5):
    """For the points ``keep``: whether at least ``share`` of their strong views (weight ≥
    ¼ of their largest) find returns in their bins (above the noise floor, or any count
    in counted data)."""
    from . import _kernels

    sub = _subset(surface, keep)
    h = H[keep]
    strong = (h >= 0.25 * h.max(axis=1, keepdims=True)).astype(float)
    # any count backs a point (at one photoelectron expected per bin, 63 % of its bins
    # hold one); sparse noise counts do not line up along a point's sinusoid
    from .reconstruct import _noise_floor

    lit = (sino.values > _noise_floor(sino, quanta=0.5) * float(np.abs(sino.values).max())
           ).astype(float)
    e0, inv_dr = _uniform(sino.bin_edges)
    phi = np.deg2rad(sino.angles_deg)
    hits = np.zeros(sub.rows.size)
    args = _segments(sub, strong)
    _kernels.surface_backproject(lit, *args, np.cos(phi), np.sin(phi), e0, inv_dr, hits)
    return hits >= share * strong.sum(axis=1)


def first_image(sino, size, extent=1.0, center=(0.0, 0.0)):
    """The default first reconstruction: FBP of the log radiance, its floor at half a
    count (or above the noise) so weak surfaces next to glints show and noise does not
    (FBP's few-views warning is for FBP's own output, not for this intermediate)."""
    import warnings

    from .errors import MeshladarWarning
    from .reconstruct import _noise_floor, fbp, log_radiance

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MeshladarWarning)
        return fbp(log_radiance(sino, floor=_noise_floor(sino, 0.5)), size=size,
                   extent=extent, center=center)


def _subset(surface, keep):
    import dataclasses

    return dataclasses.replace(
        surface, points=surface.points[keep], rows=surface.rows[keep],
        cols=surface.cols[keep], normals=surface.normals[keep],
        shadowed=None if surface.shadowed is None else surface.shadowed[keep])


def _smoother(surface, width):
    """The sparse operator that averages each surface point's value with its neighbours
    within 2 ``width`` (pixels) under a Gaussian of that width, or None for 0: the solution
    is then smooth along the surface by construction (x = S z)."""
    if width == 0:
        return None
    from scipy.sparse import csr_matrix
    from scipy.spatial import cKDTree

    p = surface.points / surface.pixel_size
    pairs = cKDTree(p).query_pairs(2.0 * width, output_type="ndarray")
    i = np.r_[pairs[:, 0], pairs[:, 1], np.arange(len(p))]
    j = np.r_[pairs[:, 1], pairs[:, 0], np.arange(len(p))]
    d2 = np.sum((p[i] - p[j]) ** 2, axis=1)
    S = csr_matrix((np.exp(-0.5 * d2 / width ** 2), (i, j)), shape=(len(p), len(p)))
    return csr_matrix(S.multiply(1.0 / np.asarray(S.sum(axis=1))))


def _uniform_fit(A, m, b, W):
    """(x0, weighted residual) of the best uniform surface c·m."""
    Am = A @ m
    c = float(np.sum(W * Am * b)) / (float(np.sum(W * Am * Am)) or 1.0)
    return c * m, float(np.sum(W * (b - c * Am) ** 2))


def _settle(surface, sino, H, W, m, smooth):
    """Shift every surface point along its normal by the one offset in ±1 bin that lets a
    uniform surface fit the data best. A first reconstruction puts a thin surface at the
    centre of the bin its returns pile into, up to half a bin off (inward on a convex
    surface); the projector is exact, so that offset shows as a residual. Returns
    (surface, shift, projector, uniform start): the uniform start keeps the solvers from
    speckling along the surface, where neighbouring points share their ranges."""
    import dataclasses

    dr = float(np.mean(np.diff(sino.bin_edges)))
    best = None
    for shift in np.linspace(-1.0, 1.0, 9) * dr:
        s = dataclasses.replace(surface, points=surface.points + shift * surface.normals)
        A = SurfaceProjector(s, sino.angles_deg, sino.bin_edges, H, smooth)
        x0, res = _uniform_fit(A, m, sino.values, W)
        if best is None or res < best[0]:
            best = (res, s, float(shift), A, x0)
    return best[1:]


#: Solvers for :func:`compensate`.
SOLVERS = ("cgls", "sirt")


def compensate(sino, material, *, size=256, extent=1.0, center=(0.0, 0.0), first=None,
               labels=None, method="cgls", n_iter=30, weights=None, threshold=0.2,
               sigma=1.5, shadows=True, blur_deg=1.0, smooth=2.0, surface=None, tol=None,
               progress=False):
    """BRDF- and shadow-compensated reconstruction (see the module docstring).

    Parameters
    ----------
    sino : Sinogram
        Views about z, uniform bins; its ``info["radiometry"]`` picks h(θ).
    material : BRDF or sequence of BRDFs
        The coatings (with ``labels`` when several).
    size, extent, center
        The image grid.
    first : Image, optional
        The first reconstruction on that grid (default FBP of the log radiance).
    labels : (size, size) int array, optional
        Each pixel's index into ``material``.
    method : {"cgls", "sirt"}
        The solver (:mod:`meshladar.iterative`), ``n_iter`` iterations, warm start zero.
    weights : (n_views, n_bins) array, optional
        Per-bin data weights (e.g. :func:`~meshladar.iterative.glint_weights`).
    threshold, sigma, shadows
        :func:`estimate_surface`.
    blur_deg : float
        Angular blur of h(θ), degrees, for the normals' uncertainty.
    smooth : float
        Width, pixels, of the Gaussian along the surface that the solution is built from
        (x = S z, :class:`SurfaceProjector`): neighbouring surface points share their
        ranges in most views, and without it the solution speckles along the surface.
        0 solves for every point independently.
    surface : Surface, optional
        Use these surface pixels and normals instead of estimating them.
    tol, progress
        As :func:`~meshladar.iterative.sirt`.

    Returns
    -------
    Image
        ``info``: method "compensated", solver, iterations, residuals, radiometry,
        surface_pixels, shadowed_fraction (of front-facing point-views), blur_deg,
        surface_shift (the offset along the normals, scene units).
    """
    from .iterative import cgls, sirt

    check_sinogram("sino", sino)
    method = check_choice("method", method, SOLVERS)
    size = check_count("size", size)
    radiometry = sino.info.get("radiometry", "paper")
    if surface is None:
        if first is None:
            first = first_image(sino, size, extent, center)
        surface = estimate_surface(first, sino, threshold=threshold, sigma=sigma,
                                   shadows=shadows)
    elif not isinstance(surface, Surface):
        raise ParameterError(f"surface must be a meshladar.compensation.Surface; got "
                             f"{type(surface).__name__}")
    if (surface.size, surface.extent, tuple(surface.center)) != (
            size, float(extent), tuple(float(c) for c in center)):
        raise ParameterError("surface must be on the image grid (size, extent, center)")
    H = surface_weights(surface, sino.angles_deg, material, labels=labels,
                               radiometry=radiometry, blur_deg=blur_deg)
    # a point no view sees (hidden behind another surface in all its front views: an
    # artefact inside a shape) carries no data, one seen only at glancing incidence (total
    # weight under 5 % of the median point's) would take any value, and a point the data
    # does not back (a noise ridge: its strong views' bins mostly empty) is not a surface
    total = H.sum(axis=1)
    seen = total > 0.05 * float(np.median(total[total > 0])) if total.any() else total > 0
    seen[seen] = _backed(surface, H, sino, seen)
    if not seen.any():
        raise ParameterError("no surface point of the first reconstruction is seen by the "
                             "data; give first= or a lower threshold")
    if not seen.all():
        surface = _subset(surface, seen)
        H = H[seen]
    W = np.ones(sino.shape) if weights is None else finite_array("weights", weights)
    m = surface.mask.astype(float)
    surface, shift, A, x0 = _settle(surface, sino, H, W, m, smooth)
    solve = cgls if method == "cgls" else sirt
    img = solve(sino, size=size, extent=extent, center=center, n_iter=n_iter, x0=x0,
                weights=weights, mask=surface.mask, projector=A, tol=tol, progress=progress)
    values = np.array(img.values)
    if A.smooth is not None:                          # the solution is x = S z
        values[surface.rows, surface.cols] = A.smooth @ values[surface.rows, surface.cols]
    phi = np.deg2rad(sino.angles_deg)
    front = (surface.normals[:, :1] * np.cos(phi) + surface.normals[:, 1:] * np.sin(phi)) > 0
    shadowed = 0.0 if surface.shadowed is None else float(
        (surface.shadowed & front).sum() / max(1, front.sum()))
    info = dict(img.info, method="compensated", solver=method, radiometry=radiometry,
                surface_pixels=int(surface.rows.size), shadowed_fraction=shadowed,
                blur_deg=blur_deg, shadows=surface.shadowed is not None,
                surface_shift=shift, smooth=smooth)
    return type(img)(values, img.extent, img.center, info=info)
