"""Surface estimation for BRDF compensation (:mod:`meshladar.reconstruct.compensation`):
sub-pixel surface points and outward normals from a first reconstruction (Steger's ridge
detector, turned outward by the data), the shadow map of each point and view, and the view
weights h(θ)/⟨h⟩ of each point (the paper's Eq. 8 over the mean of h in the plane).
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import binary_dilation, gaussian_filter, gaussian_filter1d
from scipy.spatial import cKDTree

from .._summary import text
from .._validate import check_real, check_sinogram, finite_array
from ..brdf import BRDF, check_brdf
from ..errors import ParameterError
from ..images import Image
from ..sensor import check_radiometry
from ..forward.siddon import PixelGrid
from ._kernels import surface_backproject, surface_shadows
from .radiance import log_radiance

__all__ = ["Surface", "estimate_surface", "surface_weights"]

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
        return PixelGrid.square(self.size, self.extent, self.center)

    @property
    def pixel_size(self) -> float:
        return 2.0 * self.extent / self.size


class _Ridges(NamedTuple):
    """Ridge points of an image: pixel rows and columns, sub-pixel offsets (n, 2) in pixels
    (x, y), and normals (n, 2)."""

    rows: np.ndarray
    cols: np.ndarray
    offsets: np.ndarray
    normals: np.ndarray


class _Segments(NamedTuple):
    """The surface kernels' segment arguments (flat, for the compiled loops): centres x, y,
    tangents tx, ty, half-lengths and the per-view weights H."""

    x: np.ndarray
    y: np.ndarray
    tx: np.ndarray
    ty: np.ndarray
    half: np.ndarray
    H: np.ndarray


def _ridges(values, sigma, threshold):
    """Steger's sub-pixel ridge points (IEEE PAMI 20, 1998) of a bright thin structure:
    across a ridge the Gaussian Hessian has a strongly negative eigenvalue, whose
    eigenvector n is the normal; the intensity's maximum along n lies at t = −(∇I·n) /
    (nᵀ H n) from the pixel centre, and the pixel holds a ridge point when that maximum is
    inside it. Keeps points whose strength (−eigenvalue) reaches ``threshold`` × the
    largest. Returns :class:`_Ridges` (rows, cols, offsets (n, 2) in pixels (x, y),
    normals (n, 2))."""
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
    return _Ridges(rows, cols, tt[:, None] * n, n)


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
    threshold : float in (0, 1), keyword-only, default 0.2
        Keep ridge points at least this fraction of the strongest ridge's strength.
    sigma : float in (0, size], keyword-only, default 1.5
        Gaussian scale, pixels, of the ridge detector (at most the image's size).
    shadows : bool, keyword-only, default True
        Also find, per point and view, whether another surface hides it from the ladar
        (:attr:`Surface.shadowed`).

    Returns
    -------
    Surface
        One point per pixel whose ridge maximum lies inside it: ``points`` (n, 2) on
        ``first``'s grid (scene units), outward unit ``normals`` (n, 2), and with
        ``shadows`` the (n, n_views) shadow map, else None. A point is shadowed in a view
        when the ray from its pixel toward the ladar, in half-pixel steps, leaves the
        (one-pixel dilated) surface pixels, stays out for two pixels and meets them
        again.

    Raises
    ------
    ParameterError
        When ``first`` is not a :class:`~meshladar.Image` or ``sino`` not a
        :class:`~meshladar.Sinogram`; ``threshold`` or ``sigma`` is outside its range;
        ``first`` has no bright ridge or no ridge point passes ``threshold``; or the bins
        are not uniform (to 1e-9 of their mean width).

    References
    ----------
    C. Steger, "An unbiased detector of curvilinear structures", IEEE Trans. Pattern
    Anal. Mach. Intell. 20 (1998) (sub-pixel ridge points and their normals from the
    Gaussian Hessian).
    """
    if not isinstance(first, Image):
        raise ParameterError(f"first must be a meshladar.Image; got {type(first).__name__}")
    check_sinogram("sino", sino)
    threshold = check_real("threshold", threshold, low=0.0, high=1.0, low_open=True,
                           high_open=True)
    sigma = check_real("sigma", sigma, low=0.0, low_open=True,
                       high=float(max(first.values.shape)))
    ridges = _ridges(first.values, sigma, threshold)
    rows, cols, offset, normals = ridges.rows, ridges.cols, ridges.offsets, ridges.normals
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
    surface_backproject(lit, *_segments(bare, side), cos_phi, sin_phi, e0, inv_dr, seen)
    normals[seen < 0] *= -1.0
    shadowed = None
    if shadows:
        mask = np.zeros(first.shape, bool)
        mask[rows, cols] = True
        occupied = binary_dilation(mask).astype(np.uint8)
        shadowed = np.zeros((rows.size, phi.size), bool)
        surface_shadows(occupied, rows, cols, cos_phi, sin_phi, shadowed)
    return Surface(points, rows, cols, normals, first.size, first.extent, first.center,
                   shadowed)


