"""Ray grids: per view, orthographic rays over the target's projected hull, regular or
stratified, and the defaults that size them."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .._extents import point_ranges
from .._validate import check_choice, check_real, check_seed
from ..errors import ParameterError
from ..precision import ORIGIN_MARGIN as _ORIGIN_MARGIN
from ..precision import PARALLEL_SLACK, SCENE_RADIUS_RANGE


MODES = ("slice", "3d")


#: "regular": rays at cell centres (a midpoint rule: second order on smooth slice profiles,
#: but it aliases on thin walls seen edge-on); "stratified": one ray per cell at a seeded
#: random offset (unbiased areas; see stratified_offsets).
SAMPLINGS = ("regular", "stratified")


#: Default rays per range-bin width: slice rows are cheap, 3-D grids are rays_per_bin² per
#: bin area.
_DEFAULT_RAYS_PER_BIN = {"slice": 8.0, "3d": 1.0}


#: A view's rays are held in memory together (origins and Embree's results, ~50 bytes a
#: ray): beyond this many a run is refused before it allocates (about 2.5 GB).
MAX_RAYS_PER_VIEW = 5e7


#: By default a 3-D grid has at least this many rays across the target's diameter.
_MIN_RAYS_ACROSS = 128



def dot(a, w):
    """Row-wise a·w for (k, 3) a, without BLAS (whose threads would oversubscribe the cores
    that worker processes already share)."""
    return a[:, 0] * w[0] + a[:, 1] * w[1] + a[:, 2] * w[2]



def frame(w):
    """(u, v) completing w to a right-handed orthonormal frame; v = z for horizontal w.

    u = z × w / |z × w| and v = w × u, each cross product written out as ``np.cross``
    computes it (a product, a product, a difference: the same bits, signed zeros
    included) and |z × w| as the root of the sum of squares in order, so the frame is the
    same on every CPU (a BLAS dot's order and fused multiplies are the CPU's) and
    :func:`frames` gives the same bits for many views at once."""
    w0, w1, w2 = (float(x) for x in w)
    a, b, c = 0.0 * w2 - 1.0 * w1, 1.0 * w0 - 0.0 * w2, 0.0 * w1 - 0.0 * w0
    n = math.sqrt(a * a + b * b + c * c)
    if n < PARALLEL_SLACK:                                         # looking along ±z
        a, b, c = 1.0, 0.0, 0.0
    else:
        a, b, c = a / n, b / n, c / n
    return np.array([a, b, c]), np.array([w1 * c - w2 * b, w2 * a - w0 * c, w0 * b - w1 * a])


def frames(vectors):
    """:func:`frame` of each row of ``vectors`` (k, 3): (u, v), each (k, 3), the same
    operations element by element (the same bits)."""
    w0, w1, w2 = np.asarray(vectors, dtype=float).reshape(-1, 3).T
    a, b, c = 0.0 * w2 - 1.0 * w1, 1.0 * w0 - 0.0 * w2, 0.0 * w1 - 0.0 * w0
    n = np.sqrt(a * a + b * b + c * c)
    along = n < PARALLEL_SLACK                                     # looking along ±z
    n[along] = 1.0
    a, b, c = np.where(along, 1.0, a / n), np.where(along, 0.0, b / n), np.where(along, 0.0,
                                                                                  c / n)
    return (np.stack([a, b, c], axis=-1),
            np.stack([w1 * c - w2 * b, w2 * a - w0 * c, w0 * b - w1 * a], axis=-1))


class GridPlan(NamedTuple):
    """A view's ray grid as :func:`grid_plan` describes it (flat, for the compiled loop)."""

    s: np.ndarray
    t: np.ndarray
    #: The stratified offsets' 1-D sequences (xi, ku, kv, eta), float32: the offset of ray
    #: (i, j) is wrap(xi_i + ku_j) along u and wrap(kv_i + eta_j) along v
    #: (:func:`stratified_offsets`); None on a regular grid and in slice mode.
    offsets: tuple | None
    u: np.ndarray
    v: np.ndarray
    L: float


