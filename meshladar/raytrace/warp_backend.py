"""The Warp backends: NVIDIA Warp's mesh BVH and ray queries (``wp.mesh_query_ray``),
registered in :data:`meshladar.raytrace.backends.REGISTRY` as "warp" (a CUDA device) and
"warp-cpu" (the same kernels compiled for the CPU: how they are tested without a GPU).

Warp is an optional dependency (``pip install 'meshladar[gpu]'``, the ``warp-lang``
package); it is imported only when one of these backends is asked for. "auto" takes "warp"
first when a CUDA device is present, and passes over it in silence when not.

The scenes answer embreex's ``run(origins, directions, output=, query=)``: first hits with
the face, the distance in units of |direction| and the barycentrics in Embree's convention
(the hit is (1 − u − v) p0 + u p1 + v p2; Warp's own weights p0 and p1), or occlusion.
Warp intersects in float32 with its own (not watertight) triangle test, so a ray through
an edge shared by two triangles may report either, and distances agree with Embree's to
float32 round-off (:data:`HIT_RTOL`); the weigh stage recomputes each hit's range in
float64 from the face's plane, as for the other backends.
"""

from __future__ import annotations

import contextlib
import ctypes.util
import functools
import importlib.util
import os
import sys

import numpy as np

from .backends import Backend, register

__all__ = ["available_cpu", "available_cuda", "HIT_RTOL", "WarpScene"]

#: Hit distances agree with Embree's to this relative tolerance (a few float32 ulps).
HIT_RTOL = 1e-5

_KERNELS = None


def _warp():
    """The warp module, initialised quietly, and the kernels (compiled on first use, cached
    on disk by Warp)."""
    global _KERNELS
    import warp as wp

    if _KERNELS is None:
        wp.config.log_level = wp.LOG_WARNING     # no greeting, no per-module compile lines
        with _quiet_stderr(not _cuda_driver()):
            wp.init()
        _KERNELS = _make_kernels(wp)
    return wp, _KERNELS


@contextlib.contextmanager
def _quiet_stderr(quiet):
    """Standard error closed at the file-descriptor level while ``quiet``: Warp's native
    start-up writes that there is no CUDA driver, which :func:`_cuda_driver` already knows,
    straight to fd 2 on every CPU-only machine."""
    if not quiet:
        yield
        return
    saved = os.dup(2)
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 2)
            yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)


def _make_kernels(wp):
    @wp.kernel
    def first_hits(mesh: wp.uint64, o: wp.array(dtype=wp.vec3),
                   d: wp.array(dtype=wp.vec3), each: int, tmax: float,
                   prim: wp.array(dtype=wp.int32), tfar: wp.array(dtype=wp.float32),
                   u: wp.array(dtype=wp.float32), v: wp.array(dtype=wp.float32)):
        i = wp.tid()
        q = wp.mesh_query_ray(mesh, o[i], d[i * each], tmax)
        if q.result:
            prim[i] = q.face
            tfar[i] = q.t
            u[i] = q.v                          # Warp: weights of p0, p1; Embree: p1, p2
            v[i] = 1.0 - q.u - q.v
        else:
            prim[i] = -1
            tfar[i] = wp.inf

    @wp.kernel
    def blocked(mesh: wp.uint64, o: wp.array(dtype=wp.vec3), d: wp.array(dtype=wp.vec3),
                each: int, tmax: float, out: wp.array(dtype=wp.int32)):
        i = wp.tid()
        q = wp.mesh_query_ray(mesh, o[i], d[i * each], tmax)
        if q.result:
            out[i] = 0                                    # embreex: 0 blocked, -1 free
        else:
            out[i] = -1

    @wp.func
    def bin_of(r: wp.float64, edges: wp.array(dtype=wp.float64), inv: wp.float64):
        # the bin k with edges[k] <= r < edges[k + 1]: guessed from uniform edges, checked,
        # by bisection when off (meshladar.weighing._kernels._bin_of)
        nb = edges.shape[0] - 1
        k = wp.clamp(int((r - edges[0]) * inv), 0, nb - 1)
        if edges[k] <= r and r < edges[k + 1]:
            return k
        lo = int(0)
        hi = nb
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if edges[mid] <= r:
                lo = mid
            else:
                hi = mid
        return lo

    @wp.kernel
    def cast_bin(mesh: wp.uint64, o: wp.array(dtype=wp.vec3), d: wp.vec3, inverse: float,
                 scale: float, plane_d: wp.array(dtype=wp.float64),
                 normals: wp.array(dtype=wp.vec3d), w: wp.vec3d, start: wp.float64,
                 edges: wp.array(dtype=wp.float64), ignore_back: int,
                 weight: wp.array(dtype=wp.float64), out: wp.array(dtype=wp.float64),
                 back: wp.array(dtype=wp.int32)):
        # one ray: cast, then weigh and bin its hit as weighing._kernels.bin_flat_hits
        # does (the range recomputed in float64 from the face's plane)
        i = wp.tid()
        q = wp.mesh_query_ray(mesh, o[i] * inverse, d, 3.0e38)
        if not q.result:
            return
        p = q.face
        n = normals[p]
        x = wp.vec3d(wp.float64(o[i][0]), wp.float64(o[i][1]), wp.float64(o[i][2]))
        c = n[0] * w[0] + n[1] * w[1] + n[2] * w[2]
        t = wp.float64(q.t * scale)
        if wp.abs(c) > wp.float64(1.0e-6):
            t = (plane_d[p] - (n[0] * x[0] + n[1] * x[1] + n[2] * x[2])) / (-c)
        r = start + (t - (x[0] * w[0] + x[1] * w[1] + x[2] * w[2]))
        if c < wp.float64(0.0):
            wp.atomic_add(back, 0, 1)
            if ignore_back != 0:
                return
        nb = edges.shape[0] - 1
        if r < edges[0] or r >= edges[nb]:
            return
        inv = wp.float64(nb) / (edges[nb] - edges[0])
        wp.atomic_add(out, bin_of(r, edges, inv), weight[p])

    return {"first_hits": first_hits, "blocked": blocked, "cast_bin": cast_bin}


