"""The packet backend: coherent ray packets cast with the Embree 4 library that the embreex
wheel ships, called through ctypes from numba-jitted loops that release the GIL.

No compiler is needed: ``pip install meshladar`` brings embreex, whose wheel carries the
library. :func:`library` finds it (``MESHLADAR_EMBREE4`` overrides the path), checks that it
is Embree 4, and reads the packet width the CPU runs natively (16 with AVX-512, 8 with AVX2:
a non-native width loops over single rays inside Embree). Scenes share their buffers with
numpy (no per-element copy). Hits equal embreex's (the same library, the same robust
intersection) except, rarely, which of two triangles a ray exactly along their shared edge
reports.

Layouts below are copied from Embree v4.4.0 (tag v4.4.0 of github.com/RenderKit/embree,
the version the embreex 4.4.0.post1 wheel bundles: package/embree.json downloads the
official embree-4.4.0 release binaries).  Those binaries are built with the CMake
defaults (CMakeLists.txt:211-212, 226):

    RTC_MAX_INSTANCE_LEVEL_COUNT = 1      (EMBREE_MAX_INSTANCE_LEVEL_COUNT 1)
    RTC_GEOMETRY_INSTANCE_ARRAY  defined  (EMBREE_GEOMETRY_INSTANCE_ARRAY ON)
    RTC_MIN_WIDTH                = 0      (EMBREE_MIN_WIDTH OFF)

Every field this module *reads* (primID, geomID, tfar) sits before the config-dependent
ones, and every struct is over-allocated and zeroed at its tail, so another instance
level count would change nothing but the (reserved) sizes.

RTCRayHitW, W = 4/8/16 (include/embree4/rtcore_ray.h:53-184), structure of arrays, every
field an array of W 4-byte lanes; field k starts at byte k*4*W (W=16: k*64):

    RTCRayW  (RTC_ALIGN(4W), rtcore_ray.h:143-159 for W=16)
      k  0 org_x    float      k  4 dir_x  float      k  8 tfar   float
      k  1 org_y    float      k  5 dir_y  float      k  9 mask   unsigned int
      k  2 org_z    float      k  6 dir_z  float      k 10 id     unsigned int
      k  3 tnear    float      k  7 time   float      k 11 flags  unsigned int
    RTCHitW  (RTC_ALIGN(4W), rtcore_ray.h:161-177), follows at k = 12:
      k 12 Ng_x  k 13 Ng_y  k 14 Ng_z  k 15 u  k 16 v   (float)
      k 17 primID  k 18 geomID            (unsigned int)
      k 19 instID[RTC_MAX_INSTANCE_LEVEL_COUNT][W]
      k 20 instPrimID[RTC_MAX_INSTANCE_LEVEL_COUNT][W]   (#if RTC_GEOMETRY_INSTANCE_ARRAY)
    => RTCRay16 = 768 bytes, RTCRayHit16 = 21*64 = 1344 bytes (we reserve 2048, zeroed).

RTCIntersectArguments / RTCOccludedArguments (include/embree4/rtcore_scene.h:31-41, 58-69):
      off  0 flags         enum RTCRayQueryFlags (int)  COHERENT = 1<<16 (rtcore_common.h:309)
      off  4 feature_mask  enum RTCFeatureFlags (int)   ALL = 0xffffffff (rtcore_common.h:297)
      off  8 context       RTCRayQueryContext*
      off 16 filter        RTCFilterFunctionN           NULL
      off 24 intersect / occluded  (function pointer)   NULL
      off 32 minWidthDistanceFactor float               only #if RTC_MIN_WIDTH (0 here)
    => 32 bytes (40 with min-width); we reserve 64, zeroed.  rtcInitIntersectArguments
    (rtcore_scene.h:44-55) is an inline function: replicated in _init_args.

RTCRayQueryContext (include/embree4/rtcore_common.h:335-344):
      [unsigned instStackSize, only #if RTC_MAX_INSTANCE_LEVEL_COUNT > 1]
      off 0 instID[1]      = RTC_INVALID_GEOMETRY_ID (0xffffffff)
      off 4 instPrimID[1]  = RTC_INVALID_GEOMETRY_ID
    => 8 bytes; reserve 64.  rtcInitRayQueryContext (rtcore_common.h:347-361) replicated.

Entry points (rtcore_scene.h:176, 214; rtcore_device.h:15, 84; rtcore_geometry.h:130-172):
    void rtcIntersect16(const int* valid, RTCScene, RTCRayHit16*, RTCIntersectArguments*)
    void rtcOccluded16 (const int* valid, RTCScene, RTCRay16*,    RTCOccludedArguments*)
    ssize_t rtcGetDeviceProperty(RTCDevice, enum RTCDeviceProperty)
  valid: W int32, -1 = active lane, 0 = inactive.  valid and ray structs must be aligned to
  4*W bytes (release builds do not check: a misaligned packet segfaults), we align to 64.
  rtcOccluded sets tfar = -inf on occluded lanes.

Enums: RTC_DEVICE_PROPERTY_VERSION_MAJOR/MINOR/PATCH = 1/2/3, NATIVE_RAY4/8/16_SUPPORTED
= 32/33/34 (rtcore_device.h:49-81); RTC_GEOMETRY_TYPE_TRIANGLE = 0 (rtcore_geometry.h:20);
RTC_BUFFER_TYPE_INDEX/VERTEX = 0/1 (rtcore_buffer.h:13-14); RTC_FORMAT_UINT3 = 0x5003,
RTC_FORMAT_FLOAT3 = 0x9003 (rtcore_common.h:57-112); RTC_SCENE_FLAG_ROBUST = 1<<2
(rtcore_scene.h:25).

Pitfalls handled here:
  * shared vertex buffers: Embree may load the last vertex with a 16-byte SSE load, so the
    float32 (n, 3) buffer gets one padding row (n + 1 rows allocated, n declared);
  * the ctypes functions are passed to the jitted kernels as arguments (never read from
    a module global), so cache=True works: the cache key is the ctypes signature only;
  * all pointers cross the ctypes boundary as integers (c_size_t-typed arguments).
"""