class RayGrid(NamedTuple):
    """A view's rays as :func:`ray_grid` builds them: float32 origins (n, 3) in shifted
    coordinates, row-major in rows of ``columns`` rays, the start distance L and the
    view's transverse axes u, v."""

    origins: np.ndarray
    L: float
    u: np.ndarray
    v: np.ndarray
    columns: int = 0


def grid_plan(geo, w, mode, spacing, z0_shifted, rng):
    """The grid's recipe, for :func:`ray_grid` and the packet backend's fused loop (which
    builds the same float32 origins ray by ray): (s, t, offsets, u, v, L) with s (ns,) and
    t (nt,) the cell centres along u and v, and ``offsets`` the 1-D sequences of the
    stratified offsets du, dv (ns, nt) in 3-D (:func:`stratified_offsets`; None on a
    regular grid, and in slice mode, whose offsets are drawn by :func:`ray_grid` itself).
    Ray (i, j) is o = S u + T v + L w, S = s_i (+ δ du_ij), T = t_j (+ δ dv_ij), in that
    order of float32 operations."""
    u, v = frame(w)
    L = (1.0 + _ORIGIN_MARGIN) * geo.radius + spacing
    s_lo, s_hi = geo.extent(u)
    s_lo, s_hi = s_lo - spacing, s_hi + spacing
    ns = max(1, int(math.ceil((s_hi - s_lo) / spacing)))
    s = s_lo + (np.arange(ns) + 0.5) * spacing
    if mode == "slice":
        t = np.array([z0_shifted])
    else:
        t_lo, t_hi = geo.extent(v)
        t_lo, t_hi = t_lo - spacing, t_hi + spacing
        nt = max(1, int(math.ceil((t_hi - t_lo) / spacing)))
        t = t_lo + (np.arange(nt) + 0.5) * spacing
    offsets = None
    if rng is not None and mode == "3d":
        offsets = stratified_sequences(s.size, t.size, rng)
    return GridPlan(s, t, offsets, u, v, L)


class GridPlans(NamedTuple):
    """Many views' grids as :func:`grid_plans` describes them, each view's as
    :func:`grid_plan`'s: view j's cell centres are ``s[s_at[j]:s_at[j + 1]]`` along its
    ``u[j]`` and ``t[t_at[j]:t_at[j + 1]]`` along ``v[j]``, all from the start distance
    ``L``."""

    s: np.ndarray
    s_at: np.ndarray
    t: np.ndarray
    t_at: np.ndarray
    u: np.ndarray
    v: np.ndarray
    L: float


def grid_plans(geo, vectors, mode, spacing, z0_shifted):
    """The regular grids of many views (k, 3) at once, the same numbers as :func:`grid_plan`
    gives each (with ``rng`` None): the frames (:func:`frames`), every extent in one compiled
    pass (:meth:`meshladar.raytrace.embree.Geometry.extents`) and the cell centres in numpy
    over all views (a run of many small views plans a chunk of them in one go)."""
    u, v = frames(vectors)
    L = (1.0 + _ORIGIN_MARGIN) * geo.radius + spacing
    s, s_at = _centres(geo.extents(u), spacing)
    if mode == "slice":
        t, t_at = np.full(len(u), float(z0_shifted)), np.arange(len(u) + 1)
    else:
        t, t_at = _centres(geo.extents(v), spacing)
    return GridPlans(s, s_at, t, t_at, u, v, L)


def _centres(extents, spacing):
    """Every view's cell centres along one axis, packed, and where each view's start: the
    operations of :func:`grid_plan`, element by element."""
    lo = extents[:, 0] - spacing
    n = np.maximum(1, np.ceil((extents[:, 1] + spacing - lo) / spacing)).astype(np.int64)
    at = np.zeros(len(n) + 1, np.int64)
    np.cumsum(n, out=at[1:])
    step = np.arange(at[-1]) - np.repeat(at[:-1], n)
    return np.repeat(lo, n) + (step + 0.5) * spacing, at


