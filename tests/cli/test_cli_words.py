"""Every command speaks its flags (a user trial: ``receive`` said "fwhm must be in [1e-18,
1]" for ``--pulse-fwhm``, after reading the sinogram and warning about it; ``reconstruct``
"size: ..." and "extent must be ..."; ``lrcs`` warned "ray_spacing=0.131" and
"bounces='auto'"; simulate advised "--footprint False", which its switch does not take,
"drop receiver or sensor" with no --sensor flag, and "drop tol"); and a range with no
upper end is written [low, inf), inf not in it."""

from __future__ import annotations

import sys
import warnings

import numpy as np
import pytest

from meshladar.cli import main
from meshladar.cli.lrcs import lrcs_words


def _error(capsys, argv):
    """The one line a refused command prints (exit status 2, nothing else on stderr)."""
    code = main([str(a) for a in argv])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert err.startswith("meshladar: error: "), err
    return err[len("meshladar: error: "):-1]


#: receive's numbers, refused before the sinogram is read: the result named does not
#: exist, so a refusal after reading it would say so instead.
RECEIVE = [
    (["--pulse-fwhm", "1e300"], "--pulse-fwhm must be in [1e-18, 1]; got 1e+300"),
    (["--response-fwhm", "10"], "--response-fwhm must be in [1e-18, 1]; got 10.0"),
    (["--sample-rate", "1e20"], "--sample-rate must be in [1, 1e+18]; got 1e+20"),
    (["--oversample", "5000"], "--oversample must be an integer in [1, 1024]; got 5000"),
    (["--standoff", "1e30"], "--standoff must be in [0, 1e+09]; got 1e+30"),
    (["--realisations", "2", "--excess-noise", "0.5"],
     "--excess-noise must be in [1, 1e+09]; got 0.5"),
    (["--realisations", "2", "--bits", "8"],
     "quantisation needs both --bits and --full-scale; got --bits 8, no --full-scale"),
]


@pytest.mark.parametrize("extra, message", RECEIVE)
def test_receive_refuses_in_its_flags_before_reading(extra, message, files, capsys):
    argv = ["receive", "missing.npz", "-o", "w.npz", "--sample-rate", "1e9", *extra]
    assert _error(capsys, argv) == message
    assert not (files / "w.npz").exists()


@pytest.mark.parametrize("extra, message", [
    (["--size", "100000"], "--size: a 100000 x 100000 image would need 224 GiB, more than "
                           "the 4 GiB meshladar allocates at once; use a smaller size"),
    (["--extent", "1e-300"], "--extent must be in [1e-150, 1e+300]; got 1e-300"),
])
def test_reconstruct_refuses_in_its_flags(extra, message, files, capsys):
    assert _error(capsys, ["reconstruct", "s.npz", "-o", "i.npz", *extra]) == message
    assert not (files / "i.npz").exists()


@pytest.mark.parametrize("extra, message", [
    (["--footprint", "--standoff", "2000", "--radiometry", "power"],
     "footprint binning is for parallel rays without a sensor; leave out --footprint with "
     "a sensor"),
    (["--receiver", "0,1,1", "--standoff", "2000", "--radiometry", "power"],
     "a sensor is monostatic (its receiver sits with its transmitter); drop --receiver or "
     "--standoff"),
    (["--tol", "0.1", "--ray-spacing", "0.1"],
     "--tol chooses the ray density itself: drop --ray-spacing and --rays-per-bin, or drop "
     "--tol"),
    (["--bin-width", "1e-300"], "--bin-width must be in [1e-200, inf); got 1e-300"),
])
def test_simulates_advice_is_in_flags_it_takes(extra, message, files, capsys):
    argv = ["simulate", "box.stl", "--views", "2", "-o", "x.npz", *extra]
    assert _error(capsys, argv) == message
    assert not (files / "x.npz").exists()


def test_lrcs_warnings_name_its_flags():
    """lrcs' warnings come from the same API as simulate's (the lobe's sampling, the second
    bounce's estimate): put in lrcs' own flags."""
    got = lrcs_words("the normal turns by 0.182 rad between neighbouring rays (ray_spacing "
                     "0.141) ...; ray_spacing=0.131 puts 2 rays across it; "
                     "bounces=2 or bounces='auto' includes it")
    assert got == ("the normal turns by 0.182 rad between neighbouring rays (--ray-spacing "
                   "0.141) ...; --ray-spacing 0.131 puts 2 rays across it; --bounces 2 or "
                   "--bounces auto includes it")


