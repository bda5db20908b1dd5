"""Laser radar cross sections (meshladar.forward.lrcs) against closed forms: a Lambertian
sphere (8/3)πρR², a plate 4ρA cos²θ, a disk's 2πρR per unit height; per part, bistatic,
and what is refused."""

from __future__ import annotations

import numpy as np
import pytest

import meshladar as ml
from meshladar.brdf import Lambertian
from meshladar.errors import ParameterError
from meshladar.meshes import MeshPart

RHO = 0.5


def test_a_lambertian_sphere_converges_at_the_faceting_order():
    """(8/3)πρR²: the relative error falls about fourfold per subdivision (h²), and is
    below 4e-4 at five."""
    errors = []
    for sub in (3, 4, 5):
        ball = ml.Scene.from_parts([ml.meshes.sphere((0, 0, 0), 1.0, 0, subdivisions=sub)],
                                   [Lambertian(RHO)])
        s = ml.lrcs(ball, [0.0, 37.0], ray_spacing=2e-3)
        errors.append(abs(s.values[0] / (8 / 3 * np.pi * RHO) - 1))
        assert s.units == "unit^2" and s.bounces == 1
        np.testing.assert_allclose(s.profile.values.sum(axis=1), s.values, rtol=1e-12)
    assert errors[2] < 4e-4
    assert 3.0 < errors[0] / errors[1] < 5.0 and 3.0 < errors[1] / errors[2] < 5.0


def test_an_analytic_disk_is_exact_per_unit_height():
    disk = ml.Scene([ml.Disk((0.2, 0.1), 0.7, Lambertian(RHO))])
    s = ml.lrcs(disk, [0.0, 90.0, 233.0])
    np.testing.assert_allclose(s.values, 2 * np.pi * RHO * 0.7, rtol=1e-12)
    assert s.units == "unit^2 per unit height"


@pytest.mark.parametrize("theta_deg", [0.0, 30.0, 60.0, 85.0])
def test_a_lambertian_plate_far_from_the_origin(theta_deg):
    """4ρA cos²θ for a 2 × 1 plate 200 units from the origin (rays 1e-3 apart: the grid's
    edge error is below 1e-5 of the area)."""
    plate = MeshPart(np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [0, 1, 0.0]]) + [100, 200, 50],
                     [[0, 1, 2], [0, 2, 3]], 0, "plate")
    t = np.radians(theta_deg)
    s = ml.lrcs(ml.Scene.from_parts([plate], [Lambertian(RHO)]),
                [[np.sin(t), 0.0, np.cos(t)]], ray_spacing=1e-3)
    assert s.values[0] == pytest.approx(4 * RHO * 2.0 * np.cos(t) ** 2, rel=1e-5)


def test_per_part_shares_sum_to_the_whole_when_parts_do_not_shadow():
    """Two spheres apart, seen across the line joining them: each part's σ is its own
    sphere's (8/3)πρR² and the shares sum to the total."""
    parts = [ml.meshes.sphere((0, 0, 0), 1.0, 0, subdivisions=5, name="big"),
             ml.meshes.sphere((0, 5, 0), 0.5, 0, subdivisions=5, name="small")]
    scene = ml.Scene.from_parts(parts, [Lambertian(RHO)])
    s = ml.lrcs(scene, [0.0], per_part=True, ray_spacing=4e-3)
    assert s.names == ("big", "small")
    np.testing.assert_allclose(s.per_part[0], 8 / 3 * np.pi * RHO * np.array([1.0, 0.25]),
                               rtol=2e-3)
    assert s.per_part.sum() == pytest.approx(s.values[0], rel=1e-12)


def test_a_bistatic_plate():
    """A plate lit along its normal, received at 60° from it: 4πρ/π A cos θi cos θr."""
    plate = MeshPart(np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0.0]]),
                     [[0, 1, 2], [0, 2, 3]], 0, "plate")
    t = np.radians(60.0)
    s = ml.lrcs(ml.Scene.from_parts([plate], [Lambertian(RHO)]), [[0.0, 0.0, 1.0]],
                receiver=(np.sin(t), 0.0, np.cos(t)), ray_spacing=1e-3)
    assert s.values[0] == pytest.approx(4 * RHO * 1.0 * np.cos(t), rel=1e-5)


