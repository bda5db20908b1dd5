"""Next-event estimation through flat mirrors: the deterministic specular chain inside the
bounce sampling (:mod:`.bounces`), where sampling would be hopeless.

A diffuse vertex joined to the receiver by a shadow ray finds a near-mirror surface's
glint only if its incoming direction falls within the lobe's width s of the mirror
direction: the chance is ~s², so the variance of a diffuse-then-mirror return grows as
1/s² (measured on a Lambertian plate facing a mirror of SR e = 0.01 to 0.003 at 65,536
paths: relative standard errors of 12 % and a total 30 % low). Here such returns are
computed without sampling the glint.

A **mirror** is a flat part (:func:`~meshladar.meshes.visibility.part_plane`) whose every
face's coating has a specular lobe no wider than :data:`MIRROR_LOBE` (SR's e or GGX's α),
no diffuse lobe (a mirror vertex emits no chain, so light its diffuse lobe sent on through
another mirror would be counted by neither estimate) and a known specular albedo (:func:`~meshladar.forward.specular.specular_albedo`). An
**emitter** is a vertex whose coating has no lobe that narrow. From each emitter x, for
each chain of up to :data:`MIRROR_CHAIN` mirrors P₁ … P_m (consecutive ones distinct), the
direction d₀ that leaves the last mirror toward the receiver is found by reflecting the
receiver's direction w_r about the mirrors' planes in turn (d₀ = R₁ ⋯ R_m w_r; toward a
sensor at a finite standoff, toward its image M₁ ⋯ M_m S), and one ray is followed along
it. Where it meets P₁, then P₂, … and leaves the last unoccluded, the return is

    β · F_x(w_i, d₀) cos θ_d₀ · Π ρs,j(θ_j)

(the path's weight β so far, the emitter's bistatic weight, each mirror's specular albedo
at its incidence: the glint taken as a delta about the mirror direction, whose error is of
the order of s² where the light arriving varies slowly over the lobe), at half the
unfolded optical path, and with a sensor at a finite standoff its solid angle (D/R)² for
R the unfolded distance from x to the sensor. Under the paper's Eq. 8 the last mirror
weighs ρs/cos θr (and, toward a sensor at a finite standoff, its area per emitter area
(R_y/R)², R_y its own distance from the sensor).

So that no path counts twice, the shadow ray from a mirror vertex that ends such a run
(a path that met an emitter and then 1 … MIRROR_CHAIN mirrors, every one flat) weighs the
mirror's coating without its specular lobe. Every other path is sampled as before:
mirror-first paths (the ladar's beam on a mirror) sample the lobe at every vertex, which
does not degrade with s.
"""

from __future__ import annotations

from itertools import product
from typing import NamedTuple

import numpy as np

from ..brdf import SandfordRobertson
from ..errors import ModelError
from ..meshes.part import axis_spans
from ..meshes.visibility import CONVEX_RTOL, part_plane
from ..precision import COS_HORIZON
from ..weighing.hit_weights import GRAZING_RECEIVER_COS
from ._paths import Leg, blocked, cast, dot, glint_of, lobe_width, warn_edge_on, weight
from .specular import specular_albedo

__all__ = ["MIRROR_LOBE", "MIRROR_CHAIN", "MAX_CHAINS", "Mirrors", "find_mirrors", "chains",
           "through_mirrors"]

#: Coatings whose specular lobe is no wider than this are mirrors on flat parts.
MIRROR_LOBE = 1e-2
#: The most mirrors one chain from an emitter passes through.
MIRROR_CHAIN = 3
#: The most chains followed from each vertex: with more mirror planes the chains are
#: shortened, and with more than this many planes the mirrors are sampled like any surface.
MAX_CHAINS = 64


class Mirrors(NamedTuple):
    """A scene's flat mirrors and who emits toward them.

    Attributes
    ----------
    part : tuple of tuple of int
        Each mirror plane's parts (coplanar mirror parts are one mirror: the same
        reflection).
    normal, point : (m, 3) numpy.ndarray
        Each mirror's plane: unit normal and a point on it (scene coordinates).
    of_face : (n_faces,) numpy.ndarray of int
        Each face's mirror, −1 for a face on none.
    longest : int
        The longest chain followed: MIRROR_CHAIN, or fewer where the chains of that many
        mirrors would exceed MAX_CHAINS.
    emits : (n_materials,) numpy.ndarray of bool
        Coatings without a lobe as narrow as MIRROR_LOBE.
    glints : tuple of BRDF
        Per coating, its specular lobe alone (the coating itself where it is no mirror's).
    """

    part: tuple
    normal: np.ndarray
    point: np.ndarray
    of_face: np.ndarray
    longest: int
    emits: np.ndarray
    glints: tuple


