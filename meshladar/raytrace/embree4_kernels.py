"""The packet backend's compiled loops: numba-jitted, GIL-free loops that fill Embree 4's
ray packets (:mod:`.embree4_ctypes`' layouts) in an aligned workspace and call the library's
``rtcIntersect``/``rtcOccluded`` entry points through ctypes.

:func:`cast_grid` and :func:`occluded_grid` cast every ray of a grid in packets of the
library's width, :func:`cast_single` one ray at a time
(:meth:`meshladar.raytrace.embree4.PacketGeometry.cast_grid` and ``occluded_grid`` call
them). Their building blocks, :func:`workspace`, :func:`init_args`,
:func:`load_packet` and :func:`tile_shape`, are public for the compiled loops beside other
stages (the scanner's pulse loop; the weigh stage's cast-weigh-bin loops,
:mod:`meshladar.weighing.fused`, take a workspace their caller made in numpy,
:func:`meshladar.raytrace.embree4_ctypes.new_workspace`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .embree4_ctypes import (_ALIGN, _ARGS_OFF, _CTX_OFF, _DIR_X, _DIR_Y, _DIR_Z, _FLAGS,
                             _GEOMID, _ID, _INSTID, _MASK, _ORG_X, _ORG_Y, _ORG_Z, _PRIMID,
                             _TFAR, _TIME, _TNEAR, _U, _V, _VALID_OFF, _WS_BYTES)

__all__ = ["cast_grid", "cast_single", "occluded_grid"]


@njit(cache=True, nogil=True)
def workspace():
    """A zeroed workspace whose first byte is 64-aligned: returns (int32 view, float32 view,
    int64 view, base address).  Over-allocated by 64 bytes and offset."""
    raw = np.zeros((_WS_BYTES + _ALIGN) // 8, np.int64)
    addr = raw.ctypes.data
    skip = ((_ALIGN - addr % _ALIGN) % _ALIGN) // 8        # int64 storage: addr % 8 == 0
    ws = raw[skip:skip + _WS_BYTES // 8]
    return ws.view(np.int32), ws.view(np.float32), ws, addr + skip * 8


@njit(cache=True, nogil=True, inline="always")
def init_args(i32, i64, base, flags):
    """rtcInitRayQueryContext + rtcInitIntersectArguments (inline in the headers), with
    flags and the context pointer set.  Same layout for RTCOccludedArguments."""
    c = _CTX_OFF // 4
    i32[c + 0] = -1                      # instID[0]     = RTC_INVALID_GEOMETRY_ID
    i32[c + 1] = -1                      # instPrimID[0] = RTC_INVALID_GEOMETRY_ID
    a = _ARGS_OFF // 4
    i32[a + 0] = flags                   # flags
    i32[a + 1] = -1                      # feature_mask = RTC_FEATURE_FLAG_ALL
    a8 = _ARGS_OFF // 8
    i64[a8 + 1] = base + _CTX_OFF        # context
    i64[a8 + 2] = 0                      # filter
    i64[a8 + 3] = 0                      # intersect / occluded
    i64[a8 + 4] = 0                      # [minWidthDistanceFactor] + padding


@njit(cache=True, nogil=True, inline="always")
def load_packet(f32, i32, o, d, tmax, start, n, w):
    """Fill the RTCRayW fields, the valid mask and the hit's invalid ids for rays
    start..start+w (masked past n); ``d`` (1, 3) is every ray's direction, or (n, 3) one
    per ray."""
    v = _VALID_OFF // 4
    each = d.shape[0] > 1
    for j in range(w):
        r = start + j
        ok = r < n
        if not ok:
            r = start                    # harmless finite data in inactive lanes
        k = r if each else 0
        f32[_ORG_X * w + j] = o[r, 0]
        f32[_ORG_Y * w + j] = o[r, 1]
        f32[_ORG_Z * w + j] = o[r, 2]
        f32[_TNEAR * w + j] = 0.0
        f32[_DIR_X * w + j] = d[k, 0]
        f32[_DIR_Y * w + j] = d[k, 1]
        f32[_DIR_Z * w + j] = d[k, 2]
        f32[_TIME * w + j] = 0.0
        f32[_TFAR * w + j] = tmax
        i32[_MASK * w + j] = -1
        i32[_ID * w + j] = j
        i32[_FLAGS * w + j] = 0
        i32[v + j] = -1 if ok else 0
        i32[_PRIMID * w + j] = -1        # RTCHitW: geomID/primID invalid (the occlusion
        i32[_GEOMID * w + j] = -1        # query ignores these; they lie inside the
        i32[_INSTID * w + j] = -1        # workspace's reserve either way)


@njit(cache=True, nogil=True, inline="always")
def tile_shape(w):
    """(rows, columns) of a packet's tile of a ray grid for packet width ``w``: 4 × 4 at
    16, 2 × 4 at 8, 2 × 2 at 4. Square tiles keep a packet's rays together on the target
    (one BVH path serves them all), where a 1 × w row spans w ray spacings."""
    if w == 16:
        return 4, 4
    if w == 8:
        return 2, 4
    return 2, 2


@njit(cache=True, nogil=True)
def _packet_rays(p, n, cols, w, idx):
    """The ray indices of packet ``p`` into idx[:m]; returns m. ``cols`` 0: rays p·w.. in
    scan order; else the p-th tile (:func:`tile_shape`, row-major over tiles) of a grid of
    rows ``cols`` rays long (row-major rays), fewer lanes at its edges."""
    if cols == 0:
        m = min(w, n - p * w)
        for j in range(m):
            idx[j] = p * w + j
        return m
    th, tw = tile_shape(w)
    across = (cols + tw - 1) // tw
    a0, b0 = (p // across) * th, (p % across) * tw
    m = 0
    for a in range(a0, min(a0 + th, n // cols)):
        for b in range(b0, min(b0 + tw, cols)):
            idx[m] = a * cols + b
            m += 1
    return m


@njit(cache=True, nogil=True)
def _packets(n, cols, w):
    """The packets that cover n rays (``cols``: see :func:`_packet_rays`)."""
    if cols == 0:
        return (n + w - 1) // w
    th, tw = tile_shape(w)
    return ((n // cols + th - 1) // th) * ((cols + tw - 1) // tw)


@njit(cache=True, nogil=True)
def _gather(o, d, idx, m, sub, sub_d):
    """The packet's origins (and per-ray directions) into ``sub`` (``sub_d``)."""
    for j in range(m):
        for k in range(3):
            sub[j, k] = o[idx[j], k]
    if d.shape[0] > 1:
        for j in range(m):
            for k in range(3):
                sub_d[j, k] = d[idx[j], k]
    else:
        for k in range(3):
            sub_d[0, k] = d[0, k]