def ray_grid(geo, w, mode, spacing, z0_shifted, rng):
    """Origins (n, 3) float32 in shifted coordinates, the start distance L, and (u, v).

    Built component by component in float32 (Embree's precision): o = s u + t v + L w.
    """
    plan = grid_plan(geo, w, mode, spacing, z0_shifted, rng)
    s, t, u, v, L = plan.s, plan.t, plan.u, plan.v, plan.L
    o = np.empty((s.size, t.size, 3), dtype=np.float32)
    if rng is None:
        s32, t32 = s.astype(np.float32), t.astype(np.float32)
        for k in range(3):
            np.add.outer(s32 * np.float32(u[k]), t32 * np.float32(v[k]), out=o[:, :, k])
    elif mode == "slice":
        S = s[:, None] + rng.uniform(-0.5, 0.5, (s.size, t.size)) * spacing
        T = np.broadcast_to(t[None, :], S.shape)
        for k in range(3):
            o[:, :, k] = S * u[k] + T * v[k]
    else:
        # in float32 (Embree's precision, as the regular grid): S = s + δ·du, T = t + δ·dv
        du, dv = stratified_offsets(plan.offsets)
        sp = np.float32(spacing)
        S = du
        S *= sp
        S += s.astype(np.float32)[:, None]
        T = dv
        T *= sp
        T += t.astype(np.float32)[None, :]
        for k in range(3):
            np.multiply(S, np.float32(u[k]), out=o[:, :, k])
            o[:, :, k] += T * np.float32(v[k])
    for k in range(3):
        o[:, :, k] += np.float32(L * w[k])
    return RayGrid(o.reshape(-1, 3), L, u, v, o.shape[1])


#: The golden ratio's conjugate: the Kronecker sequence frac(x + kα) is the most evenly
#: spread sequence of its kind (its gaps take at most three lengths).
_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0



def stratified_sequences(ns, nt, rng):
    """The 1-D sequences (xi (ns,), ku (nt,), kv (ns,), eta (nt,)), float32, of a grid's
    stratified offsets (:func:`stratified_offsets`): the shifts ξ and η drawn from ``rng``
    (ns, then nt uniforms) and the centred Kronecker sequences frac(kα) − ½."""
    xi = rng.uniform(0.0, 1.0, ns).astype(np.float32)     # one shift per column (along v)
    eta = rng.uniform(0.0, 1.0, nt).astype(np.float32)    # one shift per row (along u)
    return xi, kronecker(nt), kronecker(ns), eta


def kronecker(n):
    """The centred Kronecker sequence frac(kα) − ½, k = 0 … n − 1, in float64 then float32
    (offsets within a cell: float32 is plenty); a longer one starts with a shorter one."""
    return (np.mod(np.arange(n) * _GOLDEN, 1.0) - 0.5).astype(np.float32)


def stratified_offsets(sequences):
    """Offsets du, dv in [−½, ½) of each ray from its cell centre, (ns, nt) float32 along u
    and along v, from their 1-D ``sequences`` (:func:`stratified_sequences`): du_ij =
    ξ_i + ku_j and dv_ij = kv_i + η_j in float32, less 1 where ≥ ½ (the packet backend's
    fused loop makes the same float32 operations ray by ray).

    Every cell holds one ray uniformly distributed in it, so the expected number of rays
    hitting any region is its projected area over δ²: the estimate of every area (a thin
    wall seen edge-on, a sub-ray facet) is unbiased. Unlike independent jitter, the offsets
    are correlated along rows and columns to cancel most of the noise at straight edges:
    along each row (a run of cells across u at one v) the v offsets follow a randomly
    shifted Kronecker sequence frac(η + iα), and along each column the u offsets
    frac(ξ + jα), so the fraction of a row's rays that fall on one side of an edge parallel
    to it is right to O(log n / n) instead of O(n^-½). Each cell's offset stays uniform
    (η and ξ are uniform and independent), hence the expectation is exact.
    """
    xi, ku, kv, eta = sequences
    du = np.add.outer(xi, ku)                           # frac(ξ + jα) − ½ ∈ [−½, 1½) ...
    du -= du >= np.float32(0.5)                         # ... wrapped into [−½, ½)
    dv = np.add.outer(kv, eta)
    dv -= dv >= np.float32(0.5)
    return du, dv



