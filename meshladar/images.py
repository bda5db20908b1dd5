"""Reconstructed images and volumes: the records that :mod:`meshladar.reconstruct` returns.

Images: ``image[i, j]`` is the value at (x_j, y_i), pixel centres
c + (−extent + (k + ½) 2 extent/size) increasing along both axes. Volumes:
``values[k, i, j]`` at (x[j], y[i], z[k]). Their ``.plot()`` goes through the one door to
:mod:`meshladar.viz` (:mod:`meshladar.plotting`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from . import plotting
from ._summary import table, text
from ._validate import check_real, finite_array, readonly_copy
from .errors import ParameterError
from .meshes import fibonacci_sphere

__all__ = ["Image", "Volume", "pixel_centres"]


@dataclass(frozen=True, eq=False)
class Image:
    """A reconstructed image on a square pixel grid.

    Parameters
    ----------
    values : (size, size) float64
        ``values[i, j]`` is the value at (x[j], y[i]); read-only.
    extent : float
        Half-width of the square, scene units.
    center : (2,) float
        Centre (x, y) of the square.
    info : dict
        How it was made (filter, interpolation, preprocessing).

    Raises
    ------
    ParameterError
        When ``values`` is not a finite (size, size) array with size ≥ 1, ``extent`` not a
        finite real > 0, or ``center`` not two finite reals.
    """

    values: np.ndarray
    extent: float
    center: tuple[float, float] = (0.0, 0.0)
    info: dict = field(default_factory=dict)

    def __post_init__(self):
        v = finite_array("values", self.values)
        if v.ndim != 2 or v.shape[0] != v.shape[1] or v.size == 0:
            raise ParameterError(f"values must be a square (size, size) array; got shape "
                                 f"{v.shape}")
        extent = check_real("extent", self.extent, low=0.0, low_open=True)
        center = finite_array("center", self.center)
        if center.shape != (2,):
            raise ParameterError(f"center must be two numbers (x, y); got {self.center!r}")
        object.__setattr__(self, "values", readonly_copy(v))
        object.__setattr__(self, "extent", extent)
        object.__setattr__(self, "center", (float(center[0]), float(center[1])))

    @property
    def size(self) -> int:
        return self.values.shape[0]

    def plot(self, **options):
        """A quick look (:func:`meshladar.viz.quick.image`, ``options`` such as ``y`` and
        ``title`` go to it): a matplotlib Figure.

        Parameters
        ----------
        **options
            Keyword arguments passed unchanged to :func:`meshladar.viz.quick.image`.

        Returns
        -------
        matplotlib.figure.Figure
            The image and its slice along x.

        Raises
        ------
        ImportError
            When the ``viz`` extra is not installed.
        """
        return plotting.plot(self, **options)

    def _summary(self):
        i = self.info
        return (("size", self.size), ("extent", float(self.extent)),
                ("center", tuple(float(c) for c in self.center)),
                ("values", (float(self.values.min(initial=0.0)),
                            float(self.values.max(initial=0.0)))),
                ("method", i.get("method", "fbp" if "filter" in i else None)),
                ("filter", i.get("filter")), ("input", i.get("preprocess")),
                ("radiometry", i.get("radiometry")), ("input_units", i.get("input_units")),
                ("n_views", i.get("n_views")), ("iterations", i.get("iterations")))

    def __repr__(self) -> str:
        return text("Image", *self._summary())

    def _repr_html_(self) -> str:
        return table("Image", *self._summary())

    @property
    def shape(self):
        return self.values.shape

    @property
    def pixel_size(self) -> float:
        return 2.0 * self.extent / self.size

    @cached_property
    def x(self) -> np.ndarray:
        """(size,) pixel-centre x coordinates (columns), increasing."""
        return self.center[0] + pixel_centres(self.size, self.extent)

    @cached_property
    def y(self) -> np.ndarray:
        """(size,) pixel-centre y coordinates (rows), increasing."""
        return self.center[1] + pixel_centres(self.size, self.extent)

    def __getitem__(self, key):
        return self.values[key]

    def __array__(self, dtype=None, copy=None):
        return self.values if dtype is None else self.values.astype(dtype)

    def sample(self, points):
        """Bilinear interpolation at points (..., 2) (x, y); 0 outside the grid.

        Parameters
        ----------
        points : (..., 2) array_like
            Points (x, y), scene units.

        Returns
        -------
        (...) numpy.ndarray
            The image bilinearly interpolated between pixel centres at each point (scipy's
            ``map_coordinates``, order 1, constant 0 beyond the grid).
        """
        p = np.asarray(points, dtype=np.float64)
        col = (p[..., 0] - self.x[0]) / self.pixel_size
        row = (p[..., 1] - self.y[0]) / self.pixel_size
        from scipy.ndimage import map_coordinates     # here: a slow import

        return map_coordinates(self.values, [row.ravel(), col.ravel()], order=1,
                               mode="constant", cval=0.0).reshape(p.shape[:-1])

    def radial_profile(self, radii, *, center=None, n_angles=720):
        """Mean over angle of the image on circles of the given radii about ``center``.

        Parameters
        ----------
        radii : (m,) array_like
            Radii of the circles, scene units.
        center : (2,) array_like, optional
            Centre (x, y) of the circles, scene units (default the image's ``center``).
        n_angles : int
            Points per circle, evenly spaced in angle from 0 (on the +x axis); default 720.

        Returns
        -------
        (m,) numpy.ndarray
            The mean of :meth:`sample` over each circle's points.
        """
        c = np.asarray(self.center if center is None else center, dtype=np.float64)
        a = np.linspace(0.0, 2 * math.pi, n_angles, endpoint=False)
        r = np.asarray(radii, dtype=np.float64)
        pts = c + np.stack([np.cos(a), np.sin(a)], -1)[None, :, :] * r[:, None, None]
        return self.sample(pts).mean(axis=1)


def pixel_centres(size, extent):
    """(size,) pixel-centre offsets from the grid's centre: −extent + (k + ½) 2 extent/size.

    Parameters
    ----------
    size : int
        Number of pixels along the axis.
    extent : float
        Half-width of the grid, scene units.

    Returns
    -------
    (size,) numpy.ndarray
        Offsets of the pixel centres from the grid's centre, increasing, scene units.
    """
    return -extent + (np.arange(size) + 0.5) * (2.0 * extent / size)



@dataclass(frozen=True, eq=False)
class Volume:
    """A reconstructed volume: ``values[k, i, j]`` at (x[j], y[i], z[k]) (voxel centres,
    increasing, evenly spaced), and ``info`` (method, views, filter, units).

    Parameters
    ----------
    values : (nz, ny, nx) array_like
        ``values[k, i, j]`` at (x[j], y[i], z[k]); finite, stored as a read-only float64
        copy.
    x, y, z : (nx,), (ny,), (nz,) array_like
        Voxel-centre coordinates along each axis, scene units; finite and strictly
        increasing, stored as read-only float64 copies. Keyword-only.
    info : dict, optional
        How it was made (default empty; copied). Keyword-only.

    Raises
    ------
    ParameterError
        When an array is not finite real numbers, ``values`` is not 3-D of shape
        (len(z), len(y), len(x)), or an axis is not strictly increasing.
    """

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
        """Trilinear values at ``points`` (k, 3) (0 outside the grid).

        Parameters
        ----------
        points : (k, 3) or (3,) array_like
            Points (x, y, z), scene units; a single point is taken as (1, 3).

        Returns
        -------
        (k,) numpy.ndarray
            The volume trilinearly interpolated between voxel centres at each point
            (scipy's ``map_coordinates``, order 1, constant 0 beyond the grid).
        """
        p = np.atleast_2d(np.asarray(points, np.float64))
        idx = [(p[:, 2 - a] - ax[0]) / sp for a, (ax, sp) in
               enumerate(zip((self.z, self.y, self.x), self.spacing[::-1]))]
        from scipy.ndimage import map_coordinates

        return map_coordinates(self.values, idx, order=1, mode="constant", cval=0.0)

    def radial_profile(self, radii, center=(0.0, 0.0, 0.0), n_directions=2000):
        """The mean over spheres of ``radii`` about ``center`` (Fibonacci directions).

        Parameters
        ----------
        radii : (m,) array_like
            Radii of the spheres, scene units.
        center : (3,) array_like
            Centre (x, y, z) of the spheres, scene units (default the origin).
        n_directions : int
            Points per sphere, on a Fibonacci sphere (default 2000).

        Returns
        -------
        (m,) numpy.ndarray
            The mean of :meth:`sample` over each sphere's points.
        """
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

    def plot(self, **options):
        """A quick look (:func:`meshladar.viz.quick.volume`, ``options`` such as ``title`` go
        to it): three slices through the target, a matplotlib Figure.

        Parameters
        ----------
        **options
            Keyword arguments passed unchanged to :func:`meshladar.viz.quick.volume`.

        Returns
        -------
        matplotlib.figure.Figure
            Three slices through the target on one colour scale.

        Raises
        ------
        ImportError
            When the ``viz`` extra is not installed.
        """
        return plotting.plot(self, **options)

    def __repr__(self) -> str:
        return text("Volume", *self._summary())

    def _repr_html_(self) -> str:
        return table("Volume", *self._summary())
