"""The pieces a bounce path is built of (:mod:`.bounces`, :mod:`.mirrors`,
:mod:`.specular`): a coating's lobe width and bistatic weight at a vertex, a cast from
points on faces with float64 distances, a shadow ray, and one order's returns."""

from __future__ import annotations

import warnings
from dataclasses import replace
from typing import NamedTuple

import numpy as np

from ..brdf import GGX, Phong, SandfordRobertson
from ..errors import MeshladarWarning, user_stacklevel
from ..precision import COS_HORIZON, RECEIVER_LIFT
from ..raytrace.views import refine_t_along
from ..weighing.hit_weights import GRAZING_RECEIVER_COS

__all__ = ["LIFT", "GRAZING_SHARE", "Leg", "Paths", "lobe_width", "dot", "weight", "edge_on_glints", "warn_edge_on", "glint_of", "cast",
           "blocked"]

#: A sampled ray starts this fraction of the scene's radius off its face, along its normal
#: (float32 origins would otherwise hit their own face again).
LIFT = RECEIVER_LIFT
#: Under the paper's radiometry, returns from surfaces edge-on to the receiver are warned
#: about when they carry more than this share of an order's return.
GRAZING_SHARE = 1e-3


def lobe_width(m):
    """The width of a coating's specular lobe, or nan where it has none to sample."""
    if isinstance(m, SandfordRobertson) and m.has_specular:
        return float(m.e)
    if isinstance(m, GGX) and m.reflectance > 0:
        return float(m.alpha)
    if isinstance(m, Phong) and m.ks > 0:
        return float(np.sqrt(2.0 / (m.exponent + 2.0)))
    return np.nan


def dot(a, b):
    """Row-wise dot products of two (k, 3) arrays."""
    return np.einsum("ij,ij->i", a, b)


def weight(materials, mat, n, wi, wo, power=True):
    """F(wi, wo)·cos θo per vertex, each coating's own bistatic evaluation; F alone where
    not ``power`` (the paper's Eq. 8 at the last vertex: divided by cos θo floored at
    COS_HORIZON, as the single bounce's bistatic weight is; :func:`warn_edge_on`)."""
    ci, co = dot(n, wi), dot(n, wo)
    h = wi + wo
    h /= np.maximum(np.linalg.norm(h, axis=1, keepdims=True), 1e-300)
    ch = np.clip(dot(n, h), -1.0, 1.0)
    out = np.zeros(len(n))
    ok = (ci > 0) & (co > 0)
    for i, m in enumerate(materials):
        sel = ok & (mat == i)
        if np.any(sel):
            c = [np.clip(x[sel], 0.0, 1.0) for x in (ci, co, ch)]
            out[sel] = m.bistatic(c[0], np.sqrt(1.0 - c[0] ** 2), c[1],
                                  np.sqrt(1.0 - c[1] ** 2), c[2], np.sqrt(1.0 - c[2] ** 2))
    return out if power else out / np.maximum(co, COS_HORIZON)


def edge_on_glints(materials, mat, n, wi, wo):
    """Per vertex, the part of its paper-radiometry weight F (:func:`weight`) that an SR
    glint gives (its F grows as 1/cos θo, A5) where the vertex is within
    GRAZING_RECEIVER_COS of edge-on to ``wo``; 0 elsewhere (every other built-in F is
    bounded there)."""
    co = dot(n, wo)
    out = np.zeros(len(n))
    near = (co > 0) & (co < GRAZING_RECEIVER_COS)
    for i, m in enumerate(materials):
        sel = near & (mat == i)
        if np.any(sel) and isinstance(m, SandfordRobertson) and m.has_specular:
            out[sel] = weight([glint_of(m)], np.zeros(int(sel.sum()), int), n[sel],
                              wi[sel], wo[sel], power=False)
    return out


def warn_edge_on(glint, value):
    """Warn when the edge-on glints (:func:`edge_on_glints`) of the returns ``value`` that
    reach the receiver carry more than GRAZING_SHARE of them."""
    total = float(value.sum())
    share = float(glint.sum()) / total if total > 0 else 0.0
    if share > GRAZING_SHARE:
        warnings.warn(f"surfaces that light reaches after a bounce lie edge-on to the "
                      f"receiver (cos θr < 1e-6), and their glint carries {100 * share:.3g} % "
                      f"of an order's return: under radiometry='paper' a glint's F grows as "
                      f"1/cos θr there; radiometry='power' (received power, F·cos θr) is "
                      f"finite", MeshladarWarning, stacklevel=user_stacklevel())


def glint_of(m):
    """A coating's specular lobe alone (SR's ``lobes="specular"``; GGX is one).

    Parameters
    ----------
    m : BRDF
        The coating.

    Returns
    -------
    BRDF
        Its specular part; ``m`` itself for any other model.
    """
    if isinstance(m, SandfordRobertson) and m.lobes == "both":
        return replace(m, lobes="specular")
    return m


def cast(emb, geo, points, normals, d):
    """Rays from ``points`` (lifted along their normals) along ``d``: the face hit (−1 on
    a miss) and the distance from the point, recomputed in float64 against the hit face's
    plane (Embree's float32 distance from a float32 origin leaves the hit ~1e-7 off its
    face: enough for a shadow ray from it to hit that face again)."""
    shifted = points - geo.center
    o = shifted + LIFT * geo.radius * normals
    res = emb.run(np.ascontiguousarray(o, dtype=np.float32),
                  np.ascontiguousarray(d, dtype=np.float32), output=1)
    face = res["primID"].astype(np.int64)
    t = res["tfar"].astype(np.float64)
    hit = face >= 0
    t[hit] = refine_t_along(geo, face[hit], shifted[hit], d[hit], t[hit])
    return face, t


class Paths(NamedTuple):
    """A view's live paths at their current vertex: its face, point, normal (turned toward
    the light's side), the direction back toward where the light came from, the path's
    weight so far, its incoming path (−x₁·w, or R₁ from a sensor), its length from x₁, its
    number, and how many flat mirrors it has just met in a row after a surface that is not
    one (:mod:`.mirrors`; 0 otherwise)."""

    face: np.ndarray
    x: np.ndarray
    n: np.ndarray
    wi: np.ndarray
    beta: np.ndarray
    r1: np.ndarray
    length: np.ndarray
    ident: np.ndarray
    run: np.ndarray


class Leg(NamedTuple):
    """One order's returns of a view's sampled paths: the face each leaves from toward the
    receiver, the point, its power per unit irradiance, apparent range and path number."""

    face: np.ndarray
    point: np.ndarray
    value: np.ndarray
    range: np.ndarray
    path: np.ndarray


def blocked(emb, geo, points, d):
    """Whether the ray from each point (scene coordinates, lifted along its direction)
    along ``d`` meets the scene (the receiver lies beyond every face: at infinity, or a
    sensor every face is in front of, as its ray planning checks, so that nothing lies
    beyond it along a ray from the scene)."""
    o = points - geo.center + LIFT * geo.radius * d
    return emb.run(np.ascontiguousarray(o, dtype=np.float32),
                   np.ascontiguousarray(d, dtype=np.float32), query="OCCLUDED") != -1
