"""Light after more than one bounce: orders 2, 3, … of a mesh scene's returns (monostatic,
or with bistatic receivers), by Monte Carlo path sampling with next-event estimation toward
the receiver.

A path enters along a view's ray (−w), meets the scene at x₁, leaves in a sampled
direction ω₁, meets x₂, …, and at each vertex x_k (k ≥ 2) is joined to the receiver (at
infinity along w) by a shadow ray: the order-k return. Per unit incident irradiance, the
order-2 intensity toward the receiver is

    I₂ = ∫∫ F₁(w, ω) cos θ₁ · F₂(−ω, w) · cos θ₁ₒ cos θ₂ᵢ / r² · cos θ₂ᵣ · V dA₁ dA₂

in the received-power radiometry (under the paper's Eq. 8, one cosine fewer, the last
vertex weighs F₂ without cos θ₂ᵣ, as the single bounce's bistatic weight does; an SR
coating's F grows as 1/cos θ₂ᵣ toward an edge-on exit, warned as there),
sampled per first hit as δA⊥ · F₁ cos θ₁ₒ / p(ω) · F₂ cos θ₂ᵣ · V, with δA⊥ the ray's
cross-section and p the density of the sampled direction. Higher orders multiply in one
factor F cos θ / p per vertex. Each return is binned at its apparent range, half the
total optical path: (r(x₁) + L − x_k·w_r) / 2 with r(p) = −p·w, L the path's length from
x₁ to x_k and w_r the receiver's direction (w when monostatic). A sensor's beam weighs the
first hits, and a sensor at a finite standoff starts the paths on its own rays and ends
them at itself, with its receiver's solid angle and the atmosphere
(:mod:`.bounce_ends`).

Directions are sampled from a one-sample mixture (the density is the mixture's, so the
estimate is unbiased whichever branch drew; one compiled pass, :mod:`._bounce_kernels`): cosine-weighted about the normal, and, for a
coating with a specular lobe of width s (SR's e, GGX's α, Phong's √(2/(n + 2))), a half
vector drawn from the Beckmann distribution of width s about the normal, reflected about
it: narrow glints (e = 0.007) are sampled where they are. The bistatic weights are each
coating's own :meth:`~meshladar.brdf.BRDF.bistatic` (every built-in model; a user's model
without one is refused before any ray). Faces are two-sided: a vertex's normal is turned
toward the side the light arrives on.

The first hits are a view's regular ray grid at the main run's spacing (so every part the
single bounce sees is sampled), of which ``samples / BRANCHES`` are drawn at random with
replacement (their weight scaled by hits / drawn), each with :data:`BRANCHES` independent
paths. The standard error per bin is the spread of the drawn hits' totals over √draws.
Each vertex's hit distance is recomputed in float64 against its face's plane: Embree's
float32 distance leaves a hit ~1e-7 off its face, enough for its own shadow ray to hit
that face again (a bowl's second order came out 31 % low that way).
"""

from __future__ import annotations

from dataclasses import dataclass
import numpy as np

from .._lazy import deferred_module
from .._executors import thread_pool
from ..errors import ModelError, ParameterError
from ..raytrace.backends import resolve_backend
from ..raytrace.embree import embree_scene, geometry
from ._paths import (Leg, Paths, blocked, cast, dot, edge_on_glints, lobe_width,
                     warn_edge_on, weight)
from .bounce_ends import Ends, entries, to_receiver, view_ends
from .mesh import first_hits
from .mirrors import find_mirrors, through_mirrors

# compiled loops, imported (with numba) at their first use: a small run loads neither
_bounce_kernels = deferred_module("meshladar.forward._bounce_kernels")

__all__ = ["BRANCHES", "BOUNCE_SAMPLES", "Orders", "higher_orders", "check_bistatic", "walk",
           "single_bounce"]

#: Independent paths per drawn first hit.
BRANCHES = 8
#: Paths per view and order by default.
BOUNCE_SAMPLES = 1 << 15
#: Lobes at least this wide are sampled by the cosine alone.
_WIDE_LOBE = 0.5


