"""Siddon's ray-driven projector: exact intersection lengths of rays with a pixel grid.

Siddon (Med. Phys. 12, 1985; the paper's ref. 29) parameterises a ray as o + α d and walks
the pixels it crosses in order of α, crossing one vertical or horizontal grid line at a time
(Jacobs' incremental form). The length of the ray inside each pixel is exact, so the
projection of an image is Σ length · value, and the backprojection is its exact adjoint.

Conventions: a :class:`PixelGrid` follows :class:`~meshladar.reconstruct.Image`: pixel
``[i, j]`` is centred at (x_j, y_i), rows along y, both increasing. Parallel rays of a view φ
travel along −w = −(cos φ, sin φ) (from the ladar); their transverse coordinate s is measured
along u = (−sin φ, cos φ).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .._validate import check_count, check_real, finite_array
from ..errors import ParameterError
from . import _siddon_kernels as _kernels

__all__ = ["PixelGrid", "Rays", "parallel_rays", "project", "backproject", "ParallelProjector"]


@dataclass(frozen=True)
class PixelGrid:
    """A grid of ny × nx square pixels of side ``pixel_size`` whose lower-left corner is
    ``origin`` = (x_min, y_min)."""

    nx: int
    ny: int
    pixel_size: float
    origin: tuple[float, float]

    def __post_init__(self):
        for name in ("nx", "ny"):
            object.__setattr__(self, name, check_count(name, getattr(self, name)))
        object.__setattr__(self, "pixel_size",
                           check_real("pixel_size", self.pixel_size, low=0.0, low_open=True))
        o = finite_array("origin", self.origin)
        if o.shape != (2,):
            raise ParameterError(f"origin must be a point (x, y); got shape {o.shape}")
        object.__setattr__(self, "origin", (float(o[0]), float(o[1])))

    @classmethod
    def square(cls, size, extent, center=(0.0, 0.0)):
        """size × size pixels spanning [−extent, extent]² about ``center`` (an Image's grid)."""
        extent = check_real("extent", extent, low=0.0, low_open=True)
        size = check_count("size", size)
        c = finite_array("center", center)
        return cls(int(size), int(size), 2.0 * extent / size,
                   (float(c[0]) - extent, float(c[1]) - extent))

    @property
    def shape(self) -> tuple[int, int]:
        return (self.ny, self.nx)

    @cached_property
    def x(self) -> np.ndarray:
        return self.origin[0] + (np.arange(self.nx) + 0.5) * self.pixel_size

    @cached_property
    def y(self) -> np.ndarray:
        return self.origin[1] + (np.arange(self.ny) + 0.5) * self.pixel_size

    def _args(self):
        return (self.origin[0], self.origin[1], self.pixel_size)


@dataclass(frozen=True, eq=False)
class Rays:
    """Straight rays o + α d with unit d, α ≥ 0 increasing along the ray: arrays (n,)."""

    ox: np.ndarray
    oy: np.ndarray
    dx: np.ndarray
    dy: np.ndarray

    def __post_init__(self):
        arrays = [np.ascontiguousarray(finite_array(n, getattr(self, n)).ravel())
                  for n in ("ox", "oy", "dx", "dy")]
        if len({a.size for a in arrays}) != 1:
            raise ParameterError("ox, oy, dx, dy must have the same length")
        norm = np.hypot(arrays[2], arrays[3])
        if np.any(norm == 0):
            raise ParameterError("ray directions (dx, dy) must be non-zero")
        arrays[2] = arrays[2] / norm
        arrays[3] = arrays[3] / norm
        for n, a in zip(("ox", "oy", "dx", "dy"), arrays):
            object.__setattr__(self, n, a)

    @property
    def size(self) -> int:
        return self.ox.size


def parallel_rays(angles_deg, positions, *, distance):
    """Parallel rays for each view φ at transverse positions s, starting ``distance`` from
    the origin on the ladar's side and travelling along −w.

    Returns Rays ordered view-major: ray (v, k) is index v·len(positions) + k.
    """
    phi = np.deg2rad(finite_array("angles_deg", angles_deg)).ravel()
    s = finite_array("positions", positions).ravel()
    distance = check_real("distance", distance, low=0.0)
    c, sn = np.cos(phi)[:, None], np.sin(phi)[:, None]
    ox = -sn * s[None, :] + distance * c
    oy = c * s[None, :] + distance * sn
    return Rays(ox, oy, np.broadcast_to(-c, ox.shape), np.broadcast_to(-sn, ox.shape))


def project(image, grid: PixelGrid, rays: Rays) -> np.ndarray:
    """Line integrals Σ length · image of each ray through the grid: (n_rays,)."""
    img = np.ascontiguousarray(finite_array("image", image))
    if img.shape != grid.shape:
        raise ParameterError(f"image must have the grid's shape {grid.shape}; got {img.shape}")
    out = np.empty(rays.size)
    _kernels.siddon_project(img, rays.ox, rays.oy, rays.dx, rays.dy, *grid._args(), out)
    return out


#: Blocks of rays backprojected in parallel, each into its own image (summed in a fixed
#: order, so results do not depend on the number of cores).
_BACKPROJECT_PARTS = 8


def backproject(values, grid: PixelGrid, rays: Rays) -> np.ndarray:
    """The exact adjoint of :func:`project`: Σ_rays length · value into each pixel."""
    v = np.ascontiguousarray(finite_array("values", values).ravel())
    if v.size != rays.size:
        raise ParameterError(f"values must have one entry per ray ({rays.size}); got {v.size}")
    n_parts = min(_BACKPROJECT_PARTS, max(1, rays.size // 4096))
    parts = np.zeros((n_parts,) + grid.shape)
    _kernels.siddon_backproject_parallel(v, rays.ox, rays.oy, rays.dx, rays.dy,
                                         *grid._args(), parts)
    return parts.sum(axis=0)


class ParallelProjector:
    """Parallel-beam Siddon projector A and its matched backprojector Aᵀ on a grid.

    ``A @ image`` gives the (n_views, n_positions) line integrals of ``image`` along the rays
    of each view φ at transverse positions s; ``A.T @ sino`` backprojects exactly.

    Examples
    --------
    >>> import numpy as np
    >>> from meshladar.forward.siddon import PixelGrid, ParallelProjector
    >>> grid = PixelGrid.square(64, 1.0)
    >>> A = ParallelProjector(grid, np.arange(0.0, 360.0, 2.0), np.linspace(-1, 1, 96))
    >>> sino = A @ np.ones(grid.shape)           # chord lengths through the square
    >>> sino.shape, float(sino[0, 48])         # a central ray crosses the side, 2
    ((180, 96), 2.0)
    """

    def __init__(self, grid: PixelGrid, angles_deg, positions):
        self.grid = grid
        self.angles_deg = finite_array("angles_deg", angles_deg).ravel()
        self.positions = finite_array("positions", positions).ravel()
        half_diag = math.hypot(grid.nx, grid.ny) * grid.pixel_size
        reach = half_diag + math.hypot(*grid.origin) + 1.0
        self.rays = parallel_rays(self.angles_deg, self.positions, distance=reach)

    @property
    def shape(self):
        return (self.angles_deg.size * self.positions.size, self.grid.nx * self.grid.ny)

    def __matmul__(self, image):
        return project(image, self.grid, self.rays).reshape(self.angles_deg.size,
                                                             self.positions.size)

    @property
    def T(self):
        return _Adjoint(self)


class _Adjoint:
    def __init__(self, forward: ParallelProjector):
        self._f = forward

    def __matmul__(self, sino):
        return backproject(sino, self._f.grid, self._f.rays)
