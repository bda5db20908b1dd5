"""A user's coating that computes a built-in's function gives the built-in's sinogram.

Every forward model hands a coating (cos θ, sin θ) pairs through the BRDF protocol
(``projected(cos_theta, sin_theta)``); a user's model is free to read the angle from the
pair, so the pair must be a unit pair everywhere (issue 28: the pixel model clamped cos θ to
0 for back-facing staircase pixels but kept their sin θ, and the SR coating returned 16×
its grazing value there while a model reading the angle returned the grazing value).
"""

from __future__ import annotations

import numpy as np
import pytest

import meshladar as ml
from meshladar.materials import ALUMINUM, DARK_GRAY

#: the issue's bound: the same function gives the same sinogram to 1e-9 relative (bins far
#: below the profile's maximum to 1e-9 of the maximum)
RTOL = 1e-9

_VIEWS = ml.Ladar.paper(0.8, angles_deg=np.linspace(0.0, 360.0, 12, endpoint=False) + 0.37)


class AngleSR(ml.brdf.BRDF):
    """The Sandford-Robertson function computed from the ANGLE θ = atan2(sin θ, cos θ),
    through the built-in's public ``monostatic``: a user's model, not a built-in."""

    def __init__(self, sr):
        self.sr = sr
        self.name = f"angle {sr.name}"

    @property
    def angular_scales(self):
        # the same quadrature hints as the built-in (the analytic model grades its pieces
        # to them), so that the two sinograms differ only through the function's values
        return self.sr.angular_scales

    def projected(self, cos_theta, sin_theta):
        theta = np.arctan2(np.asarray(sin_theta, np.float64), np.asarray(cos_theta, np.float64))
        return self.sr.monostatic(theta, projected=True)


def _pair(big, small):
    return ml.phantoms.scene("disk_pair", large=big, small=small)


def _same(user, builtin):
    u, b = user.values, builtin.values
    assert u.shape == b.shape and np.abs(b).max() > 0
    np.testing.assert_allclose(u, b, rtol=RTOL, atol=RTOL * np.abs(b).max())


def test_the_user_model_is_not_a_builtin():
    assert not ml.brdf.is_builtin(AngleSR(ALUMINUM))
    assert AngleSR(ALUMINUM).kernel_params is None         # the mesh model's numpy path
    theta = np.linspace(0.0, 0.5 * np.pi, 101)
    np.testing.assert_allclose(AngleSR(ALUMINUM).monostatic(theta, projected=True),
                               ALUMINUM.monostatic(theta, projected=True), rtol=1e-12)


@pytest.mark.parametrize("model", ["analytic", "pixel"])
@pytest.mark.parametrize("radiometry", ["paper", "power"])
def test_analytic_and_pixel_models(model, radiometry):
    user = ml.simulate(_pair(AngleSR(DARK_GRAY), AngleSR(ALUMINUM)), _VIEWS, model=model,
                       radiometry=radiometry)
    builtin = ml.simulate(_pair(DARK_GRAY, ALUMINUM), _VIEWS, model=model,
                          radiometry=radiometry)
    _same(user, builtin)


def test_pixel_back_facing_pixels_weigh_as_grazing():
    """Staircase pixels whose centre normal faces away (cos θ < 0) are weighed as at
    grazing incidence, (cos θ, sin θ) = (0, 1): their weight is F(π/2) cos(π/2) times the
    ray's largest arc, as for the built-in coating and a user's."""
    scene = ml.Scene([ml.Disk((0.0, 0.0), 0.8, ALUMINUM)])
    lad = ml.Ladar.paper(0.8, angles_deg=[0.37])
    grazing = ALUMINUM.projected(np.array([0.0]), np.array([1.0]))[0]
    assert grazing > 0
    user = ml.simulate(ml.Scene([ml.Disk((0.0, 0.0), 0.8, AngleSR(ALUMINUM))]), lad,
                       model="pixel")
    _same(user, ml.simulate(scene, lad, model="pixel"))


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # faceted on purpose
@pytest.mark.parametrize("normals", ["flat", "smooth", "exact"])
@pytest.mark.parametrize("back_faces", ["two-sided", "ignore"])
def test_mesh_model(normals, back_faces):
    lad = ml.Ladar.paper(0.8, angles_deg=[0.37, 33.0, 90.0, 211.0])
    kw = dict(model="mesh", normals=normals, back_faces=back_faces, rays_per_bin=2)
    user = ml.simulate(_pair(AngleSR(DARK_GRAY), AngleSR(ALUMINUM)).tessellate(64), lad,
                       **kw)
    builtin = ml.simulate(_pair(DARK_GRAY, ALUMINUM).tessellate(64), lad, **kw)
    _same(user, builtin)


def test_mesh_model_power():
    lad = ml.Ladar.paper(0.8, angles_deg=[0.37, 90.0])
    kw = dict(model="mesh", normals="exact", radiometry="power", rays_per_bin=2)
    _same(ml.simulate(_pair(AngleSR(DARK_GRAY), AngleSR(ALUMINUM)).tessellate(64), lad, **kw),
          ml.simulate(_pair(DARK_GRAY, ALUMINUM).tessellate(64), lad, **kw))


class Recording(AngleSR):
    """AngleSR that keeps every (cos θ, sin θ) pair it is handed."""

    def __init__(self, sr):
        super().__init__(sr)
        self.pairs = []

    def projected(self, cos_theta, sin_theta):
        c, s = np.broadcast_arrays(np.asarray(cos_theta, np.float64),
                                   np.asarray(sin_theta, np.float64))
        self.pairs.append(np.stack([c.ravel(), s.ravel()], -1))
        return super().projected(cos_theta, sin_theta)


@pytest.mark.parametrize("model, options", [
    ("analytic", {}), ("pixel", {}), ("pixel", {"pixel_size": 0.05}),
    ("mesh", {"normals": "exact", "back_faces": "ignore"}),
    ("mesh", {"normals": "smooth", "back_faces": "two-sided"}),
    ("mesh", {"normals": "flat", "back_faces": "two-sided"})])
def test_every_pair_a_model_sees_is_a_unit_pair(model, options):
    """cos θ ≥ 0 and cos²θ + sin²θ = 1 for every pair handed to a user's model, including
    the pixel model's staircase pixels facing away (many on a coarse grid) and the mesh
    model's hits whose shading normal faces away."""
    big, small = Recording(DARK_GRAY), Recording(ALUMINUM)
    scene = _pair(big, small)
    if model == "mesh":
        scene = scene.tessellate(64)
        options = {**options, "rays_per_bin": 2}
    ml.simulate(scene, _VIEWS, model=model, **options)
    pairs = np.concatenate(big.pairs + small.pairs)
    assert len(pairs) > 0
    c, s = pairs[:, 0], pairs[:, 1]
    assert c.min() >= 0.0 and s.min() >= 0.0
    np.testing.assert_allclose(np.hypot(c, s), 1.0, rtol=0, atol=1e-12)
