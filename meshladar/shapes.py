"""Analytic shapes: disks and ellipses with a coating each, and the geometry of an ellipse's
frame (one helper for every module that needs it).

Shapes are 2-D cross-sections in the x-y plane (an extruded phantom seen by views about
the z axis). Every shape is convex and closed; its boundary is the reflecting surface.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ._validate import check_name, check_real, finite_array
from .brdf import BRDF, check_brdf
from .errors import ParameterError
from .precision import OVERLAP_RTOL

__all__ = ["Shape", "Disk", "Ellipse", "to_frame", "from_frame", "ellipse_normal"]


def _center(value):
    c = finite_array("center", value)
    if c.shape != (2,):
        raise ParameterError(f"center must be a point (x, y); got shape {c.shape}")
    return (float(c[0]), float(c[1]))


def _material(value, name=None):
    check_name(name)
    return check_brdf("material", value)


def to_frame(angle, dx, dy):
    """World offsets (dx, dy) from an ellipse's centre in its own axes: rotated by −angle.

    Parameters
    ----------
    angle : float
        The ellipse's rotation from the world x axis, counter-clockwise, radians.
    dx, dy : float or numpy.ndarray
        World offsets from the centre (any matching shapes).

    Returns
    -------
    x, y : float or numpy.ndarray
        The offsets along the ellipse's own axes: x = cos(angle) dx + sin(angle) dy,
        y = −sin(angle) dx + cos(angle) dy.
    """
    ca, sa = math.cos(angle), math.sin(angle)
    return ca * dx + sa * dy, -sa * dx + ca * dy


def from_frame(angle, x, y):
    """Vectors (x, y) in an ellipse's own axes back in the world: rotated by +angle.

    Parameters
    ----------
    angle : float
        The ellipse's rotation from the world x axis, counter-clockwise, radians.
    x, y : float or numpy.ndarray
        Components along the ellipse's own axes (any matching shapes).

    Returns
    -------
    dx, dy : float or numpy.ndarray
        World components: dx = cos(angle) x − sin(angle) y, dy = sin(angle) x +
        cos(angle) y (the inverse of :func:`to_frame`).
    """
    ca, sa = math.cos(angle), math.sin(angle)
    return ca * x - sa * y, sa * x + ca * y


def ellipse_normal(center, axes, angle, px, py):
    """Unit outward normals (nx, ny) of the ellipse's level sets through the points (the
    gradient of (x'/A)² + (y'/B)²); (0, 0) at the centre itself.

    Parameters
    ----------
    center : (2,) sequence of float
        The ellipse's centre (x, y), scene units.
    axes : (2,) sequence of float
        Semi-axes (A, B) along the ellipse's own x and y axes, scene units.
    angle : float
        The ellipse's rotation from the world x axis, counter-clockwise, radians.
    px, py : array_like
        World coordinates of the points (matching shapes), scene units.

    Returns
    -------
    nx, ny : numpy.ndarray
        The unit normal's world components at each point, the shape of ``px``.
    """
    a, b = axes
    xl, yl = to_frame(angle, np.asarray(px) - center[0], np.asarray(py) - center[1])
    nx, ny = from_frame(angle, xl / a**2, yl / b**2)
    nn = np.hypot(nx, ny)
    safe = np.where(nn > 0, nn, 1.0)
    return np.where(nn > 0, nx / safe, 0.0), np.where(nn > 0, ny / safe, 0.0)


class Shape:
    """Geometry shared by the analytic shapes: an ellipse with centre, semi-axes ``axes``
    (A, B) and rotation ``angle`` (radians). Subclasses are frozen dataclasses."""

    center: tuple[float, float]
    material: BRDF

    @property
    def axes(self) -> tuple[float, float]:
        raise NotImplementedError

    @property
    def angle(self) -> float:
        raise NotImplementedError

    @property
    def is_circle(self) -> bool:
        return self.axes[0] == self.axes[1]

    @property
    def bounding_radius(self) -> float:
        return max(self.axes)

    def boundary(self, t):
        """Points (..., 2) at eccentric angle ``t`` (radians): c + R (A cos t, B sin t).

        Parameters
        ----------
        t : float or array_like
            Eccentric angle, radians, of shape (...); R rotates by :attr:`angle`.

        Returns
        -------
        (..., 2) numpy.ndarray
            World points (x, y) on the boundary, scene units.
        """
        a, b = self.axes
        x, y = from_frame(self.angle, a * np.cos(t), b * np.sin(t))
        return np.stack([self.center[0] + x, self.center[1] + y], -1)

    def implicit(self, p):
        """(x'/A)² + (y'/B)² of points p (..., 2) in the shape's frame: < 1 inside.

        Parameters
        ----------
        p : (..., 2) array_like
            World points (x, y), scene units.

        Returns
        -------
        (...) numpy.ndarray
            The implicit function: < 1 inside, 1 on the boundary, > 1 outside.
        """
        a, b = self.axes
        d = np.asarray(p, dtype=np.float64) - np.asarray(self.center)
        x, y = to_frame(self.angle, d[..., 0], d[..., 1])
        return (x / a) ** 2 + (y / b) ** 2

    def perimeter(self) -> float:
        """Exact perimeter (complete elliptic integral of the second kind).

        Returns
        -------
        float
            4 A E(1 − (B/A)²), scene units, with A ≥ B the larger and smaller semi-axes and
            E scipy's ``ellipe`` (argument the parameter m = k²); 2πA for a disk.
        """
        from scipy.special import ellipe

        a, b = sorted(self.axes, reverse=True)
        return 4.0 * a * float(ellipe(1.0 - (b / a) ** 2))


@dataclass(frozen=True)
class Ellipse(Shape):
    """An elliptical cylinder's cross-section with an SR coating.

    Parameters
    ----------
    center : (2,) float
        Centre (x, y) in scene units.
    semi_axes : (2,) float
        Semi-axes (A, B) > 0 along the ellipse's own x and y axes (A need not be the larger).
    angle_deg : float
        Rotation of the ellipse's A axis from the scene's x axis, counter-clockwise, degrees.
    material : BRDF
        The coating.
    name : str, optional
        A label (e.g. which part of a phantom); not part of equality.

    Raises
    ------
    ParameterError
        When ``center`` is not two finite numbers, ``semi_axes`` not two finite positive
        lengths, ``angle_deg`` not finite, ``name`` not a string or None, or ``material``
        not a BRDF.
    ModelError
        When ``material`` lacks a method the BRDF protocol needs.
    """

    center: tuple[float, float]
    semi_axes: tuple[float, float]
    angle_deg: float
    material: BRDF
    name: str | None = field(default=None, kw_only=True, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "center", _center(self.center))
        axes = finite_array("semi_axes", self.semi_axes)
        if axes.shape != (2,) or np.any(axes <= 0):
            raise ParameterError(f"semi_axes must be two positive lengths (A, B); got "
                                 f"{self.semi_axes!r}")
        object.__setattr__(self, "semi_axes", (float(axes[0]), float(axes[1])))
        object.__setattr__(self, "angle_deg", check_real("angle_deg", self.angle_deg))
        _material(self.material, self.name)

    @property
    def axes(self) -> tuple[float, float]:
        return self.semi_axes

    @property
    def angle(self) -> float:
        return math.radians(self.angle_deg)


@dataclass(frozen=True)
class Disk(Shape):
    """A circular cylinder's cross-section (a disk) with an SR coating.

    Parameters
    ----------
    center : (2,) float
        Centre (x, y) in scene units.
    radius : float > 0
        Radius, scene units; finite.
    material : BRDF
        The coating.
    name : str, optional
        A label (e.g. "large" in the disk pair); not part of equality.

    Raises
    ------
    ParameterError
        When ``center`` is not two finite numbers, ``radius`` not a finite number > 0,
        ``name`` not a string or None, or ``material`` not a BRDF.
    ModelError
        When ``material`` lacks a method the BRDF protocol needs.
    """

    center: tuple[float, float]
    radius: float
    material: BRDF
    name: str | None = field(default=None, kw_only=True, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "center", _center(self.center))
        object.__setattr__(self, "radius", check_real("radius", self.radius, low=0.0,
                                                      low_open=True))
        _material(self.material, self.name)

    @property
    def axes(self) -> tuple[float, float]:
        return (self.radius, self.radius)

    @property
    def angle(self) -> float:
        return 0.0


def _overlap(p: Shape, q: Shape) -> bool:
    """True when the interiors of two ellipses intersect by more than OVERLAP_RTOL.

    Disks: exact (centre distance against the sum of radii). Ellipses: the minimum of q's
    implicit function over p's boundary (dense sampling, then bounded refinement), and the
    converse, compared with 1 − tol; plus centre containment, for one inside the other.
    """
    scale = max(p.bounding_radius, q.bounding_radius)
    if p.is_circle and q.is_circle:
        d = math.dist(p.center, q.center)
        return d < (p.axes[0] + q.axes[0]) * (1.0 - OVERLAP_RTOL)
    d = math.dist(p.center, q.center)
    if d >= (p.bounding_radius + q.bounding_radius) * (1.0 - OVERLAP_RTOL):
        return False
    if p.implicit(q.center) < 1.0 or q.implicit(p.center) < 1.0:
        return True
    from scipy import optimize          # here: a slow import, for overlapping candidates only

    for a, b in ((p, q), (q, p)):
        t = np.linspace(0.0, 2.0 * math.pi, 1025)
        f = b.implicit(a.boundary(t))
        k = int(np.argmin(f))
        res = optimize.minimize_scalar(lambda s: float(b.implicit(a.boundary(s))),
                                       bounds=(t[max(k - 1, 0)], t[min(k + 1, 1024)]),
                                       method="bounded", options={"xatol": 1e-14})
        # f ≈ 1 − 2 δ / size for a penetration depth δ
        if min(res.fun, f[k]) < 1.0 - 2.0 * OVERLAP_RTOL * scale / min(b.axes):
            return True
    return False
