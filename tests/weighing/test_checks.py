"""Every rule that only a weighing and a trace plan together decide is refused before the
first ray (meshladar.weighing.Weighing.check, meshladar.raytrace.plan.plan_trace): the
scenes below would take minutes to trace; the engine's scene builder is replaced by one
that fails the test, so an error raised after any ray was cast cannot pass."""

from __future__ import annotations

import numpy as np
import pytest

import meshladar as ml
from meshladar.errors import ModelError, ParameterError
from meshladar.forward import fused_views
from meshladar.forward import job as mesh_job
from meshladar.forward.resolved import resolve
from meshladar.materials import DARK_GRAY
from meshladar.raytrace import embree
from meshladar.raytrace.plan import plan_trace
from meshladar.sensor import FloodBeam, Sensor
from meshladar.weighing.record import Weighing

trimesh = pytest.importorskip("trimesh")


@pytest.fixture
def no_rays(monkeypatch):
    """Building an Embree scene or casting a ray fails the test."""
    def cast(*args, **kwargs):
        raise AssertionError("a ray was cast before the run was refused")

    monkeypatch.setattr(mesh_job, "embree_scene", cast)
    monkeypatch.setattr(fused_views, "cast_bin_grid", cast)
    monkeypatch.setattr(fused_views, "cast_bin_views", cast)
    monkeypatch.setattr(embree.EmbreeScene, "run", cast)


@pytest.fixture(scope="module")
def long_run():
    """An 82k-face sphere, 360 views of about 7e6 rays each (minutes to trace)."""
    scene = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=6, radius=1.0),
                               material=DARK_GRAY)
    ladar = ml.Ladar(angles_deg=np.arange(360.0), bin_edges=np.linspace(-1.0, 1.0, 257))
    return scene, ladar, {"ray_spacing": 7.5e-4}


def _photon_sensor(**beam):
    return Sensor(standoff=1000.0, pulse_energy=1e-3, aperture_diameter=0.1, **beam)


RULES = [
    # (options of simulate, error, the argument and value the message names, what is valid)
    ({"sensor": Sensor(standoff=1000.0, extinction=1e-4)}, ParameterError,
     r"extinction \(0.0001 per m\).*use radiometry='power'.*got radiometry='paper'"),
    ({"sensor": _photon_sensor(beam=FloodBeam(radius=2.0))}, ParameterError,
     r"counts photoelectrons.*use radiometry='power'.*got radiometry='paper'"),
    ({"sensor": _photon_sensor(), "radiometry": "power"}, ParameterError,
     r"photoelectrons need the flood's extent: give FloodBeam\(radius=\.\.\.\).*got "
     r"sensor\.beam=FloodBeam\(radius=None\)"),
    ({"sensor": Sensor(standoff=0.5)}, ParameterError,
     r"standoff 0.5 puts the sensor inside the target's extent.*give a larger standoff"),
    ({"receiver": (0.0, 1.0, 0.3), "materials": "tabulated"}, ModelError,
     r"materials\[0\]: Tabulated has no bistatic evaluation: define bistatic\(\).*built "
     r"in: SandfordRobertson"),
    ({"receiver": (0.0, 1.0, 0.3), "footprint": True}, ParameterError,
     r"footprint binning is monostatic only; use footprint=False"),
    ({"sensor": Sensor(standoff=1000.0), "footprint": True}, ParameterError,
     r"footprint binning is for parallel rays without a sensor; use footprint=False"),
]


def _scene(scene, options):
    if options.pop("materials", None) == "tabulated":
        theta = np.linspace(0.0, 90.0, 10)
        coating = ml.brdf.Tabulated(theta, np.full(10, 0.1))
        scene = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=6),
                                   material=coating)
    return scene


@pytest.mark.parametrize("options, error, message", RULES,
                         ids=["extinction", "photons", "flood-extent", "standoff",
                              "bistatic-coating", "footprint-bistatic", "footprint-sensor"])
def test_a_rule_is_refused_before_the_first_ray(long_run, no_rays, options, error, message):
    scene, ladar, spacing = long_run
    options = dict(options)
    scene = _scene(scene, options)
    with pytest.raises(error, match=message):
        ml.simulate(scene, ladar, model="mesh", **spacing, **options)


def test_resolved_returns_refuse_before_the_first_ray(long_run, no_rays):
    scene, ladar, spacing = long_run
    with pytest.raises(ParameterError, match=r"photoelectrons need the flood's extent"):
        resolve(scene, ladar, [("range", ladar.bin_edges)], sensor=_photon_sensor(),
                radiometry="power", **spacing)
    with pytest.raises(ParameterError, match=r"extinction .* got radiometry='paper'"):
        resolve(scene, ladar, [("range", ladar.bin_edges)],
                sensor=Sensor(standoff=1000.0, extinction=1e-4), **spacing)


def test_a_weighing_checks_a_plan_without_tracing(long_run, no_rays):
    scene, ladar, spacing = long_run
    plan = plan_trace(scene, ladar, receiver=(0.0, 1.0, 0.3), **spacing)
    assert plan.rays > 1e9 and plan.receivers.shape == (360, 3)     # minutes of rays
    Weighing((DARK_GRAY,)).check(plan)                               # applicable: silent
    with pytest.raises(ParameterError, match=r"footprint binning is monostatic only"):
        Weighing((DARK_GRAY,), footprint=True).check(plan)
    with pytest.raises(ParameterError, match=r"radiometry must be one of \('paper', "
                                             r"'power'\); got 'watts'"):
        Weighing((DARK_GRAY,), radiometry="watts")
