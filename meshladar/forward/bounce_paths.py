"""Where light beyond one bounce comes from, for the viewer: each face's return per order
of bounces for one view (the order that dominates there), and a few sampled paths' vertices
to draw. Both sample as :mod:`meshladar.forward.bounces` does (its :func:`walk`)."""

from __future__ import annotations

import numpy as np

from .._validate import check_count, unit_vectors
from ..errors import ParameterError
from ..raytrace.backends import resolve_backend
from ..raytrace.embree import embree_scene, geometry
from ..scene import Scene
from .bounces import BRANCHES, check_bistatic, single_bounce, walk
from .orders import MAX_BOUNCES

__all__ = ["face_orders", "dominant_order", "sample_paths", "GRID_RAYS"]

#: Rays across the scene's bounding box when no ``ray_spacing`` is given.
GRID_RAYS = 128


def _prepared(scene, view_vector, bounces, ray_spacing):
    if not isinstance(scene, Scene) or not scene.is_mesh:
        raise ParameterError("the bounce view needs a mesh scene")
    w = unit_vectors("view_vector", view_vector)
    if w.shape != (3,):
        raise ParameterError(f"view_vector must be one (3,) direction; got shape {w.shape}")
    bounces = check_count("bounces", bounces, 1, MAX_BOUNCES)
    check_bistatic(scene.materials)
    lo, hi = scene.bounds()
    spacing = float(np.linalg.norm(hi - lo)) / GRID_RAYS if ray_spacing is None else \
        float(ray_spacing)
    geo = geometry(scene, "flat")
    return w, bounces, spacing, geo, embree_scene(geo, resolve_backend("embreex"))


def face_orders(scene, view_vector, *, bounces=3, samples=1 << 14, ray_spacing=None,
                seed=0):
    """Each face's return toward the ladar per order: (faces, bounces), power per unit
    irradiance (received-power radiometry); order 1 from the first hits, order k ≥ 2 from
    the sampled paths whose k-th vertex lies on the face.

    Parameters
    ----------
    scene : Scene
        A mesh scene (faces numbered part by part).
    view_vector : (3,) array_like
        The view w (normalised here).
    bounces : int
        The highest order, 1 to 8.
    samples : int
        Sampled paths.
    ray_spacing : float, optional
        The first hits' grid spacing; default the box's diagonal / :data:`GRID_RAYS`.
    seed : int
        Seeds the sampling.

    Returns
    -------
    (m, bounces) numpy.ndarray
        Per face and order.

    Raises
    ------
    ParameterError
        For an analytic scene, a bad view or ``bounces``; ModelError for a coating without
        a bistatic evaluation.
    """
    w, bounces, spacing, geo, emb = _prepared(scene, view_vector, bounces, ray_spacing)
    m = len(geo.faces)
    out = np.zeros((m, bounces))
    out[:, 0] = np.bincount(*single_bounce(scene, geo, w, spacing), m)
    if bounces > 1 and scene.visibility().needs_bounces:
        legs = walk(scene, geo, emb, w, spacing, (bounces, samples),
                    np.random.default_rng(seed))
        for k, leg in enumerate(legs, start=1):
            out[:, k] = np.bincount(leg.face, leg.value, m)
    return out


def dominant_order(orders):
    """The order whose return is largest on each face, 0 where a face returns nothing.

    Parameters
    ----------
    orders : (m, bounces) array_like
        :func:`face_orders`' result.

    Returns
    -------
    (m,) numpy.ndarray of int
        1..bounces, or 0.
    """
    o = np.asarray(orders, dtype=np.float64)
    return np.where(o.max(axis=1) > 0, np.argmax(o, axis=1) + 1, 0)


def sample_paths(scene, view_vector, *, paths=12, bounces=3, ray_spacing=None, seed=0):
    """The vertices of a few sampled paths, each from a different first hit: x₁ (where the
    ray from the ladar meets the scene), x₂, … up to ``bounces`` vertices, ending where the
    path leaves the scene or its last order.

    Parameters
    ----------
    scene : Scene
        A mesh scene.
    view_vector : (3,) array_like
        The view w.
    paths : int
        How many, 1 to 1000.
    bounces : int
        The most vertices, 1 to 8.
    ray_spacing : float, optional
        As :func:`face_orders`.
    seed : int
        Seeds the draw.

    Returns
    -------
    list of (k, 3) numpy.ndarray
        Each path's vertices, scene coordinates, 1 ≤ k ≤ bounces.

    Raises
    ------
    ParameterError
        As :func:`face_orders`, or ``paths`` outside 1..1000.
    """
    paths = check_count("paths", paths, 1, 1000)
    w, bounces, spacing, geo, emb = _prepared(scene, view_vector, bounces, ray_spacing)
    trail = []
    for _ in walk(scene, geo, emb, w, spacing, (max(bounces, 2), paths * BRANCHES),
                  np.random.default_rng(seed), trail):
        pass
    if not trail:
        return []
    out = []
    for path in range(0, paths * BRANCHES, BRANCHES):       # one branch of each first hit
        pts = [x[ids == path][0] for ids, x in trail[:bounces] if np.any(ids == path)]
        out.append(np.array(pts))
    return out
