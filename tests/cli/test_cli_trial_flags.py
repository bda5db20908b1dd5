"""A user trial's command-line defects about flags: an option that does not apply is an
error (``--bounce-samples`` without bounces, ``scan``'s ``--tol`` with ``--sub-rays`` and a
flash pattern's beam flags, ``view``'s options its drawing ignores); negative comma lists
are values; an empty list item is refused by its position; bins that cut the target off
warn; and errors name the flags, never the API's parameters."""

from __future__ import annotations

import os

import numpy as np
import pytest

import meshladar as ml
import meshladar.studies.reconstruction
from meshladar import plotting
from meshladar._executors import MAX_JOBS_PER_CORE
from meshladar.cli import COMMANDS, main
from meshladar.cli import reconstruct as cli_reconstruct
from meshladar.cli import scan as cli_scan
from meshladar.cli import simulate as cli_simulate
from meshladar.cli.argv import join_negative_lists
from meshladar.cli.parser import build_parser
from meshladar.cli.simulate import check_applicable, in_flags
from meshladar.errors import MeshladarWarning
from meshladar.io import load_sinogram
from meshladar.scan import read_hdf5


def _work(*args, **kwargs):
    pytest.fail("the work started before the bad option was refused")


@pytest.fixture
def no_work(monkeypatch):
    """The commands' work fails the test if it is reached."""
    for module, name in ((cli_simulate, "simulate"), (plotting, "viz"),
                         (cli_scan.scanning, "scan"), (ml.studies.reconstruction, "run")):
        monkeypatch.setattr(module, name, _work)


def _run(capsys, argv):
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


def _parse_error(capsys, argv):
    """argparse's refusal of ``argv``: its last line."""
    with pytest.raises(SystemExit) as done:
        build_parser(COMMANDS).parse_args(argv)
    assert done.value.code == 2
    return capsys.readouterr().err.splitlines()[-1]


_SIM = ["simulate", "box.stl", "--views", "2", "-o", "x.npz"]


@pytest.mark.parametrize("extra", [["--bounce-samples", "64"],
                                   ["--bounces", "1", "--bounce-samples", "64"]])
def test_bounce_samples_need_two_bounces(extra, files, capsys, no_work):
    """--bounce-samples was ignored without --bounces 2 or more."""
    code, _, err = _run(capsys, _SIM + extra)
    assert code == 2
    assert err == ("meshladar: error: --bounce-samples samples the paths beyond the first "
                   "bounce: it needs --bounces 2 or more (or auto)\n")


@pytest.mark.parametrize("bounces", ["2", "auto"])
def test_bounce_samples_apply_with_bounces(bounces):
    args = build_parser(COMMANDS).parse_args(
        ["simulate", "box.stl", "-o", "x.npz", "--bounces", bounces, "--bounce-samples", "64"])
    check_applicable(args, "mesh", False)                 # refuses nothing


_FLASH = "flash rows=2 columns=2 ifov_deg=0.1"
_OSC = "oscillating half_angle_deg=10 scan_hz=20 pulse_rate=1000 duration=0.01"
_FLASH_PIXELS = ("its pixels are lit uniformly over their IFOV and sampled by m x m "
                 "sub-rays each, m = ceil(1/(2 tol)), set with --tol (default 0.1: 5 x 5)")


@pytest.mark.parametrize("pattern, extra, message", [
    (_OSC, ["--tol", "0.05", "--sub-rays", "16"],
     "--tol and --sub-rays both set the sub-rays per pulse; give one (--tol T | --sub-rays N)"),
    (_FLASH, ["--sub-rays", "16"], f"--sub-rays does not apply to a flash pattern: "
                                   f"{_FLASH_PIXELS}; leave --sub-rays out"),
    (_FLASH, ["--divergence", "0"], f"--divergence does not apply to a flash pattern: "
                                    f"{_FLASH_PIXELS}; leave --divergence out"),
    (_FLASH, ["--profile", "tophat"], f"--profile does not apply to a flash pattern: "
                                      f"{_FLASH_PIXELS}; leave --profile out"),
    (_FLASH, ["--tol", "0.001"],
     "--tol 0.001: a flash pixel is sampled by m x m sub-rays, m = ceil(1/(2 tol)) = 500 "
     "(250000 a pixel), more than 64 x 64 = 4096; give --tol >= 0.0078125"),
], ids=["tol+sub-rays", "flash+sub-rays", "flash+divergence", "flash+profile", "flash-tol"])
def test_scan_refuses_beam_flags_that_do_not_apply(pattern, extra, message, files, capsys,
                                                   no_work):
    """--tol with --sub-rays took --sub-rays; a flash pattern recorded --sub-rays,
    --divergence and --profile it never used, and a fine --tol failed with the beam's
    sub-ray message."""
    code, _, err = _run(capsys, ["scan", "box.stl", "--quiet", "--pattern", pattern,
                                 "--platform", "static position=-5,0,0", "-o", "p.h5", *extra])
    assert code == 2
    assert err == f"meshladar: error: {message}\n"


