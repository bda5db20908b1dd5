"""3-D reflective tomography: volumes from range profiles over the sphere of views, and from
elevation-resolved returns by stacking 2-D FBP slices.

A range profile of view w is a set of plane integrals: bin k holds the return of the surface
between the planes −p·w = r_k and r_{k+1}. Divided by the bin width it samples the 3-D
Radon transform g(w, s) = ∫ f δ(s − x·w) dx of the surface's return density f at s = −r.
The 3-D inversion formula is local:

    f(x) = −1/(8π²) ∫_{S²} ∂²g/∂s² (w, x·w) dw,

so :func:`radon3d` takes each profile's second difference (the three-point stencil, exact on
quadratics: a uniform ball's g = π(a² − s²) gives −g'' = 2π inside, and the ball back),
and backprojects over the views with quadrature weights (4π/n each for the Fibonacci
directions of ``meshladar.mesh.fibonacci_sphere``; a solid-angle Voronoi weight otherwise).
A uniform ball of value 1 reconstructs to 1 inside (tests/test_volume.py).

:func:`fbp_stack` reconstructs from returns resolved in elevation and range for views about
the z axis (:func:`meshladar.resolved.resolve`): each elevation row, per unit height, is a
2-D sinogram of that slice, reconstructed by :func:`meshladar.fbp`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ._validate import check_count, check_real, finite_array, readonly_copy
from .errors import ParameterError

__all__ = ["Volume", "radon3d", "fbp_stack", "sphere_weights", "coverage_gap_deg",
           "MAX_GAP_DEG"]


@dataclass(frozen=True, eq=False)
class Volume:
    """A reconstructed volume: ``values[k, i, j]`` at (x[j], y[i], z[k]) (voxel centres,
    increasing, evenly spaced), and ``info`` (method, views, filter, units)."""

    values: np.ndarray
    x: np.ndarray = field(kw_only=True)
    y: np.ndarray = field(kw_only=True)
    z: np.ndarray = field(kw_only=True)
    info: dict = field(default_factory=dict, kw_only=True)

    def __post_init__(self):
        v = finite_array("values", self.values)
        axes = [finite_array(n, getattr(self, n)) for n in ("x", "y", "z")]
        if v.ndim != 3 or v.shape != (axes[2].size, axes[1].size, axes[0].size):
            raise ParameterError(f"values must be (len(z), len(y), len(x)); got {v.shape}")
        for name, a in zip("xyz", axes):
            if a.size > 1 and np.any(np.diff(a) <= 0):
                raise ParameterError(f"{name} must be increasing")
        object.__setattr__(self, "values", readonly_copy(v))
        for name, a in zip("xyz", axes):
            object.__setattr__(self, name, readonly_copy(a))
        object.__setattr__(self, "info", dict(self.info))

    @property
    def shape(self):
        return self.values.shape

    @property
    def spacing(self):
        """(dx, dy, dz) voxel sizes."""
        return tuple(float(a[1] - a[0]) if a.size > 1 else 1.0 for a in (self.x, self.y, self.z))

    def sample(self, points) -> np.ndarray:
        """Trilinear values at ``points`` (k, 3) (0 outside the grid)."""
        from scipy.ndimage import map_coordinates

        p = np.atleast_2d(np.asarray(points, np.float64))
        idx = [(p[:, 2 - a] - ax[0]) / sp for a, (ax, sp) in
               enumerate(zip((self.z, self.y, self.x), self.spacing[::-1]))]
        return map_coordinates(self.values, idx, order=1, mode="constant", cval=0.0)

    def radial_profile(self, radii, center=(0.0, 0.0, 0.0), n_directions=2000):
        """The mean over spheres of ``radii`` about ``center`` (Fibonacci directions)."""
        from .mesh import fibonacci_sphere

        d = fibonacci_sphere(n_directions)
        r = np.asarray(radii, np.float64)
        pts = np.asarray(center, np.float64) + r[:, None, None] * d[None]
        return self.sample(pts.reshape(-1, 3)).reshape(r.size, -1).mean(axis=1)

    def _summary(self):
        return (("shape", self.shape), ("x", (float(self.x[0]), float(self.x[-1]))),
                ("z", (float(self.z[0]), float(self.z[-1]))),
                ("method", self.info.get("method")),
                ("radiometry", self.info.get("radiometry")),
                ("input", self.info.get("preprocess")))

    def plot(self, *, title=None):
        """A quick look (:func:`meshladar.viz.quick.volume`): three central slices, a
        matplotlib Figure."""
        from .viz.quick import volume

        return volume(self, title=title)

    def __repr__(self) -> str:
        from ._summary import text

        return text("Volume", *self._summary())

    def _repr_html_(self) -> str:
        from ._summary import table

        return table("Volume", *self._summary())


#: radon3d refuses view sets that leave a direction farther than this from every view (a
#: cap unseen: the inversion formula needs the whole sphere of directions).
MAX_GAP_DEG = 30.0


def coverage_gap_deg(view_vectors) -> float:
    """The largest angle (degrees) from any direction of the sphere to the nearest view
    (estimated on 2e4 Fibonacci directions): small for views spread over the sphere, 90 for
    a hemisphere or a plane of views."""
    from scipy.spatial import cKDTree

    from .mesh import fibonacci_sphere

    w = np.asarray(view_vectors, np.float64)
    chord, _ = cKDTree(w).query(fibonacci_sphere(20_000))
    return float(np.degrees(2 * np.arcsin(min(1.0, chord.max() / 2))))


def sphere_weights(view_vectors) -> np.ndarray:
    """Quadrature weights over the sphere for view directions covering it: each view's
    share of 4π by nearest direction (a spherical Voronoi cell estimated on 2e5 Fibonacci
    points). Views that leave part of the sphere unseen get its area too: right only for
    sets that cover the sphere (:func:`coverage_gap_deg`)."""
    from scipy.spatial import cKDTree

    from .mesh import fibonacci_sphere

    w = np.asarray(view_vectors, np.float64)
    probe = fibonacci_sphere(200_000)
    _, owner = cKDTree(w).query(probe)
    return np.bincount(owner, minlength=len(w)) * (4 * math.pi / probe.shape[0])


def _grid(size, extent, center):
    n = check_count("size", size)
    e = check_real("extent", extent, low=0.0, low_open=True)
    c = finite_array("center", center)
    if c.shape != (3,):
        raise ParameterError(f"center must be a point (x, y, z); got shape {c.shape}")
    base = -e + (np.arange(n) + 0.5) * (2 * e / n)
    return n, e, c, (base + c[0], base + c[1], base + c[2])


def radon3d(sino, *, size=128, extent=None, center=(0.0, 0.0, 0.0), weights=None,
            smooth=0.0) -> Volume:
    """Invert range profiles over the sphere of views (3-D Radon inversion, module
    docstring).

    Parameters
    ----------
    sino : Sinogram
        Range profiles with ``view_vectors`` spread over the whole sphere (the inversion
        formula integrates over all directions; a view set leaving a cap of more than
        ``MAX_GAP_DEG`` unseen is refused) and uniform bin widths.
    size : int
        Voxels per side (default 128).
    extent : float, optional
        Half-width of the cube (default the bins' reach).
    center : (3,) float
        The cube's centre.
    weights : (n_views,) array, optional
        Quadrature weight (solid angle) of each view; default 4π/n for n views, right for
        Fibonacci directions (:func:`sphere_weights` for other sets covering the sphere).
    smooth : float
        Standard deviation (in bins) of a Gaussian applied to each profile before its
        second difference (default 0: none). The second difference amplifies sampling noise
        and few views leave the planes of sharp returns uncancelled: 1-2 bins trade
        resolution for a cleaner volume.

    Returns
    -------
    Volume
        The surface's return density (per unit volume): values integrate, over a thin shell
        around the surface, to its return per unit area.
    """
    from . import _kernels
    from ._validate import check_sinogram, check_size

    check_sinogram("sino", sino)
    widths = np.diff(sino.bin_edges)
    if np.ptp(widths) > 1e-6 * widths.mean():
        raise ParameterError("radon3d needs uniform range bins")
    if sino.n_bins < 3:
        raise ParameterError(f"radon3d needs at least 3 range bins; got {sino.n_bins}")
    dr = float(widths.mean())
    gap = coverage_gap_deg(sino.view_vectors)
    if gap > MAX_GAP_DEG:
        raise ParameterError(
            f"radon3d needs views over the whole sphere of directions; these leave a "
            f"direction {gap:.0f} deg from every view (at most {MAX_GAP_DEG:g}): use views "
            "such as meshladar.mesh.fibonacci_sphere(n) (views about the z axis: fbp, or "
            "fbp_stack of elevation-resolved returns)")
    if extent is None:
        extent = float(max(abs(sino.bin_edges[0]), abs(sino.bin_edges[-1])))
    n, e, c, (x, y, z) = _grid(size, extent, center)
    check_size("size", float(n) ** 3, 8 * 2, f"a {n}^3 volume", "give a smaller size")
    if weights is None:
        wts = np.full(sino.n_views, 4 * math.pi / sino.n_views)
    else:
        wts = finite_array("weights", weights)
        if wts.shape != (sino.n_views,) or np.any(wts < 0):
            raise ParameterError(f"weights must be {sino.n_views} non-negative solid angles")
    smooth = check_real("smooth", smooth, low=0.0)
    g = sino.values / dr
    if smooth > 0:
        from scipy.ndimage import gaussian_filter1d

        g = gaussian_filter1d(g, smooth, axis=1, mode="constant", truncate=4.0)
    g = np.pad(g, ((0, 0), (1, 1)))                             # zero beyond the bins
    minus_g2 = -(g[:, 2:] - 2 * g[:, 1:-1] + g[:, :-2]) / (dr * dr)
    q = np.ascontiguousarray(minus_g2 / (8 * math.pi ** 2))
    out = np.zeros((n, n, n))
    w = sino.view_vectors
    _kernels.backproject3d(q, np.ascontiguousarray(w[:, 0]), np.ascontiguousarray(w[:, 1]),
                           np.ascontiguousarray(w[:, 2]), wts, float(sino.bin_centers[0]),
                           1.0 / dr, x, y, z, out)
    info = {"method": "radon3d", "filter": "second difference", "smooth_bins": smooth,
            "views": sino.n_views,
            "radiometry": sino.info.get("radiometry"), "size": n, "extent": e,
            "center": c.tolist()}
    if sino.info.get("preprocess"):
        info["preprocess"] = sino.info["preprocess"]
    return Volume(out, x=x, y=y, z=z, info=info)


def fbp_stack(returns, *, size=256, extent=None, filter="ramp") -> Volume:
    """Slices from returns resolved in elevation and range (views about the z axis): each
    elevation row per unit height is a 2-D sinogram, reconstructed by FBP; the slices stack
    at the elevation bins' centres.

    Parameters
    ----------
    returns : meshladar.resolved.Returns
        With axes ("elevation", "range") (either order) and views about the z axis.
    size, extent, filter
        As :func:`meshladar.fbp`, per slice.
    """
    from .reconstruct import fbp
    from .resolved import Returns
    from .sinogram import Sinogram

    if not isinstance(returns, Returns) or set(returns.axes) != {"elevation", "range"}:
        raise ParameterError("fbp_stack needs Returns resolved in ('elevation', 'range')")
    if np.any(returns.view_vectors[:, 2] != 0):
        raise ParameterError("fbp_stack needs views about the z axis (elevation is z)")
    vals = returns.values
    if returns.axes[0] == "range":
        vals = np.swapaxes(vals, 1, 2)                  # (views, elevation, range)
    el = returns.edges[returns.axes.index("elevation")]
    rng = returns.edges[returns.axes.index("range")]
    if np.ptp(np.diff(el)) > 1e-9 * np.diff(el).mean():
        raise ParameterError("fbp_stack needs evenly spaced elevation bins (the volume's z "
                             "axis)")
    if extent is None:
        extent = float(max(abs(rng[0]), abs(rng[-1])))
    slices = []
    for k in range(el.size - 1):
        s = Sinogram(vals[:, k, :] / (el[k + 1] - el[k]), angles_deg=returns.angles_deg,
                     bin_edges=rng, model="mesh", info=returns.info)
        slices.append(fbp(s, size=size, extent=extent, filter=filter))
    first = slices[0]
    info = {"method": "fbp_stack", "filter": filter, "views": vals.shape[0],
            "radiometry": returns.info.get("radiometry"), "slices": el.size - 1}
    if returns.info.get("preprocess"):
        info["preprocess"] = returns.info["preprocess"]
    return Volume(np.stack([s.values for s in slices]), x=first.x, y=first.y,
                  z=0.5 * (el[1:] + el[:-1]), info=info)
