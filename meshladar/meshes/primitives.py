"""Tessellations of analytic shapes (disks and ellipses extruded to prisms, ellipsoids and
spheres), with the exact normals of the surfaces they approximate, and view directions spread
over the sphere."""

from __future__ import annotations

import math

import numpy as np

from .._validate import check_count, check_real, check_size
from ..errors import ParameterError
from ..precision import CAP_REL
from ..shapes import ellipse_normal, to_frame
from .directions import fibonacci_sphere
from .part import MeshPart

__all__ = ["prism", "sphere", "ellipsoid", "icosphere", "fibonacci_sphere"]

#: Bytes an icosphere face takes at the peak of building it (trimesh's arrays and ours:
#: measured about 120 B a face at 3 to 7 subdivisions; twice that for margin).
ICOSPHERE_FACE_BYTES = 256


class _PrismNormal:
    """Exact outward normal of an extruded ellipse (x-y gradient of its implicit function
    on the sides, ±z on the caps). A plain class, so that parts pickle to worker processes."""

    def __init__(self, center, axes, angle, lo, hi):
        self.center, self.axes, self.angle, self.lo, self.hi = center, axes, angle, lo, hi

    def __call__(self, p):
        p = np.asarray(p, dtype=np.float64)
        a, b = self.axes
        nx, ny = ellipse_normal(self.center, self.axes, self.angle, p[:, 0], p[:, 1])
        out = np.stack([nx, ny, np.zeros_like(nx)], -1)
        eps = CAP_REL * max(a, b, self.hi - self.lo)
        top = np.abs(p[:, 2] - self.hi) < eps
        bottom = np.abs(p[:, 2] - self.lo) < eps
        out[top | bottom] = 0.0
        out[top, 2] = 1.0
        out[bottom, 2] = -1.0
        return out

    def curvature_radius(self, p):
        """Radius of curvature of the cross-section at the points' eccentric angle (inf on
        the caps): (a² sin²t + b² cos²t)^(3/2) / (a b)."""
        p = np.asarray(p, dtype=np.float64)
        (cx, cy), (a, b) = self.center, self.axes
        xl, yl = to_frame(self.angle, p[:, 0] - cx, p[:, 1] - cy)
        t = np.arctan2(yl / b, xl / a)
        rho = (a * a * np.sin(t) ** 2 + b * b * np.cos(t) ** 2) ** 1.5 / (a * b)
        eps = CAP_REL * max(a, b, self.hi - self.lo)
        cap = (np.abs(p[:, 2] - self.hi) < eps) | (np.abs(p[:, 2] - self.lo) < eps)
        return np.where(cap, np.inf, rho)


class _EllipsoidNormal:
    """Exact outward normal of an ellipsoid: the gradient of Σ ((x − c)_i / a_i)²."""

    def __init__(self, center, axes):
        self.center, self.axes = np.asarray(center), np.asarray(axes)

    def __call__(self, p):
        g = (np.asarray(p, dtype=np.float64) - self.center) / self.axes**2
        return g / np.linalg.norm(g, axis=-1, keepdims=True)


def prism(shape, segments, height, material_index, *, z0=0.0):
    """A disk/ellipse extruded to a prism of ``height`` centred on z = z0, with ``segments``
    vertices on the exact boundary (uniform in the eccentric angle) and flat caps.

    The part's ``exact_normal`` is the shape's own outward normal (in x-y) for side points
    and ±z on the caps.

    Ring vertex k (k = 0 … segments − 1) is ``shape.boundary(2πk / segments)``, at
    z0 − height/2 and z0 + height/2; each cap is a fan about the shape's centre.

    Parameters
    ----------
    shape : meshladar.Disk or meshladar.Ellipse
        The cross-section, in the x-y plane, in scene units.
    segments : int
        Vertices per ring, ≥ 3.
    height : float
        Length of the prism along z, in scene units, finite and > 0.
    material_index : int or (4·segments,) int
        Index into the scene's material list, for all faces or per face.
    z0 : float, keyword-only, default 0.0
        z of the prism's middle, in scene units, finite.

    Returns
    -------
    MeshPart
        2·segments + 2 vertices and 4·segments faces (two per side quad, one per cap fan
        slice), named ``shape.name`` or, when that is empty, the shape's class name in
        lower case.

    Raises
    ------
    ParameterError
        When ``segments`` is not an integer ≥ 3, ``height`` is not finite and > 0, ``z0``
        is not finite, or the prism (about 1 kB a segment) would need more than 4 GiB.
    """
    n = check_count("segments", segments, 3)
    height = check_real("height", height, low=0.0, low_open=True)
    z0 = check_real("z0", z0)
    # the prism's arrays and trimesh's processing of them, about 1 kB a segment at peak
    check_size("segments", n, 1024, f"a prism of {n} segments", "use fewer segments")
    t = 2 * math.pi * np.arange(n) / n
    ring = shape.boundary(t)                                 # (n, 2)
    lo, hi = z0 - height / 2, z0 + height / 2
    v = np.concatenate([np.c_[ring, np.full(n, lo)], np.c_[ring, np.full(n, hi)],
                        [[shape.center[0], shape.center[1], lo],
                         [shape.center[0], shape.center[1], hi]]])
    i = np.arange(n)
    j = (i + 1) % n
    side = np.concatenate([np.c_[i, j, n + j], np.c_[i, n + j, n + i]])
    bottom = np.c_[np.full(n, 2 * n), j, i]
    top = np.c_[np.full(n, 2 * n + 1), n + i, n + j]
    faces = np.concatenate([side, bottom, top])
    exact_normal = _PrismNormal(shape.center, shape.axes, shape.angle, lo, hi)
    return MeshPart(v, faces, material_index, shape.name or type(shape).__name__.lower(),
                    exact_normal)


