"""The packet backend's ctypes bindings: the layouts, enums and entry points of the Embree 4
library that the embreex wheel ships, called through ctypes (the loops that cast are
:mod:`.embree4`'s).

No compiler is needed: ``pip install meshladar`` brings embreex, whose wheel carries the
library. ``library()`` finds it (``MESHLADAR_EMBREE4`` overrides the path), checks that it
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

The structures, as laid out in memory::

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
        (rtcore_scene.h:44-55) is an inline function: replicated in init_args.

    RTCRayQueryContext (include/embree4/rtcore_common.h:335-344):
          [unsigned instStackSize, only #if RTC_MAX_INSTANCE_LEVEL_COUNT > 1]
          off 0 instID[1]      = RTC_INVALID_GEOMETRY_ID (0xffffffff)
          off 4 instPrimID[1]  = RTC_INVALID_GEOMETRY_ID
        => 8 bytes; reserve 64.  rtcInitRayQueryContext (rtcore_common.h:347-361) replicated.

    Entry points (rtcore_scene.h:176, 214; rtcore_device.h:15, 84; rtcore_geometry.h:130-172):
        void rtcIntersect16(const int* valid, RTCScene, RTCRayHit16*, RTCIntersectArguments*)
        void rtcOccluded16 (const int* valid, RTCScene, RTCRay16*,    RTCOccludedArguments*)
        void rtcIntersect1 (RTCScene, RTCRayHit*, RTCIntersectArguments*)   (W = 1, no mask)
        ssize_t rtcGetDeviceProperty(RTCDevice, enum RTCDeviceProperty)
      valid: W int32, -1 = active lane, 0 = inactive.  valid and ray structs must be aligned to
      4*W bytes, RTCRayHit (W = 1) to 16 (release builds do not check: a misaligned packet
      segfaults), we align to 64.
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

import numpy as np

__all__ = ["EmbreeLib", "library_candidates", "TFAR", "PRIMID", "GEOMID", "VALID_OFF",
           "ARGS_OFF", "new_workspace", "query_flags"]

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


def query_flags(coherent):
    """Embree's ray query flags for packets that are (True) or are not coherent.

    Parameters
    ----------
    coherent : bool
        Whether the packet's rays are nearly parallel and close together.

    Returns
    -------
    int
        ``RTC_RAY_QUERY_FLAG_COHERENT`` or ``RTC_RAY_QUERY_FLAG_INCOHERENT``.
    """
    return RTC_RAY_QUERY_FLAG_COHERENT if coherent else RTC_RAY_QUERY_FLAG_INCOHERENT

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

    embreex is located without being imported.

    Returns
    -------
    list of str
        ``[MESHLADAR_EMBREE4]`` when that environment variable is set and non-empty (not
        checked for existence); else the files matching the patterns above, in that
        order, each pattern's matches sorted; empty when embreex is not installed or holds
        no such file.
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
    """The ctypes-loaded library: function prototypes, one shared device, its properties.

    Parameters
    ----------
    path : str, optional
        The shared library to load; default the first of :func:`library_candidates`.

    Attributes
    ----------
    path : str
        The library loaded.
    dll : ctypes.CDLL
        The loaded library; the ``rtc*`` attributes are its entry points with their
        prototypes (every handle and pointer passed as an integer, ``c_size_t``).
    device : int
        The one RTCDevice handle, created with no configuration string
        (``rtcNewDevice(NULL)``).
    version : tuple of int
        (major, minor, patch) of Embree, as the device reports it; the major is 4.
    native : dict
        {4, 8, 16: the device's ``NATIVE_RAY4/8/16_SUPPORTED`` property}.
    width : int
        The widest natively supported packet width, 16, 8 or else 4.
    intersect, occluded : dict
        {4, 8, 16: ``rtcIntersect{w}`` / ``rtcOccluded{w}``}, the packet queries.
    intersect1 : ctypes function
        ``rtcIntersect1(scene, rayhit*, args*)``, one ray: its RTCRayHit is laid out as
        RTCRayHitW at W = 1 (field k at byte 4k), so the packet loaders fill it with w = 1.

    Raises
    ------
    OSError
        When no library is found, it cannot be loaded, its device cannot be created, or
        it is not Embree 4.
    AttributeError
        When the library lacks one of the entry points.
    """

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
        # one ray (scene, rayhit*, args*): RTCRayHit is RTCRayHitW's layout at W = 1
        self.intersect1 = proto("rtcIntersect1", None, P, P, P)

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

    def check(self, what):
        """Raise the device's pending error, if any (``rtcGetDeviceError``).

        Parameters
        ----------
        what : str
            The operation just done, named in the error message (``"scene build"``).

        Raises
        ------
        RuntimeError
            When ``rtcGetDeviceError`` reports an error: its code, ``what`` and Embree's
            last error message.
        """
        err = self.rtcGetDeviceError(self.device)
        if err:
            msg = self.rtcGetDeviceLastErrorMessage(self.device) or b""
            raise RuntimeError(f"Embree error {err} in {what}: {msg.decode(errors='replace')}")


# public names of the packet layout, for the compiled loops beside other stages
# (meshladar.weighing.fused): field indices of RTCRayHitW and workspace offsets
TFAR, PRIMID, GEOMID, U, V = _TFAR, _PRIMID, _GEOMID, _U, _V
VALID_OFF, ARGS_OFF = _VALID_OFF, _ARGS_OFF


def new_workspace():
    """A packet workspace made in numpy (zeroed, its first byte 64-aligned), as the
    compiled :func:`meshladar.raytrace.embree4_kernels.workspace` makes it inside a loop:
    for the loops whose caller allocates it (:mod:`meshladar.weighing._scratch`).

    Returns
    -------
    tuple
        (int32 view, float32 view, int64 view, base address) of the one buffer.
    """
    raw = np.zeros((_WS_BYTES + _ALIGN) // 8, np.int64)
    skip = ((_ALIGN - raw.ctypes.data % _ALIGN) % _ALIGN) // 8   # int64: addr % 8 == 0
    ws = raw[skip:skip + _WS_BYTES // 8]
    return ws.view(np.int32), ws.view(np.float32), ws, raw.ctypes.data + skip * 8
