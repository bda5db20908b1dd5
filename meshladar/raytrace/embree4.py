"""The packet backend: coherent ray packets cast with the Embree 4 library that the embreex
wheel ships, called through ctypes (:mod:`.embree4_ctypes`, the layouts and entry points)
from numba-jitted loops that release the GIL (:mod:`.embree4_kernels`).

No compiler is needed: ``pip install meshladar`` brings embreex, whose wheel carries the
library. :func:`library` finds it (``MESHLADAR_EMBREE4`` overrides the path), checks that it
is Embree 4, reads the packet width the CPU runs natively (16 with AVX-512, 8 with AVX2)
and checks that it answers packets of that width as these layouts expect. Scenes share their
buffers with numpy (no per-element copy). Hits equal embreex's (the same library, the same
robust intersection) except, rarely, which of two triangles a ray exactly along their
shared edge reports. The loop that casts, weighs and bins a view in one pass is the weigh
stage's (:mod:`meshladar.weighing.fused`).
"""

from __future__ import annotations

import threading
from typing import NamedTuple

import numpy as np

from .embree4_ctypes import (EmbreeLib, RTC_BUFFER_TYPE_INDEX, RTC_BUFFER_TYPE_VERTEX,
                             RTC_FORMAT_FLOAT3, RTC_FORMAT_UINT3, RTC_GEOMETRY_TYPE_TRIANGLE,
                             RTC_RAY_QUERY_FLAG_COHERENT, RTC_RAY_QUERY_FLAG_INCOHERENT,
                             RTC_SCENE_FLAG_ROBUST, _ALIGN, _ARGS_OFF, _CTX_OFF, _DIR_Z,
                             _GEOMID, _ID, _INSTID, _MASK, _ORG_X, _ORG_Y, _ORG_Z, _PRIMID,
                             _TFAR, _U, _V, _VALID_OFF, _WS_BYTES, library_candidates,
                             query_flags)
# the compiled packet loops, importable from here as before (the fused loop reads the
# building blocks workspace, init_args and load_packet)
from .embree4_kernels import (cast_grid, cast_single, init_args, load_packet, occluded_grid,
                              workspace)

__all__ = ["library", "available", "PacketGeometry", "cast_grid", "occluded_grid", "EmbreeLib",
           "library_candidates", "RTC_RAY_QUERY_FLAG_COHERENT", "RTC_RAY_QUERY_FLAG_INCOHERENT"]


def _self_test(lib):
    """Check the struct layouts this module relies on against the library itself, once, at
    the width it will run (``lib.width``): one triangle (z = 0, corners (0,0), (1,0),
    (0,1)) and one packet whose lanes alternate between rays that hit it at known
    (t, u, v) and rays that miss, its last lane masked off, then the occlusion query. The
    packets are filled and read here in numpy and passed to the library through ctypes,
    so no compiled loop is loaded (or compiled, on a first run) for the check. A library
    built with other layouts fails here, not later."""
    w = lib.width
    v = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], np.float32)
    scene = PacketGeometry(v, np.array([[0, 1, 2]], np.uint32), lib=lib)
    try:
        k = np.arange(w)
        active = k < w - 1                              # the last lane is masked off
        hit = (k % 2 == 0) & active                     # odd lanes miss
        i32, base = _packet(w, np.where(k % 2 == 0, 0.25, 2.0), 0.125, 2.0 + k, active)
        lib.intersect[w](base + _VALID_OFF, scene.handle, base, base + _ARGS_OFF)
        field = lambda f: i32[f * w:(f + 1) * w]       # noqa: E731 - one lane per ray
        tfar, u, uv = (field(f).view(np.float32) for f in (_TFAR, _U, _V))
        hits = (np.array_equal(field(_PRIMID), np.where(hit, 0, -1))
                and np.allclose(tfar[hit], 2.0 + k[hit]) and np.all(np.isinf(tfar[~hit]))
                and np.allclose(u[hit], 0.25) and np.allclose(uv[hit], 0.125))
        i32, base = _packet(w, np.where(k % 2 == 0, 0.25, 2.0), 0.125, 2.0 + k, active)
        lib.occluded[w](base + _VALID_OFF, scene.handle, base, base + _ARGS_OFF)
        blocked = np.isneginf(field(_TFAR).view(np.float32))
        if not (hits and np.array_equal(blocked, hit)):
            raise OSError(f"{lib.path}: Embree {'.'.join(map(str, lib.version))} does not "
                          f"answer a {w}-wide packet as the layouts this module uses "
                          "expect (a build with other options?)")
        got, miss = _single_ray(lib, scene, 0.25), _single_ray(lib, scene, 2.0)
        if not (miss == (-1,) and len(got) == 4 and got[0] == 0
                and np.allclose(got[1:], (2.0, 0.25, 0.125))):
            raise OSError(f"{lib.path}: Embree {'.'.join(map(str, lib.version))} does not "
                          "answer a single ray (rtcIntersect1) as the layouts this module "
                          "uses expect (a build with other options?)")
    finally:
        scene.release()


