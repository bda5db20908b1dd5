"""Whether a mesh run's rays resolve each coating's specular lobe, decided before the first
ray (:func:`unresolved_lobes`, warned by :func:`warn_unresolved_lobes`).

A glint narrower than the ray spacing resolves is missed without a word otherwise: the
rays sample the shading normal at points δ apart, so where it turns at κ radians per unit
length neighbouring rays see normals κδ apart, and a lobe of half-width w
(:meth:`meshladar.brdf.BRDF.lobe_width`) spans 2w/(κδ) rays. The criterion asks
:data:`RAYS_ACROSS_LOBE` rays across it (2 on a regular grid, 4 stratified), which the
spacing δ* = 2w / (rays · κ) meets.

κ is the rate at which the normal the engine shades with turns (smooth: the interpolated
corner normals; exact: the part's own): per face, the largest rate in any direction (in a
slice, along the row of rays); a part's κ is what its most-curved 5 % of curved area
reaches (an area-weighted quantile, so a sliver does not decide).

Flat normals: each face's normal is constant. Where a part is curved (its faces meet at
less than the crease angle :data:`~meshladar.meshes.CREASE_DEG`) and its faces' normals
step by more than the lobe's full width 2w from face to face (:func:`faceted_lobes`), some
views find no face inside the lobe: the glints come from single facets, not from the
curved surface the mesh may approximate (a GGX α = 1e-4 on an icosphere of 2,562 points
returns ~1e-5 of the sphere's closed form at any spacing). The step is the median angle
over a part's curved edges; the fix is ``normals="smooth"`` (or "exact" for tessellated
shapes), or a mesh whose faces step by less than 2w. Where they step by less, the glint
comes from the few facets inside the lobe, a strip 2w/κ wide, which the rays must still
find: the criterion above holds with κ the rate the faces' own normals turn across the
part's curved edges (:func:`~meshladar.meshes.curved_edge_rates`; the most-turning 5 % of
edges), asking two rays across the lobe whatever the sampling (they find its facets; the
error left is each facet's area counted in rays: 3-13 % at two on a 1024-gon's glint).
Unchecked, a 1024-gon aluminium disk of radius 0.4 traced at 0.02 returned 4-6 % of its
total without a word.
"""

from __future__ import annotations

import contextlib
import contextvars
import math
import warnings
from types import MappingProxyType
from typing import NamedTuple

import numpy as np

from ..errors import LobeSamplingWarning, user_stacklevel
from ..meshes.normals import curved_edge_rates
from ..raytrace.embree import geometry
from ..raytrace.grid import MAX_RAYS_PER_VIEW

__all__ = ["RAYS_ACROSS_LOBE", "Unresolved", "Faceted", "normal_turn", "unresolved_lobes",
           "faceted_lobes", "warn_unresolved_lobes", "checked_by_caller"]

#: Rays the criterion asks across a lobe's full width 2w, per sampling: cell centres are
#: a midpoint rule (measured 1.7 % at 2 rays, 4 % at 1.8, 34 % at 1); stratified offsets
#: are unbiased but noisy (3-D: 2–3 % rms at 4 rays, 6–8 % at 2).
RAYS_ACROSS_LOBE = MappingProxyType({"regular": 2.0, "stratified": 4.0})
_TINY = 1e-300
#: Faces per part and coating the curvature is estimated from (evenly strided beyond).
_MAX_FACES = 1 << 17
#: True inside :func:`checked_by_caller`.
_CALLER_CHECKS = contextvars.ContextVar("meshladar_lobes_checked_by_caller", default=False)
#: The share of a part's curved area whose curvature decides (the most curved 5 %).
_CURVED_SHARE = 0.05


class Unresolved(NamedTuple):
    """One part and coating whose specular lobe the run's rays do not resolve.

    Attributes
    ----------
    part : str
        The part's name.
    coating : str
        The coating's name (its class name when it has none).
    width : float
        The lobe's half-width w (radians).
    turn : float
        κδ, the shading normal's change between neighbouring rays (radians).
    spacing : float
        The spacing δ* = 2w / (``needed`` · κ) that resolves it, rounded down to three
        significant digits (scene units).
    needed : float
        Rays the criterion asks across the lobe's full width (:data:`RAYS_ACROSS_LOBE`
        for the sampling).
    rays_per_view : float
        Rays one view needs at that spacing over the whole target: the bounding box's
        diagonal over the spacing, squared in 3-D.
    """

    part: str
    coating: str
    width: float          # the lobe's half-width w, radians
    turn: float           # the normal's change between neighbouring rays κδ, radians
    spacing: float        # the spacing δ* that resolves it (RAYS_ACROSS_LOBE rays)
    needed: float         # rays the criterion asks across the lobe (per sampling)
    rays_per_view: float  # rays one view needs at δ* over the whole target