class WarpScene:
    """One triangle mesh in Warp's BVH on ``device`` ("cpu" or "cuda:0"), behind embreex's
    ``run`` interface: the backends' ``build`` (backend "warp" on "cuda:0", "warp-cpu" on
    "cpu").

    Parameters
    ----------
    vertices : (n, 3) array_like
        The triangles' corners (cast as float32).
    faces : (m, 3) array_like
        Each triangle's vertex indices (cast as int32).
    device : str
        Warp's device name.
    """

    def __init__(self, vertices, faces, device):
        wp, self._kernels = _warp()
        self._wp, self.device = wp, device
        self._points = wp.array(np.ascontiguousarray(vertices, np.float32), dtype=wp.vec3,
                                device=device)
        self._indices = wp.array(np.ascontiguousarray(faces, np.int32).ravel(),
                                 dtype=wp.int32, device=device)
        self.mesh = wp.Mesh(points=self._points, indices=self._indices)
        self._planes = None          # the faces' planes on the device, uploaded once

    def run(self, origins, directions, output=None, query="INTERSECT", columns=0):
        """Cast rays as embreex's ``run`` does: first hits, or occlusion.

        Parameters
        ----------
        origins : (n, 3) array_like
            Ray origins, cast as float32.
        directions : (3,), (1, 3) or (n, 3) array_like
            One direction for every ray, or one per ray, cast as float32; distances come
            back in units of its length.
        output : object, optional
            Ignored (embreex's signature).
        query : str
            ``"OCCLUDED"`` for the occlusion query; any other value casts for first hits.
        columns : int
            Ignored: Warp schedules its own threads (the packet backend's grid tiles).

        Returns
        -------
        dict or numpy.ndarray
            First hits: ``"primID"`` (int32, -1 on a miss), ``"tfar"`` (float32, inf on a
            miss), ``"u"``, ``"v"`` (float32, Embree's barycentrics). ``"OCCLUDED"``:
            (n,) int32, 0 where the ray meets anything and -1 where it does not.

        Raises
        ------
        ValueError
            When ``directions`` is neither one direction nor one per ray.
        """
        wp, dev = self._wp, self.device
        o = np.ascontiguousarray(origins, np.float32).reshape(-1, 3)
        d = np.ascontiguousarray(directions, np.float32).reshape(-1, 3)
        n = len(o)
        if len(d) not in (1, n):
            raise ValueError(f"directions must be one direction or one per ray ({n}, 3); "
                             f"got shape {np.shape(directions)}")
        args = [self.mesh.id, wp.array(o, dtype=wp.vec3, device=dev),
                wp.array(d, dtype=wp.vec3, device=dev), int(len(d) == n), float(3.0e38)]
        if query == "OCCLUDED":
            out = wp.empty(n, dtype=wp.int32, device=dev)
            wp.launch(self._kernels["blocked"], dim=n, inputs=args + [out], device=dev)
            return out.numpy()
        res = [wp.empty(n, dtype=t, device=dev)
               for t in (wp.int32, wp.float32, wp.float32, wp.float32)]
        wp.launch(self._kernels["first_hits"], dim=n, inputs=args + res, device=dev)
        prim, tfar, u, v = (a.numpy() for a in res)
        return {"primID": prim, "tfar": tfar, "u": u, "v": v}

    def cast_bin(self, origins, direction, inverse, scale, bins):
        """Cast, weigh and bin in one kernel: monostatic, flat normals, point bins. Each
        ray from ``origins`` (float32, as built; cast × ``inverse``) along ``direction``
        (3,) adds its face's ``bins.weight`` (every face's, for this view) to the bin of
        its range, recomputed in float64 from the face's plane as
        :func:`meshladar.weighing._kernels.bin_flat_hits` does; only the bins come back.

        Parameters
        ----------
        origins : (n, 3) float32 numpy.ndarray
            The grid's origins in shifted coordinates.
        direction : (3,) array_like
            Every ray's direction (−w).
        inverse, scale : float
            The scene's unit-size factor and its inverse (powers of two).
        bins : meshladar.forward.fused_views.FlatBins
            ``plane_d``, ``face_normals``, ``w``, ``start``, ``edges``, ``ignore_back``,
            ``weight`` (read) and ``out`` (added into).

        Returns
        -------
        int
            The back-face hits.
        """
        wp, dev = self._wp, self.device
        arr = functools.partial(wp.array, device=dev)
        if self._planes is None or self._planes[0] is not bins.plane_d:
            # the geometry's own arrays, the same for every view of this scene
            self._planes = (bins.plane_d, arr(bins.plane_d, dtype=wp.float64),
                            arr(bins.face_normals, dtype=wp.vec3d))
        out = arr(np.zeros(bins.out.shape), dtype=wp.float64)
        back = wp.zeros(1, dtype=wp.int32, device=dev)
        wp.launch(self._kernels["cast_bin"], dim=len(origins), device=dev, inputs=[
            self.mesh.id, arr(np.ascontiguousarray(origins, np.float32), dtype=wp.vec3),
            wp.vec3(*np.asarray(direction, np.float32)), float(inverse), float(scale),
            self._planes[1], self._planes[2], wp.vec3d(*np.asarray(bins.w, np.float64)),
            float(bins.start), arr(bins.edges, dtype=wp.float64), int(bins.ignore_back),
            arr(bins.weight, dtype=wp.float64), out, back])
        bins.out[...] += out.numpy()
        return int(back.numpy()[0])


