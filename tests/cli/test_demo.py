"""meshladar demo prints true, bounded numbers: at exactly 90° the monostatic F is unbounded
(it grows as 1/cos θ), and a float cos 90° of 6e-17 used to print it as 4.4e14."""

from __future__ import annotations

import re

from meshladar.cli import main

#: Above any value the paper's coatings take at the demo's angles (aluminium's F(0) is
#: 651 sr⁻¹): a number past it in the table is an artefact.
SENSIBLE_BOUND = 1e4
NUMBER = re.compile(r"[-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?")


def _demo(capsys, *args):
    assert main(["demo", *args]) == 0
    return capsys.readouterr().out


def _rows(out):
    return [line.split() for line in out.splitlines()
            if re.match(r"^\s+[-\d.]+\s+(unbounded|[-\d.e+]+)\s+[-\d.e+]+\s+[\d.]+$", line)]


def test_the_default_demo_prints_no_value_above_a_sensible_bound(capsys):
    out = _demo(capsys)
    values = [float(v) for row in _rows(out) for v in row if NUMBER.fullmatch(v)]
    assert len(_rows(out)) == 16 and max(values) <= SENSIBLE_BOUND
    assert "nan" not in out.lower() and "inf" not in out.lower()
    grazing = [row for row in _rows(out) if row[0] == "90.000"]
    assert len(grazing) == 2                              # dark gray, aluminium
    for row in grazing:                                   # F unbounded, F cos θ bounded
        assert row[1] == "unbounded" and 0.0 < float(row[2]) < 1.0
    assert out.count("F is unbounded at grazing incidence") == 2


def test_an_angle_just_below_grazing_is_printed_as_given_with_its_true_value(capsys):
    """89.9999999° is not 90°: it is printed as it is, with the model's large but true F
    (F cos θ over cos θ), not rounded to a "90.000" row."""
    out = _demo(capsys, "--angles-deg", "89.9999999,30")
    near = [row for row in _rows(out) if row[0] == "89.9999999"]
    assert len(near) == 2
    for row in near:
        f, fc = float(row[1]), float(row[2])
        assert f > SENSIBLE_BOUND and abs(f * 1.7453292519943296e-09 / fc - 1) < 1e-4
    assert "unbounded" not in out