@pytest.mark.parametrize("argv, message", [
    (["receive", "seed=3/missing.npz", "-o", "w.npz", "--sample-rate", "1e9"],
     "seed=3/missing.npz: no such result file"),
    (["reconstruct", "filter=hann/none.npz", "-o", "i.npz"],
     "filter=hann/none.npz: no such result file"),
    (["reconstruct", "size", "-o", "i.npz"],
     "size: not a readable result file: not an .npz archive (its first bytes are not a zip "
     "archive's); give an .npz file that meshladar wrote"),
])
def test_a_path_named_like_a_parameter_is_kept(argv, message, files, capsys):
    """A sweep's folders (``seed=3/``) and a file named as a parameter are the user's
    names, not the API's: a message quotes them as typed."""
    (files / "size").write_text("not a sinogram")
    assert _error(capsys, argv) == message


def test_lrcs_normals_are_a_meshs(files, capsys):
    assert _error(capsys, ["lrcs", "disk", "--views", "4", "--normals", "smooth"]) == (
        "--normals shades a mesh's faces; a phantom's cross sections come from its exact "
        "shapes (leave out --normals)")


def test_a_short_file_name_is_kept_only_where_it_stands_whole(files, capsys):
    """A sinogram in a file named ``e``: its name is kept where it stands, the letter e in
    the API's words is not (``sample_rate`` still becomes ``--sample-rate``)."""
    (files / "e").write_bytes((files / "s.npz").read_bytes())
    got = _error(capsys, ["receive", "e", "-o", "w.npz", "--sample-rate", "1e18", "--quiet"])
    assert got.startswith("--sample-rate: ") and "give a lower --sample-rate" in got, got


def test_reconstructs_view_advice_names_simulates_flags(files, capsys):
    """reconstruct has no bins to widen: a sinogram of 12 views is too few, and the advice
    names the flags that make another (simulate's), not the API's resampler."""
    assert main(["simulate", "disk", "--views", "12", "--bins", "64", "-o", "s.npz",
                 "--quiet"]) == 0
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        warnings.showwarning = lambda m, c, f, n, file=None, line=None: sys.stderr.write(
            warnings.formatwarning(m, c, f, n, line))
        assert main(["reconstruct", "s.npz", "-o", "i.npz", "--size", "32", "--quiet"]) == 0
    (line,) = [ln for ln in capsys.readouterr().err.splitlines() if "warning" in ln]
    assert line.startswith("meshladar: warning: 12 views are too few for the "), line
    assert line.endswith("use fewer, wider bins or more views (simulate --bins, --views)"), line


_RASTER = "raster azimuth_deg=-2:2:5 elevation_deg=-2:2:5 pulse_rate=1e5"