def icosphere(subdivisions):
    """Vertices (n, 3) float64 and faces (m, 3) of the unit icosphere (radius 1 about the
    origin, 20·4^subdivisions faces), as trimesh builds it.

    Parameters
    ----------
    subdivisions : int
        Number of subdivisions of the icosahedron, ≥ 0; the faces (about
        :data:`ICOSPHERE_FACE_BYTES` each while building) must fit in meshladar's 4 GiB
        allocation cap: at most 9 subdivisions.

    Returns
    -------
    vertices : (n, 3) ndarray of float64
        Unit vectors.
    faces : (m, 3) ndarray of int
        Vertex indices, m = 20·4^subdivisions, as trimesh returns them.

    Raises
    ------
    ParameterError
        When ``subdivisions`` is not an integer ≥ 0, or the icosphere would need more than
        the 4 GiB allocation cap (checked before anything is built).
    """
    import trimesh

    subdivisions = check_count("subdivisions", subdivisions, 0)
    # 20·4^n faces (inf where that passes float64, n > 500: any such n is refused)
    faces = 20.0 * 4.0 ** subdivisions if subdivisions <= 500 else math.inf
    check_size("subdivisions", faces, ICOSPHERE_FACE_BYTES,
               f"an icosphere of {subdivisions} subdivisions (20·4^{subdivisions} faces)",
               "use fewer subdivisions (at most 9)")
    m = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    return np.asarray(m.vertices, dtype=np.float64), np.asarray(m.faces)


def ellipsoid(center, semi_axes, material_index, *, subdivisions=4, name="ellipsoid"):
    """A tessellated ellipsoid (a scaled icosphere: 20·4^subdivisions faces) whose
    ``exact_normal`` is the ellipsoid's own (the gradient of Σ (x_i/a_i)²).

    Vertex i is ``center + u_i * semi_axes`` for the unit icosphere's vertex u_i
    (:func:`icosphere`), so every vertex lies on the ellipsoid.

    Parameters
    ----------
    center : (3,) array_like
        Centre, in scene units.
    semi_axes : (3,) array_like
        Semi-axes along x, y and z, in scene units, finite and > 0.
    material_index : int or (m,) int
        Index into the scene's material list, for all faces or per face.
    subdivisions : int, keyword-only, default 4
        Icosphere subdivisions, ≥ 0.
    name : str, keyword-only, default "ellipsoid"
        The part's label.

    Returns
    -------
    MeshPart
        With its ``exact_normal`` set.

    Raises
    ------
    ParameterError
        When ``center`` or ``semi_axes`` is not of shape (3,), a semi-axis is not finite
        and positive, ``subdivisions`` is not an integer ≥ 0, or the icosphere would pass
        the 4 GiB allocation cap (:func:`icosphere`).
    GeometryError
        When ``center`` is not finite (from :class:`MeshPart`).
    """
    c = np.asarray(center, dtype=np.float64)
    ax = np.asarray(semi_axes, dtype=np.float64)
    if c.shape != (3,) or ax.shape != (3,) or np.any(ax <= 0) or not np.all(np.isfinite(ax)):
        raise ParameterError(f"ellipsoid needs a 3-D center and three positive semi_axes; got "
                             f"{center!r}, {semi_axes!r}")
    v, f = icosphere(subdivisions)
    return MeshPart(c + v * ax, f, material_index, name, _EllipsoidNormal(c, ax))


def sphere(center, radius, material_index, *, subdivisions=4, name="sphere"):
    """A tessellated sphere (icosphere: 20·4^subdivisions faces) with its exact normals.

    :func:`ellipsoid` with three equal semi-axes.

    Parameters
    ----------
    center : (3,) array_like
        Centre, in scene units.
    radius : float
        Radius, in scene units, finite and > 0.
    material_index : int or (m,) int
        Index into the scene's material list, for all faces or per face.
    subdivisions : int, keyword-only, default 4
        Icosphere subdivisions, ≥ 0.
    name : str, keyword-only, default "sphere"
        The part's label.

    Returns
    -------
    MeshPart
        With its ``exact_normal`` set.

    Raises
    ------
    ParameterError
        When ``center`` is not of shape (3,), ``radius`` is not finite and positive (the
        message names ``semi_axes``), ``subdivisions`` is not an integer ≥ 0, or the
        icosphere would pass the 4 GiB allocation cap (:func:`icosphere`).
    GeometryError
        When ``center`` is not finite (from :class:`MeshPart`).
    """
    return ellipsoid(center, (radius, radius, radius), material_index,
                     subdivisions=subdivisions, name=name)