def _narrow(m):
    """Whether a coating makes a mirror: a glint no wider than MIRROR_LOBE, no diffuse lobe
    (a mirror vertex is never an emitter, so light its diffuse lobe sent on through another
    mirror would be counted by neither estimate), and a known specular albedo."""
    width = lobe_width(m)
    if not width <= MIRROR_LOBE or (isinstance(m, SandfordRobertson) and m.has_diffuse):
        return False
    try:
        specular_albedo(m)
    except ModelError:
        return False
    return True


def find_mirrors(scene, geo):
    """The scene's flat mirrors (module docstring), or None when it has none or no coating
    emits toward them.

    Parameters
    ----------
    scene : Scene
        The mesh scene.
    geo :
        Its flat-normal geometry (:mod:`meshladar.raytrace.embree`).

    Returns
    -------
    Mirrors or None
        The mirrors (found once per scene and MIRROR_LOBE: every view's walk asks).
    """
    return scene.cached(("mirrors", MIRROR_LOBE), lambda: _found(scene, geo))


def _found(scene, geo):
    narrow = np.array([_narrow(m) for m in scene.materials])
    emits = np.array([not (lobe_width(m) <= MIRROR_LOBE) for m in scene.materials])
    planes = []                                 # [normal, point, parts]
    for i, part in enumerate(scene.parts):
        if len(part.faces) and np.all(narrow[part.material]):
            plane = part_plane(part)
            if plane is not None:
                _join(planes, plane, i, part)
    m = len(planes)                             # chains of k: m (m − 1)^(k − 1)
    longest = max([k for k in range(1, MIRROR_CHAIN + 1)
                   if m * (m - 1) ** (k - 1) <= MAX_CHAINS], default=0)
    if not planes or not longest or not emits.any():
        return None
    of_part = np.full(len(scene.parts), -1)
    for k, (_, _, parts) in enumerate(planes):
        of_part[parts] = k
    return Mirrors(tuple(tuple(p[2]) for p in planes), np.array([p[0] for p in planes]),
                   np.array([p[1] for p in planes]), of_part[geo.part_of], longest, emits,
                   tuple(glint_of(m) for m in scene.materials))


def _join(planes, plane, index, part):
    """Add a mirror part to the plane it lies in, or as a new plane."""
    normal, point = plane
    tol = CONVEX_RTOL * float(np.linalg.norm(axis_spans(part.vertices)))
    for p in planes:
        if abs(abs(float(p[0] @ normal)) - 1.0) <= 1e-12 and \
                np.all(np.abs((part.vertices - p[1]) @ p[0]) <= max(tol, 1e-300)):
            p[2].append(index)
            return
    planes.append([np.asarray(normal, np.float64), np.asarray(point, np.float64), [index]])


def chains(count, longest):
    """Chains of 1..``longest`` mirrors out of ``count``, consecutive ones distinct (a flat
    mirror cannot see itself).

    Parameters
    ----------
    count : int
        The mirrors.
    longest : int
        The longest chain.

    Returns
    -------
    list of tuple of int
        The chains, shortest first.
    """
    out = []
    for m in range(1, longest + 1):
        out += [c for c in product(range(count), repeat=m)
                if all(a != b for a, b in zip(c, c[1:]))]
    return out


def _reflect(d, n):
    return d - 2.0 * (d @ n)[..., None] * n if d.ndim > 1 else d - 2.0 * (d @ n) * n


