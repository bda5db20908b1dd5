"""A mesh scene's own part names in fit_coatings (a user's trial: ``parts=['dome']`` on a
glTF file whose parts are 'dome' and 'body' was refused, "part must be one of
['aluminum', 'dark_gray']"): a mesh's fit has a part per coating, and a scene part that
holds a coating alone names it in ``parts``, ``free``, ``bounds`` and ``initial``; one that
shares its coating or holds several is refused, before anything is traced, with the names
to use."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

import meshladar as ml
from meshladar.errors import ParameterError
from meshladar.fit import coatings as coatings_module
from meshladar.fit import fit_coatings
from meshladar.materials import ALUMINUM, DARK_GRAY


#: The data's ray spacing (the spheres' radius is 0.3): several times finer than the fit's.
DATA_SPACING = 0.002


def _scene(shared=False):
    parts = [ml.meshes.sphere((-0.5, 0.0, 0.0), 0.3, 0, subdivisions=3, name="left"),
             ml.meshes.sphere((0.5, 0.0, 0.0), 0.3, 1, subdivisions=3, name="right")]
    if shared:
        parts.append(ml.meshes.sphere((0.0, 0.6, 0.0), 0.2, 1, subdivisions=2, name="top"))
    return ml.Scene.from_parts(parts, [ALUMINUM, DARK_GRAY])


def _data(scene):
    """The data of the scene's coatings with dark gray's ρd raised a fifth (a fit starts
    at the scene's own coatings: it must move), simulated at a ray spacing finer than the
    fit's kernel traces (its own resolution's data would be the kernel's prediction)."""
    ladar = ml.Ladar.covering(scene, n_bins=24, angles_deg=np.arange(0.0, 360.0, 30.0))
    truth = [ALUMINUM, dataclasses.replace(DARK_GRAY, rho_d=1.2 * DARK_GRAY.rho_d)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ml.errors.MeshladarWarning)
        return ml.simulate(ml.Scene.from_parts(scene.parts, truth), ladar, model="mesh",
                           ray_spacing=DATA_SPACING)


def _fit(scene, data, **choice):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ml.errors.MeshladarWarning)
        return fit_coatings(scene, data, kernel_tol=None, **choice)


def test_a_scene_part_names_the_coating_it_holds_alone():
    scene = _scene()
    data = _data(scene)
    by_part = _fit(scene, data, parts=["right"], free={"right": ["rho_d"]},
                   bounds={"right.rho_d": (0.0, 0.5)}, initial={"right": DARK_GRAY})
    by_coating = _fit(scene, data, parts=["dark_gray"], free={"dark_gray": ["rho_d"]},
                      bounds={"dark_gray.rho_d": (0.0, 0.5)},
                      initial={"dark_gray": DARK_GRAY})
    assert by_part.names == by_coating.names == ("dark_gray.rho_d",)
    np.testing.assert_array_equal(by_part.estimate, by_coating.estimate)
    np.testing.assert_array_equal(by_part.stderr, by_coating.stderr)
    # the data's ρd, found (not the start): 1.2 × dark gray's, within the fit's own error
    assert abs(by_part.estimate[0] - 1.2 * DARK_GRAY.rho_d) < 0.02 * DARK_GRAY.rho_d


def test_a_part_sharing_its_coating_is_refused_before_the_trace(monkeypatch):
    scene = _scene(shared=True)
    data = _data(_scene())

    def traced(*args, **kwargs):
        raise AssertionError("traced before the parts were checked")

    monkeypatch.setattr(coatings_module, "_traced_kernel", traced)
    with pytest.raises(ParameterError, match=r"part 'right' shares its coating 'dark_gray' "
                                             r"with \['top'\].*name 'dark_gray' to fit them "
                                             "together"):
        fit_coatings(scene, data, kernel_tol=None, parts=["right"])
    with pytest.raises(ParameterError, match=r"one of \['aluminum', 'dark_gray'\] .*an index "
                                             r"below 2 or one of the scene's parts "
                                             r"\['left', 'right', 'top'\]; got 'nope'"):
        fit_coatings(scene, data, kernel_tol=None, parts=["nope"])


def test_a_part_holding_several_coatings_is_refused():
    part = ml.meshes.sphere((0.0, 0.0, 0.0), 0.4, 0, subdivisions=2, name="ball")
    material = np.zeros(len(part.faces), np.int64)
    material[::2] = 1
    scene = ml.Scene.from_parts([dataclasses.replace(part, material=material)],
                                [ALUMINUM, DARK_GRAY])
    data = _data(_scene())
    with pytest.raises(ParameterError, match=r"part 'ball' holds 2 coatings "
                                             r"\['aluminum', 'dark_gray'\]: name them"):
        fit_coatings(scene, data, kernel_tol=None, parts=["ball"])


def test_parts_of_one_name_are_taken_together():
    """Two parts of one name (unnamed spheres are all 'sphere'; glTF nodes repeat names)
    name a coating only where together they hold one that no other part holds: of two
    coatings they are refused (the first one's was fitted alone, without a word)."""
    two = [ml.meshes.sphere((-0.5, 0.0, 0.0), 0.3, 0, subdivisions=2, name="x"),
           ml.meshes.sphere((0.5, 0.0, 0.0), 0.3, 1, subdivisions=2, name="x")]
    data = _data(_scene())
    scene = ml.Scene.from_parts(two, [ALUMINUM, DARK_GRAY])
    for choice in ({"parts": ["x"]}, {"free": {"x": ["rho_d"]}}):
        with pytest.raises(ParameterError, match=r"part 'x' holds 2 coatings "
                                                 r"\['aluminum', 'dark_gray'\]: name them"):
            fit_coatings(scene, data, kernel_tol=None, **choice)
    same = [dataclasses.replace(two[0], material=1), two[1]]
    scene = ml.Scene.from_parts(same + [ml.meshes.sphere((0.0, 0.6, 0.0), 0.2, 0,
                                                         subdivisions=2, name="y")],
                                [ALUMINUM, DARK_GRAY])
    fit = _fit(scene, data, parts=["x"], free={"x": ["rho_d"]})
    assert fit.names == ("dark_gray.rho_d",)


def test_free_and_bounds_say_why_a_part_names_no_coating():
    scene = _scene(shared=True)
    data = _data(_scene())
    why = r"part 'right' shares its coating 'dark_gray' with \['top'\]"
    with pytest.raises(ParameterError, match=why):
        fit_coatings(scene, data, kernel_tol=None, free={"right": ["rho_d"]})
    with pytest.raises(ParameterError, match=why):
        fit_coatings(scene, data, kernel_tol=None, bounds={"right.rho_d": (0.0, 0.5)})
    with pytest.raises(ParameterError, match=r"free's parts must be among \['aluminum', "
                                             r"'dark_gray'\] \(or an index below 2\) or the "
                                             r"scene's parts \['left', 'right', 'top'\]; "
                                             r"got \['nope'\]"):
        fit_coatings(scene, data, kernel_tol=None, free={"nope": ["rho_d"]})
    alone = _scene()
    with pytest.raises(ParameterError, match=r"free names part 'dark_gray' twice \(as "
                                             r"'right' and 'dark_gray'\): give it once"):
        fit_coatings(alone, data, kernel_tol=None,
                     free={"right": ["e"], "dark_gray": ["rho_d"]})