@pytest.mark.parametrize("extra", [[], ["--tol", "0.05"]])
def test_a_flash_scan_takes_its_tol_alone(extra, files, capsys):
    pytest.importorskip("h5py")
    code, _, err = _run(capsys, ["scan", "box.stl", "--quiet", "--pattern", _FLASH,
                                 "--platform", "static position=-5,0,0", "-o", "p.h5", *extra])
    assert (code, err) == (0, "")
    assert len(read_hdf5(files / "p.h5")) == 4            # every pixel on the box's face


VIEW = [
    (["--points", "p.las", "--view-angle", "20"], "--view-angle does not apply with --points "
     "(an isometric camera frames the scene and its points, coloured by --color-by); leave "
     "--view-angle out"),
    (["--points", "p.las", "--camera", "view"], "--camera does not apply with --points (an "
     "isometric camera frames the scene and its points, coloured by --color-by); leave "
     "--camera out"),
    (["--points", "p.las", "--log"], "--log does not apply with --points (an isometric camera "
     "frames the scene and its points, coloured by --color-by); leave --log out"),
    (["--bounces", "2", "--points", "p.las"], "--points does not apply with --bounces (faces "
     "are coloured by the order of bounces that dominates their return); leave --points out"),
    (["--bounces", "2", "--color-by", "range"], "--color-by does not apply with --bounces "
     "(faces are coloured by the order of bounces that dominates their return); leave "
     "--color-by out"),
    (["--bounces", "2", "--log"], "--log does not apply with --bounces (faces are coloured by "
     "the order of bounces that dominates their return); leave --log out"),
    (["--color-by", "range"], "--color-by range colours the points of --points; give --points "
     "FILE, or leave --color-by out (the scene is coloured by its return)"),
]


@pytest.mark.parametrize("extra, message", VIEW, ids=[" ".join(e) for e, _ in VIEW])
def test_view_refuses_options_its_drawing_ignores(extra, message, files, capsys, no_work):
    """With --points, --view-angle, --camera and --log changed nothing; with --bounces,
    --points, --color-by and --log were dropped; --color-by alone had no effect."""
    code, _, err = _run(capsys, ["view", "box.stl", "--screenshot", "v.png", *extra])
    assert code == 2
    assert err == f"meshladar: error: {message}\n"


def test_negative_comma_lists_are_values_as_written(capsys):
    """`--angles-deg -10,10`, `--receiver -1,0,0` and `--beam-offset -0.1,0` failed with
    "expected one argument" (only the `--flag=-10,10` form worked)."""
    args = build_parser(COMMANDS).parse_args(
        ["simulate", "box.stl", "-o", "x.npz", "--angles-deg", "-10,10", "--receiver",
         "-1,0,0", "--beam-offset", "-0.1,0", "--z0", "-0.25"])
    assert args.angles_deg == [-10.0, 10.0] and args.receiver == [-1.0, 0.0, 0.0]
    assert args.beam_offset == (-0.1, 0.0) and args.z0 == -0.25
    lr = build_parser(COMMANDS).parse_args(["lrcs", "disk", "--angles-deg", "-.5,-1e-3"])
    assert lr.angles_deg == [-0.5, -0.001]
    assert main(["demo", "--angles-deg", "-10,10"]) == 0
    rows = [line.split()[0] for line in capsys.readouterr().out.splitlines()
            if line.startswith("  ") and line.split()[0].lstrip("-")[:1].isdigit()]
    assert rows == ["-10.000", "10.000"] * 2               # dark gray, then aluminium


