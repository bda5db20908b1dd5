"""The SR model's compiled twin (meshladar.brdf._sandford_robertson_kernel) against the numpy
model it mirrors, and the registry of built-in models that replaced the hand-kept list."""

from __future__ import annotations

import math

import numpy as np
import pytest

import meshladar as ml
from meshladar.brdf import MODELS, BRDF, KernelRow, is_builtin, projected_weight
from meshladar.brdf._sandford_robertson_kernel import material_table, sr_bistatic, sr_monostatic
from meshladar.errors import ParameterError
from meshladar.materials import ALUMINUM, DARK_GRAY, glint, lambertian

COATINGS = {"dark_gray": DARK_GRAY, "aluminum": ALUMINUM, "glint e=1e-4": glint(1e-4),
            "lambertian": lambertian(0.7),
            "diffuse b=0.99": ml.SandfordRobertson(0.5, 0.0, 0.99, 1.0, lobes="diffuse"),
            "b=1": ml.SandfordRobertson(0.1, 0.2, 1.0, 0.3),
            "Lambertian class": ml.brdf.Lambertian(0.4)}
THETA = np.concatenate([np.linspace(0.0, math.pi / 2, 1001), [math.pi / 2, 1e-9]])


@pytest.mark.parametrize("name", list(COATINGS))
def test_the_compiled_sr_kernel_equals_the_model_on_a_grid_through_90_degrees(name):
    m = COATINGS[name]
    c, s = np.cos(THETA), np.abs(np.sin(THETA))
    got = np.array([sr_monostatic(ci, si * si, *m.kernel_params) for ci, si in zip(c, s)])
    # the same expressions rearranged (g without a norm, one square root): equal to a few
    # ulps (F spans 1e-3..1e16)
    np.testing.assert_allclose(got, m.value(c, s), rtol=1e-13, atol=0)


def test_the_material_table_stacks_each_coatings_kernel_row():
    mats = [DARK_GRAY, ALUMINUM, ml.brdf.Lambertian(0.25)]
    table = material_table(mats)
    assert table.shape == (3, 7) and table.dtype == np.float64
    row = DARK_GRAY.kernel_params
    assert isinstance(row, KernelRow) and row.rho_d == 0.032 and row.e == 0.17
    np.testing.assert_array_equal(table[2], [0.25, 0.0, 0.0, 1.0, 1.0, 1.0, 0.0])
    assert tuple(table[0]) == tuple(row)



class _BadRow(BRDF):
    kernel_params = (0.1, 0.0, 0.0, 1.0)                   # 4 numbers, not 7

    def projected(self, cos_theta, sin_theta):
        return 0.1 * np.maximum(cos_theta, 0.0)


@pytest.mark.parametrize("materials, message", [
    # a model without a compiled row gave array([nan]); mixed with one that has a row,
    # numpy's "inhomogeneous shape" ValueError
    ([ml.brdf.GGX(alpha=0.2)], r"^materials\[0\]: GGX has no kernel_params .*"
     r"\(SandfordRobertson, Lambertian\)"),
    ([DARK_GRAY, ml.brdf.Phong(0.2, 0.3, 10.0)], r"^materials\[1\]: Phong has no kernel_params"),
    ([DARK_GRAY, _BadRow()], r"^materials\[1\]: _BadRow.kernel_params must be 7 finite "
     r"numbers .*got \(0.1, 0.0, 0.0, 1.0\)"),
    (DARK_GRAY, r"^materials must be a list or tuple of BRDFs; got SandfordRobertson"),
])
def test_the_material_table_refuses_coatings_without_a_compiled_row(materials, message):
    with pytest.raises(ParameterError, match=message):
        material_table(materials)


def test_the_material_table_of_no_coatings_has_seven_columns():
    assert material_table([]).shape == (0, 7)