def _sampling(mode, sampling, seed):
    """(sampling, seed used): stratified by default in 3-D (and whenever a seed is given),
    regular in slice mode; seed 0 unless given."""
    if sampling is None:
        sampling = "stratified" if (mode == "3d" or seed is not None) else "regular"
    check_choice("sampling", sampling, SAMPLINGS)
    if sampling == "regular":
        if seed is not None:
            raise ParameterError(f"seed jitters the rays, so it needs sampling='stratified'; "
                                 f"got seed={seed!r} with sampling='regular'")
        return sampling, None
    if seed is None:
        return sampling, 0
    if isinstance(seed, (list, tuple, np.ndarray)):     # the rays' seed is one integer
        raise ParameterError(f"seed must be None or a non-negative integer; got {seed!r}")
    return sampling, check_seed("seed", seed)



#: The finest ray spacing taken (scene units): its inverse square, a ray count, stays finite.
MIN_SPACING = 1e-150
#: The coarsest: the largest scene radius taken (a spacing of 3e38 overflowed the rays'
#: float32 coordinates, a spacing beside the grid's edges).
MAX_SPACING = SCENE_RADIUS_RANGE[1]
#: rays_per_bin taken (subnormal ones made the spacing infinite); the ray budget refuses
#: what the top allows and the scene cannot hold.
RAYS_PER_BIN_RANGE = (1e-300, 1e6)


def _spacing(ladar, mode, ray_spacing, rays_per_bin, radius):
    if ray_spacing is not None and rays_per_bin is not None:
        raise ParameterError("give ray_spacing or rays_per_bin, not both")
    if ray_spacing is not None:
        return check_real("ray_spacing", ray_spacing, low=MIN_SPACING, high=MAX_SPACING)
    if rays_per_bin is not None:
        rpb = check_real("rays_per_bin", rays_per_bin, low=RAYS_PER_BIN_RANGE[0],
                         high=RAYS_PER_BIN_RANGE[1])
        spacing = float(np.min(np.diff(ladar.bin_edges))) / rpb
        if not math.isfinite(spacing):
            raise ParameterError(f"rays_per_bin={rpb:g} makes the ray spacing overflow (bins "
                                 f"{float(np.min(np.diff(ladar.bin_edges))):.3g} wide): give "
                                 "more rays_per_bin or a ray_spacing")
        return spacing
    spacing = float(np.min(np.diff(ladar.bin_edges))) / _DEFAULT_RAYS_PER_BIN[mode]
    if mode == "3d":
        # bins much wider than the target (a target far off the rotation axis, seen from
        # all around) must not leave it with a handful of rays
        spacing = min(spacing, 2.0 * radius / _MIN_RAYS_ACROSS)
    return spacing



def _largest_grid(geo, vectors, mode, spacing, limit=None):
    """The most rays any one view's grid holds (the grids of ray_grid: the projected
    hull's extent along u, and along v in 3-D, plus a spacing each side). With ``limit``,
    an upper bound (the bounding sphere's grid) when that is within it: the exact count is
    only needed to refuse a run."""
    across = (2 * geo.radius + 2 * spacing) / spacing + 2.0        # float: may be inf
    bound = across if mode == "slice" else across * across
    if limit is not None and bound <= limit:
        return bound
    largest = 0.0
    for start in range(0, len(vectors), 4096):        # the views' frames a block at a time
        axes = frames(vectors[start:start + 4096])
        n = 1.0
        for axis in range(2 if mode == "3d" else 1):   # extents along u, and v in 3-D
            lo, hi = point_ranges(geo.support, axes[axis])
            n = n * np.ceil((hi - lo + 2 * spacing) / spacing)
        largest = max(largest, float(np.max(n)))
    return largest



def _estimate_rays(geo, ladar, mode, spacing):
    extent = 2 * geo.radius / spacing + 2
    return ladar.n_views * (extent if mode == "slice" else extent * extent)


# public names for the stages above (weighing, forward): the view's frame and grids
