"""The deterministic specular chain (meshladar.forward.specular) against geometric optics:
a triangular trihedral's a²/√3 on its axis at the apex's range, a dihedral's
2ab·min(sin θ, cos θ)."""

from __future__ import annotations

import numpy as np
import pytest

import meshladar as ml
from meshladar.brdf import GGX, Lambertian, Phong, SandfordRobertson
from meshladar.errors import ModelError, ParameterError
from meshladar.forward.specular import specular_albedo, specular_chain
from meshladar.meshes import MeshPart

from _quadrature import half_vector_integral

#: Near-mirror faces: SR with ε = 0.1, ρd = 0, b = 0 and e = 0.005: its specular
#: reflectivity is 1 − ε − ρd = 0.9 at every incidence (Eq. A8 with g ≡ G = 1 at b = 0),
#: which the chain multiplies per reflection.
MIRROR = SandfordRobertson(0.0, 0.1, 0.0, 0.005)
#: The ray grid's edge error at 1e-3 spacing on unit faces (measured 4e-4 for the
#: trihedral, whose aperture's edges are oblique to the grid).
GRID_RTOL = 1e-3


def trihedral(a, offset=(0.0, 0.0, 0.0), coating=MIRROR):
    v = np.array([[0, 0, 0], [a, 0, 0], [0, a, 0], [0, 0, a]], float) + offset
    return ml.Scene.from_parts([MeshPart(v, [[0, 1, 2], [0, 2, 3], [0, 3, 1]], 0, "corner")],
                               [coating])


def test_a_trihedral_returns_its_effective_area_at_the_apex_range():
    """On the symmetry axis, ρs³ a²/√3 comes back after three reflections, none after one
    or two, all at the apex's range (every retro path is as long as the apex's), also for
    a corner 100 units from the origin."""
    a, offset = 0.8, np.array([30.0, -60.0, 70.0])
    scene = trihedral(a, offset)
    assert scene.visibility().needs_bounces
    w = np.ones(3) / np.sqrt(3)
    apex = -offset @ w
    lad = ml.Ladar(None, view_vectors=w[None], bin_edges=apex + np.array([-1, -1e-4, 1e-4, 1]))
    out = specular_chain(scene, lad, bounces=3, ray_spacing=1e-3)
    assert out.orders == (1, 2, 3)
    assert out.effective_area[0, 0] == 0 and out.effective_area[1, 0] == 0
    assert out.effective_area[2, 0] == pytest.approx(0.9 ** 3 * a * a / np.sqrt(3),
                                                     rel=GRID_RTOL)
    assert out.values[2, 0, 1] == pytest.approx(out.effective_area[2, 0], rel=1e-12)


@pytest.mark.parametrize("theta_deg", [20.0, 30.0, 45.0, 60.0])
def test_a_dihedral_returns_2ab_min_sin_cos(theta_deg):
    a, b = 1.0, 0.7

    def plate(corners, name):
        return MeshPart(np.array(corners, float), [[0, 1, 2], [0, 2, 3]], 0, name)
    scene = ml.Scene.from_parts([plate([[0, 0, 0], [a, 0, 0], [a, 0, b], [0, 0, b]], "A"),
                                 plate([[0, 0, 0], [0, 0, b], [0, a, b], [0, a, 0]], "B")],
                                [GGX(0.001, 0.8)])
    t = np.radians(theta_deg)
    w = np.array([np.cos(t), np.sin(t), 0.0])
    lad = ml.Ladar(None, view_vectors=w[None], bin_edges=np.linspace(-2, 2, 9))
    out = specular_chain(scene, lad, bounces=2, ray_spacing=1e-3)
    expected = 0.8 ** 2 * 2 * a * b * min(np.sin(t), np.cos(t))
    assert out.effective_area[1, 0] == pytest.approx(expected, rel=GRID_RTOL)
    assert out.effective_area[0, 0] == 0


def test_a_lambertian_surface_ends_the_chain():
    out = specular_chain(trihedral(1.0, coating=Lambertian(0.9)),
                         ml.Ladar(None, view_vectors=[[1.0, 1.0, 1.0]],
                                  bin_edges=np.linspace(-2, 2, 5)), ray_spacing=1e-2)
    assert not out.values.any()


