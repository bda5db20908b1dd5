"""The mesh job's calls of the packet backend's fused loop (:mod:`meshladar.weighing.fused`):
one view at a time, its rows split over threads when it is big, or, where the grids are
sparse (many small views), every view of a chunk in one compiled call, planned together
(compiled coatings; monostatic with flat or smooth normals, point or footprint bins, or
bistatic with flat ones).

A view's numbers are the same whichever way it goes: the chunk's grids are planned with the
operations of :func:`meshladar.raytrace.grid.grid_plan`, its stratified offsets drawn view
by view from the view's own seed, and each view cast, weighed and binned by the same
compiled loop in the same order (``tests/weighing/test_sparse_chunks.py``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from .._lazy import deferred_module
from .._executors import thread_pool
from ..precision import MIN_COS_FACET, RECEIVER_LIFT
from ..raytrace.grid import grid_plan, grid_plans
from ..raytrace.views import range_offset
from ..weighing.faces import check_edge_on_receiver
from ..weighing.fused import DRAWN_RAYS_PER_FACE, cast_bin_grid, cast_bin_views

if TYPE_CHECKING:            # the layers' check sees the edge; numba loads at first use
    from ..raytrace import draws
else:
    draws = deferred_module("meshladar.raytrace.draws")

__all__ = ["FlatBins", "fused_view", "chunk_views", "receiver_args"]


class FlatBins(NamedTuple):
    """The compiled binning loop's arguments after the hits (flat, for numba)."""

    plane_d: np.ndarray
    face_normals: np.ndarray
    face_material: np.ndarray
    params: np.ndarray
    w: np.ndarray
    start: float
    edges: np.ndarray
    area: float
    power: bool
    ignore_back: bool
    out: np.ndarray
    stamp: np.ndarray
    weight: np.ndarray
    tag: int
    footprint: tuple | None


def fused_view(job, scene, view, bins, receiver, smooth):
    """One view through the fused loop: its grid cast (on the "raster" backend, a 3-D grid
    of at least :data:`meshladar.weighing.fused.DRAWN_RAYS_PER_FACE` rays a face drawn),
    weighed and binned, on one thread or (``job.row_jobs`` > 1) with its rows split over
    threads.

    Parameters
    ----------
    job : meshladar.forward.job.MeshJob
        The run's job (its plan's grid and ``row_jobs``).
    scene : meshladar.raytrace.embree.EmbreeScene
        The packet backend's scene.
    view : meshladar.raytrace.plan.View
        The view.
    bins : FlatBins
        Its weigh-and-bin arguments.
    receiver, smooth : tuple or None
        As :func:`meshladar.weighing.fused.cast_bin_grid` takes them.

    Returns
    -------
    (int, int)
        The rays cast and the back-face hits.
    """
    p = job.plan
    grid = grid_plan(p.geo, view.w, p.mode, p.spacing, p.z0_shifted, view.rng)
    drawn = p.mode == "3d" and p.rays_per_face >= DRAWN_RAYS_PER_FACE
    how = (receiver, smooth, p.coherent, p.geo.closed if drawn else None)
    if job.row_jobs > 1:
        return _rows_on_threads(scene, grid, view.w, p.spacing, bins, job.row_jobs, how)[::-1]
    back, n = cast_bin_grid(scene, grid, view.w, p.spacing, bins, *how)
    return n, back


def _flat_views(job, scene, views, chunk):
    """:func:`chunk_views` with flat normals."""
    return chunk_views(job, scene, views, chunk)


def _bistatic_views(job, scene, views, chunk):
    """:func:`chunk_views` for bistatic views (flat normals, built-in compiled coatings)."""
    at = np.asarray(views, dtype=np.int64)
    return chunk_views(job, scene, views, chunk,
                       receiver=receiver_args(job, job.vectors[at], job.plan.receivers[at]))


def receiver_args(job, w, w_r):
    """The compiled loops' ``receiver`` for bistatic views w (3,) or (k, 3) toward w_r:
    (w_r, the occlusion rays' lift, whether each face's weight is made at its first hit
    (built-in coatings), the lone faces); under the paper's radiometry, with weights made
    at first hits, each view's faces edge-on to its receiver warn first (as numpy's
    per-face weights do).

    Parameters
    ----------
    job : meshladar.forward.job.MeshJob
        The run's job.
    w, w_r : (3,) or (k, 3) numpy.ndarray
        The views' directions and their receivers'.

    Returns
    -------
    tuple
        As :func:`meshladar.weighing.fused.cast_bin_grid` and
        :func:`meshladar.weighing.fused.cast_bin_views` take ``receiver``.
    """
    p, built_in = job.plan, job.weighing.compiled_bistatic
    if built_in and not job.weighing.power:
        for a, b in zip(np.reshape(w, (-1, 3)), np.reshape(w_r, (-1, 3))):
            check_edge_on_receiver(p.geo, a, b, p.ignore_back)
    return w_r, RECEIVER_LIFT * p.geo.radius, built_in, p.geo.lone