def _first_direction(ends, mirrors, chain, x):
    """d₀ from each emitter x (k, 3) through ``chain`` to the receiver."""
    if ends.position is None:
        d = ends.w_r
        for j in reversed(chain):
            d = _reflect(d, mirrors.normal[j])
        return np.broadcast_to(d, x.shape)
    image = ends.position
    for j in reversed(chain):
        image = image - 2.0 * ((image - mirrors.point[j]) @ mirrors.normal[j]) * \
            mirrors.normal[j]
    d = image - x
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def through_mirrors(scene, geo, emb, ends, mirrors, paths, longest):
    """The returns of the emitters among ``paths`` through chains of up to ``longest``
    mirrors (module docstring).

    Parameters
    ----------
    scene : Scene
        The mesh scene.
    geo, emb :
        Its flat-normal geometry and Embree scene.
    ends : Ends
        The view's ends (:mod:`.bounce_ends`).
    mirrors : Mirrors
        The scene's mirrors.
    paths : Paths
        The live paths at their current vertex.
    longest : int
        The longest chain (the orders left, at most MIRROR_CHAIN).

    Returns
    -------
    list of (int, Leg)
        Per chain with a return, its length m (the order is the vertex's plus m) and the
        returns.
    """
    go = mirrors.emits[geo.material[paths.face]] & (paths.beta > 0)
    if not go.any() or longest < 1:
        return []
    out = []
    for chain in chains(len(mirrors.part), min(longest, mirrors.longest)):
        leg = _one_chain(scene, geo, emb, ends, mirrors, paths, go, chain)
        if leg is not None:
            out.append((len(chain), leg))
    return out


def _one_chain(scene, geo, emb, ends, mirrors, paths, go, chain):
    x, n = paths.x[go], paths.n[go]
    d = _first_direction(ends, mirrors, chain, x)
    beta = paths.beta[go] * weight(scene.materials, geo.material[paths.face[go]], n,
                                   paths.wi[go], d)
    keep = np.flatnonzero(go)[beta > 0]
    x, n, d, beta = x[beta > 0], n[beta > 0], d[beta > 0], beta[beta > 0]
    travelled = np.zeros(len(x))
    face = None
    for j in chain:
        if not len(x):
            return None
        f, t = cast(emb, geo, x, n, d)
        ok = f >= 0
        ok[ok] = mirrors.of_face[f[ok]] == j
        x, d, t, f = x[ok] + t[ok, None] * d[ok], d[ok], t[ok], f[ok]
        n = mirrors.normal[j] * np.sign(-(d @ mirrors.normal[j]))[:, None]
        cos = -dot(n, d)
        beta = beta[ok] * _albedo(scene, geo, f, cos)
        travelled, keep, face = travelled[ok] + t, keep[ok], f
        d = _reflect(d, mirrors.normal[j])
    return _leave(ends, geo, emb, (face, x, n, d, beta, travelled), paths, keep)


def _albedo(scene, geo, faces, cos):
    out = np.zeros(len(faces))
    mat = geo.material[faces]
    for i in np.unique(mat):
        sel = mat == i
        out[sel] = specular_albedo(scene.materials[i], cos[sel])
    return out


def _leave(ends, geo, emb, state, paths, keep):
    """The chain's last mirror joined to the receiver: a Leg, or None."""
    face, y, n, d, beta, travelled = state
    if ends.position is not None:
        to = ends.position - y
        d = to / np.linalg.norm(to, axis=1, keepdims=True)
    seen = dot(n, d) > 0
    seen[seen] = ~blocked(emb, geo, y[seen], d[seen])
    if not seen.any():
        return None
    face, y, n, d, beta, travelled, keep = (a[seen] for a in (face, y, n, d, beta,
                                                               travelled, keep))
    r1, length = paths.r1[keep], paths.length[keep] + travelled
    if ends.position is None:
        out = -(y @ ends.w_r)
    else:
        # the sensor seen from the emitter through the mirrors is its image, `unfolded`
        # away: the receiver's solid angle (D/unfolded)² under power; under the paper's
        # Eq. 8 (no receiver factor) the last mirror's area per emitter area,
        # (out/unfolded)² (times the cosines below)
        out = np.linalg.norm(ends.position - y, axis=1)
        unfolded = travelled + out
        if ends.power:
            beta = beta * (ends.sensor.standoff / unfolded) ** 2 * np.exp(
                -ends.sensor.extinction * (r1 + length + out))
        else:
            beta = beta * (out / unfolded) ** 2
    if not ends.power:
        cos = dot(n, d)
        beta = beta / np.maximum(cos, COS_HORIZON)
        warn_edge_on(beta * (cos < GRAZING_RECEIVER_COS), beta)
    return Leg(face, y, beta, 0.5 * (r1 + length + out) - ends.offset, paths.ident[keep])