def test_built_in_models_register_themselves_and_a_users_do_not():
    assert set(MODELS) == {"SandfordRobertson", "Lambertian", "Phong", "GGX", "Tabulated"}
    assert MODELS["GGX"] is ml.brdf.GGX
    assert is_builtin(ml.brdf.GGX(alpha=0.2)) and is_builtin(DARK_GRAY)

    class Negative(BRDF):
        def projected(self, cos_theta, sin_theta):
            return -np.ones_like(cos_theta)

    assert "Negative" not in MODELS and not is_builtin(Negative())
    with pytest.raises(ParameterError, match=r"Negative.projected must be finite"):
        projected_weight(Negative(), np.array([0.5]), np.array([0.5]))

    class Brighter(ml.brdf.Lambertian):                # a user's subclass of a built-in
        def projected(self, cos_theta, sin_theta):
            return np.full(np.shape(cos_theta), np.nan)

    assert not is_builtin(Brighter(0.5))               # checked, as before
    with pytest.raises(ParameterError, match=r"Brighter.projected must be finite"):
        projected_weight(Brighter(0.5), np.array([0.5]), np.array([0.5]))
    with pytest.raises(TypeError):
        MODELS["Mine"] = Negative                     # read-only


@pytest.mark.parametrize("name", ["dark_gray", "aluminum", "glint e=1e-4", "b=1",
                                  "b=1e-149"])
def test_the_compiled_sr_kernel_holds_at_the_extremes_of_its_arguments(name):
    """Where the kernel's squares could underflow or lose bits (cos θ and b sin θ both
    tiny, cos θ² subnormal beside a small b² sin²θ, cos θ = 0 or 1 exactly, θ a hair from
    0 or 90°), it stays finite and equal to the model to 1e-13 (the model's hypot), and is
    0 or positive as the model is."""
    m = COATINGS.get(name) or ml.SandfordRobertson(0.5, 0.0, 1e-149, 1.0, lobes="diffuse")
    theta = np.array([0.0, 1e-300, 1e-160, 1e-12, math.pi / 2 - 1e-12, math.pi / 2])
    c, s = np.cos(theta), np.abs(np.sin(theta))
    c = np.concatenate([c, [1e-160, 1e-300, 0.0, 1e-152, 1e-156, 1e-158]])
    s = np.concatenate([s, [1.0, 1.0, 1.0, 1.0, 1.0, 1.0]])
    got = np.array([sr_monostatic(ci, si * si, *m.kernel_params) for ci, si in zip(c, s)])
    want = m.value(c, s)
    assert np.all(np.isfinite(got)) and np.all(got >= 0)
    np.testing.assert_allclose(got, want, rtol=1e-13, atol=0)


def _pairs(n, seed=3):
    """``n`` random incidence/exit pairs over the hemisphere (three tenths of them at the
    horizon or the normal) as the six cosines and sines the bistatic models take."""
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(2, n, 3))
    v[:, :, 2] = np.abs(v[:, :, 2])
    v[0, : n // 10, 2] = 0.0                               # incidence at the horizon
    v[1, n // 10: n // 5, :2] = 0.0                        # exit along the normal
    v[1, n // 5: 3 * n // 10, 2] = 0.0                     # exit at the horizon
    v /= np.linalg.norm(v, axis=2, keepdims=True)
    wi, wr = v
    h = (wi + wr) / np.linalg.norm(wi + wr, axis=1, keepdims=True)
    norm_xy = lambda x: np.hypot(x[:, 0], x[:, 1])          # noqa: E731
    return wi[:, 2], norm_xy(wi), wr[:, 2], norm_xy(wr), h[:, 2], norm_xy(h)


@pytest.mark.parametrize("name", list(COATINGS))
@pytest.mark.parametrize("projected", [True, False])
def test_the_compiled_bistatic_sr_kernel_equals_the_model(name, projected):
    """sr_bistatic against the numpy model's bistatic (F·cos θr) and bistatic_value (F) on
    2000 pairs of directions, horizon and normal included, and 0 below either horizon."""
    m = COATINGS[name]
    args = _pairs(2000)
    got = np.array([sr_bistatic(*a, *m.kernel_params, projected) for a in zip(*args)])
    want = m.bistatic(*args) if projected else m.bistatic_value(*args)
    np.testing.assert_allclose(got, want, rtol=1e-13, atol=0)
    assert sr_bistatic(-1e-9, 1.0, 0.5, 0.8, 0.9, 0.4, *m.kernel_params, projected) == 0.0
    assert sr_bistatic(0.5, 0.8, -1e-9, 1.0, 0.9, 0.4, *m.kernel_params, projected) == 0.0