@pytest.mark.parametrize("kwargs, match", [
    ({"radiometry": "paper"}, "lrcs takes no radiometry option"),
    ({"per_part": "yes"}, "per_part must be True or False"),
    ({"bounces": 9}, "bounces must be an integer from 1 to 8"),
    ({"bounces": "x"}, "bounces must be an integer from 1 to 8"),
    ({"n_bins": 0}, "n_bins"),
    ({"model": "ray"}, "model"),
])
def test_bad_input_is_refused(kwargs, match):
    ball = ml.Scene.from_parts([ml.meshes.sphere((0, 0, 0), 1.0, 0)], [Lambertian(RHO)])
    with pytest.raises(ParameterError, match=match):
        ml.lrcs(ball, [0.0], **kwargs)


def test_bad_views_are_refused():
    ball = ml.Scene.from_parts([ml.meshes.sphere((0, 0, 0), 1.0, 0)], [Lambertian(RHO)])
    with pytest.raises(ParameterError, match="views"):
        ml.lrcs(ball, [[[0.0, 1.0, 0.0]]])
    with pytest.raises(ParameterError, match="finite"):
        ml.lrcs(ball, [np.nan])


def test_per_part_shares_with_bounces_sum_to_the_whole():
    """A Lambertian dihedral with its second bounce: each plate's share is its single
    bounce plus the paths leaving from it; the shares sum to σ (the same paths), and by
    symmetry (view at 45°) the two plates' shares agree within their sampling error."""
    from meshladar.meshes import MeshPart as Part
    plates = [Part([[0, 0, 0], [1, 0, 0], [1, 0, 0.7], [0, 0, 0.7]], [[0, 1, 2], [0, 2, 3]], 0,
                   "a"),
              Part([[0, 0, 0], [0, 0, 0.7], [0, 1, 0.7], [0, 1, 0]], [[0, 1, 2], [0, 2, 3]], 0,
                   "b")]
    scene = ml.Scene.from_parts(plates, [Lambertian(RHO)])
    s = ml.lrcs(scene, [45.0], bounces=2, per_part=True, ray_spacing=2e-3,
                bounce_samples=1 << 18, seed=0)
    assert s.bounces == 2
    assert s.per_part.sum() == pytest.approx(s.values[0], rel=1e-9)
    single = 4 * RHO * 0.7 * np.cos(np.radians(45.0)) ** 2      # each plate: 4ρA cos²θ
    assert np.all(s.per_part[0] > single)
    assert s.per_part[0, 0] == pytest.approx(s.per_part[0, 1], rel=0.02)


def test_the_bins_hold_every_higher_order_return():
    """σ with three bounces equals 4π × the same paths' totals in bins ten scene sizes
    wide (same seed, same spacing: the same paths): no return falls outside the bins that
    lrcs chooses (the farthest range plus (k − 1) D / 2)."""
    from meshladar.meshes import MeshPart as Part
    plates = [Part([[0, 0, 0], [1, 0, 0], [1, 0, 0.7], [0, 0, 0.7]], [[0, 1, 2], [0, 2, 3]], 0,
                   "a"),
              Part([[0, 0, 0], [0, 0, 0.7], [0, 1, 0.7], [0, 1, 0]], [[0, 1, 2], [0, 2, 3]], 0,
                   "b")]
    scene = ml.Scene.from_parts(plates, [Lambertian(0.9)])
    s = ml.lrcs(scene, [20.0], bounces=3, ray_spacing=1e-2, bounce_samples=1 << 14, seed=3)
    wide = ml.simulate(scene, ml.Ladar([20.0], np.linspace(-10.0, 10.0, 101)), model="mesh",
                       radiometry="power", ray_spacing=1e-2, bounces=3,
                       bounce_samples=1 << 14, seed=3)
    assert s.values[0] == pytest.approx(4 * np.pi * sum(wide.info["order_totals"]), rel=1e-9)