_INSTALL = "warp-lang is not installed (pip install 'meshladar[gpu]')"


def available_cpu():
    """(True, "warp-lang <version> on the CPU") when Warp is installed; else (False, why).

    Returns
    -------
    tuple of (bool, str)
        Whether the "warp-cpu" backend loads here, and where or why not.
    """
    if importlib.util.find_spec("warp") is None:
        return False, _INSTALL
    wp, _ = _warp()
    return True, f"warp-lang {wp.__version__} on the CPU"


@functools.cache
def _cuda_driver():
    """Whether a CUDA driver library is on this machine (looked for without loading Warp,
    so that "auto" costs nothing where there is none). On Linux the driver is the NVIDIA
    kernel module's (/proc/driver/nvidia) or WSL's library: two file checks, where
    ``find_library`` runs ``ldconfig`` (11 ms of every command's start)."""
    if sys.platform.startswith("linux"):
        return any(os.path.exists(p) for p in _LINUX_CUDA)
    return bool(ctypes.util.find_library("cuda"))


#: Where a CUDA driver shows on Linux: the NVIDIA kernel module, WSL's driver library.
_LINUX_CUDA = ("/proc/driver/nvidia", "/usr/lib/wsl/lib/libcuda.so.1")


def available_cuda():
    """(True, "warp-lang <version> on <GPU>") when Warp is installed and sees a CUDA
    device; else (False, why), naming "warp-cpu" as the way to run the kernels on the CPU.

    Returns
    -------
    tuple of (bool, str)
        Whether the "warp" backend loads here, and where or why not.
    """
    if importlib.util.find_spec("warp") is None:
        return False, _INSTALL
    if not _cuda_driver():
        return False, ("no CUDA driver on this machine; backend='warp-cpu' runs the same "
                       "kernels on the CPU")
    wp, _ = _warp()
    if not wp.is_cuda_available():
        return False, ("Warp finds no CUDA device; backend='warp-cpu' runs the same "
                       "kernels on the CPU")
    return True, f"warp-lang {wp.__version__} on {wp.get_device('cuda:0').name}"


register(Backend("warp", functools.partial(WarpScene, device="cuda:0"), available_cuda,
                 optional=True))
register(Backend("warp-cpu", functools.partial(WarpScene, device="cpu"), available_cpu))