from __future__ import annotations

import ctypes
import glob
import importlib.util
import os
import sys
import threading

import numpy as np
from numba import njit

from .._kernels import _face_hit, bin_bistatic_hits, bin_flat_hits

__all__ = ["library", "available", "Scene"]

# ---------------------------------------------------------------- constants (see docstring)
RTC_INVALID_GEOMETRY_ID = 0xFFFFFFFF
RTC_DEVICE_PROPERTY_VERSION = 0
RTC_DEVICE_PROPERTY_VERSION_MAJOR = 1
RTC_DEVICE_PROPERTY_VERSION_MINOR = 2
RTC_DEVICE_PROPERTY_VERSION_PATCH = 3
RTC_DEVICE_PROPERTY_NATIVE_RAY4_SUPPORTED = 32
RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED = 33
RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED = 34
RTC_GEOMETRY_TYPE_TRIANGLE = 0
RTC_BUFFER_TYPE_INDEX = 0
RTC_BUFFER_TYPE_VERTEX = 1
RTC_FORMAT_UINT3 = 0x5003
RTC_FORMAT_FLOAT3 = 0x9003
RTC_SCENE_FLAG_ROBUST = 1 << 2
RTC_BUILD_QUALITY_LOW, RTC_BUILD_QUALITY_MEDIUM, RTC_BUILD_QUALITY_HIGH = 0, 1, 2
RTC_RAY_QUERY_FLAG_INCOHERENT = 0
RTC_RAY_QUERY_FLAG_COHERENT = 1 << 16
RTC_FEATURE_FLAG_ALL = 0xFFFFFFFF

