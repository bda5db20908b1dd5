"""Coatings: the paper's constants, helpers, and TOML material tables."""

from __future__ import annotations

import math

import numpy as np
import pytest

import meshladar as ml
from meshladar.errors import MaterialFileError
from meshladar.materials import ALUMINUM, DARK_GRAY, glint, lambertian, load_table, parse_table

#: algebraic identities in float64
ULP_RTOL = 1e-13


def test_paper_coatings():
    assert (DARK_GRAY.rho_d, DARK_GRAY.epsilon, DARK_GRAY.b, DARK_GRAY.e) == (0.032, 0.877, 0.1,
                                                                              0.17)
    assert (ALUMINUM.rho_d, ALUMINUM.epsilon, ALUMINUM.b, ALUMINUM.e) == (0.047, 0.53, 0.1, 0.007)
    assert DARK_GRAY.lobes == ALUMINUM.lobes == "both"
    # both conserve energy: ρs ≥ 0 everywhere
    theta = np.linspace(0, math.pi / 2, 181)
    assert np.all(DARK_GRAY.specular_reflectance(theta) > 0)
    assert np.all(ALUMINUM.specular_reflectance(theta) > 0)


def test_packaged_table_matches_constants():
    from meshladar.phantoms import materials

    table = materials()
    assert table["dark_gray"] == DARK_GRAY
    assert table["aluminum"] == ALUMINUM
    assert table["lambertian"] == lambertian(1.0)
    assert table["glint_sharp"] == glint(0.007)
    assert table["glint_rough"] == glint(1.0)
    assert table["aluminum"].name == "aluminum"
    with pytest.raises(TypeError):
        table["x"] = DARK_GRAY                      # read-only mapping


def test_lambertian_and_glint_helpers():
    m = lambertian(0.25)
    theta = np.linspace(0, math.pi / 2, 50)
    np.testing.assert_allclose(m.monostatic(theta), 0.25 / math.pi, rtol=ULP_RTOL)
    g = glint(0.05, rho_s=0.4)
    np.testing.assert_allclose(g.specular_reflectance(theta), 0.4, rtol=ULP_RTOL)
    np.testing.assert_allclose(g.diffuse_reflectance(theta), 0.0, atol=0)
    # the pure glint at normal incidence: ρs (1 + e²) / (4π e²)
    assert g.monostatic(0.0) == pytest.approx(0.4 * (1 + 0.05**2) / (4 * math.pi * 0.05**2),
                                              rel=ULP_RTOL)
    with pytest.raises(ValueError, match=r"rho_s must be in \[0, 1\]; got 1.5"):
        glint(0.1, rho_s=1.5)


def _write(tmp_path, text):
    p = tmp_path / "coatings.toml"
    p.write_text(text, encoding="utf-8")
    return p


def test_load_table_reads_valid_file(tmp_path):
    p = _write(tmp_path, '[paint]\nrho_d = 0.1\nepsilon = 0.5\nb = 0.2\ne = 0.3\n'
                         '[chalk]\nrho_d = 0.9\nepsilon = 0.0\nb = 0\ne = 1\nlobes = "diffuse"\n'
                         'description = "white"\n')
    table = load_table(p)
    assert list(table) == ["paint", "chalk"]
    assert table["paint"] == ml.SandfordRobertson(0.1, 0.5, 0.2, 0.3)
    assert table["chalk"].lobes == "diffuse" and table["chalk"].b == 0.0


@pytest.mark.parametrize("text, match", [
    ("[paint]\nrho_d = 0.1\nepsilon = 0.5\nb = 0.2\n", r"\[paint\]: missing field 'e'"),
    ("[paint]\nrho_d = 0.1\nepsilon = 0.5\nb = 0.2\ne = 0.3\ncolour = 1\n",
     r"\[paint\]: unknown field 'colour'; valid fields are"),
    ("[paint]\nrho_d = '0.1'\nepsilon = 0.5\nb = 0.2\ne = 0.3\n",
     r"\[paint\]: field 'rho_d' must be a number; got '0.1'"),
    ("[paint]\nrho_d = 0.1\nepsilon = 0.5\nb = 1.2\ne = 0.3\n",
     r"\[paint\]: b must be in \[0, 1\]; got 1.2"),
    ("[paint]\nrho_d = 0.5\nepsilon = 0.6\nb = 0.2\ne = 0.3\n",
     r"\[paint\]: coating is not energy-conserving"),
    ("[paint]\nrho_d = 0.1\nepsilon = 0.5\nb = 0.2\ne = 0.3\nlobes = 'glint'\n",
     r"\[paint\]: lobes must be one of"),
    ("[paint]\nrho_d = 0.1\nepsilon = nan\nb = 0.2\ne = 0.3\n", r"\[paint\]: epsilon must be finite"),
    ("paint = 3\n", r"\[paint\] must be a table of fields; got 3"),
    ("", r"expected at least one \[material\] table"),
    ("[paint\nrho_d = 0.1\n", r"not valid TOML"),
])
def test_load_table_errors_name_file_entry_field(tmp_path, text, match):
    p = _write(tmp_path, text)
    with pytest.raises(MaterialFileError, match=match) as info:
        load_table(p)
    assert str(p) in str(info.value)


def test_load_table_missing_file(tmp_path):
    with pytest.raises(MaterialFileError, match=r"nope.toml: cannot read material table"):
        load_table(tmp_path / "nope.toml")


def test_parse_table_source_label():
    with pytest.raises(MaterialFileError, match=r"^mine: material \[x\]: missing field"):
        parse_table({"x": {"rho_d": 0.1}}, source="mine")
