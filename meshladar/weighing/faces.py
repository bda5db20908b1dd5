"""Per-face weights and footprints of one view, for the fused loops: with flat normals
F·δA⊥ (and a footprint's range extent) is one number per face and view. For coatings
without a compiled kernel (monostatic) or that are not built in (bistatic) the loops
cannot evaluate it at a hit, so it is evaluated here for all faces before the view is
cast, in the float64 operations the per-hit path applies to each hit
(:func:`meshladar.raytrace.views.trace_view`, :func:`meshladar.weighing.weights`); the
compiled loops weigh the others at each face's first hit."""

from __future__ import annotations

import numpy as np

from .._lazy import deferred_module
from ..raytrace.grid import dot
from ..raytrace.grid import frame
from ..raytrace.views import bistatic_angles
from .hit_weights import GRAZING_RECEIVER_COS, warn_edge_on_receiver, weights

# compiled loops, imported (with numba) at their first use: a small run loads neither
_kernels = deferred_module("meshladar.weighing._kernels")

__all__ = ["footprint_args", "face_footprints", "face_weights", "face_bistatic_weights",
           "check_edge_on_receiver"]


def footprint_args(geo, w, mode, spacing, rows, tag):
    """The compiled loops' ``footprint`` argument for view w: each face's row made at its
    first hit (:func:`._kernels.footprint_row`) into ``rows``, whose stamps say for which
    view (``tag``, > 0) a row holds; or, with ``tag`` < 0, every row made now, in one pass
    over the mesh (:func:`._kernels.footprint_rows`), and no check per hit.

    Parameters
    ----------
    geo : Geometry
        The traced geometry: its face normals, shifted vertices and faces.
    w : (3,) numpy.ndarray
        The view direction, a unit vector from the scene toward the ladar.
    mode : {"slice", "3d"}
        The run's mode; in slice mode the half-width along v is 0.
    spacing : float
        The ray spacing δ (scene units).
    rows : tuple of ((n_faces, 4) float64, (n_faces,) int64 numpy.ndarray)
        The rows and their stamps, kept between the views of a chunk (zeros: none made).
    tag : int
        The view's number within the chunk, from 1; or −1: every row now.

    Returns
    -------
    tuple
        (rows, stamps, vertices, faces, w, u, v (3-tuples of floats), spacing, 3-D, tag).
    """
    w = np.asarray(w, np.float64)
    u, v = frame(w)
    fp = (rows[0], rows[1], geo.shifted, geo.faces, *(tuple(float(x) for x in a)
                                                       for a in (w, u, v)),
          float(spacing), mode == "3d", int(tag))
    if tag < 0:
        _kernels.footprint_rows(fp, geo.face_normals)
    return fp


def face_footprints(geo, w, mode, spacing, out):
    """Each face's footprint for view w, into out (n_faces, 4): the range half-widths a ray
    cell spreads over along the grid's u and v (v only in 3-D), and the face's own range
    interval (min, max of its corners' −p·w), in the same float64 operations as the
    per-hit footprint of :func:`meshladar.raytrace.views.trace_view`: the rows of
    :func:`footprint_args`, every one made in one pass.

    Parameters
    ----------
    geo, w, mode, spacing : Geometry, (3,) numpy.ndarray, str, float
        As :func:`footprint_args`.
    out : (n_faces, 4) float64 numpy.ndarray
        Output, overwritten: per face, the range half-widths |n·u| / |n·w| · δ/2 and
        |n·v| / |n·w| · δ/2 (|n·w| floored at ``meshladar.precision.TINY``), then the
        minimum and maximum of its corners' ranges −p·w (p in shifted coordinates, scene
        units).
    """
    footprint_args(geo, w, mode, spacing, (out, np.zeros(len(geo.faces), np.int64)), -1)


#: Faces per block of the per-view face weights (bounded temporaries on huge meshes).
_FACE_BLOCK = 1 << 16