class Faceted(NamedTuple):
    """One curved part and coating whose faces' normals step wider than the lobe.

    Attributes
    ----------
    part : str
        The part's name.
    coating : str
        The coating's name (its class name when it has none).
    width : float
        The lobe's half-width w (radians).
    step : float
        The median angle between neighbouring faces' normals over the part's curved
        edges (radians); it exceeds 2w.
    """

    part: str
    coating: str
    width: float          # the lobe's half-width w, radians
    step: float           # the median angle between neighbouring faces' normals, radians


def normal_turn(v, n, face_normals, mode):
    """κ per face (m,): the rate, in radians per unit length, at which the normal turns
    across each face, from its value n (m, 3, 3) at three points v (m, 3, 3) of the face,
    linearly between them. In 3-D the largest rate in any direction of the face's plane;
    in a slice the rate along the face's horizontal direction (the one the row of rays
    moves in; 0 on a horizontal face). 0 on degenerate faces. Dot products only, so a
    million faces take a fraction of a second.

    Parameters
    ----------
    v : (m, 3, 3) float64
        Three points of each face (its corners, or points inside it), scene coordinates.
    n : (m, 3, 3) float64
        The shading normal at each of those points.
    face_normals : (m, 3) float64
        Each face's unit normal; read in slice mode only.
    mode : {"3d", "slice"}
        ``"slice"``: the rate along the face's horizontal direction; any other value: the
        largest rate over the face's plane (3-D).

    Returns
    -------
    (m,) float64
        κ per face, radians per unit length (0 where the face is degenerate: its edges'
        Gram determinant at most 1e-24 of the product of their squared lengths).
    """
    d1, d2 = v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]
    g1, g2 = n[:, 1] - n[:, 0], n[:, 2] - n[:, 0]

    def dot(a, b):
        return np.einsum("ij,ij->i", a, b)

    m11, m12, m22 = dot(d1, d1), dot(d1, d2), dot(d2, d2)          # the edges' Gram matrix
    det_m = m11 * m22 - m12 * m12
    ok = det_m > 1e-24 * np.maximum(m11 * m22, _TINY)
    det_m = np.where(ok, det_m, 1.0)
    if mode == "slice":
        # t = z × n_face, horizontal in the face's plane: t = α d1 + β d2 (M [α, β] = D t)
        t = np.cross([0.0, 0.0, 1.0], face_normals)
        a1, a2 = dot(d1, t), dot(d2, t)
        alpha, beta = (m22 * a1 - m12 * a2) / det_m, (m11 * a2 - m12 * a1) / det_m
        turned = np.linalg.norm(alpha[:, None] * g1 + beta[:, None] * g2, axis=1)
        tn = np.linalg.norm(t, axis=1)
        rate = np.where(tn > 1e-12, turned / np.maximum(tn, _TINY), 0.0)
    else:
        # the largest λ of det(A − λM) = 0, A the normal differences' Gram matrix: the
        # squared largest turning rate over the face's directions
        a11, a12, a22 = dot(g1, g1), dot(g1, g2), dot(g2, g2)
        b = a11 * m22 + a22 * m11 - 2.0 * a12 * m12
        disc = np.maximum(b * b - 4.0 * det_m * (a11 * a22 - a12 * a12), 0.0)
        rate = np.sqrt(np.maximum((b + np.sqrt(disc)) / (2.0 * det_m), 0.0))
    return np.where(ok, rate, 0.0)


def _curved_quantile(values, area):
    """The value the top :data:`_CURVED_SHARE` of the curved area (values > 0) reaches."""
    curved = values > 0
    if not curved.any():
        return 0.0
    x, a = values[curved], area[curved]
    order = np.argsort(x)[::-1]
    reach = np.cumsum(a[order])
    k = int(np.searchsorted(reach, _CURVED_SHARE * reach[-1]))
    return float(x[order][min(k, x.size - 1)])


def _turns(scene, normals, mode):
    """{(part, material index): κ} of a scene, computed once per scene, normals and mode
    (smooth: the traced geometry's own corner normals, which the run has built), from at
    most :data:`_MAX_FACES` evenly strided faces of each part and material; flat: the
    rate the faces' own normals turn across the part's curved edges (:func:`_face_steps`)."""
    if normals == "flat":
        return {key: rate for key, (_, rate) in _face_steps(scene).items()}
    return scene.cached(("lobe turns", normals, mode),
                        lambda: _part_turns(scene, normals, mode))