# field indices k of RTCRayHitW (byte offset k * 4 * W)
_ORG_X, _ORG_Y, _ORG_Z, _TNEAR, _DIR_X, _DIR_Y, _DIR_Z, _TIME = 0, 1, 2, 3, 4, 5, 6, 7
_TFAR, _MASK, _ID, _FLAGS = 8, 9, 10, 11
_NG_X, _NG_Y, _NG_Z, _U, _V, _PRIMID, _GEOMID, _INSTID, _INSTPRIMID = range(12, 21)

# workspace (bytes, all multiples of 64): [rayhit 2048 | valid 64 | args 64 | context 64]
_RAYHIT_RESERVE = 2048      # RTCRayHit16 is 1344 bytes with the defaults above
_VALID_OFF = _RAYHIT_RESERVE
_ARGS_OFF = _VALID_OFF + 64
_CTX_OFF = _ARGS_OFF + 64
_WS_BYTES = _CTX_OFF + 64
_ALIGN = 64


# ------------------------------------------------------------------- locating the library
def library_candidates():
    """Paths of the Embree 4 shared library bundled with embreex, best first.

    Linux (auditwheel): site-packages/embreex.libs/libembree4-<hash>.so.4
    macOS (delocate):   site-packages/embreex/.dylibs/libembree4*.dylib     (untested)
    Windows (delvewheel): site-packages/embreex.libs/embree4*.dll            (untested)
    ``MESHLADAR_EMBREE4`` (a path) overrides the search.
    """
    env = os.environ.get("MESHLADAR_EMBREE4")
    if env:
        return [env]
    spec = importlib.util.find_spec("embreex")      # locate without importing embreex
    if spec is None or not spec.submodule_search_locations:
        return []
    pkg = list(spec.submodule_search_locations)[0]
    site = os.path.dirname(pkg)
    patterns = [
        os.path.join(site, "embreex.libs", "libembree4*.so*"),
        os.path.join(pkg, ".dylibs", "libembree4*.dylib"),
        os.path.join(site, "embreex.libs", "embree4*.dll"),
        os.path.join(pkg, "embree4*.dll"),
        os.path.join(pkg, "libembree4*"),
    ]
    out = []
    for p in patterns:
        out += sorted(glob.glob(p))
    return out