def specular_lobe_albedo(coating, theta):
    """The specular lobe's directional-hemispherical reflectance at θ, by the independent
    half-vector quadrature of its bistatic F·cos θr (lobes="specular")."""
    lobe = SandfordRobertson(coating.rho_d, coating.epsilon, coating.b, coating.e,
                             lobes="specular")
    wi = np.array([np.sin(theta), 0.0, np.cos(theta)])

    def weight(wr, _alpha):
        co = np.clip(wr[:, 2], 0.0, 1.0)
        h = wr + wi
        h = h / np.linalg.norm(h, axis=1, keepdims=True)
        s = [np.sqrt(np.clip(1.0 - x * x, 0.0, 1.0)) for x in (co, h[:, 2])]
        ci = np.full_like(co, np.cos(theta))
        return lobe.bistatic(ci, np.full_like(co, np.sin(theta)), co, s[0], h[:, 2], s[1])
    return half_vector_integral(theta, coating.e, weight, epsrel=1e-8)


def test_an_angle_dependent_specular_reflectivity_enters_each_reflection():
    """SR with b > 0: ρs(θ) changes with incidence (Eq. A8); on the trihedral's axis each
    of the three reflections is at cos θ = 1/√3, so ρs(θ)³ a²/√3 comes back, with ρs
    from the quadrature of the specular lobe (not the chain's albedo)."""
    coating = SandfordRobertson(0.2, 0.3, 0.8, 0.005)
    theta = np.arccos(1.0 / np.sqrt(3.0))
    rho = specular_lobe_albedo(coating, theta)
    assert abs(rho - (1 - 0.5)) > 0.1                           # not 1 − ε − ρd here
    w = np.ones(3) / np.sqrt(3)
    lad = ml.Ladar(None, view_vectors=w[None], bin_edges=[-1.0, -1e-4, 1e-4, 1.0])
    out = specular_chain(trihedral(1.0, coating=coating), lad, bounces=3, ray_spacing=1e-3)
    assert out.effective_area[2, 0] == pytest.approx(rho ** 3 / np.sqrt(3), rel=GRID_RTOL)


@pytest.mark.parametrize("theta_deg", [0.0, 30.0, 60.0, 80.0])
def test_the_specular_albedo_is_the_lobes_reflectance(theta_deg):
    """Against the quadrature of the lobe, to the lobe's width squared (e = 0.005)."""
    coating = SandfordRobertson(0.2, 0.3, 0.8, 0.005)
    t = np.radians(theta_deg)
    assert specular_albedo(coating, np.cos(t)) == pytest.approx(
        specular_lobe_albedo(coating, t), rel=1e-4)


def test_specular_albedos():
    assert specular_albedo(MIRROR) == pytest.approx(0.9, rel=1e-15)
    assert specular_albedo(MIRROR, np.array([0.2, 1.0])) == pytest.approx([0.9, 0.9])
    assert specular_albedo(SandfordRobertson(0.1, 0.9, 0.1, 0.1, lobes="diffuse")) == 0.0
    assert specular_albedo(GGX(0.01, 0.7)) == 0.7
    with pytest.raises(ModelError, match="got Phong"):
        specular_albedo(Phong(0.1, 0.5, 100.0))


@pytest.mark.parametrize("kwargs, match", [
    ({"bounces": 0}, "bounces must be an integer from 1 to 8"),
    ({"bounces": 2.5}, "bounces must be"),
    ({"cone": 0.0}, "cone must be an angle"),
    ({"cone": 2.0}, "cone must be an angle"),
])
def test_bad_input(kwargs, match):
    lad = ml.Ladar(None, view_vectors=[[1.0, 1.0, 1.0]], bin_edges=np.linspace(-2, 2, 5))
    with pytest.raises(ParameterError, match=match):
        specular_chain(trihedral(1.0), lad, ray_spacing=1e-2, **kwargs)
    with pytest.raises(ParameterError, match="mesh scene"):
        specular_chain(ml.Scene([ml.Disk((0, 0), 1.0, MIRROR)]), lad, ray_spacing=1e-2)
