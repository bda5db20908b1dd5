"""The fused loops' scratch buffers (:mod:`._fused_kernels`), made in numpy and kept per
thread, so that the compiled loops allocate nothing: numba compiles no allocation of its
own for them on a first run (a one-view ``simulate`` of an 82k-triangle STL, first run
after an install: 3.14–3.24 s against 4.06–4.11 s), and a run of many small views makes
its buffers once per thread instead of once per view.

Each buffer holds one band of a grid's rows (a packet tile's rows × the row's rays); a
thread's buffers grow when a view's rows are longer than any before and are reused
otherwise (the loops read the first rows × columns slots only). Every slot a loop reads
it has written for the same band first, so reused buffers give the same numbers as new
ones.
"""

from __future__ import annotations

import threading
from typing import TYPE_CHECKING

import numpy as np

from .._lazy import deferred_module
from ..raytrace.embree4_ctypes import new_workspace

if TYPE_CHECKING:            # the layers' check sees the edge; numba loads at first use
    from ..raytrace import embree4_kernels
else:
    embree4_kernels = deferred_module("meshladar.raytrace.embree4_kernels")

__all__ = ["scratch", "depth_buffer"]

_HELD = threading.local()


def _make(kind, w, size):
    """New buffers of ``kind`` for packets of ``w`` lanes and bands of ``size`` slots."""
    f32, i64 = np.float32, np.int64
    lanes = (np.empty((w, 3), f32), np.empty((w, 3), f32), np.empty(w, i64))
    if kind == "sensor":
        band = (np.empty(size, np.int32), np.empty(size), np.empty(size, f32),
                np.empty(size, f32), np.empty((size, 3)), np.empty(size))
        return new_workspace(), lanes, band
    nb = size if kind == "smooth" else 0
    band = (np.empty(size, np.int32), np.empty(size, f32), np.empty((size, 3), f32),
            np.empty(nb, f32), np.empty(nb, f32))
    out = (new_workspace(), lanes + (band,))
    if kind == "bistatic":
        hits = (np.empty(size, np.int32), np.empty(size, f32), np.empty((size, 3), f32),
                np.empty(size, i64))
        spare = (np.zeros(size, np.bool_), np.empty((size, 3), f32), np.empty(size, i64),
                 np.empty((1, 3), f32), np.zeros(size, np.bool_))
        out += (hits, spare)
    return out


def scratch(kind, w, columns):
    """This thread's buffers for a fused loop of ``kind`` ("flat", "smooth", "bistatic"
    or "sensor") casting packets of ``w`` lanes in tiles
    (:func:`meshladar.raytrace.embree4_kernels.tile_shape`) over grid rows of ``columns``
    rays.

    Parameters
    ----------
    kind : str
        The loop: "flat" and "smooth" (:func:`._fused_kernels.cast_bin_flat`,
        ``cast_bin_smooth``: the workspace and (lanes as built, lanes as cast, slots,
        band)), "bistatic" (those and the occlusion pass's hits and spare arrays) or
        "sensor" (the workspace, (lanes, directions, slots) and the sensor's band).
    w : int
        The packet width.
    columns : int
        The grid's rays a row.

    Returns
    -------
    tuple
        The loop's ``scratch`` argument, its bands at least a tile's rows × ``columns``
        slots.
    """
    held = getattr(_HELD, "buffers", None)
    if held is None:
        held = _HELD.buffers = {}
    size = embree4_kernels.tile_shape.py_func(w)[0] * columns   # (its Python: no compile)
    have = held.get((kind, w))
    if have is None or have[0] < size:
        size = max(size, 1) if have is None else max(size, have[0] + have[0] // 4)
        have = held[(kind, w)] = (size, _make(kind, w, size))
    return have[1]


def depth_buffer(size):
    """This thread's depth buffer for a view of ``size`` rays
    (:func:`._raster_kernels.zbuffer`): (faces (size,) int32, heights (size,) float64),
    grown as :func:`scratch`'s bands are; every slot is written before it is read.

    Parameters
    ----------
    size : int
        The view's rays.

    Returns
    -------
    tuple of numpy.ndarray
    """
    held = getattr(_HELD, "buffers", None)
    if held is None:
        held = _HELD.buffers = {}
    have = held.get("depth")
    if have is None or have[0] < size:
        n = max(size, 1) if have is None else max(size, have[0] + have[0] // 4)
        have = held["depth"] = (n, (np.empty(n, np.int32), np.empty(n)))
    return have[1][0][:size], have[1][1][:size]