def test_per_part_runs_do_not_repeat_the_whole_scenes_warnings():
    """Each part's run has the whole scene's geometry (the others made black): the lobe
    warning of an undersampled glint, said once by the whole scene's run, was said again
    by its part's run (the command line printed it twice)."""
    parts = [ml.meshes.sphere((0, 0, 0), 1.0, 0, subdivisions=2, name="ball"),
             ml.meshes.sphere((0, 5, 0), 0.5, 0, subdivisions=2, name="bead")]
    scene = ml.Scene.from_parts(parts, [ml.materials.ALUMINUM])
    with pytest.warns(ml.errors.LobeSamplingWarning) as caught:
        s = ml.lrcs(scene, [0.0], per_part=True, ray_spacing=0.05)
    said = [str(w.message).split(":")[0] for w in caught]
    assert sorted(said) == sorted(set(said)) and len(said) >= 2, said
    assert s.per_part.shape == (1, 2)


#: The default spacing's error on a plate: its grid's edge cells (spacing / side ≈ 4e-3
#: of the area at R / 256 on a 2 x 3 plate, the cells half in on average: 1e-4 seen).
PLATE_DEFAULT_RTOL = 1e-3


@pytest.mark.parametrize("views", [[0.0], [0.0, 180.0], [0.0, 30.0]])
def test_a_plate_seen_face_on_at_the_default_spacing(views):
    """A user's trial: a flat plate seen face-on spans no range, so the bins (and the
    default ray spacing, one bin) were 7.8e-312 wide and the run refused 'about inf rays'
    after an overflow warning. The default spacing is the scene's size over the bins:
    4ρA cos²θ."""
    plate = MeshPart(np.array([[0, -1, 0], [0, 1, 0], [0, 1, 3], [0, -1, 3.0]]),
                     [[0, 1, 2], [0, 2, 3]], 0, "plate")
    s = ml.lrcs(ml.Scene.from_parts([plate], [Lambertian(RHO)]), views)
    np.testing.assert_allclose(s.values, 4 * RHO * 6.0 * np.cos(np.radians(views)) ** 2,
                               rtol=PLATE_DEFAULT_RTOL, atol=1e-12)
    assert s.profile.info["ray_spacing"] == pytest.approx(np.hypot(1.0, 1.5) / 256)


def test_the_default_spacing_is_the_same_for_every_order():
    """A user's trial: the default spacing followed the bins, which widen with each order
    (for the paths' longer ranges), so the single bounce of a nut moved by 0.2 % with
    ``bounces`` (1956.17, 1954.60, 1959.46 for 1, 2, 3). Now the first order is the same
    number whatever the orders summed."""
    nut = ml.Scene.from_parts([ml.meshes.sphere((0, 0, 0), 1.0, 0, subdivisions=3),
                               ml.meshes.sphere((1.2, 0, 0), 0.4, 0, subdivisions=3)],
                              [Lambertian(RHO)])
    first = [ml.lrcs(nut, [90.0], bounces=b, bounce_samples=1 << 10, seed=1)
             for b in (1, 2, 3)]
    for s in first[1:]:
        assert s.profile.info["order_totals"][0] == pytest.approx(
            first[0].values[0] / (4 * np.pi), rel=1e-12)
    assert first[0].profile.info["ray_spacing"] == pytest.approx(1.3 / 256)   # R from x = 0.3


