"""Options that the others make meaningless are refused by the API and the command line,
naming both (issue 29: photon options without an aperture or a standoff, and the optics,
quantum efficiency and wavelength without photon counting, were accepted and ignored)."""

from __future__ import annotations

import re

import pytest

from meshladar.cli import main
from meshladar.errors import ParameterError
from meshladar.sensor import Sensor

API = [
    ({"pulse_energy": 1e-3, "standoff": 100.0},
     "pulse_energy counts photoelectrons only together with aperture_diameter"),
    ({"aperture_diameter": 0.1, "standoff": 100.0},
     "aperture_diameter counts photoelectrons only together with pulse_energy"),
    ({"pulse_energy": 1e-3, "aperture_diameter": 0.1},
     "pulse_energy and aperture_diameter count photoelectrons at a finite standoff"),
    ({"quantum_efficiency": 0.5}, r"quantum_efficiency \(0.5\) scales photoelectron counts"),
    ({"optics_transmission": 0.9, "standoff": 10.0},
     r"optics_transmission \(0.9\) scales photoelectron counts"),
    ({"wavelength": 1.55e-6, "standoff": 10.0}, r"wavelength \(1.55e-06\) scales"),
]


@pytest.mark.parametrize("fields, message", API)
def test_the_sensor_refuses_options_it_would_ignore(fields, message):
    with pytest.raises(ParameterError, match="^" + message):
        Sensor(**fields)


def test_photon_counting_with_everything_given_is_accepted():
    s = Sensor(standoff=100.0, pulse_energy=1e-3, aperture_diameter=0.1,
               quantum_efficiency=0.5, optics_transmission=0.9, wavelength=1.55e-6)
    assert s.counts_photons


CLI = [
    (["--pulse-energy", "1e-3", "--standoff", "100"],
     "--pulse-energy counts photoelectrons only together with --aperture"),
    (["--aperture", "0.1", "--standoff", "100"],
     "--aperture counts photoelectrons only together with --pulse-energy"),
    (["--pulse-energy", "1e-3", "--aperture", "0.1"],
     "--pulse-energy and --aperture count photoelectrons at a finite --standoff"),
    (["--quantum-efficiency", "0.5"], r"--quantum-efficiency \(0.5\) scales photoelectron"),
    (["--wavelength", "1.5e-6", "--standoff", "10"], r"--wavelength \(1.5e-06\) scales"),
    (["--standoff", "10", "--mode", "slice"],
     r"a sensor at a finite --standoff needs --mode 3d"),
]


@pytest.mark.parametrize("flags, message", CLI)
def test_the_command_line_says_it_in_flags(flags, message, tmp_path, capsys):
    out = tmp_path / "x.npz"
    code = main(["simulate", "disk", "--model", "mesh", "--views", "2", "-o", str(out),
                 *flags])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert re.search("meshladar: error: " + message, err), err
    assert not re.search(r"pulse_energy|aperture_diameter|quantum_efficiency|"
                         r"optics_transmission|mode=", err), err     # Python's words
    assert not out.exists()
