"""The cross section's figure: a polar signature for views about z, a map for views over
the sphere, and the brightest view's range profile whose bins sum to its σ."""

from __future__ import annotations

import numpy as np
import pytest

import meshladar as ml
from meshladar.meshes import MeshPart

pytest.importorskip("matplotlib")


def _dihedral(coating):
    return ml.Scene.from_parts(
        [MeshPart([[0, 0, 0], [1, 0, 0], [1, 0, 0.7], [0, 0, 0.7]], [[0, 1, 2], [0, 2, 3]], 0, "a"),
         MeshPart([[0, 0, 0], [0, 0, 0.7], [0, 1, 0.7], [0, 1, 0]], [[0, 1, 2], [0, 2, 3]], 0, "b")],
        [coating])


def test_views_about_z_draw_a_polar_signature():
    cs = ml.lrcs(_dihedral(ml.SandfordRobertson(0.1, 0.5, 0.3, 0.1)), np.arange(0, 360, 10.0),
                 ray_spacing=1e-2, bounces=2, bounce_samples=8192, seed=0)
    fig = cs.plot(floor_db=30.0)
    polar, profile = fig.axes
    assert polar.name == "polar"
    r = polar.lines[0].get_ydata()
    db = cs.dbsm
    assert r.max() == pytest.approx(db.max()) and polar.get_ylim()[0] >= db.max() - 30.0
    i = int(np.argmax(cs.values))
    heights = profile.patches[0].get_data().values
    assert heights.sum() == pytest.approx(cs.values[i], rel=1e-12)
    assert f"σ = {cs.values[i]:.4g}" in profile.get_title()


def test_views_over_the_sphere_draw_a_map():
    cs = ml.lrcs(_dihedral(ml.brdf.Lambertian(0.5)), ml.meshes.fibonacci_sphere(40),
                 ray_spacing=2e-2, bounces=2, bounce_samples=1024, seed=0)
    fig = cs.plot()
    chart = fig.axes[0]
    assert chart.get_xlabel() == "view azimuth [deg]"
    colours = chart.collections[0].get_array()
    assert len(colours) == 40 and colours.max() == pytest.approx(cs.dbsm.max())