def test_a_sampled_sigmas_standard_error_describes_its_spread_and_is_warned_of():
    """CrossSection.stderr (0 for one bounce) against the spread of σ over 12 seeds (ratio
    in [0.5, 2]: the sampling error of a standard deviation from 12 draws is ~20 %); with
    few paths the error passes STDERR_SHARE and a warning names the bounce_samples that
    brings it within, which then does not warn."""
    plates = [MeshPart([[0, 0, 0], [1, 0, 0], [1, 0, 0.7], [0, 0, 0.7]], [[0, 1, 2], [0, 2, 3]],
                       0, "a"),
              MeshPart([[0, 0, 0], [0, 0, 0.7], [0, 1, 0.7], [0, 1, 0]], [[0, 1, 2], [0, 2, 3]],
                       0, "b")]
    scene = ml.Scene.from_parts(plates, [Lambertian(0.9)])
    runs = [ml.lrcs(scene, [45.0], ray_spacing=1e-2, bounces=2, bounce_samples=4096, seed=s)
            for s in range(12)]
    spread = np.std([r.values[0] for r in runs], ddof=1)
    assert 0.5 < np.mean([r.stderr[0] for r in runs]) / spread < 2.0
    with pytest.warns(ml.errors.MeshladarWarning, match=r"standard error of [\d.]+ % .*"
                                                        r"bounce_samples=(\d+)") as caught:
        ml.lrcs(scene, [45.0], ray_spacing=1e-2, bounces=2, bounce_samples=16, seed=0)
    import re
    advised = int(re.search(r"bounce_samples=(\d+)", str(caught[0].message)).group(1))
    s = ml.lrcs(scene, [45.0], ray_spacing=1e-2, bounces=2, bounce_samples=advised, seed=0)
    assert s.stderr[0] <= 1.2 * ml.forward.lrcs.STDERR_SHARE * s.values[0]
    with pytest.warns(ml.errors.BounceWarning):                   # one bounce: exact
        assert not ml.lrcs(scene, [45.0], ray_spacing=1e-2).stderr.any()


def test_the_convention_states_the_geometry_and_the_optics():
    """A user's trial: the convention stopped at the radiometry; a glint plate's σ is
    4π F(0) A (geometric optics), not physical optics' 4π A²/λ², and a plate seen from
    behind gives the same σ (faces lit from either side): both said now, and the normals."""
    plate = MeshPart(np.array([[0, -1, 0], [0, 1, 0], [0, 1, 3], [0, -1, 3.0]]),
                     [[0, 1, 2], [0, 2, 3]], 0, "plate")
    scene = ml.Scene.from_parts([plate], [Lambertian(RHO)])
    s = ml.lrcs(scene, [0.0, 180.0], normals="smooth")
    assert s.values[0] == pytest.approx(s.values[1], rel=PLATE_DEFAULT_RTOL)   # the grids
    assert s.convention.startswith(ml.forward.lrcs.CONVENTION)
    assert s.convention.endswith("; smooth normals, two-sided faces; geometric optics "
                                 "(no diffraction)")
    disk = ml.Scene([ml.Disk((0.0, 0.0), 0.5, Lambertian(RHO))])
    assert "; exact shapes;" in ml.lrcs(disk, [0.0]).convention


def test_few_bins_keep_the_default_rays_and_shapes_take_the_mesh_model():
    """A review: with n_bins=1 (σ alone) the default spacing R / n_bins cast a handful of
    rays (a sphere read 1.52 of its σ); it is R / max(n_bins, 256). And a 2-D shape under
    model='mesh' crashed on the mesh-only default (it is the model's own there)."""
    ball = ml.Scene.from_parts([ml.meshes.sphere((0, 0, 0), 1.0, 0, subdivisions=5)],
                               [Lambertian(RHO)])
    for n_bins in (1, 4):
        s = ml.lrcs(ball, [33.0], n_bins=n_bins)
        assert s.values[0] == pytest.approx(8 / 3 * np.pi * RHO, rel=1e-3)
        assert s.profile.info["ray_spacing"] == pytest.approx(1.0 / 256, rel=1e-3)
    disk = ml.Scene([ml.Disk((0.0, 0.0), 0.5, Lambertian(RHO))])
    np.testing.assert_allclose(ml.lrcs(disk, [0.0, 90.0], model="mesh").values,
                               2 * np.pi * RHO * 0.5, rtol=1e-3)
    one_sided = ml.lrcs(ball, [0.0], back_faces="ignore").convention
    assert "; flat normals, one-sided faces;" in one_sided