def _single_ray(lib, scene, x):
    """The self-test's triangle hit by one ray from (x, 0.125, 2) along −z through
    ``lib.intersect1`` (RTCRayHit: RTCRayHitW's layout at W = 1): (primID, tfar, u, v), or
    (-1,) on a miss."""
    i32, base = _packet(1, x, 0.125, 2.0, np.array([True]))
    lib.intersect1(scene.handle, base, base + _ARGS_OFF)
    f32 = i32.view(np.float32)
    if i32[_PRIMID] == -1:
        return (-1,)
    return (int(i32[_PRIMID]), float(f32[_TFAR]), float(f32[_U]), float(f32[_V]))


def _packet(w, x, y, z, active):
    """A zeroed, 64-aligned workspace holding one w-wide packet of rays from (x, y, z)
    along -z (lanes where ``active``), its valid mask and its query arguments (the
    layout the compiled loops fill, :func:`.embree4_kernels.load_packet`): (the int32 view,
    its address)."""
    raw = np.zeros((_WS_BYTES + _ALIGN) // 4, np.int32)
    skip = (-raw.ctypes.data % _ALIGN) // 4
    i32 = raw[skip:skip + _WS_BYTES // 4]
    f32, base = i32.view(np.float32), i32.ctypes.data
    for f, value in ((_ORG_X, x), (_ORG_Y, y), (_ORG_Z, z), (_DIR_Z, -1.0), (_TFAR, np.inf)):
        f32[f * w:(f + 1) * w] = value
    for f, value in ((_MASK, -1), (_ID, np.arange(w)), (_PRIMID, -1), (_GEOMID, -1),
                     (_INSTID, -1)):
        i32[f * w:(f + 1) * w] = value
    i32[_VALID_OFF // 4:_VALID_OFF // 4 + w] = np.where(active, -1, 0)
    i32[_CTX_OFF // 4:_CTX_OFF // 4 + 2] = -1          # instID, instPrimID: invalid
    i32[_ARGS_OFF // 4] = RTC_RAY_QUERY_FLAG_COHERENT   # flags; feature mask: all
    i32[_ARGS_OFF // 4 + 1] = -1
    i32[_ARGS_OFF // 4 + 2:_ARGS_OFF // 4 + 4].view(np.int64)[0] = base + _CTX_OFF
    return i32, base


_LIB = None
_LIB_ERROR = None
_LIB_LOCK = threading.Lock()


def library():
    """The process-wide EmbreeLib (loaded and its device created on first use); raises
    OSError, with the reason, when it cannot be loaded (once per process: the reason is
    kept).

    The first call loads the library (:class:`EmbreeLib`: ``MESHLADAR_EMBREE4``, else the
    copy embreex ships) and checks it against the packet layouts this module uses, with one
    triangle and one packet of the width it runs natively (hits, barycentrics, misses, a
    masked lane, occlusion) and one single ray (``rtcIntersect1``), filled in numpy and
    passed through ctypes.
    Thread-safe.

    Returns
    -------
    EmbreeLib
        The same object for every call in the process.

    Raises
    ------
    OSError
        When no library is found, it is not Embree 4, a symbol or its device is missing,
        or it does not answer packets as the layouts expect; every later call raises
        again with the first reason, without retrying.
    """
    with _LIB_LOCK:
        return _load()


def _load():
    global _LIB, _LIB_ERROR
    if _LIB is None:
        if _LIB_ERROR is not None:
            raise OSError(_LIB_ERROR)
        try:
            lib = EmbreeLib()
            _self_test(lib)
            _LIB = lib
        except (OSError, AttributeError) as exc:      # missing file, symbol or device
            _LIB_ERROR = str(exc) or type(exc).__name__
            raise OSError(_LIB_ERROR) from exc
    return _LIB


def available():
    """(True, library path) when the packet backend loads; else (False, the reason).

    Returns
    -------
    tuple of (bool, str)
        ``(True, path)`` of the library :func:`library` loaded, or ``(False, reason)``
        with the OSError's message; never raises for a library that cannot load.
    """
    try:
        return True, library().path
    except OSError as exc:
        return False, str(exc)


# ------------------------------------------------------------------------------- the scene


class GridHits(NamedTuple):
    """:meth:`PacketGeometry.cast_grid`'s first hits with barycentrics: primitive (int32,
    -1 on a miss), distance (float32, inf on a miss) and the barycentrics u, v."""

    prim: np.ndarray
    tfar: np.ndarray
    u: np.ndarray
    v: np.ndarray


class PacketGeometry:
    """A committed Embree scene of one triangle mesh whose buffers are shared (zero-copy)
    numpy arrays: the arrays are kept alive here as long as the scene is.

    The vertices are copied once into a float32 buffer with one padding row (Embree may
    read the last vertex with a 16-byte load) and the faces are kept as a contiguous uint32
    array; Embree reads both in place. The scene is built (its BVH) at construction; as a
    context manager it is released on exit.

    Parameters
    ----------
    vertices : (n, 3) array_like
        The triangles' corners, stored as float32.
    faces : (m, 3) array_like of int
        Each triangle's three vertex indices, each in [0, n).
    robust : bool
        Embree's robust mode (``RTC_SCENE_FLAG_ROBUST``: watertight ray-triangle tests),
        default True.
    quality : int, optional
        Embree's BVH build quality (``RTC_BUILD_QUALITY_LOW``, ``_MEDIUM``, ``_HIGH`` =
        0, 1, 2 in :mod:`meshladar.raytrace.embree4_ctypes`); None (default) leaves
        Embree's default.
    lib : EmbreeLib, optional
        The library to build with (default :func:`library`'s).

    Attributes
    ----------
    lib : EmbreeLib
        The library the scene was built with.
    handle : int
        The RTCScene handle; 0 once released.
    geom_id : int
        The triangle geometry's id in the scene.
    n_faces : int
        m, the number of triangles.

    Raises
    ------
    ValueError
        When ``vertices`` or ``faces`` is not (k, 3), or a face index lies outside
        [0, n).
    OSError
        When ``lib`` is None and the library cannot be loaded (:func:`library`).
    RuntimeError
        When Embree reports an error building the scene.
    """

    def __init__(self, vertices, faces, *, robust=True, quality=None, lib=None):
        self.lib = lib = lib or library()
        v = np.asarray(vertices)
        f = np.asarray(faces)
        if v.ndim != 2 or v.shape[1] != 3 or f.ndim != 2 or f.shape[1] != 3:
            raise ValueError("vertices and faces must be (n, 3)")
        if len(f) and (f.min() < 0 or f.max() >= len(v)):
            raise ValueError("face index out of range")
        # one padding row: Embree reads the last vertex with a 16-byte load
        self._vertices = np.zeros((len(v) + 1, 3), np.float32)
        self._vertices[:-1] = v
        self._faces = np.ascontiguousarray(f, dtype=np.uint32)
        self.n_faces = len(f)
        dev = lib.device
        self.handle = lib.rtcNewScene(dev)
        geom = lib.rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE)
        lib.rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                       self._vertices.ctypes.data, 0, 12, len(v))
        lib.rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                       self._faces.ctypes.data, 0, 12, len(f))
        lib.rtcCommitGeometry(geom)
        self.geom_id = lib.rtcAttachGeometry(self.handle, geom)
        lib.rtcReleaseGeometry(geom)             # the scene holds the reference now
        if robust:
            lib.rtcSetSceneFlags(self.handle, RTC_SCENE_FLAG_ROBUST)
        if quality is not None:
            lib.rtcSetSceneBuildQuality(self.handle, quality)
        lib.rtcCommitScene(self.handle)          # BVH build (TBB threads), GIL held
        lib.check("scene build")

    def release(self):
        """Release the Embree scene and drop the shared buffers; a released scene's casts
        raise RuntimeError. Safe to call twice; also called on garbage collection."""
        if getattr(self, "handle", 0):
            self.lib.rtcReleaseScene(self.handle)
            self.handle = 0
            self._vertices = self._faces = None

    __del__ = release

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.release()

    def _live(self):
        if not self.handle:
            raise RuntimeError("scene released")
        return self.handle

    def live(self):
        """The scene's handle for a compiled loop; RuntimeError once released.

        Returns
        -------
        int
            The RTCScene handle (a pointer as an integer).

        Raises
        ------
        RuntimeError
            When the scene has been released.
        """
        return self._live()

    def cast_grid(self, origins, direction, *, width=None, coherent=True, tmax=np.inf,
                  barycentrics=False, columns=0, single=False):
        """First hits of rays from ``origins`` (n, 3) all along ``direction`` (3,) (or each
        along its own, (n, 3): coherent when neighbours are nearly parallel):
        ``prim`` (int32, -1 on a miss), ``tfar`` (float32, inf on a miss; distances in
        units of |direction|) and, with ``barycentrics``, the hits' ``u`` and ``v``
        (float32; then a :class:`GridHits`). Releases the GIL: callable from several
        threads.

        Parameters
        ----------
        origins : (n, 3) array_like
            Ray origins, cast as float32.
        direction : (3,) or (n, 3) array_like
            One direction for every ray, or one per ray, cast as float32; need not be unit
            length (distances are in units of its length).
        width : int, optional
            Packet width, 4, 8 or 16 (the library's ``rtcIntersect4/8/16``); default (None
            or 0) the CPU's native width, ``lib.width``. Another value raises KeyError.
        coherent : bool
            Embree's coherent query flag (neighbouring rays nearly parallel, the grids'
            case), default True; False asks for incoherent rays.
        tmax : float
            Each ray's far limit (cast as float32), in units of |direction|; hits beyond it
            are not reported. Default inf. Rays start at t = 0.
        barycentrics : bool
            Also return the hits' barycentrics (default False).
        columns : int
            0 (default): packets of consecutive rays. Else the rays are a grid's, row-major
            in rows of ``columns`` rays (n a multiple of it), and each packet is a tile of
            it (4 × 4 rays at width 16, 2 × 4 at 8, 2 × 2 at 4): the same hits, found
            faster, as a tile's rays share their path through the BVH.
        single : bool
            Cast the rays one at a time (``rtcIntersect1``; ``width`` and ``columns``
            unused): faster where a grid is sparser than its faces, whose packets' rays
            part at once (:attr:`meshladar.raytrace.plan.TracePlan.coherent`). Default
            False.

        Returns
        -------
        tuple of (prim, tfar) or GridHits
            ``prim`` (n,) int32: the hit face's index, -1 on a miss; ``tfar`` (n,)
            float32: the hit distance, inf on a miss. With ``barycentrics``, a
            :class:`GridHits` that adds ``u`` and ``v`` (n,) float32 (meaningful on hits
            only).

        Raises
        ------
        ValueError
            When ``direction`` is neither (3,) nor (n, 3), or ``columns`` does not divide
            the rays into rows.
        RuntimeError
            When the scene has been released.
        """
        w = width or self.lib.width
        o = np.ascontiguousarray(origins, dtype=np.float32)
        d = _directions(direction, len(o))
        n = len(o)
        if columns < 0 or (columns and n % columns):
            raise ValueError(f"columns must be 0 or the length of the grid's rows (a divisor "
                             f"of its {n} rays); got {columns}")
        prim = np.empty(n, np.int32)
        tfar = np.empty(n, np.float32)
        m = n if barycentrics else 0
        u, v = np.empty(m, np.float32), np.empty(m, np.float32)
        flags = query_flags(coherent and not single)
        if single:
            cast_single(self.lib.intersect1, self._live(), o, d, np.float32(tmax), flags,
                        prim, tfar, u, v)
        else:
            cast_grid(self.lib.intersect[w], self._live(), o, d, np.float32(tmax), w, flags,
                      prim, tfar, u, v, int(columns))
        return GridHits(prim, tfar, u, v) if barycentrics else (prim, tfar)

    def occluded_grid(self, origins, direction, *, tmax=np.inf, width=None, coherent=True):
        """Whether each ray hits anything within ``tmax``: bool (n,).

        Parameters
        ----------
        origins : (n, 3) array_like
            Ray origins, cast as float32.
        direction : (3,) or (n, 3) array_like
            One direction for every ray, or one per ray, cast as float32.
        tmax : float
            Each ray's far limit (cast as float32), in units of |direction|; default inf.
        width : int, optional
            Packet width, 4, 8 or 16; default (None or 0) the native ``lib.width``.
        coherent : bool
            Embree's coherent query flag, default True.

        Returns
        -------
        (n,) bool numpy.ndarray
            True where the ray meets a triangle between t = 0 and ``tmax``.

        Raises
        ------
        ValueError
            When ``direction`` is neither (3,) nor (n, 3).
        RuntimeError
            When the scene has been released.
        """
        w = width or self.lib.width
        o = np.ascontiguousarray(origins, dtype=np.float32)
        d = _directions(direction, len(o))
        out = np.empty(len(o), np.bool_)
        flags = query_flags(coherent)
        occluded_grid(self.lib.occluded[w], self._live(), o, d, np.float32(tmax), w,
                      flags, out)
        return out


def _directions(direction, n):
    """One direction (3,) or one per ray (n, 3), as the (k, 3) float32 the kernels read."""
    d = np.ascontiguousarray(direction, dtype=np.float32)
    d = d.reshape(1, 3) if d.size == 3 else d
    if d.ndim != 2 or d.shape[1] != 3 or d.shape[0] not in (1, n):
        raise ValueError(f"direction must be (3,) or one per ray ({n}, 3); got shape "
                         f"{np.shape(direction)}")
    return d