class EmbreeLib:
    """The ctypes-loaded library: function prototypes, one shared device, its properties."""

    def __init__(self, path=None):
        paths = [path] if path else library_candidates()
        if not paths:
            raise OSError("no Embree 4 library found (is embreex >= 4 installed?)")
        self.path = paths[0]
        if sys.platform == "win32":             # let embree4.dll find its bundled tbb12.dll
            os.add_dll_directory(os.path.dirname(self.path))
        self.dll = ctypes.CDLL(self.path)
        P, U, I, S = ctypes.c_size_t, ctypes.c_uint, ctypes.c_int, ctypes.c_ssize_t

        def proto(name, restype, *argtypes):
            f = getattr(self.dll, name)
            f.restype, f.argtypes = restype, list(argtypes)
            return f

        # handles and data pointers are all passed as integers (c_size_t): same ABI as a
        # pointer on every 64-bit target, and numba passes an int64 straight through
        self.rtcNewDevice = proto("rtcNewDevice", P, ctypes.c_char_p)
        self.rtcReleaseDevice = proto("rtcReleaseDevice", None, P)
        self.rtcGetDeviceProperty = proto("rtcGetDeviceProperty", S, P, I)
        self.rtcGetDeviceError = proto("rtcGetDeviceError", I, P)
        self.rtcGetDeviceLastErrorMessage = proto("rtcGetDeviceLastErrorMessage",
                                                  ctypes.c_char_p, P)
        self.rtcNewScene = proto("rtcNewScene", P, P)
        self.rtcSetSceneFlags = proto("rtcSetSceneFlags", None, P, I)
        self.rtcSetSceneBuildQuality = proto("rtcSetSceneBuildQuality", None, P, I)
        self.rtcCommitScene = proto("rtcCommitScene", None, P)
        self.rtcReleaseScene = proto("rtcReleaseScene", None, P)
        self.rtcNewGeometry = proto("rtcNewGeometry", P, P, I)
        self.rtcSetSharedGeometryBuffer = proto("rtcSetSharedGeometryBuffer", None,
                                                P, I, U, I, P, P, P, P)
        self.rtcCommitGeometry = proto("rtcCommitGeometry", None, P)
        self.rtcAttachGeometry = proto("rtcAttachGeometry", U, P, P)
        self.rtcReleaseGeometry = proto("rtcReleaseGeometry", None, P)
        # packet queries (valid*, scene, rayhit*, args*): identical C signature for W=4/8/16
        self.intersect = {w: proto(f"rtcIntersect{w}", None, P, P, P, P) for w in (4, 8, 16)}
        self.occluded = {w: proto(f"rtcOccluded{w}", None, P, P, P, P) for w in (4, 8, 16)}

        self.device = self.rtcNewDevice(None)
        if not self.device:
            raise OSError(f"rtcNewDevice failed ({self.path})")
        prop = lambda p: int(self.rtcGetDeviceProperty(self.device, p))  # noqa: E731
        self.version = (prop(RTC_DEVICE_PROPERTY_VERSION_MAJOR),
                        prop(RTC_DEVICE_PROPERTY_VERSION_MINOR),
                        prop(RTC_DEVICE_PROPERTY_VERSION_PATCH))
        if self.version[0] != 4:
            raise OSError(f"{self.path}: Embree {self.version}, this module needs Embree 4")
        self.native = {4: prop(RTC_DEVICE_PROPERTY_NATIVE_RAY4_SUPPORTED),
                       8: prop(RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED),
                       16: prop(RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED)}
        # widest native packet; without AVX-512, rtcIntersect16 loops over single rays
        self.width = next((w for w in (16, 8, 4) if self.native[w]), 4)
        _self_test(self)

    def check(self, what):
        err = self.rtcGetDeviceError(self.device)
        if err:
            msg = self.rtcGetDeviceLastErrorMessage(self.device) or b""
            raise RuntimeError(f"Embree error {err} in {what}: {msg.decode(errors='replace')}")


def _self_test(lib):
    """Check the struct layouts this module relies on against the library itself, once:
    one triangle (z = 0, corners (0,0), (1,0), (0,1)) and a packet of every width whose
    lanes alternate between rays that hit it at known (t, u, v) and rays that miss, plus
    the occlusion query. A library built with other layouts fails here, not later."""
    v = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], np.float32)
    f = np.array([[0, 1, 2]], np.uint32)
    scene = Scene(v, f, lib=lib)
    try:
        for w in (4, 8, 16):
            n = w + 3                                   # a full packet and a masked tail
            k = np.arange(n)
            x = np.where(k % 2 == 0, 0.25, 2.0).astype(np.float32)     # odd lanes miss
            o = np.stack([x, np.full(n, 0.125, np.float32), np.full(n, 2.0 + k, np.float32)], 1)
            prim, tfar, u, vv = scene.cast_grid(o, np.array([0, 0, -1], np.float32), width=w,
                                                barycentrics=True)
            hit = k % 2 == 0
            blocked = scene.occluded_grid(o, np.array([0, 0, -1], np.float32), width=w)
            if not (np.array_equal(prim, np.where(hit, 0, -1))
                    and np.allclose(tfar[hit], 2.0 + k[hit])
                    and np.allclose(u[hit], 0.25) and np.allclose(vv[hit], 0.125)
                    and np.array_equal(blocked, hit)):
                raise OSError(f"{lib.path}: Embree {'.'.join(map(str, lib.version))} does not "
                              f"answer a {w}-wide packet as the layouts this module uses "
                              "expect (a build with other options?)")
    finally:
        scene.release()


