"""Unknown geometry, the paper's proposal: reconstruct, segment the surfaces, fit the shapes,
then the coatings, and say how the geometry's errors carry into the coatings.

:func:`find_shapes` takes the surface points of a first reconstruction
(:func:`meshladar.reconstruct.compensation.estimate_surface`: sub-pixel ridge points of the
log-radiance FBP) and finds circles among them by RANSAC (three points define a circle; the circle with
the most points within ``tol`` wins, its points are removed, repeat), each refined by
geometric least squares; with ``kind="ellipse"`` each connected group of points is fitted
as an ellipse (Fitzgibbon's direct least-squares fit, then geometric refinement), so
ellipses must not touch. Every shape
comes with its standard errors from the fit's residuals (the point fits live in
:mod:`._conics`).

:func:`fit_scene` builds the scene from those shapes, fits the coatings
(:func:`meshladar.fit.coatings.fit_coatings`) and refits with each geometry parameter moved by
its standard error: the shifts are the coatings' sensitivity to the geometry, and their
root sum of squares the geometry's share of each coating parameter's uncertainty.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from .._validate import check_choice, check_count, check_real, check_seed
from ..brdf import SandfordRobertson
from ..reconstruct.compensation import estimate_surface, first_image
from ..errors import ParameterError
from ..ladar import Ladar
from ..scene import Scene
from ..shapes import Disk, Ellipse
from ._conics import _circle_lsq, _components, _ellipse_lsq, _ransac_circles
from .coatings import fit_coatings
from .kernels import coating_kernel

__all__ = ["find_shapes", "fit_scene", "SceneFit", "SHAPE_KINDS"]

#: Shapes :func:`find_shapes` fits.
SHAPE_KINDS = ("disk", "ellipse")


def find_shapes(sino, *, size=512, extent=None, center=(0.0, 0.0), kind="disk", first=None,
                tol_bins=1.5, min_share=0.05, max_shapes=8, seed=0, material=None):
    """Shapes found in a sinogram's first reconstruction.

    Parameters
    ----------
    sino : Sinogram
        Views about z, uniform bins.
    size, extent, center
        The first reconstruction's grid (default FBP of the log radiance): ``size`` pixels
        across [−extent, extent]² about ``center`` (defaults 512, the bins' reach as
        :func:`~meshladar.reconstruct.fbp2d.fbp`'s, and (0, 0)); unused when ``first``
        is given.
    kind : {"disk", "ellipse"}
        ``"disk"`` (default): circles found by RANSAC, each with surface points in at
        least half of its 36 equal sectors and none overlapping another (a circle
        through pieces of two shapes' boundaries is not a shape); ``"ellipse"``: each
        connected group of surface points (neighbours within 2.5 pixels) fitted as an
        ellipse.
    first : Image, optional
        The first reconstruction.
    tol_bins : float
        A surface point belongs to a shape within this many range bins (the mean bin
        width) of it (default 1.5, > 0); used by ``"disk"`` only, checked for both.
    min_share : float
        A shape needs at least this share of the surface points, in [0, 1] (default
        0.05), and at least 10 points.
    max_shapes : int
        The most shapes found (default 8, ≥ 1).
    seed : int
        Seed of the RANSAC draws (``"disk"``; default 0).
    material : BRDF, optional
        The coating the shapes carry (default a neutral SR start for fitting).

    Returns
    -------
    list of (shape, standard errors, rms distance)
        Shapes (:class:`~meshladar.Disk` or :class:`~meshladar.Ellipse`, named "shape 0",
        "shape 1", ... by decreasing size), the standard errors of their parameters
        ((cx, cy, r) or (cx, cy, A, B, angle in radians)), and the rms distance of their
        points.

    Raises
    ------
    ParameterError
        If ``kind``, ``seed``, ``tol_bins``, ``min_share`` or ``max_shapes`` is invalid,
        no shape is found among the surface points, the points of a group do not
        determine an ellipse, or the first reconstruction yields no surface point.

    References
    ----------
    M. A. Fischler and R. C. Bolles, "Random sample consensus", Commun. ACM 24, 381-395
    (1981) (RANSAC); I. Kåsa, "A circle fitting procedure and its error analysis", IEEE
    Trans. Instrum. Meas. 25, 8-14 (1976) (the algebraic circle start); A. Fitzgibbon,
    M. Pilu and R. B. Fisher, "Direct least square fitting of ellipses", IEEE Trans.
    Pattern Anal. Mach. Intell. 21, 476-480 (1999).
    """

    kind = check_choice("kind", kind, SHAPE_KINDS)
    seed = check_seed("seed", seed)                    # all before the first reconstruction
    tol_bins = check_real("tol_bins", tol_bins, low=0.0, low_open=True)
    min_share = check_real("min_share", min_share, low=0.0, high=1.0)
    max_shapes = check_count("max_shapes", max_shapes)
    if first is None:
        first = first_image(sino, size, extent, center)
    surface = estimate_surface(first, sino, shadows=False)
    tol = tol_bins * float(np.mean(np.diff(sino.bin_edges)))
    min_points = max(10, int(min_share * surface.points.shape[0]))
    if kind == "disk":
        groups = _ransac_circles(surface.points, tol, min_points, max_shapes, seed)
    else:
        groups = _components(surface.points, 2.5 * surface.pixel_size, min_points)
        groups = sorted(groups, key=len, reverse=True)[:max_shapes]
    if not groups:
        raise ParameterError("no shape found among the first reconstruction's surface "
                             "points; give first= or a coarser tol_bins")
    mat = material if material is not None else SandfordRobertson(0.05, 0.7, 0.2, 0.1)
    return _named_shapes(surface.points, groups, kind, mat)


def _named_shapes(points, groups, kind, material):
    """Each group of ``points`` (index arrays) fitted as a shape of ``kind`` carrying
    ``material``: (shape, standard errors, rms distance), named "shape 0", "shape 1", ...
    by decreasing size."""
    out = []
    for g in groups:
        p = points[g]
        if kind == "disk":
            q, cov, rms = _circle_lsq(p)
            shape = Disk((q[0], q[1]), q[2], material)
            size_ = q[2]
        else:
            q, cov, rms = _ellipse_lsq(p)
            shape = Ellipse((q[0], q[1]), (q[2], q[3]), math.degrees(q[4]), material)
            size_ = q[2] * q[3]
        out.append((size_, shape, np.sqrt(np.abs(np.diag(cov))), rms))
    out.sort(key=lambda t: -t[0])
    return [(dataclasses.replace(s, name=f"shape {i}"), se, rms)
            for i, (_, s, se, rms) in enumerate(out)]


@dataclass(frozen=True, eq=False)
class SceneFit:
    """The result of :func:`fit_scene`.

    Attributes
    ----------
    scene : Scene
        The found shapes with the fitted coatings.
    shapes : list
        :func:`find_shapes`'s (shape, standard errors, rms).
    fit : CoatingFit
        The coatings, the geometry taken as found.
    geometry_names : tuple of str
        "shape.parameter" of each geometry parameter moved (``cx``, ``cy``, ``r`` per
        disk; ``cx``, ``cy``, ``A``, ``B``, ``angle`` per ellipse).
    geometry_shift : (n_geometry, n_coating) array
        Change of each coating estimate when one geometry parameter moves by its standard
        error (rows named in ``geometry_names``).
    geometry_stderr : (n_coating,) array
        Their root sum of squares: the geometry's share of each coating's uncertainty.
    info : dict
        ``"kind"``: the shapes fitted.
    """

    scene: object
    shapes: list
    fit: object
    geometry_names: tuple
    geometry_shift: np.ndarray
    geometry_stderr: np.ndarray
    info: dict = field(default_factory=dict)

    def report(self):
        """The fit as text lines.

        Returns
        -------
        list of str
            One line per shape found (centre, semi-axes, standard errors, rms), the
            coating fit's :meth:`~meshladar.fit.CoatingFit.report`, then each coating
            parameter's σ from the noise and from the geometry.
        """
        out = ["  shapes found:"]
        for s, se, rms in self.shapes:
            axes = s.axes
            out.append(f"    {s.name}: centre ({s.center[0]:.4f}, {s.center[1]:.4f}), "
                       f"semi-axes ({axes[0]:.4f}, {axes[1]:.4f}); σ {np.round(se, 5)}, "
                       f"rms {rms:.2g}")
        out += self.fit.report()
        out.append(f"  {'parameter':<26} {'σ (noise)':>10} {'σ (geometry)':>13}")
        for i, n in enumerate(self.fit.names):
            out.append(f"  {n:<26} {self.fit.stderr[i]:10.3g} {self.geometry_stderr[i]:13.3g}")
        return out


def fit_scene(sino, *, kind="disk", size=512, extent=None, center=(0.0, 0.0), first=None,
              noise="gaussian", photons_per_unit=None, speckle_cells=None, samples=4096,
              **find):
    """Shapes, then coatings, from a sinogram alone; see the module docstring.
    ``noise``, ``photons_per_unit``, ``speckle_cells`` as
    :func:`~meshladar.fit.coatings.fit_coatings`; other keywords go to :func:`find_shapes`.

    Each disk's radius is first moved by the best of nine offsets in [−1, 1] range bins
    (the scene that fits the data best with the best starting coatings of a grid of SR
    e and b); ellipses are kept as found. Disks that then overlap are shrunk to
    touching. The coatings are fitted from those starting coatings, then refitted once
    per geometry parameter moved by its standard error (the refits' warnings silenced).

    Parameters
    ----------
    sino : Sinogram
        Views about z (``angles_deg``), uniform bins; its ``radiometry`` (default
        ``"paper"``) is the kernels'.
    kind : {"disk", "ellipse"}
        The shapes to find (default ``"disk"``).
    size, extent, center, first
        The first reconstruction, as :func:`find_shapes`.
    noise, photons_per_unit, speckle_cells
        The noise model, as :func:`~meshladar.fit.coatings.fit_coatings` (default
        ``"gaussian"``).
    samples : int
        Pieces per boundary of the coating kernels (default 4096; the radius search
        uses at most 2048).
    **find
        Other options of :func:`find_shapes` (``tol_bins``, ``min_share``,
        ``max_shapes``, ``seed``, ``material``).

    Returns
    -------
    SceneFit
        The found scene with the fitted coatings, the shapes, the coating fit, and the
        geometry's share of each coating parameter's uncertainty.

    Raises
    ------
    ParameterError
        Whatever :func:`find_shapes`, :func:`coating_kernel` or
        :func:`~meshladar.fit.coatings.fit_coatings` refuses (no shape found, an invalid
        noise option).

    References
    ----------
    Jin & Levine (2009), Section 5 (a geometric reconstruction first, to assign the
    binned radiance to components, then their BRDF parameters).
    """

    shapes = find_shapes(sino, kind=kind, size=size, extent=extent, center=center,
                         first=first, **find)
    ladar = Ladar(sino.angles_deg, sino.bin_edges)
    radiometry = sino.radiometry or "paper"
    kw = dict(noise=noise, photons_per_unit=photons_per_unit, speckle_cells=speckle_cells)

    def fit_with(parts):
        kernel = coating_kernel(_scene(parts), ladar, radiometry=radiometry,
                                samples=samples)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")            # reported by the main fit below
            return fit_coatings(kernel, sino, **kw)

    shapes = _refine_sizes(shapes, sino, ladar, radiometry, samples)
    scene = _scene([s for s, _, _ in shapes])
    shapes = [(t, se, rms) for t, (_, se, rms) in zip(scene.shapes, shapes)]
    kernel = coating_kernel(scene, ladar, radiometry=radiometry, samples=samples)
    fit = fit_coatings(kernel, sino, initial=_start(kernel, sino.values), **kw)
    kw["initial"] = dict(enumerate(fit.materials))
    names, shifts = _geometry_shifts(shapes, kind, fit, fit_with)
    found = Scene([dataclasses.replace(s, material=m)
                   for (s, _, _), m in zip(shapes, fit.materials)])
    return SceneFit(found, shapes, fit, tuple(names), shifts,
                    np.sqrt(np.sum(shifts ** 2, axis=0)), {"kind": kind})


def _geometry_shifts(shapes, kind, fit, fit_with):
    """The names of the geometry parameters and, per parameter, the change of the coating
    estimates of ``fit`` when it moves by its standard error (the coatings refitted by
    ``fit_with`` on the moved shapes)."""
    names, shifts = [], []
    fields = ("cx", "cy", "r") if kind == "disk" else ("cx", "cy", "A", "B", "angle")
    for i, (s, se, _) in enumerate(shapes):
        for j, f in enumerate(fields):
            moved = _moved(s, f, se[j])
            others = [t for k, (t, _, _) in enumerate(shapes) if k != i]
            parts = others[:i] + [moved] + others[i:]
            refit = fit_with(parts)
            names.append(f"{s.name}.{f}")
            shifts.append(refit.estimate - fit.estimate)
    return names, np.array(shifts)


#: The starting grid of :func:`fit_scene`: glint widths and diffuse narrowness tried per
#: part, two passes over the parts.
_E_GRID = (0.003, 0.007, 0.015, 0.03, 0.07, 0.15, 0.3, 0.6)
_B_GRID = (0.1, 0.5, 0.9)


def _start(kernel, y):
    """Starting coatings: per part in turn, the (e, b) of the grid whose prediction fits
    best (χ² with a variance of the prediction plus 1 % of the peak), ρd and ε neutral."""
    mats = [SandfordRobertson(0.05, 0.7, 0.2, 0.1) for _ in kernel.parts]
    parts = [kernel.contribution(i, m) for i, m in enumerate(mats)]
    floor = 0.01 * float(np.abs(y).max())
    for _ in range(2):
        for i in range(len(mats)):
            rest = sum(parts[:i] + parts[i + 1:]) if len(parts) > 1 else 0.0
            best = None
            for e in _E_GRID:
                for b in _B_GRID:
                    try:
                        m = SandfordRobertson(0.05, 0.7, b, e)
                    except ParameterError:
                        continue
                    c = kernel.contribution(i, m)
                    # the level is free: scale ρd and ε together by the best amplitude
                    pred = rest + c
                    chi = float(np.sum((y - pred) ** 2 / (np.abs(pred) + floor)))
                    if best is None or chi < best[0]:
                        best = (chi, m, c)
            mats[i], parts[i] = best[1], best[2]
    return dict(enumerate(mats))


def _refine_sizes(shapes, sino, ladar, radiometry, samples):
    """Each disk's radius moved by the offset within ±1 range bin whose scene fits the data
    best with the best starting coatings (:func:`_start`): a first reconstruction puts a
    thin convex surface up to half a bin inside, and a glint's bin needs its surface to a
    fraction of a bin. Ellipses are kept as found."""

    dr = float(np.mean(np.diff(sino.bin_edges)))
    y = sino.values
    floor = 0.01 * float(np.abs(y).max())
    shapes = list(shapes)
    for i, (s, se, rms) in enumerate(shapes):
        if not isinstance(s, Disk):
            continue
        best = None
        for off in np.linspace(-1.0, 1.0, 9) * dr:
            trial = [t for t, _, _ in shapes]
            trial[i] = dataclasses.replace(s, radius=s.radius + off)
            try:
                kernel = coating_kernel(_scene(trial), ladar, radiometry=radiometry,
                                        samples=min(samples, 2048))
            except Exception:                      # noqa: BLE001 (a degenerate trial)
                continue
            start = _start(kernel, y)
            pred = kernel.predict([start[j] for j in range(len(trial))])
            chi = float(np.sum((y - pred) ** 2 / (np.abs(pred) + floor)))
            if best is None or chi < best[0]:
                best = (chi, trial[i])
        shapes[i] = (best[1], se, rms)
    return shapes


def _scene(shapes):
    """A Scene of the shapes, disks that overlap by a sliver (fitted shapes that touch in
    truth) shrunk to touching."""

    shapes = list(shapes)
    for i in range(len(shapes)):
        for j in range(i + 1, len(shapes)):
            a, b = shapes[i], shapes[j]
            if isinstance(a, Disk) and isinstance(b, Disk):
                gap = math.dist(a.center, b.center) - a.radius - b.radius
                if gap < 0:
                    cut = 0.5 * (-gap) * (1 + 1e-9) + 1e-12
                    shapes[i] = a = dataclasses.replace(a, radius=a.radius - cut)
                    shapes[j] = dataclasses.replace(b, radius=b.radius - cut)
    return Scene(shapes)


def _moved(shape, field_, by):
    if field_ == "cx":
        return dataclasses.replace(shape, center=(shape.center[0] + by, shape.center[1]))
    if field_ == "cy":
        return dataclasses.replace(shape, center=(shape.center[0], shape.center[1] + by))
    if field_ == "r":
        return dataclasses.replace(shape, radius=shape.radius + by)
    if field_ in ("A", "B"):
        a, b = shape.semi_axes
        return dataclasses.replace(shape, semi_axes=(a + by, b) if field_ == "A" else
                                   (a, b + by))
    return dataclasses.replace(shape, angle_deg=shape.angle_deg + math.degrees(by))