def _uniform(edges):
    """(first edge, 1 / bin width) of uniform bins."""
    w = np.diff(edges)
    if np.ptp(w) > 1e-9 * w.mean():
        raise ParameterError("compensation needs uniform range bins")
    return float(edges[0]), 1.0 / float(w.mean())


def _segments(surface, H):
    """The kernels' :class:`_Segments`: centres, tangents, half-lengths, weights."""
    p, n = surface.points, surface.normals
    # each segment reaches halfway to its two nearest neighbours along the surface
    if p.shape[0] > 2:
        d, _ = cKDTree(p).query(p, k=3)
        half = np.minimum(0.25 * (d[:, 1] + d[:, 2]), surface.pixel_size)
    else:
        half = np.full(p.shape[0], 0.5 * surface.pixel_size)
    c = np.ascontiguousarray
    return _Segments(c(p[:, 0]), c(p[:, 1]), c(-n[:, 1]), c(n[:, 0]), half, c(H))


#: A blur narrower than this share of the table's step changes nothing (and underflows).
_LEAST_BLUR = 1e-3
#: The widest angular blur of h(θ) taken, degrees (wider spreads it past the hemisphere).
MAX_BLUR_DEG = 90.0


def _weight_table(material, radiometry, blur_deg):
    """(θ grid on [0, π/2], h(θ)/⟨h⟩): the monostatic weight blurred by a Gaussian of
    ``blur_deg`` in θ (the normals' uncertainty) and divided by its mean over the plane's
    directions, ⟨h⟩ = (1/π) ∫₀^{π/2} h dθ."""
    theta = np.linspace(0.0, 0.5 * math.pi, _TABLE)
    c, s = np.cos(theta), np.sin(theta)
    h = np.asarray(material.projected(c, s), dtype=float)
    if radiometry == "power":
        h = h * c
    step = theta[1] - theta[0]
    if math.radians(blur_deg) / step > _LEAST_BLUR:
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
    giving each pixel's index into it.

    h(θ) is the monostatic weight F(θ; −θ) cos θ (``radiometry="paper"``; times another
    cos θ for ``"power"``), tabulated on 8193 angles in [0, π/2], blurred in θ by a
    Gaussian of ``blur_deg`` (mirrored at normal incidence, zero beyond the horizon) and
    divided by its mean over the directions of the plane, ⟨h⟩ = (1/π) ∫₀^{π/2} h dθ; each
    pixel's θ is interpolated linearly in the table.

    Parameters
    ----------
    surface : Surface
        The points and outward normals (and, when not None, the shadow map).
    angles_deg : (n_views,) array_like
        View angles φ about z, degrees: the ladar looks from w = (cos φ, sin φ); θ is
        the angle between a normal and w.
    material : BRDF or sequence of BRDF
        The coatings.
    labels : (size, size) int array_like, keyword-only, optional
        Each pixel's index into ``material``: whole numbers, in [0, len(material)) on the
        surface (any value off it, e.g. -1); needed when it holds more than one BRDF, and
        checked whenever given.
    radiometry : {"paper", "power"}, keyword-only, default "paper"
        h = F cos θ (the paper's Eq. 8) or the received power F cos² θ.
    blur_deg : float in [0, 90], keyword-only, default 1.0
        Standard deviation, degrees, of the Gaussian blur of h(θ) (the normals'
        uncertainty); a blur below 1e-3 of the table's step is skipped.

    Returns
    -------
    (n, n_views) ndarray of float64
        The weight h(θ)/⟨h⟩ of each surface point and view: ≥ 0, 0 where the normal
        faces away from the view (n·w ≤ 0) and where ``surface.shadowed`` is True.

    Raises
    ------
    ParameterError
        When ``radiometry`` or ``blur_deg`` is invalid; a material is not a
        :class:`~meshladar.brdf.BRDF` or returns no light to a monostatic ladar; several
        materials come without ``labels``, or ``labels`` (whenever given) is not (size,
        size) of whole numbers, or holds an index outside [0, len(material)) on the
        surface (the first named, with its pixel); ``angles_deg`` is not finite; or
        the shadow map's views do not match ``angles_deg``.
    ModelError
        When a material's class does not define ``projected``.

    References
    ----------
    Jin & Levine (2009), Eq. 8 (the binned radiance weight F(θ; −θ) cos θ).
    """
    radiometry = "power" if check_radiometry(radiometry) else "paper"
    blur_deg = check_real("blur_deg", blur_deg, low=0.0, high=MAX_BLUR_DEG)
    mats = _materials(material)
    which = _material_of(surface, len(mats), labels)
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


def _materials(material):
    """``material`` as a list of checked BRDFs: one BRDF, or a sequence of them."""
    mats = [material] if isinstance(material, BRDF) else list(material)
    for i, m in enumerate(mats):
        check_brdf(f"material[{i}]", m)
    return mats


def _checked_labels(labels, size, n_materials):
    """``labels`` as a (size, size) int array of indices into ``n_materials`` materials,
    checked whenever given (one material included): finite whole numbers (the range is
    the surface's, :func:`_material_of`: pixels off it may hold a background value such
    as -1). None is refused for several materials and stands for all 0."""
    if labels is None:
        if n_materials > 1:
            raise ParameterError(f"several materials ({n_materials}) need labels: a ({size}, "
                                 f"{size}) int image of indices into material")
        return np.zeros((size, size), dtype=np.intp)
    lab = finite_array("labels", labels)
    if lab.shape != (size, size):
        raise ParameterError(f"labels must be a ({size}, {size}) array of indices into "
                             f"material; got shape {lab.shape}")
    bad = lab != np.round(lab)
    if np.any(bad):
        i, j = (int(k) for k in np.argwhere(bad)[0])
        raise ParameterError(f"labels must be whole numbers (indices into material); got "
                             f"{lab[i, j]:g} at index ({i}, {j})")
    return lab.astype(np.intp)


def _material_of(surface, n_materials, labels):
    """Each surface point's index into the materials: ``labels`` (a (size, size) image,
    :func:`_checked_labels`) at the point's pixel, in [0, n_materials) on the surface; 0
    for one material without labels."""
    which = _checked_labels(labels, surface.size, n_materials)[surface.rows, surface.cols]
    bad = (which < 0) | (which >= n_materials)
    if np.any(bad):
        k = int(np.argmax(bad))
        raise ParameterError(f"labels on the surface must be in [0, {n_materials}) (indices "
                             f"into the {n_materials} material(s)); got {which[k]} at pixel "
                             f"({int(surface.rows[k])}, {int(surface.cols[k])})")
    return which


def _subset(surface, keep):
    return dataclasses.replace(
        surface, points=surface.points[keep], rows=surface.rows[keep],
        cols=surface.cols[keep], normals=surface.normals[keep],
        shadowed=None if surface.shadowed is None else surface.shadowed[keep])