@njit(cache=True, nogil=True)
def cast_grid(fn, scene, o, d, tmax, w, flags, prim, tfar, u, v, cols):
    """rtcIntersectW over rays o[i] + t d, in packets of w: in scan order (``cols`` 0;
    the tail masked), or in tiles of a grid whose rows are ``cols`` rays long.
    ``fn`` is the ctypes rtcIntersect{w} (an argument, not a global: cacheable). ``u`` and
    ``v`` receive the barycentrics when they have one entry per ray (else they are empty).

    Parameters
    ----------
    fn : ctypes function
        ``EmbreeLib.intersect[w]``, the library's rtcIntersect4, 8 or 16 matching ``w``.
    scene : int
        The committed scene's handle (:meth:`meshladar.raytrace.embree4.PacketGeometry.live`).
    o : (n, 3) float32 numpy.ndarray
        Ray origins, C-contiguous.
    d : (1, 3) or (n, 3) float32 numpy.ndarray
        One direction for every ray, or one per ray.
    tmax : numpy.float32
        Each ray's far limit, in units of |d|.
    w : int
        Packet width, 4, 8 or 16, as ``fn``.
    flags : int
        Ray query flags (``RTC_RAY_QUERY_FLAG_COHERENT`` or ``_INCOHERENT``).
    prim : (n,) int32 numpy.ndarray
        Output: the hit face's index, -1 on a miss.
    tfar : (n,) float32 numpy.ndarray
        Output: the hit distance, inf on a miss.
    u, v : (n,) or (0,) float32 numpy.ndarray
        Output: the barycentrics, written only when they have n entries.
    cols : int
        0: packets of w consecutive rays. Else the rays are a grid, row-major, rows of
        ``cols`` rays (n a multiple of it), cast in tiles (:func:`tile_shape`).
    """
    i32, f32, i64, base = workspace()
    init_args(i32, i64, base, flags)
    n = o.shape[0]
    idx = np.empty(w, np.int64)
    sub = np.empty((w, 3), np.float32)
    sub_d = np.empty((w if d.shape[0] > 1 else 1, 3), np.float32)
    for p in range(_packets(n, cols, w)):
        m = _packet_rays(p, n, cols, w, idx)
        _gather(o, d, idx, m, sub, sub_d)
        load_packet(f32, i32, sub, sub_d, tmax, 0, m, w)
        fn(base + _VALID_OFF, scene, base, base + _ARGS_OFF)
        for j in range(m):
            r = idx[j]
            if i32[_GEOMID * w + j] == -1:
                prim[r] = -1
                tfar[r] = np.inf
            else:
                prim[r] = i32[_PRIMID * w + j]
                tfar[r] = f32[_TFAR * w + j]
            if u.shape[0] == n:
                u[r] = f32[_U * w + j]
                v[r] = f32[_V * w + j]