def face_bistatic_weights(geo, materials, w, w_r, area, out, power, ignore_back):
    """F·area of every face for the ladar along w and the receiver along w_r, into out
    (n_faces,), in the float64 operations :func:`meshladar.raytrace.views.trace_view` and
    :func:`meshladar.weighing.weights` apply to each hit of the face (flat normals: the
    same for all of them; the normal turned toward the ladar unless back faces are
    ignored, which weigh 0). A hit whose receiver ray is blocked weighs 0, in the loop.
    In blocks of faces: a handful of temporaries per face, not per mesh.

    Parameters
    ----------
    geo : Geometry
        The traced geometry (``TracePlan.geo``): its flat face normals and face materials.
    materials : sequence of BRDF
        One coating per material index; each must evaluate ``bistatic``.
    w : (3,) numpy.ndarray
        The view direction, a unit vector from the scene toward the ladar.
    w_r : (3,) numpy.ndarray
        The receiver's direction, a unit vector from the scene toward it.
    area : float
        δA⊥ of one ray (``TracePlan.area``: δ in slice mode, δ² in 3-D).
    out : (n_faces,) float64 numpy.ndarray
        Output, overwritten: each face's weight, as
        :func:`meshladar.weighing.weights` with the bistatic angles of the face's normal.
    power : bool
        Received power, F·cos θr·area (True), or the paper's Eq. 8 weight F·area (False).
    ignore_back : bool
        Whether back faces are ignored (weight 0) rather than weighed two-sided.

    Warns
    -----
    MeshladarWarning
        Under the paper's convention, when a face toward the ladar lies edge-on to the
        receiver (:func:`meshladar.weighing.weights`).

    References
    ----------
    Jin & Levine (2009), Eq. 8 (the weight under ``power=False``).
    """
    step = _FACE_BLOCK
    for a in range(0, len(geo.face_normals), step):
        out[a:a + step] = _bistatic_weights(geo.face_normals[a:a + step],
                                            geo.material[a:a + step], materials, w, w_r,
                                            area, power, ignore_back)


def check_edge_on_receiver(geo, w, w_r, ignore_back):
    """Warn, as :func:`face_bistatic_weights` does under the paper's radiometry, when a
    face toward the ladar lies edge-on to the receiver: for the fused loop that weighs
    built-in coatings at each face's first hit, in one compiled pass over the faces.

    Parameters
    ----------
    geo : Geometry
        The traced geometry (``TracePlan.geo``): its flat face normals.
    w, w_r : (3,) numpy.ndarray
        The view direction and the receiver's direction, unit vectors from the scene.
    ignore_back : bool
        Whether back faces are ignored (never weighed) rather than turned toward the
        ladar.

    Warns
    -----
    MeshladarWarning
        When 0 ≤ cos θr < :data:`meshladar.weighing.hit_weights.GRAZING_RECEIVER_COS` on a
        face toward the ladar.
    """
    if _kernels.edge_on_receiver(geo.face_normals, np.asarray(w, np.float64),
                                 np.asarray(w_r, np.float64), bool(ignore_back),
                                 GRAZING_RECEIVER_COS):
        warn_edge_on_receiver()


def _bistatic_weights(n, material, materials, w, w_r, area, power, ignore_back):
    cos_t = dot(n, w)
    back = cos_t < 0
    if not ignore_back:
        sign = np.where(back, -1.0, 1.0)
        n = n * sign[:, None]
        cos_t = cos_t * sign
    sin_t = np.sqrt(np.maximum(1.0 - cos_t * cos_t, 0.0))
    if ignore_back:
        cos_t = np.where(back, -1.0, cos_t)
    bi = bistatic_angles(n, w, w_r, ignore_back & back)
    return weights(cos_t, sin_t, material, materials, area, bi, power=power)


def face_weights(geo, materials, w, area, out, power=False):
    """F(θ)·area of every face for view w, into out (n_faces,): θ between the face's flat
    normal and w (either side: the kernel skips back faces that are ignored), weighed by
    :func:`meshladar.weighing.weights` exactly as the unfused path weighs a hit.

    Parameters
    ----------
    geo : Geometry
        The traced geometry (``TracePlan.geo``): its flat face normals and face materials.
    materials : sequence of BRDF
        One coating per material index.
    w : (3,) numpy.ndarray
        The view direction, a unit vector from the scene toward the ladar.
    area : float
        δA⊥ of one ray (``TracePlan.area``: δ in slice mode, δ² in 3-D).
    out : (n_faces,) float64 numpy.ndarray
        Output, overwritten: each face's weight at cos θ = |n·w|.
    power : bool
        Received power, F·cos θ·area (True), or the paper's Eq. 8 weight F·area (default
        False).

    References
    ----------
    Jin & Levine (2009), Eq. 8 (the weight under ``power=False``).
    """
    n = geo.face_normals
    c = np.abs(n[:, 0] * w[0] + n[:, 1] * w[1] + n[:, 2] * w[2])
    out[:] = weights(c, np.sqrt(np.maximum(1.0 - c * c, 0.0)), geo.material, materials, area,
                      power=power)


