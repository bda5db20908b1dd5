"""Laser radar cross sections: σ = 4π × the power returned toward the receiver per unit
solid angle per unit incident irradiance (m², scene units squared).

With a plane wave of unit irradiance along −w, the received-power radiometry's bin
integrals ∫ F cos θᵢ cos θᵣ dA are exactly the radiant intensity (power per steradian)
toward the receiver, so σ = 4π Σₖ P[k] and the range-resolved profile 4π P[k] sums to it.
A Lambertian sphere of albedo ρ and radius R gives (8/3)πρR², a Lambertian plate of area A
at incidence θ gives 4ρA cos²θ (both tested). Analytic (2-D) scenes give σ per unit
height (the extruded target's, m² per metre). ``bounces`` counts as for
:func:`meshladar.simulate`; a convex scene's σ is exactly single-bounce.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, replace

import numpy as np

from .._validate import check_choice, check_count, unit_vectors
from ..brdf import Lambertian
from ..errors import MeshladarWarning, ParameterError, user_stacklevel
from ..ladar import Ladar
from ..meshes import MeshPart
from ..plotting import plot
from ..scene import Scene
from ..sinogram import Sinogram
from . import simulate
from .orders import MAX_BOUNCE_SAMPLES, MAX_BOUNCES, check_bounces

__all__ = ["CrossSection", "LRCS_BINS", "CONVENTION", "STDERR_SHARE", "lrcs"]

#: Range bins of the profile by default.
LRCS_BINS = 256
#: A σ whose standard error (its sampled orders') exceeds this share of it is warned of.
STDERR_SHARE = 0.05
#: The convention every cross section states.
CONVENTION = ("sigma = 4 pi x power toward the receiver per unit solid angle per unit "
              "incident irradiance (received-power radiometry, plane wave, far field)")


@dataclass(frozen=True)
class CrossSection:
    """Laser radar cross sections per view (module docstring).

    Attributes
    ----------
    values : (n_views,) numpy.ndarray
        σ per view, in scene units squared (per unit height for a 2-D scene).
    per_part : (n_views, n_parts) numpy.ndarray or None
        Each part's (or shape's) share, when asked for: its single bounce (the other parts
        shadow it but reflect nothing), plus the orders beyond the first whose paths leave
        from it toward the receiver; the shares sum to ``values``.
    profile : Sinogram
        The range-resolved cross section 4π P[k] per view and bin; it sums to ``values``.
    names : tuple of str
        The parts' names (the columns of ``per_part``).
    bounces : int
        The orders summed.
    units : str
        ``"unit^2"`` (the scene's length unit squared: m² for a scene in metres, mm² for
        one in millimetres) or ``"unit^2 per unit height"`` (2-D scenes).
    convention : str
        :data:`CONVENTION`, then the geometry's: a mesh's normals (flat or smooth) and
        faces (two-sided: lit from either side, or one-sided), or a 2-D scene's exact
        shapes; and geometric optics (no diffraction: a mirror plate's σ is 4π F(0) A,
        its coating's peak, not the 4π A²/λ² of physical optics).
    stderr : (n_views,) numpy.ndarray
        The standard error of each σ from the sampled orders beyond the first (Monte
        Carlo paths; ``bounce_samples`` sets their number): 0 where only the exact single
        bounce is summed.
    """

    values: np.ndarray
    per_part: np.ndarray | None
    profile: Sinogram
    names: tuple
    bounces: int
    units: str
    convention: str = CONVENTION
    stderr: np.ndarray | None = None

    def plot(self, *, floor_db=60.0):
        """The signature over the views and the brightest view's range-resolved cross
        section (:func:`meshladar.viz.lrcs.signature`, through :mod:`meshladar.plotting`).

        Parameters
        ----------
        floor_db : float
            Decibels below the largest σ where the scale stops. Keyword-only.

        Returns
        -------
        matplotlib.figure.Figure
            The figure.
        """
        return plot(self, floor_db=floor_db)

    @property
    def dbsm(self) -> np.ndarray:
        """σ in dB relative to one square scene unit (dBsm for a scene in metres), −inf
        where 0."""
        with np.errstate(divide="ignore"):
            return 10.0 * np.log10(self.values)


def _ladar(scene, views, bounces, n_bins, bistatic):
    """A ladar over ``views`` whose bins hold every return up to ``bounces`` orders (and,
    ``bistatic``, every point's range (−p·(w + w_r)/2) for any receiver: the span widened
    by the scene's size on each side)."""
    try:
        v = np.asarray(views, dtype=np.float64)
    except (TypeError, ValueError):
        raise ParameterError(f"views must be angles in degrees (n,) or view vectors (n, 3); "
                             f"got {views!r}") from None
    if v.size == 0:
        raise ParameterError("views must hold at least one view; got none")
    if v.ndim == 2:
        w = unit_vectors("views", v)
        kw = {"view_vectors": w}
    elif v.ndim == 1:
        if not np.all(np.isfinite(v)):
            raise ParameterError(f"views (angles in degrees) must be finite; got {views!r}")
        w = np.stack([np.cos(np.radians(v)), np.sin(np.radians(v)), np.zeros_like(v)], 1)
        kw = {"angles_deg": v}
    else:
        raise ParameterError(f"views must be angles in degrees (n,) or view vectors (n, 3); "
                             f"got shape {v.shape}")
    lo, hi = scene.view_ranges(w)
    top = 1 if bounces == "auto" and not scene.visibility().needs_bounces else (
        MAX_BOUNCES if bounces == "auto" else bounces)
    # a k-bounce path's apparent range is at most the farthest range plus (k − 1) D / 2;
    # a bistatic one's within D of the monostatic span
    reach = _diameter(scene)
    if bistatic:
        lo, hi = lo - reach, hi + reach
    size = float(np.max(hi - lo))
    a, b = float(lo.min()), float(hi.max()) + 0.5 * (top - 1) * reach
    # at least D / 2 across (a sphere's depth): a flat plate seen face-on spans no range
    # at all, and bins of its width (1e-312) gave an infinite ray count
    grow = max(0.0, 0.5 * (0.5 * reach - (b - a)))
    a, b = a - grow, b + grow
    pad = max(0.5 * (b - a) / n_bins, 1e-9 * max(abs(a), abs(b), size, 1e-300))
    edges = np.linspace(a - pad, b + pad, n_bins + 1)
    return Ladar(kw.get("angles_deg"), view_vectors=kw.get("view_vectors"), bin_edges=edges)


def _convention(scene, model, sino, options):
    """:data:`CONVENTION` and the geometry's (:class:`CrossSection`)."""
    if model == "mesh":
        faces = {"ignore": "one-sided"}.get(options.get("back_faces"), "two-sided")
        shape = f"{sino.info.get('normals', 'flat')} normals, {faces} faces"
    else:
        shape = "exact shapes" if model == "analytic" else "rasterised shapes"
    return f"{CONVENTION}; {shape}; geometric optics (no diffraction)"


def _check_stderr(values, stderr, samples):
    """Warn where a σ's standard error passes :data:`STDERR_SHARE` of it, with the
    bounce_samples that would bring the worst view's within it (the error falls as
    1/√N)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        share = np.where(values > 0, stderr / values, 0.0)
    worst = int(np.argmax(share))
    if share[worst] > STDERR_SHARE:
        need = min(int(np.ceil(samples * (share[worst] / STDERR_SHARE) ** 2)),
                   MAX_BOUNCE_SAMPLES)
        then = share[worst] * np.sqrt(samples / need)
        warnings.warn(f"the sampled orders beyond the first leave sigma uncertain: a "
                      f"standard error of {100 * share[worst]:.3g} % in view {worst} "
                      f"({samples} paths a view and order); bounce_samples={need} brings it "
                      f"to {100 * then:.2g} %", MeshladarWarning,
                      stacklevel=user_stacklevel())


def _default_spacing(scene, n_bins, options):
    """A mesh scene's ``ray_spacing`` into ``options`` unless it, ``rays_per_bin`` or
    ``tol`` is given (or the mode is a slice): R / max(``n_bins``, :data:`LRCS_BINS`), R
    the largest distance of a vertex from the bounding box's centre (fewer bins, for σ
    alone, keep the default's rays: at R / 1 a sphere read 1.52 of its σ)."""
    if scene.is_mesh and options.get("mode", "3d") == "3d" and all(
            options.get(k) is None for k in ("ray_spacing", "rays_per_bin", "tol")):
        pts = scene.hull_points()
        centre = 0.5 * (pts.min(axis=0) + pts.max(axis=0))
        options["ray_spacing"] = float(np.max(np.linalg.norm(pts - centre, axis=1))
                                       / max(n_bins, LRCS_BINS))


def _shares(scene, ladar, model, sino, options, n_parts):
    """Each part's σ per view (n_views, n_parts): its single bounce with the others black,
    plus the orders beyond the first that leave from it (``sino``'s)."""
    single = {**options, "bounces": 1} if model == "mesh" else options
    with warnings.catch_warnings():      # a part's run (the others black) would say again
        warnings.simplefilter("ignore", MeshladarWarning)       # what the whole scene's did
        shares = np.stack([4.0 * np.pi * simulate(_alone(scene, i), ladar, model=model,
                                                  radiometry="power", **single)
                           .values.sum(axis=1) for i in range(n_parts)], axis=1)
    if "bounce_part_totals" in sino.info:
        shares = shares + 4.0 * np.pi * np.asarray(sino.info["bounce_part_totals"])
    return shares


def _diameter(scene):
    """The scene's diameter D: its hull's bounding box diagonal (a mesh's), or its bounding
    circle's (2-D shapes)."""
    if scene.is_mesh:
        return float(np.linalg.norm(np.ptp(scene.hull_points(), axis=0)))
    return 2.0 * scene.bounding_circle()[1]


def _alone(scene, i):
    """``scene`` with every part (or shape) but the i-th made black (Lambertian 0)."""
    black = Lambertian(0.0, name="black")
    if not scene.is_mesh:
        return Scene([s if j == i else replace(s, material=black)
                      for j, s in enumerate(scene.shapes)])
    n = len(scene.materials)
    parts = [p if j == i else MeshPart(p.vertices, p.faces, n, p.name, p.exact_normal)
             for j, p in enumerate(scene.parts)]
    return Scene.from_parts(parts, [*scene.materials, black])


def lrcs(scene, views, *, model=None, bounces=1, per_part=False, n_bins=LRCS_BINS,
         **options) -> CrossSection:
    """Laser radar cross sections of ``scene`` from ``views`` (module docstring).

    Parameters
    ----------
    scene : Scene
        Analytic shapes (σ per unit height) or meshes.
    views : (n,) or (n, 3) array_like
        View angles about z in degrees, or view vectors w (toward the ladar; normalised).
    model : {"analytic", "mesh", "pixel"}, optional
        The forward model; default "analytic" for analytic shapes, "mesh" for meshes.
    bounces : int or "auto"
        Orders of bounces, as :func:`meshladar.simulate` (mesh model).
    per_part : bool
        Also each part's share (:class:`CrossSection`).
    n_bins : int
        Range bins of the profile (default :data:`LRCS_BINS`), spanning the scene's
        ranges over the views (and the longer paths of higher orders).
    **options
        The model's other options (``ray_spacing``, ``tol``, ``receiver`` for a bistatic
        σ, ``seed``, …); not ``radiometry`` (always ``"power"``) or ``sensor``. A mesh's
        ``ray_spacing``, unless it, ``rays_per_bin`` or ``tol`` is given, is R /
        max(``n_bins``, 256), R the largest distance of a vertex from its bounding box's
        centre (a sphere's range depth over the bins): the same for every view and every
        ``bounces`` (a flat plate seen face-on, which spans no range, included).

    Returns
    -------
    CrossSection
        ``values`` (n,) σ, ``profile``, ``per_part``, ``units``, ``convention``.

    Raises
    ------
    ParameterError
        For a ``radiometry`` or ``sensor`` option, bad ``views``, ``per_part`` or
        ``n_bins``; and whatever :func:`meshladar.simulate` refuses, before any ray.

    Examples
    --------
    >>> import numpy as np, meshladar as ml
    >>> ball = ml.Scene.from_parts([ml.meshes.sphere((0, 0, 0), 1.0, 0, subdivisions=5)],
    ...                            [ml.brdf.Lambertian(0.5)])
    >>> s = ml.lrcs(ball, [0.0], ray_spacing=2e-3)
    >>> round(float(s.values[0] / (8 / 3 * np.pi * 0.5)), 3)      # (8/3) pi rho R^2
    1.0
    """
    if not isinstance(scene, Scene):
        raise ParameterError(f"scene must be a meshladar.Scene; got {type(scene).__name__}")
    for name in ("radiometry", "sensor"):
        if name in options:
            raise ParameterError(f"lrcs takes no {name} option: a cross section is the "
                                 "received power per unit irradiance, in the far field")
    model = check_choice("model", model or ("mesh" if scene.is_mesh else "analytic"),
                         ("analytic", "mesh", "pixel"))
    n_bins = check_count("n_bins", n_bins)
    if per_part not in (True, False):
        raise ParameterError(f"per_part must be True or False; got {per_part!r}")
    check_bounces(scene, bounces, options.get("bounce_samples"),
                  {**options, "radiometry": "power"})
    ladar = _ladar(scene, views, bounces, n_bins, options.get("receiver") is not None)
    if model == "mesh":
        options["bounces"] = bounces
        _default_spacing(scene, n_bins, options)
    elif bounces != 1:
        raise ParameterError(f"bounces > 1 needs model='mesh'; got model={model!r}")
    sino = simulate(scene, ladar, model=model, radiometry="power", **options)
    profile = replace(sino, values=4.0 * np.pi * sino.values,
                      info=dict(sino.info, quantity="laser radar cross section"))
    names = tuple(p.name for p in scene.parts) if scene.is_mesh else tuple(
        s.name or f"shape {i}" for i, s in enumerate(scene.shapes))
    shares = _shares(scene, ladar, model, sino, options, len(names)) if per_part else None
    units = "unit^2" if scene.is_mesh or model == "mesh" and options.get("mode") == "3d" \
        else "unit^2 per unit height"
    stderr = 4.0 * np.pi * np.asarray(sino.info.get("view_stderr", np.zeros(ladar.n_views)))
    _check_stderr(profile.values.sum(axis=1), stderr, sino.info.get("bounce_samples"))
    return CrossSection(profile.values.sum(axis=1), shares, profile, names,
                        int(sino.info.get("bounces", 1)), units,
                        _convention(scene, model, sino, options), stderr)
