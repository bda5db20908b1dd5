"""The deterministic specular chain: what near-mirror coatings return after k reflections,
in geometric optics: corner reflectors, dihedrals, mirrors.

Where a coating's specular lobe is narrow (SR's e, GGX's α of 0.01 and below), sampling a
path that leaves toward a receiver at infinity is hopeless: each ray is instead reflected
as in a mirror (about the hit face's flat normal, turned toward the light), its power
multiplied at each vertex by the coating's specular albedo at its incidence θ (SR's
ρs(θ) = 1 − (ε + ρd) g(θ)/G(b), Eq. A8; GGX's reflectance: the lobe's
directional-hemispherical reflectance in the narrow-lobe limit; a Lambertian
surface reflects nothing specularly and ends the chain), until it leaves the scene. A
path that leaves after k reflections within ``cone`` of the receiver's direction w is a
k-bounce return: its power per unit incident irradiance (an area, δA⊥ Π ρₛ summed over
rays) is binned at half its optical path, r(x₁) + (L + (x₁ − x_k)·w)/2.

This is the power inside the retro beam, not its intensity: a retroreflector of
effective area A_eff returns ρₛᵏ A_eff, the area of the incoming beam that leaves toward
the receiver after k reflections (a triangular trihedral of edge a on its axis:
A_eff = a²/√3 for k = 3; a dihedral of faces a × b seen at θ from a face, in the plane
normal to its edge: 2ab·min(sin θ, cos θ) for k = 2; both tested). Its cross section
follows from the beam's spread, e.g. 4π A_eff² / λ² for a perfect corner cube of aperture
larger than the wavelength (diffraction) or the convolution of the faces' lobes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..brdf import GGX, Lambertian, SandfordRobertson
from ..errors import ModelError, ParameterError
from ..raytrace.backends import resolve_backend
from ..raytrace.embree import embree_scene, geometry
from ..scene import Scene
from ._paths import cast
from .mesh import first_hits

__all__ = ["SpecularReturns", "specular_albedo", "specular_chain", "RETRO_CONE"]

#: Paths leaving within this angle (radians) of the receiver's direction are returns.
RETRO_CONE = 1e-3


@dataclass(frozen=True)
class SpecularReturns:
    """Power per unit irradiance returned after k mirror reflections, per view and bin.

    Attributes
    ----------
    orders : tuple of int
        1..bounces.
    values : (bounces, n_views, n_bins) numpy.ndarray
        Square scene units (the incoming beam's area that returns, times Π ρₛ).
    effective_area : (bounces, n_views) numpy.ndarray
        The same summed over the bins.
    cone : float
        The acceptance angle about w, radians.
    """

    orders: tuple
    values: np.ndarray
    effective_area: np.ndarray
    cone: float


def specular_albedo(coating, cos_theta=1.0):
    """A coating's specular albedo in the narrow-lobe limit (module docstring): the
    specular lobe's directional-hemispherical reflectance at incidence θ.

    Parameters
    ----------
    coating : BRDF
        SandfordRobertson, GGX or Lambertian.
    cos_theta : float or array_like
        cos θ of the incidence (default 1: normal incidence); clipped to [0, 1].

    Returns
    -------
    float or numpy.ndarray
        SR's ρs(θ) = 1 − (ε + ρd) g(θ)/G(b) (A8; ε is the emissivity, not the
        reflectance; 0 for ``lobes="diffuse"``), GGX's reflectance, 0 for Lambertian; of
        ``cos_theta``'s shape.

    Raises
    ------
    ModelError
        For any other model (its specular albedo is not known here).
    """
    c = np.clip(np.asarray(cos_theta, np.float64), 0.0, 1.0)
    if isinstance(coating, SandfordRobertson):
        out = c * 0.0 if coating.lobes == "diffuse" else \
            coating.specular_reflectance(np.arccos(c)) + c * 0.0
    elif isinstance(coating, GGX):
        out = c * 0.0 + float(coating.reflectance)
    elif isinstance(coating, Lambertian):
        out = c * 0.0
    else:
        raise ModelError(f"the specular chain knows the specular albedo of SandfordRobertson, "
                     f"GGX and Lambertian coatings; got {type(coating).__name__}")
    return float(out) if out.ndim == 0 else out


def _albedos(materials, mat, cos_theta):
    """Each vertex's specular albedo at its incidence (:func:`specular_albedo`)."""
    out = np.zeros(len(mat))
    for i, m in enumerate(materials):
        sel = mat == i
        if np.any(sel):
            out[sel] = specular_albedo(m, cos_theta[sel])
    return out


