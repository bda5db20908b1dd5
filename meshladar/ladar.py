"""The ladar: view directions and range bins (monostatic, range-resolved).

Conventions (the guide's Concepts page, "Views and range"): a view is a unit vector w from
the scene toward the ladar, which sits at infinity along w; for views about the z axis, view
angle φ gives w = (cos φ, sin φ, 0). The range of a point p is r = −p·w (zero on the plane
through the origin, growing away from the ladar). Range bins are given by strictly
increasing edges.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ._summary import table, text
from ._validate import (azimuths_deg, check_count, check_real, check_size, check_views_agree,
                        finite_array, readonly_copy, unit_vectors)
from .errors import MeshladarWarning, ParameterError, user_stacklevel
from .precision import COUNT_SLACK, SCENE_RADIUS_RANGE, SPAN_FLOOR
from .scene import Scene

__all__ = ["Ladar", "PAPER_BIN_DIVISOR", "OFF_CENTRE_FACTOR", "target_centre"]

#: The paper's range resolution is A/256 for a disk of radius A (Sec. 4.A).
PAPER_BIN_DIVISOR = 256
#: The most views a named set-up asks for (a command line's ``--views``, a phantom spec's
#: ladar): a sinogram of 1e6 views x 512 bins is 4 GB, allocated before any work.
MAX_VIEWS = 10**6


#: The narrowest bins taken: 1/width and its square stay finite (subnormal widths did not).
MIN_BIN_WIDTH = 1e-200
_FLOAT_MAX = float(np.finfo(np.float64).max)


@dataclass(frozen=True, eq=False)
class Ladar:
    """A monostatic, range-resolved ladar: where it looks from and how it bins range.

    Parameters
    ----------
    angles_deg : (n_views,) array_like or None
        View angles φ in degrees about the z axis (w = (cos φ, sin φ, 0)). Any finite
        values; at least one. None when ``view_vectors`` are given (then the vectors'
        azimuths).
    bin_edges : (n_bins + 1,) array_like
        Strictly increasing, finite range bin edges in scene units; at least one bin.
    view_vectors : (n_views, 3) array_like, keyword-only, optional
        Arbitrary view directions (from the scene toward the ladar), normalised here; for
        3-D meshes seen from anywhere (see ``meshladar.meshes.fibonacci_sphere``). Only the mesh
        model accepts views off the x-y plane.

    Raises
    ------
    ParameterError
        When neither ``angles_deg`` nor ``view_vectors`` is given; an array is not finite;
        ``view_vectors`` is not (n_views, 3) non-zero vectors; both are given and an
        angle differs from its vector's azimuth by more than
        :data:`meshladar.precision.ANGLE_TOL_DEG` (vectors along ±z excepted) or their
        lengths differ; ``angles_deg`` is not a non-empty 1-D array; ``bin_edges`` is not
        1-D with at least 2 strictly increasing edges; or the sinogram (n_views × n_bins
        float64) would pass meshladar's allocation cap.

    Examples
    --------
    >>> import numpy as np, meshladar as ml
    >>> ladar = ml.Ladar(angles_deg=np.arange(360.0), bin_edges=np.linspace(-1, 1, 513))
    >>> ladar = ml.Ladar.centered(n_bins=512, bin_width=0.8 / 256)     # the paper's A/256
    >>> ladar.n_views, ladar.n_bins
    (360, 512)
    """

    angles_deg: np.ndarray
    bin_edges: np.ndarray
    view_vectors: np.ndarray = field(default=None, kw_only=True)

    def __post_init__(self):
        if self.view_vectors is not None:
            vec = unit_vectors("view_vectors", self.view_vectors)
            if vec.ndim != 2 or len(vec) == 0:
                raise ParameterError(f"view_vectors must have shape (n_views, 3); got "
                                     f"{vec.shape}")
            azimuth = azimuths_deg(vec)
            if self.angles_deg is None:
                object.__setattr__(self, "angles_deg", azimuth)
            else:
                given = finite_array("angles_deg", self.angles_deg)
                if given.shape == azimuth.shape:
                    # the same views, or a contradiction the forward models would read
                    # differently (the analytic and pixel models use the angles)
                    check_views_agree(given, vec)
            object.__setattr__(self, "view_vectors", readonly_copy(vec))
        elif self.angles_deg is None:
            raise ParameterError("give angles_deg or view_vectors; got neither")
        angles = finite_array("angles_deg", self.angles_deg)
        edges = finite_array("bin_edges", self.bin_edges)
        if angles.ndim != 1 or angles.size == 0:
            raise ParameterError(f"angles_deg must be a non-empty 1-D array of view angles; got "
                                 f"shape {angles.shape}")
        if edges.ndim != 1 or edges.size < 2:
            raise ParameterError(f"bin_edges must be a 1-D array of at least 2 edges; got shape "
                                 f"{edges.shape}")
        steps = np.diff(edges)
        if np.any(steps <= 0):
            k = int(np.argmax(steps <= 0))
            raise ParameterError(f"bin_edges must be strictly increasing; got "
                                 f"{float(edges[k])!r} then {float(edges[k + 1])!r} at index {k}")
        if self.view_vectors is not None and len(self.view_vectors) != angles.size:
            raise ParameterError(f"angles_deg and view_vectors must have the same length; got "
                                 f"{angles.size} and {len(self.view_vectors)}")
        check_size("ladar", angles.size * (edges.size - 1), 8,
                   f"a sinogram of {angles.size} views x {edges.size - 1} bins",
                   "use fewer views or bins")
        object.__setattr__(self, "angles_deg", readonly_copy(angles))
        object.__setattr__(self, "bin_edges", readonly_copy(edges))
        if self.view_vectors is None:
            phi = np.deg2rad(angles)
            object.__setattr__(self, "view_vectors", readonly_copy(
                np.stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)], axis=-1)))

    @property
    def planar(self) -> bool:
        """True when every view lies in the x-y plane (views about the z axis)."""
        return bool(np.all(self.view_vectors[:, 2] == 0.0))

    # -- constructors -------------------------------------------------------------------
    @classmethod
    def centered(cls, n_bins, bin_width, *, center=0.0, angles_deg=None):
        """n_bins bins of width ``bin_width`` centred on range ``center``.

        ``angles_deg`` defaults to the paper's 360 views at 1° (0, 1, ..., 359).

        Parameters
        ----------
        n_bins : int
            Number of range bins, ≥ 1.
        bin_width : float
            Width of each bin, scene units, in [1e-200, 2 × 1e30 / n_bins].
        center : float
            Range of the middle of the bins, scene units, in [−1e30, 1e30] (default 0.0).
            Keyword-only.
        angles_deg : (n_views,) array_like, optional
            View angles, degrees (default 0, 1, ..., 359). Keyword-only.

        Returns
        -------
        Ladar
            Edges ``center + (k − n_bins/2) bin_width`` for k = 0, ..., n_bins.

        Raises
        ------
        ParameterError
            When ``n_bins``, ``bin_width`` or ``center`` is out of range, 360 views of
            ``n_bins`` bins would pass meshladar's allocation cap, or the angles are
            invalid (see :class:`Ladar`).
        """
        n = check_count("n_bins", n_bins)
        check_size("n_bins", n, 8 * 360, f"{n} bins (a sinogram of 360 views)", "use fewer bins")
        top = SCENE_RADIUS_RANGE[1]          # ranges of scenes meshladar takes, in units
        # from 1e-200 (1/width and its square stay finite) to the scenes' range
        w = check_real("bin_width", bin_width, low=MIN_BIN_WIDTH, high=2 * top / n)
        c = check_real("center", center, low=-top, high=top)
        edges = c + (np.arange(n + 1) - n / 2.0) * w
        return cls(np.arange(360.0) if angles_deg is None else angles_deg, edges)

    @classmethod
    def paper(cls, radius=0.8, *, n_bins=2 * PAPER_BIN_DIVISOR, angles_deg=None):
        """The paper's set-up: bins of width A/256 for A = ``radius``, 360 views at 1°.

        With the default A = 0.8 and 512 bins, the bins cover [−A, A]: the paper's disk.

        Parameters
        ----------
        radius : float
            The disk's radius A, scene units, in (0, 1e30] (default 0.8).
        n_bins : int
            Number of range bins, ≥ 1 (default 2 × :data:`PAPER_BIN_DIVISOR` = 512).
            Keyword-only.
        angles_deg : (n_views,) array_like, optional
            View angles, degrees (default 0, 1, ..., 359). Keyword-only.

        Returns
        -------
        Ladar
            ``n_bins`` bins of width A / :data:`PAPER_BIN_DIVISOR` centred on range 0
            (:meth:`centered`).

        Raises
        ------
        ParameterError
            When ``radius`` is out of range, or :meth:`centered` refuses the bins or
            angles.

        References
        ----------
        Jin & Levine (2009), Sec. 4.A and Fig. 6 (range bins of width A/256 for a disk of
        radius A; 360 views at 1°).
        """
        a = check_real("radius", radius, low=0.0, low_open=True, high=SCENE_RADIUS_RANGE[1])
        return cls.centered(n_bins, a / PAPER_BIN_DIVISOR, angles_deg=angles_deg)

    @classmethod
    def covering(cls, scene, *, bin_width=None, n_bins=None, margin=0.0, angles_deg=None,
                 view_vectors=None):
        """Bins covering the ranges the scene spans over the requested views.

        Range r = −p·w is zero on the plane through the world origin perpendicular to the
        view and grows away from the ladar: the views turn about the origin. For a mesh
        scene the bins span exactly the nearest to the farthest range of any vertex over
        the views (half a bin beyond each end); for analytic shapes (the paper's phantoms,
        centred on the rotation axis) they are centred on range 0 and reach |C| + R, the
        scene's bounding circle, in every view about z.

        The bins are shared by all the views, so a target whose centre c is off the origin
        spreads its ranges −c·w ± R over the views: each view's returns fill only about
        R / (|c| + R) of the bins, and a reconstruction's default square or cube (the bins'
        reach about the origin) holds the target small and off-centre. When centring the
        target on the origin would at least halve the bins' span (``OFF_CENTRE_FACTOR``),
        ``covering`` warns with the fill and the translation that centres it (views about
        z: its x and y; over the sphere: all three).

        Give ``bin_width`` or ``n_bins`` (or both: ``n_bins`` bins of that width centred on
        the span). Views: ``angles_deg`` about z (default 0, 1, ..., 359) or
        ``view_vectors``.

        Parameters
        ----------
        scene : Scene
            The target: a mesh or an analytic scene.
        bin_width : float, optional
            Width of each bin, scene units, ≥ 1e-200. Keyword-only.
        n_bins : int, optional
            Number of bins, ≥ 1. Keyword-only.
        margin : float
            Extra range, scene units, ≥ 0, added beyond the nearest and the farthest range
            (default 0.0). Keyword-only.
        angles_deg : (n_views,) array_like, optional
            View angles about z, degrees (default 0, 1, ..., 359). Keyword-only.
        view_vectors : (n_views, 3) array_like, optional
            View directions instead (``angles_deg`` then None or their azimuths).
            Keyword-only.

        Returns
        -------
        Ladar
            The views given and uniform bins centred on the span's middle (a mesh) or on
            range 0 (analytic shapes). For a mesh of span s (nearest to farthest range,
            margins included): with only ``bin_width``, ceil(s / bin_width) + 1 bins (to a
            slack of 1e-9 bin); with only ``n_bins``, width s / (n_bins − 1) (for one bin
            or s = 0: max(s, 1e-12 (1 + |middle|))). For analytic shapes of half-span
            h = |C| + R + margin: ceil(2h / bin_width) bins, or width 2h / n_bins.

        Raises
        ------
        ParameterError
            When ``scene`` is not a Scene, neither ``bin_width`` nor ``n_bins`` is given,
            ``margin``, ``bin_width`` or ``n_bins`` is out of range, the views are invalid
            (see :class:`Ladar`), or the bins would pass meshladar's allocation cap.

        Warns
        -----
        MeshladarWarning
            When the target's centre is so far from the origin that centring it would at
            least halve the bins' span (:data:`OFF_CENTRE_FACTOR`).
        """
        m, w, n = _covering_options(scene, bin_width, n_bins, margin)
        views = _requested_views(cls, angles_deg, view_vectors)
        if n is not None:
            check_size("n_bins", n, 8 * views.n_views, f"{n} bins", "use fewer bins")
        near, far = scene.view_ranges(views.view_vectors)
        _warn_off_centre(scene, views, near, far)
        edges = _covering_edges(scene, (near, far), m, w, n, views.n_views)
        if view_vectors is not None:
            return cls(None, edges, view_vectors=views.view_vectors)
        return cls(views.angles_deg, edges)

    # -- derived ------------------------------------------------------------------------
    @property
    def n_views(self) -> int:
        return self.angles_deg.size

    @property
    def n_bins(self) -> int:
        return self.bin_edges.size - 1

    @cached_property
    def bin_centers(self) -> np.ndarray:
        return 0.5 * (self.bin_edges[1:] + self.bin_edges[:-1])

    def _summary(self):
        width = np.diff(self.bin_edges)
        uniform = bool(np.ptp(width) <= 1e-9 * width.mean())
        if self.planar:
            a = np.asarray(self.angles_deg, dtype=np.float64)
            step = np.diff(a)
            views = (f"about z, {a[0]:.4g} to {a[-1]:.4g} deg"
                     + (f" every {step[0]:.4g}" if a.size > 1 and
                        np.ptp(step) <= 1e-9 * max(abs(step[0]), 1.0) else ""))
        else:
            views = "3-D directions"
        return (("n_views", self.n_views), ("n_bins", self.n_bins),
                ("range", (float(self.bin_edges[0]), float(self.bin_edges[-1]))),
                ("bin_width", float(width[0]) if uniform else "uneven"), ("views", views))

    def __repr__(self) -> str:
        return text("Ladar", *self._summary())

    def _repr_html_(self) -> str:
        return table("Ladar", *self._summary())


#: ``Ladar.covering`` warns when the views' shared range span is more than this many times
#: the span the target would need centred on the origin (the point the views turn about):
#: centring it would give each view's returns at least this many times more bins.
OFF_CENTRE_FACTOR = 2.0


def target_centre(scene, planar):
    """The point a scene's views should turn about: a mesh's bounding-box centre, the
    shapes' bounding circle's centre for analytic scenes; z = 0 for views about z (z does
    not change their ranges).

    Parameters
    ----------
    scene : Scene
        The target.
    planar : bool
        True for views about z: the centre's z is then 0.

    Returns
    -------
    (3,) numpy.ndarray
        The centre (x, y, z), scene units: the middle of a mesh scene's bounding box, or
        the centre of an analytic scene's :meth:`Scene.bounding_circle` with z = 0.
    """
    if scene.is_mesh:
        b = scene.bounds()
        c = 0.5 * (b[0] + b[1])
    else:
        (cx, cy), _ = scene.bounding_circle()
        c = np.array([cx, cy, 0.0])
    if planar:
        c[2] = 0.0
    return c


def _warn_off_centre(scene, views, near, far):
    """Warn, with the translation that fixes it, when the target's centre is so far from
    the origin (the point the views turn about) that the views' shared bins span more than
    ``OFF_CENTRE_FACTOR`` times the ranges it would span centred there (``near``, ``far``:
    the scene's range interval in each view)."""
    span = float(far.max() - near.min())
    c = target_centre(scene, views.planar)
    shift = views.view_vectors @ c                        # r about c = r + c·w
    centred = float((far + shift).max() - (near + shift).min())
    if not (centred > 0 and span > OFF_CENTRE_FACTOR * centred):
        return
    depth = float(np.max(far - near))
    move = ", ".join(f"{-x:.6g}" if x else "0" for x in c)
    warnings.warn(
        f"the target is far from the origin, the {'axis' if views.planar else 'point'} the "
        f"views turn about: each view sees it over at most {depth:.3g} of the {span:.3g} "
        f"range units the views span together ({100 * depth / span:.0f}% of the bins; "
        f"{100 * depth / centred:.0f}% centred on the origin), and a reconstruction's "
        f"default frame (the bins' reach about the origin) holds it small and off-centre: "
        f"move its centre ({', '.join(f'{x:.6g}' for x in c)}) to the origin before "
        f"simulating (trimesh: mesh.apply_translation(({move})), or Scene.from_mesh(mesh, "
        f"..., transform=trimesh.transformations.translation_matrix(({move}))))",
        MeshladarWarning, stacklevel=user_stacklevel())


def _covering_options(scene, bin_width, n_bins, margin):
    """:meth:`Ladar.covering`'s scene and bin options, checked: (margin, bin width, bin
    count), the width or the count None when not given."""
    if not isinstance(scene, Scene):
        raise ParameterError(f"scene must be a meshladar.Scene; got {type(scene).__name__}")
    if bin_width is None and n_bins is None:
        raise ParameterError("give bin_width or n_bins (or both); got neither")
    m = check_real("margin", margin, low=0.0)
    w = check_real("bin_width", bin_width, low=MIN_BIN_WIDTH) \
        if bin_width is not None else None
    n = check_count("n_bins", n_bins) if n_bins is not None else None
    return m, w, n


def _requested_views(ladar_class, angles_deg, view_vectors):
    """A ladar (of ``ladar_class``) of :meth:`Ladar.covering`'s views and one placeholder
    bin, which checks them: ``view_vectors``, else ``angles_deg`` (default 0, 1, ..., 359)."""
    if view_vectors is not None:
        return ladar_class(angles_deg, np.array([0.0, 1.0]), view_vectors=view_vectors)
    return ladar_class(np.arange(360.0) if angles_deg is None else angles_deg,
                       np.array([0.0, 1.0]))


def _covering_edges(scene, ranges, m, w, n, n_views):
    """The edges of :meth:`Ladar.covering`'s bins: ``n`` bins of width ``w`` (the one not
    given, None, derived from the other) covering a mesh scene's ``ranges`` (its nearest
    and farthest range in each view), or an analytic scene's bounding circle, with margin
    ``m`` beyond each end; refused when ``n_views`` views of them would pass meshladar's
    allocation cap."""
    near, far = ranges
    if scene.is_mesh:
        lo, hi = float(near.min()) - m, float(far.max()) + m
        center = 0.5 * (lo + hi)
        span = max(hi - lo, 0.0)
        if n is None:
            n = max(1, int(np.ceil(span / w - COUNT_SLACK)) + 1)
        elif w is None:
            # n bins whose centres run from the nearest to the farthest range
            w = span / (n - 1) if n > 1 and span > 0 else max(span, SPAN_FLOOR * (
                1.0 + abs(center)))
    else:
        c, radius = scene.bounding_circle()
        center = 0.0
        half = float(np.hypot(*c)) + radius + m
        if n is None:
            n = max(1, int(np.ceil(2 * half / w - COUNT_SLACK)))
        elif w is None:
            w = 2 * half / n
    check_size("bin_width", n, 8 * n_views, f"{n:.4g} bins of width {w:g}",
               "give wider bins")
    # edges center ± (n/2)·w stay finite (16 bins of 1e308 overflowed to inf)
    check_real("bin_width", w, low=MIN_BIN_WIDTH, high=_FLOAT_MAX / (n + 2))
    return center + (np.arange(n + 1) - n / 2.0) * w
