"""Options that the others make meaningless are refused by the API and the command line,
naming both (issue 29: photon options without an aperture or a standoff, and the optics,
quantum efficiency and wavelength without photon counting, were accepted and ignored)."""

from __future__ import annotations

import re
import sys
import warnings

import pytest

import meshladar as ml
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
    (["--standoff", "100", "--mode", "3d", "--pulse-energy", "1e-3", "--aperture", "0.1",
      "--radiometry", "power"],
     r"photoelectrons need the flood's extent: give --flood-radius \(m at the aim point\), "
     r"or --beam-waist; got no --flood-radius"),
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


def _photon_sinogram(tmp_path):
    """A sinogram that counts photoelectrons, saved as the command line would."""
    out = tmp_path / "pe.npz"
    assert main(["simulate", "disk", "--model", "mesh", "--views", "2", "--mode", "3d",
                 "--standoff", "100", "--pulse-energy", "1e-3", "--aperture", "0.1",
                 "--flood-radius", "1", "--radiometry", "power", "--quiet", "-o",
                 str(out)]) == 0
    return out


def test_receive_scale_on_photoelectrons_is_refused(tmp_path, capsys):
    """--scale on a photoelectron sinogram multiplied the counts again and kept calling
    them photoelectrons."""
    src = _photon_sinogram(tmp_path)
    capsys.readouterr()
    out = tmp_path / "w.npz"
    code = main(["receive", str(src), "-o", str(out), "--sample-rate", "1e9", "--scale", "3"])
    err = capsys.readouterr().err
    assert code == 2 and "--scale converts relative power to photoelectrons" in err, err
    assert "already counts photoelectrons" in err and not out.exists()
    from meshladar.io import load_sinogram
    from meshladar.waveforms import receive

    waves = receive(load_sinogram(src)[0], sample_rate=1e9)
    with pytest.raises(ParameterError, match="^these waveforms already count photoelectrons"):
        waves.scaled(3.0)


def test_receive_refuses_a_negative_sinogram():
    """A log-input or differenced sinogram was clipped to zero waveforms without a word."""
    import numpy as np

    import meshladar as ml
    from meshladar.waveforms import receive

    sino = ml.Sinogram(np.array([[1.0, -2.0, 3.0]]), angles_deg=[0.0],
                       bin_edges=[0.0, 1.0, 2.0, 3.0])
    with pytest.raises(ParameterError, match=r"^sino must hold received power or counts "
                                             r"\(>= 0\); its smallest value is -2"):
        receive(sino, sample_rate=1e9)


@pytest.mark.parametrize("flag", ["--photons", "--speckle", "--background"])
def test_noise_options_on_the_3d_study_are_refused(flag, tmp_path, capsys):
    """--photons on study tomography3d was accepted and ignored."""
    code = main(["study", "tomography3d", str(tmp_path / "out"), flag, "5"])
    err = capsys.readouterr().err
    assert code == 2 and f"{flag} is an option of the reconstruction study; the " \
                         "tomography3d study does not use it" in err, err


def test_too_many_local_workers_are_refused_in_flags(tmp_path, capsys):
    """--workers 64 started 64 local Dask workers on a 2-core machine."""
    import os

    pytest.importorskip("distributed")
    many = 4 * (os.cpu_count() or 1) + 1
    code = main(["simulate", "disk", "--views", "4", "--workers", str(many), "-o",
                 str(tmp_path / "x.npz")])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith(f"meshladar: error: --workers: {many} local workers"), err


def test_a_warning_is_in_flags_too(tmp_path, capsys):
    """The faceting check's advice reaches the command line as --normals, not normals=."""
    import trimesh

    stl = tmp_path / "ball.stl"
    trimesh.creation.icosphere(subdivisions=3).export(stl)
    out = tmp_path / "x.npz"
    with warnings.catch_warnings():
        warnings.simplefilter("always", ml.errors.LobeSamplingWarning)
        # shown as a plain Python shows it (pytest records warnings instead)
        warnings.showwarning = lambda m, c, f, n, file=None, line=None: sys.stderr.write(
            warnings.formatwarning(m, c, f, n, line))
        code = main(["simulate", str(stl), "--coating", "mesh=aluminum", "--views", "2",
                     "-o", str(out), "--quiet"])
    err = capsys.readouterr().err
    assert code == 0 and out.exists()
    (line,) = [ln for ln in err.splitlines() if ln.startswith("meshladar: warning:")]
    assert "with flat normals" in line and "use --normals smooth" in line, line
    assert "normals=" not in line, line
