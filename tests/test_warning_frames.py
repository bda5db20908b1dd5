"""Every warning meshladar gives points at the user's own line, however deep in the engine
it is raised (``errors.user_stacklevel``): here, at this file."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import trimesh

import meshladar as ml
from meshladar.forward import resolve
from meshladar.meshes import fibonacci_sphere
from meshladar.reconstruct.volumes import fbp3d
from meshladar.sensor import Sensor


def _ball(center=(0.0, 0.0, 0.0)):
    mesh = trimesh.creation.icosphere(subdivisions=2, radius=0.5).apply_translation(center)
    return ml.Scene.from_mesh(mesh, material=ml.materials.DARK_GRAY)


def _pair():
    return ml.phantoms.scene("disk_pair", large=ml.materials.DARK_GRAY,
                             small=ml.materials.ALUMINUM)


CASES = {
    # views over half the circle: FBP warns of the gap
    "fbp's view gap": lambda: ml.fbp(ml.simulate(_pair(), ml.Ladar.paper(
        angles_deg=np.arange(0.0, 180.0, 1.0))), size=32),
    # bins beside the scene: the analytic model's all-zero sinogram
    "simulate's empty bins": lambda: ml.simulate(_pair(), ml.Ladar(
        angles_deg=[0.0], bin_edges=np.linspace(5.0, 6.0, 5))),
    # the same for resolve, through the mesh engine's layers
    "resolve's empty bins": lambda: resolve(_ball(), ml.Ladar.covering(
        _ball(), n_bins=8, angles_deg=[0.0]), [("range", np.linspace(5.0, 6.0, 5))]),
    # the mesh model's all-zero sinogram, through the plan, the job and the stream
    "the mesh model's empty bins": lambda: ml.simulate(_ball(), ml.Ladar(
        angles_deg=[0.0], bin_edges=np.linspace(5.0, 6.0, 5)), model="mesh"),
    # the accuracy knob stops at its ray budget, from inside its refinement loop
    "tol's budget": lambda: ml.simulate(_pair(), ml.Ladar.paper(angles_deg=[0.0, 90.0]),
                                        model="mesh", tol=1e-6, max_rays=1e5),
    # the mesh model's warning from inside the accuracy knob's runs
    "the knob's empty bins": lambda: ml.simulate(_ball(), ml.Ladar(
        angles_deg=[0.0], bin_edges=np.linspace(5.0, 6.0, 5)), model="mesh", tol=1e-2),
    # a standoff so far that the ranges round coarsely, from the trace's plan
    "a far standoff": lambda: ml.simulate(_ball(), ml.Ladar(
        angles_deg=[0.0], bin_edges=np.linspace(-0.5, -0.49, 101)), model="mesh",
        radiometry="power", sensor=Sensor(standoff=1e9), ray_spacing=0.01),
    # a part far from the origin fills few bins
    "covering's off-centre part": lambda: ml.Ladar.covering(
        _ball((20.0, 0.0, 0.0)), n_bins=16, angles_deg=np.arange(0.0, 360.0, 90.0)),
    # a slice above the target
    "a slice outside the target": lambda: ml.simulate(_ball(), ml.Ladar.covering(
        _ball(), n_bins=8, angles_deg=[0.0]), model="mesh", mode="slice", z0=2.0),
    # far too few views for a 3-D inversion
    "fbp3d's few views": lambda: fbp3d(ml.simulate(_ball(), ml.Ladar(
        None, np.linspace(-0.8, 0.8, 129), view_vectors=fibonacci_sphere(60)),
        model="mesh"), size=64),
    # the paper's b = 0.99 surface reflects more than it receives
    "an energy-creating coating": lambda: ml.SandfordRobertson(1.0, 0.0, 0.99, 1.0,
                                                               lobes="diffuse"),
}


@pytest.mark.parametrize("name", list(CASES))
def test_the_warning_points_at_the_callers_line(name):
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        CASES[name]()
    ours = [w for w in seen if issubclass(w.category, ml.errors.MeshladarWarning)]
    assert ours, f"{name}: no meshladar warning (the case no longer warns)"
    for w in ours:
        assert w.filename == __file__, (name, w.filename, w.lineno, str(w.message)[:80])