def specular_chain(scene, ladar, *, bounces=3, ray_spacing, cone=RETRO_CONE):
    """Mirror-reflected returns of orders 1..``bounces`` (module docstring).

    Parameters
    ----------
    scene : Scene
        A mesh scene.
    ladar : Ladar
        Views (monostatic, at infinity) and range bins.
    bounces : int
        The most reflections followed, 1 to 8.
    ray_spacing : float
        The first hits' grid spacing, scene units.
    cone : float
        Acceptance half-angle about the receiver's direction, radians in (0, π/2].

    Returns
    -------
    SpecularReturns
        Per order, view and bin.

    Raises
    ------
    ParameterError
        For an analytic scene, ``bounces`` outside 1..8 or ``cone`` outside (0, π/2].
    ModelError
        For a coating whose specular albedo is not known (:func:`specular_albedo`).
    """
    if not isinstance(scene, Scene) or not scene.is_mesh:
        raise ParameterError("specular_chain needs a mesh scene")
    if isinstance(bounces, bool) or not isinstance(bounces, (int, np.integer)) or \
            not 1 <= bounces <= 8:
        raise ParameterError(f"bounces must be an integer from 1 to 8; got {bounces!r}")
    if not 0 < cone <= np.pi / 2:
        raise ParameterError(f"cone must be an angle in (0, pi/2] radians; got {cone!r}")
    for m in scene.materials:
        specular_albedo(m)                                  # known, before any ray
    geo = geometry(scene, "flat")
    emb = embree_scene(geo, resolve_backend("auto"))
    out = np.zeros((bounces, ladar.n_views, ladar.n_bins))
    for i, w in enumerate(np.asarray(ladar.view_vectors, np.float64)):
        out[:, i] = _view_chain(scene, geo, emb, w, ladar.bin_edges, ray_spacing,
                                (bounces, np.cos(cone)))
    return SpecularReturns(tuple(range(1, bounces + 1)), out, out.sum(axis=2), float(cone))


def _view_chain(scene, geo, emb, w, edges, spacing, plan):
    """One view's mirror chains: (bounces, bins) returned power."""
    bounces, cos_cone = plan
    out = np.zeros((bounces, len(edges) - 1))
    x, f, r1 = first_hits(scene, w, ray_spacing=spacing)
    x1, d = x, np.broadcast_to(-w, x.shape)
    beta = np.full(len(f), spacing * spacing)
    length = np.zeros(len(f))
    for k in range(bounces):
        n = geo.face_normals[f]
        n = n * np.sign(-np.einsum("ij,ij->i", n, d))[:, None]
        beta = beta * _albedos(scene.materials, geo.material[f],
                               -np.einsum("ij,ij->i", n, d))
        d = d - 2.0 * np.einsum("ij,ij->i", d, n)[:, None] * n
        go = beta > 0
        x, n, d, beta, length, x1, r1 = (a[go] for a in (x, n, d, beta, length, x1, r1))
        f, t = cast(emb, geo, x, n, d)
        leave = (f < 0) & (d @ w >= cos_cone)
        rng = r1[leave] + 0.5 * (length[leave] + (x1[leave] - x[leave]) @ w)
        out[k] = np.histogram(rng, edges, weights=beta[leave])[0]
        hit = f >= 0
        t = t[hit]
        x = x[hit] + t[:, None] * d[hit]
        f, d, beta, x1, r1 = f[hit], d[hit], beta[hit], x1[hit], r1[hit]
        length = length[hit] + t
    return out