def _part_turns(scene, normals, mode):
    geo = geometry(scene, normals)
    key = geo.part_of.astype(np.int64) * (int(geo.material.max()) + 1) + geo.material
    out = {}
    for first in np.unique(key, return_index=True)[1]:
        faces = np.flatnonzero(key == key[first])
        faces = faces[::-(-faces.size // _MAX_FACES)]
        out[int(geo.part_of[first]), int(geo.material[first])] = _curved_quantile(
            *_face_rates(scene, geo, faces, normals, mode))
    return out


def _face_rates(scene, geo, faces, normals, mode):
    """(κ, area) of the geometry's ``faces`` (indices)."""
    v = geo.vertices[geo.faces[faces]]
    if normals == "exact":
        c = v.mean(axis=1, keepdims=True)
        v = c + 0.5 * (v - c)                 # inside the face: a prism's caps share corners
        n = scene.parts[int(geo.part_of[faces[0]])].exact_normal(
            v.reshape(-1, 3)).reshape(v.shape)
    else:
        n = geo.corner[faces]
    area = 0.5 * np.linalg.norm(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1)
    return normal_turn(v, n, geo.face_normals[faces], mode), area


def unresolved_lobes(scene, materials, *, spacing, normals="smooth", mode="3d",
                     sampling="stratified"):
    """The parts and coatings whose specular lobe a mesh run does not resolve with rays
    ``spacing`` apart, shading ``normals``, in ``mode`` ("3d" or "slice") with ``sampling``
    ("regular" or "stratified"): :class:`Unresolved` records, empty when every lobe is
    resolved or no coating states a lobe width (diffuse coatings, a user's model without
    ``lobe_width``); with flat normals a part whose faces step wider than the lobe is left
    to :func:`faceted_lobes`. Nothing is traced; the per-face rates are computed once per
    scene, normals and mode.

    A lobe of half-width w on a part whose normal turns at κ (module docstring) is
    resolved when 2w / (κ · spacing) is at least ``RAYS_ACROSS_LOBE[sampling]`` (with flat
    normals, ``RAYS_ACROSS_LOBE["regular"]``).

    Parameters
    ----------
    scene : Scene
        A mesh scene (its parts, and the traced geometry for ``normals``).
    materials : sequence of BRDF
        One coating per material index of the scene; a coating without a finite, positive
        ``lobe_width()`` is not checked.
    spacing : float
        The run's ray spacing δ (scene units), > 0 (not checked).
    normals : {"smooth", "exact", "flat"}, optional
        The shading normals (default ``"smooth"``).
    mode : {"3d", "slice"}, optional
        Default ``"3d"``.
    sampling : {"stratified", "regular"}, optional
        Default ``"stratified"``; picks the rays asked across a lobe.

    Returns
    -------
    list of Unresolved
        One per part and material index whose lobe is not resolved, by part, then
        material index.

    Raises
    ------
    KeyError
        If ``sampling`` is not a key of :data:`RAYS_ACROSS_LOBE` (only when the normals are
        not flat and some coating states a lobe width).
    """
    widths = [_lobe_width(m) for m in materials]
    if all(w is None for w in widths):
        return []                                          # no lobe: nothing to check
    need = RAYS_ACROSS_LOBE["regular" if normals == "flat" else sampling]
    out = []
    for (k, m), kappa in _turns(scene, normals, mode).items():
        w = widths[m] if m < len(widths) else None
        if w is None or kappa <= 0 or 2.0 * w / (kappa * spacing) >= need * (1 - 1e-9):
            continue
        if normals == "flat" and _face_steps(scene)[k, m][0] > 2.0 * w:
            continue                              # single facets glint (faceted_lobes)
        good = _floor3(2.0 * w / (need * kappa))     # as printed, and at most δ*
        across = _diameter(scene) / good
        out.append(Unresolved(scene.parts[k].name, _label(materials[m]), float(w),
                              float(kappa * spacing), float(good), need,
                              float(across if mode == "slice" else across * across)))
    return out


def faceted_lobes(scene, materials):
    """The curved parts and coatings whose faces' normals step from face to face by more
    than the lobe's full width 2w (:class:`Faceted` records; empty for flat-faced
    polyhedra, diffuse coatings and fine meshes). With flat normals their glints come from
    single facets. Nothing is traced; the steps are computed once per scene.

    Parameters
    ----------
    scene : Scene
        A mesh scene.
    materials : sequence of BRDF
        One coating per material index of the scene; a coating without a finite, positive
        ``lobe_width()`` is not checked.

    Returns
    -------
    list of Faceted
        One per curved part and material index whose median normal step exceeds 2w, by
        part, then material index.
    """
    widths = [_lobe_width(m) for m in materials]
    if all(w is None for w in widths):
        return []
    out = []
    for (k, m), (step, _) in _face_steps(scene).items():
        w = widths[m] if m < len(widths) else None
        if w is not None and step > 2.0 * w:
            out.append(Faceted(scene.parts[k].name, _label(materials[m]), float(w),
                               float(step)))
    return out


def _face_steps(scene):
    """{(part, material index): (median angle between the normals of neighbouring faces,
    the rate their flat normals turn that the most-turning :data:`_CURVED_SHARE` of edges
    reach) over the part's curved edges (:func:`~meshladar.meshes.curved_edge_rates`)},
    for parts that have any; computed once per scene."""
    return scene.cached("face steps", lambda: _part_face_steps(scene))


def _part_face_steps(scene):
    out = {}
    for k, part in enumerate(scene.parts):
        angle, rate, mats = curved_edge_rates(part)
        for m in np.unique(mats):
            mine = mats == m
            out[k, int(m)] = (float(np.median(angle[mine])),
                              float(np.quantile(rate[mine], 1.0 - _CURVED_SHARE)))
    return out


def _floor3(x):
    """x rounded down to three significant digits (so the spacing printed meets δ*)."""
    p = 10.0 ** (math.floor(math.log10(x)) - 2)
    return math.floor(x / p * (1 + 1e-12)) * p


def _diameter(scene):
    """The scene's bounding-box diagonal (the grids' extent, to within √3)."""
    lo = np.min([p.vertices.min(axis=0) for p in scene.parts], axis=0)
    hi = np.max([p.vertices.max(axis=0) for p in scene.parts], axis=0)
    return float(np.linalg.norm(hi - lo))


def _lobe_width(m):
    """The coating's lobe half-width, or None (a user's model without ``lobe_width``)."""
    f = getattr(m, "lobe_width", None)
    w = f() if callable(f) else None
    return float(w) if w is not None and np.isfinite(w) and w > 0 else None


def _label(m):
    return m.name or type(m).__name__


def warn_unresolved_lobes(scene, materials, *, spacing, normals, mode, sampling):
    """One :class:`~meshladar.errors.LobeSamplingWarning` per part and coating that
    :func:`unresolved_lobes` finds, naming the lobe width, the normal change per ray and
    the spacing that resolves it; nothing inside :func:`checked_by_caller`.

    With flat normals it warns as well once per record of :func:`faceted_lobes` (faces
    that step wider than the lobe), naming the fix.

    Parameters
    ----------
    scene : Scene
        A mesh scene.
    materials : sequence of BRDF
        One coating per material index of the scene.
    spacing : float
        The run's ray spacing (scene units).
    normals : {"flat", "smooth", "exact"}
        The run's shading normals.
    mode : {"3d", "slice"}
        The run's mode.
    sampling : {"regular", "stratified"}
        The run's sampling.

    Warns
    -----
    LobeSamplingWarning
        One per part and coating found, at the user's call site.
    """
    if _CALLER_CHECKS.get():
        return
    if normals == "flat":
        for f in faceted_lobes(scene, materials):
            warnings.warn(_faceted_message(f), LobeSamplingWarning, stacklevel=user_stacklevel())
    for u in unresolved_lobes(scene, materials, spacing=spacing, normals=normals, mode=mode,
                              sampling=sampling):
        warnings.warn(_message(u, spacing), LobeSamplingWarning, stacklevel=user_stacklevel())


@contextlib.contextmanager
def checked_by_caller():
    """Within it, :func:`warn_unresolved_lobes` says nothing: for a caller that runs the
    mesh model several times and checks only the run it keeps (the ``tol`` knob's coarse
    runs are undersampled on purpose). Per thread and task (a context variable).

    Yields
    ------
    None
        The previous setting is restored on exit, also when the block raises.
    """
    token = _CALLER_CHECKS.set(True)
    try:
        yield
    finally:
        _CALLER_CHECKS.reset(token)


def _message(u, spacing):
    fix = f"ray_spacing={u.spacing:.3g} puts {u.needed:g} rays across it"
    if u.rays_per_view > MAX_RAYS_PER_VIEW:
        fix += (f" (about {u.rays_per_view:.2g} rays per view over the target, past the "
                f"{MAX_RAYS_PER_VIEW:.0e} a view may hold: simulate the glinting region "
                "alone, or expect the glint to be undersampled)")
    return (f"part {u.part!r}: the specular lobe of {u.coating} is {u.width:.3g} rad wide "
            f"(half-width) but the normal turns by {u.turn:.3g} rad between neighbouring "
            f"rays (ray_spacing {spacing:.3g}): {2 * u.width / u.turn:.2g} rays across the "
            f"lobe, fewer than {u.needed:g}, so the glint is undersampled (its return comes "
            f"out low or noisy); {fix}")


def _faceted_message(f):
    return (f"part {f.part!r}: with flat normals its faces' normals step by {f.step:.3g} rad "
            f"from face to face where it is curved (median), wider than the specular lobe of "
            f"{f.coating} ({2 * f.width:.3g} rad across): its glints come from single "
            "facets, not from the curved surface the mesh approximates; use "
            "normals='smooth' (or 'exact' for tessellated shapes), a mesh whose faces step "
            f"by less than {2 * f.width:.3g} rad, or keep the facets if they are the object")
