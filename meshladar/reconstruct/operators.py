"""The projectors of reconstruction as one operator protocol.

Every projector is a :class:`Projector` (the protocol, in
:mod:`meshladar.reconstruct.projector`), a :class:`scipy.sparse.linalg.LinearOperator` from
an image on a :class:`~meshladar.forward.siddon.PixelGrid` to a sinogram's (n_views, n_bins) bin
integrals, with its exact adjoint as ``A.T`` (ODL's habit: FBP is ``ray_trafo.adjoint *
filter_op``; the solvers of :mod:`meshladar.reconstruct.iterative` only use ``@`` and
``.T``). ``A @ image`` takes and gives arrays in their own shapes (image (ny, nx) →
(n_views, n_bins); ``A.T @ values`` back); flat vectors go through scipy's ``matvec`` and
``rmatvec``, so a projector also composes with scipy's solvers (``lsqr``, ``cg``).

* :class:`RangeProjector` — Siddon lines (exact pixel lengths) averaged over each bin;
* :class:`LinearProjector` — the pixel-driven pair: splat (linear interpolation) and FBP's
  backprojection;
* :class:`SurfaceProjector` — the surface segments of BRDF compensation, weighted per view.

The data model is FBP's: a sinogram's ``values / bin_width`` are line integrals
of the image along the iso-range lines −p·w = r, so ``A @ image`` is directly comparable
with ``sino.values``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from scipy.sparse import csr_matrix
from scipy.spatial import cKDTree

from .._validate import check_choice, check_count, check_real
from ..errors import ParameterError
from ..forward.siddon import backproject as siddon_backproject
from ..forward.siddon import parallel_rays
from ..forward.siddon import project as siddon_project
from ._folded import opposite_pairs
from ._kernels import backproject, splat_project, surface_backproject, surface_project
from .projector import Projector
from .surface import _segments, _uniform

__all__ = ["Projector", "RangeProjector", "LinearProjector", "SurfaceProjector",
           "PROJECTORS", "uniform_bins", "projector_name", "build"]

#: The projector pairs by name (``projector=`` of the solvers): Siddon lines (exact lengths)
#: or pixel-driven linear interpolation (faster).
PROJECTORS = ("siddon", "linear")
#: Relative spread of the bin widths below which the bins count as uniform.
UNIFORM_RTOL = 1e-9


def uniform_bins(bin_edges):
    """Whether the range bins are uniform (widths equal to within :data:`UNIFORM_RTOL` of
    their mean): where :class:`LinearProjector` applies.

    Parameters
    ----------
    bin_edges : (n_bins + 1,) array_like
        Range bin edges, scene units. Not checked for finiteness or order.

    Returns
    -------
    bool
        True when there is at least one bin and the spread (max − min) of the widths is at
        most :data:`UNIFORM_RTOL` (1e-9) times their mean.
    """
    w = np.diff(np.asarray(bin_edges, dtype=float))
    return bool(w.size) and float(np.ptp(w)) <= UNIFORM_RTOL * float(np.mean(w))


def projector_name(projector, bin_edges):
    """The projector pair ``projector="auto"`` means: ``"linear"`` (the pixel-driven pair,
    about 20× faster than Siddon lines at 256², the same image error: measured on the
    reconstruction guide's SIRT example, 60 iterations) where the bins are uniform,
    ``"siddon"`` (which takes any bins) where they are not; any other name is itself.

    Parameters
    ----------
    projector : str or object
        ``"auto"``, a name of :data:`PROJECTORS`, or an operator. Not checked
        (:func:`build` checks).
    bin_edges : (n_bins + 1,) array_like
        Range bin edges (:func:`uniform_bins`), read only for ``"auto"``.

    Returns
    -------
    str or object
        ``"linear"`` or ``"siddon"`` for ``"auto"``; ``projector`` unchanged otherwise.
    """
    if projector == "auto":
        return "linear" if uniform_bins(bin_edges) else "siddon"
    return projector


def build(projector, grid, sino, rays_per_bin=2):
    """The solvers' operator for a sinogram's views and bins on ``grid``: a projector name
    (``"auto"``, :data:`PROJECTORS`), or a user's operator: anything with ``@``, ``.T`` and
    a ``grid`` equal to the image's (an ODL-like composition), returned as it is.

    Parameters
    ----------
    projector : {"auto", "siddon", "linear"} or operator
        The pair by name (``"auto"``: :func:`projector_name`), or an operator with
        ``__matmul__``, ``T`` and ``grid == grid``.
    grid : meshladar.forward.siddon.PixelGrid
        The image's pixel grid.
    sino : Sinogram
        The data whose ``angles_deg`` and ``bin_edges`` the projector maps to.
    rays_per_bin : int >= 1, default 2
        Iso-range lines per bin, for the Siddon projector only.

    Returns
    -------
    Projector or object
        A :class:`LinearProjector` or :class:`RangeProjector` for a name, or ``projector``
        itself.

    Raises
    ------
    ParameterError
        When ``projector`` is neither one of ``("auto",) +`` :data:`PROJECTORS` nor an
        operator as above; when ``"linear"`` is asked for with non-uniform bins; when
        ``rays_per_bin`` is not an integer >= 1 (Siddon projector).
    """
    if not isinstance(projector, str):
        if not (hasattr(projector, "__matmul__") and hasattr(projector, "T")
                and getattr(projector, "grid", None) == grid):
            raise ParameterError(f"projector must be one of {('auto',) + PROJECTORS} or an "
                                 f"operator with @, .T and .grid equal to the image grid "
                                 f"{grid}; got {projector!r}")
        return projector
    check_choice("projector", projector, ("auto",) + PROJECTORS)
    if projector_name(projector, sino.bin_edges) == "linear":
        return LinearProjector(grid, sino.angles_deg, sino.bin_edges)
    return RangeProjector(grid, sino.angles_deg, sino.bin_edges, rays_per_bin)


class RangeProjector(Projector):
    """A: image on ``grid`` → (n_views, n_bins) bin integrals of its iso-range line
    integrals; ``A.T`` its exact adjoint.

    Each bin holds the bin width times the mean line integral of ``rays_per_bin`` evenly
    spaced iso-range lines inside it (Siddon's exact pixel lengths).

    Parameters
    ----------
    grid : meshladar.forward.siddon.PixelGrid
    angles_deg : (n_views,) array
        View angles about z (w = (cos φ, sin φ)).
    bin_edges : (n_bins + 1,) array
        Range bin edges (range r = −p·w).
    rays_per_bin : int
        Iso-range lines per bin (at the centres of equal sub-bins), averaged.
    """

    def __init__(self, grid, angles_deg, bin_edges, rays_per_bin=2):
        super().__init__(grid, angles_deg, bin_edges)
        self.rays_per_bin = check_count("rays_per_bin", rays_per_bin)
        k = self.rays_per_bin
        e = self.bin_edges
        frac = (np.arange(k) + 0.5) / k
        r = (e[:-1, None] + frac[None, :] * np.diff(e)[:, None]).ravel()      # (n_bins·k,)
        # the line −p·w = r runs along u; Siddon's parallel rays of angle φ − 90° travel
        # along u, at transverse position s = p·w = −r
        reach = math.hypot(grid.nx, grid.ny) * grid.pixel_size + math.hypot(*grid.origin) + 1
        self.rays = parallel_rays(self.angles_deg - 90.0, -r, distance=reach)
        self.width = np.diff(e)

    def _forward(self, image):
        lines = siddon_project(image, self.grid, self.rays).reshape(self.n_views, self.n_bins,
                                                                    self.rays_per_bin)
        return lines.mean(axis=2) * self.width

    def _backward(self, values):
        v = np.asarray(values, np.float64).reshape(self.n_views, self.n_bins)
        spread = np.repeat((v * self.width / self.rays_per_bin)[:, :, None], self.rays_per_bin,
                           axis=2)
        return siddon_backproject(spread.ravel(), self.grid, self.rays)


class LinearProjector(Projector):
    """The pixel-driven pair: Aᵀ is FBP's linear-interpolation backprojection (pixel area ×
    the profile interpolated at each pixel centre's range), A its exact transpose (each
    pixel's value times its area split between the two nearest bin centres, a splat).
    Faster than Siddon lines (the measured speed-up is in :func:`projector_name`); needs
    uniform bins. Same interface as :class:`RangeProjector`.

    Opposite views see the same iso-range lines in reverse order: with bins symmetric
    about range 0, view φ + 180° projects to view φ's bins reversed. The pair then computes
    only one view of each opposite pair (half the work on a full circle of views).

    Views count as opposite when their angles modulo 360°, rounded to 1e-6 degree, differ
    by 180° and their directions are opposite to
    ``meshladar.reconstruct._folded.FOLD_TOL`` (8 units in the last place; repeated
    angles pair in order); bins count as symmetric when every edge matches the negated mirrored edge to
    within 1e-12 of the largest |edge|.

    Parameters
    ----------
    grid : meshladar.forward.siddon.PixelGrid
        The image's pixel grid; samples at the pixel centres.
    angles_deg : (n_views,) array_like
        View angles about z, degrees (w = (cos φ, sin φ)).
    bin_edges : (n_bins + 1,) array_like
        Uniform range bin edges, scene units (range r = −p·w); the profile is sampled at
        the bin centres.

    Raises
    ------
    ParameterError
        When the bins are not uniform (:func:`uniform_bins`), or ``angles_deg`` or
        ``bin_edges`` is not finite.
    """

    def __init__(self, grid, angles_deg, bin_edges):
        super().__init__(grid, angles_deg, bin_edges)
        if not uniform_bins(self.bin_edges):
            raise ParameterError("the linear projector needs uniform range bins")
        self.dr = float(np.mean(np.diff(self.bin_edges)))
        phi = np.deg2rad(self.angles_deg)
        self.cos, self.sin = np.cos(phi), np.sin(phi)
        p = grid.pixel_size
        self.x = grid.origin[0] + (np.arange(grid.nx) + 0.5) * p
        self.y = grid.origin[1] + (np.arange(grid.ny) + 0.5) * p
        self.r0 = float(self.bin_edges[0] + 0.5 * self.dr)
        self.base, self.mirror, self.partner = _opposite_views(self.angles_deg,
                                                               self.bin_edges)
        self.weight = np.full(self.base.size, p * p)

    def _forward(self, image):
        half = np.zeros((self.base.size, self.n_bins))
        b = self.base
        splat_project(np.ascontiguousarray(image, dtype=np.float64), self.cos[b], self.sin[b],
                      self.weight, self.r0, 1.0 / self.dr, self.x, self.y, half)
        out = np.empty((self.n_views, self.n_bins))
        out[b] = half
        out[self.mirror] = half[self.partner, ::-1]
        return out

    def _backward(self, values):
        q = np.asarray(values, dtype=np.float64).reshape(self.n_views, self.n_bins)
        folded = q[self.base].copy()
        np.add.at(folded, self.partner, q[self.mirror, ::-1])
        out = np.zeros(self.grid.shape)
        backproject(folded, self.cos[self.base], self.sin[self.base], self.weight, self.r0,
                    1.0 / self.dr, self.x, self.y, False, out)
        return out


def _opposite_views(angles_deg, edges):
    """(base, mirror, partner): the views to compute, and the views that are the
    reversed-bin copy of base view ``partner`` (an index into base): the later view of
    each pair 180° apart (``meshladar.reconstruct._folded.opposite_pairs``) when the
    bins are symmetric about 0; otherwise every view is a base view."""
    n = angles_deg.size
    scale = float(np.max(np.abs(edges)))
    if not np.allclose(edges, -edges[::-1], rtol=0.0, atol=1e-12 * scale):
        return np.arange(n), np.zeros(0, int), np.zeros(0, int)
    phi = np.deg2rad(angles_deg)
    partner_of, mirror = opposite_pairs(angles_deg, np.cos(phi), np.sin(phi))
    is_base = np.ones(n, bool)
    is_base[mirror] = False
    base = np.flatnonzero(is_base)
    index = np.full(n, -1)
    index[base] = np.arange(base.size)
    return base, mirror, index[partner_of]


class _SurfaceArgs(NamedTuple):
    """:func:`surface_project`'s and :func:`surface_backproject`'s arguments between the
    values and the output: the segments (centres, tangents, half-lengths, per-view
    weights), every view's cos φ and sin φ, the first bin edge and 1 / bin width."""

    x: np.ndarray
    y: np.ndarray
    tx: np.ndarray
    ty: np.ndarray
    half: np.ndarray
    H: np.ndarray
    cos: np.ndarray
    sin: np.ndarray
    e0: float
    inv_dr: float


class SurfaceProjector(Projector):
    """A: image → (n_views, n_bins), the exact projector of a
    :class:`~meshladar.reconstruct.surface.Surface` as straight segments (one per surface
    pixel, through its point, along its tangent, halfway to its neighbours), each weighted
    per view by ``H`` (:func:`~meshladar.reconstruct.surface.surface_weights`) and spread
    over the bins its range interval covers; ``A.T`` its exact adjoint (zero off the
    surface). With ``smooth`` > 0 (pixels), the values are first averaged along the surface
    by a Gaussian of that width (A S, adjoint Sᵀ Aᵀ). Image values are areal densities (a
    segment carries value × pixel area), as FBP's. Composes with
    :func:`~meshladar.reconstruct.iterative.sirt` and
    :func:`~meshladar.reconstruct.iterative.cgls` through ``projector=``.

    Each segment's half-length is half the mean distance to its two nearest neighbouring
    points, at most one pixel (half a pixel when the surface has two points or fewer); its
    tangent is the normal turned by +90°.

    Parameters
    ----------
    surface : meshladar.reconstruct.surface.Surface
        The n surface points, their pixels, normals and grid (the operator's ``grid``).
    angles_deg : (n_views,) array_like
        View angles about z, degrees (w = (cos φ, sin φ)).
    bin_edges : (n_bins + 1,) array_like
        Uniform range bin edges, scene units (range r = −p·w).
    H : (n, n_views) array_like
        Per point and view weights, e.g.
        :func:`~meshladar.reconstruct.surface.surface_weights`; 0 drops a point-view.
    smooth : float in [0, surface.size], default 0.0
        Standard deviation, pixels, of the Gaussian along the surface: each point's value
        is averaged over the points within 2 ``smooth`` pixels of it with weights
        exp(−d² / (2 s²)), s = ``smooth``, normalised to sum 1. Below 1e-3: no smoothing.

    Attributes
    ----------
    surface : meshladar.reconstruct.surface.Surface
        As given.
    smooth : scipy.sparse.csr_matrix or None
        The (n, n) smoothing operator S, or None without smoothing (not the width given).
    view_weights : (n, n_views) ndarray
        ``H`` times the pixel area: the weights the segments carry.

    Raises
    ------
    ParameterError
        When ``smooth`` is outside [0, surface.size], the bins are not uniform (to 1e-9
        of their mean width), ``H`` is not (n, n_views), or ``angles_deg`` or
        ``bin_edges`` is not finite.
    """

    def __init__(self, surface, angles_deg, bin_edges, H, smooth=0.0):
        self.surface = surface
        self.smooth = _smoother(surface, check_real("smooth", smooth, low=0.0,
                                                    high=float(surface.size)))
        super().__init__(surface.grid, angles_deg, bin_edges)
        self.e0, self.inv_dr = _uniform(self.bin_edges)
        H = np.asarray(H, dtype=float)
        if H.shape != (surface.rows.size, self.n_views):
            raise ParameterError(f"H must be ({surface.rows.size}, {self.n_views}); got "
                                 f"{H.shape}")
        # image values are areal densities: a segment carries value × pixel area (the view
        # weights are ``view_weights``: ``H`` is the operator's adjoint, as scipy's)
        self.view_weights = np.ascontiguousarray(H * self.grid.pixel_size ** 2)
        phi = np.deg2rad(self.angles_deg)
        self.cos, self.sin = np.cos(phi), np.sin(phi)

    def _args(self):
        """The compiled loops' arguments after the values (flat, in their order)."""
        return _SurfaceArgs(*_segments(self.surface, self.view_weights), self.cos,
                            self.sin, self.e0, self.inv_dr)

    def _forward(self, image):
        v = np.asarray(image, float)[self.surface.rows, self.surface.cols]
        if self.smooth is not None:
            v = self.smooth @ v
        v = np.ascontiguousarray(v)
        out = np.zeros((self.n_views, self.n_bins))
        surface_project(v, *self._args(), out)
        return out

    def _backward(self, values):
        q = np.ascontiguousarray(np.asarray(values, float).reshape(self.n_views, self.n_bins))
        acc = np.zeros(self.surface.rows.size)
        surface_backproject(q, *self._args(), acc)
        if self.smooth is not None:
            acc = self.smooth.T @ acc
        out = np.zeros(self.grid.shape)
        out[self.surface.rows, self.surface.cols] = acc
        return out


def _smoother(surface, width):
    """The sparse operator that averages each surface point's value with its neighbours
    within 2 ``width`` (pixels) under a Gaussian of that width, or None for 0: the solution
    is then smooth along the surface by construction (x = S z)."""
    if width < 1e-3:            # no two points that close: the identity (and w² underflows)
        return None
    p = surface.points / surface.pixel_size
    pairs = cKDTree(p).query_pairs(2.0 * width, output_type="ndarray")
    i = np.r_[pairs[:, 0], pairs[:, 1], np.arange(len(p))]
    j = np.r_[pairs[:, 1], pairs[:, 0], np.arange(len(p))]
    d2 = np.sum((p[i] - p[j]) ** 2, axis=1)
    S = csr_matrix((np.exp(-0.5 * d2 / width ** 2), (i, j)), shape=(len(p), len(p)))
    return csr_matrix(S.multiply(1.0 / np.asarray(S.sum(axis=1))))