@dataclass(frozen=True)
class Orders:
    """The orders of bounces beyond the first, per view and bin.

    Attributes
    ----------
    orders : tuple of int
        The orders held (2, 3, …).
    values : (n_orders, n_views, n_bins) numpy.ndarray
        Each order's bin integrals, in the single bounce's radiometry and units.
    stderr : (n_orders, n_views, n_bins) numpy.ndarray
        Their Monte Carlo standard errors (0 where no path was sampled: a convex scene).
    samples : int
        Paths per view and order.
    radiometry : str
        ``"power"`` or ``"paper"`` (module docstring).
    per_part : (n_orders, n_views, n_parts) numpy.ndarray or None
        Each order's total per part of the scene, by the part of each path's last surface
        (they sum to ``values`` over the bins).
    total_stderr : (2, n_orders, n_views) numpy.ndarray or None
        The standard errors of each view's total over the bins: [0, k] of order k + 2
        alone, [1, k] of orders 2..k + 2 together; from the spread of the first hits'
        totals (``stderr`` is per bin: a hit's paths reach several bins and orders, so
        their variances summed would leave out the covariance).
    """

    orders: tuple
    values: np.ndarray
    stderr: np.ndarray
    samples: int
    radiometry: str = "power"
    per_part: np.ndarray | None = None
    total_stderr: np.ndarray | None = None


def check_bistatic(materials):
    """Refuse, before any ray, a coating without a bistatic evaluation.

    Parameters
    ----------
    materials : sequence of BRDF
        The scene's coatings.

    Raises
    ------
    ModelError
        Naming the first coating whose :meth:`~meshladar.brdf.BRDF.bistatic` is the base class's.
    """
    for m in materials:
        try:
            m.bistatic(1.0, 0.0, 1.0, 0.0, 1.0, 0.0)
        except ModelError:
            raise ModelError(f"bounces > 1 needs each coating's bistatic evaluation; "
                             f"{type(m).__name__} has none (define bistatic())") from None


def _sample(n, wi, width, rng):
    """Directions (k, 3) from the mixture (module docstring) and their densities (k,), in
    one compiled pass (:mod:`._bounce_kernels`): cosine-weighted, sin θ = √u₁; the lobe's
    half vector, tan² θh = −s² ln(1 − u₁), reflected; the lobe taken with probability ½
    where a coating has one narrower than 0.5."""
    k = len(n)
    u1, u2, pick = rng.random(k), rng.random(k), rng.random(k)
    d, pdf = np.empty((k, 3)), np.empty(k)
    _bounce_kernels.sample_mixture(
        np.ascontiguousarray(n, np.float64), np.ascontiguousarray(wi, np.float64),
        np.ascontiguousarray(width, np.float64), u1, u2, pick, _WIDE_LOBE, d, pdf)
    return d, pdf


def _bin_stats(edges, ranges, values, path_id, draws):
    """Per bin: the sum of ``values`` at ``ranges`` and its variance, estimated from the
    spread of the ``draws`` first hits' totals (each hit drawn independently, its
    BRANCHES paths numbered ``path_id // BRANCHES``; a hit with no path in a bin counts
    as a zero there)."""
    k = len(edges) - 1
    b = np.searchsorted(edges, ranges, side="right") - 1
    keep = (b >= 0) & (b < k)
    b, v, hit = b[keep], values[keep], path_id[keep] // BRANCHES
    total = np.bincount(b, v, k)
    key, inverse = np.unique(hit * k + b, return_inverse=True)
    per_hit = np.bincount(inverse, v, len(key))
    squares = np.bincount(key % k, per_hit * per_hit, k)
    var = draws / max(draws - 1.0, 1.0) * np.maximum(squares - total * total / draws, 0.0)
    return total, var