@njit(cache=True, nogil=True)
def cast_single(fn1, scene, o, d, tmax, flags, prim, tfar, u, v):
    """rtcIntersect1 over rays o[i] + t d one at a time: what a grid sparser than its faces
    is cast with (its packets' rays part at once; RTCRayHit is RTCRayHitW's layout at
    W = 1, so :func:`load_packet` fills it). ``fn1`` is ``EmbreeLib.intersect1``; the other
    arguments as :func:`cast_grid`'s."""
    i32, f32, i64, base = workspace()
    init_args(i32, i64, base, flags)
    n = o.shape[0]
    for r in range(n):
        load_packet(f32, i32, o, d, tmax, r, n, 1)
        fn1(scene, base, base + _ARGS_OFF)
        if i32[_GEOMID] == -1:
            prim[r] = -1
            tfar[r] = np.inf
        else:
            prim[r] = i32[_PRIMID]
            tfar[r] = f32[_TFAR]
        if u.shape[0] == n:
            u[r] = f32[_U]
            v[r] = f32[_V]


@njit(cache=True, nogil=True)
def occluded_grid(fn, scene, o, d, tmax, w, flags, out):
    """rtcOccludedW over the same packets: out[i] = the ray is blocked within tmax
    (Embree sets tfar = -inf on occluded lanes).

    Parameters
    ----------
    fn : ctypes function
        ``EmbreeLib.occluded[w]``, the library's rtcOccluded4, 8 or 16 matching ``w``.
    scene : int
        The committed scene's handle (:meth:`meshladar.raytrace.embree4.PacketGeometry.live`).
    o : (n, 3) float32 numpy.ndarray
        Ray origins, C-contiguous.
    d : (1, 3) or (n, 3) float32 numpy.ndarray
        One direction for every ray, or one per ray.
    tmax : numpy.float32
        Each ray's far limit, in units of |d|.
    w : int
        Packet width, 4, 8 or 16, as ``fn``.
    flags : int
        Ray query flags (``RTC_RAY_QUERY_FLAG_COHERENT`` or ``_INCOHERENT``).
    out : (n,) bool numpy.ndarray
        Output: True where the ray is blocked.
    """
    i32, f32, i64, base = workspace()
    init_args(i32, i64, base, flags)
    n = o.shape[0]
    for start in range(0, n, w):
        load_packet(f32, i32, o, d, tmax, start, n, w)
        fn(base + _VALID_OFF, scene, base, base + _ARGS_OFF)
        m = min(w, n - start)
        for j in range(m):
            out[start + j] = f32[_TFAR * w + j] == -np.inf

