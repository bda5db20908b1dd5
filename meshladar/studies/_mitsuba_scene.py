"""The Mitsuba scene of :func:`meshladar.studies.peer.mitransient_profile`: the checked
target, its diffuse (two-sided) mesh, the orthographic sensor's frame, the film's
path-length mapping and the single-bounce transient scene. ``mi`` is the loaded Mitsuba
module (imported lazily by the peer module)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


def _opl_mapping(mi, mesh, w, fr, edges, width):
    """The film's path-length mapping (see :func:`meshladar.studies.peer.mitransient_profile`)."""
    r_bs = float(mi.load_dict({"type": "scene", "target": mesh}).bbox().bounding_sphere()
                 .radius)
    eps = float(mi.math.RayEpsilon)
    r_near = float(-(fr.origin @ w) + fr.near)
    const = 2.0 * r_bs * (1.0 + eps)
    start = float(edges[0] - r_near + const)
    return {"start_opl": start, "bin_width_opl": width, "r_near": r_near,
            "bounding_radius": r_bs, "ray_epsilon": eps,
            "formula": "opl = r - r_near + 2 R_bs (1 + RayEpsilon)"}


class _Target(NamedTuple):
    """A checked target: vertices, faces, unit view w and range edges."""

    v: np.ndarray
    f: np.ndarray
    w: np.ndarray
    edges: np.ndarray


def _checked(vertices, faces, view, bin_edges):
    """The mesh, unit view and range edges as float64/int64 arrays, checked."""
    v = np.ascontiguousarray(vertices, dtype=np.float64)
    f = np.ascontiguousarray(faces, dtype=np.int64)
    if v.ndim != 2 or v.shape[1] != 3 or f.ndim != 2 or f.shape[1] != 3 or len(f) == 0:
        raise ValueError("vertices must be (n, 3) and faces (m, 3), m >= 1")
    if f.min() < 0 or f.max() >= len(v):
        raise ValueError("faces index vertices out of range")
    w = np.asarray(view, dtype=np.float64).reshape(3)
    w = w / np.linalg.norm(w)
    return _Target(v, f, w, np.asarray(bin_edges, dtype=np.float64))


def _samples(spp, sampler):
    """Samples per pixel: the stratified samplers stratify a square grid per pixel (and
    round any other count up)."""
    spp = int(spp)
    if spp < 1:
        raise ValueError(f"spp must be a positive integer; got {spp}")
    if sampler in ("stratified", "ldsampler", "multijitter"):
        spp = int(np.ceil(np.sqrt(spp))) ** 2
    return spp


def _target(mi, v, f, reflectance, two_sided):
    """The mesh as a Mitsuba shape with its (two-sided) BSDF: diffuse of ``reflectance``,
    or ``reflectance`` itself when it is a Mitsuba BSDF dictionary."""
    bsdf = reflectance if isinstance(reflectance, dict) else {
        "type": "diffuse", "reflectance": {"type": "uniform", "value": float(reflectance)}}
    if two_sided:
        bsdf = {"type": "twosided", "bsdf": bsdf}
    props = mi.Properties()
    props["bsdf"] = mi.load_dict(bsdf)
    mesh = mi.Mesh("target", len(v), len(f), props=props, has_vertex_normals=False)
    params = mi.traverse(mesh)
    params["vertex_positions"] = mi.Float(v.astype(np.float32).ravel())
    params["faces"] = mi.UInt32(f.astype(np.uint32).ravel())
    params.update()
    return mesh


def _transient_scene(mi, mesh, w, fr, sampling, max_depth=2):
    """The transient scene: a directional emitter along −w, the orthographic sensor of frame
    ``fr`` with ``sampling``'s sampler and film; ``max_depth`` 2 is the single bounce, each
    more one bounce more."""
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "transient_path", "max_depth": int(max_depth)},
        "emitter": {"type": "directional", "direction": (-w).tolist(), "irradiance": 1.0},
        "target": mesh,
        "sensor": {"type": "orthographic", "to_world": fr.to_world, "near_clip": fr.near,
                   "far_clip": fr.dist + 2.0 * fr.rad + fr.near, **sampling},
    })

class _Frame(NamedTuple):
    """The orthographic sensor's frame: half-width h, distance, near clip, bounding
    radius, origin and its to_world transform."""

    h: float
    dist: float
    near: float
    rad: float
    origin: np.ndarray
    to_world: object


def _frame(mi, v, w, nx, ny):
    """The sensor's x spans [-h, h], y [-h ny/nx, h ny/nx] (square pixels of side 2h/nx);
    it covers the vertices' bounding sphere about the bbox centre."""
    c = 0.5 * (v.min(axis=0) + v.max(axis=0))
    rad = float(np.sqrt(((v - c) ** 2).sum(axis=1).max()))
    rad = max(rad, 1e-6)
    h = rad * (1.0 + 1e-3) * max(1.0, nx / ny)
    dist = 2.0 * rad
    near = 1e-3 * rad
    origin = c + dist * w
    up = np.array([0.0, 0.0, 1.0]) if abs(w[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    to_world = (mi.ScalarTransform4f().look_at(origin=origin.tolist(), target=c.tolist(),
                                               up=up.tolist())
                @ mi.ScalarTransform4f().scale([h, h, 1.0]))
    return _Frame(h, dist, near, rad, origin, to_world)