def test_a_simulated_run_takes_negative_angles(tmp_path):
    out = tmp_path / "d.npz"
    assert main(["simulate", "disk", "--angles-deg", "-10,10", "-o", str(out), "--quiet"]) == 0
    np.testing.assert_array_equal(load_sinogram(out)[0].angles_deg, [-10.0, 10.0])


def test_only_a_flags_negative_list_is_joined_to_it():
    assert join_negative_lists(["simulate", "a.stl", "--angles-deg", "-10,10", "--z0", "-1",
                                "--receiver", "-inf,0,0", "-o", "x.npz"]) == [
        "simulate", "a.stl", "--angles-deg=-10,10", "--z0", "-1", "--receiver=-inf,0,0",
        "-o", "x.npz"]
    assert join_negative_lists(["--angles-deg", "-10,,5"]) == ["--angles-deg=-10,,5"]
    assert join_negative_lists(["-o", "-1,2", "--", "--x", "-1,2"]) == [
        "-o", "-1,2", "--", "--x", "-1,2"]                 # a short flag; after --


@pytest.mark.parametrize("argv, message", [
    (["simulate", "disk", "-o", "x.npz", "--angles-deg", "0,,5"],
     "meshladar simulate: error: argument --angles-deg: item 2 of '0,,5' is empty; give "
     "comma-separated numbers in degrees"),
    (["demo", "--angles-deg", "0,5,"],
     "meshladar demo: error: argument --angles-deg: item 3 of '0,5,' is empty; give "
     "comma-separated numbers in degrees"),
    (["lrcs", "disk", "--angles-deg", "-10,,5"],
     "meshladar lrcs: error: argument --angles-deg: item 2 of '-10,,5' is empty; give "
     "comma-separated numbers in degrees"),
    (["simulate", "box.stl", "-o", "x.npz", "--receiver", "-1,,0"],
     "meshladar simulate: error: argument --receiver: item 2 of '-1,,0' is empty; give a "
     "direction X,Y,Z"),
    (["simulate", "box.stl", "-o", "x.npz", "--beam-offset", ",0"],
     "meshladar simulate: error: argument --beam-offset: item 1 of ',0' is empty; give two "
     "finite numbers U,V"),
    (["simulate", "disk_pair", "-o", "x.npz", "--coating", "small=aluminum,,large=dark_gray"],
     "meshladar simulate: error: argument --coating: item 2 of "
     "'small=aluminum,,large=dark_gray' is empty; give PART=COATING pairs"),
    (["view", "box.stl", "--bounces", "9"],
     "meshladar view: error: argument --bounces: must be a number of bounces from 1 to 8; got "
     "'9'"),
], ids=["angles-gap", "angles-trailing", "negative-gap", "receiver", "beam-offset", "coating",
        "view-bounces"])
def test_an_empty_item_or_a_bad_count_is_refused_by_its_flag(argv, message, capsys):
    """`--angles-deg 0,,5` ran two views, dropping the empty item without a word."""
    assert _parse_error(capsys, argv) == message


def test_bins_that_do_not_cover_the_target_warn_with_the_fix(files, capsys):
    """`--bins 64 --bin-width 0.01` covered +-0.32 of a target spanning +-0.5 and cut it off
    without a word. The unit box seen along its diagonals spans +-sqrt(1/2)."""
    argv = ["simulate", "box.stl", "--angles-deg", "45,135", "-o", "x.npz", "--quiet"]
    with pytest.warns(MeshladarWarning) as caught:
        assert main(argv + ["--bins", "64", "--bin-width", "0.01"]) == 0
    assert [str(w.message) for w in caught] == [
        "--bins 64 x --bin-width 0.01 cover ranges [-0.32, 0.32], but the target spans "
        "[-0.707107, 0.707107] over these views: returns beyond the bins are lost; give --bins "
        "142 (or only one of --bins and --bin-width: the bins then cover the target)"]
    assert main(argv + ["--bins", "142", "--bin-width", "0.01"]) == 0      # no warning