def _smooth_views(job, scene, views, chunk):
    """:func:`chunk_views` with smooth normals (the faces' corner normals, the least
    |cos θ| of a facet as the one-view loop takes them)."""
    return chunk_views(job, scene, views, chunk, (job.plan.geo.corner, MIN_COS_FACET))


def chunk_views(job, scene, views, chunk, smooth=None, receiver=None):
    """A chunk's views in one compiled call
    (:func:`meshladar.weighing.fused.cast_bin_views`), monostatic with flat or ``smooth``
    normals (point or footprint bins), or bistatic (``receiver``) with flat ones (point
    bins): the grids planned together
    (:func:`meshladar.raytrace.grid.grid_plans`), each view's stratified offsets drawn
    from its own seed as :func:`meshladar.raytrace.grid.stratified_sequences` draws them
    (:func:`meshladar.raytrace.draws.plans_sequences`), each view's footprint rows made
    as :func:`meshladar.weighing.faces.footprint_args` makes them.
    For sparse grids, whose views are small (:attr:`meshladar.forward.job.MeshJob.batched`).

    Parameters
    ----------
    job : meshladar.forward.job.MeshJob
        The run's job.
    scene : meshladar.raytrace.embree.EmbreeScene
        The packet backend's scene.
    views : (k,) array_like of int
        The chunk's view indices.
    chunk : meshladar.forward.job.Chunk
        The chunk's bins (k, n_bins), weight cache and footprint rows; view j is tagged
        j + 1.
    smooth : tuple of ((m, 3, 3) numpy.ndarray, float), optional
        Smooth normals, as :func:`meshladar.weighing.fused.cast_bin_views` takes them.
    receiver : tuple, optional
        The views' receivers, as :func:`meshladar.weighing.fused.cast_bin_views` takes
        them (each view's direction a row, in the order of ``views``).

    Returns
    -------
    (k, 2) int64 numpy.ndarray
        Each view's rays cast and back-face hits.
    """
    p, wg = job.plan, job.weighing
    w = job.vectors[np.asarray(views, dtype=np.int64)]
    plans = grid_plans(p.geo, w, p.mode, p.spacing, p.z0_shifted)
    sequences = None
    if p.seed is not None and p.mode == "3d":
        sequences = draws.plans_sequences(plans, views, p.seed)
    w_r = [None] * len(w) if receiver is None else receiver[0]
    starts = np.array([range_offset(p.geo.center, x, y) for x, y in zip(w, w_r)])
    fp = None if chunk.footprints is None else (
        chunk.footprints + (p.geo.shifted, p.geo.faces, float(p.spacing), p.mode == "3d",
                            p.dense))
    bins = FlatBins(p.geo.plane_d, p.geo.face_normals, p.geo.material, chunk.params, w,
                    starts, wg.edges[0], p.area, wg.power, p.ignore_back, chunk.values,
                    chunk.stamp, chunk.weight, 0, fp)
    return cast_bin_views(scene, plans, sequences, p.spacing, bins, p.coherent, smooth,
                          receiver)[:, ::-1]


def _rows_on_threads(scene, grid, w, spacing, bins, row_jobs, how=(None, None, True, None)):
    """One big view's grid split into ``row_jobs`` bands of rows, cast on as many threads
    (the fused loop releases the GIL), each band with its own bins and a copy of the weight
    cache (weights already evaluated for the view stay valid); the
    bands' bins are added in order, so a given ``row_jobs`` always gives the same numbers
    (and the one-thread numbers to rounding). ``how``: :func:`cast_bin_grid`'s
    (receiver, smooth, coherent, closed). Returns (back-face hits, rays cast)."""
    cuts = np.linspace(0, grid.s.size, row_jobs + 1).astype(int)
    parts = []
    for a0, a1 in zip(cuts[:-1], cuts[1:]):
        if a1 > a0:
            band = grid._replace(s=grid.s[a0:a1], offsets=None if grid.offsets is None else
                                 _rows_of(grid.offsets, a0, a1))
            fp = bins.footprint                # each band makes its own faces' rows
            parts.append((band, bins._replace(out=np.zeros_like(bins.out),
                                              stamp=bins.stamp.copy(),
                                              weight=bins.weight.copy(),
                                              footprint=None if fp is None else
                                              (fp[0].copy(), fp[1].copy()) + fp[2:])))
    with thread_pool(len(parts)) as ex:
        done = list(ex.map(lambda p: cast_bin_grid(scene, p[0], w, spacing, p[1], *how),
                           parts))
    for _, band in parts:
        bins.out[...] += band.out
    return sum(b for b, _ in done), sum(n for _, n in done)


def _rows_of(offsets, a0, a1):
    """The stratified offsets' sequences of rows a0..a1 (xi and kv run along the rows)."""
    xi, ku, kv, eta = offsets
    return xi[a0:a1], ku, kv[a0:a1], eta