def single_bounce(scene, geo, w, spacing, power=True):
    """A view's single bounce on a regular grid, monostatic, at infinity: (faces hit, each
    ray's F·cos θ·δA⊥, or F·δA⊥ where not ``power``), the first order :func:`walk`'s paths
    start from.

    Parameters
    ----------
    scene : Scene
        The mesh scene.
    geo :
        Its flat-normal geometry (:mod:`meshladar.raytrace.embree`).
    w : (3,) numpy.ndarray
        The unit view.
    spacing : float
        The grid's spacing.
    power : bool
        Received power (default) or the paper's Eq. 8.

    Returns
    -------
    faces : (k,) numpy.ndarray of int
        The global face of each ray's first hit.
    value : (k,) numpy.ndarray
        Each hit's value per unit irradiance.
    """
    _, f, _ = first_hits(scene, w, ray_spacing=spacing)
    n = geo.face_normals[f]
    n = n * np.sign(n @ w)[:, None]
    ww = np.broadcast_to(w, n.shape)
    return f, spacing * spacing * weight(scene.materials, geo.material[f], n, ww, ww, power)


def walk(scene, geo, emb, w, spacing, plan, rng, trail=None):
    """A view's sampled paths (module docstring), one leg per order 2..n as they are built.

    Parameters
    ----------
    scene : Scene
        The mesh scene.
    geo, emb :
        Its flat-normal geometry and Embree scene (:mod:`meshladar.raytrace.embree`).
    w : (3,) numpy.ndarray or tuple or Ends
        The view, (view, receiver) for a bistatic receiver, or the view's
        :class:`~meshladar.forward.bounce_ends.Ends` (a sensor, the radiometry).
    spacing : float
        The first hits' grid spacing.
    plan : (int, int)
        (bounces, samples): max(2, samples // BRANCHES) first hits are drawn.
    rng : numpy.random.Generator
        The sampling's generator.
    trail : list, optional
        Receives each vertex's (path numbers, points), x₁ first, to draw the paths.

    Yields
    ------
    Leg
        Per order 2..bounces: the face each return leaves from toward the receiver, the
        point, its value per unit irradiance (in the ends' radiometry), apparent range and
        path number. Nothing for a view that meets nothing.
    """
    bounces, samples = plan
    ends = w if isinstance(w, Ends) else view_ends(*((w,) if np.ndim(w) == 1 else w))
    paths = _start(scene, geo, emb, ends, spacing, (samples, rng))
    if paths is None:
        return
    mirrors = find_mirrors(scene, geo)
    pending = {}
    if trail is not None:
        trail.append((paths.ident, paths.x))
    widths = np.array([lobe_width(m) for m in scene.materials])
    for order in range(2, bounces + 1):
        if mirrors is not None:            # the glints of flat mirrors, without sampling
            for m, leg in through_mirrors(scene, geo, emb, ends, mirrors, paths,
                                          bounces - order + 1):
                pending.setdefault(order - 1 + m, []).append(leg)
        paths = _step(scene, geo, emb, paths, (widths, rng), mirrors)
        if trail is not None:
            trail.append((paths.ident, paths.x))
        legs = [_leg(scene, geo, emb, ends, paths, mirrors), *pending.pop(order, [])]
        yield Leg(*(np.concatenate(a) for a in zip(*legs)))