#: Errors checked by the command line before any work, naming the flags.
UP_FRONT = [
    (_SIM + ["--rays-per-bin", "4", "--ray-spacing", "0.01"],
     "--ray-spacing and --rays-per-bin both set how dense the rays are; give one"),
    (_SIM + ["--run-dir", "f.txt"], "--run-dir must name a folder; got 'f.txt' (a file)"),
    (_SIM + ["--coating", "foo=aluminum"], "--coating: no part named 'foo'; parts are ['mesh']"),
    (["simulate", "disk_pair", "--views", "2", "-o", "x.npz", "--coating", "foo=aluminum"],
     "--coating: no shape named 'foo'; shapes are ['large', 'small']"),
    (["simulate", "flat.stl", "--views", "2", "-o", "x.npz"],
     "SCENE 'flat.stl': the mesh scene has no faces (all degenerate or none given)"),
    (["simulate", "disk", "--views", "4", "--bins", "1000000000", "-o", "x.npz"],
     "--bins: 1000000000 bins would need 29.8 GiB, more than the 4 GiB meshladar allocates at "
     "once; use fewer bins"),
    (["receive", "s.npz", "--sample-rate", "2e9", "--pulse-samples", "nofile.txt",
      "--pulse-interval", "1e-9", "-o", "w.npz"],
     "--pulse-samples 'nofile.txt': cannot be read (no such file or directory)"),
    (["receive", "s.npz", "--sample-rate", "2e9", "--gain", "2", "-o", "w.npz"],
     "--gain shapes the noise: give --realisations N too"),
    (["study", "reconstruction", "st", "--speckle", "2"],
     "--speckle needs --photons (the signal's scale in photoelectrons): give --photons N too"),
    (["study", "reconstruction", "st", "--background", "1"],
     "--background needs --photons (the signal's scale in photoelectrons): give --photons N "
     "too"),
]


@pytest.mark.parametrize("argv, message", UP_FRONT, ids=[m[:30] for _, m in UP_FRONT])
def test_errors_name_the_flags_before_any_work(argv, message, files, monkeypatch, capsys,
                                               no_work):
    """`give ray_spacing or rays_per_bin, not both`, `run_dir must be a folder`,
    `materials: no part named 'foo'`, `'nofile.txt' No such file or directory`, `the mesh
    scene has no faces` (no file named), `n_bins: ...`, `speckle_cells and background need
    photons`: Python's names, some after the work."""
    monkeypatch.setattr(cli_reconstruct, "receive", _work)
    code, _, err = _run(capsys, argv)
    assert code == 2
    assert err == f"meshladar: error: {message}\n"
    assert not os.path.exists("x.npz") and not os.path.exists("w.npz")


def test_the_apis_refusals_are_put_in_flags(files, capsys):
    """`--tol 2` said "tol must be in (0, 1)", `--jobs 9` "jobs must be at most 8": the
    API's own up-front refusals, in the flags' words."""
    cores = os.cpu_count() or 1
    most = MAX_JOBS_PER_CORE * cores
    for extra, message in (
            (["--tol", "2"], "--tol must be in (0, 1); got 2.0"),
            (["--jobs", str(most + 1)],
             f"--jobs must be at most {most} ({MAX_JOBS_PER_CORE} per core on this "
             f"{cores}-core machine: more workers only compete for the cores); got "
             f"{most + 1}")):
        code, _, err = _run(capsys, _SIM + extra)
        assert code == 2
        assert err == f"meshladar: error: {message}\n"


@pytest.mark.parametrize("message, expected", [
    ("/data/n_bins/part.stl: no faces left", "/data/n_bins/part.stl: no faces left"),
    ("runs/standoff/a.stl: cannot be read", "runs/standoff/a.stl: cannot be read"),
    ("n_bins.stl: empty", "n_bins.stl: empty"),
    ("give ray_spacing or rays_per_bin, not both", "give --ray-spacing or --rays-per-bin, "
                                                   "not both"),
    ("a sensor at a finite standoff needs mode='3d'", "a sensor at a finite --standoff needs "
                                                      "--mode 3d"),
])
def test_api_names_become_flags_but_paths_are_kept(message, expected):
    """Every error of the command is translated at one place (main): a file's path that
    happens to hold an API name (unquoted) is not rewritten."""
    assert in_flags(message) == expected


def test_the_beam_flags_defaults_are_the_beams():
    """The parser's help shows the beam's defaults without loading the scanner: they are
    ScanBeam's own (profile and tol), so the help cannot drift from what a scan uses."""
    fields = ml.scan.ScanBeam.__dataclass_fields__
    assert cli_scan.BEAM_DEFAULTS["tol"] == fields["tol"].default
    assert cli_scan.BEAM_DEFAULTS["profile"] == fields["profile"].default