_LIB = None
_LIB_ERROR = None
_LIB_LOCK = threading.Lock()


def library():
    """The process-wide EmbreeLib (loaded and its device created on first use); raises
    OSError, with the reason, when it cannot be loaded (once per process: the reason is
    kept)."""
    with _LIB_LOCK:
        return _load()


def _load():
    global _LIB, _LIB_ERROR
    if _LIB is None:
        if _LIB_ERROR is not None:
            raise OSError(_LIB_ERROR)
        try:
            _LIB = EmbreeLib()
        except (OSError, AttributeError) as exc:      # missing file, symbol or device
            _LIB_ERROR = str(exc) or type(exc).__name__
            raise OSError(_LIB_ERROR) from exc
    return _LIB


def available():
    """(True, library path) when the packet backend loads; else (False, the reason)."""
    try:
        return True, library().path
    except OSError as exc:
        return False, str(exc)


# ------------------------------------------------------------------------------- the scene
class Scene:
    """A committed Embree scene of one triangle mesh whose buffers are shared (zero-copy)
    numpy arrays: the arrays are kept alive here as long as the scene is."""

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

    def cast_grid(self, origins, direction, *, width=None, coherent=True, tmax=np.inf,
                  barycentrics=False):
        """First hits of rays from ``origins`` (n, 3) all along ``direction`` (3,) (or each
        along its own, (n, 3): coherent when neighbours are nearly parallel):
        ``prim`` (int32, -1 on a miss), ``tfar`` (float32, inf on a miss; distances in
        units of |direction|) and, with ``barycentrics``, the hits' ``u`` and ``v``
        (float32). Releases the GIL: callable from several threads."""
        w = width or self.lib.width
        o = np.ascontiguousarray(origins, dtype=np.float32)
        d = _directions(direction, len(o))
        n = len(o)
        prim = np.empty(n, np.int32)
        tfar = np.empty(n, np.float32)
        m = n if barycentrics else 0
        u, v = np.empty(m, np.float32), np.empty(m, np.float32)
        flags = RTC_RAY_QUERY_FLAG_COHERENT if coherent else RTC_RAY_QUERY_FLAG_INCOHERENT
        cast_grid(self.lib.intersect[w], self._live(), o, d, np.float32(tmax), w, flags,
                  prim, tfar, u, v)
        return (prim, tfar, u, v) if barycentrics else (prim, tfar)

    def occluded_grid(self, origins, direction, *, tmax=np.inf, width=None, coherent=True):
        """Whether each ray hits anything within ``tmax``: bool (n,)."""
        w = width or self.lib.width
        o = np.ascontiguousarray(origins, dtype=np.float32)
        d = _directions(direction, len(o))
        out = np.empty(len(o), np.bool_)
        flags = RTC_RAY_QUERY_FLAG_COHERENT if coherent else RTC_RAY_QUERY_FLAG_INCOHERENT
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