@pytest.mark.parametrize("change, message", [
    ({"--platform": "static"}, "--platform: static needs position as key=value (it takes "
                               "position, attitude_deg, mount_offset, boresight_deg); got "
                               "'static'"),
    ({"--pattern": "rotating elevations_deg=0 rotation_hz=10 pulse_rate=1e3"},
     "--pattern: rotating needs duration as key=value (it takes elevations_deg, rotation_hz, "
     "pulse_rate, duration); got 'rotating elevations_deg=0 rotation_hz=10 pulse_rate=1e3'"),
    ({"--platform": "nofile.csv"}, "--platform: cannot read the trajectory 'nofile.csv' "
                                   "([Errno 2] No such file or directory: 'nofile.csv')"),
    ({"--platform": "one.csv"},
     "--platform: one.csv: a trajectory needs 2 or more rows (its poses cover their first to "
     "last time); got 1 (a platform at rest: --platform 'static position=X,Y,Z')"),
    ({"--pattern": "raster azimuth_deg=-200:10:5 elevation_deg=0 pulse_rate=1e5"},
     "--pattern: azimuth_deg must be 1 or more angles in [-180, 180] deg; got -200 (value 0 "
     "of 5)"),
    ({"--sample-rate": "1e6"},
     "the echo (the pulse and the response: 2.355 sigma = 5e-09 s, a Gaussian's FWHM) spans "
     "0.005 samples at --sample-rate 1e+06; the detector (a linear receiver's, or a "
     "Geiger-mode array's on its histogram) needs 1 or more (ranges fall on the sample "
     "grid): give --sample-rate >= 4e+08 or a wider pulse (--pulse-fwhm)"),
    ({"--sample-rate": "1e6", "--geiger-shots": "10"},                # (a user's trial)
     "the echo (the pulse and the response: 2.355 sigma = 5e-09 s, a Gaussian's FWHM) spans "
     "0.005 samples at --sample-rate 1e+06; the detector (a linear receiver's, or a "
     "Geiger-mode array's on its histogram) needs 1 or more (ranges fall on the sample "
     "grid): give --sample-rate >= 4e+08 or a wider pulse (--pulse-fwhm)"),
    ({"--pulse-fwhm": "1e-3"},
     "the echo (the pulse and the response) takes 13589151 samples at --sample-rate 2e+09, "
     "more than a record's 65536: give a lower --sample-rate or a shorter pulse "
     "(--pulse-fwhm)"),
    ({"--cfar": None, "--geiger-shots": "4"},
     "--cfar applies to a linear receiver's records, not --geiger-shots; Geiger-mode "
     "thresholds follow each sample's armed shots"),
])
def test_scan_speaks_its_flags(change, message, files, capsys):
    """A user's trial: scan said "Platform.static() missing 1 required positional argument",
    "path: cannot read the trajectory", and took --sample-rate 1e6 for a 5 ns pulse (every
    range on a 150 m sample grid) without a word."""
    (files / "one.csv").write_text("time,x,y,z,roll,pitch,yaw\n0,0,0,0,0,0,0\n")
    flags = {"--pattern": _RASTER, "--platform": "static position=-5,0,0", **change}
    argv = ["scan", "box.stl", "-o", "p.npz"] + [w for kv in flags.items() for w in kv
                                                  if w is not None]
    assert _error(capsys, argv) == message
    assert not (files / "p.npz").exists()


def test_an_empty_scans_advice_names_scans_flags(files, capsys):
    """The box 500 m away returns too little at 0.01 pJ: the advice names --pulse-energy,
    --aperture and --false-alarm, not the API's pulse_energy, aperture_diameter or the
    detector's false_alarm; with Geiger-mode pixels, --geiger-shots."""
    for extra, more in (([], ", or --false-alarm (the threshold follows it)"),
                        (["--geiger-shots", "10"], ", or --geiger-shots")):
        with warnings.catch_warnings():
            warnings.simplefilter("always")
            warnings.showwarning = lambda m, c, f, n, file=None, line=None: sys.stderr.write(
                warnings.formatwarning(m, c, f, n, line))
            assert main(["scan", "box.stl", "--quiet", "--pattern", "raster azimuth_deg="
                         "-1e-4:1e-4:3 elevation_deg=-1e-4:1e-4:3 pulse_rate=1e5",
                         "--platform", "static position=-500,0,0", "-o", "p.npz",
                         "--pulse-energy", "1e-14", *extra]) == 0
        (line,) = capsys.readouterr().err.splitlines()
        assert f"raise --pulse-energy or --aperture{more} (the sensor at " in line, line
        assert "_" not in line.split("(the sensor at")[0], line


def test_view_names_points_not_path(files, capsys):
    assert _error(capsys, ["view", "box.stl", "--points", "nope.las"]) == (
        "--points: no such file 'nope.las'")


def test_view_colours_another_tools_las_only_by_what_it_holds(files, capsys):
    """A LAS without meshladar's fields is drawn (it was refused); coloured by a field it
    lacks, the refusal names --color-by and the fields it holds."""
    laspy = pytest.importorskip("laspy")
    header = laspy.LasHeader(point_format=1, version="1.2")
    las = laspy.LasData(header)
    las.x, las.y, las.z = np.array([[-0.5, -0.5], [0.0, 0.1], [0.0, 0.1]])
    las.write(files / "other.las")
    assert _error(capsys, ["view", "box.stl", "--points", "other.las", "--color-by",
                           "range_error", "--screenshot", "v.png"]) == (
        "--color-by range_error: other.las is another tool's LAS, without meshladar's "
        "true_range; colour it by one of ['intensity', 'return_number', 'scan_angle', "
        "'emission_time']")