def _start(scene, geo, emb, ends, spacing, draws):
    """The paths at their first hits: ``samples // BRANCHES`` hits drawn with replacement
    (at least 2), BRANCHES paths each; None where the view meets nothing."""
    samples, rng = draws
    p, f, r, power = entries(scene, geo, emb, ends, spacing)
    if not len(f):
        return None
    draw = max(2, samples // BRANCHES)
    pick = rng.integers(0, len(f), draw)
    x, face, r1 = p[pick].repeat(BRANCHES, 0), f[pick].repeat(BRANCHES), r[pick].repeat(BRANCHES)
    wi = (ends.position - x) / r1[:, None] if ends.position is not None else \
        np.broadcast_to(ends.w, x.shape)
    n = geo.face_normals[face]
    n = n * np.sign(dot(n, wi))[:, None]
    beta = power[pick].repeat(BRANCHES) * (len(f) / draw / BRANCHES)
    zero = np.zeros(len(face))
    return Paths(face, x, n, wi, beta, r1, zero, np.arange(len(face)), zero.astype(np.int64))


def _step(scene, geo, emb, paths, draws, mirrors):
    """The paths one vertex on: a direction sampled at each, its ray cast, the survivors
    at their new vertex (their run of flat mirrors counted, :mod:`.mirrors`)."""
    widths, rng = draws
    mat = geo.material[paths.face]
    d, pdf = _sample(paths.n, paths.wi, widths[mat], rng)
    beta = paths.beta * weight(scene.materials, mat, paths.n, paths.wi, d) / np.where(
        pdf > 0, pdf, np.inf)
    go = beta > 0
    f2, t = cast(emb, geo, paths.x[go], paths.n[go], d[go])
    alive = np.flatnonzero(go)[f2 >= 0]
    f2, t = f2[f2 >= 0], t[f2 >= 0]
    wi = -d[alive]
    n = geo.face_normals[f2]
    n = n * np.sign(dot(n, wi))[:, None]
    run = np.zeros(len(f2), np.int64)
    if mirrors is not None:
        before = paths.face[alive]
        run = np.where(mirrors.of_face[f2] < 0, 0, np.where(
            mirrors.emits[geo.material[before]], 1,
            np.where((mirrors.of_face[before] >= 0) & (paths.run[alive] >= 1),
                     paths.run[alive] + 1, 0)))
    return Paths(f2, paths.x[alive] + t[:, None] * d[alive], n, wi, beta[alive],
                 paths.r1[alive], paths.length[alive] + t, paths.ident[alive], run)


def _leg(scene, geo, emb, ends, paths, mirrors):
    """The vertices' returns: each joined to the receiver by a shadow ray (a :class:`Leg`
    of those that reach it). A flat mirror that ends a run from an emitter weighs its
    coating without the glint, which :func:`.mirrors.through_mirrors` counted."""
    face, x, n, wi = paths.face, paths.x, paths.n, paths.wi
    d_r, out, receive = to_receiver(ends, x, paths.r1, paths.length)
    mat = geo.material[face]
    g = weight(scene.materials, mat, n, wi, d_r, power=ends.power)
    ex = (paths.run >= 1) & (paths.run <= (0 if mirrors is None else mirrors.longest))
    if mirrors is not None:
        if ex.any():
            g[ex] = np.maximum(g[ex] - weight(mirrors.glints, mat[ex], n[ex], wi[ex],
                                              d_r[ex], power=ends.power), 0.0)
    if receive is not None:
        g = g * receive
    seen = g > 0
    seen[seen] = ~blocked(emb, geo, x[seen], d_r[seen])
    if not ends.power:                 # the glints that reached it (not those left out)
        glint = edge_on_glints(scene.materials, mat[seen], n[seen], wi[seen], d_r[seen])
        if mirrors is not None:
            glint[ex[seen]] = 0.0
        warn_edge_on(paths.beta[seen] * glint, paths.beta[seen] * g[seen])
    return Leg(face[seen], x[seen], (paths.beta * g)[seen],
               (0.5 * (paths.r1 + paths.length + out) - ends.offset)[seen],
               paths.ident[seen])


def _view_orders(scene, geo, emb, w, edges, spacing, plan, rng):
    """One view's orders 2..n binned: (sums (n−1, bins), variances (n−1, bins)); each
    part's share of each order (n−1, parts), by the part of the path's last surface; and
    (2, n−1) the variances of the view's total within the bins of each order and of
    orders 2..k, for each k, from the spread of the first hits' totals (a hit's paths
    reach several bins and orders: the bins' variances summed leave out their
    covariance)."""
    out = np.zeros((2, plan[0] - 1, len(edges) - 1))
    parts = np.zeros((plan[0] - 1, len(scene.parts)))
    draw = max(2, plan[1] // BRANCHES)
    totals, total_var = np.zeros(draw), np.zeros((2, plan[0] - 1))
    for order, leg in enumerate(walk(scene, geo, emb, w, spacing, plan, rng)):
        out[:, order] = _bin_stats(edges, leg.range, leg.value, leg.path, draw)
        parts[order] = np.bincount(geo.part_of[leg.face], leg.value, len(scene.parts))
        inside = (leg.range >= edges[0]) & (leg.range < edges[-1])
        per_hit = np.bincount(leg.path[inside] // BRANCHES, leg.value[inside], draw)
        if len(per_hit) > len(totals):
            totals = np.pad(totals, (0, len(per_hit) - len(totals)))
        totals[:len(per_hit)] += per_hit
        total_var[:, order] = _spread(per_hit, draw), _spread(totals, draw)
    return out, parts, total_var


def _spread(per_hit, draws):
    """The variance of a sum over ``draws`` independent first hits from their totals
    ``per_hit`` (a hit with no path counts as 0)."""
    return draws / (draws - 1.0) * max(
        float(np.sum(per_hit * per_hit) - per_hit.sum() ** 2 / draws), 0.0)


def higher_orders(scene, ladar, *, bounces, ray_spacing, samples=BOUNCE_SAMPLES,
                  seed=None, jobs=1, backend="embreex", receivers=None, sensor=None,
                  radiometry="power") -> Orders:
    """Orders 2..``bounces`` of a mesh scene's returns (module docstring).

    A scene whose :meth:`~meshladar.scene.Scene.visibility` needs no bounce gets exact
    zeros without a ray cast.

    Parameters
    ----------
    scene : Scene
        A mesh scene.
    ladar : Ladar
        Views and range bins.
    bounces : int
        The highest order, ≥ 2.
    ray_spacing : float
        The first hits' grid spacing (the single bounce's).
    samples : int
        Paths per view and order, ≥ BRANCHES.
    seed : int, optional
        Seeds the sampling (view i draws from ``default_rng([seed, i])``); None: fresh.
    jobs : int
        Threads over the views (the same numbers for any count: each view has its seed).
    backend : str
        The ray-casting backend of the bounce segments (:mod:`meshladar.raytrace.backends`);
        default ``"embreex"``, one ray at a time: the bounce rays are incoherent, and the
        packet backend ran them at 0.89 of its speed (``meshladar bench``, bounce line).
    receivers : (n_views, 3) array_like, optional
        Bistatic receivers' unit directions, one per view (None: monostatic); a path's
        last vertex is joined to its view's receiver, and binned at half of
        −x₁·w + L − x_k·w_r (the single bounce's bistatic range −p·(w + w_r)/2).
    sensor : Sensor, optional
        The run's sensor (monostatic): its beam weighs the first hits, and at a finite
        standoff paths start on its rays and end at it (:mod:`.bounce_ends`). Values are
        per unit of the aim point's irradiance, as the single bounce's before its
        photoelectrons.
    radiometry : {"power", "paper"}
        Received power (default), or the paper's Eq. 8: the last vertex weighs F, not
        F·cos θr.

    Returns
    -------
    Orders
        Values and standard errors per order, view and bin.
    """
    if samples < BRANCHES:
        raise ParameterError(f"bounce_samples must be at least {BRANCHES}; got {samples}")
    check_bistatic(scene.materials)
    shape = (bounces - 1, ladar.n_views, ladar.n_bins)
    values, var = np.zeros(shape), np.zeros(shape)
    per_part = np.zeros((bounces - 1, ladar.n_views, len(scene.parts)))
    total_var = np.zeros((2, bounces - 1, ladar.n_views))
    if scene.visibility().needs_bounces:
        geo = geometry(scene, "flat")
        emb = embree_scene(geo, resolve_backend(backend))
        seeds = np.random.SeedSequence(seed).spawn(ladar.n_views)

        def view(i):
            ends = view_ends(ladar.view_vectors[i],
                             None if receivers is None else receivers[i], sensor,
                             radiometry == "power")
            return _view_orders(scene, geo, emb, ends, ladar.bin_edges, ray_spacing,
                                (bounces, samples), np.random.default_rng(seeds[i]))
        with thread_pool(min(jobs, ladar.n_views)) as pool:
            for i, ((v, e), share, t) in enumerate(pool.map(view, range(ladar.n_views))):
                values[:, i], var[:, i], per_part[:, i], total_var[:, :, i] = v, e, share, t
    return Orders(tuple(range(2, bounces + 1)), values, np.sqrt(var), samples, radiometry,
                  per_part=per_part, total_stderr=np.sqrt(total_var))