# ----------------------------------------------------------------------- jitted kernels
@njit(cache=True, nogil=True)
def _workspace():
    """A zeroed workspace whose first byte is 64-aligned: returns (int32 view, float32 view,
    int64 view, base address).  Over-allocated by 64 bytes and offset."""
    raw = np.zeros((_WS_BYTES + _ALIGN) // 8, np.int64)
    addr = raw.ctypes.data
    skip = ((_ALIGN - addr % _ALIGN) % _ALIGN) // 8        # int64 storage: addr % 8 == 0
    ws = raw[skip:skip + _WS_BYTES // 8]
    return ws.view(np.int32), ws.view(np.float32), ws, addr + skip * 8


@njit(cache=True, nogil=True, inline="always")
def _init_args(i32, i64, base, flags):
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
def _load_packet(f32, i32, o, d, tmax, start, n, w):
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


@njit(cache=True, nogil=True)
def cast_grid(fn, scene, o, d, tmax, w, flags, prim, tfar, u, v):
    """rtcIntersectW over rays o[i] + t d, in packets of w in scan order (tail masked).
    ``fn`` is the ctypes rtcIntersect{w} (an argument, not a global: cacheable). ``u`` and
    ``v`` receive the barycentrics when they have one entry per ray (else they are empty)."""
    i32, f32, i64, base = _workspace()
    _init_args(i32, i64, base, flags)
    n = o.shape[0]
    for start in range(0, n, w):
        _load_packet(f32, i32, o, d, tmax, start, n, w)
        fn(base + _VALID_OFF, scene, base, base + _ARGS_OFF)
        m = min(w, n - start)
        for j in range(m):
            if i32[_GEOMID * w + j] == -1:
                prim[start + j] = -1
                tfar[start + j] = np.inf
            else:
                prim[start + j] = i32[_PRIMID * w + j]
                tfar[start + j] = f32[_TFAR * w + j]
        if u.shape[0] == n:
            for j in range(m):
                u[start + j] = f32[_U * w + j]
                v[start + j] = f32[_V * w + j]


@njit(cache=True, nogil=True)
def occluded_grid(fn, scene, o, d, tmax, w, flags, out):
    """rtcOccludedW over the same packets: out[i] = the ray is blocked within tmax
    (Embree sets tfar = -inf on occluded lanes)."""
    i32, f32, i64, base = _workspace()
    _init_args(i32, i64, base, flags)
    n = o.shape[0]
    for start in range(0, n, w):
        _load_packet(f32, i32, o, d, tmax, start, n, w)
        fn(base + _VALID_OFF, scene, base, base + _ARGS_OFF)
        m = min(w, n - start)
        for j in range(m):
            out[start + j] = f32[_TFAR * w + j] == -np.inf


@njit(cache=True, nogil=True)
def _occlude_block(occ, scene, w, i32, f32, base, prim, tf, o, n, plane_d, face_normals, wv,
                   wr32, lift, inv_scale, one, lifted, blocked):
    """Occlusion toward the receiver of n hits (face ``prim``, Embree's ``tf``, float32
    origin ``o`` as built): from p = o − t w (t in float64 against the face's plane) lifted
    by ``lift`` along the face's normal turned toward the ladar, rounded to float32 (and
    to unit size), cast along ``wr32`` in packets of w by ``occ`` (rtcOccludedW): the rays
    of meshladar.raytrace.views._trace_view. Fills blocked[:n]."""
    for i in range(n):
        p = prim[i]
        c, t, _ = _face_hit(p, tf[i], o, i, wv, plane_d, face_normals)
        sign = -1.0 if c < 0.0 else 1.0
        for k in range(3):
            q = np.float32((o[i, k] * 1.0 - t * wv[k]) + lift * (face_normals[p, k] * sign))
            lifted[i, k] = q if one else q * inv_scale
    for first in range(0, n, w):
        _load_packet(f32, i32, lifted, wr32, np.float32(np.inf), first, n, w)
        occ(base + _VALID_OFF, scene, base, base + _ARGS_OFF)
        for j in range(min(w, n - first)):
            blocked[first + j] = f32[_TFAR * w + j] == -np.inf


#: Rays per block of hits handed to the weigh-and-bin kernel: small enough to stay in cache,
#: large enough that the call costs nothing per ray.
_BLOCK = 1024


@njit(cache=True, nogil=True)
def cast_bin_grid(fn, scene, w, flags, s, t, du, dv, sp, u, v, lw, d, inv_scale, scale,
                  plane_d, face_normals, face_material, params, wv, start, edges, area,
                  power, ignore_back, out, stamp, weight, tag, footprint, occ, wr, lift):
    """One view, grid to bins in one loop (monostatic, flat normals, point or footprint
    bins): each
    packet's float32 origins are built as :func:`meshladar.raytrace.grid._ray_grid` builds
    them (o = (S u + T v) + L w, S = s (+ δ du), T = t (+ δ dv) when ``du`` is not empty),
    cast at unit size (× ``inv_scale``), and the hits, with Embree's distance scaled back
    (× ``scale``), are weighed and binned a cache-sized block at a time by
    :func:`meshladar._kernels.bin_flat_hits`: the numbers of the unfused path, without
    per-ray arrays. With a receiver direction ``wr`` (3,) (empty: monostatic) each block's
    hits first cast their occlusion rays toward it with ``occ`` (rtcOccludedW; see
    :func:`_occlude_block`), and :func:`meshladar._kernels.bin_bistatic_hits` bins them
    with the per-face bistatic weights in ``weight``. Returns (back-face hits, rays
    cast)."""
    i32, f32, i64, base = _workspace()
    _init_args(i32, i64, base, flags)
    ns, nt = s.shape[0], t.shape[0]
    n = ns * nt
    jitter = du.shape[0] > 0
    one = scale == 1.0
    lanes = np.empty((w, 3), np.float32)          # origins as built (for the ranges)
    cast = np.empty((w, 3), np.float32)           # and as cast (at unit size)
    hit_prim = np.empty(_BLOCK + w, np.int32)
    hit_t = np.empty(_BLOCK + w, np.float32)
    hit_o = np.empty((_BLOCK + w, 3), np.float32)
    bistatic = wr.shape[0] == 3
    blocked = np.zeros(_BLOCK + w if bistatic else 0, np.bool_)
    lifted = np.empty((_BLOCK + w if bistatic else 0, 3), np.float32)
    wr32 = np.empty((1, 3), np.float32)
    if bistatic:
        for k in range(3):
            wr32[0, k] = wr[k]
    held = 0
    back = 0
    for first in range(0, n, w):
        m = min(w, n - first)
        for j in range(m):
            a, b = (first + j) // nt, (first + j) % nt
            if jitter:
                S = np.float32(du[a, b] * sp) + s[a]
                T = np.float32(dv[a, b] * sp) + t[b]
            else:
                S = s[a]
                T = t[b]
            for k in range(3):
                lanes[j, k] = np.float32(np.float32(S * u[k]) + np.float32(T * v[k])) + lw[k]
                cast[j, k] = lanes[j, k] if one else lanes[j, k] * inv_scale
        _load_packet(f32, i32, cast, d, np.float32(np.inf), 0, m, w)
        fn(base + _VALID_OFF, scene, base, base + _ARGS_OFF)
        for j in range(m):
            if i32[_GEOMID * w + j] == -1:
                continue
            tf = f32[_TFAR * w + j]
            hit_prim[held] = i32[_PRIMID * w + j]
            hit_t[held] = tf if one else np.float32(tf * scale)
            hit_o[held, 0] = lanes[j, 0]
            hit_o[held, 1] = lanes[j, 1]
            hit_o[held, 2] = lanes[j, 2]
            held += 1
        if held >= _BLOCK or first + w >= n:
            if bistatic:
                _occlude_block(occ, scene, w, i32, f32, base, hit_prim, hit_t, hit_o, held,
                               plane_d, face_normals, wv, wr32, lift, inv_scale, one,
                               lifted, blocked)
                _init_args(i32, i64, base, flags)
                back += bin_bistatic_hits(hit_prim[:held], hit_t[:held], hit_o[:held],
                                          blocked[:held], plane_d, face_normals, wv, wr,
                                          start, edges, ignore_back, out, weight)
            else:
                back += bin_flat_hits(hit_prim[:held], hit_t[:held], hit_o[:held], plane_d,
                                      face_normals, face_material, params, wv, start, edges,
                                      area, power, ignore_back, out, stamp, weight, tag,
                                      footprint)
            held = 0
    return back, n
