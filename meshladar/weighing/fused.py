"""The fused path of the packet backend: one view from ray grid to bins in one compiled
loop (:mod:`meshladar.weighing._fused_kernels`: one kernel each for flat, smooth and
bistatic views, so that a run compiles or loads only its own), with the weights and bins a
:mod:`meshladar.forward.mesh` job prepared for it."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .._lazy import deferred_module
from ..raytrace.embree4_ctypes import query_flags
from ..raytrace.grid import dot
from ._scratch import depth_buffer, scratch

# compiled loops, imported (with numba) at their first use: a small run loads neither
_fused_kernels = deferred_module("meshladar.weighing._fused_kernels")
_raster_kernels = deferred_module("meshladar.weighing._raster_kernels")

if TYPE_CHECKING:            # the layers' check sees the edge; numba loads at first use
    from ..raytrace import embree4_kernels
else:
    embree4_kernels = deferred_module("meshladar.raytrace.embree4_kernels")

__all__ = ["cast_bin_grid", "cast_bin_views", "queries", "draw_bin_grid", "DRAWN_RAYS",
           "DRAWN_RAYS_PER_FACE"]

#: A 3-D view is drawn on the "raster" backend from this many rays on the face a ray hits
#: (:attr:`meshladar.raytrace.plan.TracePlan.rays_per_face`), below it cast: drawing costs
#: per face and cell, casting per ray. Measured against the packets on icospheres, 10⁶
#: stratified rays a view, one thread: 1.5× at 38 rays a face (82k faces), 1.1× at 9.6
#: (328k), 0.73× at 2.4 (1.31M).
DRAWN_RAYS_PER_FACE = 6.0
#: The most rays a view's depth buffer holds (12 bytes each: 48 MiB a thread); a bigger
#: view is drawn in blocks of rows (:func:`draw_bin_grid`), binned in the same order.
DRAWN_RAYS = 1 << 22


def queries(lib, coherent):
    """The compiled loops' ``query`` argument: (rtcIntersectW at the library's width,
    rtcIntersect1, whether to cast each ray on its own). Coherent grids are cast in packets
    of tiles; sparser ones ray by ray: there a packet's rays part at the BVH's first levels
    and rtcIntersect1 is faster (measured on an 82k-triangle icosphere, one thread, width
    16: at 0.19 rays a face 1.03x raw embreex against 0.77x for coherent tiles and 0.76x
    incoherent; at 0.39, 1.02x against 0.99x and 0.80x; at 1.55, 1.03x against 1.70x).

    Parameters
    ----------
    lib : meshladar.raytrace.embree4_ctypes.EmbreeLib
        The Embree library.
    coherent : bool
        :attr:`meshladar.raytrace.plan.TracePlan.coherent`.

    Returns
    -------
    tuple
        (ctypes function, ctypes function, bool).
    """
    return lib.intersect[lib.width], lib.intersect1, not coherent


def _head(emb, coherent):
    """The compiled loops' first arguments: (query, the scene's handle, the width, the
    flags) and, after the grid, (inverse scale, scale)."""
    sc = emb.scene.scene
    lib = sc.lib
    return ((queries(lib, coherent), sc.live(), lib.width, query_flags(coherent)),
            (np.float32(emb.inverse), float(emb.scale)))


def _coating(bins, w, wr, built_in):
    """The bistatic loops' ``coating``: (face materials, SR table, the half vector
    (w + w_r)/|w + w_r| of each view, a row each for (k, 3) ``w`` and ``wr``, area, power,
    built in); |w + w_r| the root of its squares summed in order, as
    :func:`meshladar.raytrace.grid.frames` takes |z × w| (a BLAS dot's order and fused
    multiplies would be the CPU's)."""
    x = np.reshape(w, (-1, 3)) + np.reshape(wr, (-1, 3))
    n = np.sqrt(x[:, 0] * x[:, 0] + x[:, 1] * x[:, 1] + x[:, 2] * x[:, 2])
    return (bins.face_material, bins.params, np.reshape(x / n[:, None], np.shape(w)),
            float(bins.area), bool(bins.power), bool(built_in))


def cast_bin_views(emb, plans, sequences, spacing, bins, coherent=False, smooth=None,
                   receiver=None):
    """Cast, weigh and bin many views in one compiled call
    (:func:`._fused_kernels.cast_bin_flat_views`, ``cast_bin_smooth_views``,
    ``cast_bin_bistatic_views``), each view as :func:`cast_bin_grid` casts it alone: a run
    of many small views (sparse grids) pays the call and its planning once a chunk.

    Parameters
    ----------
    emb : EmbreeScene
        As for :func:`cast_bin_grid`.
    plans : meshladar.raytrace.grid.GridPlans
        The views' grids (k views).
    sequences : tuple of numpy.ndarray or None
        The stratified offsets' sequences (xi packed as ``plans.s``, ku and kv for the
        longest columns and rows, eta packed as ``plans.t``: view j's are those
        :func:`meshladar.raytrace.grid.stratified_sequences` draws for it); None: regular
        grids.
    spacing : float
        The ray spacing δ.
    bins : FlatBins
        As for :func:`cast_bin_grid`, with ``w`` the views' directions (k, 3), ``start``
        their range offsets (k,) and ``out`` their bins (k, n_bins); view j is tagged
        j + 1 in the weight cache (``tag`` is unused). ``footprint``: None (point bins),
        or for footprint bins (rows, stamps, vertices, faces, spacing, 3-D, dense), whose
        view j is :func:`meshladar.weighing.faces.footprint_args`' tuple for it (its rows
        made at their faces' first hits under tag j + 1; a dense grid's every row first).
    coherent : bool
        As for :func:`cast_bin_grid` (default False: the sparse grids this is for).
    smooth : tuple of ((m, 3, 3) numpy.ndarray, float), optional
        Smooth normals, as for :func:`cast_bin_grid` (``bins.stamp`` and ``bins.weight``
        are then unused). None (default): flat normals.
    receiver : tuple of ((k, 3) array_like, float, bool, (n_faces,) uint8), optional
        Bistatic views (flat normals), as for :func:`cast_bin_grid` with each view's
        receiver direction a row. None (default): monostatic.

    Returns
    -------
    (k, 2) int64 numpy.ndarray
        Each view's back-face hits and rays cast.
    """
    w = np.ascontiguousarray(bins.w, dtype=np.float64)
    f32 = np.float32
    seq = sequences or (np.empty(0, f32),) * 4
    grids = (plans.s.astype(f32), plans.s_at, plans.t.astype(f32), plans.t_at, seq,
             f32(spacing), plans.u.astype(f32), plans.v.astype(f32), (plans.L * w).astype(f32))
    first, size = _head(emb, coherent)
    lib, b, start = emb.scene.scene.lib, bins, np.asarray(bins.start, np.float64)
    counts = np.zeros((len(w), 2), np.int64)
    columns = int(np.max(np.diff(plans.t_at)))
    head = first + (grids, (-w).astype(f32)[:, None, :]) + size
    if receiver is not None:
        wr = np.ascontiguousarray(receiver[0], dtype=np.float64).reshape(-1, 3)
        coating = _coating(b, w, wr, receiver[2])
        _fused_kernels.cast_bin_bistatic_views(
            *head, b.plane_d, b.face_normals, w, start, b.edges, b.ignore_back, b.out,
            b.weight, lib.occluded[lib.width], wr, float(receiver[1]), b.stamp, coating,
            receiver[3], counts, scratch("bistatic", lib.width, columns))
        return counts
    head += tuple(b[:4]) + (w, start) + tuple(b[6:11])
    fp = None if b.footprint is None else b.footprint[:4] + (plans.u, plans.v) + b.footprint[4:]
    if smooth is not None:
        _fused_kernels.cast_bin_smooth_views(*head, fp, smooth[0], float(smooth[1]), counts,
                                             scratch("smooth", lib.width, columns))
    else:
        _fused_kernels.cast_bin_flat_views(*head, b.stamp, b.weight, fp, counts,
                                           scratch("flat", lib.width, columns))
    return counts


def cast_bin_grid(emb, plan, direction, spacing, bins, receiver=None, smooth=None,
                  coherent=True, closed=None):
    """Cast, weigh and bin one view of the packet scene ``emb``
    (:class:`meshladar.raytrace.embree.EmbreeScene` whose backend is fused): ``plan`` is
    :func:`meshladar.raytrace.grid.grid_plan`'s :class:`~meshladar.raytrace.grid.GridPlan`,
    ``bins`` the weigh-and-bin arguments (:class:`~meshladar.forward.fused_views.FlatBins`).

    Monostatic or bistatic with flat normals, or monostatic with smooth ones (``smooth``),
    binned at a point (``bins.footprint`` None) or over each face's footprint, in packets
    of the library's native width; the ray origins built in float32 as ``ray_grid`` builds
    them, cast at unit size (× ``emb.inverse``), Embree's distances scaled back
    (× ``emb.scale``); the loop's buffers this thread's (:func:`._scratch.scratch`).

    Parameters
    ----------
    emb : EmbreeScene
        The view's packet scene (``emb.scene.scene`` a ``PacketGeometry``).
    plan : GridPlan
        The view's ray grid (s, t, offsets, u, v, L; shifted coordinates).
    direction : (3,) array_like
        The view direction w (unit, toward the ladar; the rays travel along −w).
    spacing : float
        The ray spacing δ (scene units) that scales the stratified offsets.
    bins : FlatBins
        The compiled loop's 15 arguments after the hits, in order: ``plane_d``,
        ``face_normals``, ``face_material``, ``params``, ``w``, ``start``, ``edges``,
        ``area``, ``power``, ``ignore_back``, ``out``, ``stamp``, ``weight``, ``tag``,
        ``footprint``. The weights are added into ``out`` (n_bins,).
    receiver : tuple of ((3,) array_like, float, bool, (n_faces,) uint8), optional
        Bistatic: the receiver's direction w_r, the lift (scene units) along the hit
        face's normal, turned toward the ladar, from which each hit's occlusion ray toward
        it starts, whether the coatings are built in (F is 0 where the face turns away
        from the receiver: no occlusion ray), and the ``lone`` faces (a hit on the front
        of one casts none: :meth:`~meshladar.raytrace.embree.Geometry.for_receivers`).
        A face whose ``bins.stamp`` is not ``bins.tag`` gets its bistatic weight at its
        first hit, from the SR table ``bins.params`` (built-in coatings); for other
        coatings the job stamps every face's weight
        (:func:`meshladar.weighing.faces.face_bistatic_weights`) first. None (default):
        monostatic.
    smooth : tuple of ((m, 3, 3) numpy.ndarray, float), optional
        Smooth normals (monostatic): each face's corner normals and the least |cos θ| of
        the facet in the area factor (:func:`meshladar.weighing._kernels.bin_smooth_hits`);
        ``bins.stamp`` and ``bins.weight`` are then unused. None (default): flat normals.
    coherent : bool
        Whether the rays are cast in coherent packets (default True), else one at a time
        (:func:`queries`; :attr:`meshladar.raytrace.plan.TracePlan.coherent`).
    closed : (n_faces,) uint8 numpy.ndarray, optional
        ``Geometry.closed``: on the "raster" backend a monostatic view's first hits are
        drawn (:func:`draw_bin_grid`). None (default): cast.

    Returns
    -------
    back : int
        The view's back-face hits.
    rays : int
        The rays cast, len(s) × len(t).
    """
    s, t, u, v, L = plan.s, plan.t, plan.u, plan.v, plan.L
    lib = emb.scene.scene.lib
    w = np.asarray(direction, dtype=np.float64)
    offsets = plan.offsets or (np.empty(0, np.float32),) * 4
    grid = (s.astype(np.float32), t.astype(np.float32), offsets, np.float32(spacing),
            u.astype(np.float32), v.astype(np.float32), (L * w).astype(np.float32))
    first, size = _head(emb, coherent)
    head = first + (grid, (-w).astype(np.float32)[None, :]) + size
    b = bins
    if receiver is not None:
        wr = np.asarray(receiver[0], np.float64)
        coating = _coating(b, w, wr, receiver[2])
        return _fused_kernels.cast_bin_bistatic(
            *head, b.plane_d, b.face_normals, b.w, b.start, b.edges, b.ignore_back, b.out,
            b.weight, lib.occluded[lib.width], wr, float(receiver[1]), b.stamp, b.tag,
            coating, receiver[3], scratch("bistatic", lib.width, t.size))
    if emb.raster is not None and closed is not None:
        return draw_bin_grid(emb, grid, w, bins, lib.width, closed, smooth)
    if smooth is not None:
        return _fused_kernels.cast_bin_smooth(*head, *b[:11], b.footprint, smooth[0],
                                              float(smooth[1]),
                                              scratch("smooth", lib.width, t.size))
    return _fused_kernels.cast_bin_flat(*head, *bins, scratch("flat", lib.width, t.size))


def draw_bin_grid(emb, grid, w, bins, width, closed, smooth=None):
    """:func:`cast_bin_grid` of a monostatic view on the "raster" backend: its first hits
    drawn into a depth buffer (:func:`._raster_kernels.raster_bin_flat`, with ``smooth``
    normals ``raster_bin_smooth``), then weighed and binned as the packet loop bins them,
    a packet tile's rows at a time; a view
    of more than :data:`DRAWN_RAYS` rays in blocks of rows, each drawn on its own.

    Parameters
    ----------
    emb : EmbreeScene
        A "raster" scene (``emb.raster`` its vertices at unit size and faces).
    grid : tuple
        The packet loop's ``grid``: (s, t, offsets, sp, u, v, lw), float32.
    w : (3,) numpy.ndarray
        The view direction.
    bins : FlatBins
        As :func:`cast_bin_grid`'s.
    width : int
        The packet width (the band's rows: a tile's).
    closed : (n_faces,) uint8 numpy.ndarray
        1 where a face's part is closed with outward normals
        (``Geometry.closed`` of :mod:`meshladar.raytrace.embree`): its faces turned away from
        the view are not drawn.
    smooth : tuple, optional
        As :func:`cast_bin_grid`'s (None: flat normals).

    Returns
    -------
    (int, int)
        The back-face hits and the rays.
    """
    vertices, faces = emb.raster
    proj = np.empty((len(vertices), 3))      # elementwise (no BLAS): a vertex's numbers
    for k, axis in enumerate((grid[4], grid[5], w)):      # are the same in every face
        proj[:, k] = dot(vertices * emb.scale, np.asarray(axis, np.float64))
    normals_w = dot(bins.face_normals, np.asarray(w, np.float64))
    rows = embree4_kernels.tile_shape.py_func(width)[0]
    band = scratch("flat" if smooth is None else "smooth", width, grid[1].size)[1][3]
    s, t, (xi, ku, kv, eta) = grid[0], grid[1], grid[2]
    step = max(rows, DRAWN_RAYS // max(t.size, 1) // rows * rows)
    back = 0
    for a0 in range(0, s.size, step):              # at most DRAWN_RAYS rays a buffer
        part = (s[a0:a0 + step], t, (xi[a0:a0 + step], ku, kv[a0:a0 + step], eta)
                if xi.size else grid[2]) + grid[3:]
        head = (proj, faces, normals_w, closed, part, depth_buffer(part[0].size * t.size),
                rows)
        back += (_raster_kernels.raster_bin_flat(*head, *bins[:14], bins.footprint, band)
                 if smooth is None else
                 _raster_kernels.raster_bin_smooth(*head, *bins[:11], bins.footprint,
                                                   smooth[0], float(smooth[1]), band))[0]
    return back, s.size * t.size
